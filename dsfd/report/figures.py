"""The report's seven figures, each with a title that says what it shows, units on its axes
and local standard time on its time axes. A time series is broken (not bridged by a line)
where cycles are missing, and every figure draws a readable "nothing to show" note instead of
an empty or failing plot when its data are absent (a one-hour log, a day without sun, an old
database). Shared pieces: :mod:`dsfd.report.plotting`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator, NullFormatter

from dsfd.config.panel import REGIME_NAMES
from dsfd.physics.solar import solar_position
from dsfd.report.comfort_figure import CAPTION as COMFORT_CAPTION
from dsfd.report.comfort_figure import comfort_figure
from dsfd.report.kpis import HEAT_TERMS, STATES, Kpis, PredictionErrors, zone_name
from dsfd.report.plotting import (
    HEAT_COLOURS,
    METHOD_COLOURS,
    OUTSIDE,
    PARAM_UNITS,
    PLAIN,
    PLAIN_MINOR,
    STATE_COLOURS,
    STATE_LABELS,
    WIDTH_IN,
    Context,
    ReportFigure,
    bin_width_s,
    binned,
    broken,
    nothing,
    png,
    regime_colour,
    time_axis,
)
from dsfd.storage.history import History
from dsfd.weather.sky import SKY_CONDITIONS, sky_conditions

__all__ = ["FIGURES", "ReportFigure", "draw_figures"]


# ---------------------------------------------------------------------------- the figures
def states_figure(ctx: Context) -> Figure:
    """Measured vs predicted x1..x5 and cavity speed (the paper's Figs. 7 and 9)."""
    h = ctx.history
    fig = Figure(figsize=(WIDTH_IN, 13.0), layout="constrained")
    axes = fig.subplots(6, 1, sharex=True)
    horizon = ctx.kpis.horizon_steps * ctx.kpis.step_s
    for ax, s in zip(axes[:5], STATES, strict=True):
        meas = h.good(f"{s}_c")
        pred = h.model[f"pred_{s}_c"]
        ax.plot(*broken(ctx, meas), color="black", lw=1.2, label="measured")
        ax.plot(*broken(ctx, pred), color=STATE_COLOURS[s], lw=1.0,
                label="predicted one step (1 cycle) ahead")
        hz = h.model[f"hz_{s}_c"]
        if horizon > 0 and np.isfinite(hz).any():
            # Shown at the time it predicts.
            tt, yy = broken(ctx, hz)
            ax.plot(tt + np.timedelta64(int(horizon * 1e3), "ms"), yy, color=STATE_COLOURS[s],
                    lw=0.9, ls="--", alpha=0.8,
                    label=f"predicted {horizon / 60:g} min ahead (applied command held)")
        ax.set_ylabel(f"{STATE_LABELS[s]}\n[°C]")
        if not (np.isfinite(meas).any() or np.isfinite(pred).any()):
            nothing(ax, f"no reading and no prediction of {s}")
        time_axis(ctx, ax, label=False)
    ax = axes[5]
    v = np.abs(h.good("v_cav_ms")) * 100.0
    pv = h.model["pred_v_cav_ms"] * 100.0
    ax.plot(*broken(ctx, v), color="black", lw=1.2, label="measured |v|")
    ax.plot(*broken(ctx, pv), color="#8c564b", lw=1.0, label="predicted one step ahead")
    ax.set_ylabel("cavity air speed\n[cm/s]")
    ax.set_ylim(bottom=0)
    if not (np.isfinite(v).any() or np.isfinite(pv).any()):
        nothing(ax, "no cavity speed measured or predicted")
    time_axis(ctx, ax, label=True)
    axes[0].legend(loc="lower left", bbox_to_anchor=(0.0, 1.02), ncols=3, fontsize=9,
                   frameon=False, borderaxespad=0.0)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
    fig.suptitle("Façade temperatures and cavity air speed: measured vs the self-calibrating "
                 "model's predictions", fontsize=13, x=0.01, ha="left")
    return fig


def _regime_ticks(ax: Axes) -> None:
    ax.set_ylim(0.5, 10.5)
    ax.set_yticks(range(1, 11))
    ax.tick_params(axis="y", labelsize=8)


def controls_figure(ctx: Context) -> Figure:
    """Louver, regime and damper opening with irradiance and air temperatures (Figs. 10-11)."""
    h = ctx.history
    applied = h.applied()
    fig = Figure(figsize=(WIDTH_IN, 12.0), layout="constrained")
    axes = fig.subplots(6, 1, sharex=True, height_ratios=[0.45, 1.2, 1.2, 0.9, 1, 1])
    # Who decided: a strip of colour per cycle.
    ax = axes[0]
    methods = h.decisions["method"]
    t = ctx.local(h.time_s)
    step = np.timedelta64(int(ctx.kpis.step_s * 1e3), "ms")
    for m in sorted(set(methods.tolist())):
        sel = methods == m
        ax.bar(t[sel], 1.0, width=step, align="edge", color=METHOD_COLOURS.get(m, "#7f7f7f"),
               label=m, linewidth=0)
    ax.set_yticks([])
    ax.set_ylabel("decided\nby", rotation=0, ha="right", va="center")
    ax.legend(**OUTSIDE)
    time_axis(ctx, ax, label=False)
    # Louver with the solar elevation (the paper's Fig. 11a).
    ax = axes[1]
    ax.step(*broken(ctx, applied["phi_deg"]), where="post", color="black", lw=1.4,
            label="louver angle")
    site = ctx.site()
    if site is not None and len(h):
        elev = solar_position(h.time_s, *site).elevation_deg
        ax.plot(*broken(ctx, np.where(elev > 0, elev, np.nan)), color="#ff7f0e", lw=1.0,
                label="solar elevation")
    ax.set_ylim(-95, 95)
    ax.set_yticks(range(-90, 91, 30))
    ax.set_ylabel("angle [deg]")
    ax.legend(**OUTSIDE)
    time_axis(ctx, ax, label=False)
    ax = axes[2]
    ax.step(*broken(ctx, applied["afr"]), where="post", color="#1f77b4", lw=1.4)
    _regime_ticks(ax)
    ax.set_ylabel("airflow regime\n(1-10, Fig. 4)")
    time_axis(ctx, ax, label=False)
    ax = axes[3]
    ax.step(*broken(ctx, applied["or_pct"]), where="post", color="#2ca02c", lw=1.4)
    ax.set_ylim(-5, 105)
    ax.set_ylabel("damper opening\n[%]")
    time_axis(ctx, ax, label=False)
    ax = axes[4]
    ghi = h.good("ghi_wm2")
    ax.plot(*broken(ctx, ghi), color="#bcbd22", lw=1.2, label="global horizontal")
    ax.set_ylim(bottom=0, top=max(100.0, float(np.nanmax(ghi)) * 1.1)
                if np.isfinite(ghi).any() else 100.0)
    ax.set_ylabel("irradiance\n[W/m²]")
    if not np.isfinite(ghi).any():
        nothing(ax, "no good irradiance reading")
    time_axis(ctx, ax, label=False)
    ax = axes[5]
    ax.plot(*broken(ctx, h.good("t_out_c")), color="#17becf", lw=1.2, label="outdoor air")
    if "t_room_c" in h.values:
        ax.plot(*broken(ctx, h.good("t_room_c")), color="#7f7f7f", lw=1.0, label="room air")
    ax.set_ylabel("air temperature\n[°C]")
    ax.legend(**OUTSIDE)
    time_axis(ctx, ax, label=True)
    fig.suptitle("What the controller commanded: louver, airflow regime and damper opening, "
                 "with the weather", fontsize=13, x=0.01, ha="left")
    return fig


def regimes_by_sky_figure(ctx: Context) -> Figure:
    """Share of cycles in each airflow regime per sky condition (cf. the paper's Fig. 11)."""
    h = ctx.history
    fig = Figure(figsize=(WIDTH_IN, 3.8), layout="constrained")
    ax = fig.subplots()
    site = ctx.site()
    afr = h.applied()["afr"]
    fig.suptitle("Airflow regime chosen under each sky condition (share of cycles)",
                 fontsize=13, x=0.01, ha="left")
    if site is None or not len(h):
        nothing(ax, "sky condition unknown: the site is not recorded for this run")
        ax.set_axis_off()
        return fig
    # The irradiance of a cycle is the mean of the interval ending at it.
    cond = sky_conditions(h.time_s - ctx.kpis.step_s / 2, h.good("ghi_wm2"), *site)
    names = [c for c in SKY_CONDITIONS]
    regimes = sorted({int(r) for r in afr[np.isfinite(afr)]})
    left = np.zeros(len(names))
    for r in regimes:
        share = np.array([np.mean(afr[cond == c] == r) if np.any(cond == c) else 0.0
                          for c in names])
        bars = ax.barh(names, share * 100, left=left, color=regime_colour(r),
                       label=f"{r}: {REGIME_NAMES.get(r, '?')}")
        for b, s in zip(bars, share, strict=True):
            if s >= 0.06:
                ax.text(b.get_x() + b.get_width() / 2, b.get_y() + b.get_height() / 2,
                        str(r), ha="center", va="center", fontsize=9, color="white",
                        fontweight="bold")
        left += share * 100
    counts = [int(np.sum(cond == c)) for c in names]
    ax.set_yticks(range(len(names)),
                  [f"{c} ({n} cycles)" if n else f"{c} (no cycles)"
                   for c, n in zip(names, counts, strict=True)])
    ax.invert_yaxis()
    ax.set_xlim(0, 100)
    ax.set_xlabel("share of the cycles in that sky condition [%]  —  clear: k_t > 0.55, "
                  "overcast: k_t < 0.3, night: sun below 5° or GHI < 20 W/m²")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, title="regime",
              frameon=False)
    ax.grid(True, axis="x", alpha=0.3)
    return fig


