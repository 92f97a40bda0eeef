"""One figure per stored finding: the evidence its detector judged, drawn from the same rows.

The series come from :mod:`dsfd.storage.evidence` (what the daemon's check feeds the
detectors) and the detectors' own first steps (:func:`~dsfd.estimation.diagnostics.
residual_blocks`, :func:`~dsfd.estimation.crosschecks.nightly_offsets`), so a figure shows
what was judged, not a look-alike. The window is the finding's: for a residual shift a day
before its start to the last check that saw it; for the cross-checks the window the last
check that saw it judged. Times on the axes are local standard time, like every figure of
the report; marked: the finding's start and detection (and its end), as stored.
"""

from __future__ import annotations

import dataclasses
import sqlite3
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from dsfd.config.panel import Parameters
from dsfd.estimation.crosschecks import FlowCheckSettings, NightCheckSettings, nightly_offsets
from dsfd.estimation.daylight_split import told_by_daylight
from dsfd.estimation.diagnostics import (
    residual_settings,
)
from dsfd.estimation.night_offsets import (
    NIGHT_OFFSET_SETTINGS,
    NIGHT_SPREAD_ALLOWANCE,
    night_allowance,
)
from dsfd.estimation.parameter_watch import LOG_UNIT
from dsfd.estimation.params import OFFSET_NAMES
from dsfd.report.cusum_figures import block_figure
from dsfd.report.figure_axes import FindingAxes as _Axes
from dsfd.report.figure_axes import NoEvidence
from dsfd.report.figure_axes import end_s as _end_s
from dsfd.report.plotting import OUTSIDE, STATE_COLOURS, STATE_LABELS, WIDTH_IN
from dsfd.report.solar_figures import daylight_figure, solar_figure
from dsfd.storage.evidence import (
    CROSSCHECK_WINDOW_S,
    NIGHT_OFFSET_REFERENCE_S,
    NIGHT_OFFSET_WINDOW_S,
    NIGHT_WINDOW_S,
    RESIDUAL_REFERENCE_S,
    RESIDUAL_WINDOW_S,
    RESIDUALS,
    flow_series,
    night_mask,
    night_series,
    residual_series,
)
from dsfd.storage.findings import first_signal
from dsfd.storage.parameter_series import (
    PARAMETER_MIN_DAYS,
    offset_series,
    parameter_series,
    parameter_unit,
)

__all__ = ["FLOW_KINDS", "NIGHT_KINDS", "NoEvidence", "evidence_figure", "flow_figure",
           "night_figure", "night_offset_figure", "parameter_figure", "residual_figure"]

