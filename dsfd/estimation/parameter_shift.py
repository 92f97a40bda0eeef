"""The parameter detector: a calibrated parameter's daily history against its own past
(docs/model.md#diagnostics-parameters).

Pure (no files, clocks or logging). :func:`parameter_change` takes one parameter's history
(one estimate a day) with the calibration's posterior sd: each estimate's distance from the
mean of a trailing reference, in units of the posterior sd widened by the parameter's own
between-day wander (:func:`between_day_variance`), then the two-sided CUSUM of
:func:`dsfd.estimation.diagnostics.page_cusum` with an allowance of 1.5 of those units, so
that estimates wandering as they did on the days before never add up to a finding; the
action says what that parameter's change means for the façade
(:func:`dsfd.estimation.parameter_watch.parameter_action`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dsfd.estimation.diagnostics import Evidence, Finding, cusum_confidence, page_cusum
from dsfd.estimation.parameter_watch import SECONDS_PER_DAY, parameter_action

__all__ = ["ParameterSettings", "between_day_variance", "parameter_change", "standardised_days"]


@dataclass(frozen=True, kw_only=True)
class ParameterSettings:
    """Parameters of :func:`parameter_change` (docs/model.md#diagnostics).

    Attributes
    ----------
    reference_days, guard_days : float, [d]
        The reference is the estimates from ``guard_days + reference_days`` to
        ``guard_days`` before the one tested (7 and 2 days).
    wander_days : float, [d]
        The between-day variance is estimated over the estimates from ``guard_days +
        wander_days`` to ``guard_days`` before (28 days): from a week's six differences its
        sampling error alone (about ±60 % in τ²) raised findings on clean synthetic days, and
        a step beyond the guard weighs 1/27 of it.
    min_wander : int
        Fewer estimates in that span: no statistic (6: the detector learns a façade's daily
        wander for about a week before it judges; with 3, 6 of 50 synthetic clean histories
        of 120 days whose wander is ten posterior sd raised a finding in their first week).
    min_reference : int
        Fewer estimates in the reference: no statistic.
    k_sd, h_sd : float
        CUSUM allowance and threshold in posterior sd (1.5 and 5): an estimate within
        1.5 sd of the reference adds nothing; three days at 4 sd, or two at 4 sd and one at 1.5
        sd beyond the allowance, are a finding.
    """

    reference_days: float = 7.0
    guard_days: float = 2.0
    wander_days: float = 28.0
    min_wander: int = 6
    min_reference: int = 3
    k_sd: float = 1.5
    h_sd: float = 5.0


def between_day_variance(values: np.ndarray, sds: np.ndarray) -> float:
    """Variance of the day-to-day wander of daily estimates beyond their own sd, τ² ≥ 0.

    Parameters
    ----------
    values, sds : array (n,)
        Daily estimates in time order and their sd (same coordinates).

    Returns
    -------
    float
        τ² = max(0, mean over consecutive pairs of ((θ_j+1 − θ_j)² − σ_j² − σ_j+1²) / 2); 0
        for fewer than two estimates.

    Notes
    -----
    A random-effects model of the days, θ_j = μ + u_j + e_j with u_j ~ (0, τ²) the day's own
    departure and e_j ~ (0, σ_j²) the estimate's error, as in DerSimonian & Laird's
    method-of-moments estimate of τ² (Controlled Clinical Trials 7, 1986). The moments are
    taken of successive differences, E[(θ_j+1 − θ_j)²] = σ_j² + σ_j+1² + 2τ², rather than of
    the deviations from the mean (von Neumann's mean square successive difference, Ann.
    Math. Statist. 12, 1941): a slow drift adds only the square of one day's step to each
    difference, so soiling under way in the reference does not hide itself by inflating τ².
    """
    v = np.asarray(values, float)
    sd = np.asarray(sds, float)
    if v.size < 2:
        return 0.0
    excess = np.diff(v) ** 2 - sd[1:] ** 2 - sd[:-1] ** 2
    return max(0.0, 0.5 * float(np.mean(excess)))


def parameter_change(times_s: np.ndarray, values: np.ndarray, sds: np.ndarray, *, name: str,
                     unit: str = "", settings: ParameterSettings | None = None
                     ) -> Finding | None:
    """The first change of a calibrated parameter beyond its posterior sd, or None.

    Parameters
    ----------
    times_s : array (n,), [s]
        Times of the estimates, increasing (typically one a day).
    values, sds : array (n,)
        The estimates and their posterior sd in the same coordinates (for a positive
        parameter the calibration's log coordinates make the sd relative).
    name, unit : str
        For the evidence and the action (``unit`` ``"log"``: values and sds are of log θ).

    Notes
    -----
    z_i = (θ_i − θ̄_ref) / sqrt(σ_i² + τ² + σ̄_ref²): τ² the reference days' between-day
    variance (:func:`between_day_variance`), θ̄_ref their mean weighted by 1/(σ_j² + τ²)
    and σ̄_ref its standard error; two-sided CUSUM of z with ``k_sd``, ``h_sd``. The
    posterior sd is the floor of the spread, and a lumped parameter whose clean days
    wander by more than it (the model's form error changes with the weather) raises the
    spread by the wander the reference itself shows (docs/model.md#diagnostics-parameters).
    """
    st = settings or ParameterSettings()
    t = np.asarray(times_s, float)
    v = np.asarray(values, float)
    z, ref_mean = standardised_days(t, v, np.asarray(sds, float), st)
    cs = page_cusum(z, k=st.k_sd, h=st.h_sd)
    if cs.alarm is None:
        return None
    after = slice(cs.start, cs.alarm + 1)
    ev = Evidence(signal=f"parameter:{name}", shift=float(np.nanmean(v[after] - ref_mean[after])),
                  shift_sd=float(np.nanmean(z[after])), unit=unit, since_s=float(t[cs.start]),
                  statistic=float(cs.statistic[-1]), threshold=st.h_sd)
    return Finding(kind="parameter_shift", confidence=cusum_confidence(ev.statistic, st.h_sd),
                   start_s=ev.since_s, detected_s=float(t[cs.alarm]), evidence=(ev,),
                   action=parameter_action(name, side=cs.side, shift=ev.shift,
                                           shift_sd=ev.shift_sd, unit=unit))


def standardised_days(t: np.ndarray, v: np.ndarray, sd: np.ndarray,
                      st: ParameterSettings) -> tuple[np.ndarray, np.ndarray]:
    """Each daily value's distance from its trailing reference in units of its spread, and
    the reference means (NaN where the history is too short; :func:`parameter_change`,
    Notes)."""
    z = np.full(v.size, np.nan)
    ref_mean = np.full(v.size, np.nan)
    ok = np.isfinite(v) & np.isfinite(sd) & (sd > 0)
    for i in range(v.size):
        if not ok[i]:
            continue
        sel = (ok & (t >= t[i] - (st.guard_days + st.reference_days) * SECONDS_PER_DAY)
               & (t < t[i] - st.guard_days * SECONDS_PER_DAY))
        wander = (ok & (t >= t[i] - (st.guard_days + st.wander_days) * SECONDS_PER_DAY)
                  & (t < t[i] - st.guard_days * SECONDS_PER_DAY))
        if (np.count_nonzero(sel) < st.min_reference
                or np.count_nonzero(wander) < st.min_wander):
            continue
        tau2 = between_day_variance(v[wander], sd[wander])
        w = 1.0 / (sd[sel] ** 2 + tau2)
        ref_mean[i] = float(np.sum(w * v[sel]) / np.sum(w))
        z[i] = (v[i] - ref_mean[i]) / math.sqrt(sd[i] ** 2 + tau2 + 1.0 / float(np.sum(w)))
    return z, ref_mean
