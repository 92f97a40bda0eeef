"""Occupied or not, for an array of UTC times, from the weekly schedule (docs/model.md#occupancy).

Pure: the times are given (Unix seconds, UTC), the schedule is :class:`dsfd.config.comfort.
Occupancy` and the panel's local standard time is UTC + ``site.utc_offset_h``. Over a
horizon the optimiser sees where occupancy starts and ends as the edges of the returned mask.
"""

from __future__ import annotations

import datetime

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.config.comfort import Occupancy

__all__ = ["occupied"]

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