FLOW_KINDS = ("damper_no_flow", "cavity_no_flow", "cavity_flow_when_closed")
NIGHT_KINDS = ("pane_out_of_bounds", "pane_offset_shift")
_HOUR = 3600.0
_PATH_COLOURS = ("#1f77b4", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22")


def _signal(row: Mapping[str, Any]) -> str:
    ev = row.get("evidence") or [{}]
    name = str(row.get("subject") or ev[0].get("signal") or "")
    return name.split(":", 1)[-1]


def residual_figure(conn: sqlite3.Connection, row: Mapping[str, Any], offset_h: float
                    ) -> Figure:
    """Block means of the one-step prediction error with the detector's same-time reference,
    and the CUSUM statistic against its threshold."""
    reading = _signal(row)
    unit = next((u for r, _, u in RESIDUALS if r == reading), "")
    end = _end_s(row)
    lo_s = float(row["start_s"]) - 86400.0
    output = [o for o in RESIDUALS if o[0] == reading]
    judge_from = float(row["detected_s"]) - RESIDUAL_WINDOW_S  # as the check that found it
    times, errors, regime = (residual_series(conn, judge_from - RESIDUAL_REFERENCE_S,
                                             end + _HOUR, output) if output
                             else (np.zeros(0), {}, np.zeros(0)))
    err = errors.get(reading, np.zeros(0))
    if not np.isfinite(err).any():
        raise NoEvidence(f"no stored readings and predictions of {reading or '?'} in the "
                         "finding's window")
    label = STATE_LABELS.get(reading[:2], "cavity air speed" if reading == "v_cav_ms"
                             else reading)
    return block_figure(
        row, _Axes(offset_h, lo_s, end + _HOUR), times, err, settings=residual_settings(unit),
        control=regime,
        judge_from_s=judge_from, title=f"one-step prediction error of {label}", unit=unit,
        colour=STATE_COLOURS.get(reading[:2], "#8c564b"),
        each="each cycle: reading − prediction", ylabel="measured − predicted",
        centre="reference: median at this time of day, 5 previous days")


def night_offset_figure(conn: sqlite3.Connection, row: Mapping[str, Any], offset_h: float,
                        config: Mapping[str, Any] | None) -> Figure:
    """A node's heat-flux offset at night: each stored estimate, the 30-min block means the
    detector judges with their reference, and the CUSUM statistic against its threshold."""
    name = _signal(row)
    end = _end_s(row)
    lo_s = float(row["start_s"]) - 2 * 86400.0
    site = (config or {}).get("site") or {}
    if site.get("latitude_deg") is None or site.get("longitude_deg") is None:
        raise NoEvidence("the site is not recorded with this log (give --config): night "
                         "cannot be told")
    judge_from = float(row["detected_s"]) - NIGHT_OFFSET_WINDOW_S  # as the check that found it
    times, values = offset_series(conn, judge_from - NIGHT_OFFSET_REFERENCE_S, end + _HOUR)
    q = values.get(name, np.full(times.size, np.nan))
    night = night_mask(times, latitude_deg=float(site["latitude_deg"]),
                       longitude_deg=float(site["longitude_deg"]))
    q = np.where(night, q, np.nan)
    if not np.isfinite(q).any():
        raise NoEvidence(f"no stored night estimates of {name or '?'} in the finding's window")
    return block_figure(
        row, _Axes(offset_h, lo_s, end + _HOUR), times, q, settings=NIGHT_OFFSET_SETTINGS,
        control=None,
        judge_from_s=judge_from, title=f"heat-flux offset {name} at night", unit="W/m2",
        allowance=night_allowance,
        allowance_label=f",\nor {NIGHT_SPREAD_ALLOWANCE:g}× the recent nights' departures,",
        colour=STATE_COLOURS.get(name.removeprefix("q_")[:2], "#8c564b"),
        each="each on-line estimate at night", ylabel="offset",
        centre="reference: median at this time of night, 5 previous days")


def flow_figure(conn: sqlite3.Connection, row: Mapping[str, Any], offset_h: float) -> Figure:
    """The measured cavity speed, coloured by the dampers the command in force opened, above
    the commanded regime and damper opening: the last day the latest check judged."""
    end = _end_s(row)
    ax_t = _Axes(offset_h, end - CROSSCHECK_WINDOW_S, end)
    s = flow_series(conn, ax_t.lo_s, ax_t.hi_s)
    fig = Figure(figsize=(WIDTH_IN, 5.2), layout="constrained")
    speed, regime, opening = fig.subplots(3, 1, sharex=True, height_ratios=[1.7, 0.8, 0.6])
    subject = f" {row['subject']}" if row.get("subject") else ""
    fig.suptitle(f"#{row['finding_id']} {row['kind']}{subject}: cavity air speed against "
                 "the commanded regime", fontsize=12, x=0.01, ha="left")
    if not s.time_s.size:
        raise NoEvidence("no stored cavity speed readings in the window the check judged")
    ax_t.lo_s = max(ax_t.lo_s, float(s.time_s[0]) - 10 * 60.0)  # no empty day on the left
    st = FlowCheckSettings()
    t = ax_t.local(s.time_s)
    paths = sorted(set(s.opened), key=lambda p: (len(p) > 0, sorted(p)))
    hollow = False
    for i, p in enumerate(paths):
        sel = np.array([o == p for o in s.opened])
        name = "+".join(sorted(p)) if p else "all shut"
        colour = "#7f7f7f" if not p else _PATH_COLOURS[i % len(_PATH_COLOURS)]
        judged = sel if not p else sel & (s.drive_k >= st.min_drive_k) & ~(
            s.expected_ms < st.min_expected_ms)
        speed.plot(t[judged], s.v_cav_ms[judged], "o", ms=3, color=colour,
                   label=f"{name} open" if p else name)
        if (sel & ~judged).any():
            speed.plot(t[sel & ~judged], s.v_cav_ms[sel & ~judged], "o", ms=3, mfc="none",
                       color=colour, alpha=0.6)
            hollow = True
    thresholds = sorted({round(float(e["threshold"]), 6) for e in row.get("evidence") or []
                         if e.get("threshold") is not None})
    for thr in thresholds:
        speed.axhline(thr, color="black", ls="--", lw=1.0,
                      label=f"threshold {thr:.3g} m/s" + (
                          " (closed-cavity limit)" if row["kind"] == "cavity_flow_when_closed"
                          else " (an open path must move more)"))
    if hollow:
        speed.plot([], [], "o", ms=3, mfc="none", color="#555555",
                   label=f"hollow: not judged (driving difference < {st.min_drive_k:g} K, "
                   f"or the model expected < {st.min_expected_ms:g} m/s)")
    speed.set_ylabel("cavity air speed\n[m/s]")
    speed.set_ylim(bottom=0)
    ax_t.marks(speed, row, legend=True)
    speed.legend(**OUTSIDE)
    ax_t.setup(speed, label=False)
    regime.step(t, s.afr, where="pre", color="#1f77b4", lw=1.3)
    regime.set_ylim(0.5, 10.5)
    regime.set_yticks([1, 4, 7, 10])
    regime.set_ylabel("regime\n(1-10)")
    ax_t.marks(regime, row, legend=False)
    ax_t.setup(regime, label=False)
    opening.step(t, s.or_pct, where="pre", color="#2ca02c", lw=1.3)
    opening.set_ylim(-5, 105)
    opening.set_ylabel("opening\n[%]")
    ax_t.marks(opening, row, legend=False)
    ax_t.setup(opening, label=True)
    return fig


def night_figure(conn: sqlite3.Connection, row: Mapping[str, Any], offset_h: float,
                 config: Mapping[str, Any] | None) -> Figure:
    """A pane minus the outdoor air at night: each reading, the nightly medians the check
    judges and its bounds, over the weeks the latest check judged."""
    end = _end_s(row)
    ax_t = _Axes(offset_h, end - NIGHT_WINDOW_S, end)
    fig = Figure(figsize=(WIDTH_IN, 4.2), layout="constrained")
    ax = fig.subplots()
    pane = _signal(row).split("-", 1)[0] or "x1_c"
    fig.suptitle(f"#{row['finding_id']} {row['kind']}: {STATE_LABELS.get(pane[:2], pane)} "
                 "minus the outdoor air at night", fontsize=12, x=0.01, ha="left")
    site, room = (config or {}).get("site") or {}, (config or {}).get("room") or {}
    if site.get("latitude_deg") is None or site.get("longitude_deg") is None:
        raise NoEvidence("the site is not recorded with this log (give --config): night "
                         "cannot be told")
    s = night_series(conn, ax_t.lo_s, ax_t.hi_s, latitude_deg=float(site["latitude_deg"]),
                     longitude_deg=float(site["longitude_deg"]),
                     room_c=float(room.get("t_in_c", 22.0)), pane=pane)
    st = NightCheckSettings()
    o = nightly_offsets(s.time_s, s.pane_c, s.t_out_c, s.t_room_c, s.night, settings=st)
    if not o.nights:
        raise NoEvidence("no night with enough readings in the window the check judged")
    ax_t.lo_s = max(ax_t.lo_s, float(s.time_s[o.nights[0][0]]) - 6 * _HOUR)
    ax.plot(ax_t.local(s.time_s), o.offset_k, ".", ms=1.5, color="#aaaaaa",
            label="each night reading")
    mid = np.array([float(np.median(s.time_s[n])) for n in o.nights])
    ax.plot(ax_t.local(mid), o.medians, "o-", ms=4, color=STATE_COLOURS.get(pane[:2], "k"),
            label="nightly median (the check's input)")
    start = float(row["start_s"])
    before = o.medians[mid < start][-st.reference_nights:]
    if row["kind"] == "pane_out_of_bounds":
        # the bounds a pane between the sky and the room keeps to
        ax.plot(ax_t.local(mid), o.upper_k, "_", ms=12, mew=2, color="#d62728",
                label=f"upper bound: room − outdoor air + {st.tolerance_k:g} K")
        ax.axhline(-st.sky_depression_k, color="#1f77b4", ls="--", lw=1.0,
                   label=f"lower bound: −{st.sky_depression_k:g} K (clear sky)")
    elif before.size:
        # an offset shift is judged against the nights before it, well inside the bounds
        level = float(np.median(before))
        ax.plot(ax_t.local(np.array([mid[mid < start][-before.size], start])), [level, level],
                color="black", ls="--", lw=1.1,
                label="reference: median of the nights before the start")
    ax.set_ylabel(f"{pane[:2]} − outdoor air\n[K]")
    ax_t.marks(ax, row, legend=True)
    ax.legend(**OUTSIDE)
    ax_t.setup(ax, label=True)
    return fig


def parameter_figure(conn: sqlite3.Connection, row: Mapping[str, Any], offset_h: float
                     ) -> Figure:
    """A calibrated parameter's on-line estimates and the daily values the detector judged,
    each ± its posterior sd, with the level of the days before the start."""
    name = _signal(row)
    end = _end_s(row)
    series = parameter_series(conn, end)
    if series is None or name not in series or not series[name][0].size:
        raise NoEvidence(f"fewer than {PARAMETER_MIN_DAYS} days of {name or '?'} estimates "
                         "with their posterior sd before the last check")
    t_day, z_day, sd_day = series[name]
    linear = parameter_unit(name) != LOG_UNIT

    def physical(z: np.ndarray) -> np.ndarray:  # the detector's coordinate → θ
        return z if linear else np.exp(z)

    ax_t = _Axes(offset_h, float(t_day[0]) - 86400.0, end)
    raw = _online_estimates(conn, name, ax_t.lo_s, end)
    fig = Figure(figsize=(WIDTH_IN, 4.2), layout="constrained")
    ax = fig.subplots()
    fig.suptitle(f"#{row['finding_id']} parameter_shift: the calibrated {name}, day by day",
                 fontsize=12, x=0.01, ha="left")
    ax.plot(ax_t.local(raw[:, 0]), raw[:, 1], ".", ms=1.5, color="#aaaaaa",
            label="each on-line estimate")
    mid = t_day - 43200.0  # a day's value is complete at its last estimate: drawn mid-day
    centre = physical(z_day)
    ax.errorbar(ax_t.local(mid), centre, yerr=[centre - physical(z_day - sd_day),
                                               physical(z_day + sd_day) - centre],
                fmt="o", ms=4, capsize=3, color="#1f77b4",
                label=("daily value ± posterior sd (the detector's input)" if name not in
                       OFFSET_NAMES else "daily value ± the sd it is given (the detector's "
                       "input)"))
    before = t_day < float(row["start_s"])
    if before.any():
        w = 1.0 / sd_day[before] ** 2
        level = float(physical(np.sum(w * z_day[before]) / np.sum(w)))
        ax.plot(ax_t.local(np.array([mid[before][0], float(row["start_s"])])),
                [level, level], color="black", ls="--", lw=1.1,
                label="level of the days before the start")
    unit = {f.name: f.metadata.get("unit") for f in dataclasses.fields(Parameters)}.get(
        name, "W/m²" if name in OFFSET_NAMES else None)
    ax.set_ylabel(f"{name}\n[{'-' if unit in (None, '1') else unit}]")
    if not linear:
        ax.set_yscale("log")  # the sd is relative: equal bars for equal evidence
    ax_t.marks(ax, row, legend=True)
    ax.legend(**OUTSIDE)
    ax_t.setup(ax, label=True)
    return fig


def _online_estimates(conn: sqlite3.Connection, name: str, since_s: float, until_s: float
                      ) -> np.ndarray:
    """(time, value) of a parameter's on-line estimates; a heat-flux offset is read from the
    ``other`` JSON column, where the daemon stores it."""
    if name not in OFFSET_NAMES:
        return np.array(conn.execute(
            f"SELECT time_s, {name} FROM parameters WHERE source = 'online' AND time_s >= ? "
            "AND time_s <= ? ORDER BY time_s", (since_s, until_s)).fetchall(),
            float).reshape(-1, 2)
    rows = conn.execute(
        "SELECT time_s, json_extract(other, ?) FROM parameters WHERE source = 'online' AND "
        "time_s >= ? AND time_s <= ? ORDER BY time_s", (f"$.{name}", since_s, until_s))
    return np.array([(t, np.nan if v is None else v) for t, v in rows], float).reshape(-1, 2)


def evidence_figure(conn: sqlite3.Connection, row: Mapping[str, Any], *, offset_h: float,
                    config: Mapping[str, Any] | None, state_dir: Path | None = None
                    ) -> Figure | str:
    """The figure of one stored finding (a row of :func:`dsfd.storage.findings.
    findings_between`), or why there is none (a kind with no figure, or no rows to draw it
    from)."""
    draw: dict[str, Callable[[], Figure]] = {
        "residual_shift": lambda: residual_figure(conn, row, offset_h),
        **{k: (lambda: flow_figure(conn, row, offset_h)) for k in FLOW_KINDS},
        **{k: (lambda: night_figure(conn, row, offset_h, config)) for k in NIGHT_KINDS},
        "parameter_shift": lambda: parameter_figure(conn, row, offset_h),
        "night_offset_shift": lambda: night_offset_figure(conn, row, offset_h, config)}
    if state_dir is not None:
        draw["solar_gain_shift"] = lambda: solar_figure(conn, row, offset_h, config, state_dir)
    if told_by_daylight(str(row["kind"]), first_signal(row)):
        draw["solar_gain_shift"] = lambda: daylight_figure(conn, row, offset_h, config)
    f = draw.get(str(row["kind"]))
    if f is None:
        return f"no figure for a {row['kind']} finding"
    try:
        return f()
    except NoEvidence as exc:
        return f"no figure: {exc}"
