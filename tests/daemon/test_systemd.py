"""The systemd side: the unit file verifies offline and is hardened; the daemon speaks sd_notify.

The notification test binds a datagram socket as ``$NOTIFY_SOCKET`` (what systemd does for a
``Type=notify`` service) and runs the real ``dsfd run`` process against it.
"""

from __future__ import annotations

import asyncio
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from dsfd.daemon.notify import Notifier
from tests.daemon.harness import ROOT, DaemonProcess, query, write_panel

UNIT = ROOT / "systemd" / "dsfd@.service"
MAX_EXPOSURE = 3.0

needs_systemd_analyze = pytest.mark.skipif(shutil.which("systemd-analyze") is None,
                                           reason="systemd-analyze not installed (.ci/run "
                                           "installs it)")


def concrete_unit(tmp_path: Path) -> Path:
    """``dsfd@test.service`` with ExecStart pointing at this interpreter (it must exist)."""
    text = UNIT.read_text()
    exec_start = f"ExecStart={sys.executable} -m dsfd run --config %E/dsfd/%i.yaml"
    text, n = re.subn(r"^ExecStart=.*$", exec_start, text, flags=re.MULTILINE)
    assert n == 1
    path = tmp_path / "dsfd@test.service"
    path.write_text(text)
    return path


@needs_systemd_analyze
def test_unit_verifies_offline(tmp_path: Path) -> None:
    unit = concrete_unit(tmp_path)
    done = subprocess.run(["systemd-analyze", "verify", "--man=no", str(unit)],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert "Failed to parse" not in done.stderr


@needs_systemd_analyze
def test_unit_exposure_is_at_most_three(tmp_path: Path) -> None:
    unit = concrete_unit(tmp_path)
    done = subprocess.run(["systemd-analyze", "security", "--offline=yes",
                           f"--threshold={round(MAX_EXPOSURE * 10)}", str(unit)],
                          capture_output=True, text=True, check=False)
    found = re.search(r"Overall exposure level for dsfd@test\.service: ([0-9.]+)",
                      done.stdout)
    assert found, done.stdout + done.stderr
    assert float(found.group(1)) <= MAX_EXPOSURE
    assert done.returncode == 0


def test_unit_keeps_serial_ports_reachable_and_is_a_notify_service() -> None:
    settings = dict(line.split("=", 1) for line in UNIT.read_text().splitlines()
                    if "=" in line and not line.startswith("#"))
    assert settings["Type"] == "notify" and settings["NotifyAccess"] == "main"
    assert "PrivateDevices" not in settings  # it would hide /dev/ttyUSB*
    assert settings["SupplementaryGroups"] == "dialout"
    assert settings["StateDirectory"] == "dsfd/%i" and settings["DynamicUser"] == "yes"
    assert settings["Restart"] == "on-failure" and "StartLimitBurst" in settings
    # A bad config (2) and a state directory held by another dsfd (3) are not transient.
    assert settings["RestartPreventExitStatus"].split() == ["2", "3"]


def _datagrams(sock: socket.socket) -> list[str]:
    out = []
    while True:
        try:
            out.append(sock.recv(4096).decode())
        except BlockingIOError:
            return out


@pytest.mark.parametrize("stop", ["cycles", "sigterm"])
def test_daemon_sends_ready_a_watchdog_per_cycle_and_stopping(tmp_path: Path,
                                                              stop: str) -> None:
    """Ended by ``--cycles`` or, as ``systemctl stop`` does, by SIGTERM mid-run: READY, one
    WATCHDOG per cycle, STOPPING last; after SIGTERM the cycle in flight completes and the
    run is marked ended by the signal."""
    address = str(tmp_path / "notify.sock")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(address)
    sock.setblocking(False)
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    cycles = 6

    messages: list[str] = []

    async def scenario() -> int:
        # Read as systemd does, while the daemon runs (a full queue would drop messages).
        asyncio.get_running_loop().add_reader(sock.fileno(),
                                              lambda: messages.extend(_datagrams(sock)))
        limit = cycles if stop == "cycles" else 10_000
        daemon = DaemonProcess(["run", "--config", str(panel), "--dry-run", "--plant", "sim",
                                "--cycles", str(limit), "--state-dir", str(tmp_path / "s")],
                               env={"NOTIFY_SOCKET": address, "WATCHDOG_USEC": "180000000"})
        await daemon.start()
        if stop == "sigterm":
            await daemon.wait_cycle(cycles)
            daemon.signal(signal.SIGTERM)
        rc = await daemon.wait_exit()
        messages.extend(_datagrams(sock))
        return rc

    try:
        assert asyncio.run(scenario()) == 0
    finally:
        sock.close()
    fields = [dict(line.split("=", 1) for line in m.splitlines()) for m in messages]
    assert fields[0].get("READY") == "1"
    (reason, stored), = query(tmp_path / "s" / "timeseries.sqlite",
                              "SELECT end_reason, cycles FROM runs")
    assert reason == ("cycles done" if stop == "cycles" else "signal")
    assert stored >= cycles if stop == "sigterm" else stored == cycles
    assert sum(f.get("WATCHDOG") == "1" for f in fields) == stored
    assert fields[-1].get("STOPPING") == "1"
    # READY comes before the first ping, STOPPING after the last.
    first_ping = next(i for i, f in enumerate(fields) if "WATCHDOG" in f)
    assert first_ping > 0
    assert all("STATUS" in f for f in fields if "READY" in f or "STOPPING" in f)


def test_notifier_speaks_to_abstract_sockets_and_is_silent_without_one(
        monkeypatch: pytest.MonkeyPatch) -> None:
    name = f"dsfd-test-{os.getpid()}"
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind("\0" + name)
    sock.setblocking(False)
    try:
        notifier = Notifier(f"@{name}")
        assert notifier.ready("up") and notifier.watchdog() and notifier.reloading()
        assert notifier.stopping()
        got = _datagrams(sock)
    finally:
        sock.close()
    assert got[0] == "READY=1\nSTATUS=up" and got[1] == "WATCHDOG=1"
    assert got[2].startswith("RELOADING=1\nMONOTONIC_USEC=")
    assert got[3].startswith("STOPPING=1")
    monkeypatch.delenv("NOTIFY_SOCKET", raising=False)
    assert Notifier().ready("up") is False  # no socket: a no-op, not an error
