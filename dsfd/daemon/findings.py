"""The daemon's diagnostics: the detectors run every few minutes on what it stored
(docs/model.md#findings).

After each stored cycle the runner calls :meth:`FindingsStage.after_cycle`; when
:data:`CHECK_EVERY_S` of the daemon's clock (simulated in a dry run) have passed since the
last check and no check is running, a thread starts one, so the cycle never waits for it.
A check, on its own SQLite connection:

1. reads the rows of the last :data:`CROSSCHECK_WINDOW_S` (the cavity speed, the cavity,
   room and outdoor air readings, and the command in force during each step) and, once
   :data:`RESIDUAL_MIN_S` of history is stored, the one-step prediction errors of the last
   :data:`RESIDUAL_WINDOW_S` (every :data:`RESIDUAL_EVERY_S`);
2. runs :func:`~dsfd.estimation.crosschecks.cavity_flow_check` and
   :func:`~dsfd.estimation.diagnostics.residual_change` per output;
3. reconciles what they report with the stored findings
   (:func:`dsfd.estimation.lifecycle.reconcile`) and writes the changes in one transaction
   (:mod:`dsfd.storage.findings`); each opened or ended finding is logged.

Every :data:`NIGHT_EVERY_S`, once :data:`NIGHT_MIN_S` of history is stored, it also runs
:func:`~dsfd.estimation.crosschecks.night_pane_check` on the exterior pane x1 over the last
:data:`NIGHT_WINDOW_S` (readings with the sun 6° below the horizon that had it below the
horizon two hours before).

Every :data:`PARAMETER_EVERY_S` it runs :func:`~dsfd.estimation.diagnostics.parameter_change`
per θ parameter on its on-line estimates of the last :data:`PARAMETER_WINDOW_S` of complete
UTC days, each with the posterior sd stored with it (schema 8; in the fitting coordinates,
ln θ for the positive parameters), since the calibration last started from its priors:
one value a day, the precision-weighted mean of the day's estimates with the sd of one of
them (:func:`~dsfd.estimation.parameter_watch.daily_estimates`, read by
:mod:`dsfd.storage.parameter_series`), once :data:`PARAMETER_MIN_DAYS` days make a series.
A detector that did not run in a check ends none of its findings.
"""

from __future__ import annotations

import contextvars
import itertools
import math
import sqlite3
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from dsfd.config.panel import REGIME_OPENINGS
from dsfd.daemon.logging_setup import get_logger
from dsfd.estimation.crosschecks import cavity_flow_check, night_pane_check
from dsfd.estimation.diagnostics import Finding, parameter_change, residual_change
from dsfd.estimation.lifecycle import Changes, reconcile
from dsfd.physics.solar.position import solar_position
from dsfd.storage import findings as table
from dsfd.storage.parameter_series import (
    PARAMETER_MIN_DAYS,
    PARAMETER_WINDOW_S,
    parameter_series,
    parameter_unit,
)
from dsfd.storage.schema import BUSY_TIMEOUT_MS

__all__ = ["CHECK_EVERY_S", "CROSSCHECK_WINDOW_S", "DAMPER_SHORT", "PARAMETER_EVERY_S",
           "PARAMETER_MIN_DAYS", "PARAMETER_WINDOW_S", "FindingsStage", "NightSite", "detect"]

log = get_logger("dsfd.findings")

