"""The manual hold and operator commands as pure logic: validation against the panel, the hold
tracker (detection, input, commands, expiry on the monotonic grid, daily reset) and the hold
stage of the safety pipeline (wind first, nothing written while held in place)."""

from __future__ import annotations

import dataclasses

import pytest

from dsfd.config import load_panel
from dsfd.daemon.commands import CommandError, OperatorCommand, parse_duration, validate_command
from dsfd.daemon.hold import Hold, HoldTracker, PendingCommand, hold_seconds, moved_actuators
from dsfd.daemon.safety import SafetyContext, SafetyPipeline
from dsfd.drivers.base import Command
from tests.conftest import PANELS

#: 2022-01-02 00:00 UTC = 09:00 in Suwon (UTC+9).
T0 = 1_641_081_600.0


@pytest.fixture
def cfg():
    return load_panel(PANELS / "suwon-south.yaml")


def with_safety(cfg, **changes):
    return dataclasses.replace(cfg, safety=dataclasses.replace(cfg.safety, **changes))


# ------------------------------------------------------------------ validation
def test_a_valid_override_and_resume(cfg) -> None:
    cmd = validate_command(cfg, {"command": "override", "hold": "1h30m", "louver_deg": -36,
                                 "regime": 3, "or_pct": 40})
    assert cmd == OperatorCommand("override", hold_s=5400.0, phi_deg=-36.0, afr=3, or_pct=40.0)
    assert validate_command(cfg, {"command": "override"}) == OperatorCommand("override")
    # Regime 10 closes every damper: the opening follows.
    assert validate_command(cfg, {"command": "override", "regime": 10}).or_pct == 0.0
    assert validate_command(cfg, {"command": "resume"}) == OperatorCommand("resume")
    assert validate_command(cfg, {"command": "mode", "mode": "cooling"}) == \
        OperatorCommand("mode", mode="cooling")


@pytest.mark.parametrize("request_, field, words", [
    ({"command": "override", "louver_deg": 45}, "louver_deg", "nearest: 36 or 54"),
    ({"command": "override", "louver_deg": float("nan")}, "louver_deg", "finite number"),
    ({"command": "override", "louver_deg": True}, "louver_deg", "finite number"),
    ({"command": "override", "regime": 11}, "regime", "1..10"),
    ({"command": "override", "regime": 2.5}, "regime", "1..10"),
    ({"command": "override", "or_pct": 42.5}, "or_pct", "1 % steps"),
    ({"command": "override", "or_pct": 120}, "or_pct", "outside 0..100"),
    ({"command": "override", "regime": 10, "or_pct": 30}, "or_pct", "regime 10 closes"),
    ({"command": "override", "hold": "soon"}, "hold", "duration"),
    ({"command": "override", "hold": "10s"}, "hold", "between 1 min and 168 h"),
    ({"command": "override", "hold": "8d"}, "hold", "between"),
    ({"command": "override", "speed": 3}, "speed", "unknown field for override"),
    ({"command": "resume", "hold": "2h"}, "hold", "resume takes no other fields"),
    ({"command": "explode"}, "command", "override, resume, mode"),
    ({"command": "override", "louver_deg": 10**400}, "louver_deg", "finite number"),
    ({"command": "override", "regime": -10**400}, "regime", "finite number"),
    ({"command": "override", "or_pct": 10**400}, "or_pct", "finite number"),
    ({"command": "mode", "mode": "summer"}, "mode", "heating, cooling, auto"),
    ({"command": "mode"}, "mode", "heating, cooling, auto"),
    ({"command": "mode", "mode": ["auto"]}, "mode", "heating, cooling, auto"),
    ({"command": "mode", "mode": "auto", "hold": "2h"}, "hold", "unknown field for mode"),
])
def test_malformed_requests_name_the_field_and_the_value(cfg, request_, field, words) -> None:
    with pytest.raises(CommandError) as err:
        validate_command(cfg, request_)
    assert err.value.field == field and words in str(err.value)
    shown = repr(request_.get(field))
    assert (shown if len(shown) <= 120 else shown[:100]) in str(err.value)


