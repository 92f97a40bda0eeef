"""State that survives, with the real ``dsfd run`` process (or ``serve()`` in-process where
the test must reach the clock): one controller per state directory, a corrupt calibration
file, a full disk, a wall-clock step, a restart during a hold, a late optimiser."""

from __future__ import annotations

import asyncio
import dataclasses
import itertools
import json
import resource
import signal
from pathlib import Path

from dsfd.daemon.clock import SimulatedClock
from dsfd.daemon.runner import RunOptions, load_for_run, serve
from dsfd.measured import parse_iso_utc
from dsfd.sim.daemon_plant import plant_for_run
from dsfd.storage.commands import submit
from dsfd.storage.timeseries import Store
from tests.daemon.harness import (
    MORNING_ISO,
    DaemonProcess,
    UntouchedDevice,
    query,
    run_dsfd,
    write_panel,
)


def sim_args(panel: Path, state: Path, cycles: int, *more: str) -> list[str]:
    return ["run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
            "lumped", "--start", MORNING_ISO, "--cycles", str(cycles), "--state-dir",
            str(state), *more]


def run_to_end(panel: Path, state: Path, cycles: int) -> DaemonProcess:
    """A lumped dry run of ``cycles`` cycles that must end by itself with status 0."""
    async def run() -> DaemonProcess:
        daemon = await DaemonProcess(sim_args(panel, state, cycles)).start()
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    return asyncio.run(run())


def test_a_second_daemon_on_the_same_state_directory_exits_3_naming_the_holder(
        tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "sim.yaml", devices=False)
    device = UntouchedDevice()  # the second daemon's I/O module: nothing may connect
    hardware = write_panel(tmp_path / "hw.yaml", tcp_port=device.port)
    state = tmp_path / "state"

    async def scenario() -> tuple[int, str, str, int | None, int]:
        first = await DaemonProcess(sim_args(panel, state, 2000, "--speed", "60")).start()
        try:
            await first.wait_cycle(2)
            rc, out, err = await run_dsfd("run", "--config", str(hardware), "--state-dir",
                                          str(state))
            still_running = first.proc.returncode  # None: the first was never disturbed
            assert first.proc is not None
            pid = first.proc.pid
        finally:
            first.signal(signal.SIGTERM)
            assert await first.wait_exit() == 0
        return rc, out, err, still_running, pid

    rc, _, err, still_running, pid = asyncio.run(scenario())
    connected = device.contacted()
    assert rc == 3
    assert f"in use by PID {pid}" in err and "nothing was opened" in err
    assert still_running is None and not connected
    runs = query(state / "timeseries.sqlite", "SELECT pid FROM runs")
    assert runs == [(pid,)]  # the second one did not even record a run