#: How often the detectors run, on the daemon's clock [s].
CHECK_EVERY_S = 600.0
#: The cross-checks judge the last day: long enough that every path the controller uses in
#: a day is judged, so a finding does not end at night only because no path was used.
CROSSCHECK_WINDOW_S = 86400.0
#: The residual detector needs five previous days at the same time of day
#: (ResidualSettings.reference_days) and a day of spread: it runs once six days are stored,
#: on the last seven.
RESIDUAL_MIN_S = 6 * 86400.0
RESIDUAL_WINDOW_S = 7 * 86400.0
#: ... every hour: its blocks are 10 min and a step takes hours to find, and a check on
#: a week of one-minute rows costs about 0.4 s of CPU (a dry run has no minute to spare).
RESIDUAL_EVERY_S = 3600.0
#: The night check compares each night with the 7-14 before it (NightCheckSettings): it runs
#: once 8 days are stored, on the last 3 weeks, every 6 h (a night is judged once it ended).
NIGHT_MIN_S = 8 * 86400.0
NIGHT_WINDOW_S = 21 * 86400.0
NIGHT_EVERY_S = 6 * 3600.0
#: The parameter detector runs every 6 h (once PARAMETER_MIN_DAYS make a series): a day is
#: judged once it ended.
PARAMETER_EVERY_S = 6 * 3600.0
#: Night: the sun this far below the horizon [deg] (civil twilight over), and below it
#: :data:`NIGHT_AFTER_S` before too, so the day's heat has left the panes.
NIGHT_SUN_DEG = -6.0
NIGHT_AFTER_S = 2 * 3600.0
#: How often the detectors that need days of history run: (name, every [s]).
_CADENCE = (("residual", RESIDUAL_EVERY_S), ("night", NIGHT_EVERY_S),
            ("parameter", PARAMETER_EVERY_S))
_FLOW_KINDS = ("damper_no_flow", "cavity_no_flow", "cavity_flow_when_closed")
#: Short damper names (the plant's, the findings'), by opening name.
DAMPER_SHORT = {"exterior_bottom": "EB", "exterior_top": "ET", "interior_bottom": "IB",
                "interior_top": "IT"}
#: The outputs whose one-step prediction errors are watched: (reading, prediction, unit).
_RESIDUALS = (*((f"x{i}_c", f"pred_x{i}_c", "K") for i in range(1, 6)),
              ("v_cav_ms", "pred_v_cav_ms", "m/s"))
_SIGNALS = ("v_cav_ms", "x5_c", "t_room_c", "t_out_c")


def _rows(conn: sqlite3.Connection, since_s: float, until_s: float, signals: Sequence[str],
          model_cols: Sequence[str]) -> tuple[list[tuple[int, int, float]],
                                              dict[tuple[int, int], dict[str, float]]]:
    """(run, cycle, time) of the stored cycles from ``since_s`` to ``until_s`` in order, and
    per cycle the GOOD readings of ``signals`` and the ``model`` columns asked for."""
    first = conn.execute("SELECT MIN(run_id) FROM decisions WHERE time_s >= ?",
                         (since_s,)).fetchone()[0]
    if first is None:
        return [], {}
    values: dict[tuple[int, int], dict[str, float]] = {}
    marks = ", ".join("?" for _ in signals)
    for run, cycle, signal, value in conn.execute(
            f"SELECT run_id, cycle, signal, value FROM samples WHERE time_s >= ? AND "
            f"time_s <= ? AND signal IN ({marks}) AND quality = 'good' AND value IS NOT NULL",
            (since_s, until_s, *signals)):
        values.setdefault((run, cycle), {})[signal] = float(value)
    cycles = []
    for run, cycle, time_s, *cols in conn.execute(
            f"SELECT {', '.join(['run_id', 'cycle', 'time_s', *model_cols])} FROM model "
            "WHERE run_id >= ? AND time_s >= ? AND time_s <= ? ORDER BY run_id, cycle",
            (first, since_s, until_s)):
        cycles.append((int(run), int(cycle), float(time_s)))
        row = values.setdefault((run, cycle), {})
        row.update({c: float(v) for c, v in zip(model_cols, cols, strict=True)
                    if v is not None})
    return cycles, values


