"""On-line self-calibration (Eq. 3 over a moving window) and the off-line baseline.

* :class:`OnlineCalibrator` — every ``update_interval_s`` it refits θ on the last
  ``window_h`` hours (forgetting factor λ per hour of age), warm-started from and
  regularised by the previous estimate (arrival cost with random-walk growth, Rao,
  Rawlings & Mayne 2003), with at most ``max_nfev`` residual evaluations so an update
  fits in a controller cycle. f moves only on windows with regimes 1–4 or 9, c and n only
  on windows with 5–8; parameters the panel cannot excite never move.
* :func:`offline_fit` — the same fit run once as a batch over a training period (no
  forgetting, the first prior, ``offline_max_nfev``); its θ is then frozen.

Both are pure: the caller supplies the data (:class:`~dsfd.estimation.stepdata.StepData`)
and the observer states (:func:`~dsfd.estimation.observer.observe`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from dsfd.config.calibration import Calibration
from dsfd.estimation.fit import FitResult, fit_staged, fit_window
from dsfd.estimation.objective import WindowProblem, window_problem
from dsfd.estimation.observer import observe, observer_step
from dsfd.estimation.params import (
    FIT_NAMES,
    I_Q,
    N_PARAMS,
    Param,
    ParameterSpace,
    full_vector,
)
from dsfd.estimation.state import CalibrationState
from dsfd.estimation.stepdata import StepData
from dsfd.physics.airflow import AirflowGeometry, diagonal_path_resistance
from dsfd.physics.model import LumpedModel


@dataclass(frozen=True, eq=False)
class UpdateReport:
    """What one on-line update did.

    Attributes
    ----------
    state : CalibrationState
        State after the update (unchanged when skipped or failed).
    fit : FitResult or None
        None when the update was skipped.
    skipped : str
        Reason the update was skipped ("" if it ran).
    """

    state: CalibrationState
    fit: FitResult | None
    skipped: str = ""


def make_problem(model: LumpedModel, steps: StepData, x_hat: np.ndarray, x_pred: np.ndarray,
                 settings: Calibration, *, forgetting_per_h: float | None = None
                 ) -> WindowProblem:
    """The Eq. 3 residual of a window with the settings' horizon, stride and scales."""
    return window_problem(
        model, steps, x_hat, x_pred, horizon=settings.horizon_steps,
        stride=settings.start_stride_steps,
        forgetting_per_h=settings.forgetting_factor if forgetting_per_h is None
        else forgetting_per_h,
        temperature_scale_k=settings.temperature_scale_k,
        velocity_scale_ms=settings.velocity_scale_ms,
        spike_threshold_k=settings.spike_threshold_k,
        start_smoothing=settings.smoothing_samples(steps.step_s))


def c_following_f(theta_before: np.ndarray, theta_after: np.ndarray, free: np.ndarray,
                  space: ParameterSpace, geom: AirflowGeometry) -> np.ndarray:
    """ϑ after a fit, with an unfitted c moved as f moved (docs/model.md#c-follows-f).

    Parameters
    ----------
    theta_before, theta_after : array (13,)
        The estimate before the fit and after it.
    free : array (13,), bool
        What the fit could move.
    space : ParameterSpace
    geom : AirflowGeometry
        The panel's openings.

    Returns
    -------
    ndarray (13,)
        ``theta_after``, with c ← c·mean_p √(K_p(f_before) / K_p(f_after)) over the diagonal
        paths p present when f was free and c not (clipped into c's bounds).

    Notes
    -----
    A diagonal path is its two dampers and the cavity in series, like the orifice paths
    whose loss f measures (docs/model.md#openings): at one pascal its conductance is
    √(2/(ρ K)), K = K_in + K_out the path's series loss. c's power law stands for that path
    ([ENG] matched at 1 Pa), so a change of f that no diagonal window has told c about
    changes c by the ratio of the two conductances.
    """
    if free[Param.C] or not free[Param.F] or space.fixed[Param.C]:
        return theta_after
    k = diagonal_path_resistance(np.array([theta_before[Param.F], theta_after[Param.F]]), geom)
    present = np.all(np.isfinite(k), axis=0)
    if not present.any():
        return theta_after
    ratio = float(np.mean(np.sqrt(k[0, present] / k[1, present])))
    theta = theta_after.copy()
    theta[Param.C] = np.clip(theta[Param.C] * ratio, space.lower[Param.C],
                             space.upper[Param.C])
    return theta


#: Rounds of the staged fit: an on-line update starts from the last estimate, the off-line
#: fit from the defaults (:func:`dsfd.estimation.fit.fit_staged`).
ONLINE_ROUNDS, OFFLINE_ROUNDS = 1, 3


def _fit(settings: Calibration, rounds: int) -> Callable[..., FitResult]:
    """The window fit the settings ask for: staged (flow from the speed) or joint."""
    return partial(fit_staged, rounds=rounds) if settings.flow_from_velocity else fit_window


def window_start(time_s: np.ndarray, end_row: int, window_h: float) -> int:
    """First row of the window of ``window_h`` hours that ends at ``end_row``."""
    return int(np.searchsorted(time_s, time_s[end_row] - window_h * 3600.0 - 1e-6))


