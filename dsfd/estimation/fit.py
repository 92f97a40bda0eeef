"""One bounded, robust, prior-regularised least-squares fit of θ on a window (Eq. 3).

Minimises, over the free parameters z_F (log θ; n linear) within the bounds,

    ½ Σ_j c² ρ(e_j(θ)²/c²)  +  ½ w (z_F − z̄_F)ᵀ P̄_F⁻¹ (z_F − z̄_F)

with e the weighted multi-step residuals of :mod:`dsfd.estimation.objective`, ρ a robust
loss with soft threshold c (``f_scale``), and the arrival cost of moving-horizon
estimation (Rao, Rawlings & Mayne 2003): the previous estimate z̄ with covariance P̄
summarises the data before the window, so parameters the window does not excite stay put.

Notes
-----
* Robust loss: the data residuals are replaced by r̃ = c·sgn(e)·√ρ(e²/c²), so that
  Σ r̃² is the robust cost, with Jacobian scaled by dr̃/de = ρ'·|e|/(c√ρ) (the "square-root
  robustification" of Triggs et al. 2000, §4.3); the prior rows stay quadratic. ρ as in
  ``scipy.optimize.least_squares``: soft_l1 2(√(1+u) − 1), huber, cauchy ln(1+u),
  arctan(u) of u = e²/c². One wrong sample therefore pulls with a bounded force.
* Jacobian: forward differences in z, all perturbed θ as extra batch rows of ONE model
  rollout (:meth:`WindowProblem.predict`); backward at an upper bound.
* Covariance: P = (J̃ᵀJ̃ / (s² m_r) + w P̄⁻¹)⁻¹ with s = 1.4826·median|r̃| (robust
  residual scale) and m_r the mean number of lead times per rollout — the residuals of one
  rollout share its start-state and model-form error, so a rollout is counted as about one
  independent observation (a conservative effective-sample-size correction).
* :func:`dsfd.estimation.lsq.bounded_least_squares` (bounded, scaled Levenberg–Marquardt;
  SciPy's ``least_squares`` until its import cost was measured) with ``max_nfev`` residual
  evaluations; each accepted step costs one more batched rollout for the Jacobian, or,
  with ``broyden`` > 0, a Broyden rank-one update of the previous one (Broyden 1965;
  Dennis & Schnabel 1996, §8.1) between finite-difference refreshes.
* Identifiability (docs/model.md#identifiability): with ``determined_sd_ratio`` < 1 (the
  on-line updates), the Jacobian at the start point first decides which free parameters
  the window determines — those whose sd under the window's data and the *first* prior
  alone, √[(JᵀJ/m_r + P₀⁻¹)⁻¹]_jj with the residuals in their scales σ_T, σ_v, falls below
  that fraction of the first prior's √P₀_jj (a local, linearised Fisher-information test;
  the marginal, so a parameter that only a combination with another determines, such as
  h_out with x1's offset at night, is not). Only those are fitted; the others keep the
  arrival cost's mean. Without it, an undetermined parameter moves along the ridge the data
  leave flat, and over many windows walks to a bound absorbing another parameter's or the
  model's error.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from dsfd.estimation.lsq import bounded_least_squares
from dsfd.estimation.objective import OUTPUTS, WindowProblem
from dsfd.estimation.params import N_PARAMS, Param, ParameterSpace

#: Forward-difference steps in z: 1 % of θ for log coordinates, 0.01 for n, 1 W/m2 for
#: the offsets — output changes of ~0.01 K, a hundred times the coupling tolerance of
#: the fit's rollouts (dsfd.estimation.objective.COUPLING_TOL_K).
FD_STEP_LOG, FD_STEP_N, FD_STEP_OFFSET_WM2 = 1e-2, 1e-2, 1.0


def robust_rho(u: np.ndarray, loss: str) -> tuple[np.ndarray, np.ndarray]:
    """ρ(u) and ρ'(u) of the scipy losses (u = (e/c)²)."""
    if loss == "linear":
        return u, np.ones_like(u)
    if loss == "soft_l1":
        t = np.sqrt(1.0 + u)
        return 2.0 * (t - 1.0), 1.0 / t
    if loss == "huber":
        big = u > 1.0
        rz = np.sqrt(np.where(big, u, 1.0))
        return np.where(big, 2.0 * rz - 1.0, u), np.where(big, 1.0 / rz, 1.0)
    if loss == "cauchy":
        return np.log1p(u), 1.0 / (1.0 + u)
    if loss == "arctan":
        return np.arctan(u), 1.0 / (1.0 + u * u)
    raise ValueError(f"unknown loss {loss!r}")