def _flow_finding(conn: sqlite3.Connection, now_s: float) -> Finding | None:
    """The cavity cross-check on the last day: each reading against the command in force
    during the step that ended at it (the previous cycle's applied position, same run)."""
    cycles, values = _rows(conn, now_s - CROSSCHECK_WINDOW_S, now_s, _SIGNALS,
                           ("applied_afr", "applied_or_pct"))
    t, v, opened, drive = [], [], [], []
    for (run0, c0, _), (run, cycle, time_s) in itertools.pairwise(cycles):
        before, now = values.get((run0, c0), {}), values.get((run, cycle), {})
        if run0 != run or c0 != cycle - 1 or "applied_afr" not in before \
                or not {"v_cav_ms", "x5_c"} <= now.keys():
            continue
        afr, or_pct = int(before["applied_afr"]), before.get("applied_or_pct", 0.0)
        t.append(time_s)
        v.append(now["v_cav_ms"])
        opened.append(frozenset(DAMPER_SHORT[n] for n in REGIME_OPENINGS.get(afr, ()))
                      if or_pct > 0 else frozenset())
        # the larger of the stack (cavity against outdoor air) and the room-side difference
        drive.append(max(abs(now["x5_c"] - now.get("t_room_c", np.nan)),
                         abs(now["x5_c"] - now.get("t_out_c", np.nan))))
    if not t:
        return None
    return cavity_flow_check(np.array(t), np.array(v), opened, np.array(drive))


def _residual_findings(conn: sqlite3.Connection, now_s: float) -> list[Finding]:
    cycles, values = _rows(conn, now_s - RESIDUAL_WINDOW_S, now_s,
                           [r for r, _, _ in _RESIDUALS],
                           [p for _, p, _ in _RESIDUALS])
    times = np.array([c[2] for c in cycles])
    out = []
    for reading, pred, unit in _RESIDUALS:
        res = np.array([values[c[:2]].get(reading, np.nan) - values[c[:2]].get(pred, np.nan)
                        for c in cycles])
        f = residual_change(times, res, signal=reading, unit=unit)
        if f is not None:
            out.append(f)
    return out


@dataclass(frozen=True, kw_only=True)
class NightSite:
    """What the night check needs of the panel: where the sun is, and the room temperature
    used when the room air is not measured (``room.t_in_c``)."""

    latitude_deg: float
    longitude_deg: float
    room_c: float


def _night_finding(conn: sqlite3.Connection, now_s: float, site: NightSite) -> Finding | None:
    cycles, values = _rows(conn, now_s - NIGHT_WINDOW_S, now_s, ("x1_c", "t_out_c", "t_room_c"),
                           ())
    if not cycles:
        return None
    t = np.array([c[2] for c in cycles])
    col = {n: np.array([values[c[:2]].get(n, np.nan) for c in cycles])
           for n in ("x1_c", "t_out_c", "t_room_c")}
    room = np.where(np.isfinite(col["t_room_c"]), col["t_room_c"], site.room_c)
    lat, lon = site.latitude_deg, site.longitude_deg
    night = ((solar_position(t, lat, lon).elevation_deg < NIGHT_SUN_DEG)
             & (solar_position(t - NIGHT_AFTER_S, lat, lon).elevation_deg < 0.0))
    return night_pane_check(t, col["x1_c"], col["t_out_c"], room, night, pane="x1_c")


def _parameter_findings(conn: sqlite3.Connection, now_s: float) -> list[Finding] | None:
    """The parameter detector on each θ parameter's daily series; None (not run) while the
    series are too short."""
    series = parameter_series(conn, now_s)
    if series is None:
        return None
    found = (parameter_change(t, v, sd, name=name, unit=parameter_unit(name))
             for name, (t, v, sd) in series.items())
    return [_since_the_day(f) for f in found if f is not None]


def _since_the_day(f: Finding) -> Finding:
    """The finding dated from the start of the first day that moved (a daily value's time is
    the day's last estimate; the change began some time during that day)."""
    day_s = math.floor(f.start_s / 86400.0) * 86400.0
    return replace(f, start_s=day_s, evidence=tuple(replace(e, since_s=day_s)
                                                    for e in f.evidence))


