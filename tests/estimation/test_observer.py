"""The measurement update of the state observer (dsfd.estimation.observer.fill_state)."""

from __future__ import annotations

import numpy as np

from dsfd.estimation.observer import fill_state, observe
from dsfd.estimation.stepdata import model_config, step_data
from dsfd.physics.model import LumpedModel
from tests.estimation.synthetic import lumped_record, true_theta, with_calibration


def test_gain_one_takes_the_readings_and_gaps_keep_the_prediction():
    pred = np.array([280.0, 285.0, 290.0, 287.0, 283.0, 288.0])
    y = np.array([281.0, np.nan, 291.0, 288.0, 284.0])
    x = fill_state(y, pred, has_louver=True)
    np.testing.assert_array_equal(x[[0, 2, 3, 4]], y[[0, 2, 3, 4]])
    assert x[1] == pred[1]  # x2 missing: prediction kept
    assert x[5] == pred[5]  # x6 needs both panes


def test_fractional_gain_moves_the_prediction_towards_the_reading():
    pred = np.array([280.0, 285.0, 290.0, 287.0, 283.0, 288.0])
    y = np.array([282.0, 286.0, 289.0, np.nan, 283.0])
    x = fill_state(y, pred, has_louver=True, gain=0.25)
    np.testing.assert_allclose(x[:3], pred[:3] + 0.25 * (y[:3] - pred[:3]))
    assert x[3] == pred[3]
    assert x[5] == 0.5 * (x[1] + x[2])  # the gap gas follows the updated panes
    # Without a prediction (start-up) the reading is taken as it is.
    first = fill_state(y, np.full(6, np.nan), has_louver=True, gain=0.25)
    np.testing.assert_array_equal(first[[0, 1, 2, 4]], y[[0, 1, 2, 4]])


def test_fixed_gain_filter_has_the_exponential_smoothing_variance():
    """Steady temperature, white noise σ, prediction = last estimate: the estimate's error
    variance is K/(2 − K)·σ² (exponential smoothing), far below the reading's σ²."""
    rng = np.random.default_rng(4)
    truth, sigma, gain = 290.0, 0.2, 0.2
    x = np.full(6, truth)
    errors = []
    for _ in range(20000):
        y = truth + sigma * rng.standard_normal(5)
        x = fill_state(y, x, has_louver=True, gain=gain)
        errors.append(x[:5] - truth)
    errors = np.array(errors[100:])
    expected = gain / (2.0 - gain) * sigma ** 2
    np.testing.assert_allclose(errors.var(axis=0), expected, rtol=0.08)


def test_gain_per_state():
    pred = np.full(6, 290.0)
    y = np.full(5, 291.0)
    x = fill_state(y, pred, has_louver=True, gain=(1.0, 0.5, 0.25, 1.0, 1.0))
    np.testing.assert_allclose(x[:5], [291.0, 290.5, 290.25, 291.0, 291.0])


def test_default_update_filters_the_inner_panes_noise_out_of_the_next_prediction(suwon):
    """A perfect model (lumped record, the true θ) and 0.2 K white thermocouple noise.

    Taking each reading as it is (gain 1) starts every prediction from the noise: the
    one-step error against the next reading has variance a²σ² + σ², a = e^(−T/τ) ≈ 1 for
    a glass pane over a minute. The default gain g = 0.3 on x2, x3 leaves the estimate
    g/(2 − g)·σ² = 0.18σ² (exponential smoothing, previous test), so the RMS error drops
    to √(1.18/2) ≈ 0.77 of it. x1, x4, x5 keep gain 1 and their errors stay (what they
    gain from filtered panes is a few mK of coupling).
    """
    assert suwon.calibration.measurement_gain == (1.0, 0.3, 0.3, 1.0, 1.0)
    theta = true_theta(suwon)
    data, _ = lumped_record(suwon, theta, step_s=60.0, hours=3.0, seed=7, noise_k=0.2)
    steps = step_data(suwon, data)
    rms = {}
    for gain in ((1.0,) * 5, suwon.calibration.measurement_gain):
        cfg = with_calibration(suwon, measurement_gain=gain)
        track = observe(LumpedModel(model_config(cfg, steps.step_s)), steps, theta[None])
        err = track.x_pred[0, 11:, :5] - steps.y_k[11:]  # after the start-up
        rms[gain[1]] = np.sqrt(np.nanmean(err ** 2, axis=0))
    ratio = rms[0.3] / rms[1.0]
    assert np.all((ratio[1:3] > 0.68) & (ratio[1:3] < 0.86)), ratio
    np.testing.assert_allclose(ratio[[0, 3, 4]], 1.0, atol=0.03)
