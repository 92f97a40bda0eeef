"""The series the diagnostics judge, read from a panel's database (docs/model.md#findings).

The daemon's findings check (:mod:`dsfd.daemon.findings`) feeds these to the detectors, and
``dsfd report`` draws the evidence of a stored finding from the same series
(:mod:`dsfd.report.diagnostics`), so a figure shows what the detector judged, not a
look-alike. Each reader takes a connection and a time window and returns arrays; nothing
here writes.

The windows and the history each detector needs before it judges are defined here too: the
daemon schedules its checks with them and the report says them when it has nothing to show.
"""

from __future__ import annotations

import itertools
import sqlite3
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import REGIME_OPENINGS
from dsfd.physics.solar.position import solar_position

__all__ = ["CROSSCHECK_WINDOW_S", "DAMPER_SHORT", "NIGHT_AFTER_S", "NIGHT_MIN_S",
           "NIGHT_OFFSET_MIN_S", "NIGHT_OFFSET_REFERENCE_S", "NIGHT_OFFSET_WINDOW_S",
           "NIGHT_SUN_DEG", "NIGHT_WINDOW_S", "RESIDUALS", "RESIDUAL_MIN_S",
           "RESIDUAL_REFERENCE_S", "RESIDUAL_WINDOW_S", "FlowSeries", "NightSeries",
           "flow_series", "night_mask", "night_series", "read_rows", "residual_series"]

#: The cross-checks judge the last day: long enough that every path the controller uses in
#: a day is judged, so a finding does not end at night only because no path was used.
CROSSCHECK_WINDOW_S = 86400.0
#: The residual detector needs five previous days at the same time of day
#: (ResidualSettings.reference_days) and a day of spread: it runs once six days are stored
#: and judges the last seven, reading the 6 days before them as references only (the 5
#: days and the spread's 6-h guard), so a block's reference is the same at every check
#: (dsfd.estimation.diagnostics.block_change).
RESIDUAL_MIN_S = 6 * 86400.0
RESIDUAL_WINDOW_S = 7 * 86400.0
RESIDUAL_REFERENCE_S = 6 * 86400.0
#: The night check compares each night with the 7-14 before it (NightCheckSettings): it runs
#: once 8 days are stored, on the last 3 weeks.
NIGHT_MIN_S = 8 * 86400.0
NIGHT_WINDOW_S = 21 * 86400.0
#: The night offsets compare each hour of a night with the same hours of the 5 nights before,
#: and need two of them for a reference and about three for the spread
#: (dsfd.estimation.night_offsets.NIGHT_OFFSET_SETTINGS): they run once 4 days are stored and
#: judge the last 7 days, reading the 6 before as references only (5 days and the spread's
#: guard), so a block's reference is the same at every check.
NIGHT_OFFSET_MIN_S = 4 * 86400.0
NIGHT_OFFSET_WINDOW_S = 7 * 86400.0
NIGHT_OFFSET_REFERENCE_S = 6 * 86400.0
#: Night: the sun this far below the horizon [deg] (civil twilight over), and below it
#: :data:`NIGHT_AFTER_S` before too, so the day's heat has left the panes.
NIGHT_SUN_DEG = -6.0
NIGHT_AFTER_S = 2 * 3600.0
#: Short damper names (the plant's, the findings'), by opening name.
DAMPER_SHORT = {"exterior_bottom": "EB", "exterior_top": "ET", "interior_bottom": "IB",
                "interior_top": "IT"}
#: The outputs whose one-step prediction errors are watched: (reading, prediction, unit).
RESIDUALS = (*((f"x{i}_c", f"pred_x{i}_c", "K") for i in range(1, 6)),
             ("v_cav_ms", "pred_v_cav_ms", "m/s"))
_FLOW_SIGNALS = ("v_cav_ms", "x5_c", "t_room_c", "t_out_c")


def read_rows(conn: sqlite3.Connection, since_s: float, until_s: float,
              signals: Sequence[str], model_cols: Sequence[str]
              ) -> tuple[list[tuple[int, int, float]], dict[tuple[int, int], dict[str, float]]]:
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


@dataclass(frozen=True, eq=False)
class FlowSeries:
    """What the cavity cross-check judges: per reading of the cavity speed, the command in
    force during the step that ended at it. Arrays of shape (n,)."""

    time_s: np.ndarray
    v_cav_ms: np.ndarray
    #: The dampers that command opened (short names; empty: the closed cavity).
    opened: list[frozenset[str]]
    #: The larger of |x5 − t_room| and |x5 − t_out| [K].
    drive_k: np.ndarray
    #: The commanded regime (1-10) and damper opening [%] in force.
    afr: np.ndarray
    or_pct: np.ndarray
    #: The model's one-step prediction of the reading [m/s] (NaN where none is stored).
    expected_ms: np.ndarray