def test_panel_limits_and_missing_parts_are_checked(cfg) -> None:
    narrow = with_safety(cfg, phi_min_deg=-54.0, phi_max_deg=54.0)
    with pytest.raises(CommandError, match=r"outside the louver limits -54\.\.54"):
        validate_command(narrow, {"command": "override", "louver_deg": 72})
    no_louver = dataclasses.replace(cfg, louver=None)
    with pytest.raises(CommandError, match="no louver"):
        validate_command(no_louver, {"command": "override", "louver_deg": 0})
    no_exterior = dataclasses.replace(cfg, openings=dataclasses.replace(
        cfg.openings, exterior_bottom=None, exterior_top=None))
    with pytest.raises(CommandError, match=r"exterior_bottom, exterior_top.*available: 1, 2, "
                       r"10"):
        validate_command(no_exterior, {"command": "override", "regime": 3})


def test_durations() -> None:
    assert parse_duration("2h") == 7200.0 and parse_duration("90min") == 5400.0
    assert parse_duration("1h 30m") == 5400.0 and parse_duration("45") == 2700.0
    assert parse_duration(15) == 900.0 and parse_duration("1d") == 86400.0
    for bad in ("", "2 hours", "h", "-5m", None, 10**400):
        with pytest.raises(ValueError):
            parse_duration(bad)


# ------------------------------------------------------------------ the tracker
def test_detection_needs_a_move_beyond_the_motor_grid_and_the_dead_band(cfg) -> None:
    here = Command(phi_deg=18.0, afr=3, or_pct=50.0)
    assert moved_actuators(cfg, Command(phi_deg=26.0, afr=3, or_pct=54.0), here) == []
    assert moved_actuators(cfg, Command(phi_deg=27.0, afr=3, or_pct=50.0), here) == ["phi_deg"]
    assert moved_actuators(cfg, Command(phi_deg=18.0, afr=4, or_pct=56.0), here) == [
        "afr", "or_pct"]


def test_a_detected_hold_lasts_manual_hold_min_on_the_monotonic_grid(cfg) -> None:
    cfg = with_safety(cfg, manual_hold_min=5.0)
    tracker = HoldTracker(cfg)
    ours = Command(phi_deg=18.0, afr=3, or_pct=50.0)
    person = Command(phi_deg=-54.0, afr=3, or_pct=50.0)
    up = tracker.update(now_mono_s=0.0, now_s=T0, read_back=person, expected=ours,
                        input_active=None)
    assert up.moved == ["phi_deg"] and up.adopted and up.hold is not None
    assert (up.hold.source, up.hold.position, up.hold.expires_s) == ("detected", person,
                                                                     T0 + 300.0)
    assert [k for _, k, _ in up.events] == ["manual_override", "hold_started"]
    # The wall clock steps back an hour: the hold still ends after 5 minutes of grid time.
    for k in range(1, 5):
        up = tracker.update(now_mono_s=60.0 * k, now_s=T0 - 3600 + 60 * k, read_back=person,
                            expected=person, input_active=None)
        assert up.hold is not None and not up.events
    up = tracker.update(now_mono_s=300.0, now_s=T0 - 3300, read_back=person, expected=person,
                        input_active=None)
    assert up.hold is None and "held for 5 min" in up.events[0][2]


