"""Test harness for the daemon: panel files for test runs, the ``dsfd run`` subprocess, the DB.

Tests start the real ``dsfd run`` process and talk to it only as an operator or systemd
would: files, signals, stdout (JSON lines), ``$NOTIFY_SOCKET`` and the SQLite database.
Time limits here are hang guards, never assertions.
"""

from __future__ import annotations

import asyncio
import copy
import json
import os
import signal
import socket
import sqlite3
import sys
from collections.abc import Mapping
from datetime import datetime
from pathlib import Path
from typing import Any

import yaml

from dsfd.integrations.mqtt.broker import free_port as free_port  # for the HIL tests

ROOT = Path(__file__).resolve().parents[2]
SUWON = ROOT / "config" / "panels" / "suwon-south.yaml"
#: Start of the simulated clock in the HIL runs: 08:30 local time in Suwon on the clear
#: 2 January (the controller takes over before the sun heats the closed cavity).
MORNING_ISO = "2022-01-01T23:30:00Z"
#: Hang guard for one daemon run [s].
RUN_LIMIT_S = 150.0

#: Settings that keep test cycles short: a 5-step horizon, a small calibration window with
#: an early first update, fast-failing devices (the behaviour under test is unchanged).
FAST: dict[str, Any] = {
    "control": {"horizon_steps": 5},
    "calibration": {"window_h": 1.0, "min_window_h": 0.5, "update_interval_s": 600,
                    "max_nfev": 3},
    "daemon": {"max_predicted_cycles": 1},
}
FAST_DEVICE: dict[str, Any] = {"timeout_s": 0.3, "retries": 0, "reconnect_backoff_min_s": 1.0,
                               "reconnect_backoff_max_s": 60.0}


