"""What the report's figures share: colours, labels, the drawing context, broken time
series, time axes in local standard time, "nothing to show" notes and PNG output (matplotlib's
Agg canvas: no display, no pyplot state)."""

from __future__ import annotations

import base64
import io
from collections.abc import Mapping
from dataclasses import dataclass
from html import escape
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.dates import AutoDateLocator, ConciseDateFormatter
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter

from dsfd.report.kpis import Kpis, PredictionErrors, zone_name
from dsfd.storage.history import History

__all__ = ["HEAT_COLOURS", "METHOD_COLOURS", "OUTSIDE", "PARAM_UNITS", "PLAIN", "PLAIN_MINOR",
           "STATE_COLOURS", "STATE_LABELS", "WIDTH_IN", "Context", "ReportFigure", "bin_width_s",
           "binned", "broken", "figure_html", "nothing", "png", "regime_colour", "time_axis"]

WIDTH_IN = 11.0
STATE_LABELS = {"x1": "x1 exterior pane", "x2": "x2 DGU outer pane", "x3": "x3 DGU inner pane",
                "x4": "x4 louver slat", "x5": "x5 cavity air"}
STATE_COLOURS = {"x1": "#1f77b4", "x2": "#ff7f0e", "x3": "#2ca02c", "x4": "#d62728",
                 "x5": "#9467bd"}
METHOD_COLOURS = {"mpc": "#2ca02c", "paper-sqp": "#17becf", "rule": "#ff7f0e",
                  "safe": "#d62728", "manual": "#9467bd"}
HEAT_COLOURS = {"q_cv_rd": "#d62728", "q_sol_trans": "#ff7f0e", "q_air": "#1f77b4",
                "q_da": "#bcbd22"}
PARAM_UNITS = {"h": "W/(m² K)", "f": "-", "c": "m³/(s Paⁿ)", "n": "-"}


#: Legend to the right of a panel of a time-series figure (all panels share that margin).
OUTSIDE = {"loc": "upper left", "bbox_to_anchor": (1.0, 1.0), "fontsize": 8, "frameon": False}
#: Log axes labelled 3, 10, 40 rather than 3×10⁰, 10¹, 4×10¹.
PLAIN = FuncFormatter(lambda v, _pos: f"{v:g}")
PLAIN_MINOR = FuncFormatter(lambda v, _pos: f"{v:g}" if f"{v:.0e}"[0] in "235" else "")


@dataclass(frozen=True)
class ReportFigure:
    """One figure of the report: its HTML id, caption and PNG image."""

    fig_id: str
    title: str
    caption: str
    png: bytes


def figure_html(f: ReportFigure) -> str:
    """The figure as an HTML ``<figure>`` with its PNG inline."""
    return (f'<figure id="{f.fig_id}"><h3>{escape(f.title)}</h3>'
            f'<img alt="{escape(f.title)}" src="data:image/png;base64,'
            f'{base64.b64encode(f.png).decode("ascii")}">'
            f"<figcaption>{escape(f.caption)}</figcaption></figure>")


@dataclass(frozen=True)
class Context:
    """What every figure needs besides the history."""

    history: History
    kpis: Kpis
    errors: PredictionErrors
    config: Mapping[str, Any] | None
    dpi: int

    @property
    def offset_h(self) -> float:
        return self.kpis.utc_offset_h

    def local(self, time_s: np.ndarray) -> np.ndarray:
        """UTC seconds → naive local standard datetimes (for the time axes)."""
        t = np.asarray(time_s, float) + self.offset_h * 3600.0
        return (t * 1e3).astype("int64").astype("datetime64[ms]")

    def site(self) -> tuple[float, float] | None:
        site = (self.config or {}).get("site") or {}
        lat, lon = site.get("latitude_deg"), site.get("longitude_deg")
        return None if lat is None or lon is None else (float(lat), float(lon))


def broken(ctx: Context, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(times, values) with a NaN inserted wherever cycles are missing, so lines break."""
    t = ctx.history.time_s
    if t.size < 2:
        return ctx.local(t), y
    gap = (np.diff(t) > 1.5 * ctx.kpis.step_s) | (np.diff(ctx.history.run_id) != 0)
    at = np.flatnonzero(gap) + 1
    tt = np.insert(t, at, t[at - 1] + ctx.kpis.step_s / 2)
    yy = np.insert(np.asarray(y, float), at, np.nan)
    return ctx.local(tt), yy


def time_axis(ctx: Context, ax: Axes, *, label: bool, max_ticks: int = 10) -> None:
    locator = AutoDateLocator(minticks=2 if max_ticks < 5 else 4, maxticks=max_ticks)
    ax.xaxis.set_major_locator(locator)
    ax.xaxis.set_major_formatter(ConciseDateFormatter(locator))
    t = ctx.local(ctx.history.time_s)
    if t.size:
        pad = np.timedelta64(int(ctx.kpis.step_s * 500), "ms")
        ax.set_xlim(t[0] - pad, t[-1] + pad)
    if label:
        ax.set_xlabel(f"local standard time ({zone_name(ctx.offset_h)})")
    ax.grid(True, alpha=0.3)


def nothing(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=10,
            color="#555555", wrap=True)


def png(fig: Figure, dpi: int) -> bytes:
    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def regime_colour(r: int) -> str:
    palette = ("#1f77b4", "#aec7e8", "#ff7f0e", "#ffbb78", "#2ca02c", "#98df8a", "#d62728",
               "#ff9896", "#9467bd", "#7f7f7f")
    return palette[(r - 1) % len(palette)]


def bin_width_s(span_s: float) -> float:
    for minutes in (10, 15, 30, 60, 120, 180, 360, 720, 1440):
        if span_s / (minutes * 60) <= 48:
            return minutes * 60.0
    return 86400.0


def binned(t: np.ndarray, e: np.ndarray, width_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Bin centres and the mean of the finite values of ``e`` in each (NaN if none)."""
    if not t.size:
        return t, e
    k = np.floor((t - t[0]) / width_s).astype(int)
    n = int(k.max()) + 1
    ok = np.isfinite(e)
    sums = np.bincount(k[ok], weights=e[ok], minlength=n)
    counts = np.bincount(k[ok], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    return t[0] + (np.arange(n) + 0.5) * width_s, mean
