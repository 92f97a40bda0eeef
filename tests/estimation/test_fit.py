"""The Eq. 3 fit: recovery of known parameters, bounds, robustness to one bad sample."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.config.parameters import N_PARAMS, Param
from dsfd.estimation.calibration import offline_fit
from dsfd.estimation.params import ParameterSpace
from dsfd.estimation.stepdata import model_config, step_data
from dsfd.measured import MeasuredData
from dsfd.physics.model import LumpedModel
from tests.estimation.synthetic import (
    lumped_record,
    suwon_diagonal_k,
    true_theta,
    with_calibration,
)


@pytest.fixture(scope="module")
def record(suwon):
    """8 h of 2-minute lumped-model data, thermocouple-like noise (σ 0.1 K, 3 mm/s)."""
    theta = true_theta(suwon)
    data, _ = lumped_record(suwon, theta, step_s=120.0, hours=8.0, seed=1)
    return data, theta


@pytest.fixture(scope="module")
def clean_fit(suwon, record):
    data, _ = record
    steps = step_data(suwon, data)
    model = LumpedModel(model_config(suwon, steps.step_s))
    return offline_fit(model, steps)


def test_identifiable_parameters_are_recovered_within_5_percent(suwon, record, clean_fit):
    _, theta = record
    state, fit = clean_fit
    assert fit.free[:N_PARAMS].all()
    err = np.abs(state.theta[:N_PARAMS] / theta - 1.0)
    worst = PARAMETER_NAMES[int(np.argmax(err))]
    assert err.max() < 0.05, f"{worst}: {err.max():.1%}"
    # the heat-flux offsets stay near zero on data the model can represent
    assert np.all(np.abs(state.theta[N_PARAMS:]) < 3.0)


def test_standard_errors_are_positive_and_small(suwon, clean_fit):
    state, _ = clean_fit
    se = state.std_error(ParameterSpace.from_panel(suwon))
    assert np.all(se[:N_PARAMS] > 0)
    assert np.all(se[:N_PARAMS] / state.theta[:N_PARAMS] < 0.05)


def _with(data: MeasuredData, column: str, row: int, delta: float) -> MeasuredData:
    cols = {k: v.copy() for k, v in data.columns.items()}
    cols[column][row] += delta
    return MeasuredData(data.time_s, cols, data.source)


@pytest.mark.parametrize("spike_filter", [True, False], ids=["spike-filter", "robust-loss"])
def test_one_outlier_moves_no_estimate_by_more_than_its_standard_error(suwon, record,
                                                                        clean_fit, spike_filter):
    data, _ = record
    cfg = suwon
    if not spike_filter:  # the robust loss alone must hold the fit
        cfg = with_calibration(suwon, spike_threshold_k=100.0)
    bad = _with(data, "x2_c", len(data) // 2, 15.0)
    steps = step_data(cfg, bad)
    model = LumpedModel(model_config(cfg, steps.step_s))
    state, _ = offline_fit(model, steps)
    ref, _ = clean_fit
    se = ref.std_error(ParameterSpace.from_panel(cfg))
    moved = np.abs(state.theta - ref.theta)[:N_PARAMS]
    assert np.all(moved <= se[:N_PARAMS]), dict(zip(PARAMETER_NAMES,
                                                    np.round(moved / se[:N_PARAMS], 2),
                                                    strict=True))


def test_estimates_stay_inside_the_bounds(suwon):
    """Data made with h_out and f beyond the panel's bounds: the fit stops at the bound."""
    theta = true_theta(suwon)
    theta[Param.H_OUT] = 60.0  # upper bound 40
    theta[Param.F] = 3.0  # lower bound 5
    data, _ = lumped_record(suwon, theta, step_s=300.0, hours=4.0, seed=2,
                            regimes=(1, 3, 10))
    steps = step_data(suwon, data)
    model = LumpedModel(model_config(suwon, steps.step_s))
    space = ParameterSpace.from_panel(suwon)
    state, fit = offline_fit(model, steps, max_nfev=15)
    assert np.all(state.theta >= space.lower) and np.all(state.theta <= space.upper)
    assert state.theta[Param.H_OUT] == pytest.approx(40.0, rel=0.02)
    c_n = [Param.C, Param.N]
    assert not fit.free[c_n].any()  # no regime 5-8 in the data: c, n not fitted
    assert state.theta[Param.N] == space.default[Param.N]
    # c kept step with f (docs/model.md#c-follows-f), by the hand-computed path resistance
    expected_c = space.default[Param.C] * np.sqrt(suwon_diagonal_k(space.default[Param.F])
                                                  / suwon_diagonal_k(state.theta[Param.F]))
    assert state.theta[Param.C] == pytest.approx(expected_c, rel=1e-9)


