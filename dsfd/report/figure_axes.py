"""The time axis every finding's figure shares: local standard time, the finding's marks.

Times on the axes are local standard time, like every figure of the report; marked: the
finding's start and detection (and its end), as stored.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.dates import AutoDateLocator, ConciseDateFormatter

from dsfd.report.kpis import zone_name

__all__ = ["MARKS", "FindingAxes", "NoEvidence", "end_s"]

#: The finding's stored times drawn on its figure: (column, label, colour, line style).
MARKS = (("start_s", "start", "#ff7f0e", "--"), ("detected_s", "detected", "#d62728", "-"),
         ("ended_s", "closed", "#555555", ":"))


class NoEvidence(Exception):  # noqa: N818 (not an error: a finding with nothing to draw)
    """The database holds none of the rows the finding's figure needs (the message says
    which)."""


class FindingAxes:
    """Local standard time on the axes of one finding's figure."""

    def __init__(self, offset_h: float, lo_s: float, hi_s: float) -> None:
        self.offset_h, self.lo_s, self.hi_s = offset_h, lo_s, hi_s

    def local(self, time_s: np.ndarray | float) -> np.ndarray:
        t = np.asarray(time_s, float) + self.offset_h * 3600.0
        with np.errstate(invalid="ignore"):  # NaN (no value) casts to NaT, which is not drawn
            return (t * 1e3).astype("int64").astype("datetime64[ms]")

    def setup(self, ax: Axes, *, label: bool) -> None:
        locator = AutoDateLocator(minticks=3, maxticks=8)
        ax.xaxis.set_major_locator(locator)
        ax.xaxis.set_major_formatter(ConciseDateFormatter(locator))
        # a little room on the right, so a detection at the window's end shows
        pad = 0.02 * (self.hi_s - self.lo_s)
        ax.set_xlim(self.local(self.lo_s), self.local(self.hi_s + pad))
        ax.grid(True, alpha=0.3)
        if label:
            ax.set_xlabel(f"local standard time ({zone_name(self.offset_h)})")

    def marks(self, ax: Axes, row: Mapping[str, Any], *, legend: bool) -> None:
        """The finding's stored start, detection and end (when inside the window)."""
        for key, name, colour, style in MARKS:
            t = row.get(key)
            if t is None or not self.lo_s <= float(t) <= self.hi_s:
                continue
            what = f"{name} ({row['state']})" if key == "ended_s" else name
            ax.axvline(self.local(float(t)), color=colour, ls=style, lw=1.3,
                       label=what if legend else None)


def end_s(row: Mapping[str, Any]) -> float:
    """The last time the finding's evidence was judged: its last check, or its end."""
    ts = [float(row[k]) for k in ("detected_s", "last_seen_s", "ended_s")
          if row.get(k) is not None]
    return max(ts)

