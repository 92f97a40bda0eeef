"""The parameter history as the parameter detector judges it (docs/model.md#findings).

Read from the ``parameters`` table: the on-line estimates of each θ parameter with the
posterior sd stored with them (schema 8), in the fitting coordinates (ln θ for the positive
parameters, n as it is), over the last :data:`PARAMETER_WINDOW_S` since the calibration last
started from its priors (a ``prior`` row: what came before is another history), one value a
day, the days being the 24-h periods that end at the time of the check
(:func:`dsfd.estimation.parameter_watch.daily_estimates`). Rows without an sd (written before
schema 8) are left out.

The heat-flux offsets q_x1 … q_x4 [W/m²] (the ``other`` column) are watched too: a sensor
that reads off by a constant (a thermocouple offset) moves its node's offset, since the
state update takes the reading as it is. The rows carry no sd for them, so each estimate is
given :data:`OFFSET_SD_FLOOR_WM2`; the detector's between-day variance does the rest.
"""

from __future__ import annotations

import json
import math
import sqlite3

import numpy as np

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.estimation.parameter_watch import LOG_UNIT, OFFSET_UNIT, daily_estimates
from dsfd.estimation.params import LINEAR_NAMES, OFFSET_NAMES
from dsfd.storage.schema import PARAMETER_SD_COLUMNS

__all__ = ["OFFSET_SD_FLOOR_WM2", "PARAMETER_MIN_DAYS", "PARAMETER_WINDOW_S", "DailySeries",
           "offset_series", "offsets_of", "parameter_rows", "parameter_series",
           "parameter_unit"]

#: The parameter detector compares each day with the 7 days ending 2 days before it and
#: needs 3 of them (ParameterSettings): it runs once 5 days make a series ...
PARAMETER_MIN_DAYS = 5
#: ... on the last 3 weeks.
PARAMETER_WINDOW_S = 21 * 86400.0

#: The sd given to each stored estimate of a heat-flux offset [W/m²] (the rows carry none):
#: the least spread credited to a day's value. On the diagnostics bench's 8 clean winter days
#: the daily values of q_x2 … q_x4 moved 0.1–4 W/m² from day to day (q_x1, the exterior pane
#: in the sun, 5–30); a thermocouple reading 1 K high on the inner pane moved q_x3 by 15–18.
OFFSET_SD_FLOOR_WM2 = 2.0

#: One parameter's daily series: the days' times (the last estimate of each) [s], values
#: and sds, in the fitting coordinates.
DailySeries = tuple[np.ndarray, np.ndarray, np.ndarray]


def parameter_unit(name: str) -> str:
    """The unit of a parameter's series: :data:`LOG_UNIT` where it is ln θ, '' for n,
    W/m2 for a heat-flux offset."""
    if name in OFFSET_NAMES:
        return OFFSET_UNIT
    return "" if name in LINEAR_NAMES else LOG_UNIT


def _since_restart(conn: sqlite3.Connection, until_s: float, window_s: float) -> float:
    """The start of the window of ``window_s`` ending at ``until_s``, or the calibration's
    last start from its priors (a ``prior`` row) if later: what came before it is another
    history."""
    restart = conn.execute("SELECT MAX(time_s) FROM parameters WHERE source = 'prior' AND "
                           "time_s < ?", (until_s,)).fetchone()[0]
    return until_s - window_s if restart is None else max(until_s - window_s, float(restart))


def parameter_rows(conn: sqlite3.Connection, now_s: float
                   ) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """The on-line estimates the detector reads at ``now_s``: their times [s], and per θ
    parameter its values in the fitting coordinate (ln θ where positive) with their sd."""
    since = _since_restart(conn, now_s, PARAMETER_WINDOW_S)
    n = len(PARAMETER_NAMES)
    stored = conn.execute(
        f"SELECT time_s, {', '.join(PARAMETER_NAMES)}, {', '.join(PARAMETER_SD_COLUMNS)}, "
        "other FROM parameters WHERE source = 'online' AND time_s >= ? AND time_s < ? "
        "ORDER BY time_s", (since, now_s)).fetchall()
    rows = np.array([r[:-1] for r in stored], float).reshape(-1, 1 + 2 * n)
    out = {}
    for i, name in enumerate(PARAMETER_NAMES):
        value = rows[:, 1 + i]
        if name not in LINEAR_NAMES:  # the fitting coordinate, in which the sd is given
            value = np.log(np.where(value > 0, value, np.nan))
        out[name] = (value, rows[:, 1 + n + i])
    for name, value in _offset_columns([r[-1] for r in stored]).items():
        out[name] = (value, np.full(len(stored), OFFSET_SD_FLOOR_WM2))
    return rows[:, 0], out


def parameter_series(conn: sqlite3.Connection, now_s: float
                     ) -> dict[str, DailySeries] | None:
    """Each θ parameter's and heat-flux offset's daily series over the 24-h days ending at
    ``now_s``; None while fewer than :data:`PARAMETER_MIN_DAYS` days make one (the detector
    does not run)."""
    # the last day is the last 24 h, judged whole whenever the check runs
    times, rows = parameter_rows(conn, now_s)
    series = {name: daily_estimates(times, value, sd, end_s=now_s)
              for name, (value, sd) in rows.items()}
    if max(t.size for t, _, _ in series.values()) < PARAMETER_MIN_DAYS:
        return None
    return series


def offsets_of(other: str | None) -> dict[str, float]:
    """The heat-flux offsets of a ``parameters`` row's ``other`` JSON (those that are
    numbers; none from text that is not a JSON object)."""
    try:
        values = json.loads(other or "{}")
    except ValueError:
        return {}
    if not isinstance(values, dict):
        return {}
    return {k: float(v) for k, v in values.items()
            if k in OFFSET_NAMES and isinstance(v, int | float)}


def offset_series(conn: sqlite3.Connection, since_s: float, until_s: float
                  ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The on-line estimates of the heat-flux offsets [W/m²] from ``since_s`` (or the
    calibration's last start from its priors, if later) to ``until_s``: their times [s] and
    the values per offset name (NaN where a row has none)."""
    since = _since_restart(conn, until_s, until_s - since_s)
    stored = conn.execute("SELECT time_s, other FROM parameters WHERE source = 'online' AND "
                          "time_s >= ? AND time_s <= ? ORDER BY time_s",
                          (since, until_s)).fetchall()
    return (np.array([r[0] for r in stored], float),
            _offset_columns([r[1] for r in stored]))


def _offset_columns(others: list[str | None]) -> dict[str, np.ndarray]:
    """Per offset name, its value in each ``other`` JSON of :func:`offsets_of` (NaN: none)."""
    parsed = [offsets_of(o) for o in others]
    return {name: np.array([o.get(name, math.nan) for o in parsed], float)
            for name in OFFSET_NAMES}
