"""Vectorised scalar fixed-point solver for the thermal–airflow coupling (docs/model.md#coupling).

Solves T = Φ(T) independently for every element of a batch, i.e. finds a root of
h(T) = Φ(T) − T. Φ is bounded (flows are bounded), so h → +∞ as T → −∞ and h → −∞ as
T → +∞ and a sign change always exists.

Method: the first step is the plain iteration T₁ = Φ(T₀) (Φ depends weakly on T, so this
is already close) or, when the caller knows the slope of h from a neighbouring solve (the
previous step of a rollout), a Newton step with that slope; then secant steps. Before the
root is bracketed a step must move in the direction of the sign of h and is limited to
``max_step``; once a sign change is seen, the secant step is accepted only if it falls
between the latest point and the bracket midpoint, otherwise the bracket is bisected
(Dekker's method). The latest iterate is always the returned one, so callers can keep
per-evaluation side results. Uniqueness of the root is not guaranteed (docs/model.md#coupling); the
one bracketed is returned.

Reference: T. J. Dekker, "Finding a zero by means of successive linear interpolation",
in Constructive Aspects of the Fundamental Theorem of Algebra, Wiley (1969) 37–48.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np


class FixedPoint(NamedTuple):
    """Result per batch element."""

    t: np.ndarray
    evaluations: np.ndarray
    converged: np.ndarray
    slope: np.ndarray
    """Last secant slope of h(T) = Φ(T) − T [-] (the given slope, or NaN, after a single
    evaluation): a warm start for the next, similar solve."""


def solve_fixed_point(
    phi: Callable[[np.ndarray, np.ndarray], np.ndarray],
    t0: np.ndarray,
    *,
    tol: float,
    max_evals: int,
    max_step: float = 50.0,
    slope: np.ndarray | None = None,
) -> FixedPoint:
    """Solve ``t = phi(t)`` elementwise.

    Parameters
    ----------
    phi : callable
        ``phi(t, rows) -> values`` evaluates Φ for batch elements ``rows`` (int array) at
        points ``t``. The last call for each element is at its returned point.
    t0 : array (B,)
        Starting guesses.
    tol : float
        Convergence when |Φ(t) − t| ≤ tol or the bracket is narrower than tol.
    max_evals : int
        Evaluation limit per element (≥ 2).
    max_step : float
        Largest single move before the root is bracketed.
    slope : array (B,), optional
        Estimate of dh/dT at the start (e.g. :attr:`FixedPoint.slope` of the previous step).
        A finite negative value turns the first move into a Newton step, which usually
        lands within the tolerance so that the second evaluation is the last.

    Returns
    -------
    FixedPoint
    """
    b = np.array(t0, dtype=float).ravel()
    nb = b.size
    s0 = np.full(nb, np.nan) if slope is None else np.broadcast_to(
        np.asarray(slope, float).ravel(), (nb,))
    s0 = np.where(s0 < 0, s0, np.nan)  # h decreases through its root: other slopes are stale
    if nb == 1:
        return _solve_one(phi, float(b[0]), tol=tol, max_evals=max_evals, max_step=max_step,
                          slope=float(s0[0]))
    rows = np.arange(nb)
    fb = phi(b, rows) - b
    evals = np.ones(nb, dtype=int)
    # A known slope acts as a virtual earlier point one kelvin away: the first secant
    # step is then Newton's step.
    c = np.where(np.isfinite(s0), b - 1.0, np.nan)
    fc = fb - s0
    a = np.full(nb, np.nan)
    done = np.abs(fb) <= tol
    while True:
        rows = np.flatnonzero(~done)
        if rows.size == 0:
            break
        br, fbr, ar = b[rows], fb[rows], a[rows]
        t_new = _next_points(br, fbr, c[rows], fc[rows], ar, max_step)
        f_new = phi(t_new, rows) - t_new
        evals[rows] += 1
        # The contrapoint keeps the sign opposite to the newest point.
        flip = np.sign(f_new) != np.sign(fbr)
        new_a = np.where(flip, br, ar)
        a[rows] = new_a
        c[rows], fc[rows] = br, fbr
        b[rows], fb[rows] = t_new, f_new
        width = np.abs(new_a - t_new)
        done[rows] = (
            (np.abs(f_new) <= tol)
            | (np.isfinite(width) & (width <= tol))
            | (evals[rows] >= max_evals)
        )
    converged = (np.abs(fb) <= tol) | (np.abs(a - b) <= tol)
    with np.errstate(divide="ignore", invalid="ignore"):
        last = np.where(evals > 1, (fb - fc) / (b - c), s0)
    return FixedPoint(t=b, evaluations=evals, converged=converged, slope=last)


def _next_points(b: np.ndarray, fb: np.ndarray, c: np.ndarray, fc: np.ndarray, a: np.ndarray,
                 max_step: float) -> np.ndarray:
    """Next iterate from the newest point b (h = fb), the previous one c (fc) and the
    contrapoint a (NaN until the root is bracketed): before bracketing, the secant step if
    it moves towards the sign of h, else b + h, at most ``max_step``; inside a bracket the
    secant point if it lies between b and the midpoint, else the midpoint."""
    # (no errstate context here: this runs every coupling evaluation; a zero denominator
    # is masked, NaNs propagate silently and are caught by isfinite)
    den = fb - fc
    sec = b - np.divide(fb * (b - c), den, out=np.full(den.shape, np.nan), where=den != 0)
    sec = np.where(np.isfinite(sec), sec, b + fb)
    bracketed = np.isfinite(a)
    search = np.where((sec - b) * fb > 0, sec, b + fb)
    search = b + np.clip(search - b, -max_step, max_step)
    mid = 0.5 * (a + b)
    between = (sec - b) * (sec - mid) < 0
    return np.where(bracketed, np.where(between, sec, mid), search)


def _solve_one(phi: Callable[[np.ndarray, np.ndarray], np.ndarray], b: float, *, tol: float,
               max_evals: int, max_step: float, slope: float) -> FixedPoint:
    """The same iteration for a single element, on Python floats (no array overhead)."""
    row = np.zeros(1, dtype=int)

    def h(t: float) -> float:
        return float(phi(np.array([t]), row)[0]) - t

    fb = h(b)
    evals = 1
    c = fc = a = math.nan
    if math.isfinite(slope):
        c, fc = b - 1.0, fb - slope
    while abs(fb) > tol and evals < max_evals:
        sec = b - fb * (b - c) / (fb - fc) if fb != fc and math.isfinite(c) else b + fb
        if not math.isfinite(sec):
            sec = b + fb
        if math.isfinite(a):
            mid = 0.5 * (a + b)
            t_new = sec if (sec - b) * (sec - mid) < 0 else mid
        else:
            step = sec - b if (sec - b) * fb > 0 else fb
            t_new = b + max(-max_step, min(max_step, step))
        f_new = h(t_new)
        evals += 1
        if (f_new > 0) != (fb > 0):
            a = b
        c, fc, b, fb = b, fb, t_new, f_new
        if math.isfinite(a) and abs(a - b) <= tol:
            break
    ok = abs(fb) <= tol or (math.isfinite(a) and abs(a - b) <= tol)
    last = (fb - fc) / (b - c) if evals > 1 and b != c else slope
    return FixedPoint(t=np.array([b]), evaluations=np.array([evals]), converged=np.array([ok]),
                      slope=np.array([last]))
