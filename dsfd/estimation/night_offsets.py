"""The night offsets: a sensor that starts to read off, seen in its node's heat-flux offset
at night (docs/model.md#diagnostics-night-offsets).

Pure (no files, clocks or logging). The calibration's heat-flux offset q_x of a node is the
constant flux [W/m²] its balance needs to hold the node at its reading
(docs/model.md#heat-offsets): the state update takes a reading as it is, so a thermocouple
that reads 1 K high moves its node's offset by about the node's conductance (15–18 W/m² for
the inner pane x3 on the diagnostics bench). By day the offsets also take up the lumped
model's solar form error, which changes with the sky (the inner pane's swings by ±18 W/m²
from one morning to the next), which is why the parameter detector judges them only as
daily means. At night that error is gone, and on the bench's clean winter nights q_x3 held
within ±0.8 W/m²: there a sensor's new offset or drift stands out within hours.

:func:`night_offset_change` runs the block CUSUM of the residual detector
(:func:`dsfd.estimation.diagnostics.block_change`) on a node's offsets at night only:
hourly blocks, each against the same time of night on the previous nights.
"""

from __future__ import annotations

import math

import numpy as np

from dsfd.estimation.diagnostics import (
    Finding,
    ResidualBlocks,
    ResidualSettings,
    block_change,
    cusum_confidence,
)

__all__ = ["NIGHT_OFFSET_NAMES", "NIGHT_OFFSET_SETTINGS", "NIGHT_SPREAD_ALLOWANCE",
           "night_allowance", "night_offset_change", "night_spread"]

#: The offsets judged at night: the inner panes and the louver. Not the exterior pane's
#: q_x1: at night it takes up the long-wave exchange with the sky, whose model (clear sky,
#: docs/model.md#sky) errs by a cloud cover that changes from night to night (on the bench's
#: clean winter nights q_x1 sat between +11 and +35 W/m², and a CUSUM on it raised a false
#: finding on the fifth night); the night pane check judges x1 against the outdoor air.
NIGHT_OFFSET_NAMES = ("q_x2", "q_x3", "q_x4")

#: The residual detector's CUSUM on 1-h blocks (the offsets are stored with each
#: calibration update, every 10 min by default, hourly at the least: every block holds one):
#: each block against the median of the blocks within ±1 h of the same time on the 5
#: previous days (at least 6 of them: two nights), the spread from the night blocks of the
#: 5 days that end 6 h before it (at least 24: about three nights). 30-min blocks of hourly
#: updates alternate with empty ones, which hides their correlation from the long-run spread.
#: The smallest shift worth a finding is 4 W/m² (a sensor about 0.25 K off on the inner
#: pane; the allowance is at least half of it), whatever the spread: a clean night's level
#: wanders by 1–2 W/m² from the nights before, and with a smallest shift of 2 W/m² one of 12
#: synthetic clean histories whose nightly level wanders uniformly within ±1 W/m² raised a
#: finding when checked hourly. The spread is at least 0.5 W/m². An alarm also needs the
#: nights since its start to sit 4 W/m² off on average (``alarm_min_shift``): on the real
#: Aalborg week, with the identifiability test on (``calibration.identifiability_sd_ratio``
#: 0.5) q_x3 held −2.8 to −3.9 W/m² for five nights and −0.1 on the last, and the CUSUM
#: crossed 8 (8.09) on a mean departure of 3.3 W/m², below the smallest change worth one.
NIGHT_OFFSET_SETTINGS = ResidualSettings(
    block_s=3600.0, period_blocks=24, reference_days=5, half_width_blocks=1,
    min_reference_blocks=6, guard_blocks=6, min_scale_blocks=24, min_block_samples=1,
    k_sd=0.75, h_sd=8.0, scale_floor=0.5, min_shift=4.0, alarm_min_shift=True)

#: The allowance is at least this many times :func:`night_spread` (in the offset's unit): a
#: night that departs from its reference as far as twice the recent nights did never adds
#: to the statistic. On the real Aalborg week the offsets at night moved by up to 20 W/m²
#: from one night to the next (q_x2), and with 1× a night at −16 W/m² was a finding; with
#: 1.5× the largest statistic was 5.9 (h = 8), with 2× 2.8. On the bench's quiet simulated
#: nights (about 0.3 W/m²) the 2 W/m² floor of NIGHT_OFFSET_SETTINGS binds instead.
NIGHT_SPREAD_ALLOWANCE = 2.0
#: Night blocks more than this far apart belong to different nights [s].
_NEW_NIGHT_S = 3 * 3600.0