def flow_series(conn: sqlite3.Connection, since_s: float, until_s: float) -> FlowSeries:
    """Each reading against the command in force during the step that ended at it (the
    previous cycle's applied position, same run)."""
    cycles, values = read_rows(conn, since_s, until_s, _FLOW_SIGNALS,
                               ("applied_afr", "applied_or_pct", "pred_v_cav_ms"))
    t, v, opened, drive, afr, or_pct, expected = [], [], [], [], [], [], []
    for (run0, c0, _), (run, cycle, time_s) in itertools.pairwise(cycles):
        before, now = values.get((run0, c0), {}), values.get((run, cycle), {})
        if run0 != run or c0 != cycle - 1 or "applied_afr" not in before \
                or not {"v_cav_ms", "x5_c"} <= now.keys():
            continue
        regime, opening = int(before["applied_afr"]), before.get("applied_or_pct", 0.0)
        t.append(time_s)
        v.append(now["v_cav_ms"])
        opened.append(frozenset(DAMPER_SHORT[n] for n in REGIME_OPENINGS.get(regime, ()))
                      if opening > 0 else frozenset())
        # the larger of the stack (cavity against outdoor air) and the room-side difference
        drive.append(max(abs(now["x5_c"] - now.get("t_room_c", np.nan)),
                         abs(now["x5_c"] - now.get("t_out_c", np.nan))))
        afr.append(regime)
        or_pct.append(opening)
        # the row's prediction is of this reading, made with the command in force
        expected.append(now.get("pred_v_cav_ms", np.nan))
    return FlowSeries(np.array(t, float), np.array(v, float), opened, np.array(drive, float),
                      np.array(afr, float), np.array(or_pct, float),
                      np.array(expected, float))


def residual_series(conn: sqlite3.Connection, since_s: float, until_s: float,
                    outputs: Sequence[tuple[str, str, str]] = RESIDUALS
                    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
    """Times of the stored cycles; per output reading, its one-step prediction error (GOOD
    reading minus the ``model`` table's prediction; NaN where either is missing); and the
    regime in force during the step that ended at each cycle (the previous cycle's applied
    regime in the same run; NaN where unknown), which the prediction was made with."""
    cycles, values = read_rows(conn, since_s, until_s, [r for r, _, _ in outputs],
                               [*(p for _, p, _ in outputs), "applied_afr"])
    times = np.array([c[2] for c in cycles], float)
    regime = np.full(times.size, np.nan)
    for i, ((run0, c0, _), (run, cycle, _)) in enumerate(itertools.pairwise(cycles), start=1):
        if run0 == run and c0 == cycle - 1:
            regime[i] = values[(run0, c0)].get("applied_afr", np.nan)
    return times, {reading: np.array([values[c[:2]].get(reading, np.nan)
                                      - values[c[:2]].get(pred, np.nan) for c in cycles], float)
                   for reading, pred, _ in outputs}, regime


@dataclass(frozen=True, eq=False)
class NightSeries:
    """What the night pane check judges: the pane, outdoor and room air of each stored cycle
    and whether it was night. Arrays of shape (n,)."""

    time_s: np.ndarray
    pane_c: np.ndarray
    t_out_c: np.ndarray
    #: The room air reading, else the panel's ``room.t_in_c``.
    t_room_c: np.ndarray
    night: np.ndarray


def night_series(conn: sqlite3.Connection, since_s: float, until_s: float, *,
                 latitude_deg: float, longitude_deg: float, room_c: float,
                 pane: str = "x1_c") -> NightSeries:
    """Night: the sun more than :data:`NIGHT_SUN_DEG` below the horizon that was already
    below it :data:`NIGHT_AFTER_S` before (docs/model.md#findings)."""
    cycles, values = read_rows(conn, since_s, until_s, (pane, "t_out_c", "t_room_c"), ())
    t = np.array([c[2] for c in cycles], float)
    col = {n: np.array([values[c[:2]].get(n, np.nan) for c in cycles], float)
           for n in (pane, "t_out_c", "t_room_c")}
    room = np.where(np.isfinite(col["t_room_c"]), col["t_room_c"], room_c)
    night = night_mask(t, latitude_deg=latitude_deg, longitude_deg=longitude_deg)
    return NightSeries(t, col[pane], col["t_out_c"], room, night)


def night_mask(times_s: np.ndarray, *, latitude_deg: float, longitude_deg: float
               ) -> np.ndarray:
    """Night at each of ``times_s`` [s]: the sun more than :data:`NIGHT_SUN_DEG` below the
    horizon, and below it :data:`NIGHT_AFTER_S` before (bool array)."""
    t = np.asarray(times_s, float)
    if not t.size:
        return np.zeros(0, bool)
    return ((solar_position(t, latitude_deg, longitude_deg).elevation_deg < NIGHT_SUN_DEG)
            & (solar_position(t - NIGHT_AFTER_S, latitude_deg,
                              longitude_deg).elevation_deg < 0.0))