def test_the_daily_reset_cuts_a_default_hold_but_not_an_explicit_one(cfg) -> None:
    cfg = with_safety(cfg, manual_hold_min=120.0, manual_reset_local="10:00")
    # 09:00 local: the reset comes after one hour.
    assert hold_seconds(cfg, now_s=T0, requested_s=None) == (3600.0, "reset")
    assert hold_seconds(cfg, now_s=T0, requested_s=3 * 3600.0) == (10800.0, "time")
    assert hold_seconds(cfg, now_s=T0 + 7200, requested_s=None) == (7200.0, "time")
    tracker = HoldTracker(cfg)
    up = tracker.update(now_mono_s=0.0, now_s=T0, read_back=Command(phi_deg=90.0, afr=10,
                                                                    or_pct=0.0),
                        expected=Command(phi_deg=0.0, afr=10, or_pct=0.0), input_active=None)
    assert up.hold.expires_s == T0 + 3600.0
    up = tracker.update(now_mono_s=3600.0, now_s=T0 + 3600, read_back=None, expected=None,
                        input_active=None)
    assert up.hold is None and "daily reset at 10:00" in up.events[0][2]


def test_the_input_holds_while_set_and_outranks_operator_commands(cfg) -> None:
    tracker = HoldTracker(cfg)
    here = Command(phi_deg=0.0, afr=1, or_pct=30.0)
    up = tracker.update(now_mono_s=0.0, now_s=T0, read_back=here, expected=here,
                        input_active=True, input_where="io coil 3")
    assert up.hold.source == "input" and up.hold.expires_s is None and up.adopted
    cmds = [PendingCommand(1, OperatorCommand("override", phi_deg=36.0), "cli", "a@b"),
            PendingCommand(2, OperatorCommand("resume"), "cli", "a@b")]
    up = tracker.update(now_mono_s=1e6, now_s=T0 + 1e6, read_back=here, expected=here,
                        input_active=True, commands=cmds)
    assert up.hold.source == "input"  # no expiry for an input hold
    assert [(c, s) for c, s, _ in up.results] == [(1, "rejected"), (2, "rejected")]
    assert "io coil 3" in up.results[0][2]
    up = tracker.update(now_mono_s=1e6 + 60, now_s=T0, read_back=here, expected=here,
                        input_active=None)  # unreadable: nothing changes
    assert up.hold is not None
    up = tracker.update(now_mono_s=1e6 + 120, now_s=T0, read_back=here, expected=here,
                        input_active=False)
    assert up.hold is None and "released" in up.events[0][2]


def test_operator_commands_merge_positions_and_the_latest_action_wins(cfg) -> None:
    tracker = HoldTracker(cfg)
    here = Command(phi_deg=0.0, afr=3, or_pct=60.0)
    override = OperatorCommand("override", hold_s=3600.0, afr=10, or_pct=0.0)
    up = tracker.update(now_mono_s=0.0, now_s=T0, read_back=here, expected=here,
                        input_active=None,
                        commands=[PendingCommand(7, override, "cli", "alice@host")])
    assert up.hold.position == Command(phi_deg=0.0, afr=10, or_pct=0.0)
    assert (up.hold.source, up.hold.command_id, up.hold.expires_s) == ("operator", 7,
                                                                       T0 + 3600)
    assert up.results == [(7, "applied", up.results[0][2])] and not up.adopted
    # A person moves it during the operator hold: a detected hold replaces it.
    closed = up.hold.position
    moved = Command(phi_deg=72.0, afr=10, or_pct=0.0)
    up = tracker.update(now_mono_s=60.0, now_s=T0 + 60, read_back=moved, expected=closed,
                        input_active=None)
    assert up.hold.source == "detected" and up.hold.position == moved
    # A malformed command is answered and changes nothing; resume ends the hold.
    bad = CommandError("regime", 11, "expected an airflow regime 1..10")
    up = tracker.update(now_mono_s=120.0, now_s=T0 + 120, read_back=moved, expected=moved,
                        input_active=None,
                        commands=[PendingCommand(8, bad, "mqtt", "bms"),
                                  PendingCommand(9, OperatorCommand("resume"), "cli", "a@b")])
    assert up.hold is None
    assert up.results[0] == (8, "rejected", "regime: 11: expected an airflow regime 1..10")
    assert up.results[1][:2] == (9, "applied")
    # Without a read-back an override needs all three positions.
    up = tracker.update(now_mono_s=180.0, now_s=T0 + 180, read_back=None, expected=None,
                        input_active=None,
                        commands=[PendingCommand(10, OperatorCommand("override", afr=1),
                                                 "cli", "a@b")])
    assert up.hold is None and up.results[0][1] == "rejected"
    assert "give louver_deg, regime and or_pct" in up.results[0][2]


