"""Identifiability: a window fit moves only the parameters its data determine.

Synthetic records of the lumped model with known θ (tests/estimation/synthetic.py): a day
with the dampers cycled through the regimes sees every heat-transfer coefficient, a night
with the cavity closed sees almost none of them. The arrival cost starts h_out and h_in 60 %
off the truth (the others at the truth), as an on-line window would after a bad day.
"""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.config.parameters import Param
from dsfd.estimation.calibration import make_problem
from dsfd.estimation.fit import fit_window
from dsfd.estimation.observer import observe
from dsfd.estimation.params import FIT_NAMES, ParameterSpace, full_vector
from dsfd.estimation.stepdata import model_config, step_data
from dsfd.physics.model import LumpedModel
from tests.estimation.synthetic import lumped_record, true_theta

RATIO = 0.5  # calibration.identifiability_sd_ratio as measured in docs/model.md
HEAT_TRANSFER = [Param.H_OUT, Param.H_CA1, Param.H_CA2, Param.H_CA3, Param.H_CA4, Param.H_IN]
FLOW = [Param.F, Param.C, Param.N]


def _window(suwon, *, start_h: float, regimes: tuple[int, ...]):
    truth = full_vector(true_theta(suwon)[None])[0]
    data, _ = lumped_record(suwon, truth[:9], step_s=120.0, hours=4.0, start_h=start_h,
                            seed=1, regimes=regimes)
    steps = step_data(suwon, data)
    model = LumpedModel(model_config(suwon, steps.step_s))
    track = observe(model, steps, truth[None])
    problem = make_problem(model, steps, track.x_hat[0], track.x_pred[0], suwon.calibration)
    space = ParameterSpace.from_panel(suwon)
    prior = truth.copy()
    prior[[Param.H_OUT, Param.H_IN]] *= 1.6

    def fit(ratio: float, always: np.ndarray | None = None):
        return fit_window(problem, space, prior_z=space.to_z(prior),
                          prior_cov=np.diag(space.prior_sd ** 2), free=np.ones(13, bool),
                          loss="soft_l1", f_scale=1.0, prior_weight=1.0, max_nfev=40,
                          determined_sd_ratio=ratio, always_fit=always)
    return truth, prior, fit


@pytest.fixture(scope="module")
def day(suwon):
    return _window(suwon, start_h=9.0, regimes=(1, 3, 5, 6, 10))


@pytest.fixture(scope="module")
def night(suwon):
    return _window(suwon, start_h=20.0, regimes=(10,))


def test_a_window_that_sees_a_parameter_recovers_it(day):
    truth, _, fit = day
    result = fit(RATIO)
    for p in (*HEAT_TRANSFER, *FLOW):
        assert result.free[p], f"{FIT_NAMES[p]} should be determined by a day of regimes"
    # the two started 60 % off come back to the truth
    for p in (Param.H_OUT, Param.H_IN):
        assert result.theta[p] == pytest.approx(truth[p], rel=0.02), FIT_NAMES[p]


def test_a_window_that_cannot_see_a_parameter_leaves_it_at_its_prior(night):
    truth, prior, fit = night
    result = fit(RATIO)
    held = ~result.free
    # a closed cavity says nothing of the flow, a still night little of the heat transfer
    assert held[FLOW].all()
    assert held[[Param.H_CA2, Param.H_CA4]].all()
    # what the window cannot determine stays exactly where the prior puts it
    assert np.allclose(result.theta[held], prior[held], rtol=1e-12, atol=1e-12)
    # without the test, the same window moves h_ca4 (prior = truth) by noise along a ridge
    # the data leave flat: the drift that the selection stops
    unselected = fit(1.0)
    assert abs(unselected.theta[Param.H_CA4] / truth[Param.H_CA4] - 1.0) > 0.1


def test_a_parameter_always_fitted_moves_although_the_window_cannot_see_it(night):
    """``calibration.identifiability_always_fit``: the listed parameter is fitted (and on
    the still night moves along its flat ridge, as without the test), the others the
    window cannot see stay exactly at their prior."""
    truth, prior, fit = night
    always = np.isin(FIT_NAMES, ["h_ca4"])
    result = fit(RATIO, always)
    assert result.free[Param.H_CA4] and not result.free[Param.H_CA2]
    assert abs(result.theta[Param.H_CA4] / truth[Param.H_CA4] - 1.0) > 0.1
    assert result.theta[Param.H_CA2] == pytest.approx(prior[Param.H_CA2], rel=1e-12)
    assert not result.free[FLOW].any()