def parameters_figure(ctx: Context) -> Figure:
    """The calibrated parameters over time with their bounds and prior."""
    h = ctx.history
    p = h.parameters
    fig = Figure(figsize=(WIDTH_IN, 6.4), layout="constrained")
    axes = fig.subplots(2, 5, sharex=True).ravel()
    fig.suptitle("Self-calibrated parameters over time, with their bounds (dashed) and "
                 "prior (dotted)", fontsize=13, x=0.01, ha="left")
    end = h.time_s[-1] if len(h) else 0.0
    names = ["h_out", "h_ca1", "h_ca2", "h_ca3", "h_ca4", "h_in", "f", "c", "n"]
    bounds_doc = (ctx.config or {}).get("parameters") or {}
    for ax, name in zip(axes, names, strict=False):
        unit = PARAM_UNITS.get(name[0] if name.startswith("h_") else name, "-")
        ax.set_title(f"{name} [{unit}]", fontsize=10)
        values = p.values.get(name)
        b = bounds_doc.get(name) or {}
        if values is None or not np.isfinite(values).any():
            nothing(ax, "not recorded")
        else:
            tt = np.append(p.time_s, max(end, p.time_s[-1]))
            vv = np.append(values, values[-1])
            ax.step(ctx.local(tt), vv, where="post", color="#1f77b4", lw=1.5)
            online = p.source == "online"
            ax.plot(ctx.local(p.time_s[online]), values[online], "o", ms=3, color="#1f77b4")
        for key, style in (("lower", "--"), ("upper", "--"), ("default", ":")):
            if b.get(key) is not None:
                ax.axhline(float(b[key]), color="#7f7f7f", ls=style, lw=1.0)
        if name != "n" and b.get("lower"):
            ax.set_yscale("log")
            ax.yaxis.set_major_formatter(PLAIN)
            lo, hi = ax.get_ylim()
            # Minor labels (2, 3, 5 …) only where a decade or two shows: else a wall of text.
            ax.yaxis.set_minor_formatter(PLAIN_MINOR if hi / lo < 30 else NullFormatter())
        time_axis(ctx, ax, label=False, max_ticks=4)
        ax.tick_params(axis="x", labelsize=8)
        ax.tick_params(axis="y", which="both", labelsize=8)
    ax = axes[9]
    ax.set_title("offsets q_x1..q_x4 [W/m²]", fontsize=10)
    drawn = False
    for i, s in enumerate(STATES[:4], start=1):
        values = p.values.get(f"q_x{i}")
        if values is not None and np.isfinite(values).any():
            tt = np.append(p.time_s, max(end, p.time_s[-1]))
            ax.step(ctx.local(tt), np.append(values, values[-1]), where="post",
                    color=STATE_COLOURS[s], lw=1.3, label=f"q_x{i}")
            drawn = True
    bound = ((ctx.config or {}).get("calibration") or {}).get("offset_bound_wm2")
    if bound:
        for v in (-bound, bound):
            ax.axhline(v, color="#7f7f7f", ls="--", lw=1.0)
    if drawn:
        ax.legend(fontsize=7, ncols=2, loc="best")
    else:
        nothing(ax, "no offsets calibrated")
    time_axis(ctx, ax, label=False, max_ticks=4)
    ax.tick_params(axis="both", labelsize=8)
    fig.supxlabel(f"local standard time ({zone_name(ctx.offset_h)}); dots: on-line updates",
                  fontsize=10)
    return fig