class OnlineCalibrator:
    """Self-calibration of one panel, updated as data arrive (pure: no clock, no files).

    Parameters
    ----------
    model : LumpedModel
        Model of the panel with the data's step.
    settings : Calibration
        Usually ``model.cfg.calibration``.
    state : CalibrationState, optional
        Resumed state (e.g. loaded by :mod:`dsfd.storage.calibration_file`); default the
        first prior.
    """

    def __init__(self, model: LumpedModel, settings: Calibration | None = None, *,
                 state: CalibrationState | None = None) -> None:
        self.model = model
        self.settings = settings or model.cfg.calibration
        self.space = ParameterSpace.from_panel(model.cfg, self.settings)
        self.state = state or CalibrationState.initial(model.cfg.panel.id, self.space)
        #: Low-passed innovations of x1..x4 [K] driving the offset tracking (filter state,
        #: not persisted: it settles within a few smoothing time constants).
        self._innovation = np.zeros(4)

    @property
    def theta(self) -> np.ndarray:
        """Current estimate of the fit vector ϑ̂ = (θ̂, q̂) (copy)."""
        return self.state.theta.copy()

    @property
    def model_theta(self) -> np.ndarray:
        """The model parameters θ̂ (9,) of the current estimate (what the model, the observer
        and the optimiser take as ``theta``)."""
        return full_vector(self.state.theta)[:N_PARAMS].copy()

    @property
    def heat_offsets_wm2(self) -> np.ndarray:
        """The heat-flux offsets q̂ (4,) [W/m2] of the current estimate (the optimiser's
        ``ControlProblem.heat_offsets_wm2``)."""
        return full_vector(self.state.theta)[N_PARAMS:].copy()

    def due(self, now_s: float, data_start_s: float) -> bool:
        """True when an update is due at ``now_s`` [s] with data since ``data_start_s``."""
        if now_s - data_start_s < self.settings.min_window_h * 3600.0 - 1e-6:
            return False
        last = self.state.last_update_s
        return last is None or now_s - last >= self.settings.update_interval_s - 1e-6

    def update(self, window: StepData, x_hat: np.ndarray, x_pred: np.ndarray, *,
               max_nfev: int | None = None) -> UpdateReport:
        """Refit θ on ``window`` (ending now) from the observer states of its rows.

        Parameters
        ----------
        window : StepData
            The last ``window_h`` hours (see :func:`window_start`).
        x_hat, x_pred : arrays (n + 1, 6), [K]
            Observer estimates and one-step predictions at the window rows.
        max_nfev : int, optional
            Override of ``settings.max_nfev``.

        Returns
        -------
        UpdateReport
        """
        st, cfg = self.state, self.settings
        now = float(window.time_s[-1])
        problem = make_problem(self.model, window, x_hat, x_pred, cfg)
        free = self.space.free_in_window(problem.regimes, problem.measured)
        if problem.n_residuals < 3 * max(int(free.sum()), 1):
            return UpdateReport(st, None, f"only {problem.n_residuals} residuals in the window")
        hours = 0.0 if st.last_update_s is None else (now - st.last_update_s) / 3600.0
        prior_cov = self.space.grown_prior(st.cov_z, hours)
        try:
            fit = _fit(cfg, ONLINE_ROUNDS)(
                problem, self.space, prior_z=self.space.to_z(st.theta),
                prior_cov=prior_cov, free=free, loss=cfg.loss, f_scale=cfg.f_scale,
                prior_weight=cfg.prior_weight, max_nfev=max_nfev or cfg.max_nfev,
                broyden=cfg.broyden_updates, adaptive_scales=cfg.adaptive_scales,
                determined_sd_ratio=cfg.identifiability_sd_ratio,
                always_fit=np.isin(FIT_NAMES, cfg.identifiability_always_fit))
        except (np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
            self.state = dataclasses.replace(st, failed_updates=st.failed_updates + 1)
            return UpdateReport(self.state, None, f"fit failed: {exc}")
        if not fit.success or not np.all(np.isfinite(fit.theta)):
            self.state = dataclasses.replace(st, failed_updates=st.failed_updates + 1)
            return UpdateReport(self.state, fit, f"fit failed: {fit.message}")
        theta = np.where(fit.free, self.space.clip(fit.theta), st.theta)
        if cfg.c_follows_f:
            theta = c_following_f(st.theta, theta, fit.free, self.space, self.model.geom)
        self.state = dataclasses.replace(
            st, theta=theta,
            cov_z=fit.cov_z, last_update_s=now,
            updates=st.updates + 1, residuals_last=fit.n_residuals, cost_last=fit.cost,
            free_last=tuple(k for k, f in zip(FIT_NAMES, fit.free, strict=True) if f))
        return UpdateReport(self.state, fit)


    def track(self, steps: StepData, k: int, x_hat: np.ndarray, y_next: np.ndarray) -> None:
        """Recursive update of the heat-flux offsets from the innovation of step k.

        Parameters
        ----------
        steps : StepData
        k : int
            Step just completed (row k → k + 1).
        x_hat : array (6,), [K]
            Observer estimate at row k (the start of the step).
        y_next : array (5,), [K]
            Measurements at row k + 1 (NaN where missing).

        Notes
        -----
        With e = y_{k+1} − x̂_{k+1|k} on the measured nodes, ē its low-pass (time constant
        τ_e = ``innovation_smoothing_s`` of each node: white sensor noise averages out, a
        persistent model error passes) and S = ∂x_{k+1}/∂q (finite differences, all rows in
        one batched model step),

            ē ← ē + a (clip(e, ±spike_threshold) − ē),   a = 1 − exp(−T/τ_e)
            q ← q + L S⁺ ē,                               L = 1 − exp(−T/τ_q)

        — the input-disturbance observer of offset-free estimation (Pannocchia & Rawlings
        2003) with time constant τ_q = ``offset_tracking_s``; the next window fit re-estimates
        q with all other parameters. No-op when offsets are off or τ_q = 0.
        """
        cfg, sp = self.settings, self.space
        if cfg.offset_tracking_s <= 0 or not steps.valid[k]:
            return
        meas = np.isfinite(np.asarray(y_next, float)[:4])
        idx = np.array([i for i, ok in zip(I_Q, meas, strict=True) if ok and not sp.fixed[i]],
                       int)
        if idx.size == 0:
            return
        delta = 10.0  # W/m2
        rows = np.repeat(self.state.theta[None], idx.size + 1, axis=0)
        rows[np.arange(1, idx.size + 1), idx] += delta
        x_next, _, _ = observer_step(self.model, steps, k, np.asarray(x_hat)[None], rows,
                                     np.full(5, np.nan))
        nodes = idx - N_PARAMS
        sens = (x_next[1:, nodes] - x_next[0, nodes]).T / delta      # ∂x_node/∂q [K m2/W]
        e_all = np.zeros(4)
        e_all[nodes] = np.clip(y_next[nodes] - x_next[0, nodes], -cfg.spike_threshold_k,
                               cfg.spike_threshold_k)
        tau = np.asarray(cfg.innovation_smoothing_s, float)
        a = np.where(tau > 0, -np.expm1(-steps.step_s / np.where(tau > 0, tau, 1.0)), 1.0)
        self._innovation = np.where(meas, self._innovation + a * (e_all - self._innovation),
                                    self._innovation)
        dq = np.linalg.lstsq(sens, self._innovation[nodes], rcond=1e-6)[0]
        gain = 1.0 - np.exp(-steps.step_s / cfg.offset_tracking_s)
        theta = self.state.theta.copy()
        theta[idx] = np.clip(theta[idx] + gain * dq, sp.lower[idx], sp.upper[idx])
        self.state = dataclasses.replace(self.state, theta=theta)


def offline_fit(model: LumpedModel, steps: StepData, settings: Calibration | None = None, *,
                max_nfev: int | None = None, passes: int = 1,
                progress: Callable[[int, int, float], None] | None = None,
                ) -> tuple[CalibrationState, FitResult]:
    """The off-line baseline: one batch fit of θ over a training record, then frozen.

    The observer runs with the defaults (estimates of unmeasured states), the residual
    covers the whole record without forgetting (λ = 1) and the prior is the first prior.
    With ``passes`` > 1 the observer is re-run with the new θ and the fit repeated.

    Parameters
    ----------
    model : LumpedModel
    steps : StepData
        Training record.
    settings : Calibration, optional
    max_nfev : int, optional
        Default ``settings.offline_max_nfev``.
    passes : int
    progress : callable (nfev, max_nfev, cost), optional

    Returns
    -------
    state : CalibrationState
        θ, covariance and counts of the fit (``last_update_s`` = end of the record).
    fit : FitResult
    """
    settings = settings or model.cfg.calibration
    space = ParameterSpace.from_panel(model.cfg, settings)
    state = CalibrationState.initial(model.cfg.panel.id, space)
    mean, cov = space.first_prior()
    theta = space.default.copy()
    fit = None
    for _ in range(max(passes, 1)):
        track = observe(model, steps, theta[None])
        problem = make_problem(model, steps, track.x_hat[0], track.x_pred[0], settings,
                               forgetting_per_h=1.0)
        free = space.free_in_window(problem.regimes, problem.measured)
        fit = _fit(settings, OFFLINE_ROUNDS)(
            problem, space, prior_z=mean, prior_cov=cov, free=free, loss=settings.loss,
            f_scale=settings.f_scale, prior_weight=settings.prior_weight,
            max_nfev=max_nfev or settings.offline_max_nfev,
            adaptive_scales=settings.adaptive_scales, progress=progress)
        theta = np.where(fit.free, space.clip(fit.theta), space.default)
        if settings.c_follows_f:
            theta = c_following_f(space.default, theta, fit.free, space, model.geom)
    assert fit is not None
    state = dataclasses.replace(
        state, theta=theta, cov_z=fit.cov_z, last_update_s=float(steps.time_s[-1]),
        updates=1, residuals_last=fit.n_residuals, cost_last=fit.cost,
        free_last=tuple(k for k, f in zip(FIT_NAMES, fit.free, strict=True) if f))
    return state, fit
