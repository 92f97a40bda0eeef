"""The solar detector: how much of the sun the model computes does the façade still take
(docs/model.md#diagnostics-solar).

Pure (no files, clocks or logging). Dirt on the exterior glass scales every solar gain of
the façade by (1 − s): what each pane and the slats absorb, and what reaches the room. The
model computes its gains S_i from the clean façade's optics, so the calibration's heat-flux
offsets (docs/model.md#heat-offsets) take up the difference, q_i ≈ −s·S_i on each node. Per
day, the least-squares factor of the offsets on the absorbed sun over the day's sunny steps,

    b = Σ_t Σ_i q_i(t) S_i(t) / Σ_t Σ_i S_i(t)²,

is the share of the computed sun that the offsets remove (b ≈ −s on a soiled façade; on a
clean one the lumped model's own solar form error, which changes with the sky), each node
with its own level (:func:`solar_response`, Notes). Its
change against its own past is judged as a calibrated parameter's daily value is
(:func:`dsfd.estimation.parameter_shift.standardised_days`, the two-sided CUSUM with the
parameter detector's allowance and threshold), so a clean façade's day-to-day wander is
the spread, not a finding.

The same factor per node tells two causes apart: dirt takes sun from the exterior pane x1
and the slats x4 alike, a louver whose slats sit at another angle than their read-back
changes the slats' share only (:func:`solar_cause`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dsfd.estimation.diagnostics import Evidence, Finding, cusum_confidence, page_cusum
from dsfd.estimation.parameter_shift import ParameterSettings, standardised_days
from dsfd.estimation.parameter_watch import SECONDS_PER_DAY

__all__ = ["DIRT", "DIRT_OR_LOUVER", "LOUVER_OR_CLEANED", "SOLAR_SIGNAL", "DailySolarResponse",
           "SolarSettings", "factor_shift", "solar_action", "solar_cause", "solar_response",
           "solar_response_change"]

#: The evidence's signal (the pooled factor b) and the per-node factors' prefix.
SOLAR_SIGNAL = "solar_response"
#: A node's offset that moved less than this over a day's sunny steps [W/m2] was held.
MOVED_WM2 = 0.1

#: What a solar finding names (its subject): dirt alone, dirt or the louver, and for a rise
#: the louver or cleaned glass.
DIRT, DIRT_OR_LOUVER, LOUVER_OR_CLEANED = ("exterior glass", "exterior glass or louver",
                                          "louver or cleaned glass")


@dataclass(frozen=True, kw_only=True)
class SolarSettings:
    """Parameters of :func:`solar_response` and :func:`solar_response_change`.

    Attributes
    ----------
    min_louver_wm2 : float, [W/m2]
        A step counts as sunny when the slats (or, without a louver, the exterior pane)
        absorb at least this much in the model (50: about a tenth of a clear winter noon's).
    min_sun_s : float, [s]
        A day with less sun (sunny steps × the step) has no value (two hours).
    days : ParameterSettings
        Reference, guard, between-day wander and the CUSUM's allowance and threshold of
        the daily values: the parameter detector's, but an allowance of 1 spread instead
        of 1.5. Soiling is a ramp (the issue's 10 % over a week), which a trailing
        reference follows two days behind; on simulated histories of daily factors that
        wander by 0.02 from day to day (the diagnostics bench's clean winter days), the
        allowance 1 found the ramp within 7 days in 71 % of 200 histories and raised a
        finding in 3 of 200 clean 30-day ones; 1.5 in 45 % and none, 0.75 in 80 % and 5
        (docs/model.md#diagnostics-solar).
    """

    min_louver_wm2: float = 50.0
    min_sun_s: float = 7200.0
    days: ParameterSettings = field(default_factory=lambda: ParameterSettings(k_sd=1.0))


@dataclass(frozen=True)
class DailySolarResponse:
    """One day's factors (:func:`solar_response`).

    Attributes
    ----------
    time_s : float, [s]
        The day's last sunny step (when its value was complete).
    factor, sd : float, [-]
        b over all nodes and its standard error.
    node_factors : tuple of float, [-]
        b of each node x1…x4 alone (NaN where the node absorbs nothing).
    sunny_steps : int
    """

    time_s: float
    factor: float
    sd: float
    node_factors: tuple[float, ...]
    sunny_steps: int


def solar_response(time_s: np.ndarray, offsets_wm2: np.ndarray, sources_wm2: np.ndarray,
                   clusters: np.ndarray, *, settings: SolarSettings | None = None
                   ) -> DailySolarResponse | None:
    """The factor b of one day's offsets on the model's absorbed sun, or None.

    Parameters
    ----------
    time_s : array (n,), [s]
        Times of the steps.
    offsets_wm2 : array (n, 4), [W/m2]
        The heat-flux offsets q_x1…q_x4 in force during each step.
    sources_wm2 : array (n, 4), [W/m2]
        The absorbed short-wave S_1…S_4 the model computes for each step (per unit façade
        area, as the offsets).
    clusters : array (n,), int
        The calibration update each step's offsets come from: steps of one update share
        their offsets, so they are one observation for the standard error.

    Notes
    -----
    Over the sunny steps, each node i with its own level (intercept) c_i,
    q_i ≈ c_i + b·S_i: b = Σ_i Σ_t q_i (S_i − S̄_i) / Σ_i Σ_t (S_i − S̄_i)². The level takes
    what does not follow the sun (the sky's long-wave on the exterior pane, a sensor's
    offset); a node whose offset did not move while the sun was up (held by the
    calibration's identifiability test, docs/model.md#identifiability) says nothing of the
    sun and is left out, as it would pull b towards 0. The standard error is the
    cluster-robust (sandwich) one, sqrt(Σ_c (Σ_{t∈c} Σ_i e_i (S_i − S̄_i))²) / Σ (S_i − S̄_i)²
    with e the residual (Liang & Zeger 1986), since the offsets change only at each update.
    """
    st = settings or SolarSettings()
    t = np.asarray(time_s, float)
    q = np.asarray(offsets_wm2, float)
    s = np.asarray(sources_wm2, float)
    louver = s[:, 3] if np.any(s[:, 3] > 0) else s[:, 0]
    sunny = (louver >= st.min_louver_wm2) & np.all(np.isfinite(q), axis=1) \
        & np.all(np.isfinite(s), axis=1)
    n = int(np.count_nonzero(sunny))
    step_s = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    if n * step_s < st.min_sun_s:
        return None
    q, s, c = q[sunny], s[sunny], np.asarray(clusters)[sunny]
    xs = s - s.mean(axis=0)
    ys = q - q.mean(axis=0)
    den = np.sum(xs * xs, axis=0)
    moved = (np.ptp(q, axis=0) > MOVED_WM2) & (den > 0)
    if not moved.any():
        return None
    num = np.sum(xs * ys, axis=0)
    b = float(num[moved].sum() / den[moved].sum())
    score = np.sum(((ys - b * xs) * xs)[:, moved], axis=1)
    _, inverse = np.unique(c, return_inverse=True)
    sd = float(np.sqrt(np.sum(np.bincount(inverse, weights=score) ** 2))) / den[moved].sum()
    nodes = np.where(moved, num / np.where(den > 0, den, 1.0), np.nan)
    return DailySolarResponse(time_s=float(t[sunny][-1]), factor=b, sd=max(sd, 1e-4),
                              node_factors=tuple(float(v) for v in nodes), sunny_steps=n)


def solar_response_change(days: list[DailySolarResponse], *,
                          settings: SolarSettings | None = None) -> Finding | None:
    """The first change of the daily factor b beyond its own day-to-day spread, or None.

    Parameters
    ----------
    days : list of DailySolarResponse
        In time order, at most one per day.

    Notes
    -----
    z_i of each day against the mean of its trailing reference in units of its spread
    (the day's standard error widened by the between-day wander the reference days show,
    :func:`~dsfd.estimation.parameter_shift.standardised_days`), then the two-sided CUSUM
    with ``settings.days``' allowance and threshold. The finding's evidence is b's shift
    and, per node of the exterior pane x1 and the slats x4, that node's own shift over the
    same days against the same reference (:func:`solar_cause` names the cause from them; the
    finding's subject).
    """
    st = settings or SolarSettings()
    if not days:
        return None
    t = np.array([d.time_s for d in days])
    v = np.array([d.factor for d in days])
    z, ref_mean = standardised_days(t, v, np.array([d.sd for d in days]), st.days)
    cs = page_cusum(z, k=st.days.k_sd, h=st.days.h_sd)
    if cs.alarm is None:
        return None
    after = slice(cs.start, cs.alarm + 1)
    shift = float(np.nanmean(v[after] - ref_mean[after]))
    ev = [Evidence(signal=SOLAR_SIGNAL, shift=shift, shift_sd=float(np.nanmean(z[after])),
                   unit="1", since_s=float(t[cs.start]), statistic=float(cs.statistic[-1]),
                   threshold=st.days.h_sd)]
    nodes = np.array([d.node_factors for d in days])
    g = st.days
    before = _reference_days(t, float(t[cs.start]), g)
    node_shift = {}
    for i in (0, 3):
        if not (np.isfinite(nodes[after, i]).any() and np.isfinite(nodes[before, i]).any()):
            continue  # the node's offset was held on those days: no evidence of its own
        node_shift[i] = float(np.nanmean(nodes[after, i]) - np.nanmean(nodes[before, i]))
        ev.append(Evidence(signal=f"{SOLAR_SIGNAL}:x{i + 1}", shift=node_shift[i],
                           shift_sd=float("nan"), unit="1", since_s=float(t[cs.start]),
                           statistic=float("nan"), threshold=float("nan")))
    cause = solar_cause(shift, pane_shift=node_shift.get(0), slat_shift=node_shift.get(3))
    return Finding(kind="solar_gain_shift", confidence=cusum_confidence(ev[0].statistic, g.h_sd),
                   start_s=float(t[cs.start]), detected_s=float(t[cs.alarm]),
                   evidence=tuple(ev), subject=cause, action=solar_action(shift, cause))


def solar_cause(shift: float, *, pane_shift: float | None, slat_shift: float | None) -> str:
    """What the change of b by ``shift`` names, from the exterior pane's and the slats' own
    shifts: :data:`DIRT`, :data:`DIRT_OR_LOUVER` or :data:`LOUVER_OR_CLEANED`.

    Dirt on the exterior glass takes the same share from every layer behind it and from the
    pane itself (its film absorbs what the glass no longer does, or scatters it away), so
    both nodes fall alike; slats at another angle than their read-back change the slats'
    share while the exterior pane's stays. Where the pane's shift is less than a third of
    the slats' (or unknown: its offset held), the two causes are named together."""
    if shift >= 0:
        return LOUVER_OR_CLEANED
    both = (slat_shift is not None and pane_shift is not None and slat_shift < 0
            and pane_shift <= slat_shift / 3.0)
    return DIRT if both else DIRT_OR_LOUVER


def solar_action(shift: float, cause: str) -> str:
    """What to check when the share of the computed sun the façade takes moved by ``shift``
    (b's change: −0.1 = a tenth less) and the evidence names ``cause``
    (:func:`solar_cause`)."""
    pct = f"{abs(shift):.0%}"
    if cause == LOUVER_OR_CLEANED:
        return (f"the façade takes about {pct} more of the sun than the model computes, "
                "compared with the days before: the exterior glass was cleaned (nothing to "
                "do), or the slats sit at another angle than their read-back (compare the "
                "angle by eye), or the pyranometer reads high")
    head = (f"the façade takes about {pct} less of the sun than the model computes from its "
            "clean optics, compared with the days before")
    if cause == DIRT:
        return (f"{head}, on the exterior pane and the slats alike: dirt on the exterior "
                "glass; clean it (the pyranometer reading low looks the same: check it "
                "against a clear-sky day first)")
    return (f"{head}: dirt on the exterior glass (clean it) or the slats sitting at another "
            "angle than their read-back (a slipped motor step: compare the angle by eye with "
            "the read-back); the evidence cannot tell these apart")


def factor_shift(days: list[DailySolarResponse], *, since_s: float,
                 settings: SolarSettings | None = None) -> float | None:
    """The daily factor b's mean over the days from ``since_s`` minus its mean over the
    reference days before them (the detector's guard and reference spans), or None when
    either has no day: the direction of a change found elsewhere (< 0: less sun taken)."""
    t = np.array([d.time_s for d in days], float)
    b = np.array([d.factor for d in days], float)
    after = t >= since_s
    before = _reference_days(t, since_s, (settings or SolarSettings()).days)
    if not (after.any() and before.any()):
        return None
    return float(np.mean(b[after]) - np.mean(b[before]))


def _reference_days(t: np.ndarray, since_s: float, g: ParameterSettings) -> np.ndarray:
    """The days ``t`` [s] of the reference a change from ``since_s`` is measured against:
    the ``g.reference_days`` ending ``g.guard_days`` before it."""
    return ((t >= since_s - (g.guard_days + g.reference_days) * SECONDS_PER_DAY)
            & (t < since_s - g.guard_days * SECONDS_PER_DAY))