# ------------------------------------------------------------------ the hold stage
def held(source: str, position: Command | None) -> Hold:
    return Hold(source, position, T0, T0 + 3600, 3600.0)


def test_held_in_place_nothing_is_written_and_the_stages_leave_it_alone(cfg) -> None:
    p = SafetyPipeline(cfg)
    person = Command(phi_deg=45.0, afr=3, or_pct=37.0)  # off the grid: a person's choice
    ctx = SafetyContext(now_s=0.0, wind_speed_ms=3.0, current=person,
                        bad_signals=frozenset({"t_out_c"}), hold=held("detected", person),
                        no_decision_reason="required weather not GOOD")
    out = p.apply(None, ctx)
    assert out.held and not out.write and not out.faulted and out.command == person
    assert [t.stage for t in out.trace] == ["wind", "hold", "faults", "limits",
                                            "quantisation", "rate", "regimes"]
    assert all("manual hold" in t.why for t in out.trace[2:])


def test_wind_acts_during_a_hold_and_the_held_position_comes_back(cfg) -> None:
    p = SafetyPipeline(with_safety(cfg, wind_release_cycles=1))
    person = Command(phi_deg=-36.0, afr=3, or_pct=50.0)  # exterior dampers open
    hold = held("detected", person)
    gale = p.apply(None, SafetyContext(now_s=0.0, wind_speed_ms=25.0, current=person,
                                       hold=hold))
    assert gale.write and gale.held and gale.wind_override
    assert gale.command == Command(phi_deg=cfg.safety.wind_safe_angle_deg, afr=10, or_pct=0.0)
    calm = p.apply(None, SafetyContext(now_s=60.0, wind_speed_ms=2.0, current=gale.command,
                                       hold=hold))
    assert calm.write and calm.command == person  # restored, still held
    still = p.apply(None, SafetyContext(now_s=120.0, wind_speed_ms=2.0, current=person,
                                        hold=hold))
    assert not still.write and still.command == person
    # An operator's positions are written once, then held.
    target = Command(phi_deg=54.0, afr=10, or_pct=0.0)
    first = p.apply(None, SafetyContext(now_s=180.0, wind_speed_ms=2.0, current=person,
                                        hold=held("operator", target)))
    assert first.write and first.command == target


def test_commands_are_read_from_the_table_once_and_stale_ones_expire(cfg, tmp_path) -> None:
    import time

    from dsfd.daemon.manual import ManualStage
    from dsfd.storage.commands import MAX_AGE_S, submit
    from dsfd.storage.timeseries import Store

    store = Store.open(tmp_path)
    store.begin_run(panel=cfg.panel.id, mode="test", version="0", config_path=None)
    old = submit(store.path, kind="override", args={}, source="cli", requester="a@b",
                 now_s=time.time() - MAX_AGE_S - 60)
    bad = submit(store.path, kind="override", args={"louver_deg": 45}, source="mqtt",
                 requester="bms")
    ok = submit(store.path, kind="override", args={"hold": "1h"}, source="cli",
                requester="a@b")
    stage = ManualStage(cfg, store)
    here = Command(phi_deg=0.0, afr=10, or_pct=0.0)
    up = stage.update(now_mono_s=0.0, now_s=T0, read_back=here, expected=here,
                      input_active=None, input_where="")
    stage.handled(up.results)
    assert [(c, s) for c, s, _ in up.results] == [(old, "rejected"), (bad, "rejected"),
                                                  (ok, "applied")]
    assert "expired" in up.results[0][2] and "nearest: 36 or 54" in up.results[1][2]
    # Not yet stored (e.g. a full disk): the next cycle does not apply them again.
    again = stage.update(now_mono_s=60.0, now_s=T0 + 60, read_back=here, expected=here,
                         input_active=None, input_where="")
    assert again.results == [] and again.hold is not None
    store.close()


