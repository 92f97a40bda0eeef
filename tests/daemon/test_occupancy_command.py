"""The occupancy override command (issue 36): its forms from the CLI and MQTT, the one
validation, the end time resolved on the daemon's clock, and the stage that keeps it.

Expected instants are written as Seoul local times with Python's own calendar (a fixed
+09:00 zone, as ``site.utc_offset_h: 9`` of the Suwon panel), not with the code under test.
"""

from __future__ import annotations

import datetime as dt
import json

import pytest

from dsfd.config import load_panel
from dsfd.config.comfort import Occupancy
from dsfd.daemon.commands import (
    CommandError,
    OperatorCommand,
    occupancy_request,
    resolve_until,
    validate_command,
)
from dsfd.daemon.occupancy import OccupancyStage
from dsfd.drivers.base import Quality, Reading, Sample
from dsfd.integrations.mqtt.commands import request_of
from tests.conftest import PANELS

SEOUL = dt.timezone(dt.timedelta(hours=9))
CFG = load_panel(PANELS / "suwon-south.yaml")
#: Monday 2026-11-30 16:20 in Seoul.
NOW = dt.datetime(2026, 11, 30, 16, 20, tzinfo=SEOUL).timestamp()


def _at(*args: int) -> float:
    return dt.datetime(*args, tzinfo=SEOUL).timestamp()


@pytest.mark.parametrize(("text", "request_"), [
    ("occupied until 18:00", {"state": "occupied", "until": "18:00"}),
    ("unoccupied  until 2026-12-01T08:00", {"state": "unoccupied",
                                            "until": "2026-12-01T08:00"}),
    ("auto", {"state": "auto"}),
])
def test_the_written_forms_give_the_same_request_from_cli_and_mqtt(
        text: str, request_: dict[str, str]) -> None:
    expected = {"command": "occupancy", **request_}
    assert occupancy_request(text) == expected
    assert request_of("occupancy", text.encode()) == expected
    assert request_of("occupancy", json.dumps(request_).encode()) == expected
    assert isinstance(validate_command(CFG, expected), OperatorCommand)


@pytest.mark.parametrize(("request_", "field", "message"), [
    ({"state": "busy", "until": "18:00"}, "state", "expected one of occupied, unoccupied"),
    ({"state": "occupied"}, "until", "needs an end time"),
    ({"state": "occupied", "until": "25:00"}, "until", "expected a local time HH:MM"),
    ({"state": "occupied", "until": "tomorrow"}, "until", "expected a local time HH:MM"),
    ({"state": "occupied", "until": "2026-12-01"}, "until", "expected a local time HH:MM"),
    ({"state": "occupied", "until": 1800}, "until", "expected a local time HH:MM"),
    ({"state": "auto", "until": "18:00"}, "until", "give no time"),
    ({"state": "occupied", "until": "18:00", "hold": "2h"}, "hold", "unknown field"),
])
def test_malformed_requests_name_the_field(request_: dict[str, object], field: str,
                                           message: str) -> None:
    with pytest.raises(CommandError) as err:
        validate_command(CFG, {"command": "occupancy", **request_})
    assert err.value.field == field and message in err.value.message


@pytest.mark.parametrize("text", ["occupied 18:00", "occupied until", "occupied until 18:00 x",
                                  ""])
def test_malformed_text_is_refused(text: str) -> None:
    with pytest.raises(CommandError):
        occupancy_request(text)


def test_until_resolves_on_the_daemons_clock() -> None:
    # HH:MM: the next such local time, today if still ahead, else tomorrow
    assert resolve_until("18:00", now_s=NOW, utc_offset_h=9) == _at(2026, 11, 30, 18, 0)
    assert resolve_until("08:00", now_s=NOW, utc_offset_h=9) == _at(2026, 12, 1, 8, 0)
    assert resolve_until("16:20", now_s=NOW, utc_offset_h=9) == _at(2026, 12, 1, 16, 20)
    # a date-time: panel local time unless it names a zone
    assert resolve_until("2026-12-01T08:00", now_s=NOW, utc_offset_h=9) == \
        _at(2026, 12, 1, 8, 0)
    assert resolve_until("2026-11-30T23:00Z", now_s=NOW, utc_offset_h=9) == \
        _at(2026, 12, 1, 8, 0)
    with pytest.raises(CommandError, match="already past"):
        resolve_until("2026-11-30T16:00", now_s=NOW, utc_offset_h=9)
    with pytest.raises(CommandError, match="168 h ahead"):
        resolve_until("2026-12-08T08:00", now_s=NOW, utc_offset_h=9)


def test_the_stage_applies_ends_and_restores_an_override() -> None:
    stage = OccupancyStage()
    cmd = validate_command(CFG, occupancy_request("unoccupied until 17:00"))
    (cid, status, reason), event = stage.command(cmd, 4, now_s=NOW, utc_offset_h=9, who="cli x")
    assert (cid, status) == (4, "applied") and "unoccupied until" in reason
    assert event is not None and event[1] == "occupancy_set"
    assert stage.override is not None and stage.override.until_s == _at(2026, 11, 30, 17, 0)
    # a past date-time is rejected at apply time and changes nothing
    late = validate_command(CFG, occupancy_request("occupied until 2026-11-30T12:00"))
    (_, status, reason), event = stage.command(late, 5, now_s=NOW, utc_offset_h=9, who="x")
    assert status == "rejected" and "already past" in reason and event is None
    assert stage.override is not None and not stage.override.occupied
    # the schedule says occupied on a Monday afternoon; the override says not
    sample = Sample(NOW, {})
    office = CFG.__class__(**{**CFG.__dict__, "occupancy": Occupancy(mon=("08:00-18:00",))})
    assert stage.resolve(office, sample, {}, now_s=NOW)[:2] == (False, "override")
    # restored after a restart from the decision columns, until its time
    last = {"occupancy_override": "unoccupied", "occupancy_until_s": stage.override.until_s,
            "occupancy_command_id": 4}
    again = OccupancyStage()
    assert again.restore(last, now_s=NOW) is not None and again.override == stage.override
    assert OccupancyStage().restore(last, now_s=_at(2026, 11, 30, 17, 0)) is None
    # it ends at its time, with an event
    assert stage.expire(_at(2026, 11, 30, 16, 59)) == []
    assert [e[1] for e in stage.expire(_at(2026, 11, 30, 17, 0))] == ["occupancy_ended"]
    assert stage.override is None
    assert stage.resolve(office, sample, {}, now_s=NOW)[:2] == (True, "schedule")


def test_a_flagged_signal_hands_over_to_the_schedule_and_is_logged_once() -> None:
    from structlog.testing import capture_logs

    office = CFG.__class__(**{**CFG.__dict__, "occupancy": Occupancy(mon=("08:00-18:00",))})
    stage = OccupancyStage()
    good = Sample(NOW, {"occupied": Reading.good(0.0, "io")})
    stale = Sample(NOW, {"occupied": Reading.bad(Quality.STALE, "io", "io: stale")})
    assert stage.resolve(office, good, {}, now_s=NOW)[:2] == (False, "signal")
    with capture_logs() as logs:
        for _ in range(3):
            e = stage.resolve(office, stale, {"occupied": "stale"}, now_s=NOW)
            assert (e.occupied, e.source) == (True, "schedule") and "stale" in e.why
        stage.resolve(office, good, {}, now_s=NOW)
    events = [(r["log_level"], r["event"]) for r in logs]
    assert [level for level, _ in events] == ["warning", "info"], events
    assert "occupied signal not usable" in events[0][1] and "stale" in events[0][1]
    assert "occupied signal GOOD again" in events[1][1]