def _merge(base: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(base)
    for key, value in extra.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def suwon_mapping() -> dict[str, Any]:
    return yaml.safe_load(SUWON.read_text())


def write_panel(path: Path, *, tcp_port: int | None = None, rtu_port: str | None = None,
                station_port: str | None = None, devices: bool = True,
                extra: Mapping[str, Any] | None = None,
                io_extra: Mapping[str, Any] | None = None) -> Path:
    """A copy of the Suwon panel with the devices moved to the test's emulators
    (``io_extra``: more keys of the I/O module's entry, e.g. its ``override_input``)."""
    doc = _merge(suwon_mapping(), FAST)
    # The example panel's schedule is there for the README's dry run; the daemon's tests
    # start from a panel without one (energy only) and add it where they test comfort.
    doc.pop("occupancy", None)
    if not devices:
        doc["devices"] = None
    else:
        io, station = doc["devices"]["entries"]
        io.update(FAST_DEVICE, **(io_extra or {}))
        if rtu_port is not None:
            io.pop("tcp")
            io.update(kind="modbus_rtu", serial={"port": rtu_port, "baudrate": 115200})
        elif tcp_port is not None:
            io["tcp"] = {"host": "127.0.0.1", "port": tcp_port}
        if station_port is not None:
            station["serial"] = {"port": station_port, "baudrate": 9600}
            station["timeout_s"] = 0.05
    if extra:
        doc = _merge(doc, extra)
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


class UntouchedDevice:
    """A listening TCP socket standing in for a Modbus device that nothing may contact."""

    def __init__(self) -> None:
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.listen()
        self._sock.setblocking(False)
        self.port = int(self._sock.getsockname()[1])

    def contacted(self) -> bool:
        """True if a connection arrived (the socket is closed afterwards)."""
        try:
            self._sock.accept()
            return True
        except BlockingIOError:
            return False
        finally:
            self._sock.close()


def dsfd_command(*args: str) -> list[str]:
    return [sys.executable, "-m", "dsfd", *args]


async def run_dsfd(*args: str, env: Mapping[str, str] | None = None,
                   limit_s: float = RUN_LIMIT_S) -> tuple[int, str, str]:
    """Run one ``dsfd`` command to its end: (exit status, stdout, stderr)."""
    proc = await asyncio.create_subprocess_exec(
        *dsfd_command(*args), cwd=ROOT, env={**os.environ, **(env or {})},
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE)
    try:
        async with asyncio.timeout(limit_s):
            out, err = await proc.communicate()
    except TimeoutError:
        proc.kill()
        await proc.wait()
        raise
    return int(proc.returncode or 0), out.decode(), err.decode()


class DaemonProcess:
    """``dsfd run`` as a subprocess; collects its JSON log lines as they arrive."""

    def __init__(self, args: list[str], *, env: Mapping[str, str] | None = None,
                 preexec_fn: Any = None) -> None:
        self.args = args
        self.preexec_fn = preexec_fn
        self.env = {**os.environ, **(env or {}), "PYTHONUNBUFFERED": "1"}
        self.proc: asyncio.subprocess.Process | None = None
        self.records: list[dict[str, Any]] = []
        self.text: list[str] = []
        self.stderr = ""
        self._reader: asyncio.Task[None] | None = None
        self._changed = asyncio.Event()

    async def start(self) -> DaemonProcess:
        self.proc = await asyncio.create_subprocess_exec(
            *dsfd_command(*self.args), cwd=ROOT, env=self.env,
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
            preexec_fn=self.preexec_fn)
        self._reader = asyncio.create_task(self._read())
        return self

    async def _read(self) -> None:
        assert self.proc is not None and self.proc.stdout is not None
        async for raw in self.proc.stdout:
            line = raw.decode("utf-8", "replace").rstrip("\n")
            if line.startswith("{"):
                self.records.append(json.loads(line))
            else:
                self.text.append(line)
            self._changed.set()

    @property
    def cycles_logged(self) -> list[int]:
        """Cycles whose end-of-cycle line was printed (each is committed to the DB first,
        unless the line says ``stored: waiting``)."""
        return [r["cycle"] for r in self.records if r.get("event") == "cycle"]

    def cycle_ended_s(self, cycle: int) -> float:
        """Host time [s, UTC] at which ``cycle``'s line was logged."""
        (stamp,) = [r["timestamp"] for r in self.records
                    if r.get("event") == "cycle" and r["cycle"] == cycle]
        return datetime.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()

    def events(self, name: str) -> list[dict[str, Any]]:
        return [r for r in self.records if r.get("event", "").startswith(name)]

    async def wait_for(self, predicate: Any, *, limit_s: float = RUN_LIMIT_S) -> None:
        """Until ``predicate(self)`` holds (hang guard ``limit_s``)."""
        async with asyncio.timeout(limit_s):
            while not predicate(self):
                if self.proc is not None and self.proc.returncode is not None:
                    raise AssertionError(f"daemon exited early: {self.proc.returncode}\n"
                                         f"{self.stderr_now()}")
                self._changed.clear()
                try:
                    async with asyncio.timeout(0.5):
                        await self._changed.wait()
                except TimeoutError:
                    pass

    async def wait_cycle(self, n: int) -> None:
        await self.wait_for(lambda d: bool(d.cycles_logged) and d.cycles_logged[-1] >= n)

    def signal(self, sig: int) -> None:
        assert self.proc is not None
        self.proc.send_signal(sig)

    async def wait_exit(self, *, limit_s: float = RUN_LIMIT_S) -> int:
        assert self.proc is not None
        try:
            async with asyncio.timeout(limit_s):
                rc = await self.proc.wait()
                if self._reader is not None:
                    await self._reader
                assert self.proc.stderr is not None
                self.stderr = (await self.proc.stderr.read()).decode("utf-8", "replace")
        except TimeoutError:
            self.proc.send_signal(signal.SIGKILL)
            await self.proc.wait()
            raise
        return rc

    def stderr_now(self) -> str:
        return self.stderr


def query(db: Path, sql: str, *params: Any) -> list[tuple[Any, ...]]:
    """Rows of ``sql`` from the daemon's database (opened read-only)."""
    conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        return conn.execute(sql, params).fetchall()
    finally:
        conn.close()