def detect(conn: sqlite3.Connection, now_s: float, *, residuals: bool = True,
           night: NightSite | None = None, parameters: bool = True
           ) -> tuple[list[Finding], set[str]]:
    """What the detectors report on the rows stored up to ``now_s``, and the kinds judged
    (those of the detectors that ran): the cavity cross-check always, the residual CUSUM if
    ``residuals``, the night check if ``night``, the parameter detector if ``parameters``;
    each of the last three once its history is stored."""
    found = [f for f in (_flow_finding(conn, now_s),) if f is not None]
    judged = set(_FLOW_KINDS)
    oldest = conn.execute("SELECT MIN(time_s) FROM decisions").fetchone()[0]
    history_s = 0.0 if oldest is None else now_s - float(oldest)
    if residuals and history_s >= RESIDUAL_MIN_S:
        found += _residual_findings(conn, now_s)
        judged.add("residual_shift")
    if night is not None and history_s >= NIGHT_MIN_S:
        found += [f for f in (_night_finding(conn, now_s, night),) if f is not None]
        judged |= {"pane_out_of_bounds", "pane_offset_shift"}
    shifts = _parameter_findings(conn, now_s) if parameters else None
    if shifts is not None:
        found += shifts
        judged.add("parameter_shift")
    return found, judged


class FindingsStage:
    """Runs :func:`detect` off the loop and keeps the ``findings`` table up to date."""

    def __init__(self, database: Path, *, run_id: Callable[[], int | None],
                 night: NightSite | None = None, every_s: float = CHECK_EVERY_S) -> None:
        self.database = database
        self.run_id = run_id
        self.night = night
        self.every_s = every_s
        self._last_s: float | None = None
        #: The last check that ran the residual CUSUM, the night check, the parameters.
        self._ran_s: dict[str, float] = {}
        self._thread: threading.Thread | None = None
        #: Checks that failed (logged); the next one is tried as usual.
        self.failures = 0

    def after_cycle(self, now_s: float) -> bool:
        """Start a check if one is due and none runs; whether one started."""
        if self._thread is not None and self._thread.is_alive():
            return False
        # abs: a wall clock stepped back (NTP) must not stop the checks until it catches up
        if self._last_s is not None and abs(now_s - self._last_s) < self.every_s:
            return False
        self._last_s = now_s
        ctx = contextvars.copy_context()  # the log lines keep the panel
        self._thread = threading.Thread(target=ctx.run, args=(self._check, now_s),
                                        name="dsfd-findings", daemon=True)
        self._thread.start()
        return True

    def stop(self, *, timeout_s: float = 30.0) -> None:
        """Let a running check finish (its transaction is short; the detectors bounded)."""
        if self._thread is not None:
            self._thread.join(timeout_s)

    def _check(self, now_s: float) -> None:
        try:
            conn = sqlite3.connect(self.database, timeout=BUSY_TIMEOUT_MS / 1000)
            try:
                self.check(conn, now_s)
            finally:
                conn.close()
        except Exception:  # diagnostics must never stop the control of the panel
            self.failures += 1
            log.exception("findings check failed")

    def check(self, conn: sqlite3.Connection, now_s: float) -> Changes:
        """One check at ``now_s`` on ``conn``: detect, reconcile, store, log."""
        due = {name for name, every in _CADENCE
               if abs(now_s - self._ran_s.get(name, -math.inf)) >= every}
        found, judged = detect(conn, now_s, residuals="residual" in due,
                               night=self.night if "night" in due else None,
                               parameters="parameter" in due)
        for name, kind in (("residual", "residual_shift"), ("night", "pane_offset_shift"),
                           ("parameter", "parameter_shift")):
            if kind in judged:
                self._ran_s[name] = now_s
        changes = reconcile(found, table.load(conn), judged=judged)
        opened = table.apply(conn, changes, now_s=now_s, run_id=self.run_id())
        for fid, f in zip(opened, changes.opened, strict=True):
            log.warning("finding #%d %s: %s", fid, f.kind, f.action, finding_id=fid,
                        kind=f.kind, confidence=round(f.confidence, 3))
        for fid in changes.ended:
            log.info("finding #%d ended: the evidence went away", fid, finding_id=fid)
        return changes
