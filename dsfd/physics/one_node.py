"""The one-node cavity: all four openings open (regime 9, docs/model.md#one-node).

With every damper open the cavity pressure P_c is the unknown of one mass balance,
Σ_k ṁ_k(P_c) = 0, each opening an orifice (square-root law, regularised near zero flow:
docs/model.md#regularisation). Σṁ is strictly decreasing in P_c, so the root is unique. The coupling
of the thermal model re-solves it at every evaluation of the cavity temperature, so the solver
is built for warm starts: from a start predicted along the solution's sensitivities it
takes plain Newton steps, and stops at a Newton point it has not evaluated when the
residual there is provably below the tolerance; anything else goes to Newton's method
inside a shrinking bracket.

The opening laws are those of :mod:`dsfd.physics.airflow` (regularised as in the IBPSA
Modelica library's ``Airflow.Multizone``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from dsfd.physics.airflow import (
    _poly_coefficients_scalar,
    _regularised_power_slope,
    regularised_power,
)
from dsfd.physics.constants import GRAVITY

#: Unbracketed Newton steps from a warm start before the bracketed iteration takes over.
_WARM_NEWTON_STEPS = 4
#: Largest batch whose warm start is iterated row by row on Python floats. A vectorised
#: Newton solve is ~50 numpy calls of 1–2 µs each whatever the batch size, the scalar one
#: ~3 µs plus ~10 µs a row: the optimiser's full-resolution rollouts carry a few all-open
#: rows, and the coupling's later evaluations only the rows still iterating.
SCALAR_MAX_ROWS = 8
#: Bound on the regularising polynomial's curvature for m = ½ in units of C Δp_t^-1.5 (its
#: maximum is 1.56): the acceptance bound of the warm Newton steps inside the band.
_BAND_CURVATURE = 1.6


class OneNodeFlow(NamedTuple):
    """Solution of the one-node cavity (:func:`one_node_flows`).

    Attributes
    ----------
    m_dot : ndarray (B, 4), [kg/s]
        Mass flows into the cavity.
    p_c : ndarray (B,), [Pa]
        Cavity pressure at z = 0.
    dpc_drho : ndarray (B,), [Pa/(kg/m3)]
        dP_c/dρ_c at the solution, boundary pressures held (NaN where no opening is
        open): the tangent that predicts P_c for a nearby cavity density, so that a
        re-solve inside the coupling starts within Newton's quadratic range.
    dpc_dpb : ndarray (B, 4), [-]
        ∂P_c/∂p_B,k: the share of each opening's boundary-pressure change that the cavity
        pressure follows (the openings' flow slopes over their sum; rows sum to 1). With
        ``dpc_drho`` it predicts P_c of the next step, whose wind and temperatures differ.
    """

    m_dot: np.ndarray
    p_c: np.ndarray
    dpc_drho: np.ndarray
    dpc_dpb: np.ndarray


# long: 104 lines, 45 of them the docstring; the closures total() and result() carry the
# per-call flow coefficients shared by the warm Newton steps and _bracketed_newton. Left
# whole while issue 24 (perf) reworks this solver.
def one_node_flows(
    p_b: np.ndarray,
    rho_b: np.ndarray,
    z: np.ndarray,
    k: np.ndarray,
    rho_c: np.ndarray,
    dp_t: float,
    *,
    tol_kgs: float = 1e-15,
    max_iter: int = 100,
    p_c_start: np.ndarray | None = None,
    scalar_max_rows: int = SCALAR_MAX_ROWS,
) -> OneNodeFlow:
    """General one-node cavity flow solver (docs/model.md#one-node).

    Solves Σ_k ṁ_k(P_c) = 0 for the cavity pressure P_c at z = 0, where
    ṁ_k = reg(Δp_k; C_k = sqrt(2 ρ_up,k / K_k)), Δp_k = p_B,k − (P_c − ρ_c g z_k),
    ρ_up,k = ρ_B,k for inflow and ρ_c for outflow. Σṁ is strictly decreasing in P_c, so
    a safeguarded Newton iteration inside a shrinking bracket converges to the unique root.

    Parameters
    ----------
    p_b, rho_b : arrays (B, 4), [Pa], [kg/m3]
        Boundary pressure and density outside each opening.
    z : array (4,), [m]
        Opening heights.
    k : array (B, 4), [1/m4]
        Loss coefficients (inf = closed).
    rho_c : array (B,), [kg/m3]
        Cavity air density.
    dp_t : float, [Pa]
        Regularisation threshold.
    p_c_start : array (B,), optional, [Pa]
        Starting guesses (e.g. the previous solution); NaN or outside the bracket means
        "use the conductance-weighted mean head".
    scalar_max_rows : int
        Warm starts of batches up to this size are iterated row by row on Python floats
        (same iteration and acceptance; the vectorised path takes over when a row leaves
        it).

    Returns
    -------
    OneNodeFlow
    """
    warm = p_c_start is not None and bool(np.isfinite(p_c_start).all())
    if warm and p_b.shape[0] <= scalar_max_rows:
        sol = _warm_rows(p_b, rho_b, z, k, rho_c, dp_t, tol_kgs, p_c_start)
        if sol is not None:
            return sol
    inv_k = 1.0 / k  # 0 where closed (k = inf)
    head = p_b + rho_c[:, None] * (GRAVITY * z)  # Δp_k = head_k − P_c
    # Flow coefficients for inflow (boundary air) and outflow (cavity air) of each opening.
    c_in = np.sqrt(2.0 * rho_b * inv_k)
    c_out = np.sqrt((2.0 * rho_c)[:, None] * inv_k)

    def total(pc: np.ndarray) -> tuple[np.ndarray, ...]:
        """ṁ_k, Σṁ, dṁ_k/dΔp_k, Δp_k and the flow coefficients at cavity pressure ``pc``."""
        dp = head - pc[:, None]
        coef = np.where(dp > 0, c_in, c_out)
        mag = np.abs(dp)
        if mag.min() >= dp_t:  # usual case: plain orifice law, no regularisation needed
            root = np.sqrt(mag)
            m = coef * np.copysign(root, dp)
            return m, m.sum(axis=1), 0.5 * coef / root, dp, coef
        m = regularised_power(dp, coef, 0.5, dp_t)
        return m, m.sum(axis=1), _regularised_power_slope(dp, coef, 0.5, dp_t), dp, coef

    def result(m: np.ndarray, slope: np.ndarray, pc: np.ndarray) -> OneNodeFlow:
        # Implicit differentiation of Σṁ(P_c, ρ_c, p_B) = 0: ∂Σṁ/∂ρ_c = Σ ṁ'_k g z_k (the
        # cavity column) + Σ_out ṁ_k/(2ρ_c) (outflows carry cavity air, C ∝ √ρ_c), and
        # ∂Σṁ/∂p_B,k = ṁ'_k; both over ∂Σṁ/∂P_c = −Σ ṁ'_k.
        d_rho = slope @ (GRAVITY * z) + np.minimum(m, 0.0).sum(axis=1) / (2.0 * rho_c)
        d_pc = slope.sum(axis=1)
        inv = np.divide(1.0, d_pc, out=np.full(d_pc.shape, np.nan), where=d_pc > 0)
        return OneNodeFlow(m, pc, d_rho * inv, slope * inv[:, None])

    if warm:
        # Warm start (the coupling's re-solves): plain Newton steps. The last Newton point
        # is accepted without evaluating it when its residual is provably small: the flows
        # moved along their tangents balance exactly, and each is off by at most
        # ½ δ² max|ṁ''_k| over the step δ. That needs each law smooth along the step, so
        # no opening may cross its zero-flow point (the upstream density, hence the slope,
        # jumps there); a step that crosses one is taken and evaluated. Along a step that
        # does not, |Δp_k| stays ≥ u_k, the smaller of its ends, and |ṁ''_k| ≤ C_k u^-1.5/4
        # (square-root law) where u_k ≥ Δp_t, ≤ 1.6 C_k Δp_t^-1.5 (the largest curvature
        # of the regularising polynomial, 1.56 for m = ½) where the step enters the band.
        pc = np.asarray(p_c_start, float)
        for _ in range(_WARM_NEWTON_STEPS):
            m_dot, s, slope, dp, coef = total(pc)
            ds = slope.sum(axis=1)  # 0 only where nothing is open: then inf → bracketed
            step = np.divide(s, ds, out=np.full(ds.shape, np.inf), where=ds > 0)
            step = np.where(np.abs(s) <= tol_kgs, 0.0, step)
            if not np.isfinite(step).all():
                break
            end = dp - step[:, None]
            u = np.minimum(np.abs(dp), np.abs(end))
            curv = coef * np.where(u >= dp_t, 0.25 * np.maximum(u, dp_t) ** -1.5,
                                   _BAND_CURVATURE * dp_t**-1.5)
            smooth = (end * dp > 0) | (step == 0.0)[:, None]
            if smooth.all() and (0.5 * step * step * curv.sum(axis=1) <= tol_kgs).all():
                return result(m_dot - slope * step[:, None], slope, pc + step)
            pc = pc + step
        p_c_start = pc
    return _bracketed_newton(total, result, head, inv_k, tol_kgs, max_iter, p_c_start)


def _warm_rows(p_b: np.ndarray, rho_b: np.ndarray, z: np.ndarray, k: np.ndarray,
               rho_c: np.ndarray, dp_t: float, tol_kgs: float,
               p_c_start: np.ndarray) -> OneNodeFlow | None:
    """The warm-start Newton of :func:`one_node_flows`, row by row on Python floats.

    The same flow law (square root, IBPSA polynomial below Δp_t), the same steps and the
    same acceptance bound, decided per row. None when a row is not accepted within the
    step limit: the vectorised path then solves the whole batch.
    """
    a, b, c, d = _poly_coefficients_scalar(0.5)
    sqrt_t = math.sqrt(dp_t)
    band_curvature = _BAND_CURVATURE * dp_t**-1.5
    gz = (GRAVITY * np.asarray(z, float)).tolist()
    rows = []
    for pb, rb, kk, rho, pc in zip(p_b.tolist(), rho_b.tolist(), k.tolist(), rho_c.tolist(),
                                   p_c_start.tolist(), strict=True):
        head = [p + rho * g for p, g in zip(pb, gz, strict=True)]
        c_in = [math.sqrt(2.0 * r / q) for r, q in zip(rb, kk, strict=True)]  # 0 if closed
        c_out = [math.sqrt(2.0 * rho / q) for q in kk]
        for _ in range(_WARM_NEWTON_STEPS):
            total = slopes = 0.0
            flows = []
            for h, ci, co in zip(head, c_in, c_out, strict=True):
                dp = h - pc
                mag = abs(dp)
                coef = ci if dp > 0 else co
                if mag >= dp_t:
                    root = math.sqrt(mag)
                    m = coef * root if dp > 0 else -coef * root
                    slope = 0.5 * coef / root
                else:
                    x = dp / dp_t
                    x2 = x * x
                    m = coef * sqrt_t * x * (a + x2 * (b + x2 * (c + x2 * d)))
                    slope = coef / sqrt_t * (a + x2 * (3 * b + x2 * (5 * c + x2 * 7 * d)))
                total += m
                slopes += slope
                flows.append((m, slope, dp, coef))
            if not slopes > 0:
                return None
            step = 0.0 if abs(total) <= tol_kgs else total / slopes
            curvature = 0.0
            for _, _, dp, coef in flows:
                end = dp - step
                if end * dp <= 0 and step != 0.0:  # crosses a zero-flow point
                    curvature = math.inf
                    break
                u = min(abs(dp), abs(end))
                curvature += coef * (0.25 * u**-1.5 if u >= dp_t else band_curvature)
            if 0.5 * step * step * curvature <= tol_kgs:
                moved = [m - slope * step for m, slope, _, _ in flows]
                d_rho = (sum(f[1] * g for f, g in zip(flows, gz, strict=True))
                         + sum(min(m, 0.0) for m in moved) / (2.0 * rho))
                rows.append([*moved, pc + step, d_rho / slopes,
                             *(f[1] / slopes for f in flows)])
                break
            pc += step
        else:
            return None
    out = np.array(rows).reshape(-1, 10)
    return OneNodeFlow(out[:, :4], out[:, 4], out[:, 5], out[:, 6:])


def _bracketed_newton(total: Callable[[np.ndarray], tuple[np.ndarray, ...]],
                      result: Callable[[np.ndarray, np.ndarray, np.ndarray], OneNodeFlow],
                      head: np.ndarray, inv_k: np.ndarray, tol_kgs: float, max_iter: int,
                      p_c_start: np.ndarray | None) -> OneNodeFlow:
    """Newton's method inside a shrinking bracket for :func:`one_node_flows`."""
    open_ = inv_k > 0
    # Bracket of P_c: the open openings' heads ± 1 Pa.
    if open_.all():
        lo, hi = head.min(axis=1) - 1.0, head.max(axis=1) + 1.0
    else:
        lo = np.where(open_, head, np.inf).min(axis=1) - 1.0
        hi = np.where(open_, head, -np.inf).max(axis=1) + 1.0
        lo = np.where(np.isfinite(lo), lo, 0.0)
        hi = np.where(np.isfinite(hi), hi, 0.0)
    usable = (np.zeros(lo.shape, bool) if p_c_start is None
              else np.isfinite(p_c_start) & (p_c_start > lo) & (p_c_start < hi))
    if usable.all():
        pc = p_c_start
    else:  # start from the conductance-weighted mean head (exact for linear openings)
        w = np.sqrt(inv_k)
        pc = np.where(w.sum(axis=1) > 0, (np.where(open_, head, 0.0) * w).sum(axis=1)
                      / np.maximum(w.sum(axis=1), 1e-300), 0.5 * (lo + hi))
        if p_c_start is not None:
            pc = np.where(usable, p_c_start, pc)
    # The whole batch iterates together (batches are small; converged rows stay put), which
    # is cheaper than re-indexing the unfinished rows every iteration.
    for _ in range(max_iter):
        m_dot, s, slope, *_ = total(pc)
        ds = -slope.sum(axis=1)
        # Bracket update: s > 0 means P_c is too low.
        too_low = s > 0
        lo = np.where(too_low, pc, lo)
        hi = np.where(too_low, hi, pc)
        done = (np.abs(s) <= tol_kgs) | (hi - lo <= 1e-13 * (1 + np.abs(pc)))
        if done.all():
            return result(m_dot, slope, pc)
        # ds < 0 wherever an opening is open; elsewhere the step falls outside → bisect.
        newton = pc - s / np.where(ds < 0, ds, -1.0)
        inside = (newton > lo) & (newton < hi)
        pc = np.where(done, pc, np.where(inside, newton, 0.5 * (lo + hi)))
    m_dot, _, slope, *_ = total(pc)
    return result(m_dot, slope, pc)