def robustify(e: np.ndarray, loss: str, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """r̃ = c sgn(e) √ρ(e²/c²) and dr̃/de (shape of ``e``)."""
    u = (e / scale) ** 2
    rho, drho = robust_rho(u, loss)
    root = np.sqrt(np.clip(rho, 0.0, None))
    r = scale * np.sign(e) * root
    small = u < 1e-12
    slope = np.where(small, 1.0, drho * np.abs(e) / (scale * np.where(small, 1.0, root)))
    return r, slope


@dataclass(frozen=True, eq=False)
class FitResult:
    """Outcome of :func:`fit_window`.

    Attributes
    ----------
    theta : ndarray (9,)
        Estimate (held parameters at the prior mean).
    cov_z : ndarray (9, 9)
        Posterior covariance in z for the free block, the prior elsewhere.
    free : ndarray (9,), bool
        Parameters the fit moved (the window determined them).
    cost : float
        Final robust cost (data + prior).
    cost_start : float
        Cost at the prior mean.
    nfev, njev : int
        Residual and Jacobian evaluations.
    n_residuals : int
    success : bool
    message : str
    """

    theta: np.ndarray
    cov_z: np.ndarray
    free: np.ndarray
    cost: float
    cost_start: float
    nfev: int
    njev: int
    n_residuals: int
    success: bool
    message: str


def _prior_rows(cov_free: np.ndarray, weight: float) -> np.ndarray:
    """A with AᵀA = w P̄⁻¹ (A = √w C⁻¹, P̄ = C Cᵀ)."""
    p = cov_free.shape[0]
    if weight <= 0.0 or p == 0:
        return np.zeros((0, p))
    chol = np.linalg.cholesky(cov_free + 1e-12 * np.eye(p))
    return np.sqrt(weight) * np.linalg.solve(chol, np.eye(p))


def fit_window(problem: WindowProblem, space: ParameterSpace, *, prior_z: np.ndarray,
               prior_cov: np.ndarray, free: np.ndarray, loss: str, f_scale: float,
               prior_weight: float, max_nfev: int, broyden: int = 0,
               adaptive_scales: bool = False, determined_sd_ratio: float = 1.0,
               always_fit: np.ndarray | None = None,
               progress: Callable[[int, int, float], None] | None = None) -> FitResult:
    """Fit the free parameters of θ on one window.

    Parameters
    ----------
    problem : WindowProblem
    space : ParameterSpace
    prior_z : array (9,)
        Arrival-cost mean z̄ (also the start point and the value of held parameters).
    prior_cov : array (9, 9)
        Arrival-cost covariance P̄ in z.
    free : array (9,), bool
        Parameters the fit may move.
    loss, f_scale : str, float
        Robust loss ρ and its soft threshold c (in residual scales).
    prior_weight : float
        w of the arrival cost.
    max_nfev : int
        Residual evaluations allowed.
    broyden : int
        Broyden rank-one updates between finite-difference Jacobians (0: always finite
        differences).
    adaptive_scales : bool
        Re-estimate each output's residual scale at the start point
        (:meth:`WindowProblem.rescaled`) before fitting.
    determined_sd_ratio : float
        Fit only the free parameters the window determines (module Notes); 1 fits them all.
    always_fit : array (9,) or (13,), bool, optional
        Free parameters fitted whether the window determines them or not.
    progress : callable (nfev, max_nfev, cost), optional
        Called after every residual evaluation.

    Returns
    -------
    FitResult
    """
    objective = _WindowObjective(problem, space, prior_z=prior_z, prior_cov=prior_cov,
                                 free=free, loss=loss, f_scale=f_scale,
                                 prior_weight=prior_weight, broyden=broyden,
                                 progress=progress, max_nfev=max_nfev)
    if adaptive_scales:
        objective.rescale()
    if determined_sd_ratio < 1.0 and objective.idx.size and objective.problem.n_residuals:
        objective = objective.restricted_to_determined(determined_sd_ratio,
                                                       always=always_fit)
    problem, idx, x0 = objective.problem, objective.idx, objective.x0
    if idx.size == 0 or problem.n_residuals == 0:
        r0 = objective.residuals(x0) if idx.size else np.zeros(0)
        c0 = 0.5 * float(r0 @ r0)
        return FitResult(theta=space.to_theta(objective.prior_z), cov_z=np.array(prior_cov),
                         free=objective.free, cost=c0, cost_start=c0, nfev=objective.calls,
                         njev=0, n_residuals=problem.n_residuals, success=True,
                         message="nothing to fit")
    r0 = objective.residuals(x0)
    cost0 = 0.5 * float(r0 @ r0)
    res = bounded_least_squares(objective.residuals, objective.jacobian, x0, objective.lo,
                                objective.hi, x_scale=space.prior_sd[idx], max_nfev=max_nfev,
                                ftol=1e-5, xtol=1e-5, gtol=1e-8)
    x = res.x if res.cost <= cost0 else x0
    cov = np.array(prior_cov, float)
    cov[idx, :] = 0.0
    cov[:, idx] = 0.0
    cov[np.ix_(idx, idx)] = _posterior(res.jac, res.fun, objective.a_prior, problem)
    return FitResult(theta=objective.theta_of(x), cov_z=cov, free=objective.free,
                     cost=float(min(res.cost, cost0)), cost_start=cost0, nfev=objective.calls,
                     njev=int(res.njev or 0), n_residuals=problem.n_residuals,
                     success=bool(np.all(np.isfinite(x))), message=str(res.message))


class _WindowObjective:
    """The least-squares problem of :func:`fit_window` in the free coordinates x = z[free]:
    robustified data residuals stacked on the prior rows, and their Jacobian (forward
    differences as one batched rollout, or Broyden updates in between)."""

    def __init__(self, problem: WindowProblem, space: ParameterSpace, *, prior_z: np.ndarray,
                 prior_cov: np.ndarray, free: np.ndarray, loss: str, f_scale: float,
                 prior_weight: float, broyden: int,
                 progress: Callable[[int, int, float], None] | None, max_nfev: int) -> None:
        self.problem, self.space = problem, space
        self.free = np.asarray(free, bool)
        self.idx = idx = np.flatnonzero(self.free)
        self.prior_z = np.asarray(prior_z, float)
        self.lo, self.hi = space.z_lower[idx], space.z_upper[idx]
        span = self.hi - self.lo
        self.x0 = np.clip(self.prior_z[idx], self.lo + 1e-6 * span, self.hi - 1e-6 * span)
        self.prior_cov, self.prior_weight = prior_cov, prior_weight
        self.a_prior = _prior_rows(prior_cov[np.ix_(idx, idx)], prior_weight)
        is_offset = np.arange(space.is_log.size) >= N_PARAMS
        self.fd_step = np.where(space.is_log, FD_STEP_LOG,
                                np.where(is_offset, FD_STEP_OFFSET_WM2, FD_STEP_N))[idx]
        self.loss, self.f_scale = loss, f_scale
        self.broyden = broyden
        self.progress, self.max_nfev = progress, max_nfev
        #: Residual evaluations so far (repeats of the last point are cached, not counted).
        self.calls = 0
        self._last: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        self._jac: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # J, x, r
        self._since_fd = broyden

    def restricted_to_determined(self, ratio: float, *, always: np.ndarray | None = None
                                 ) -> _WindowObjective:
        """The objective over the free parameters that the window determines (module Notes)
        and those in ``always``, with the start point's Jacobian carried over; ``self`` if
        it keeps them all."""
        x0, m = self.x0, self.problem.n_residuals
        out = self.residuals(x0)
        j_data = self.jacobian(x0)[:m]
        # in the residuals' own scales (σ_T, σ_v): the misfit of a start far from the
        # truth is no measure of the noise the data are determined against
        info = _data_information(j_data, None, self.problem)
        prior_sd = self.space.prior_sd[self.idx]
        post = np.linalg.inv(info + np.diag(1.0 / prior_sd ** 2))
        keep = np.sqrt(np.clip(np.diag(post), 0.0, None)) < ratio * prior_sd
        if always is not None:
            keep |= np.asarray(always, bool)[self.idx]
        if keep.all():
            return self
        free = self.free.copy()
        free[self.idx[~keep]] = False
        sub = _WindowObjective(self.problem, self.space, prior_z=self.prior_z,
                               prior_cov=self.prior_cov, free=free, loss=self.loss,
                               f_scale=self.f_scale, prior_weight=self.prior_weight,
                               broyden=self.broyden, progress=self.progress,
                               max_nfev=self.max_nfev)
        sub.calls = self.calls
        if keep.any():  # the start point's residuals and Jacobian columns stay valid
            e, slope = self._last[1], self._last[2]
            prior_rows = sub.a_prior @ (x0[keep] - sub.prior_z[sub.idx])
            sub._last = (x0[keep].copy(), e, slope, np.concatenate([out[:m], prior_rows]))
            sub._jac = (j_data[:, keep], x0[keep].copy(), out[:m].copy())
            sub._since_fd = 0
        return sub

    def theta_of(self, x: np.ndarray) -> np.ndarray:
        z = self.prior_z.copy()
        z[self.idx] = x
        return self.space.to_theta(z)

    def rescale(self) -> None:
        """Each output's residual scale re-estimated at the start point."""
        if self.problem.n_residuals:
            start = self.problem.predict(self.theta_of(self.x0)[None])[0]
            self.problem = self.problem.rescaled(start)

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Robustified data residuals, then the prior rows."""
        if self._last is not None and np.array_equal(self._last[0], x):
            return self._last[3]
        e = self.problem.residuals(self.theta_of(x))
        r, slope = robustify(e, self.loss, self.f_scale)
        out = np.concatenate([r, self.a_prior @ (x - self.prior_z[self.idx])])
        self._last = (x.copy(), e, slope, out)
        self.calls += 1
        if self.progress is not None:
            self.progress(self.calls, self.max_nfev, 0.5 * float(out @ out))
        return out

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        out = self.residuals(x)
        m = self.problem.n_residuals
        if self._jac is not None and np.array_equal(self._jac[1], x):
            return np.vstack([self._jac[0], self.a_prior])  # the same point: the same J
        if self._jac is not None and self._since_fd < self.broyden:
            # Broyden rank-one update of the data block (robustified residuals)
            prev, x_prev, r_prev = self._jac
            step_x = x - x_prev
            ss = float(step_x @ step_x)
            if ss > 0.0:
                j_data = prev + np.outer(out[:m] - r_prev - prev @ step_x, step_x) / ss
                self._jac = (j_data, x.copy(), out[:m].copy())
                self._since_fd += 1
                return np.vstack([j_data, self.a_prior])
        j_data = self._finite_differences(x)
        self._jac = (j_data, x.copy(), out[:m].copy())
        self._since_fd = 0
        return np.vstack([j_data, self.a_prior])

    def _finite_differences(self, x: np.ndarray) -> np.ndarray:
        """Forward differences (backward at an upper bound), all perturbed θ as extra batch
        rows of one rollout."""
        assert self._last is not None  # residuals(x) was just evaluated
        _, e, slope, _ = self._last
        step = np.where(x + self.fd_step <= self.hi, self.fd_step, -self.fd_step)
        rows = []
        for j in range(len(self.idx)):
            xj = x.copy()
            xj[j] += step[j]
            rows.append(self.theta_of(xj))
        pert = self.problem.residuals_of(self.problem.predict(np.array(rows),
                                                              near=self.theta_of(x)))
        return ((pert - e[None, :]) / step[:, None]).T * slope[:, None]


def _data_information(j_data: np.ndarray, residual: np.ndarray | None,
                      problem: WindowProblem) -> np.ndarray:
    """JᵀJ/(s² m_r): the window's information on the free z (see module Notes); s = 1
    without ``residual`` (the residuals' configured scales)."""
    m = problem.n_residuals
    scale = (max(0.05, 1.4826 * float(np.median(np.abs(residual[:m]))))
             if m and residual is not None else 1.0)
    lead = problem.mask.any(axis=-1).sum(axis=1)
    m_r = float(np.mean(lead[lead > 0])) if np.any(lead > 0) else 1.0
    return j_data.T @ j_data / (scale * scale * m_r)


def _posterior(jac: np.ndarray, residual: np.ndarray, a_prior: np.ndarray,
               problem: WindowProblem) -> np.ndarray:
    """Covariance of the free z from the final Jacobian and residuals (see module Notes)."""
    j_data = np.asarray(jac)[:problem.n_residuals]
    if j_data.shape[1] == 0:
        return np.zeros((0, 0))
    info = _data_information(j_data, residual, problem) + a_prior.T @ a_prior
    vals, vecs = np.linalg.eigh(0.5 * (info + info.T))
    vals = np.clip(vals, 1e-12 * max(float(vals.max()), 1e-12), None)
    cov = (vecs / vals) @ vecs.T
    return 0.5 * (cov + cov.T)


#: The airflow parameters f, c, n (the first stage of :func:`fit_staged`).
FLOW_PARAMETERS = (Param.F, Param.C, Param.N)
TEMPERATURES = OUTPUTS[:5]  # x1..x5


def fit_staged(problem: WindowProblem, space: ParameterSpace, *, prior_z: np.ndarray,
               prior_cov: np.ndarray, free: np.ndarray, max_nfev: int, rounds: int = 1,
               **options) -> FitResult:
    """Flow parameters from the cavity speed, the rest from the temperatures.

    Each round: stage 1 fits the free f, c, n to the |v| residuals alone (every other
    parameter held at its current value); stage 2 fits the free heat-transfer
    coefficients and offsets to the x1…x5 residuals alone, with f, c, n held at stage
    1's estimate. Both stages keep the arrival cost of the prior (``prior_z``,
    ``prior_cov``). ``rounds`` > 1 alternates the stages towards their common solution,
    where each block is the least-squares estimate from its own measurements given the
    other (needed when the start is far off, e.g. an off-line fit from the defaults).
    Each stage is a :func:`fit_window` with ``max_nfev`` evaluations and ``options``.

    Why: in one joint fit the airflow parameters also absorb the model-form error of the
    temperatures (the mid-height cavity-air sensor, the solar loads by day). On the truth
    plant the exponent n then ran to its bound of 1 and c halved every afternoon, and the
    speed the model predicted in the exhaust regime was three times worse on-line than
    with the off-line fit. The anemometer measures the flow; the temperatures measure the
    heat transfer. Without speed residuals in the window this is the joint fit.

    Returns
    -------
    FitResult
        The last stage's θ and covariance (each block's posterior), with the evaluation
        counts of all stages and the costs of the last round.
    """
    free = np.asarray(free, bool)
    flow = np.zeros_like(free)
    flow[list(FLOW_PARAMETERS)] = True
    speed = problem.only(("v",))
    if not (free & flow).any() or speed.n_residuals == 0:
        return fit_window(problem, space, prior_z=prior_z, prior_cov=prior_cov,
                          free=free, max_nfev=max_nfev, **options)
    temperatures = problem.only(TEMPERATURES)
    prior_z = np.asarray(prior_z, float)
    start = prior_z.copy()
    nfev = njev = 0
    cov_flow = cov_rest = None
    for _ in range(max(rounds, 1)):
        first = _block(speed, space, start, prior_z, prior_cov, free & flow, max_nfev,
                       options)
        start = space.to_z(first.theta)
        second = _block(temperatures, space, start, prior_z, prior_cov, free & ~flow,
                        max_nfev, options)
        start = space.to_z(second.theta)
        nfev, njev = nfev + first.nfev + second.nfev, njev + first.njev + second.njev
        cov_flow, cov_rest = first.cov_z, second.cov_z
    assert cov_flow is not None and cov_rest is not None
    cov = np.array(cov_rest)
    fi = np.flatnonzero(free & flow)
    cov[fi, :] = 0.0
    cov[:, fi] = 0.0
    cov[np.ix_(fi, fi)] = cov_flow[np.ix_(fi, fi)]
    return FitResult(
        theta=space.to_theta(start), cov_z=cov, free=first.free | second.free,
        cost=first.cost + second.cost, cost_start=first.cost_start + second.cost_start,
        nfev=nfev, njev=njev, n_residuals=first.n_residuals + second.n_residuals,
        success=first.success and second.success,
        message=f"speed: {first.message}; temperatures: {second.message}")


def _block(problem: WindowProblem, space: ParameterSpace, start: np.ndarray,
           prior_z: np.ndarray, prior_cov: np.ndarray, free: np.ndarray, max_nfev: int,
           options: dict) -> FitResult:
    """Fit the ``free`` block from ``start`` (the other parameters held there), keeping the
    arrival cost of ``prior_z`` on the block."""
    # fit_window starts the free block at its prior mean and holds the rest there
    held = np.where(free, prior_z, start)
    return fit_window(problem, space, prior_z=held, prior_cov=prior_cov, free=free,
                      max_nfev=max_nfev, **options)
