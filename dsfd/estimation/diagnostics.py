"""Change detectors on what the self-calibrating model leaves behind (docs/model.md#diagnostics).

Pure functions (no files, clocks or logging): arrays in, a :class:`Finding` or None out.

The finding record and Page's CUSUM live in :mod:`dsfd.estimation.finding` (re-exported).

* :func:`residual_change` — the one-step prediction errors of one output (x1..x5 [K],
  the cavity speed [m/s]), averaged in blocks, each block centred and scaled by the median
  and robust spread (MAD) of the blocks at the same time of day on the previous days, then
  a two-sided CUSUM (Page 1954) with allowance k and threshold h in those units.

The parameter detector, which uses the same CUSUM, is :mod:`dsfd.estimation.parameter_shift`.

The physical cross-checks are in :mod:`dsfd.estimation.crosschecks`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from dsfd.estimation.finding import (
    MAD_TO_SD,
    Cusum,
    Evidence,
    Finding,
    cusum_confidence,
    page_cusum,
)

__all__ = ["MAD_TO_SD", "TEMPERATURE_MIN_SHIFT_K", "BlockChange", "Cusum", "Evidence", "Finding",
           "ResidualBlocks", "ResidualSettings", "block_change", "block_cusum", "block_labels",
           "block_means",
           "cusum_confidence", "judged_blocks", "page_cusum", "residual_blocks", "residual_change",
           "residual_settings"]


# ----------------------------------------------------------------------------- residuals
@dataclass(frozen=True, kw_only=True)
class ResidualSettings:
    """Parameters of :func:`residual_change` (docs/model.md#diagnostics).

    Attributes
    ----------
    block_s : float, [s]
        Residuals are averaged over blocks this long (10 min): one-step errors of a
        one-minute model are strongly correlated; block means are much less so.
    period_blocks : int
        Blocks in a day (144 of 10 min): the reference of a block is the same time of day.
    reference_days : int
        How many previous days at that time of day make the reference (5).
    half_width_blocks : int
        The reference takes this many blocks either side of the same time of day (3:
        ±30 min), so 5 days give up to 35 blocks.
    min_reference_blocks : int
        Fewer blocks in the reference: no statistic for that block (15: three days).
    guard_blocks : int
        The scale comes from deviations that end this many blocks before the block tested
        (36: six hours), so a change does not widen its own scale before it is found.
    min_scale_blocks : int
        Fewer deviations for the scale: no statistic (144: a day's worth).
    min_block_samples : int
        Blocks with fewer finite residuals are skipped.
    k_sd, h_sd : float
        CUSUM allowance and threshold in long-run spreads (0.75 and 8): a shift of two
        spreads is found within about 7 blocks (a 1 K step on residuals of 0.3 K sd within
        about two hours).
    scale_floor : float
        Least spread used [the residual's unit], so a quiet reference (a closed cavity at
        night) does not turn sensor noise into findings.
    min_shift : float
        The smallest change worth a finding [the residual's unit]; the allowance is at
        least half of it (Page's k = δ/2 for a shift δ), whatever the spread. 0: the
        allowance is ``k_sd`` spreads only. See :func:`residual_settings`.
    alarm_min_shift : bool
        An alarm also needs the blocks since the change's start to depart from their
        references by ``min_shift`` on average (False: the statistic alone decides). Page's
        k = δ/2 lets a long departure between δ/2 and δ reach the threshold; with this, a
        departure smaller than the smallest change worth a finding never is one, while one
        that grows past it still is (:func:`block_cusum`).
    """

    block_s: float = 600.0
    period_blocks: int = 144
    reference_days: int = 5
    half_width_blocks: int = 3
    min_reference_blocks: int = 15
    guard_blocks: int = 36
    min_scale_blocks: int = 144
    min_block_samples: int = 3
    k_sd: float = 0.75
    h_sd: float = 8.0
    scale_floor: float = 0.05
    min_shift: float = 0.0
    alarm_min_shift: bool = False


#: The smallest change of a temperature's prediction error worth a finding [K]: the
#: allowance of 0.4 K stays above what a calibrated lumped model's one-step errors shift
#: from one kind of day to another (up to 0.34 K between the bundled record's overcast,
#: clear and mixed days, measured on the bench's clean winter days, which at 0.05-0.08 K of
#: spread were 2-5 spreads and so findings) and below a 1 K thermocouple step and what a
#: drift of 0.5 K a day reaches within a day.
TEMPERATURE_MIN_SHIFT_K = 0.8


def residual_settings(unit: str) -> ResidualSettings:
    """The residual detector's settings for an output in ``unit`` (``K``: the allowance at
    least :data:`TEMPERATURE_MIN_SHIFT_K` / 2; else the defaults)."""
    return ResidualSettings(min_shift=TEMPERATURE_MIN_SHIFT_K if unit == "K" else 0.0)


def block_means(times_s: np.ndarray, values: np.ndarray, *, block_s: float,
                min_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Block numbers (floor(t/block_s)) and means of the finite values in each block with
    at least ``min_samples`` of them, in time order."""
    t = np.asarray(times_s, float)
    v = np.asarray(values, float)
    ok = np.isfinite(t) & np.isfinite(v)
    idx = np.floor(t[ok] / block_s).astype(np.int64)
    if idx.size == 0:
        return idx, np.zeros(0)
    blocks, inverse, counts = np.unique(idx, return_inverse=True, return_counts=True)
    sums = np.bincount(inverse, weights=v[ok])
    keep = counts >= min_samples
    return blocks[keep], sums[keep] / counts[keep]


@dataclass(frozen=True, eq=False)
class ResidualBlocks:
    """What :func:`residual_change` runs its CUSUM on, per block with enough residuals.

    ``blocks`` are block numbers (block start = ``blocks × block_s``), ``means`` the block
    means, ``centre`` and ``scale`` each block's reference (NaN where the history is too
    short) and ``z`` = (means − centre) / scale.
    """

    blocks: np.ndarray
    means: np.ndarray
    centre: np.ndarray
    scale: np.ndarray
    z: np.ndarray
    #: The CUSUM allowance per block [spreads]: ``k_sd``, or half ``min_shift`` if larger.
    k: np.ndarray


def block_labels(times_s: np.ndarray, residuals: np.ndarray, labels: np.ndarray,
                 blocks: np.ndarray, *, block_s: float) -> np.ndarray:
    """Per block of :func:`block_means`, the label (the control in force) held by most of
    its finite residuals; NaN where none of them has a known label."""
    t = np.asarray(times_s, float)
    lab = np.asarray(labels, float)
    ok = np.isfinite(t) & np.isfinite(np.asarray(residuals, float)) & np.isfinite(lab)
    idx = np.floor(t[ok] / block_s).astype(np.int64)
    out = np.full(blocks.size, np.nan)
    if blocks.size == 0 or idx.size == 0:
        return out
    pos = np.clip(np.searchsorted(blocks, idx), 0, blocks.size - 1)
    inside = blocks[pos] == idx
    pairs, counts = np.unique(np.stack([pos[inside], lab[ok][inside]], axis=1), axis=0,
                              return_counts=True)
    for (i, value), _count in sorted(zip(map(tuple, pairs), counts, strict=True),
                                    key=lambda item: item[1]):
        out[int(i)] = value  # ascending counts: the most held label is written last
    return out


def residual_blocks(times_s: np.ndarray, residuals: np.ndarray, *,
                    settings: ResidualSettings | None = None,
                    control: np.ndarray | None = None) -> ResidualBlocks:
    """Block means of one output's prediction errors, standardised by their same-time
    reference (the first steps of :func:`residual_change`; ``dsfd report`` draws them).
    ``control``: per residual, the control it was predicted under (the regime in force);
    a block is then compared only with blocks of the same control."""
    st = settings or ResidualSettings()
    blocks, means = block_means(times_s, residuals, block_s=st.block_s,
                                min_samples=st.min_block_samples)
    labels = (None if control is None else
              block_labels(times_s, residuals, control, blocks, block_s=st.block_s))
    centre, scale = _same_time_reference(blocks, means, st, labels)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.fmax(st.k_sd, 0.5 * st.min_shift / scale)
    return ResidualBlocks(blocks, means, centre, scale, (means - centre) / scale, k)


def residual_change(times_s: np.ndarray, residuals: np.ndarray, *, signal: str, unit: str,
                    settings: ResidualSettings | None = None,
                    control: np.ndarray | None = None, judge_from_s: float = -math.inf
                    ) -> Finding | None:
    """The first change in one output's prediction errors, or None.

    Parameters
    ----------
    times_s : array (n,), [s]
        Times of the residuals (any order is not allowed: increasing).
    residuals : array (n,)
        Measured minus predicted (one step ahead), NaN where either is missing.
    signal, unit : str
        The output's name (``x3_c``) and unit, for the evidence.
    settings : ResidualSettings, optional
    control : array (n,), optional
        The control each residual was predicted under (the regime in force; NaN unknown).
        A block is compared only with the same time of day's blocks under the same control
        (held by most of its residuals; an unknown control is compared with any): a lumped model's
        error differs between controls, and a control first used at an hour of the day is
        not a change of the façade.
    judge_from_s : float, [s]
        Blocks before it are references only (:func:`block_change`).

    Returns
    -------
    Finding or None
        ``residual_shift`` with the block where the CUSUM crossed ``h_sd`` (``detected_s``:
        that block's end, or its last residual) and the block after its last zero
        (``start_s``: that block's start).
    """
    st = settings or ResidualSettings()
    change = block_change(times_s, residuals, settings=st, control=control,
                          judge_from_s=judge_from_s)
    if change is None:
        return None
    ev = change.evidence(f"residual:{signal}", unit)
    direction = "above" if change.side > 0 else "below"
    return Finding(kind="residual_shift", confidence=cusum_confidence(ev.statistic, st.h_sd),
                   start_s=change.start_s, detected_s=change.detected_s, evidence=(ev,),
                   action=(f"{signal} reads {abs(ev.shift):.3g} {unit} {direction} what the "
                           f"calibrated model predicts: check the {signal} sensor, or what "
                           "changed on the façade (the residual alone cannot tell which)"))


@dataclass(frozen=True)
class BlockChange:
    """The first alarm of the CUSUM of :func:`residual_blocks` (:func:`block_change`).

    ``shift`` and ``shift_sd`` are the mean departure of the blocks from the alarm's start to
    the alarm from their references (in the signal's unit and in spreads), ``side`` +1 for
    an upward shift, ``start_s`` the start of the block after the last zero and
    ``detected_s`` the end of the block where the statistic crossed the threshold (its last
    value, if that block is the latest and not yet over).
    """

    side: int
    shift: float
    shift_sd: float
    start_s: float
    detected_s: float
    statistic: float
    threshold: float

    def evidence(self, signal: str, unit: str) -> Evidence:
        """The change as the evidence of a finding about ``signal``."""
        return Evidence(signal=signal, shift=self.shift, shift_sd=self.shift_sd, unit=unit,
                        since_s=self.start_s, statistic=self.statistic,
                        threshold=self.threshold)


def block_change(times_s: np.ndarray, values: np.ndarray, *, settings: ResidualSettings,
                 control: np.ndarray | None = None, judge_from_s: float = -math.inf,
                 allowance: Callable[[ResidualBlocks], np.ndarray] | None = None
                 ) -> BlockChange | None:
    """The two-sided CUSUM (:func:`page_cusum`) of the standardised blocks of
    :func:`residual_blocks` that start at or after ``judge_from_s``: its first alarm, or None.

    The blocks before ``judge_from_s`` only serve as references. A caller that checks again
    and again on a moving window should pass values from a reference span (``reference_days``
    and the spread's guard) before it: then every judged block keeps the same reference from
    one check to the next, and as the CUSUM's origin moves later it can only lose alarms
    (the recursion is monotone in its start value), so a later check never finds a change
    in old blocks that the earlier checks judged without one. ``allowance``: a floor of the
    CUSUM's allowance per block [spreads], from the blocks (NaN: none)."""
    st = settings
    b = judged_blocks(times_s, values, settings=st, control=control,
                      judge_from_s=judge_from_s, allowance=allowance)
    cs = block_cusum(b, st)
    if cs.alarm is None:
        return None
    after = slice(cs.start, cs.alarm + 1)
    return BlockChange(side=cs.side, shift=float(np.nanmean(b.means[after] - b.centre[after])),
                       shift_sd=float(np.nanmean(b.z[after])),
                       start_s=float(b.blocks[cs.start] * st.block_s),
                       detected_s=min(float((b.blocks[cs.alarm] + 1) * st.block_s),
                                      _last_time(times_s, values)),
                       statistic=float(cs.statistic[-1]), threshold=st.h_sd)


def judged_blocks(times_s: np.ndarray, values: np.ndarray, *, settings: ResidualSettings,
                  control: np.ndarray | None = None, judge_from_s: float = -math.inf,
                  allowance: Callable[[ResidualBlocks], np.ndarray] | None = None
                  ) -> ResidualBlocks:
    """:func:`residual_blocks` as :func:`block_change` runs its CUSUM on them: ``z`` NaN
    before ``judge_from_s`` and ``k`` at least ``allowance`` (what ``dsfd report`` draws)."""
    b = residual_blocks(times_s, values, settings=settings, control=control)
    z = np.where(b.blocks * settings.block_s >= judge_from_s, b.z, np.nan)
    k = b.k if allowance is None else np.fmax(b.k, allowance(b))
    return dataclasses.replace(b, z=z, k=k)


def block_cusum(b: ResidualBlocks, settings: ResidualSettings) -> Cusum:
    """:func:`page_cusum` of the judged blocks ``b`` (:func:`judged_blocks`) with the
    settings' threshold, and with ``alarm_min_shift`` an alarm only where the blocks since
    its start depart by ``min_shift`` on average."""
    accept = None
    if settings.alarm_min_shift and settings.min_shift > 0:
        dev = b.means - b.centre

        def accept(side: int, start: int, i: int) -> bool:
            return bool(side * np.nanmean(dev[start:i + 1]) >= settings.min_shift)
    return page_cusum(b.z, k=b.k, h=settings.h_sd, accept=accept)


def _last_time(times_s: np.ndarray, values: np.ndarray) -> float:
    """Time of the last finite value (a block's end can lie beyond it, after the check)."""
    t = np.asarray(times_s, float)[np.isfinite(np.asarray(values, float))]
    return float(t[-1]) if t.size else math.inf


def _same_time_reference(blocks: np.ndarray, means: np.ndarray, st: ResidualSettings,
                         labels: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each block's centre and scale (NaN where the history is too short).

    Centre: the median of the blocks at the same time of day (± ``half_width_blocks``) on
    the ``reference_days`` previous days (with ``labels``: those of the block's own
    label). Scale: 1.4826 MAD (at least ``scale_floor``) of
    the deviations from their own centres over the ``reference_days`` days that end
    ``guard_blocks`` before the block: pooled over all times of day, so a few days give a
    steady spread.
    """
    nan = np.full(means.size, np.nan)
    if means.size == 0:
        return nan, nan.copy()
    dense = np.full(int(blocks[-1] - blocks[0]) + 1, np.nan)
    pos = (blocks - blocks[0]).astype(np.int64)
    dense[pos] = means
    lags = np.array([j * st.period_blocks + d for j in range(1, st.reference_days + 1)
                     for d in range(-st.half_width_blocks, st.half_width_blocks + 1)])
    idx = pos[:, None] - lags[None, :]
    ref = np.where(idx >= 0, dense[np.clip(idx, 0, None)], np.nan)
    if labels is not None:
        dense_label = np.full(dense.size, np.nan)
        dense_label[pos] = labels
        other = dense_label[np.clip(idx, 0, None)]
        # an unknown control (NaN, e.g. the first cycle of a run) is compared with any
        differ = np.isfinite(labels)[:, None] & np.isfinite(other) & (other != labels[:, None])
        ref = np.where(differ, np.nan, ref)
    enough = np.count_nonzero(np.isfinite(ref), axis=1) >= st.min_reference_blocks
    centre = nan.copy()
    if np.any(enough):
        centre[enough] = np.nanmedian(ref[enough], axis=1)
    dev = np.full(dense.size, np.nan)
    dev[pos] = means - centre
    scale = nan.copy()
    span = st.reference_days * st.period_blocks
    for i, p in enumerate(pos):
        if not enough[i]:
            continue
        window = dev[max(0, p - st.guard_blocks - span):max(0, p - st.guard_blocks)]
        if np.count_nonzero(np.isfinite(window)) >= st.min_scale_blocks:
            scale[i] = _long_run_sd(window, st.scale_floor)
    return centre, scale


def _long_run_sd(dev: np.ndarray, floor: float) -> float:
    """Robust sd of the deviations (1.4826 MAD) × sqrt((1 + φ)/(1 − φ)), φ their lag-one
    autocorrelation clipped to [0, 0.9] (NaN gaps break the pairs).

    A sum of n AR(1)-like values has the variance of n independent ones times
    (1 + φ)/(1 − φ); the CUSUM sums, so its units must be the long-run sd, or correlated
    errors reach the threshold far sooner than independent ones (the variance of the mean
    of an AR(1) process, Box, Jenkins & Reinsel; docs/model.md#diagnostics-residuals).
    """
    ok = dev[np.isfinite(dev)]
    c = float(np.median(ok))
    sd = max(MAD_TO_SD * float(np.median(np.abs(ok - c))), floor)
    a, b = dev[:-1] - c, dev[1:] - c
    pair = np.isfinite(a) & np.isfinite(b)
    a, b = np.clip(a[pair], -3 * sd, 3 * sd), np.clip(b[pair], -3 * sd, 3 * sd)
    denom = float(np.sqrt(np.sum(a * a) * np.sum(b * b)))
    phi = float(np.clip(np.sum(a * b) / denom, 0.0, 0.9)) if denom > 0 else 0.0
    return sd * float(np.sqrt((1.0 + phi) / (1.0 - phi)))
