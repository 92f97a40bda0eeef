"""Crash safety of the state directory, with the real ``dsfd run`` process.

* SIGKILL mid-run, then restart: the database opens cleanly, every cycle the daemon reported
  (it logs a cycle only after committing it) is in the database, and the calibration resumes
  from the state file it saved atomically;
* a corrupt database is moved aside (``*.corrupt.<iso>``) and a new one started.
"""

from __future__ import annotations

import asyncio
import json
import signal
import sqlite3
from pathlib import Path

from dsfd.config import load_panel
from dsfd.daemon.loop import Controller
from dsfd.daemon.runner import RunOptions, serve
from dsfd.sim.daemon_plant import simulated_plant
from tests.daemon.harness import MORNING_ISO, DaemonProcess, query, write_panel


def run_args(panel: Path, state: Path, cycles: int) -> list[str]:
    return ["run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
            "lumped", "--start", MORNING_ISO, "--cycles", str(cycles), "--state-dir", str(state)]


def test_sigkill_mid_run_loses_no_committed_cycle_and_calibration_resumes(
        tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"

    async def first_run() -> list[int]:
        daemon = await DaemonProcess(run_args(panel, state, 5000)).start()
        await daemon.wait_for(lambda d: bool(d.events("calibration updated")))
        updated_at = daemon.events("calibration updated")[0]["cycle"]
        await daemon.wait_cycle(updated_at + 4)
        daemon.signal(signal.SIGKILL)  # no chance to clean up
        assert await daemon.wait_exit() == -signal.SIGKILL
        return daemon.cycles_logged

    logged = asyncio.run(first_run())
    saved = json.loads((state / "calibration.json").read_text())
    assert saved["updates"] >= 1
    # The database opens cleanly after the kill and holds every reported cycle.
    conn = sqlite3.connect(db)
    try:
        assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        stored = {c for (c,) in conn.execute("SELECT cycle FROM decisions WHERE run_id = 1")}
        samples = dict(conn.execute("SELECT cycle, COUNT(*) FROM samples WHERE run_id = 1 "
                                    "GROUP BY cycle").fetchall())
        ended = conn.execute("SELECT ended_utc FROM runs WHERE run_id = 1").fetchone()[0]
    finally:
        conn.close()
    assert set(logged) <= stored
    assert all(samples[c] == samples[logged[0]] > 0 for c in logged)
    assert ended is None  # the killed run never said goodbye

    async def second_run() -> DaemonProcess:
        daemon = await DaemonProcess(run_args(panel, state, 3)).start()
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    daemon = asyncio.run(second_run())
    resumed = [r for r in daemon.records if str(r.get("event", "")).startswith("resumed")]
    assert resumed and f"({saved['updates']} updates)" in resumed[0]["event"]
    assert resumed[0]["theta"]["h_out"] == saved["theta"]["h_out"]
    (source, h_out, f), = query(db, "SELECT source, h_out, f FROM parameters WHERE run_id = 2")
    assert source == "resumed"
    assert (h_out, f) == (saved["theta"]["h_out"], saved["theta"]["f"])
    assert query(db, "SELECT COUNT(*) FROM decisions WHERE run_id = 1")[0][0] == len(stored)
    assert [c for (c,) in query(db, "SELECT cycle FROM decisions WHERE run_id = 2")] == [1, 2, 3]


def test_corrupt_database_is_moved_aside_and_a_new_one_started(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    state.mkdir()
    junk = b"this is not an SQLite database " * 100
    (state / "timeseries.sqlite").write_bytes(junk)

    async def run() -> DaemonProcess:
        daemon = await DaemonProcess(run_args(panel, state, 2)).start()
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    daemon = asyncio.run(run())
    (moved,) = state.glob("timeseries.sqlite.corrupt.*")
    assert moved.read_bytes() == junk
    assert daemon.events("database was unusable")
    db = state / "timeseries.sqlite"
    assert query(db, "SELECT COUNT(*) FROM decisions")[0][0] == 2
    (kind, message), = query(db, "SELECT kind, message FROM events WHERE level = 'error'")
    assert kind == "database_recovered" and moved.name in message


def test_a_database_of_a_newer_dsfd_is_refused_and_left_as_it_is(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    state.mkdir()
    db = state / "timeseries.sqlite"
    with sqlite3.connect(db) as conn:
        conn.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
        conn.execute("INSERT INTO meta VALUES ('schema_version', '999')")
    before = db.read_bytes()

    async def run() -> DaemonProcess:
        daemon = await DaemonProcess(run_args(panel, state, 2)).start()
        assert await daemon.wait_exit() == 1, daemon.stderr
        return daemon

    daemon = asyncio.run(run())
    assert "schema version 999" in daemon.stderr and "newer dsfd" in daemon.stderr
    assert db.read_bytes() == before
    assert not list(state.glob("timeseries.sqlite.corrupt.*"))


def test_a_dry_run_whose_every_cycle_fails_still_stops_after_its_cycles(tmp_path):
    """``--cycles N`` counts failed cycles too: a cycle that raises every time (a bug) is
    logged and the dry run ends after N of them instead of running forever."""
    class Broken(Controller):
        async def _decide(self, *args, **kwargs):
            raise RuntimeError("a bug in the decision")

    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    cfg = load_panel(panel)
    sim = simulated_plant(cfg, cycles=3, seed=1)
    opts = RunOptions(config_path=panel, dry_run=True, plant="sim", plant_fidelity="lumped",
                      cycles=3, seed=1, controller=Broken)
    summary = asyncio.run(asyncio.wait_for(
        serve(opts, cfg, state_dir=tmp_path / "state", plant=sim, print_line=lambda _l: None),
        timeout=120))
    assert summary.cycles == 0  # none completed, and the run ended
