"""Paired difference of two models' absolute errors and its batch-means standard error."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.estimation.stepdata import step_data
from dsfd.estimation.validation import STATES, paired_difference, replay_scores
from tests.estimation.synthetic import lumped_record, true_theta, with_calibration


def test_identical_errors_differ_by_zero():
    e = np.abs(np.random.default_rng(0).normal(size=600))
    assert paired_difference(e, e, 60) == (0.0, 0.0)


def test_white_differences_give_the_textbook_standard_error():
    # iid differences: the standard error of their mean is σ/√n, whatever the batch length
    rng = np.random.default_rng(1)
    n, sigma, shift = 24_000, 0.1, 0.004
    a = rng.normal(size=n) * sigma + shift
    diff, se = paired_difference(a, np.zeros(n), 60)
    assert diff == pytest.approx(np.mean(a))
    assert se == pytest.approx(sigma / np.sqrt(n), rel=0.2)
    assert abs(diff - shift) < 3 * se


def test_correlated_differences_get_the_long_run_standard_error():
    # AR(1) with coefficient r: the variance of the mean is σ²(1 + r)/(1 − r)/n for large n,
    # far above the naive σ²/n that treats neighbouring rollouts as independent
    rng = np.random.default_rng(2)
    n, r = 200_000, 0.9
    x = np.empty(n)
    x[0] = 0.0
    noise = rng.normal(size=n)
    for k in range(1, n):
        x[k] = r * x[k - 1] + noise[k]
    sigma = 1.0 / np.sqrt(1.0 - r * r)
    long_run = sigma * np.sqrt((1 + r) / (1 - r) / n)
    _, se = paired_difference(x, np.zeros(n), 500)
    assert se == pytest.approx(long_run, rel=0.2)
    assert se > 3 * sigma / np.sqrt(n)


def test_fewer_than_two_batches_has_no_standard_error():
    diff, se = paired_difference(np.ones(50), np.zeros(50), 60)
    assert diff == 1.0 and np.isnan(se)


def test_replay_reports_the_difference_of_the_mean_absolute_errors(suwon):
    # the mean of |e_a| − |e_b| over the same samples is MAE_a − MAE_b exactly
    cfg = with_calibration(suwon, update_interval_s=1800.0, max_nfev=4)
    data, _ = lumped_record(cfg, true_theta(cfg), step_s=300.0, hours=4.0, seed=5)
    steps = step_data(cfg, data)
    h1 = replay_scores(cfg, steps, offline_theta=true_theta(cfg), horizons=(1,)).horizons[1]
    for other in ("offline", "uncalibrated", "persistence"):
        for s in STATES:
            diff, se = h1.paired[other][s]
            assert diff == pytest.approx(h1.mae_c["online"][s] - h1.mae_c[other][s], abs=1e-12)
            assert se >= 0.0
