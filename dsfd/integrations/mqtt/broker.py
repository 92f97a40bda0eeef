"""A local Mosquitto broker on a free loopback port, for ``dsfd bench mqtt`` and the tests.

Runs the Debian ``mosquitto`` binary (``/usr/sbin/mosquitto``; ``apt-get install mosquitto
mosquitto-clients``) with a generated configuration in a directory of its own: one listener on
127.0.0.1, no anonymous access, a password file made with ``mosquitto_passwd -b``, and
persistence in that directory, so :meth:`LocalBroker.stop` (SIGTERM: Mosquitto saves its
database) and :meth:`LocalBroker.start` again keep retained messages and the queued messages
of persistent sessions, as a real broker restart does.
"""

from __future__ import annotations

import getpass
import shutil
import signal
import socket
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["LocalBroker", "find_mosquitto", "free_port"]

_SEARCH = ("/usr/sbin", "/usr/local/sbin", "/usr/bin", "/usr/local/bin")


def find_mosquitto(name: str = "mosquitto") -> str | None:
    """Path of a Mosquitto program (``mosquitto``, ``mosquitto_passwd``, ...), or None."""
    found = shutil.which(name)
    if found:
        return found
    for folder in _SEARCH:
        path = Path(folder) / name
        if path.exists():
            return str(path)
    return None


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class LocalBroker:
    """Mosquitto with one user; ``start``/``stop``/``kill`` like an operator would."""

    directory: Path
    username: str = "dsfd"
    password: str = "s3cret-for-tests"
    port: int = field(default_factory=free_port)
    _proc: subprocess.Popen[bytes] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        binary = find_mosquitto()
        passwd = find_mosquitto("mosquitto_passwd")
        if binary is None or passwd is None:
            raise FileNotFoundError("mosquitto is not installed (apt-get install mosquitto "
                                    "mosquitto-clients)")
        self.binary = binary
        self.directory.mkdir(parents=True, exist_ok=True)
        self.password_file = self.directory / "passwd"
        subprocess.run([passwd, "-b", "-c", str(self.password_file), self.username,
                        self.password], check=True, capture_output=True)
        self.config_file = self.directory / "mosquitto.conf"
        self.log_file = self.directory / "mosquitto.log"
        # Run as ourselves: as root Mosquitto would switch to the user 'mosquitto', which
        # cannot write into a private test directory.
        self.config_file.write_text(
            f"user {getpass.getuser()}\n"
            f"listener {self.port} 127.0.0.1\n"
            "allow_anonymous false\n"
            f"password_file {self.password_file}\n"
            "persistence true\n"
            f"persistence_location {self.directory}/\n"
            "autosave_interval 0\n"
            "max_queued_messages 100000\n"
            f"log_dest file {self.log_file}\n"
            "log_type error\nlog_type warning\nlog_type notice\nlog_type information\n")

    @property
    def address(self) -> str:
        return f"127.0.0.1:{self.port}"

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def start(self, *, timeout_s: float = 10.0) -> LocalBroker:
        """Start Mosquitto and wait until it accepts connections."""
        if self.running:
            return self
        self._proc = subprocess.Popen([self.binary, "-c", str(self.config_file)],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self._proc.poll() is not None:
                err = self._proc.stderr.read().decode() if self._proc.stderr else ""
                raise RuntimeError(f"mosquitto exited at start: {err}{self.log()}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                    return self
            except OSError:
                time.sleep(0.05)
        raise TimeoutError(f"mosquitto did not listen on {self.port} within {timeout_s} s")

    def stop(self, *, timeout_s: float = 10.0) -> None:
        """SIGTERM: Mosquitto saves its database (retained messages, sessions) and exits."""
        self._end(signal.SIGTERM, timeout_s)

    def pause(self) -> None:
        """SIGSTOP: a hung broker — connections stay open, nothing is answered."""
        if self.running and self._proc is not None:
            self._proc.send_signal(signal.SIGSTOP)

    def kill(self) -> None:
        """SIGKILL: gone without saving anything."""
        self._end(signal.SIGKILL, 10.0)

    def _end(self, sig: int, timeout_s: float) -> None:
        proc = self._proc
        if proc is None or proc.poll() is not None:
            return
        proc.send_signal(sig)
        proc.send_signal(signal.SIGCONT)  # a paused broker handles the signal now
        try:
            proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        if proc.stderr is not None:
            proc.stderr.close()

    def log(self) -> str:
        try:
            return self.log_file.read_text(errors="replace")
        except OSError:
            return ""

    def __enter__(self) -> LocalBroker:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
