"""The operator commands as an operator runs them: another user than the daemon's, with the
access docs/operating.md describes for a group-shared state directory (the unit's static-user
drop-in: ``StateDirectoryMode=0770``, ``UMask=0007``, the operator in the daemon's group).

The daemon runs as root here with the group-shared umask; ``dsfd status``/``override`` run
as an unprivileged user in the directory's group (``setpriv``), through the system Python of
the same version with this checkout on ``PYTHONPATH``. A user outside the group is refused
with a message naming the way in. Needs root (to switch users) and ``setpriv``.
"""

from __future__ import annotations

import asyncio
import json
import os
import shutil
import signal
import sysconfig
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.daemon.harness import MORNING_ISO, ROOT, DaemonProcess, query, write_panel

OPERATOR_UID, OUTSIDER_UID, GROUP = 65530, 65531, 65534
SYSTEM_PYTHON = Path(f"/usr/bin/python{os.sys.version_info[0]}.{os.sys.version_info[1]}")

pytestmark = pytest.mark.skipif(
    os.geteuid() != 0 or shutil.which("setpriv") is None or not SYSTEM_PYTHON.exists(),
    reason="needs root, setpriv and a system Python of this version to act as another user")


@pytest.fixture
def shared() -> Iterator[Path]:
    """A directory other users can reach (pytest's own tmp dirs are private)."""
    path = Path(tempfile.mkdtemp(prefix="dsfd-operator-"))
    path.chmod(0o755)
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)


async def as_user(uid: int, gid: int, *args: str) -> tuple[int, str, str]:
    env = {"PYTHONPATH": f"{ROOT}:{sysconfig.get_paths()['purelib']}", "LOGNAME": f"u{uid}",
           "PATH": "/usr/bin:/bin", "HOME": "/nonexistent"}
    proc = await asyncio.create_subprocess_exec(
        "setpriv", f"--reuid={uid}", f"--regid={gid}", "--clear-groups", str(SYSTEM_PYTHON),
        "-m", "dsfd", *args, cwd="/", env=env, stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE)
    async with asyncio.timeout(120):
        out, err = await proc.communicate()
    return int(proc.returncode or 0), out.decode(), err.decode()


def test_an_operator_in_the_daemons_group_can_ask_and_command(shared: Path) -> None:
    panel = write_panel(shared / "panel.yaml", devices=False)
    panel.chmod(0o644)
    state = shared / "state"
    state.mkdir()
    os.chown(state, 0, GROUP)
    state.chmod(0o2770)  # setgid: the daemon's files belong to the group
    got: dict[str, tuple[int, str, str]] = {}

    async def scenario() -> DaemonProcess:
        daemon = await DaemonProcess(
            ["run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
             "lumped", "--speed", "60", "--start", MORNING_ISO, "--cycles", "2000",
             "--state-dir", str(state)], preexec_fn=lambda: os.umask(0o007)).start()
        try:
            await daemon.wait_cycle(2)
            got["status"] = await as_user(OPERATOR_UID, GROUP, "status", "--state-dir",
                                          str(state), "--json")
            got["override"] = await as_user(OPERATOR_UID, GROUP, "override", "--config",
                                            str(panel), "--state-dir", str(state), "--hold",
                                            "45min")
            got["held"] = await as_user(OPERATOR_UID, GROUP, "status", "--config", str(panel),
                                        "--state-dir", str(state))
            got["outsider"] = await as_user(OUTSIDER_UID, OUTSIDER_UID, "status",
                                            "--state-dir", str(state))
        finally:
            daemon.signal(signal.SIGTERM)
        assert await daemon.wait_exit() == 0, daemon.stderr
        got["stopped"] = await as_user(OPERATOR_UID, GROUP, "status", "--state-dir",
                                       str(state))
        return daemon

    daemon = asyncio.run(scenario())
    rc, out, err = got["status"]
    assert rc == 0, err
    status = json.loads(out)
    assert status["daemon"] == {"running": True, "pid": daemon.proc.pid,
                                "lock": str(state / "dsfd.lock")}
    rc, out, err = got["override"]
    assert rc == 0 and "applied" in out, err
    (source, requester, status_), = query(state / "timeseries.sqlite",
                                          "SELECT source, requester, status FROM commands")
    assert (source, status_) == ("cli", "applied") and requester.startswith(f"u{OPERATOR_UID}@")
    rc, out, _ = got["held"]
    assert rc == 0 and "hold:        operator by cli u65530@" in out
    rc, _, err = got["outsider"]
    assert rc == 4 and "permission denied" in err.lower() and "sudo" in err
    # After the stop no -wal/-shm is left; the operator still reads the database.
    rc, out, err = got["stopped"]
    assert rc == 3 and "daemon not running" in out, err
    assert {p.stat().st_gid for p in state.iterdir()} == {GROUP}
