"""The measurement update of the state observer (dsfd.estimation.observer.fill_state)."""

from __future__ import annotations

import numpy as np

from dsfd.estimation.observer import fill_state


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
