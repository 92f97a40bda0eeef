"""Velocity scores against a reference (the simulated plant's true cavity speed)."""

from __future__ import annotations

import pytest

from dsfd.estimation.stepdata import step_data
from dsfd.estimation.validation import replay_scores
from tests.estimation.synthetic import lumped_record, true_theta


@pytest.fixture(scope="module")
def record(suwon):
    data, _ = lumped_record(suwon, true_theta(suwon), step_s=300.0, hours=4.0, seed=5,
                            regimes=(1, 5), noise_v=0.0)
    return data


def test_reference_equal_to_the_readings_scores_like_the_readings(suwon, record):
    steps = step_data(suwon, record)
    scores = replay_scores(suwon, steps, horizons=(1,), online=False,
                           reference_v_ms=record.get("v_cav_ms"))
    assert sorted(scores.velocity) == [1, 5]
    for v in scores.velocity.values():
        assert v.sensor_mae_cms == 0.0
        for m in ("uncalibrated", "persistence"):
            assert v.true_mae_cms[m] == pytest.approx(v.mae_cms[m])


def test_the_sensor_error_is_the_reading_minus_the_reference(suwon, record):
    steps = step_data(suwon, record)
    v = record.get("v_cav_ms")
    offset = 0.02  # a reference 2 cm/s below every reading
    out = replay_scores(suwon, steps, horizons=(1,), online=False, reference_v_ms=v - offset)
    assert out.velocity[1].sensor_mae_cms == pytest.approx(2.0)
    assert out.flat()["sensor.velocity_mae_cms.regime_1"] == out.velocity[1].sensor_mae_cms
    without = replay_scores(suwon, steps, horizons=(1,), online=False).flat()
    assert not any(k.startswith("sensor.") or "velocity_true" in k for k in without)