def test_the_outlier_matters_without_robust_loss_and_spike_filter(suwon, record, clean_fit):
    """Control for the test above: with a plain quadratic loss the same sample does move θ."""
    data, _ = record
    cfg = with_calibration(suwon, spike_threshold_k=100.0, loss="linear")
    steps = step_data(cfg, _with(data, "x2_c", len(data) // 2, 15.0))
    state, _ = offline_fit(LumpedModel(model_config(cfg, steps.step_s)), steps)
    ref, _ = clean_fit
    se = ref.std_error(ParameterSpace.from_panel(cfg))
    assert np.max(np.abs(state.theta - ref.theta)[:9] / se[:9]) > 1.5


def test_flow_parameters_come_from_the_speed_not_from_a_biased_cavity_sensor(suwon, record):
    """A cavity-air sensor that reads 1.5 K high whenever a diagonal regime runs (a
    stratified cavity's mid-height air, which the well-mixed x5 does not represent): the
    joint fit bends the flow coefficient c to absorb it; the staged fit takes f, c, n from
    the anemometer, which is right, and keeps them within 2 %."""
    data, theta = record
    cols = {k: v.copy() for k, v in data.columns.items()}
    cols["x5_c"] = cols["x5_c"] + np.where(np.isin(cols["afr"], [5, 6, 7, 8]), 1.5, 0.0)
    steps = step_data(suwon, MeasuredData(data.time_s, cols, data.source))
    model = LumpedModel(model_config(suwon, steps.step_s))
    flow = [PARAMETER_NAMES.index(k) for k in ("f", "c", "n")]
    err = {}
    for staged in (False, True):
        cal = dataclasses.replace(suwon.calibration, flow_from_velocity=staged)
        state, _ = offline_fit(model, steps, cal)
        err[staged] = np.abs(state.theta[flow] / theta[flow] - 1.0)
    assert np.all(err[True] < 0.02), err[True]
    assert err[False].max() > 0.05, err[False]


def test_a_window_that_frees_one_flow_parameter_alone_is_fitted(suwon):
    """Only orifice regimes (1, 3) and closed in the window: f is the only flow parameter
    the speed can inform, so the staged fit's first block has one free variable. SciPy's
    trust-region subspace solver (``tr_solver='lsmr'``) needs two and raised IndexError
    from a start near a bound (the cooling closed loop lost 41 of 564 updates to it); here
    the start is f = 5.5 against a lower bound of 5 and a truth of 150."""
    theta = true_theta(suwon)
    data, _ = lumped_record(suwon, theta, step_s=120.0, hours=6.0, seed=3,
                            regimes=(1, 3, 10))
    p = suwon.parameters
    cfg = dataclasses.replace(suwon, parameters=dataclasses.replace(
        p, f=dataclasses.replace(p.f, default=1.1 * p.f.lower)))
    steps = step_data(cfg, data)
    model = LumpedModel(model_config(cfg, steps.step_s))
    state, fit = offline_fit(model, steps)
    f = PARAMETER_NAMES.index("f")
    assert fit.success
    assert abs(state.theta[f] / theta[f] - 1.0) < 0.05


def test_diagonal_orifice_regimes_inform_f_and_leave_c_n_alone(suwon):
    """Under model.diagonal_flow: orifice a diagonal regime's flow goes through f (as
    regimes 1-4 and 9) and c, n are in no flow law: a window of regime 5 frees f and never
    c, n; under the paper's power law it is the other way round."""
    orifice = dataclasses.replace(suwon, model=dataclasses.replace(suwon.model,
                                                                   diagonal_flow="orifice"))
    regime5 = np.full(30, 5)
    power_free = ParameterSpace.from_panel(suwon).free_in_window(regime5)
    orifice_space = ParameterSpace.from_panel(orifice)
    orifice_free = orifice_space.free_in_window(regime5)
    assert power_free[[Param.C, Param.N]].all() and not power_free[Param.F]
    assert orifice_free[Param.F] and not orifice_free[[Param.C, Param.N]].any()
    assert orifice_space.fixed[[Param.C, Param.N]].all()
    assert not orifice_space.free_in_window(np.full(30, 10))[Param.F]
