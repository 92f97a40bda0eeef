"""Reading offsets: the per-regime output-disturbance model of the daemon's state update.

docs/model.md#reading-offsets. The filter is checked against its closed form (a first-order
low-pass of a constant: the remaining error after m steps is (1 − a)^m, a = 1 − e^{−T/τ}),
and the daemon's observer on a record of the lumped model itself (known θ, so the model's
one-step prediction is exact up to the sensor noise) whose readings carry a different bias
in each regime, as the stratified plant's cavity-air probe does.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.daemon.observer import STATE_SIGNALS, StateObserver
from dsfd.drivers.base import Command
from dsfd.estimation.reading_offsets import (
    initial_reading_offsets,
    reading_offset,
    track_reading_offsets,
)
from dsfd.estimation.stepdata import model_config, step_data
from dsfd.physics.constants import T_ZERO
from dsfd.physics.model import LumpedModel
from tests.estimation.synthetic import lumped_record, true_theta, with_calibration

TAU = np.array([0.0, 0.0, 0.0, 300.0, 300.0])
STEP = 60.0


def _run(offsets, regime, bias, steps):
    """``steps`` steps in ``regime`` of readings ``bias`` above the offset-free prediction."""
    for _ in range(steps):
        e = bias - reading_offset(offsets, regime)
        offsets = track_reading_offsets(offsets, regime=regime, innovation_k=e, step_s=STEP,
                                        tracking_s=TAU, memory_s=3600.0, clip_k=3.0)
    return offsets


def test_a_constant_bias_is_followed_at_the_low_pass_rate():
    bias = np.array([0.5, 0.5, 0.5, -0.8, 2.0])
    d = _run(initial_reading_offsets(), 7, bias, 10)
    a = 1.0 - math.exp(-STEP / 300.0)
    expected = bias * (1.0 - (1.0 - a) ** 10)
    np.testing.assert_allclose(reading_offset(d, 7)[3:], expected[3:], rtol=1e-12)
    # sensors without a time constant never get an offset, whatever their innovation
    np.testing.assert_array_equal(reading_offset(d, 7)[:3], 0.0)
    # other regimes learnt nothing
    assert not np.any(reading_offset(d, 1))


def test_each_regime_keeps_its_own_offset_and_forgets_it_slowly():
    b7, b1 = np.array([0, 0, 0, 0, -1.5]), np.array([0, 0, 0, 0, 2.5])
    d = _run(initial_reading_offsets(), 7, b7, 60)
    d7 = reading_offset(d, 7)[4]
    assert d7 == pytest.approx(-1.5, abs=1e-3)
    d = _run(d, 1, b1, 30)
    assert reading_offset(d, 1)[4] == pytest.approx(2.5, abs=0.02)
    # 30 minutes of regime 1 only aged regime 7's offset by e^{-1800/3600}
    assert reading_offset(d, 7)[4] == pytest.approx(d7 * math.exp(-0.5), rel=1e-12)


def test_a_missing_reading_leaves_the_offset_and_a_spike_moves_it_by_the_clip_only():
    d = _run(initial_reading_offsets(), 7, np.array([0, 0, 0, 0, 1.0]), 20)
    before = reading_offset(d, 7)
    e = np.array([np.nan] * 4 + [np.nan])
    after = track_reading_offsets(d, regime=7, innovation_k=e, step_s=STEP, tracking_s=TAU,
                                  memory_s=3600.0, clip_k=3.0)
    np.testing.assert_array_equal(reading_offset(after, 7), before)
    spike = track_reading_offsets(d, regime=7, innovation_k=np.array([0, 0, 0, 0, 50.0]),
                                  step_s=STEP, tracking_s=TAU, memory_s=3600.0, clip_k=3.0)
    a = 1.0 - math.exp(-STEP / 300.0)
    assert reading_offset(spike, 7)[4] == pytest.approx(before[4] + 3.0 * a)


@pytest.fixture(scope="module")
def record(suwon):
    cfg = with_calibration(suwon, reading_offset_tracking_s=(0.0, 0.0, 0.0, 300.0, 300.0))
    theta = true_theta(cfg)
    data, _ = lumped_record(cfg, theta, step_s=60.0, hours=4.0, start_h=9.0, noise_k=0.0,
                            seed=2, regimes=(1, 7), block_min=40.0)
    steps = step_data(cfg, data)
    return cfg, theta, steps


def _observe(cfg, theta, steps, bias_by_regime):
    """The daemon's observer along the record; the readings carry a per-regime bias.
    Returns the one-step prediction error of x5 and the estimate's x5 less the truth."""
    model = LumpedModel(model_config(cfg, steps.step_s))
    obs = StateObserver(model, max_predicted_cycles=5)
    err, state_err = [], []
    prev = None
    for k in range(steps.n_steps + 1):
        truth = steps.y_k[k]
        regime = int(steps.regime[k - 1]) if k else int(steps.regime[0])
        y = truth + np.array([0, 0, 0, 0, bias_by_regime[regime]])
        est = obs.update({n: float(v) - T_ZERO for n, v in zip(STATE_SIGNALS, y, strict=True)},
                         step=None if prev is None else steps.inputs.at((slice(k - 1, k),)),
                         applied=prev, theta=theta)
        if est.prediction is not None:
            err.append(est.prediction.x_k[4] - y[4])
            state_err.append(est.x_k[4] - truth[4])
        if k < steps.n_steps:
            # the louver angle is in the step's inputs already; the observer uses regime and OR
            prev = Command(phi_deg=0.0, afr=int(steps.regime[k]),
                           or_pct=float(steps.or_[k]) * 100.0)
    return np.array(err), np.array(state_err)


def test_the_observer_predicts_the_biased_readings_and_keeps_the_model_state(record):
    cfg, theta, steps = record
    bias = {1: 2.5, 7: -1.5}
    err, state_err = _observe(cfg, theta, steps, bias)
    off = with_calibration(cfg, reading_offset_tracking_s=(0.0,) * 5)
    err_off, _ = _observe(off, theta, steps, bias)
    late = slice(len(err) // 2, None)
    # without offsets the one-step prediction misses by the bias of the regime
    assert np.mean(np.abs(err_off[late])) > 1.4
    # with them, a fraction of it: what is left is the first minutes after each switch
    assert np.mean(np.abs(err[late])) < 0.15 * np.mean(np.abs(err_off[late]))
    # the estimate is the model's air, not the biased reading
    assert np.median(np.abs(state_err[late])) < 0.1
