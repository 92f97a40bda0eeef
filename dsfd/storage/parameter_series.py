"""The parameter history as the parameter detector judges it (docs/model.md#findings).

Read from the ``parameters`` table: the on-line estimates of each θ parameter with the
posterior sd stored with them (schema 8), in the fitting coordinates (ln θ for the positive
parameters, n as it is), over the last :data:`PARAMETER_WINDOW_S` of complete UTC days since
the calibration last started from its priors (a ``prior`` row: what came before is another
history), one value a day (:func:`dsfd.estimation.parameter_watch.daily_estimates`). Rows
without an sd (written before schema 8) are left out.
"""

from __future__ import annotations

import math
import sqlite3

import numpy as np

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.estimation.parameter_watch import LOG_UNIT, daily_estimates
from dsfd.estimation.params import LINEAR_NAMES
from dsfd.storage.schema import PARAMETER_SD_COLUMNS

__all__ = ["PARAMETER_MIN_DAYS", "PARAMETER_WINDOW_S", "DailySeries", "parameter_series",
           "parameter_unit"]

#: The parameter detector compares each day with the 7 days ending 2 days before it and
#: needs 3 of them (ParameterSettings): it runs once 5 days make a series ...
PARAMETER_MIN_DAYS = 5
#: ... on the last 3 weeks.
PARAMETER_WINDOW_S = 21 * 86400.0

#: One parameter's daily series: the days' times (the last estimate of each) [s], values
#: and sds, in the fitting coordinates.
DailySeries = tuple[np.ndarray, np.ndarray, np.ndarray]


def parameter_unit(name: str) -> str:
    """The unit of a parameter's series: :data:`LOG_UNIT` where it is ln θ, '' for n."""
    return "" if name in LINEAR_NAMES else LOG_UNIT


def parameter_series(conn: sqlite3.Connection, now_s: float
                     ) -> dict[str, DailySeries] | None:
    """Each θ parameter's daily series up to the last complete UTC day before ``now_s``;
    None while fewer than :data:`PARAMETER_MIN_DAYS` days make one (the detector does not
    run)."""
    until = math.floor(now_s / 86400.0) * 86400.0  # a day is judged once it ended
    restart = conn.execute("SELECT MAX(time_s) FROM parameters WHERE source = 'prior' AND "
                           "time_s < ?", (until,)).fetchone()[0]
    since = until - PARAMETER_WINDOW_S if restart is None else \
        max(until - PARAMETER_WINDOW_S, float(restart))
    n = len(PARAMETER_NAMES)
    rows = np.array(conn.execute(
        f"SELECT time_s, {', '.join(PARAMETER_NAMES)}, {', '.join(PARAMETER_SD_COLUMNS)} "
        "FROM parameters WHERE source = 'online' AND time_s >= ? AND time_s < ? "
        "ORDER BY time_s", (since, until)).fetchall(), float).reshape(-1, 1 + 2 * n)
    series = {}
    for i, name in enumerate(PARAMETER_NAMES):
        value = rows[:, 1 + i]
        if name not in LINEAR_NAMES:  # the fitting coordinate, in which the sd is given
            value = np.log(np.where(value > 0, value, np.nan))
        series[name] = daily_estimates(rows[:, 0], value, rows[:, 1 + n + i])
    if max(t.size for t, _, _ in series.values()) < PARAMETER_MIN_DAYS:
        return None
    return series
