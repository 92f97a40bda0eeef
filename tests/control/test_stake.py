"""The energy at stake in a parameter change (dsfd.control.stake, docs/model.md#energy-at-stake).

* Nothing changed, nothing at stake: the same θ twice gives J_now = J_before.
* Physics: with every damper shut (regime 10) no air crosses the cavity's path, so the path
  resistance f cannot matter, while the exterior convection h_out does.
* Reference: J by hand from the paper's Eq. 4/5, stepping the model one step at a time
  (``LumpedModel.step``, the observer's path, not the rollout the function uses) and
  restarting at a gap in the record as the function says it does.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.control.objective import is_heating
from dsfd.control.stake import energy_at_stake, solar_energy_at_stake
from dsfd.estimation.observer import initial_state
from dsfd.estimation.params import PARAMETER_NAMES
from dsfd.estimation.stepdata import StepData, model_config, step_data
from dsfd.physics.model import LumpedModel
from tests.estimation.synthetic import lumped_record, true_theta


def _record(cfg, theta, **kw) -> tuple[LumpedModel, StepData]:
    data, _ = lumped_record(cfg, theta, step_s=120.0, hours=6.0, seed=3, **kw)
    steps = step_data(cfg, data)
    return LumpedModel(model_config(cfg, steps.step_s)), steps


def _with(theta: np.ndarray, name: str, factor: float) -> np.ndarray:
    out = theta.copy()
    out[PARAMETER_NAMES.index(name)] *= factor
    return out


def test_the_same_parameters_put_nothing_at_stake(suwon):
    theta = true_theta(suwon)
    model, steps = _record(suwon, theta)
    s = energy_at_stake(model, steps, theta, theta)
    assert s.j_now_kwh == s.j_before_kwh and s.per_week_kwh == 0.0
    assert s.days == pytest.approx(steps.n_steps * steps.step_s / 86400.0)


def test_with_every_damper_shut_the_path_resistance_is_not_at_stake_but_h_out_is(suwon):
    theta = true_theta(suwon)
    model, steps = _record(suwon, theta, regimes=(10,))
    assert set(np.unique(steps.regime)) == {10}
    f = energy_at_stake(model, steps, theta, _with(theta, "f", 3.0))
    h = energy_at_stake(model, steps, theta, _with(theta, "h_out", 1.5))
    assert abs(f.per_week_kwh) < 1e-9
    assert abs(h.per_week_kwh) > 0.01


def _by_hand(model: LumpedModel, steps: StepData, theta: np.ndarray) -> float:
    """Eq. 4 (heating: J = −∫(Q_cv,rd + Q_sol + Q_air + Q_DA) dt) or Eq. 5 (cooling:
    J = ∫(Q_cv,rd + Q_sol + Q_air − Q_DA) dt) in kWh, one model step at a time."""
    total_j = 0.0
    x = None
    for k in range(steps.n_steps):
        if not steps.valid[k]:
            x = None
            continue
        if x is None:
            x = initial_state(model, steps, k, theta[None])
        inp = steps.inputs.at((slice(k, k + 1),))
        r = model.step(x, steps.regime[k], steps.or_[k], inp, theta)
        q = float(r.q_cv_rd_w[0] + r.q_sol_w[0] + r.q_air_w[0])
        heating = is_heating(model.cfg.control, float(np.asarray(inp.t_out_k)[0]))
        da = float(r.q_da_w[0])
        total_j += (-(q + da) if heating else q - da) * steps.step_s
        x = r.x_next
    return total_j / 3.6e6


def test_j_matches_the_paper_objective_stepped_by_hand_across_a_gap(suwon):
    theta = true_theta(suwon)
    model, steps = _record(suwon, theta)
    valid = steps.valid.copy()
    valid[60] = False  # a gap: both sides restart from the observer's initial state
    steps = dataclasses.replace(steps, valid=valid)
    changed = _with(theta, "h_in", 1.4)
    s = energy_at_stake(model, steps, theta, changed)
    assert s.j_before_kwh == pytest.approx(_by_hand(model, steps, theta), rel=1e-6)
    assert s.j_now_kwh == pytest.approx(_by_hand(model, steps, changed), rel=1e-6)
    simulated_s = (steps.n_steps - 1) * steps.step_s
    assert s.per_week_kwh == pytest.approx(
        (s.j_now_kwh - s.j_before_kwh) * 7 * 86400.0 / simulated_s)


def _sun_times(steps: StepData, k: float) -> StepData:
    """The record with every solar term of the façade scaled by ``k`` (what dirt does)."""
    inp = steps.inputs
    return dataclasses.replace(steps, inputs=inp._replace(
        sources=np.asarray(inp.sources) * k, q_trans_wm2=np.asarray(inp.q_trans_wm2) * k,
        q_da_w=np.asarray(inp.q_da_w) * k))


def test_no_change_of_the_sun_puts_nothing_at_stake(suwon):
    theta = true_theta(suwon)
    model, steps = _record(suwon, theta)
    s = solar_energy_at_stake(model, steps, theta, 0.0)
    assert s.j_now_kwh == s.j_before_kwh and s.per_week_kwh == 0.0


def test_the_sun_given_back_is_the_record_stepped_by_hand_with_more_sun(suwon):
    """"Before" a tenth less sun is the record with every solar term ×1.1, stepped by hand
    (the observer's one-step path); "now" is the record as it is."""
    theta = true_theta(suwon)
    model, steps = _record(suwon, theta)
    s = solar_energy_at_stake(model, steps, theta, -0.1)
    assert s.j_now_kwh == pytest.approx(_by_hand(model, steps, theta), rel=1e-6)
    assert s.j_before_kwh == pytest.approx(_by_hand(model, _sun_times(steps, 1.1), theta),
                                           rel=1e-6)


def test_in_heating_lost_sun_costs_no_more_than_the_sun_the_facade_lost(suwon):
    """A winter morning (heating throughout): a tenth less sun costs heat, and at most the
    tenth of what the façade took (absorbed in its layers, transmitted, and the daylight
    benefit): the room cannot gain more from the sun than the façade received."""
    theta = true_theta(suwon)
    model, steps = _record(suwon, theta)
    assert all(is_heating(model.cfg.control, float(t)) for t in steps.inputs.t_out_k)
    s = solar_energy_at_stake(model, steps, theta, -0.1)
    area_m2 = suwon.facade.width_m * suwon.facade.glazed_height_m
    inp = steps.inputs
    taken_j = ((np.asarray(inp.sources).sum(axis=1) + np.asarray(inp.q_trans_wm2)) * area_m2
               + np.asarray(inp.q_da_w)).sum() * steps.step_s
    lost_kwh = s.j_now_kwh - s.j_before_kwh
    assert 0.0 < lost_kwh <= 0.1 * taken_j / 3.6e6
