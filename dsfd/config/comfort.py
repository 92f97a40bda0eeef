"""Settings of the occupants: a weekly occupancy schedule and the comfort limits.

YAML shape (both sections optional)::

    occupancy:              # absent: never occupied, so no comfort limit applies (energy only)
      mon: ["08:00-12:00", "13:00-18:00"]
      tue: ["08:00-18:00"]
      # wed … sun likewise; a day not listed is unoccupied
      holidays: [2026-12-25, "2027-01-01"]   # unoccupied all day
    comfort:
      category: B           # ISO 7730:2005 category (A, B, C) of the draught and asymmetry limits
      direct_sun_max_wm2: 5
      dgp_max: 0.35         # EN 17037:2018 glare protection: 0.35 high, 0.40 medium, 0.45 minimum
      supply_air_min_c: null   # null: derived from the category's draught-rate limit

Times are panel local time (``site.utc_offset_h``); an interval is ``"HH:MM-HH:MM"`` with
the end after the start (``"24:00"`` allowed as an end; split a night shift at midnight).
The formulas are docs/model.md#comfort. Errors name the key path, e.g. ``occupancy.tue[0]``.
"""

from __future__ import annotations

import datetime
import itertools
import re
from dataclasses import dataclass
from typing import Literal

from dsfd.config.loader import Problem, setting

__all__ = ["DAY_KEYS", "DRAUGHT_RATE_MAX_PCT", "Comfort", "Occupancy", "parse_interval"]

#: Weekday keys, Monday first (``datetime.date.weekday`` order).
DAY_KEYS = ("mon", "tue", "wed", "thu", "fri", "sat", "sun")

_INTERVAL = re.compile(r"^([01][0-9]|2[0-3]):([0-5][0-9])-([01][0-9]|2[0-4]):([0-5][0-9])$")


def parse_interval(text: str) -> tuple[int, int] | None:
    """``"HH:MM-HH:MM"`` as (start, end) minutes after local midnight, or None if invalid.

    The end may be ``"24:00"`` and must be after the start.
    """
    m = _INTERVAL.match(text)
    if m is None:
        return None
    start = int(m.group(1)) * 60 + int(m.group(2))
    end = int(m.group(3)) * 60 + int(m.group(4))
    return (start, end) if start < end <= 24 * 60 else None


def _day(doc: str) -> tuple[str, ...]:
    return setting((), doc=f"Occupied intervals on {doc}, \"HH:MM-HH:MM\" local time")


@dataclass(frozen=True, kw_only=True)
class Occupancy:
    """Weekly occupancy schedule in panel local time (docs/model.md#occupancy)."""

    mon: tuple[str, ...] = _day("Mondays")
    tue: tuple[str, ...] = _day("Tuesdays")
    wed: tuple[str, ...] = _day("Wednesdays")
    thu: tuple[str, ...] = _day("Thursdays")
    fri: tuple[str, ...] = _day("Fridays")
    sat: tuple[str, ...] = _day("Saturdays")
    sun: tuple[str, ...] = _day("Sundays")
    holidays: tuple[str, ...] = setting(
        (), doc="Dates (YYYY-MM-DD, local) that are unoccupied all day")

    def intervals(self, weekday: int) -> tuple[tuple[int, int], ...]:
        """Occupied (start, end) minutes of a weekday (0 = Monday); valid after ``check``."""
        parsed = (parse_interval(t) for t in getattr(self, DAY_KEYS[weekday]))
        return tuple(p for p in parsed if p is not None)

    def holiday_dates(self) -> tuple[datetime.date, ...]:
        """The holidays as dates; valid after ``check``."""
        return tuple(datetime.date.fromisoformat(d) for d in self.holidays)

    def check(self) -> list[Problem]:
        out = []
        for key in DAY_KEYS:
            spans = []
            for i, text in enumerate(getattr(self, key)):
                span = parse_interval(text)
                if span is None:
                    out.append(Problem(f"{key}[{i}]", text, 'expected "HH:MM-HH:MM" with the '
                                       'end after the start, e.g. "08:00-18:00"'))
                else:
                    spans.append((span, i, text))
            spans.sort()
            for (a, _, _), (b, j, text) in itertools.pairwise(spans):
                if b[0] < a[1]:
                    out.append(Problem(f"{key}[{j}]", text, "overlaps another interval"))
        for i, text in enumerate(self.holidays):
            try:
                datetime.date.fromisoformat(text)
            except ValueError:
                out.append(Problem(f"holidays[{i}]", text, "expected a date YYYY-MM-DD"))
        return out


#: ISO 7730:2005 Table A.1: draught rate DR [%] allowed per category.
DRAUGHT_RATE_MAX_PCT = {"A": 10.0, "B": 20.0, "C": 30.0}


@dataclass(frozen=True, kw_only=True)
class Comfort:
    """Comfort limits while occupied (docs/model.md#comfort); nothing applies unoccupied."""

    category: Literal["A", "B", "C"] = setting(
        "B", doc="ISO 7730:2005 category of the draught-rate and radiant-asymmetry limits")
    direct_sun_max_wm2: float = setting(
        5.0, doc="Largest solar beam passing the louver unscattered into the room",
        unit="W/m2", ge=0, le=1000)
    dgp_max: float = setting(
        0.35, doc="Largest simplified daylight glare probability DGPs (EN 17037:2018 glare "
        "protection: 0.35 high, 0.40 medium, 0.45 minimum)", unit="1", gt=0.184, le=1)
    supply_air_min_c: float | None = setting(
        None, doc="Coldest air allowed into the room; null: the temperature at which the "
        "category's draught rate is reached at supply_air_speed_ms", unit="degC", ge=0, le=40)
    supply_air_speed_ms: float = setting(
        0.15, doc="Mean air speed at the occupant from the supply, for the draught rate",
        unit="m/s", gt=0.05, le=1)
    turbulence_pct: float = setting(
        40.0, doc="Turbulence intensity of that air (ISO 7730: 40 for mixing ventilation)",
        unit="%", ge=0, le=100)
    occupant_distance_m: float = setting(
        1.0, doc="Horizontal distance of the occupant (eye, body) from the inner pane",
        unit="m", gt=0.1, le=20)
    eye_height_m: float = setting(
        1.2, doc="Eye height above the floor (seated), for the glare view factor",
        unit="m", gt=0, le=3)
    asymmetry_height_m: float = setting(
        0.6, doc="Height of the radiant-asymmetry point above the floor (ISO 7730: 0.6 seated)",
        unit="m", gt=0, le=3)
    sill_height_m: float = setting(
        0.0, doc="Height of the glazing's lower edge above the floor", unit="m", ge=0, le=10)