def prediction_error_figure(ctx: Context) -> Figure:
    """Mean absolute prediction error per time bin, one step and horizon ahead."""
    h, err = ctx.history, ctx.errors
    fig = Figure(figsize=(WIDTH_IN, 6.4), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    span = float(h.time_s[-1] - h.time_s[0]) if len(h) else 0.0
    width = bin_width_s(span)
    horizon_min = err.horizon_steps * ctx.kpis.step_s / 60
    panels = ((axes[0], err.model, err.persistence,
               f"one step ({ctx.kpis.step_s / 60:g} min) ahead"),
              (axes[1], err.horizon_model, err.horizon_persistence,
               f"{horizon_min:g} min ahead (applied command held, forecast weather)"))
    for ax, model, persist, what in panels:
        any_drawn = False
        for s in STATES:
            e = model.get(s)
            if e is None or not np.isfinite(e).any():
                continue
            tb, mb = binned(h.time_s, e, width)
            ax.plot(ctx.local(tb), mb, "-o", ms=3, color=STATE_COLOURS[s], lw=1.2,
                    label=STATE_LABELS[s])
            any_drawn = True
        stacked = np.vstack([persist[s] for s in STATES if s in persist])
        counts = np.isfinite(stacked).sum(axis=0)
        mean_p = np.where(counts > 0, np.nansum(stacked, axis=0) / np.maximum(counts, 1),
                          np.nan)
        if np.isfinite(mean_p).any():
            tb, mb = binned(h.time_s, mean_p, width)
            ax.plot(ctx.local(tb), mb, "--", color="black", lw=1.2,
                    label="persistence (last reading held), mean of x1..x5")
        ax.set_ylabel("mean absolute\nerror [K]")
        ax.set_ylim(bottom=0)
        ax.set_title(f"predicted {what}", fontsize=10, loc="left")
        if any_drawn:
            ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
        else:
            nothing(ax, "no scored predictions in this period (the log is shorter than "
                     "the horizon, or predictions were not stored)")
        time_axis(ctx, ax, label=ax is axes[1])
    fig.suptitle(f"Prediction error over time ({width / 60:g}-minute means), so drift "
                 "shows", fontsize=13, x=0.01, ha="left")
    return fig


def heat_figure(ctx: Context) -> Figure:
    """Daily heat into the room by term: model estimate (and the plant's own in simulation)."""
    days = ctx.kpis.days
    fig = Figure(figsize=(WIDTH_IN, 4.6), layout="constrained")
    ax = fig.subplots()
    plant = any(d.heat_plant_kwh is not None for d in days)
    sources = [("model", "model estimate")] + ([("plant", "simulated plant")] if plant else [])
    n_bars = len(HEAT_TERMS) * len(sources)
    width = 0.8 / n_bars
    x = np.arange(len(days))
    for i, (key, label) in enumerate(HEAT_TERMS):
        for j, (src, src_label) in enumerate(sources):
            vals = [(d.heat_model_kwh if src == "model" else d.heat_plant_kwh or {}).get(
                key, np.nan) for d in days]
            pos = x - 0.4 + (i * len(sources) + j + 0.5) * width
            bars = ax.bar(pos, vals, width=width * 0.95, color=HEAT_COLOURS[key],
                          hatch="//" if src == "plant" else None, edgecolor="white",
                          label=f"{label} ({src_label})")
            if len(days) <= 7:
                ax.bar_label(bars, fmt="%.2f", fontsize=7, padding=2)
    ax.axhline(0, color="black", lw=0.8)
    ax.set_xticks(x, [f"{d.day}\n{d.hours:.1f} h logged" for d in days])
    ax.set_ylabel("heat into the room [kWh]")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, frameon=False)
    ax.grid(True, axis="y", alpha=0.3)
    ax.yaxis.set_major_locator(MaxNLocator(nbins=8))
    if not days or all(d.heat_model_hours == 0 and d.heat_plant_kwh is None for d in days):
        nothing(ax, "no heat estimate stored")
    fig.suptitle("Heat into the room per day by term (negative: heat leaving the room)"
                 + ("; hatched: the simulated plant's own" if plant else ""),
                 fontsize=13, x=0.01, ha="left")
    return fig


