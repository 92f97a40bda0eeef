"""State update from the measurements: x1..x5 from the readings, x6 by the quasi-steady observer.

Each step the model predicts x_{k+1} from the current estimate x̂_k; the estimate is then
corrected by the measurements where they exist:

* x1..x5: the prediction moved towards the measured value by ``calibration.measurement_gain``
  (1 takes the reading as it is, the paper's update, the default for x1, x4, x5; the slow
  inner panes x2, x3 default to 0.3, a fixed-gain filter of their sensor noise); a missing
  (NaN) or flagged value keeps the prediction;
* x6 (DGU gap gas, never measured): (x2 + x3)/2 when both panes are measured — exact at
  quasi-steady state because node 6 sees both panes through the same h_ca4 and its time
  constant (≈ 1.6 s) is far below the step (docs/model.md#initial-state); otherwise the prediction;
* a panel without a louver has only a dummy louver node tied to the cavity air, so an
  unmeasured x4 is set to x5.

The first estimate is the steady state of the first step's inputs with the measured
values put in (docs/model.md#initial-state). A gap in the record (a step that does not span exactly
one sampling interval) restarts the observer the same way.

Isolated spikes — a temperature that jumps by more than a threshold from both neighbours
while the neighbours agree — are flagged by :func:`spike_mask`; the calibrator treats them
as missing. It needs the next sample, so the newest sample is never flagged.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dsfd.estimation.params import N_PARAMS, full_vector, with_offsets
from dsfd.estimation.stepdata import StepData
from dsfd.physics.model import LumpedModel

X2, X3, X4, X5, X6 = 1, 2, 3, 4, 5


class ObserverTrack(NamedTuple):
    """Observer estimates along a record (B observers with their own θ).

    Attributes
    ----------
    x_hat : ndarray (B, n + 1, 6), [K]
        State estimate at each row after the measurement update.
    x_pred : ndarray (B, n + 1, 6), [K]
        One-step prediction of each row from the previous estimate (row 0: the initial
        steady state).
    v_pred_ms : ndarray (B, n), [m/s]
        Signed mean cavity velocity of each step's prediction.
    """

    x_hat: np.ndarray
    x_pred: np.ndarray
    v_pred_ms: np.ndarray


def spike_mask(y: np.ndarray, threshold: float) -> np.ndarray:
    """Isolated spikes in a series of rows (axis 0) [bool, same shape as ``y``].

    Sample k is a spike when |y_k − y_{k−1}| and |y_k − y_{k+1}| both exceed ``threshold``
    with the same sign while |y_{k+1} − y_{k−1}| does not. First and last rows never are.
    """
    y = np.asarray(y, float)
    out = np.zeros(y.shape, bool)
    if y.shape[0] < 3:
        return out
    prev, mid, nxt = y[:-2], y[1:-1], y[2:]
    with np.errstate(invalid="ignore"):
        d_prev, d_next = mid - prev, mid - nxt
        spike = ((np.abs(d_prev) > threshold) & (np.abs(d_next) > threshold)
                 & (np.sign(d_prev) == np.sign(d_next))
                 & (np.abs(nxt - prev) <= threshold))
    out[1:-1] = spike
    return out


def probe_to_state(y5: np.ndarray, x5_pred: np.ndarray, x5_probe: np.ndarray) -> np.ndarray:
    """Readings with the cavity-air probe's turned into the model's x5 [K] (…, 5).

    The probe reads T_in + p(a)(x5 − T_in), not the column mean x5
    (docs/model.md#cavity-probe); the reading moves the estimate by its innovation against
    the predicted probe value, y5 − (probe − x5_pred): the predicted stratification is
    taken off the reading (slope 1 instead of 1/p, p ∈ [1, 1.15]; the cavity air's time
    constant of about 30 s makes the difference vanish within the next step).
    """
    out = np.array(np.broadcast_to(y5, np.broadcast_shapes(np.shape(y5),
                                                           (*np.shape(x5_pred), 5))), float)
    out[..., 4] = out[..., 4] - (np.asarray(x5_probe) - np.asarray(x5_pred))
    return out


def fill_state(y5: np.ndarray, x_pred: np.ndarray, *, has_louver: bool,
               gain: float | tuple[float, ...] | np.ndarray = 1.0) -> np.ndarray:
    """Measurement update: measured x1..x5 correct the prediction, x6 by the observer.

    Parameters
    ----------
    y5 : array (..., 5), [K]
        Measured x1..x5, NaN where missing or flagged.
    x_pred : array (..., 6), [K]
        Model prediction (broadcast against ``y5``); NaN where there is none.
    has_louver : bool
        False: an unmeasured x4 follows x5.
    gain : float or array (5,), [-]
        Weight of the measurement (per state): x̂ = x_pred + gain·(y − x_pred). 1 takes the reading
        as it is (the paper's state update); below 1 the update is a fixed-gain
        (steady-state Kalman) filter that averages white sensor noise against the model's
        prediction. Without a prediction the reading is taken as it is.

    Returns
    -------
    x_hat : ndarray (..., 6), [K]
    """
    y5 = np.asarray(y5, float)
    x = np.array(np.broadcast_to(x_pred, np.broadcast_shapes(x_pred.shape,
                                                             (*y5.shape[:-1], 6))), float)
    meas = np.broadcast_to(y5, (*x.shape[:-1], 5))
    ok = np.isfinite(meas)
    pred = x[..., :5]
    gain = np.asarray(gain, float)
    if np.any(gain < 1.0):
        with np.errstate(invalid="ignore"):
            meas = np.where(np.isfinite(pred), pred + gain * (meas - pred), meas)
    x[..., :5] = np.where(ok, meas, pred)
    panes = ok[..., X2] & ok[..., X3]
    x[..., X6] = np.where(panes, 0.5 * (x[..., X2] + x[..., X3]), x[..., X6])
    if not has_louver:
        x[..., X4] = np.where(ok[..., X4], x[..., X4], x[..., X5])
    return x


def initial_state(model: LumpedModel, steps: StepData, row: int,
                  theta: np.ndarray) -> np.ndarray:
    """Estimate at ``row``: steady state of that step's inputs, measured values put in.

    ``theta`` (B, 13) or (B, 9) gives B estimates (one per fit vector) [K], shape (B, 6).
    """
    theta = full_vector(np.atleast_2d(theta))
    k = min(row, steps.n_steps - 1)
    inp = with_offsets(steps.inputs.at((slice(k, k + 1),)), theta[:, N_PARAMS:])
    nb = theta.shape[0]
    x_ss = model.steady_state(np.full(nb, steps.regime[k]), steps.or_[k], inp,
                              theta[:, :N_PARAMS])
    return fill_state(steps.y_k[row], x_ss, has_louver=model.cfg.louver is not None)


def observer_step(model: LumpedModel, steps: StepData, k: int, x_hat: np.ndarray,
                  theta: np.ndarray, y_next: np.ndarray):
    """One prediction + measurement update from row k to k + 1 for B fit vectors.

    Returns ``(x_hat_next, x_pred_next, v_pred_ms)``, shapes (B, 6), (B, 6), (B,).
    """
    theta = full_vector(np.atleast_2d(theta))
    nb = theta.shape[0]
    if not steps.valid[k]:
        x = initial_state(model, steps, k + 1, theta)
        return x, x, np.zeros(nb)
    inp = with_offsets(steps.inputs.at((slice(k, k + 1),)), theta[:, N_PARAMS:])
    x_hat = np.broadcast_to(np.asarray(x_hat, float), (nb, 6))
    res = model.step(x_hat, np.full(nb, steps.regime[k]), steps.or_[k], inp,
                     theta[:, :N_PARAMS])
    y_state = probe_to_state(y_next, res.x_next[:, X5], res.x5_probe_k)
    x_new = fill_state(y_state, res.x_next, has_louver=model.cfg.louver is not None,
                       gain=model.cfg.calibration.measurement_gain)
    return x_new, res.x_next, res.v_cav_ms


def observe(model: LumpedModel, steps: StepData, theta: np.ndarray, *,
            y_k: np.ndarray | None = None) -> ObserverTrack:
    """Run the observer over a record for B parameter vectors at once.

    Parameters
    ----------
    model : LumpedModel
        Built with the data's step (``dsfd.estimation.stepdata.model_config``).
    steps : StepData
    theta : array (B, 13) or (B, n, 13)
        Fit vectors ϑ = (θ, q), constant or per step (9 columns: no offsets).
    y_k : array (n + 1, 5), optional, [K]
        Measurements to use (default ``steps.y_k``), e.g. with flagged samples set to NaN.

    Returns
    -------
    ObserverTrack
    """
    theta = full_vector(np.asarray(theta, float))
    if theta.ndim == 1:
        theta = theta[None]
    n = steps.n_steps
    per_step = theta.ndim == 3
    nb = theta.shape[0]
    y = steps.y_k if y_k is None else y_k
    x_hat = np.empty((nb, n + 1, 6))
    x_pred = np.empty((nb, n + 1, 6))
    v_pred = np.zeros((nb, n))
    x_hat[:, 0] = initial_state(model, steps, 0, theta[:, 0] if per_step else theta)
    x_pred[:, 0] = x_hat[:, 0]
    for k in range(n):
        th = theta[:, k] if per_step else theta
        x_hat[:, k + 1], x_pred[:, k + 1], v_pred[:, k] = observer_step(
            model, steps, k, x_hat[:, k], th, y[k + 1])
    return ObserverTrack(x_hat, x_pred, v_pred)
