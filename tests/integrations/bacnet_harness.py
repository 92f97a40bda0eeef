"""The BACnet tests' pieces: a panel file with a ``bacnet:`` section on loopback, the daemon's
run arguments, and the third-party client (:mod:`dsfd.bench.bacnet_client`) as a process of
its own.

The device binds 127.0.0.1 on a free UDP port; the client binds 127.0.0.1 on another one.
BACnet/IP broadcasts go to the sender's own port on the subnet's broadcast address, so two
endpoints on one host with different ports cannot reach each other by broadcast: the client
sends its Who-Is and Who-Has to the device's address (unicast, which clause 16.10 allows),
and the device answers the way it answers a broadcast one. A broadcast Who-Is is tested
from a raw socket (test_bacnet.py), which can send to the device's port on 127.255.255.255.
Time limits are hang guards.
"""

from __future__ import annotations

import asyncio
import json
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Awaitable, Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from tests.daemon.harness import ROOT, DaemonProcess, write_panel

#: Hang guard for one answer of the client [s].
ANSWER_LIMIT_S = 30.0
DEVICE_INSTANCE = 41001
START = "2022-01-01T23:30:00Z"  # 08:30 in Suwon, January
SPEED = 240.0


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def bacnet_section(port: int, *, writable: bool, **more: Any) -> dict[str, Any]:
    """A ``bacnet:`` section: the device on 127.0.0.1:``port``."""
    return {"device_instance": DEVICE_INSTANCE, "address": "127.0.0.1", "port": port,
            "writable": writable, **more}


def run_args(panel: Path, state: Path, *, start: str, cycles: int, speed: float) -> list[str]:
    return ["run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
            "lumped", "--start", start, "--cycles", str(cycles), "--speed", str(speed),
            "--state-dir", str(state)]


