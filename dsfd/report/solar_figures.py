"""The figures of a ``solar_gain_shift`` finding: the solar detector's daily share of the
computed sun (docs/model.md#diagnostics-solar), or, for a heat-transfer coefficient's change
told as the sun's, that coefficient's estimates from the dark and the sunlit calibration
windows (docs/model.md#daylight-split).
"""

from __future__ import annotations

import dataclasses
import sqlite3
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import ScalarFormatter

from dsfd.config.panel import PanelConfig, Parameters
from dsfd.estimation.daylight_split import MIN_HALF_SPAN_S, window_dark
from dsfd.estimation.parameter_watch import daily_estimates
from dsfd.report.figure_axes import FindingAxes, NoEvidence, end_s
from dsfd.report.plotting import OUTSIDE, WIDTH_IN
from dsfd.storage.findings import first_signal
from dsfd.storage.parameter_series import parameter_rows

__all__ = ["daylight_figure", "solar_figure"]

#: The two halves of a coefficient's estimates: (mask of dark windows wanted, label, colour).
_HALVES = ((True, "night windows", "#1f3a93"), (False, "sunlit windows", "#2ca02c"))


def _panel(config: Mapping[str, Any] | None) -> PanelConfig:
    from dsfd.config import ConfigError, panel_from_mapping

    try:
        return panel_from_mapping(dict(config or {}), source="the stored configuration")
    except ConfigError as exc:
        raise NoEvidence(f"the stored configuration does not load ({exc})") from exc


def solar_figure(conn: sqlite3.Connection, row: Mapping[str, Any], offset_h: float,
                 config: Mapping[str, Any] | None, state_dir: Path) -> Figure:
    """The daily share of the computed sun the offsets remove (the solar detector's input,
    recomputed from the stored rows) ± its standard error, and the exterior pane's and the
    slats' own shares, with the level of the days before the start."""
    from dsfd.storage.solar_series import SolarDays

    days = SolarDays(_panel(config), state_dir).days(conn, end_s(row))
    if not days:
        raise NoEvidence("no day with two hours of sun before the last check")
    t = np.array([d.time_s for d in days])
    b = np.array([d.factor for d in days])
    nodes = np.array([d.node_factors for d in days])
    ax_t = FindingAxes(offset_h, float(t[0]) - 86400.0, end_s(row))
    fig = Figure(figsize=(WIDTH_IN, 4.2), layout="constrained")
    ax = fig.subplots()
    fig.suptitle(f"#{row['finding_id']} solar_gain_shift: share of the computed sun the "
                 "offsets remove, day by day", fontsize=12, x=0.01, ha="left")
    ax.errorbar(ax_t.local(t), b, yerr=[d.sd for d in days], fmt="o", ms=4, capsize=3,
                color="#1f77b4", label="all nodes ± standard error (the detector's input)")
    ax.plot(ax_t.local(t), nodes[:, 0], "s", ms=3.5, color="#ff7f0e", mfc="none",
            label="exterior pane x1 alone (none: its offset was held)")
    ax.plot(ax_t.local(t), nodes[:, 3], "^", ms=3.5, color="#2ca02c", mfc="none",
            label="slats x4 alone")
    before = t < float(row["start_s"])
    if before.any():
        level = float(np.mean(b[before][-7:]))
        ax.plot(ax_t.local(np.array([t[before][-7:][0], float(row["start_s"])])),
                [level, level], color="black", ls="--", lw=1.1,
                label="level of the days before the start")
    ax.axhline(0.0, color="#888888", lw=0.8)
    ax.set_ylabel("offset / computed sun\n[-]")
    ax_t.marks(ax, row, legend=True)
    ax.legend(**OUTSIDE)
    ax_t.setup(ax, label=True)
    return fig


def daylight_figure(conn: sqlite3.Connection, row: Mapping[str, Any], offset_h: float,
                    config: Mapping[str, Any] | None) -> Figure:
    """A heat-transfer coefficient's on-line estimates and daily values from the windows
    that were all night and from those with sun, each with its level before the start."""
    panel = _panel(config)
    name = first_signal(row).removeprefix("parameter:")
    end = end_s(row)
    times, rows = parameter_rows(conn, end)
    if name not in rows or not times.size:
        raise NoEvidence(f"no on-line estimates of {name} before the last check")
    value, sd = rows[name]
    dark = window_dark(times, panel.calibration.window_h * 3600.0,
                       latitude_deg=panel.site.latitude_deg,
                       longitude_deg=panel.site.longitude_deg)
    ax_t = FindingAxes(offset_h, float(times[0]), end)
    fig = Figure(figsize=(WIDTH_IN, 4.2), layout="constrained")
    ax = fig.subplots()
    fig.suptitle(f"#{row['finding_id']} solar_gain_shift: the calibrated {name} by night and "
                 "in the sun", fontsize=12, x=0.01, ha="left")
    start = float(row["start_s"])
    for want_dark, label, colour in _HALVES:
        half = dark == want_dark
        ax.plot(ax_t.local(times[half]), np.exp(value[half]), ".", ms=1.5, color=colour,
                alpha=0.35)
        t_day, z_day, sd_day = daily_estimates(times[half], value[half], sd[half], end_s=end,
                                               min_span_s=MIN_HALF_SPAN_S)
        mid = t_day - 43200.0  # a day's value is complete at its last estimate
        ax.errorbar(ax_t.local(mid), np.exp(z_day),
                    yerr=[np.exp(z_day) - np.exp(z_day - sd_day),
                          np.exp(z_day + sd_day) - np.exp(z_day)],
                    fmt="o", ms=4, capsize=3, color=colour,
                    label=f"{label}: daily value ± sd")
        before = t_day < start
        if before.any():
            level = float(np.exp(np.mean(z_day[before][-7:])))
            ax.plot(ax_t.local(np.array([mid[before][-7:][0], start])), [level, level],
                    color=colour, ls=":", lw=1.4, label=f"{label}: level before")
    unit = {f.name: f.metadata.get("unit") for f in dataclasses.fields(Parameters)}.get(name)
    ax.set_ylabel(f"{name}\n[{unit or '-'}]")
    ax.set_yscale("log")  # the sd is relative: equal bars for equal evidence
    ax.yaxis.set_major_formatter(ScalarFormatter())
    ax.yaxis.set_minor_formatter(ScalarFormatter())
    ax_t.marks(ax, row, legend=True)
    ax.legend(**OUTSIDE)
    ax_t.setup(ax, label=True)
    return fig