def test_corrupt_calibration_is_kept_aside_and_resumes_from_the_database(
        tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"

    async def run(args: list[str]) -> DaemonProcess:
        daemon = await DaemonProcess(args).start()
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    # 45 cycles: the first updates come after half an hour of data (harness FAST settings).
    asyncio.run(run(sim_args(panel, state, 45)))
    (newest,) = query(db, "SELECT h_out, h_in, f, other FROM parameters WHERE source = "
                      "'online' ORDER BY time_s DESC LIMIT 1")
    garbage = b'{"schema": "dsfd.calibration-state", "theta": {"h_out": '  # torn
    (state / "calibration.json").write_bytes(garbage)
    daemon = asyncio.run(run(sim_args(panel, state, 2)))
    (kept,) = state.glob("calibration.json.corrupt.*")
    assert kept.read_bytes() == garbage
    (source, h_out, h_in, f, other, detail), = query(
        db, "SELECT source, h_out, h_in, f, other, detail FROM parameters WHERE run_id = 2")
    assert source == "database"
    assert (h_out, h_in, f, json.loads(other)) == (newest[0], newest[1], newest[2],
                                                   json.loads(newest[3]))
    (message,), = query(db, "SELECT message FROM events WHERE run_id = 2 AND "
                        "kind = 'calibration_recovered'")
    assert kept.name in message and "resumed from the database" in message
    assert detail == message
    assert any("calibration state unusable" in r.get("event", "") for r in daemon.records)
    # Without any history in the database, the priors (and it says so).
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    (fresh / "calibration.json").write_text("[]")
    asyncio.run(run(sim_args(panel, fresh, 1)))
    (source, message), = query(fresh / "timeseries.sqlite", "SELECT p.source, e.message "
                               "FROM parameters p JOIN events e USING (run_id) WHERE "
                               "e.kind = 'calibration_recovered'")
    assert source == "prior" and "starting from the priors" in message
    assert list(fresh.glob("calibration.json.corrupt.*"))


def test_a_full_disk_does_not_stop_control_and_rows_come_later_or_are_counted(
        tmp_path: Path) -> None:
    buffer_cycles = 4
    panel = write_panel(tmp_path / "panel.yaml", devices=False,
                        extra={"daemon": {"store_buffer_cycles": buffer_cycles}})
    state = tmp_path / "state"
    wal = state / "timeseries.sqlite-wal"
    marks: dict[str, int] = {}

    async def scenario() -> DaemonProcess:
        daemon = await DaemonProcess(sim_args(panel, state, 400, "--speed", "240")).start()
        assert daemon.proc is not None
        pid = daemon.proc.pid
        try:
            await daemon.wait_cycle(4)
            # The disk is full: no file of the daemon may grow beyond its size now.
            limit = wal.stat().st_size
            resource.prlimit(pid, resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))
            marks["full"] = daemon.cycles_logged[-1]
            await daemon.wait_for(lambda d: sum(bool(r.get("stored")) for r in
                                                d.events("cycle")) >= buffer_cycles + 3)
            resource.prlimit(pid, resource.RLIMIT_FSIZE,
                             (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
            marks["space"] = daemon.cycles_logged[-1]
            await daemon.wait_cycle(marks["space"] + 3)
        finally:
            daemon.signal(signal.SIGTERM)
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    daemon = asyncio.run(scenario())
    db = state / "timeseries.sqlite"
    logged = daemon.cycles_logged
    assert logged == list(range(1, len(logged) + 1))  # it kept cycling, none failed
    waiting = [r["cycle"] for r in daemon.events("cycle") if r.get("stored")]
    assert waiting and min(waiting) > marks["full"] and max(waiting) <= marks["space"] + 1
    stored = {c for (c,) in query(db, "SELECT cycle FROM decisions")}
    missing = sorted(set(logged) - stored)
    # What the buffer could not keep is exactly what is missing, and the event says so: it
    # holds buffer_cycles cycles, the one that found space again included.
    assert len(missing) == len(waiting) + 1 - buffer_cycles
    assert missing == sorted(waiting)[:len(missing)]
    events = dict(query(db, "SELECT kind, message FROM events WHERE kind LIKE 'store_%'"))
    assert events["store_rows_lost"].startswith(f"{len(missing)} cycle(s) could not be kept")
    assert f"cycles {missing[0]}-{missing[-1]}" in events["store_rows_lost"]
    assert f"from cycle {min(waiting)}" in events["store_recovered"]
    # The late rows are whole cycles: every signal sampled, written in cycle order.
    late = sorted(set(waiting) - set(missing))
    counts = dict(query(db, "SELECT cycle, COUNT(*) FROM samples GROUP BY cycle"))
    assert {counts[c] for c in late} == {counts[1]}
    (reason,), = query(db, "SELECT end_reason FROM runs")
    assert reason == "signal"


def test_a_wall_clock_step_moves_neither_the_grid_nor_the_stored_order(
        tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    cfg = load_for_run(panel, simulated_plant=True, dry_run=True)
    opts = RunOptions(config_path=panel, dry_run=True, plant="sim", plant_fidelity="lumped",
                      cycles=10, start_s=parse_iso_utc(MORNING_ISO))
    plant = plant_for_run(cfg, opts)
    clock = SimulatedClock(start_utc_s=plant.start_s)

    def step(out) -> None:  # NTP steps the clock between cycles
        if out.cycle == 4:
            clock.step_wall(-3600.0)
        elif out.cycle == 7:
            clock.step_wall(+1800.0)

    state = tmp_path / "state"
    summary = asyncio.run(serve(dataclasses.replace(opts, on_cycle=step), cfg,
                                state_dir=state, plant=plant, clock=clock,
                                print_line=lambda _: None))
    assert summary.cycles == 10
    db = state / "timeseries.sqlite"
    rows = query(db, "SELECT cycle, slot, time_s, run_elapsed_s FROM decisions ORDER BY cycle")
    assert [r[1] for r in rows] == list(range(10))  # the grid: no slot skipped or repeated
    assert [r[3] for r in rows] == [60.0 * k for k in range(10)]
    gaps = [round(b[2] - a[2]) for a, b in itertools.pairwise(rows)]
    assert gaps == [60, 60, 60, 60 - 3600, 60, 60, 60 + 1800, 60, 60]
    steps = query(db, "SELECT cycle, message FROM events WHERE kind = 'clock_step'")
    assert [c for c, _ in steps] == [5, 8]
    assert "-3600.0 s" in steps[0][1] and "+1800.0 s" in steps[1][1]
    assert "calibration record restarts" in steps[0][1]


def test_a_hold_survives_a_restart(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"

    Store.open(state).close()  # the database the service would have created
    # Queued the way the CLI queues it (the CLI itself insists on a running daemon).
    cid = submit(db, kind="override", args={"hold": "2h", "louver_deg": 54},
                 source="cli", requester="test@host")
    run_to_end(panel, state, 3)
    daemon = run_to_end(panel, state, 3)
    rows = query(db, "SELECT run_id, cycle, method, phi_deg, hold_source, hold_command_id, "
                 "hold_expires_s, write_status FROM decisions ORDER BY run_id, cycle")
    assert [r[:2] for r in rows] == [(1, 1), (1, 2), (1, 3), (2, 1), (2, 2), (2, 3)]
    assert all(r[2] == "manual" and r[4:6] == ("operator", cid) for r in rows)
    assert len({r[6] for r in rows}) == 1  # the same expiry after the restart
    assert [r[7] for r in rows] == ["verified", "held", "held", "held", "held", "held"]
    assert [r[3] for r in rows[:3]] == [54.0] * 3
    # After the restart it is held where the actuators are (a new simulated plant here):
    # a restart never moves the panel.
    assert len({r[3] for r in rows[3:]}) == 1
    (message,), = query(db, "SELECT message FROM events WHERE kind = 'hold_restored'")
    assert "operator hold" in message
    assert any("hold of the previous run restored" in r.get("event", "")
               for r in daemon.records)


def test_an_occupancy_override_survives_a_restart(tmp_path: Path) -> None:
    """Issue 36: queued as the CLI queues it, applied in the first run, taken over by the
    second until its time (10:00 local; both runs simulate 08:30-08:33 local)."""
    panel = write_panel(tmp_path / "panel.yaml", devices=False,
                        extra={"occupancy": {"sun": ["08:00-18:00"]}})
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"

    Store.open(state).close()
    cid = submit(db, kind="occupancy", args={"state": "unoccupied", "until": "10:00"},
                 source="cli", requester="test@host")
    run_to_end(panel, state, 3)
    daemon = run_to_end(panel, state, 3)
    rows = query(db, "SELECT d.run_id, d.cycle, d.occupancy_override, d.occupancy_until_s, "
                 "d.occupancy_command_id, c.occupied, c.occupancy_source FROM decisions d "
                 "JOIN comfort c USING (run_id, cycle) ORDER BY run_id, cycle")
    ten_local_s = parse_iso_utc("2022-01-02T01:00:00Z")  # 10:00 at UTC+9
    assert [r[:2] for r in rows] == [(1, 1), (1, 2), (1, 3), (2, 1), (2, 2), (2, 3)]
    assert {r[2:] for r in rows} == {("unoccupied", ten_local_s, cid, 0, "override")}
    (message,), = query(db, "SELECT message FROM events WHERE kind = 'occupancy_restored'")
    assert "unoccupied until 2022-01-02T01:00:00Z" in message
    assert any("occupancy override of the previous run restored" in r.get("event", "")
               for r in daemon.records)


def test_a_late_optimiser_hands_over_to_the_baseline(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False,
                        extra={"control": {"time_budget_s": 0.0001}})
    state = tmp_path / "state"

    async def run() -> DaemonProcess:
        daemon = await DaemonProcess(sim_args(panel, state, 4)).start()
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    asyncio.run(run())
    rows = query(state / "timeseries.sqlite", "SELECT method, fallback_reason, write_status "
                 "FROM decisions ORDER BY cycle")
    assert len(rows) == 4 and all(m == "rule" and w == "verified" for m, _, w in rows)
    reasons = {f for _, f, _ in rows}
    assert reasons <= {"optimisation exceeded its budget of 0.0001 s",
                       "previous optimisation still running"}, reasons


def test_status_and_commands_need_no_lock_and_refuse_without_a_daemon(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"

    async def scenario() -> dict[str, tuple[int, str, str]]:
        out: dict[str, tuple[int, str, str]] = {}
        out["none"] = await run_dsfd("status", "--state-dir", str(state))
        daemon = await DaemonProcess(sim_args(panel, state, 2)).start()
        assert await daemon.wait_exit() == 0
        out["stopped"] = await run_dsfd("status", "--config", str(panel), "--state-dir",
                                        str(state))
        out["override"] = await run_dsfd("override", "--config", str(panel), "--state-dir",
                                         str(state), "--hold", "1h")
        out["mode"] = await run_dsfd("mode", "--config", str(panel), "--state-dir",
                                     str(state), "cooling")
        out["bad mode"] = await run_dsfd("mode", "--config", str(panel), "--state-dir",
                                         str(state), "summer")
        return out

    got = asyncio.run(scenario())
    rc, _, err = got["none"]
    assert rc == 1 and "no database" in err
    rc, text, _ = got["stopped"]
    assert rc == 3 and "daemon not running" in text and "last cycle:  2 at" in text
    rc, _, err = got["override"]
    assert rc == 3 and "no daemon is running" in err and "nothing was queued" in err
    rc, _, err = got["mode"]
    assert rc == 3 and "no daemon is running" in err
    rc, _, err = got["bad mode"]  # the request is checked before anything else
    assert rc == 2 and "OBJECTIVE summer: expected one of heating, cooling, auto" in err
    assert query(state / "timeseries.sqlite", "SELECT COUNT(*) FROM commands") == [(0,)]