class BacnetClient:
    """``bacnet_client.py`` in its own process; :meth:`ask` sends one request and returns its
    answer, notifications are collected in :attr:`notifications`, every line in
    :attr:`transcript` (requests as ``>``, answers as ``<``)."""

    def __init__(self, device_port: int, *, bind_port: int | None = None) -> None:
        self.device_port = device_port
        self.bind_port = bind_port or free_udp_port()
        self.cmd = [sys.executable, "-m", "dsfd.bench.bacnet_client", "--bind",
                    f"127.0.0.1:{self.bind_port}",
                    "--device", f"127.0.0.1:{device_port}"]
        self.proc: subprocess.Popen[str] | None = None
        self.answers: queue.Queue[dict[str, Any]] = queue.Queue()
        self.notifications: list[dict[str, Any]] = []
        self.transcript: list[str] = []
        self._next = 0
        self._lock = threading.Lock()

    @property
    def address(self) -> str:
        return f"127.0.0.1:{self.bind_port}"

    def start(self) -> BacnetClient:
        self.proc = subprocess.Popen(self.cmd, cwd=ROOT, stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        threading.Thread(target=self._read, daemon=True).start()
        ready = self.answers.get(timeout=ANSWER_LIMIT_S)
        assert ready.get("ready"), ready
        return self

    def _read(self) -> None:
        assert self.proc is not None and self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._lock:
                self.transcript.append(f"< {line.rstrip()}")
            msg = json.loads(line)
            if "cov" in msg:
                with self._lock:
                    self.notifications.append(msg)
            else:
                self.answers.put(msg)

    def ask(self, op: str, **fields: Any) -> dict[str, Any]:
        assert self.proc is not None and self.proc.stdin is not None
        self._next += 1
        request = {"id": self._next, "op": op, **fields}
        line = json.dumps(request)
        with self._lock:
            self.transcript.append(f"> {line}")
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        answer = self.answers.get(timeout=ANSWER_LIMIT_S)
        assert answer.get("id") == request["id"], (request, answer)
        assert "exception" not in answer, answer
        return answer

    def write(self, obj: str, value: Any, *, priority: int | None = 8, kind: str = "real"
              ) -> Any:
        return self.ask("write", object=obj, value=value, priority=priority,
                        type=kind)["answer"]

    def cov_values(self, obj: str, prop: str = "present-value", *,
                   process: int | None = None) -> list[Any]:
        """Values notified for one object's property (``process``: of that
        SubscribeCOVProperty subscription; None: of the SubscribeCOV ones)."""
        with self._lock:
            return [n["value"] for n in self.notifications
                    if n["cov"] == obj and n["property"] == prop
                    and n.get("process") == process]

    def wait_for(self, predicate: Callable[[BacnetClient], bool], *,
                 limit_s: float = ANSWER_LIMIT_S) -> None:
        deadline = time.monotonic() + limit_s
        while not predicate(self):
            if time.monotonic() > deadline:
                raise AssertionError("the client did not see it in time; last lines:\n"
                                     + "\n".join(self.transcript[-6:]))
            time.sleep(0.05)

    def stop(self) -> str:
        """Quit; the client's stderr (empty unless it failed)."""
        if self.proc is None:
            return ""
        if self.proc.poll() is None:
            assert self.proc.stdin is not None
            try:
                self.proc.stdin.write('{"op": "quit"}\n')
                self.proc.stdin.flush()
                self.proc.wait(10)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait(10)
        assert self.proc.stderr is not None
        return self.proc.stderr.read()


def rpm_values(answer: Mapping[str, Any]) -> dict[tuple[str, str], Any]:
    """(object, property) → value of a ReadPropertyMultiple answer."""
    return {(o, p): v for o, p, _, v in answer["values"]}


def f32(x: float) -> float:
    """A value as a BACnet REAL carries it (IEEE 754 single precision)."""
    return float(np.float32(x))


async def ask(client: BacnetClient, op: str, **fields: Any) -> dict[str, Any]:
    return await asyncio.to_thread(client.ask, op, **fields)


async def write(client: BacnetClient, obj: str, value: Any, **kw: Any) -> Any:
    return await asyncio.to_thread(client.write, obj, value, **kw)


def setup(tmp_path: Path, *, writable: bool, extra: dict[str, Any] | None = None,
          bacnet: dict[str, Any] | None = None
          ) -> tuple[int, Path, Path, Path, BacnetClient]:
    """Device port, panel file, state directory, database and a client (not started);
    ``bacnet``: more keys of the section."""
    port = free_udp_port()
    panel = write_panel(tmp_path / "panel.yaml", devices=False, extra={
        "bacnet": bacnet_section(port, writable=writable, **(bacnet or {})), **(extra or {})})
    state = tmp_path / "state"
    return port, panel, state, state / "timeseries.sqlite", BacnetClient(port)


def run_with_client(panel: Path, state: Path, client: BacnetClient,
                    body: Callable[[DaemonProcess], Awaitable[None]], *,
                    first_cycle: int = 3, speed: float = SPEED,
                    after_stop: Callable[[DaemonProcess], Awaitable[None]] | None = None
                    ) -> DaemonProcess:
    """Run the daemon, start the client at ``first_cycle``, run ``body``, stop the daemon
    with SIGTERM (then ``after_stop``), stop the client; the daemon logged no exception."""

    async def scenario() -> DaemonProcess:
        d = await DaemonProcess(run_args(panel, state, start=START, cycles=2000,
                                         speed=speed)).start()
        await d.wait_cycle(first_cycle)
        await asyncio.to_thread(client.start)
        await body(d)
        d.signal(signal.SIGTERM)
        assert await d.wait_exit() == 0, d.stderr
        if after_stop is not None:
            await after_stop(d)
        return d

    try:
        d = asyncio.run(scenario())
    finally:
        assert client.stop() == ""
    no_exceptions(d)
    return d


def no_exceptions(d: DaemonProcess) -> None:
    bad = [r for r in d.records if "exception" in r or r.get("level") in ("error",
                                                                         "critical")]
    assert not bad, bad[:3]
    assert "Traceback" not in d.stderr


def camel(name: str) -> str:
    """``analog-input,1`` → ``analogInput,1`` (bacpypes3's attribute names)."""
    head, _, rest = name.partition(",")
    parts = head.split("-")
    text = parts[0] + "".join(w.capitalize() for w in parts[1:])
    return f"{text},{rest}" if rest else text
