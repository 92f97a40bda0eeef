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


def replay_scores(cfg: PanelConfig, steps: StepData, *, offline_theta: np.ndarray | None = None,
                  horizons: tuple[int, ...] = (1, 15), warmup_h: float = 0.0,
                  online: bool = True, reference_v_ms: np.ndarray | None = None,
                  progress: Callable[[int, int, int], None] | None = None) -> dict[str, float]:
    """Scores of the models on a measured record (flat keys, units in the names).

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
        Adds the velocity scores against it (``<model>.velocity_true_mae_cms.regime_<r>``)
        and the anemometer's own error (``sensor.velocity_mae_cms.regime_<r>``: the score a
        perfect model would get against the readings).
    progress : callable (row, rows, updates), optional

    Returns
    -------
    dict
        ``<model>.h<N>.<state>_mae_c``, ``<model>.h<N>.mean_mae_c``,
        ``<model>.velocity_mae_cms.regime_<r>``, ``measured.velocity_mean_cms.regime_<r>``,
        ``online_vs_<model>.h<N>.<state>_mae_diff_c`` and ``..._mae_diff_se_c`` (the paired
        difference of the absolute errors and its standard error, :func:`paired_difference`),
        ``measured.<state>_mean_c``, ``online.theta.<name>``, counts and the step.
    """
    model = LumpedModel(model_config(cfg, steps.step_s))
    names = (["online"] if online else []) + (["offline"] if offline_theta is not None else [])
    names.append("uncalibrated")
    default = model.default_theta()
    thetas = np.array([full_vector(offline_theta) if m == "offline" else full_vector(default)
                       for m in names], float)
    calibrator = OnlineCalibrator(model) if online else None
    theta_k, x_hat, updates = _observer_replay(model, steps, thetas, calibrator, progress)
    n = steps.n_steps
    h_max = max(horizons)
    scored = steps.time_s[:-1] >= steps.time_s[0] + warmup_h * 3600.0
    valid_run = np.array([steps.valid[k:k + h_max].all() for k in range(n)])
    starts = np.flatnonzero(scored & valid_run & (np.arange(n) + h_max <= n))
    out: dict[str, float] = {"steps": float(n), "step_s": steps.step_s,
                             "scored_starts": float(len(starts)), "online_updates": float(updates)}
    if len(starts) == 0:
        return out
    y = steps.y_k
    held = _held(y)
    preds: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for i, m in enumerate(names):
        preds[m] = _rollouts(model, steps, starts, x_hat[i, starts], theta_k[i, starts], h_max)
    present = [j for j, s in enumerate(STATES) if s in steps.present]
    batch = max(4 * h_max, round(3600.0 / steps.step_s))
    for h in horizons:
        target = y[starts + h]
        common = np.isfinite(target) & np.isfinite(held[starts])
        errs: dict[str, np.ndarray] = {}
        for m in [*names, "persistence"]:
            pred = held[starts] if m == "persistence" else preds[m][0][:, h, :5]
            err = errs[m] = np.abs(pred - target)
            maes = []
            for j in present:
                ok = common[:, j]
                if ok.any():
                    mae = float(np.mean(err[ok, j]))
                    out[f"{m}.h{h}.{STATES[j]}_mae_c"] = mae
                    maes.append(mae)
            if maes:
                out[f"{m}.h{h}.mean_mae_c"] = float(np.mean(maes))
        if "online" in errs:
            for m in [x for x in errs if x != "online"]:
                for j in present:
                    ok = common[:, j]
                    diff, se = paired_difference(errs["online"][ok, j], errs[m][ok, j], batch)
                    if np.isfinite(se):
                        out[f"online_vs_{m}.h{h}.{STATES[j]}_mae_diff_c"] = diff
                        out[f"online_vs_{m}.h{h}.{STATES[j]}_mae_diff_se_c"] = se
    for j in present:
        out[f"measured.{STATES[j]}_mean_c"] = float(np.nanmean(y[starts, j]) - T_ZERO)
    if "v" in steps.present:
        v_meas = steps.v_ms[starts + 1]
        regime = steps.regime[starts]
        v_held = _held(steps.v_ms[:, None])[:, 0][starts]
        ok = np.isfinite(v_meas) & np.isfinite(v_held)
        for r in np.unique(regime[ok]):
            sel = ok & (regime == r)
            out[f"measured.velocity_mean_cms.regime_{r}"] = float(np.mean(v_meas[sel]) * 100)
            out[f"measured.velocity_samples.regime_{r}"] = float(sel.sum())
            v_true = (None if reference_v_ms is None
                      else np.abs(np.asarray(reference_v_ms, float))[starts + 1])
            if v_true is not None:
                out[f"sensor.velocity_mae_cms.regime_{r}"] = float(
                    np.nanmean(np.abs(v_meas[sel] - v_true[sel])) * 100)
            for m in [*names, "persistence"]:
                v = v_held if m == "persistence" else preds[m][1][:, 0]
                out[f"{m}.velocity_mae_cms.regime_{r}"] = float(
                    np.mean(np.abs(v[sel] - v_meas[sel])) * 100)
                if v_true is not None:
                    out[f"{m}.velocity_true_mae_cms.regime_{r}"] = float(
                        np.nanmean(np.abs(v[sel] - v_true[sel])) * 100)
    for i, m in enumerate(names):
        if m in ("online", "offline"):
            final = theta_k[i, -1]
            for k, v in zip(FIT_NAMES, final, strict=True):
                out[f"{m}.theta.{k}"] = float(v)
    return out
