"""Occupied or not, for an array of UTC times (docs/model.md#occupancy).

Pure: the times are given (Unix seconds, UTC), the schedule is :class:`dsfd.config.comfort.
Occupancy` and the panel's local standard time is UTC + ``site.utc_offset_h``. Over a
horizon the optimiser sees where occupancy starts and ends as the edges of the returned mask.

:func:`occupied` is the weekly schedule alone. :func:`effective_occupancy` (now) and
:func:`effective_profile` (over a horizon) resolve the three sources in one place, the
stronger word first:

1. an operator's **override** (``dsfd occupancy``, MQTT ``<base>/cmd/occupancy``) until its
   end time;
2. the **occupied signal** (a presence sensor, the BMS's flag) while its reading is GOOD;
   over a horizon its present value is carried forward (persistence, as the measured
   weather is);
3. the **schedule**, when neither says anything (no signal configured, or its reading
   flagged: stale, out of range, device down).
"""

from __future__ import annotations

import datetime
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.config.comfort import Occupancy

__all__ = ["OCCUPANCY_SOURCES", "EffectiveOccupancy", "OccupancyOverride",
           "effective_occupancy", "effective_profile", "occupied"]

#: Where the effective occupancy came from, strongest first.
OCCUPANCY_SOURCES = ("override", "signal", "schedule")

_DAY_S = 86400.0
#: 1970-01-01, day 0 of Unix time, was a Thursday (weekday 3 with Monday = 0).
_EPOCH_WEEKDAY = 3
_EPOCH = datetime.date(1970, 1, 1)


def occupied(
    time_s: ArrayLike, *, occupancy: Occupancy | None, utc_offset_h: float
) -> NDArray[np.bool_]:
    """Whether each instant is inside an occupied interval of the local schedule.

    Parameters
    ----------
    time_s : array_like
        Instants [s since 1970-01-01 UTC], any shape.
    occupancy : Occupancy or None
        The schedule; None (no ``occupancy:`` section) means never occupied, so that no
        comfort limit applies and the controller optimises energy alone, as without it.
    utc_offset_h : float
        Local standard time minus UTC [h] (``site.utc_offset_h``; no daylight saving).

    Returns
    -------
    ndarray of bool, the shape of ``time_s``
        True inside an interval ``[start, end)`` of the local weekday, False on holidays.
    """
    t_local = np.asarray(time_s, dtype=float) + 3600.0 * float(utc_offset_h)
    out = np.zeros(t_local.shape, dtype=bool)
    if occupancy is None:
        return out
    day = np.floor(t_local / _DAY_S)
    minute = (t_local - day * _DAY_S) / 60.0
    weekday = (day.astype(np.int64) + _EPOCH_WEEKDAY) % 7
    for wd in range(7):
        on_day = weekday == wd
        for start, end in occupancy.intervals(wd):
            out |= on_day & (minute >= start) & (minute < end)
    holidays = [(d - _EPOCH).days for d in occupancy.holiday_dates()]
    if holidays:
        out &= ~np.isin(day.astype(np.int64), holidays)
    return out


@dataclass(frozen=True)
class OccupancyOverride:
    """An operator's word on occupancy: ``occupied`` until ``until_s`` [s, UTC]."""

    occupied: bool
    until_s: float
    command_id: int | None = None

    def active(self, time_s: float) -> bool:
        """True before its end (an override ends at ``until_s``, exclusive)."""
        return time_s < self.until_s

    def describe(self) -> str:
        state = "occupied" if self.occupied else "unoccupied"
        by = "" if self.command_id is None else f" (operator command #{self.command_id})"
        return f"{state} until {_utc(self.until_s)}{by}"


class EffectiveOccupancy(NamedTuple):
    """The occupancy in force at one instant, where it came from and why."""

    occupied: bool
    source: str  #: one of :data:`OCCUPANCY_SOURCES`
    why: str  #: one line for the decision trace and the log


def effective_profile(
    time_s: ArrayLike, *, occupancy: Occupancy | None, utc_offset_h: float,
    override: OccupancyOverride | None = None, signal: float | None = None,
) -> tuple[NDArray[np.bool_], NDArray[np.str_]]:
    """Occupied or not at each of ``time_s`` (the first is now), and the source of each.

    Parameters
    ----------
    time_s : array_like
        Instants [s since 1970-01-01 UTC], now first, in increasing order.
    occupancy, utc_offset_h
        The schedule and the local time offset, as :func:`occupied`.
    override : OccupancyOverride or None
        An operator's override; it decides every instant before its ``until_s``.
    signal : float or None
        The occupied signal's GOOD reading now (1 occupied, 0 not); None when there is no
        signal or its reading is flagged. Carried over every instant the override leaves.

    Returns
    -------
    (ndarray of bool, ndarray of str)
        The occupancy and its source (:data:`OCCUPANCY_SOURCES`) per instant.
    """
    t = np.asarray(time_s, dtype=float)
    out = occupied(t, occupancy=occupancy, utc_offset_h=utc_offset_h)
    source = np.full(t.shape, "schedule", dtype="<U8")
    if signal is not None and math.isfinite(signal):
        out[:] = bool(signal >= 0.5)
        source[:] = "signal"
    if override is not None:
        held = t < override.until_s
        out[held] = override.occupied
        source[held] = "override"
    return out, source


def effective_occupancy(
    now_s: float, *, occupancy: Occupancy | None, utc_offset_h: float,
    override: OccupancyOverride | None = None, signal: float | None = None,
    signal_problem: str | None = None,
) -> EffectiveOccupancy:
    """The occupancy in force at ``now_s``: override > signal > schedule (module doc).

    ``signal_problem`` says why a configured signal gave nothing usable (its quality flag,
    e.g. ``"stale"``), for the reason; ignored while the signal or an override decides.
    """
    flags, sources = effective_profile([now_s], occupancy=occupancy, utc_offset_h=utc_offset_h,
                                       override=override, signal=signal)
    is_occupied, source = bool(flags[0]), str(sources[0])
    state = "occupied" if is_occupied else "unoccupied"
    if source == "override":
        assert override is not None
        why = f"{state}: operator override, {override.describe()}"
    elif source == "signal":
        why = f"{state}: occupied signal reads {signal:g}"
    else:
        sched = "no occupancy schedule" if occupancy is None else "the schedule"
        why = f"{state}: {sched}"
        if signal_problem:
            why += f" (occupied signal not usable: {signal_problem})"
    return EffectiveOccupancy(is_occupied, source, why)


def _utc(time_s: float) -> str:
    if not math.isfinite(time_s):
        return "?"
    return datetime.datetime.fromtimestamp(round(time_s), datetime.UTC).strftime(
        "%Y-%m-%dT%H:%M:%SZ")