def test_an_operators_objective_lasts_until_the_file_changes_and_survives_a_restart(
        cfg, tmp_path) -> None:
    from dsfd.daemon.manual import ManualStage
    from dsfd.storage.commands import submit
    from dsfd.storage.timeseries import Store

    assert cfg.control.mode == "auto"
    store = Store.open(tmp_path)
    store.begin_run(panel=cfg.panel.id, mode="test", version="0", config_path=None)
    held = submit(store.path, kind="override", args={"hold": "1h"}, source="cli",
                  requester="a@b")
    cooling = submit(store.path, kind="mode", args={"mode": "cooling"}, source="mqtt",
                     requester="127.0.0.1:1883 dsfd/p/cmd/mode")
    stage = ManualStage(cfg, store)
    assert stage.objective_mode == ("auto", None)
    here = Command(phi_deg=0.0, afr=10, or_pct=0.0)
    up = stage.update(now_mono_s=0.0, now_s=T0, read_back=here, expected=here,
                      input_active=None, input_where="")
    stage.handled(up.results)
    # Both applied: the objective is no hold and the hold no objective.
    assert [(c, s) for c, s, _ in up.results] == [(held, "applied"), (cooling, "applied")]
    assert "control objective cooling (was auto, the panel file's control.mode)" in \
        up.results[1][2]
    assert up.hold is not None and up.hold.source == "operator"
    assert stage.objective_mode == ("cooling", cooling)
    assert [k for _, k, _ in up.events][-1] == "mode_set"
    # A reload that leaves control.mode alone keeps it; one that changes it ends it.
    stage.reconfigure(dataclasses.replace(cfg, safety=cfg.safety))
    assert stage.objective_mode == ("cooling", cooling)
    heating_file = dataclasses.replace(cfg, control=dataclasses.replace(cfg.control,
                                                                        mode="heating"))
    stage.reconfigure(heating_file)
    assert stage.objective_mode == ("heating", None)
    up = stage.update(now_mono_s=60.0, now_s=T0 + 60, read_back=here, expected=here,
                      input_active=None, input_where="")
    assert [k for _, k, _ in up.events] == ["mode_ended"]
    # A restart keeps the operator's objective unless the file's control.mode changed since.
    last = {"objective_mode": "cooling", "mode_command_id": cooling}
    again = ManualStage(cfg, store)
    assert again.restore_mode(last, file_mode_then="auto") is not None
    assert again.objective_mode == ("cooling", cooling)
    edited = ManualStage(heating_file, store)
    assert edited.restore_mode(last, file_mode_then="auto") is None
    assert edited.objective_mode == ("heating", None)
    assert ManualStage(cfg, store).restore_mode({"objective_mode": "auto",
                                                 "mode_command_id": None},
                                                file_mode_then="auto") is None
    store.close()
    # At start the runner finds the previous run's control.mode in its stored configuration.
    from dsfd.storage.queries import last_decision, run_control_mode
    from dsfd.storage.timeseries import CycleRecord

    store = Store.open(tmp_path / "again")
    store.begin_run(panel=cfg.panel.id, mode="test", version="0", config_path=None,
                    config=dataclasses.asdict(heating_file))
    store.append(CycleRecord(cycle=1, time_s=T0, samples=[], decision={
        "slot": 0, "time_s": T0, "time_utc": "t", "method": "mpc", "phi_deg": 0.0, "afr": 10,
        "or_pct": 0.0, "write_status": "verified", "cycle_ms": 1.0,
        "objective_mode": "cooling", "mode_command_id": 7}))
    last = last_decision(store.reader())
    assert run_control_mode(store.reader(), last["run_id"]) == "heating"
    assert ManualStage(cfg, store).restore_mode(last, file_mode_then="heating") is None
    store.close()
