"""On-line self-calibration: what moves, what stays put, when it updates, resuming."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.config import load_panel
from dsfd.config.parameters import N_PARAMS, Param
from dsfd.estimation.calibration import OnlineCalibrator, window_start
from dsfd.estimation.observer import fill_state, observe, spike_mask
from dsfd.estimation.params import FIT_NAMES, ParameterSpace
from dsfd.estimation.state import state_from_dict
from dsfd.estimation.stepdata import model_config, step_data
from dsfd.physics.model import LumpedModel
from tests.conftest import PANELS
from tests.estimation.synthetic import lumped_record, true_theta, with_calibration


def _setup(cfg, **record):
    theta = true_theta(cfg)
    data, _ = lumped_record(cfg, theta, **record)
    steps = step_data(cfg, data)
    model = LumpedModel(model_config(cfg, steps.step_s))
    track = observe(model, steps, model.default_theta()[None])
    return model, steps, track, theta


def test_window_without_flow_regimes_holds_f_c_n_at_the_prior(suwon):
    model, steps, track, _ = _setup(suwon, step_s=300.0, hours=4.0, regimes=(10,))
    cal = OnlineCalibrator(model)
    before = cal.theta
    rep = cal.update(steps, track.x_hat[0], track.x_pred[0])
    assert rep.fit is not None and not rep.skipped
    names = dict(zip(FIT_NAMES, rep.fit.free, strict=True))
    assert not names["f"] and not names["c"] and not names["n"]
    assert names["h_out"] and names["h_ca2"]
    for k in ("f", "c", "n"):
        i = FIT_NAMES.index(k)
        assert cal.theta[i] == before[i]
    assert cal.theta[0] != before[0]
    assert cal.state.updates == 1 and cal.state.last_update_s == steps.time_s[-1]


def test_panels_fix_what_they_cannot_excite(suwon):
    no_louver = ParameterSpace.from_panel(load_panel(PANELS / "suwon-south-no-louver.yaml"))
    assert no_louver.fixed[FIT_NAMES.index("h_ca2")] and no_louver.fixed[FIT_NAMES.index("q_x4")]
    cube = ParameterSpace.from_panel(load_panel(PANELS / "aalborg-cube.yaml"))
    fixed = {k for k, f in zip(FIT_NAMES, cube.fixed, strict=True) if f}
    assert fixed == {"h_ca2", "c", "n", "q_x4"}
    off = dataclasses.replace(suwon.calibration, heat_offsets=False, fixed=("n",))
    space = ParameterSpace.from_panel(suwon, off)
    assert {k for k, f in zip(FIT_NAMES, space.fixed, strict=True) if f} == {
        "n", "q_x1", "q_x2", "q_x3", "q_x4"}


def test_updates_are_due_after_the_minimum_window_and_interval(suwon):
    model = LumpedModel(suwon)
    cal = OnlineCalibrator(model)
    t0 = 1.6409e9
    assert cal.settings.min_window_h == 0.25
    assert not cal.due(t0 + 840.0, t0)           # min_window_h = 0.25: 15 min of data
    assert cal.due(t0 + 900.0, t0)
    cal.state = dataclasses.replace(cal.state, last_update_s=t0 + 900.0)
    assert not cal.due(t0 + 1200.0, t0)          # update_interval_s = 600
    assert cal.due(t0 + 1500.0, t0)
    time_s = t0 + 60.0 * np.arange(600)
    assert time_s[window_start(time_s, 599, 4.0)] == time_s[599] - 4 * 3600.0


def test_resumed_state_continues_the_calibration(suwon):
    model, steps, track, theta = _setup(suwon, step_s=300.0, hours=6.0, seed=3)
    first = steps.window(0, 36)
    cal = OnlineCalibrator(model)
    cal.update(first, track.x_hat[0, :37], track.x_pred[0, :37])
    doc = cal.state.to_dict(cal.space)
    resumed = OnlineCalibrator(model, state=state_from_dict(doc, space=cal.space,
                                                            panel_id=suwon.panel.id))
    assert np.array_equal(resumed.theta, cal.theta)
    rest = steps.window(24, 72)
    a = cal.update(rest, track.x_hat[0, 24:], track.x_pred[0, 24:])
    b = resumed.update(rest, track.x_hat[0, 24:], track.x_pred[0, 24:])
    assert np.allclose(a.state.theta, b.state.theta)
    # two windows bring the well-excited conductances close to the truth
    well_excited = [Param.H_OUT, Param.H_CA1, Param.H_CA3]
    err = np.abs(b.state.theta[well_excited] / theta[well_excited] - 1)
    assert err.max() < 0.1


def test_offsets_follow_a_sensor_bias(suwon):
    """With every excited parameter free (identifiability_sd_ratio 1, the paper's fit) the
    exterior pane's 1.5 K bias goes into its offset q_x1. On this 3-h window h_out and q_x1
    are not determined apart, so a ratio of 0.5 holds both at their prior
    (docs/model.md#identifiability); what this test checks is the offset itself."""
    suwon = with_calibration(suwon, identifiability_sd_ratio=1.0)
    model, steps, track, _ = _setup(suwon, step_s=120.0, hours=3.0, seed=4, noise_k=0.05)
    biased = dataclasses.replace(steps, y_k=steps.y_k + np.array([1.5, 0, 0, 0, 0]))
    track = observe(model, biased, model.default_theta()[None])
    cal = OnlineCalibrator(model)
    cal.update(biased, track.x_hat[0], track.x_pred[0])
    q1 = cal.theta[Param.Q_X1]
    assert q1 > 5.0  # W/m2: the exterior pane reads warm, so it gets heat
    for k in range(20, 40):
        cal.track(biased, k, track.x_hat[0, k], biased.y_k[k + 1])
    assert np.isfinite(cal.theta).all()
    assert np.all(cal.theta >= cal.space.lower) and np.all(cal.theta <= cal.space.upper)


def test_observer_fills_gaps_from_the_prediction_and_estimates_x6(suwon):
    pred = np.array([[280.0, 290.0, 295.0, 300.0, 285.0, 292.0]])
    y = np.array([281.0, np.nan, 296.0, np.nan, 286.0])
    x = fill_state(y, pred, has_louver=True)[0]
    assert x.tolist() == [281.0, 290.0, 296.0, 300.0, 286.0, 292.0]
    y = np.array([281.0, 291.0, 297.0, np.nan, 286.0])
    x = fill_state(y, pred, has_louver=False)[0]
    assert x[5] == pytest.approx(294.0) and x[3] == 286.0  # x6 = (x2+x3)/2; x4 = x5


def test_spikes_are_isolated_jumps_only():
    y = np.array([10.0, 10.1, 18.0, 10.2, 10.3, 14.0, 14.1, 14.0])
    assert np.flatnonzero(spike_mask(y, 3.0)).tolist() == [2]


def test_inner_pane_offsets_average_out_white_sensor_noise(suwon):
    """No model error, 0.2 K white thermocouple noise: the tracked offsets should stay put.

    The innovations of a perfect model are the sensor noise; a low-pass of time constant τ
    passes a share √(a/(2 − a)), a = 1 − e^(−T/τ), of white noise: 0.41 times as much at
    1800 s as at 300 s. The offsets integrate that through the tracking loop, so the wander
    of q_x2 and q_x3 should drop by about that much (0.40 and 0.49 on this record); the test
    asks for below 0.6. x1 and x4 keep 300 s and barely change. The states take each
    reading as it is (gain 1), so the innovations are the sensor noise alone, unfiltered.
    """
    suwon = with_calibration(suwon, measurement_gain=(1.0,) * 5)
    theta = true_theta(suwon)
    data, _ = lumped_record(suwon, theta, step_s=60.0, hours=3.0, seed=5, noise_k=0.2)
    steps = step_data(suwon, data)
    model = LumpedModel(model_config(suwon, steps.step_s))
    track = observe(model, steps, theta[None])
    spread = {}
    for tau in ((300.0, 300.0, 300.0, 300.0), suwon.calibration.innovation_smoothing_s):
        m = LumpedModel(model_config(with_calibration(suwon, innovation_smoothing_s=tau),
                                     steps.step_s))
        cal = OnlineCalibrator(m)
        cal.state = dataclasses.replace(cal.state, theta=np.concatenate([theta, np.zeros(4)]))
        q = []
        for k in range(steps.n_steps):
            cal.track(steps, k, track.x_hat[0, k], steps.y_k[k + 1])
            q.append(cal.theta[N_PARAMS:].copy())
        spread[tau[1]] = np.std(q, axis=0)  # W/m2, per node x1..x4
    assert suwon.calibration.innovation_smoothing_s == (300.0, 1800.0, 1800.0, 300.0)
    fast, slow = spread[300.0], spread[1800.0]
    assert np.all(slow[1:3] < 0.6 * fast[1:3])
    np.testing.assert_allclose(slow[[0, 3]], fast[[0, 3]], rtol=0.2)
