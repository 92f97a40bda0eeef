"""Replay a measured record and score the models the way the paper's Tables 1 and 2 do.

Models compared at every row k (step start) of the record:

* ``online`` — self-calibrating: an :class:`~dsfd.estimation.calibration.OnlineCalibrator`
  updated as the replay goes, using only rows ≤ k (θ_k is the estimate at time t_k);
* ``offline`` — θ frozen from an off-line fit on other data (if given);
* ``uncalibrated`` — the panel defaults;
* ``persistence`` — the last measurement held.

Every model predicts from its own observer state x̂_k (measured x1..x5, x6 observer,
missing values from its own one-step prediction), rolled out with the recorded controls
and weather. Scores: the mean absolute difference between predicted and measured x1..x5
at each horizon h (steps) and their mean over the states measured (Table 2); the mean
absolute difference of the cavity speed |v| one step ahead per commanded airflow regime
(Table 1). All models are scored on the same samples. Rows before ``warmup_h`` hours are
replayed but not scored.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.estimation.calibration import OnlineCalibrator, window_start
from dsfd.estimation.observer import initial_state, observer_step
from dsfd.estimation.params import FIT_NAMES, N_FIT, N_PARAMS, full_vector, with_offsets
from dsfd.estimation.stepdata import StepData, model_config
from dsfd.physics.constants import T_ZERO
from dsfd.physics.coupling import StepInputs
from dsfd.physics.model import LumpedModel

STATES = ("x1", "x2", "x3", "x4", "x5")
#: Rollouts per batched model call when scoring (bounds the memory).
CHUNK = 2000


def _observer_replay(model: LumpedModel, steps: StepData, thetas: np.ndarray,
                     calibrator: OnlineCalibrator | None,
                     progress: Callable[[int, int, int], None] | None):
    """Sequential observer for B models; row 0 of ``thetas`` is replaced by the on-line θ."""
    n = steps.n_steps
    nb = thetas.shape[0]
    theta_k = np.empty((nb, n, N_FIT))
    x_hat = np.empty((nb, n + 1, 6))
    th = full_vector(thetas).copy()
    x_hat[:, 0] = initial_state(model, steps, 0, th)
    x_pred_online = x_hat[0].copy()
    updates = 0
    for k in range(n):
        if calibrator is not None and calibrator.due(steps.time_s[k], steps.time_s[0]):
            s = window_start(steps.time_s, k, calibrator.settings.window_h)
            if k - s >= 2:
                report = calibrator.update(steps.window(s, k), x_hat[0, s:k + 1],
                                           x_pred_online[s:k + 1])
                updates += report.fit is not None and not report.skipped
            th[0] = calibrator.theta
        theta_k[:, k] = th
        x_hat[:, k + 1], x_pred, _ = observer_step(model, steps, k, x_hat[:, k], th,
                                                   steps.y_k[k + 1])
        x_pred_online[k + 1] = x_pred[0]
        if calibrator is not None:
            calibrator.track(steps, k, x_hat[0, k], steps.y_k[k + 1])
            th[0] = calibrator.theta
        if progress is not None:
            progress(k + 1, n, updates)
    return theta_k, x_hat, updates


def _rollouts(model: LumpedModel, steps: StepData, starts: np.ndarray, x0: np.ndarray,
              theta: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
    """x (S, H+1, 6) and |v| (S, H) of rollouts from rows ``starts``, in chunks."""
    n = steps.n_steps
    idx = np.minimum(starts[:, None] + np.arange(horizon)[None, :], n - 1)
    xs = np.empty((len(starts), horizon + 1, 6))
    vs = np.empty((len(starts), horizon))
    for a in range(0, len(starts), CHUNK):
        b = slice(a, a + CHUNK)
        inp = StepInputs(*(np.asarray(v)[idx[b]] for v in steps.inputs))
        inp = with_offsets(inp, theta[b][:, None, N_PARAMS:])
        tr = model.rollout(x0[b], steps.regime[idx[b]], steps.or_[idx[b]], inp,
                           theta[b][:, None, :N_PARAMS])
        xs[b], vs[b] = tr.x, np.abs(tr.v_cav_ms)
        xs[b, 1:, :5] = tr.readings()  # scored against the sensors: the probe's x5
    return xs, vs


def _held(y: np.ndarray) -> np.ndarray:
    """Last finite value at or before each row (NaN before the first)."""
    idx = np.where(np.isfinite(y), np.arange(y.shape[0])[:, None], -1)
    idx = np.maximum.accumulate(idx, axis=0)
    out = np.take_along_axis(y, np.maximum(idx, 0), axis=0)
    return np.where(idx >= 0, out, np.nan)


def paired_difference(err_a: np.ndarray, err_b: np.ndarray, batch: int) -> tuple[float, float]:
    """Mean of |e_a| − |e_b| and its standard error by batch means [K, K].

    Parameters
    ----------
    err_a, err_b : array (S,), [K]
        Absolute errors of two models on the same samples, in time order.
    batch : int
        Consecutive samples per batch; longer than the errors' correlation (a rollout's
        errors at neighbouring starts share most of their path).

    Returns
    -------
    diff, se : float
        Negative ``diff``: model a is better. ``se`` is NaN with fewer than two batches.

    Notes
    -----
    Batch means: the series is cut into k batches of ``batch`` samples (the remainder
    dropped for the standard error); their means are treated as independent, so
    se = sd(batch means)/√k (Law & Kelton, *Simulation Modeling and Analysis*, batch-means
    method). A |diff| below about 2 se means the two models cannot be ranked on this record.
    """
    d = np.asarray(err_a, float) - np.asarray(err_b, float)
    if d.size == 0:
        return float("nan"), float("nan")
    k = d.size // batch
    if k < 2:
        return float(np.mean(d)), float("nan")
    means = d[:k * batch].reshape(k, batch).mean(axis=1)
    return float(np.mean(d)), float(np.std(means, ddof=1) / np.sqrt(k))


@dataclass(frozen=True)
class HorizonScores:
    """Table 2 at one lead time: mean absolute differences of x1..x5 [K] (= degC).

    Attributes
    ----------
    mae_c : dict model → dict state → float
        Per state measured in the record (states without a finite target left out).
    mean_mae_c : dict model → float
        Mean over the states in ``mae_c[model]``.
    paired : dict model → dict state → (diff, se)
        Self-calibrating minus that model, the paired difference of the absolute errors and
        its standard error (:func:`paired_difference`); only where the standard error is
        finite. Empty without the self-calibrating model.
    """

    mae_c: dict[str, dict[str, float]]
    mean_mae_c: dict[str, float]
    paired: dict[str, dict[str, tuple[float, float]]]


@dataclass(frozen=True)
class RegimeVelocity:
    """Table 1 for one commanded regime: the cavity speed |v| one step ahead [cm/s].

    Attributes
    ----------
    measured_mean_cms : float
        Mean reading of the anemometer.
    samples : int
    mae_cms : dict model → float
        Mean absolute difference against the readings.
    sensor_mae_cms : float or None
        The anemometer against the reference speed (what a perfect model would score).
    true_mae_cms : dict model → float, or None
        Mean absolute difference against the reference speed (None without a reference).
    """

    measured_mean_cms: float
    samples: int
    mae_cms: dict[str, float]
    sensor_mae_cms: float | None = None
    true_mae_cms: dict[str, float] | None = None


@dataclass(frozen=True)
class ReplayScores:
    """What :func:`replay_scores` measured; :meth:`flat` is the flat form the JSON files hold.

    Attributes
    ----------
    steps, scored_starts, online_updates : int
    step_s : float, [s]
    models : tuple of str
        The models compared, in order (``online``, ``offline``, ``uncalibrated``,
        ``persistence`` as present); empty when no row was scored.
    horizons : dict lead time [steps] → HorizonScores
    measured_mean_c : dict state → float, [degC]
        Mean measured temperature over the scored rows.
    velocity : dict regime → RegimeVelocity
    final_theta : dict model → ndarray (13,)
        The last fit vector of ``online`` and ``offline``.
    one_step_time_s : ndarray (S,), [s]
        Time of the row each one-step prediction is for (a scored start's next row).
    one_step_error_k : dict state → ndarray (S,), [K]
        The first model's (``online`` when run) one-step prediction errors, measured minus
        predicted, NaN where the state was not measured: what the daemon's residual
        detector watches (docs/model.md#diagnostics-residuals).
    online_offsets_wm2 : dict offset name → ndarray (n,), [W/m²]
        The first model's heat-flux offsets in force over each step (from row k, at
        ``steps.time_s[:-1]``): what the night offsets watch
        (docs/model.md#diagnostics-night-offsets).
    """

    steps: int
    step_s: float
    scored_starts: int
    online_updates: int
    models: tuple[str, ...] = ()
    horizons: dict[int, HorizonScores] = field(default_factory=dict)
    measured_mean_c: dict[str, float] = field(default_factory=dict)
    velocity: dict[int, RegimeVelocity] = field(default_factory=dict)
    final_theta: dict[str, np.ndarray] = field(default_factory=dict)
    one_step_time_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    one_step_error_k: dict[str, np.ndarray] = field(default_factory=dict)
    online_offsets_wm2: dict[str, np.ndarray] = field(default_factory=dict)

    def mae_c(self, model: str, horizon: int, state: str) -> float | None:
        """Table 2 cell; ``state`` ``"mean"`` for the mean over the states (None if absent)."""
        h = self.horizons.get(horizon)
        if h is None:
            return None
        if state == "mean":
            return h.mean_mae_c.get(model)
        return h.mae_c.get(model, {}).get(state)

    def scored_models(self) -> tuple[str, ...]:
        """The models with at least one score."""
        return tuple(m for m in self.models
                     if any(h.mae_c.get(m) for h in self.horizons.values())
                     or self.velocity or m in self.final_theta)

    def flat(self) -> dict[str, float]:
        """Flat keys, units in the names: ``<model>.h<N>.<state>_mae_c``,
        ``<model>.h<N>.mean_mae_c``, ``online_vs_<model>.h<N>.<state>_mae_diff_c`` and
        ``..._mae_diff_se_c``, ``measured.<state>_mean_c``,
        ``measured.velocity_mean_cms.regime_<r>``, ``measured.velocity_samples.regime_<r>``,
        ``sensor.velocity_mae_cms.regime_<r>``, ``<model>.velocity_mae_cms.regime_<r>``,
        ``<model>.velocity_true_mae_cms.regime_<r>``, ``<model>.theta.<name>``, the counts and
        the step."""
        out: dict[str, float] = {"steps": float(self.steps), "step_s": self.step_s,
                                 "scored_starts": float(self.scored_starts),
                                 "online_updates": float(self.online_updates)}
        for h, hs in self.horizons.items():
            for m in self.models:
                for s, mae in hs.mae_c.get(m, {}).items():
                    out[f"{m}.h{h}.{s}_mae_c"] = mae
                if m in hs.mean_mae_c:
                    out[f"{m}.h{h}.mean_mae_c"] = hs.mean_mae_c[m]
            for m, by_state in hs.paired.items():
                for s, (diff, se) in by_state.items():
                    out[f"online_vs_{m}.h{h}.{s}_mae_diff_c"] = diff
                    out[f"online_vs_{m}.h{h}.{s}_mae_diff_se_c"] = se
        for s, mean in self.measured_mean_c.items():
            out[f"measured.{s}_mean_c"] = mean
        for r, v in self.velocity.items():
            out[f"measured.velocity_mean_cms.regime_{r}"] = v.measured_mean_cms
            out[f"measured.velocity_samples.regime_{r}"] = float(v.samples)
            if v.sensor_mae_cms is not None:
                out[f"sensor.velocity_mae_cms.regime_{r}"] = v.sensor_mae_cms
            for m in self.models:
                out[f"{m}.velocity_mae_cms.regime_{r}"] = v.mae_cms[m]
                if v.true_mae_cms is not None:
                    out[f"{m}.velocity_true_mae_cms.regime_{r}"] = v.true_mae_cms[m]
        for m, theta in self.final_theta.items():
            for k, value in zip(FIT_NAMES, theta, strict=True):
                out[f"{m}.theta.{k}"] = float(value)
        return out


def replay_scores(cfg: PanelConfig, steps: StepData, *, offline_theta: np.ndarray | None = None,
                  horizons: tuple[int, ...] = (1, 15), warmup_h: float = 0.0,
                  online: bool = True, reference_v_ms: np.ndarray | None = None,
                  progress: Callable[[int, int, int], None] | None = None) -> ReplayScores:
    """Scores of the models on a measured record (module docstring).

    Parameters
    ----------
    cfg : PanelConfig
        The panel; its model step is replaced by the data's sampling interval.
    steps : StepData
        The record (:func:`dsfd.estimation.stepdata.step_data`).
    offline_theta : array (13,) or (9,), optional
        Frozen fit vector of the off-line model; omitted from the scores if None.
    horizons : tuple of int
        Lead times scored [steps].
    warmup_h : float
        Hours at the start that are replayed but not scored.
    online : bool
        Run the self-calibrating model (the slow part).
    reference_v_ms : array (n + 1,), optional, [m/s]
        The true cavity speed |v| at the probe at each row (a simulation's ``truth_v_cav_ms``).
        Adds the velocity scores against it and the anemometer's own error against it (the
        score a perfect model would get against the readings).
    progress : callable (row, rows, updates), optional

    Returns
    -------
    ReplayScores
    """
    model = LumpedModel(model_config(cfg, steps.step_s))
    names = (["online"] if online else []) + (["offline"] if offline_theta is not None else [])
    names.append("uncalibrated")
    default = model.default_theta()
    thetas = np.array([full_vector(offline_theta) if m == "offline" else full_vector(default)
                       for m in names], float)
    calibrator = OnlineCalibrator(model) if online else None
    theta_k, x_hat, updates = _observer_replay(model, steps, thetas, calibrator, progress)
    h_max = max(horizons)
    starts = _scored_starts(steps, h_max, warmup_h)
    if len(starts) == 0:
        return ReplayScores(steps.n_steps, steps.step_s, 0, int(updates))
    preds = {m: _rollouts(model, steps, starts, x_hat[i, starts], theta_k[i, starts], h_max)
             for i, m in enumerate(names)}
    models = (*names, "persistence")
    present = [j for j, s in enumerate(STATES) if s in steps.present]
    batch = max(4 * h_max, round(3600.0 / steps.step_s))
    return ReplayScores(
        steps.n_steps, steps.step_s, len(starts), int(updates), models=models,
        horizons={h: _horizon_scores(steps, starts, h, preds, present, batch) for h in horizons},
        measured_mean_c={STATES[j]: float(np.nanmean(steps.y_k[starts, j]) - T_ZERO)
                         for j in present},
        velocity=(_velocity_scores(steps, starts, preds, reference_v_ms)
                  if "v" in steps.present else {}),
        final_theta={m: theta_k[i, -1] for i, m in enumerate(names)
                     if m in ("online", "offline")},
        one_step_time_s=steps.time_s[starts + 1],
        one_step_error_k={STATES[j]: steps.y_k[starts + 1, j] - preds[names[0]][0][:, 1, j]
                          for j in present},
        online_offsets_wm2={name: theta_k[0, :, N_PARAMS + i]
                            for i, name in enumerate(FIT_NAMES[N_PARAMS:])})


def _scored_starts(steps: StepData, h_max: int, warmup_h: float) -> np.ndarray:
    """Rows scored: after the warm-up, with ``h_max`` valid steps ahead inside the record."""
    n = steps.n_steps
    scored = steps.time_s[:-1] >= steps.time_s[0] + warmup_h * 3600.0
    valid_run = np.array([steps.valid[k:k + h_max].all() for k in range(n)])
    return np.flatnonzero(scored & valid_run & (np.arange(n) + h_max <= n))


def _horizon_scores(steps: StepData, starts: np.ndarray, h: int,
                    preds: dict[str, tuple[np.ndarray, np.ndarray]], present: list[int],
                    batch: int) -> HorizonScores:
    """Table 2 at lead time ``h``: every model, and persistence, on the same samples (those
    with a finite target and a finite last reading)."""
    target = steps.y_k[starts + h]
    held = _held(steps.y_k)[starts]
    common = np.isfinite(target) & np.isfinite(held)
    errs: dict[str, np.ndarray] = {}
    mae_c: dict[str, dict[str, float]] = {}
    mean_mae_c: dict[str, float] = {}
    for m in [*preds, "persistence"]:
        pred = held if m == "persistence" else preds[m][0][:, h, :5]
        err = errs[m] = np.abs(pred - target)
        maes = mae_c[m] = {STATES[j]: float(np.mean(err[common[:, j], j]))
                           for j in present if common[:, j].any()}
        if maes:
            mean_mae_c[m] = float(np.mean(list(maes.values())))
    paired: dict[str, dict[str, tuple[float, float]]] = {}
    if "online" in errs:
        for m in [x for x in errs if x != "online"]:
            pairs = paired[m] = {}
            for j in present:
                ok = common[:, j]
                diff, se = paired_difference(errs["online"][ok, j], errs[m][ok, j], batch)
                if np.isfinite(se):
                    pairs[STATES[j]] = (diff, se)
    return HorizonScores(mae_c, mean_mae_c, paired)


def _velocity_scores(steps: StepData, starts: np.ndarray,
                     preds: dict[str, tuple[np.ndarray, np.ndarray]],
                     reference_v_ms: np.ndarray | None) -> dict[int, RegimeVelocity]:
    """Table 1: |v| one step ahead per commanded regime, against the readings (and the
    reference speed, if given), on the samples with a reading and a last reading."""
    v_meas = steps.v_ms[starts + 1]
    regime = steps.regime[starts]
    v_held = _held(steps.v_ms[:, None])[:, 0][starts]
    v_true = (None if reference_v_ms is None
              else np.abs(np.asarray(reference_v_ms, float))[starts + 1])
    v_pred = {m: pred[1][:, 0] for m, pred in preds.items()} | {"persistence": v_held}
    ok = np.isfinite(v_meas) & np.isfinite(v_held)
    out: dict[int, RegimeVelocity] = {}
    for r in np.unique(regime[ok]):
        sel = ok & (regime == r)
        out[int(r)] = RegimeVelocity(
            measured_mean_cms=float(np.mean(v_meas[sel]) * 100),
            samples=int(sel.sum()),
            mae_cms={m: float(np.mean(np.abs(v[sel] - v_meas[sel])) * 100)
                     for m, v in v_pred.items()},
            sensor_mae_cms=(None if v_true is None else
                            float(np.nanmean(np.abs(v_meas[sel] - v_true[sel])) * 100)),
            true_mae_cms=(None if v_true is None else
                          {m: float(np.nanmean(np.abs(v[sel] - v_true[sel])) * 100)
                           for m, v in v_pred.items()}))
    return out