#: (id, title, caption, drawing function), in report order.
FIGURES: Sequence[tuple[str, str, str, Callable[[Context], Figure]]] = (
    ("fig-states", "Model tracking (cf. paper Figs. 7 and 9)",
     "Readings (black) against the model's one-step prediction from the previous cycle's "
     "estimate with the position actually applied, and its horizon-end prediction (dashed, "
     "drawn at the time it predicts). Gaps are cycles not logged or readings flagged.",
     states_figure),
    ("fig-controls", "Control (cf. paper Figs. 10 and 11)",
     "The position in effect each cycle (the command, or the position read back when nothing "
     "was written), who decided it, and the measured weather.", controls_figure),
    ("fig-comfort", "Occupant comfort: glare and sun cut-off", COMFORT_CAPTION, comfort_figure),
    ("fig-regimes-sky", "Regimes by sky condition",
     "Airflow regime shares per sky condition, classified from the measured global "
     "irradiance by the clearness index.", regimes_by_sky_figure),
    ("fig-parameters", "Parameter history",
     "The calibrated parameters as they were in force; dots mark on-line updates.",
     parameters_figure),
    ("fig-prediction-error", "Prediction error over time",
     "Mean absolute error of the daemon's predictions against the readings they predicted, "
     "per time bin, with persistence for reference: a rising line is drift.",
     prediction_error_figure),
    ("fig-heat-daily", "Daily heat terms",
     "Heat into the room per local day by term: the model's estimate for the applied "
     "commands, and in a simulation the plant's own integrals.", heat_figure),
)


def draw_figures(history: History, kpis: Kpis, errors: PredictionErrors,
                 config: Mapping[str, Any] | None, *, dpi: int = 90) -> list[ReportFigure]:
    """Every figure of :data:`FIGURES` as PNG."""
    ctx = Context(history, kpis, errors, config, dpi)
    out = []
    for fig_id, title, caption, draw in FIGURES:
        fig = draw(ctx)
        out.append(ReportFigure(fig_id, title, caption, png(fig, dpi)))
    return out
