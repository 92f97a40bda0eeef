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

__all__ = ["LocalBroker", "find_mosquitto", "free_port", "make_test_ca"]

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
    """A TCP port on 127.0.0.1 that was free a moment ago (the tests' devices and brokers)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def make_test_ca(directory: Path) -> tuple[Path, Path, Path]:
    """A throw-away CA and a server certificate for 127.0.0.1 (``openssl`` CLI, EC P-256):
    (ca.pem, server.pem, server.key). For tests and benchmarks only."""
    openssl = shutil.which("openssl")
    if openssl is None:
        raise FileNotFoundError("openssl is not installed (apt-get install openssl)")
    directory.mkdir(parents=True, exist_ok=True)
    ca, ca_key = directory / "ca.pem", directory / "ca.key"
    cert, key, csr = directory / "server.pem", directory / "server.key", directory / "server.csr"
    ext = directory / "server.ext"
    ext.write_text("subjectAltName=IP:127.0.0.1\nbasicConstraints=CA:FALSE\n"
                   "keyUsage=critical,digitalSignature\nextendedKeyUsage=serverAuth\n"
                   "authorityKeyIdentifier=keyid\nsubjectKeyIdentifier=hash\n")
    ec = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]
    for args in (
            ["req", "-x509", *ec, "-keyout", ca_key, "-out", ca, "-days", "2",
             "-subj", "/CN=dsfd test CA", "-addext", "basicConstraints=critical,CA:TRUE",
             "-addext", "keyUsage=critical,keyCertSign,cRLSign"],
            ["req", *ec, "-keyout", key, "-out", csr, "-subj", "/CN=127.0.0.1"],
            ["x509", "-req", "-in", csr, "-CA", ca, "-CAkey", ca_key, "-CAcreateserial",
             "-out", cert, "-days", "2", "-extfile", ext]):
        subprocess.run([openssl, *map(str, args)], check=True, capture_output=True)
    return ca, cert, key


@dataclass
class LocalBroker:
    """Mosquitto with one user; ``start``/``stop``/``kill`` like an operator would.

    With ``tls=True`` a second listener (:attr:`tls_port`) speaks TLS with a certificate of a
    throw-away CA (:attr:`ca_file`).
    """

    directory: Path
    username: str = "dsfd"
    password: str = "s3cret-for-tests"
    port: int = field(default_factory=free_port)
    tls: bool = False
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
            "log_type error\nlog_type warning\nlog_type notice\nlog_type information\n"
            + self._tls_listener())

    def _tls_listener(self) -> str:
        if not self.tls:
            return ""
        self.ca_file, cert, key = make_test_ca(self.directory / "tls")
        self.tls_port = free_port()
        return (f"listener {self.tls_port} 127.0.0.1\ncafile {self.ca_file}\n"
                f"certfile {cert}\nkeyfile {key}\n")

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
