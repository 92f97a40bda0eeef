"""Objective signs, move penalty, persistence forecast and the rule-based baseline."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.config import load_panel
from dsfd.control.baseline import quantise_louver, rule_decision
from dsfd.control.forecast import persistence_forecast
from dsfd.control.objective import horizon_cost, is_heating, louver_move_penalty
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import WeatherInputs
from dsfd.physics.model import Trajectory
from dsfd.physics.solar import solar_position
from tests.conftest import PANELS


def _traj(cv, sol, air, da):
    z = np.zeros((1, 2))

    def full(v):
        return np.full((1, 2), float(v))

    return Trajectory(x=np.zeros((1, 3, 6)), x_mean=np.zeros((1, 2, 6)),
                      m_dot=np.zeros((1, 2, 4)), label=np.ones((1, 2), int), v_cav_ms=z,
                      q_cv_rd_w=full(cv), q_sol_w=full(sol), q_air_w=full(air),
                      q_da_w=full(da), heat_in_wm2=z, evaluations=np.ones((1, 2), int),
                      x5_probe=np.zeros((1, 2)))


def test_objective_signs_follow_eq_4_and_5():
    tr = _traj(cv=-100.0, sol=300.0, air=50.0, da=20.0)
    heat = horizon_cost(tr, dt=60.0, heating=True)
    cool = horizon_cost(tr, dt=60.0, heating=False)
    gains = (-100 + 300 + 50) * 120.0
    assert heat.cost_j[0] == pytest.approx(-(gains + 20 * 120.0))
    assert cool.cost_j[0] == pytest.approx(gains - 20 * 120.0)
    # More solar gain is better when heating and worse when cooling.
    more = _traj(cv=-100.0, sol=400.0, air=50.0, da=20.0)
    assert horizon_cost(more, dt=60.0, heating=True).cost_j < heat.cost_j
    assert horizon_cost(more, dt=60.0, heating=False).cost_j > cool.cost_j


def test_mode_and_move_penalty(suwon):
    assert is_heating(suwon.control, T_ZERO + 5.0)
    assert not is_heating(suwon.control, T_ZERO + 25.0)
    fixed = dataclasses.replace(suwon.control, mode="cooling")
    assert not is_heating(fixed, T_ZERO - 5.0)
    pen = louver_move_penalty(np.array([0.0, 36.0, -90.0]), 0.0, penalty_wh=2.0, step_deg=18.0)
    np.testing.assert_allclose(pen, [0.0, 2 * 2 * 3600, 5 * 2 * 3600])
    assert np.all(louver_move_penalty(np.array([36.0]), None, penalty_wh=2.0,
                                      step_deg=18.0) == 0)


def test_persistence_forecast_follows_the_sun():
    """Held clearness index: a morning forecast rises with the sun, a night one stays dark."""
    lat, lon = 37.3, 127.0
    morning = 1451602800.0 + 0.5 * 3600  # 2016-01-01 08:30 KST ≈ 1 h after sunrise
    sun = solar_position(np.array([morning]), lat, lon)
    assert 0 < 90 - sun.zenith_deg[0] < 15

    def last(t, ghi):
        one = np.array([1.0])
        return WeatherInputs(time_s=t * one, t_out_k=270.0 * one, ghi_wm2=ghi * one,
                             dni_wm2=np.nan * one, dhi_wm2=np.nan * one,
                             wind_speed_ms=2.0 * one, wind_dir_deg=180.0 * one,
                             pressure_pa=101325.0 * one, t_in_k=295.0 * one,
                             t_mrt_k=295.0 * one, t_dew_k=np.nan * one)

    fc = persistence_forecast(last(morning, 150.0), latitude_deg=lat, longitude_deg=lon,
                              start_s=morning, step_s=60.0, n_steps=15)
    assert np.all(np.diff(fc.ghi_wm2) > 0)
    assert np.all(fc.t_out_k == 270.0)
    night = persistence_forecast(last(morning - 6 * 3600, 0.0), latitude_deg=lat,
                                 longitude_deg=lon, start_s=morning - 6 * 3600, step_s=60.0,
                                 n_steps=15)
    assert np.all(night.ghi_wm2 == 0.0)


def test_rule_baseline(suwon):
    sunny = dict(t_in_c=22.0, t_out_c=0.0, beam_wm2=500.0, profile_deg=31.0)
    d = rule_decision(suwon, heating=True, t5_c=35.0, **sunny)
    assert (d.phi_deg, d.afr, d.or_pct) == (36.0, 1, 100.0)
    d = rule_decision(suwon, heating=True, t5_c=23.0, **sunny)
    assert (d.afr, d.or_pct) == (10, 0.0)
    # Hysteresis: once open, stays open down to margin − hysteresis above the room.
    d = rule_decision(suwon, heating=True, t5_c=23.5, previous_afr=1, **sunny)
    assert d.afr == 1
    night = rule_decision(suwon, heating=True, t5_c=15.0, t_in_c=22.0, t_out_c=-5.0,
                          beam_wm2=0.0, profile_deg=0.0)
    assert (night.phi_deg, night.afr) == (90.0, 10)
    cool = rule_decision(suwon, heating=False, t5_c=40.0, t_in_c=24.0, t_out_c=28.0,
                         beam_wm2=500.0, profile_deg=60.0)
    assert cool.afr == 3 and cool.phi_deg == -36.0  # blocks the beam
    blind = rule_decision(suwon, heating=True, t5_c=None, **sunny)
    assert blind.afr == 10 and any("unusable" in t for t in blind.trace)


def test_baseline_respects_missing_dampers():
    cfg = load_panel(PANELS / "suwon-south.yaml")
    only_outside = dataclasses.replace(cfg.openings, interior_bottom=None, interior_top=None)
    cfg = dataclasses.replace(cfg, openings=only_outside)
    d = rule_decision(cfg, heating=True, t5_c=40.0, t_in_c=22.0, t_out_c=0.0, beam_wm2=500.0,
                      profile_deg=31.0)
    assert d.afr == 10 and any("lacks" in t for t in d.trace)


def test_louver_quantisation(suwon):
    assert quantise_louver(31.0, suwon.louver) == 36.0
    assert quantise_louver(-100.0, suwon.louver) == -90.0
    assert quantise_louver(8.0, suwon.louver) == 0.0
