"""The solar detector's days from what the daemon stored (docs/model.md#diagnostics-solar).

Each day (24 h from local solar midnight at the panel's longitude) the model's absorbed sun
S_1…S_4 of every stored cycle is recomputed from the stored weather readings and the
commands applied (read as ``dsfd export`` reads them, :mod:`dsfd.storage.history`), the
heat-flux offsets in force at each step are those of the last on-line calibration row, and
:func:`dsfd.estimation.solar_response.solar_response` gives the day's factor. A day is
computed once it has ended and kept (:class:`SolarDays`); a restart computes the last
month's days again from the store (about 0.15 s of CPU a day of one-minute cycles).

:func:`by_daylight` tells a heat-transfer coefficient's parameter finding as the sun's when
its change shows in the sunlit calibration windows alone, its direction from these days
(docs/model.md#daylight-split).
"""

from __future__ import annotations

import math
import sqlite3
from collections.abc import Callable
from pathlib import Path

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.estimation.daylight_split import (
    HEAT_TRANSFER_NAMES,
    as_solar_finding,
    daylight_only,
    daylight_split,
    window_dark,
)
from dsfd.estimation.diagnostics import Finding
from dsfd.estimation.parameter_shift import ParameterSettings
from dsfd.estimation.parameter_watch import SECONDS_PER_DAY, day_start_s
from dsfd.estimation.params import OFFSET_NAMES
from dsfd.estimation.solar_response import (
    DailySolarResponse,
    SolarSettings,
    factor_shift,
    solar_response,
    solar_response_change,
)
from dsfd.estimation.stepdata import step_data
from dsfd.measured import MeasuredDataError
from dsfd.storage.history import HistoryError, measured_from_history, read_history
from dsfd.storage.parameter_series import offset_series, parameter_rows

__all__ = ["SOLAR_EVERY_S", "SolarDays", "by_daylight", "solar_day_start_s"]

#: The solar detector runs every 6 h: a day is judged once it has ended, so a new day's
#: value is judged within 6 h of the day's end (its days are solar days, not the check's).
SOLAR_EVERY_S = 6 * 3600.0


def solar_day_start_s(time_s: float, longitude_deg: float) -> float:
    """Start [s] of the solar day (from local mean solar midnight) that holds ``time_s``:
    the days of :func:`~dsfd.estimation.parameter_watch.day_start_s` that end at the mean
    solar midnight, ``longitude_deg``/15 h before 00:00 UTC."""
    return day_start_s(time_s, end_s=-longitude_deg / 15.0 * 3600.0)


class SolarDays:
    """The daily factors of one panel's store, each computed once its day ended."""

    def __init__(self, panel: PanelConfig, state_dir: Path, *,
                 settings: SolarSettings | None = None) -> None:
        self.panel = panel
        self.state_dir = Path(state_dir)
        self.settings = settings or SolarSettings()
        #: Day start [s] → its factors (None: no value, e.g. overcast or no data).
        self._days: dict[float, DailySolarResponse | None] = {}

    @property
    def history_days(self) -> int:
        """Days the detector reads back: the guard, the wander's span and the day judged."""
        d = self.settings.days
        return math.ceil(d.guard_days + d.wander_days) + 1

    def finding(self, conn: sqlite3.Connection, now_s: float) -> Finding | None:
        """The detector on the ended days of the last :attr:`history_days` stored."""
        return solar_response_change(self.days(conn, now_s), settings=self.settings)

    def days(self, conn: sqlite3.Connection, now_s: float) -> list[DailySolarResponse]:
        """The factors of the ended days of the last :attr:`history_days`, in time order
        (days without a value left out); each day is computed once."""
        today = solar_day_start_s(now_s, self.panel.site.longitude_deg)
        starts = [today - k * SECONDS_PER_DAY for k in range(self.history_days, 0, -1)]
        first = conn.execute("SELECT MIN(time_s) FROM decisions").fetchone()[0]
        for start in starts:
            if start not in self._days and first is not None and start + SECONDS_PER_DAY > first:
                self._days[start] = self.day(conn, start)
        self._days = {s: d for s, d in self._days.items() if s >= starts[0]}
        return [d for s in sorted(self._days) if (d := self._days[s]) is not None]

    def day(self, conn: sqlite3.Connection, start_s: float) -> DailySolarResponse | None:
        """The factors of the day from ``start_s``, or None when the store cannot give them."""
        end_s = start_s + SECONDS_PER_DAY
        try:
            steps = step_data(self.panel, measured_from_history(
                read_history(self.state_dir, since_s=start_s, until_s=end_s - 1.0)))
        except (HistoryError, MeasuredDataError, ValueError):
            return None
        row_t, offsets = offset_series(conn, start_s - SECONDS_PER_DAY, end_s)
        if steps.n_steps < 2 or row_t.size == 0:
            return None
        t = steps.time_s[:-1]
        row = np.searchsorted(row_t, t, side="right") - 1
        use = steps.valid & (row >= 0)
        q = np.column_stack([offsets[name] for name in OFFSET_NAMES])
        sources = np.asarray(steps.inputs.sources, float)[:, :4]
        return solar_response(t[use], q[row[use]], sources[use], row[use],
                              settings=self.settings)


def by_daylight(conn: sqlite3.Connection, found: list[Finding], now_s: float, *,
                panel: PanelConfig, solar_days: Callable[[], list[DailySolarResponse]]
                ) -> list[Finding]:
    """``found`` with each parameter finding of a heat-transfer coefficient whose change
    shows in the sunlit windows alone told as a ``solar_gain_shift``
    (:mod:`dsfd.estimation.daylight_split`, docs/model.md#daylight-split), after the other
    findings (a ``solar_gain_shift`` of the solar detector itself comes first and counts).
    ``solar_days`` gives the solar detector's daily factors (:meth:`SolarDays.days`), read
    only when there is a finding to tell; without them a finding stays as it is."""
    told = {id(f) for f in found if f.kind == "parameter_shift" and f.evidence
            and f.evidence[0].signal.removeprefix("parameter:") in HEAT_TRANSFER_NAMES}
    if not told:
        return found
    times, rows = parameter_rows(conn, now_s)
    dark = window_dark(times, panel.calibration.window_h * 3600.0,
                       latitude_deg=panel.site.latitude_deg,
                       longitude_deg=panel.site.longitude_deg)
    days = solar_days()
    kept, as_solar = [], []
    for f in found:
        if id(f) not in told:
            kept.append(f)
            continue
        value, sd = rows[f.evidence[0].signal.removeprefix("parameter:")]
        split = daylight_split(times, value, sd, dark, since_s=f.start_s, end_s=now_s)
        shift = factor_shift(days, since_s=f.start_s)
        side = 1 if f.evidence[0].shift > 0 else -1
        if shift is None or not daylight_only(split, side=side, k_sd=ParameterSettings().k_sd):
            kept.append(f)
        else:
            as_solar.append(as_solar_finding(f, split, factor_shift=shift))
    return kept + as_solar
