"""The objective of Eq. 3 over a moving window: multi-step prediction residuals.

For a window of steps a … z − 1 (rows a … z) and parameters θ:

    S(θ) = Σ_{s ∈ starts} Σ_{i=1}^{H} Σ_{o} λ^{(t_z − t_{s+i})/1 h} ρ( e_{s,i,o}² )
    e_{s,i,o} = (ψ_o(x̂_s, u_{s…s+i−1}; θ)_i − Y_{o,s+i}) / σ_o

ψ is the model rolled out i steps from the observer state x̂_s with the recorded controls
and weather; o runs over the measured outputs x1…x5 (σ_T) and the cavity speed |v|
(σ_v, docs/model.md#cavity-velocity: the model's |Q_cav|/(D·W) against the probe); λ is the
forgetting factor per hour of age (the paper's λ^{z−k}); ρ is the robust loss of the least-squares
solver. Missing, flagged and out-of-window targets are left out.

Why multi-step residuals from measured states: the controller predicts 15 steps ahead
from the measured state every cycle, so that error is what the fit should minimise. A
one-step residual mostly sees the fast cavity-air modes (τ of seconds, already pinned by
the measurements) and hardly the glass time constants; an open-loop simulation over the
whole window lets an initial-state or disturbance error accumulate for hours and bends
the parameters to absorb it. Rollouts of H steps starting every ``stride`` steps weight
all lead times 1 … H, each from a measured start (multiple shooting without continuity
constraints).

Every rollout of a residual evaluation, and of a finite-difference Jacobian (the perturbed
θ as extra batch rows), is ONE batched call of :meth:`LumpedModel.rollout`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from dsfd.estimation.observer import spike_mask
from dsfd.estimation.params import N_PARAMS, full_vector, with_offsets
from dsfd.estimation.stepdata import StepData
from dsfd.physics.coupling import StepInputs
from dsfd.physics.model import LumpedModel

OUTPUTS = ("x1", "x2", "x3", "x4", "x5", "v")
#: Tolerance of the thermal–airflow fixed point in the fit's rollouts [K]: a hundredth of
#: the output change of the finite-difference step (dsfd.estimation.fit.FD_STEP), far
#: below the sensors' resolution, and about half the coupling iterations of the default.
COUPLING_TOL_K = 1e-4
#: Single-θ rollouts kept as warm starts (the fit's latest accepted and trial points).
WARM_KEPT = 4
N_OUT = len(OUTPUTS)


@dataclass(frozen=True, eq=False)
class WindowProblem:
    """Prepared residual of one window: starts, targets, weights and gathered inputs.

    Build it with :func:`window_problem`; evaluate with :meth:`predict` and
    :meth:`residuals`.

    Attributes
    ----------
    model : LumpedModel
    x_start : ndarray (S, 6), [K]
        Observer states the rollouts start from.
    regime, or_ : ndarray (S, H)
        Controls of each rollout step.
    inputs : StepInputs
        Inputs of each rollout step, fields (S, H, ...).
    target : ndarray (S, H, 6)
        Measured outputs at each lead time (x1..x5 [K], |v| [m/s]).
    weight : ndarray (S, H, 6)
        √λ^{age} / σ_o where the target counts, 0 elsewhere.
    mask : ndarray (S, H, 6), bool
        Residuals that enter the objective.
    regimes : ndarray
        Commanded regimes of the steps the residual covers.
    horizon : int
        Rollout length H [steps].
    scale : ndarray (6,)
        Residual scale σ_o of each output (x1..x5 [K], |v| [m/s]).
    """

    model: LumpedModel
    x_start: np.ndarray
    regime: np.ndarray
    or_: np.ndarray
    inputs: StepInputs
    target: np.ndarray
    weight: np.ndarray
    mask: np.ndarray
    regimes: np.ndarray
    horizon: int
    scale: np.ndarray
    #: Cavity temperatures and coupling slopes (S, H) of the latest single-θ rollouts, by
    #: the θ's bytes: the warm start of :meth:`predict`'s ``near`` (shared by the copies
    #: :meth:`only` and :meth:`rescaled` make, whose rollouts are the same).
    warm: dict[bytes, tuple[np.ndarray, np.ndarray]] = dataclasses.field(
        default_factory=dict, repr=False)

    @property
    def n_starts(self) -> int:
        return int(self.x_start.shape[0])

    @property
    def n_residuals(self) -> int:
        return int(self.mask.sum())

    @property
    def measured(self) -> tuple[str, ...]:
        """Outputs with at least one residual in the window."""
        return tuple(name for j, name in enumerate(OUTPUTS) if self.mask[..., j].any())

    def counts(self) -> dict[str, int]:
        """Residuals per output."""
        return {name: int(self.mask[..., j].sum()) for j, name in enumerate(OUTPUTS)}

    def predict(self, theta_rows: np.ndarray, *, near: np.ndarray | None = None) -> np.ndarray:
        """Outputs of every rollout for R parameter vectors in one batched model call.

        Parameters
        ----------
        theta_rows : array (R, 13) or (R, 9)
            Fit vectors ϑ = (θ, q) (:mod:`dsfd.estimation.params`).
        near : array (13,) or (9,), optional
            A fit vector close to every row whose rollouts an earlier single-row call
            computed (a finite-difference Jacobian's base point): its cavity temperatures and
            coupling slopes start every row's coupling. Only the number of fixed-point
            evaluations depends on it, within the coupling tolerance.

        Returns
        -------
        ndarray (R, S, H, 6)
            x1..x5 [K] at lead times 1..H and |v| [m/s] of each step.
        """
        theta_rows = full_vector(np.atleast_2d(theta_rows))
        r, s, h = theta_rows.shape[0], self.n_starts, self.horizon
        tile = lambda a: np.broadcast_to(a, (r, *a.shape)).reshape(r * s, *a.shape[1:])  # noqa: E731
        inputs = StepInputs(*(tile(np.asarray(v)) for v in self.inputs))
        rows = np.repeat(theta_rows, s, axis=0)[:, None, :]
        inputs = with_offsets(inputs, rows[..., N_PARAMS:])
        theta = rows[..., :N_PARAMS]
        if near is not None:
            base = self.warm.get(full_vector(np.atleast_2d(near))[0].tobytes())
        else:  # a single θ (a trial point of the fit): the latest one's rollouts
            base = self.warm[next(reversed(self.warm))] if r == 1 and self.warm else None
        traj = self.model.rollout(tile(self.x_start), tile(self.regime), tile(self.or_),
                                  inputs, theta, coupling_tol_k=COUPLING_TOL_K,
                                  t5_guess=None if base is None else tile(base[0]),
                                  slope_guess=None if base is None else tile(base[1]))
        if r == 1:  # kept newest last (a θ rolled out again moves to the end)
            key = theta_rows[0].tobytes()
            self.warm.pop(key, None)
            if len(self.warm) >= WARM_KEPT:
                self.warm.pop(next(iter(self.warm)))
            self.warm[key] = (traj.x[:, 1:, 4].copy(), np.array(traj.coupling_slope))
        out = np.empty((r * s, h, N_OUT))
        out[..., :5] = traj.readings()
        out[..., 5] = np.abs(traj.v_cav_ms)
        return out.reshape(r, s, h, N_OUT)

    def only(self, outputs: tuple[str, ...]) -> WindowProblem:
        """The same window with residuals of ``outputs`` only (subset of :data:`OUTPUTS`;
        the others masked out)."""
        use = np.array([name in outputs for name in OUTPUTS])
        mask = self.mask & use
        return dataclasses.replace(self, mask=mask, weight=np.where(mask, self.weight, 0.0))

    def residuals_of(self, outputs: np.ndarray) -> np.ndarray:
        """Weighted residual vectors of predicted outputs (R, S, H, 6) → (R, m)."""
        diff = np.where(self.mask, outputs - self.target, 0.0) * self.weight
        return diff[:, self.mask]

    def rescaled(self, outputs: np.ndarray, *, low: float = 0.5,
                 high: float = 3.0) -> WindowProblem:
        """The problem with each output's σ_o re-estimated from predicted ``outputs``.

        σ_o = 1.4826 · median |prediction − measurement| of output o (robust scale, the
        maximum-likelihood weight of an output with unknown error variance), kept within
        [``low``, ``high``] × the configured scale, so every output weighs by its own
        predictability and a badly modelled one (e.g. a mid-height cavity-air sensor)
        cannot bend the parameters of the others.
        """
        diff = np.abs(np.asarray(outputs) - self.target)
        new = self.scale.copy()
        for j in range(N_OUT):
            ok = self.mask[..., j]
            if ok.any():
                robust = 1.4826 * float(np.median(diff[ok, j]))
                new[j] = np.clip(robust, low * self.scale[j], high * self.scale[j])
        return dataclasses.replace(self, weight=self.weight * (self.scale / new), scale=new)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """Weighted residual vector e(θ) of Eq. 3 (length :attr:`n_residuals`)."""
        return self.residuals_of(self.predict(np.asarray(theta)[None]))[0]


def rollout_starts(n_steps: int, valid: np.ndarray, *, stride: int) -> np.ndarray:
    """Start steps s = n − 1, n − 1 − stride, … (aligned on the newest step), valid only."""
    starts = np.arange(n_steps - 1, -1, -stride)[::-1]
    return starts[valid[starts]]


def window_problem(model: LumpedModel, steps: StepData, x_hat: np.ndarray,
                   x_pred: np.ndarray, *, horizon: int, stride: int,
                   forgetting_per_h: float, temperature_scale_k: float,
                   velocity_scale_ms: float, spike_threshold_k: float,
                   start_smoothing: int = 1) -> WindowProblem:
    """Prepare the Eq. 3 residual of a window.

    Parameters
    ----------
    model : LumpedModel
    steps : StepData
        The window (n steps, rows 0 … n; row n is "now", t_z).
    x_hat, x_pred : arrays (n + 1, 6), [K]
        Observer estimates and one-step predictions at the rows of the window.
    horizon, stride : int
        Rollout length H and spacing of the start steps [steps].
    forgetting_per_h : float
        λ per hour of age of the target sample.
    temperature_scale_k, velocity_scale_ms : float
        Residual scales σ_T [K] and σ_v [m/s].
    spike_threshold_k : float
        Isolated spikes of the measured temperatures are dropped (targets) or replaced by
        the prediction (start states), see :func:`dsfd.estimation.observer.spike_mask`.
    start_smoothing : int
        Samples of the centred smoothing of the measured start states (odd; 1 = raw), see
        :func:`smoothed_starts`.

    Returns
    -------
    WindowProblem
    """
    n = steps.n_steps
    y = np.array(steps.y_k, float)
    spikes = spike_mask(y, spike_threshold_k)
    y[spikes] = np.nan
    starts = rollout_starts(n, steps.valid, stride=stride)
    x_start = np.array(x_hat[starts], float)
    bad_start = spikes[starts]
    x_start[:, :5] = np.where(bad_start, x_pred[starts, :5], x_start[:, :5])
    if start_smoothing > 1:
        x_start[:, :4] = smoothed_starts(steps, y[:, :4], starts, x_start[:, :4],
                                         start_smoothing)

    lead = np.arange(horizon)
    step_idx = starts[:, None] + lead[None, :]                      # (S, H) step of lead i+1
    inside = step_idx < n
    clamped = np.minimum(step_idx, n - 1)
    # a rollout stops counting at the first gap in the record
    ok_step = np.cumprod(steps.valid[clamped] & inside, axis=1).astype(bool)
    row = clamped + 1                                              # target row of lead i+1
    target = np.empty((len(starts), horizon, N_OUT))
    target[..., :5] = y[row]
    target[..., 5] = steps.v_ms[row]
    mask = ok_step[..., None] & np.isfinite(target)
    age_h = (steps.time_s[-1] - steps.time_s[row]) / 3600.0
    lam = np.sqrt(forgetting_per_h ** age_h)
    scale = np.array([temperature_scale_k] * 5 + [velocity_scale_ms])
    weight = np.where(mask, lam[..., None] / scale, 0.0)
    inputs = StepInputs(*(np.asarray(v)[clamped] for v in steps.inputs))
    covered = clamped[ok_step]
    return WindowProblem(model=model, x_start=x_start, regime=steps.regime[clamped],
                         or_=steps.or_[clamped], inputs=inputs,
                         target=np.where(mask, target, 0.0), weight=weight, mask=mask,
                         regimes=steps.regime[covered], horizon=horizon, scale=scale)


def savgol_centre_weights(width: int) -> np.ndarray:
    """Weights of the centre value of a quadratic least-squares fit over ``width`` (odd)
    equally spaced samples (Savitzky & Golay 1964):
    c_k = (3(3m² + 3m − 1) − 15k²) / ((2m + 3)(2m + 1)(2m − 1)), k = −m … m."""
    m = (width - 1) // 2
    k = np.arange(-m, m + 1, dtype=float)
    return (3.0 * (3 * m * m + 3 * m - 1) - 15.0 * k * k) / ((2 * m + 3) * (2 * m + 1)
                                                          * (2 * m - 1))


def smoothed_starts(steps: StepData, y: np.ndarray, starts: np.ndarray, raw: np.ndarray,
                    width: int) -> np.ndarray:
    """Start temperatures [K] smoothed over ``width`` rows centred on each start.

    Why: the fit's rollouts start from measured states. Sensor noise in a start value is
    an error in the regressors (errors-in-variables): the least-squares fit then prefers
    parameters that make the model forget its start quickly (larger couplings of the slow
    nodes), a bias that the on-line arrival cost accumulates update after update until the
    parameter sits on its bound. A centred quadratic fit over 9 samples cuts the noise
    variance of the start to a quarter and keeps the trend of nodes whose time constants
    are many samples long: the panes and the louver (x1…x4). The cavity air x5 is left
    raw: it follows the weather within seconds, so smoothing would blur it more than the
    noise does, and a rollout forgets its start value as fast. The window lies in the
    past, so centring costs nothing.

    A start keeps its ``raw`` value where the smoothing window leaves the record, where a
    sample in it is missing or flagged (NaN in ``y``), or where the commanded regime,
    opening or louver angle changes inside it (a fast transient is not noise).

    Parameters
    ----------
    steps : StepData
        The window (rows 0 … n).
    y : array (n + 1, N), [K]
        Measured temperatures with flagged samples set to NaN.
    starts : array (S,), int
        Start rows.
    raw : array (S, N), [K]
        Unsmoothed start states.
    width : int
        Samples in the smoothing window (odd, ≥ 3).
    """
    m = (width - 1) // 2
    n = steps.n_steps
    out = np.array(raw, float)
    inside = (starts - m >= 0) & (starts + m <= n)
    if not inside.any():
        return out
    s = starts[inside]
    rows = s[:, None] + np.arange(-m, m + 1)[None, :]              # (S', width)
    ctl = rows[:, :-1]                                              # steps inside the window
    steady = np.ones(s.size, bool)
    for series in (steps.regime, steps.or_, steps.phi_rad):
        steady &= np.all(series[ctl] == series[ctl[:, :1]], axis=1)
    steady &= np.all(steps.valid[ctl], axis=1)
    window = y[rows]                                                # (S', width, N)
    smooth = np.einsum("k,skj->sj", savgol_centre_weights(width), window)
    use = steady[:, None] & np.isfinite(smooth)
    out[inside] = np.where(use, smooth, out[inside])
    return out
