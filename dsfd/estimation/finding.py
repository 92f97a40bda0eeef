"""What a detector reports, and the change detector they share (docs/model.md#diagnostics).

Pure: :class:`Finding` (kind, confidence, start, detection time, evidence, action) with its
:class:`Evidence`, and Page's two-sided CUSUM (:func:`page_cusum`) that the residual
detector, the parameter detector, the night offsets and the night check run. Re-exported by
:mod:`dsfd.estimation.diagnostics`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["MAD_TO_SD", "Cusum", "Evidence", "Finding", "cusum_confidence", "page_cusum"]

#: MAD → σ for normal data (Rousseeuw & Croux 1993).
MAD_TO_SD = 1.4826


@dataclass(frozen=True, kw_only=True)
class Evidence:
    """What a finding rests on.

    Attributes
    ----------
    signal : str
        The residual (``residual:x3_c``), parameter (``parameter:h_out``) or cross-check
        (``crosscheck:v_cav_ms``) it was seen in.
    shift : float
        Size of the change in the signal's unit (mean after the start minus the reference).
    shift_sd : float
        The same in units of the reference spread (residuals) or posterior sd (parameters).
    unit : str
    since_s : float, [s]
        When the change started (the last time the CUSUM statistic was zero).
    statistic, threshold : float
        The detector's statistic at the detection and the threshold it crossed [-].
    """

    signal: str
    shift: float
    shift_sd: float
    unit: str
    since_s: float
    statistic: float
    threshold: float


@dataclass(frozen=True, kw_only=True)
class Finding:
    """Something the façade, a sensor or an actuator is doing that the model says is new.

    Attributes
    ----------
    kind : str
        What changed, e.g. ``residual_shift``, ``parameter_shift``, ``cavity_no_flow``.
    confidence : float, [0, 1]
        The statistic over twice its threshold, capped at 1 (0.5 at the threshold): a scale
        of how far past the threshold the evidence is, not a probability.
    start_s : float, [s]
        Estimated start of the change.
    detected_s : float, [s]
        When the evidence crossed the threshold (the CUSUMs), or the last reading the
        evidence rests on (the cavity cross-check, which judges a window).
    evidence : tuple of Evidence
    action : str
        What a person should check; names every cause the evidence cannot separate.
    subject : str
        What the finding is about when a kind can be about several things (the damper(s) of
        ``damper_no_flow``, e.g. ``IT``); empty otherwise (dsfd.estimation.lifecycle
        tells findings apart).
    """

    kind: str
    confidence: float
    start_s: float
    detected_s: float
    evidence: tuple[Evidence, ...]
    action: str
    subject: str = ""


@dataclass(frozen=True)
class Cusum:
    """Result of :func:`page_cusum` over standardised values ``z``.

    ``alarm`` is the first index where a side exceeds ``h`` (None: no alarm), ``side`` +1
    (upward shift) or −1, ``start`` the index after that side's last zero before the alarm
    (the change-point estimate of Page's scheme), ``statistic`` the larger side per index.
    """

    alarm: int | None
    side: int
    start: int
    statistic: np.ndarray


def page_cusum(z: np.ndarray, *, k: float | np.ndarray, h: float,
               accept: Callable[[int, int, int], bool] | None = None) -> Cusum:
    """Two-sided CUSUM (Page 1954): S⁺ = max(0, S⁺ + z − k), S⁻ = max(0, S⁻ − z − k).

    ``k`` is one allowance or one per value. Non-finite ``z`` leave both sides unchanged.
    With independent standard normal z, k = 0.75 and h = 8, the mean run to a false alarm
    of one side is about 8·10⁵ values (Siegmund's approximation (e^{2kb} − 2kb − 1)/(2k²),
    b = h + 1.166, as given by Basseville & Nikiforov 1993).

    ``accept(side, start, i)``: an alarm at index ``i`` also needs it to return True (a
    side over ``h`` that it refuses carries on, so a change that grows is still found).
    """
    z = np.asarray(z, float)
    allowance = np.broadcast_to(np.asarray(k, float), z.shape)
    s_pos = s_neg = 0.0
    zero_pos = zero_neg = 0
    stat = np.zeros(z.size)
    for i, v in enumerate(z):
        if math.isfinite(v):
            s_pos = max(0.0, s_pos + v - allowance[i])
            s_neg = max(0.0, s_neg - v - allowance[i])
        # a missing value while a side is at zero moves that side's start past it
        if s_pos == 0.0:
            zero_pos = i + 1
        if s_neg == 0.0:
            zero_neg = i + 1
        stat[i] = max(s_pos, s_neg)
        if s_pos > h or s_neg > h:
            up = s_pos >= s_neg
            side, start = (1, zero_pos) if up else (-1, zero_neg)
            if accept is None or accept(side, start, i):
                return Cusum(i, side, start, stat[:i + 1])
    return Cusum(None, 0, z.size, stat)


def cusum_confidence(statistic: float, threshold: float) -> float:
    """:attr:`Finding.confidence` of a CUSUM: statistic / (2 × threshold), at most 1."""
    return float(min(1.0, statistic / (2.0 * threshold)))
