"""The effective occupancy: override > occupied signal > schedule (issue 36), now and over a
horizon. The instants are written as Seoul local times and the schedule's answer comes from
the calendar by hand (a Monday 10:00 is inside 08:00-18:00, a Saturday is not)."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from dsfd.config.comfort import Occupancy
from dsfd.control.occupancy import (
    OccupancyOverride,
    effective_occupancy,
    effective_profile,
)

WEEKDAYS = Occupancy(mon=("08:00-18:00",), tue=("08:00-18:00",), wed=("08:00-18:00",),
                     thu=("08:00-18:00",), fri=("08:00-18:00",))
SEOUL = dt.timezone(dt.timedelta(hours=9))
#: Monday 2026-11-30 10:00 local: inside the schedule; Saturday 2026-11-28 10:00: outside.
MONDAY_10 = dt.datetime(2026, 11, 30, 10, 0, tzinfo=SEOUL).timestamp()
SATURDAY_10 = dt.datetime(2026, 11, 28, 10, 0, tzinfo=SEOUL).timestamp()


def _now(t: float, **kw: object) -> tuple[bool, str]:
    e = effective_occupancy(t, occupancy=WEEKDAYS, utc_offset_h=9.0, **kw)  # type: ignore
    return e.occupied, e.source


@pytest.mark.parametrize(("t", "override", "signal", "expected"), [
    # nothing but the schedule
    (MONDAY_10, None, None, (True, "schedule")),
    (SATURDAY_10, None, None, (False, "schedule")),
    # a GOOD signal overrides the schedule both ways
    (MONDAY_10, None, 0.0, (False, "signal")),
    (SATURDAY_10, None, 1.0, (True, "signal")),
    # an override beats the signal and the schedule, both ways
    (SATURDAY_10, OccupancyOverride(True, SATURDAY_10 + 3600), 0.0, (True, "override")),
    (MONDAY_10, OccupancyOverride(False, MONDAY_10 + 60), 1.0, (False, "override")),
    # an override that has ended says nothing: the signal, else the schedule decides
    (MONDAY_10, OccupancyOverride(False, MONDAY_10), 1.0, (True, "signal")),
    (MONDAY_10, OccupancyOverride(False, MONDAY_10 - 1.0), None, (True, "schedule")),
])
def test_the_stronger_word_wins(t: float, override: OccupancyOverride | None,
                                signal: float | None, expected: tuple[bool, str]) -> None:
    assert _now(t, override=override, signal=signal) == expected


def test_a_flagged_signal_falls_back_to_the_schedule_and_says_why() -> None:
    e = effective_occupancy(MONDAY_10, occupancy=WEEKDAYS, utc_offset_h=9.0, signal=None,
                            signal_problem="stale")
    assert (e.occupied, e.source) == (True, "schedule")
    assert "occupied signal not usable: stale" in e.why
    # a NaN reading is no reading
    assert _now(SATURDAY_10, signal=float("nan")) == (False, "schedule")


def test_without_a_schedule_the_room_is_empty_unless_someone_says_otherwise() -> None:
    e = effective_occupancy(MONDAY_10, occupancy=None, utc_offset_h=9.0)
    assert (e.occupied, e.source) == (False, "schedule")
    assert "no occupancy schedule" in e.why
    e = effective_occupancy(MONDAY_10, occupancy=None, utc_offset_h=9.0,
                            override=OccupancyOverride(True, MONDAY_10 + 600, 7))
    assert (e.occupied, e.source) == (True, "override")
    assert "#7" in e.why and "2026-11-30T01:10:00Z" in e.why  # 10:10 Seoul in UTC


def test_over_a_horizon_the_override_ends_at_its_time_and_the_schedule_takes_over() -> None:
    # Monday 17:40 .. 18:20 local, every 10 min; the override says unoccupied until 17:55.
    start = dt.datetime(2026, 11, 30, 17, 40, tzinfo=SEOUL).timestamp()
    t = start + 600.0 * np.arange(5)
    until = dt.datetime(2026, 11, 30, 17, 55, tzinfo=SEOUL).timestamp()
    flags, sources = effective_profile(t, occupancy=WEEKDAYS, utc_offset_h=9.0,
                                       override=OccupancyOverride(False, until))
    # 17:40, 17:50 overridden; 18:00.. past the schedule's end (18:00 exclusive)
    assert flags.tolist() == [False, False, False, False, False]
    assert sources.tolist() == ["override", "override", "schedule", "schedule", "schedule"]
    flags, sources = effective_profile(t, occupancy=WEEKDAYS, utc_offset_h=9.0)
    assert flags.tolist() == [True, True, False, False, False]
    # a GOOD signal now is carried over the horizon where no override speaks
    flags, sources = effective_profile(t, occupancy=WEEKDAYS, utc_offset_h=9.0, signal=1.0,
                                       override=OccupancyOverride(False, until))
    assert flags.tolist() == [False, False, True, True, True]
    assert sources.tolist() == ["override", "override", "signal", "signal", "signal"]
