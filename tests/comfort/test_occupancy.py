"""Occupancy schedule: config validation and the occupied mask over UTC times.

Expected values come from Python's own calendar (``datetime`` with a fixed-offset timezone),
not from the code under test: weekday, local clock time and holiday of each instant.
"""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
import yaml

from dsfd.config import ConfigError, panel_from_mapping
from dsfd.config.comfort import Occupancy
from dsfd.control.occupancy import occupied
from tests.conftest import PANELS

OFFICE = Occupancy(mon=("08:00-18:00",), tue=("08:00-18:00",), wed=("08:00-12:00",
                   "13:00-18:00"), thu=("08:00-18:00",), fri=("08:00-18:00",),
                   holidays=("2026-12-25",))
SEOUL = dt.timezone(dt.timedelta(hours=9))


def _utc_s(local: dt.datetime) -> float:
    return local.replace(tzinfo=SEOUL).timestamp()


def _expected(local: dt.datetime) -> bool:
    """The office calendar written out by hand from the local date and clock."""
    if local.date() == dt.date(2026, 12, 25) or local.weekday() >= 5:
        return False
    minutes = local.hour * 60 + local.minute + local.second / 60
    if local.weekday() == 2:
        return 480 <= minutes < 720 or 780 <= minutes < 1080
    return 480 <= minutes < 1080


def test_a_week_every_ten_minutes_matches_the_calendar():
    start = dt.datetime(2026, 12, 21, 0, 0)  # a Monday; Friday the 25th is a holiday
    local = [start + dt.timedelta(minutes=10 * k) for k in range(7 * 144)]
    got = occupied(np.array([_utc_s(t) for t in local]), occupancy=OFFICE, utc_offset_h=9)
    want = np.array([_expected(t) for t in local])
    assert np.array_equal(got, want)
    assert not got[[t.weekday() >= 5 for t in local]].any()  # the weekend
    assert not got[[t.day == 25 for t in local]].any()  # the holiday
    assert got.sum() == 3 * 60 + 54  # Mon, Tue, Thu 10 h; Wed 9 h (10-minute samples)


def test_interval_edges_and_a_horizon_crossing_the_start():
    # Horizon from Monday 07:00 local to 09:00 every 15 min: occupancy starts at 08:00.
    t0 = _utc_s(dt.datetime(2026, 12, 21, 7, 0))
    horizon = t0 + 900.0 * np.arange(9)
    mask = occupied(horizon, occupancy=OFFICE, utc_offset_h=9)
    assert mask.tolist() == [False] * 4 + [True] * 5
    # 18:00 is the first unoccupied instant, 17:59:59 the last occupied one.
    end = _utc_s(dt.datetime(2026, 12, 21, 18, 0))
    assert occupied([end - 1.0, end], occupancy=OFFICE, utc_offset_h=9).tolist() == [True,
                                                                                      False]


def test_utc_offset_shifts_the_local_day():
    # 2026-12-20 23:30 UTC is Monday 08:30 in UTC+9 but Sunday 23:30 in UTC.
    t = dt.datetime(2026, 12, 20, 23, 30, tzinfo=dt.UTC).timestamp()
    assert occupied(t, occupancy=OFFICE, utc_offset_h=9)
    assert not occupied(t, occupancy=OFFICE, utc_offset_h=0)


def test_no_schedule_means_never_occupied_so_no_comfort_limit():
    t = _utc_s(dt.datetime(2026, 12, 21, 10, 0)) + 3600.0 * np.arange(48)
    assert not occupied(t, occupancy=None, utc_offset_h=9).any()


def test_an_interval_may_end_at_midnight():
    occ = Occupancy(sat=("20:00-24:00",))
    t = [_utc_s(dt.datetime(2026, 12, 26, 23, 59)), _utc_s(dt.datetime(2026, 12, 27, 0, 0))]
    assert occupied(t, occupancy=occ, utc_offset_h=9).tolist() == [True, False]


def _issues(extra: dict) -> dict[str, str]:
    data = yaml.safe_load((PANELS / "suwon-south.yaml").read_text())
    data.update(extra)
    with pytest.raises(ConfigError) as exc:
        panel_from_mapping(data, source="test.yaml")
    return {issue.path: str(issue) for issue in exc.value.issues}


def test_bad_schedules_name_the_key_path_and_value():
    issues = _issues({"occupancy": {"mon": ["18:00-08:00"], "tue": ["8-18"],
                                    "wed": ["08:00-12:00", "11:00-13:00"], "sunday": [],
                                    "holidays": ["2026-13-01"]},
                      "comfort": {"dgp_max": 0.1, "category": "D"}})
    assert "'18:00-08:00'" in issues["occupancy.mon[0]"]
    assert "'8-18'" in issues["occupancy.tue[0]"]
    assert "overlaps" in issues["occupancy.wed[1]"]
    assert "unknown key" in issues["occupancy.sunday"]
    assert "'2026-13-01'" in issues["occupancy.holidays[0]"]
    assert "0.1" in issues["comfort.dgp_max"]
    assert "'D'" in issues["comfort.category"]


def test_yaml_dates_and_the_default_are_read():
    data = yaml.safe_load((PANELS / "suwon-south.yaml").read_text())
    data.pop("occupancy")  # the example panel has one (for the README's dry run)
    assert panel_from_mapping(data).occupancy is None  # absent: no comfort constraints
    data.update(yaml.safe_load("occupancy: {fri: ['08:00-18:00'], holidays: [2026-12-25]}"))
    cfg = panel_from_mapping(data)
    assert cfg.occupancy is not None and cfg.occupancy.holidays == ("2026-12-25",)
    assert cfg.comfort.dgp_max == 0.35 and cfg.comfort.category == "B"
