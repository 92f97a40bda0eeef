"""The figure of a finding whose detector is the block CUSUM
(:func:`dsfd.estimation.diagnostics.block_change`): the residual detector's and the night
offsets' (:mod:`dsfd.report.finding_figures` gives each its series and time axes)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from dsfd.estimation.diagnostics import (
    ResidualBlocks,
    ResidualSettings,
    block_cusum,
    judged_blocks,
)
from dsfd.report.plotting import OUTSIDE, WIDTH_IN

__all__ = ["TimeAxes", "block_figure", "broken"]


class TimeAxes(Protocol):
    """The time axes of one finding's figure (``figure_axes.FindingAxes``)."""

    lo_s: float
    hi_s: float

    def local(self, time_s: np.ndarray | float) -> np.ndarray: ...

    def setup(self, ax: Axes, *, label: bool) -> None: ...

    def marks(self, ax: Axes, row: Mapping[str, Any], *, legend: bool) -> None: ...


def block_figure(row: Mapping[str, Any], ax_t: TimeAxes, times: np.ndarray,
                 values: np.ndarray, *, settings: ResidualSettings,
                 control: np.ndarray | None, title: str, unit: str, colour: str, each: str,
                 ylabel: str, centre: str, judge_from_s: float = -np.inf,
                 allowance: Callable[[ResidualBlocks], np.ndarray] | None = None,
                 allowance_label: str = "") -> Figure:
    """The block CUSUM of :func:`~dsfd.estimation.diagnostics.block_change` on ``values``,
    recomputed as the detector did: values, block means and reference above; the statistic
    and its threshold below; ``ax_t`` the finding's time axes."""
    st = settings
    fig = Figure(figsize=(WIDTH_IN, 5.0), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[1.6, 1.0])
    fig.suptitle(f"#{row['finding_id']} {row['kind']}: {title}", fontsize=12, x=0.01,
                 ha="left")
    b = judged_blocks(times, values, settings=st, control=control, judge_from_s=judge_from_s,
                      allowance=allowance)
    mid = (b.blocks + 0.5) * st.block_s
    seen = (times >= ax_t.lo_s) & (times <= ax_t.hi_s)
    top.plot(ax_t.local(times[seen]), values[seen], color="#bbbbbb", lw=0.6, label=each)
    # no line across hours without blocks (the days between nights, an outage)
    gap_mid, (lo, hi, ref, means) = broken(b.blocks, mid, b.centre - b.scale,
                                            b.centre + b.scale, b.centre, b.means)
    top.fill_between(ax_t.local(gap_mid), lo, hi, color="#dddddd", lw=0, step="mid",
                     label="reference ± its long-run spread")
    top.plot(ax_t.local(gap_mid), ref, color="black", ls="--", lw=1.1, label=centre)
    top.plot(ax_t.local(gap_mid), means, "o-", ms=2.5, lw=1.0, color=colour,
             label=f"{st.block_s / 60:g}-min block means (the detector's input)")
    top.set_ylabel(f"{ylabel}\n[{unit}]")
    ax_t.marks(top, row, legend=True)
    top.legend(**OUTSIDE)
    ax_t.setup(top, label=False)
    cs = block_cusum(b, st)
    n = cs.statistic.size
    gap_mid, (stat,) = broken(b.blocks[:n], mid[:n], cs.statistic)
    bottom.plot(ax_t.local(gap_mid), stat, color=colour, lw=1.3,
                label=("CUSUM, recomputed from the stored rows\n"
                       + (f"k = {st.k_sd:g} spreads, or {st.min_shift / 2:g} {unit}"
                          f"{allowance_label} if larger" if st.min_shift else
                          f"k = {st.k_sd:g} spreads")))
    bottom.axhline(st.h_sd, color="black", ls="--", lw=1.0, label=f"threshold h = {st.h_sd:g}")
    bottom.set_ylim(bottom=0)
    bottom.set_ylabel("CUSUM statistic\n[long-run sd]")
    ax_t.marks(bottom, row, legend=False)
    bottom.legend(**OUTSIDE)
    ax_t.setup(bottom, label=True)
    return fig


def broken(blocks: np.ndarray, x: np.ndarray, *series: np.ndarray
            ) -> tuple[np.ndarray, list[np.ndarray]]:
    """``x`` and ``series`` with a NaN put between blocks that are not consecutive, so a
    line is not drawn across the hours between them."""
    cut = np.flatnonzero(np.diff(blocks) > 1) + 1
    return (np.insert(np.asarray(x, float), cut, np.nan),
            [np.insert(np.asarray(v, float), cut, np.nan) for v in series])