def night_spread(blocks: ResidualBlocks, settings: ResidualSettings = NIGHT_OFFSET_SETTINGS,
                 *, nights: int = 5, min_nights: int = 3) -> np.ndarray:
    """Per block, how far a whole night departs from its reference on this façade: the rms
    of the mean departure (block mean − reference) of each of the ``nights`` nights before
    the block's night [the offset's unit]; NaN with fewer than ``min_nights`` of them.

    A night is a run of blocks without a gap of 3 h. Its level moves with the weather (sky,
    wind, the room's own schedule), and a CUSUM sums a night's blocks, so such a departure
    adds up like a change unless the allowance covers it: the random-effects view of the
    parameter detector's between-day variance (docs/model.md#diagnostics-parameters)."""
    t = blocks.blocks * settings.block_s
    night_id = np.cumsum(np.r_[True, np.diff(t) > _NEW_NIGHT_S]) - 1
    dev = blocks.means - blocks.centre
    means = np.full(int(night_id[-1]) + 1 if t.size else 0, np.nan)
    for n in range(means.size):
        d = dev[(night_id == n) & np.isfinite(dev)]
        if d.size >= 3:
            means[n] = float(np.mean(d))
    out = np.full(t.size, np.nan)
    for i, n in enumerate(night_id):
        before = means[max(0, n - nights):n]
        before = before[np.isfinite(before)]
        if before.size >= min_nights:
            out[i] = float(np.sqrt(np.mean(before ** 2)))
    return out


def night_allowance(blocks: ResidualBlocks,
                    settings: ResidualSettings = NIGHT_OFFSET_SETTINGS) -> np.ndarray:
    """The floor of the CUSUM's allowance per block [spreads]:
    :data:`NIGHT_SPREAD_ALLOWANCE` × :func:`night_spread` over the block's spread."""
    return NIGHT_SPREAD_ALLOWANCE * night_spread(blocks, settings) / blocks.scale


_NODE = {"q_x2": ("the inner glazing's cavity-side pane", "x2"),
         "q_x3": ("the inner (room-side) pane", "x3"),
         "q_x4": ("the louver", "x4")}
#: The unit's two panes share their gap: a sensor off on one moves the other's offset the
#: opposite way (on the bench, the night after x3 began drifting up q_x3 sat about 9 W/m²
#: above the night before, q_x2 about 3 below; a clean night's q_x2 can move that much).
_GAP = ("; the insulating unit's panes share their gap, so a sensor off on the other pane "
        "({other}) moves this offset the opposite way: with a finding on both, the sensor of "
        "the one found first and moved further is the likelier")
_OTHERWISE = {
    "q_x2": "a pane of the insulating glass unit that passes heat differently (a failed "
            "edge seal)" + _GAP.format(other="x3"),
    "q_x3": "a heat source or cold air at the inner glass at night (a heater, radiator or "
            "diffuser below the window newly running)" + _GAP.format(other="x2"),
    "q_x4": "the slats sitting at another angle than their read-back at night",
}


def night_offset_change(times_s: np.ndarray, values: np.ndarray, night: np.ndarray, *,
                        name: str, settings: ResidualSettings = NIGHT_OFFSET_SETTINGS,
                        judge_from_s: float = -math.inf) -> Finding | None:
    """The first change of heat-flux offset ``name`` at night, or None.

    Parameters
    ----------
    times_s : array (n,), [s]
        Times of the stored estimates, increasing.
    values : array (n,), [W/m²]
        The on-line estimates of the offset (NaN: none).
    night : array (n,) of bool
        Estimates made at night (the sun well below the horizon, and the day's heat gone).
    name : str
        ``q_x2``, ``q_x3`` or ``q_x4``.
    judge_from_s : float, [s]
        Blocks before it are references only (:func:`~dsfd.estimation.diagnostics.
        block_change`; the daemon passes the 6 days before its window).

    Returns
    -------
    Finding or None
        ``night_offset_shift`` about ``night:<name>``: its start the start of the block after
        the CUSUM's last zero, detected at the end of the block where it crossed.
    """
    v = np.where(np.asarray(night, bool), np.asarray(values, float), np.nan)
    change = block_change(times_s, v, settings=settings, judge_from_s=judge_from_s,
                          allowance=lambda b: night_allowance(b, settings))
    if change is None:
        return None
    ev = change.evidence(f"night:{name}", "W/m2")
    node, sensor = _NODE.get(name, (name, name.removeprefix("q_")))
    reads = "warmer" if change.side > 0 else "cooler"
    action = (f"at night {node} reads {reads} than its heat paths explain, by "
              f"{abs(ev.shift):.1f} W/m² ({abs(ev.shift_sd):.1f} spreads) against the same "
              f"hours of the nights before; with no sun to explain it, check its sensor "
              f"{sensor} first (an offset or a drift, a sensor loose from its surface) against "
              f"a reference thermometer; otherwise "
              f"{_OTHERWISE.get(name, 'what changed at that node')}")
    return Finding(kind="night_offset_shift", confidence=cusum_confidence(ev.statistic,
                                                                          settings.h_sd),
                   start_s=change.start_s, detected_s=change.detected_s, evidence=(ev,),
                   action=action)
