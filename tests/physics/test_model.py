"""The coupled lumped model: invariants, magnitudes and the coupling (docs/model.md#coupling,
docs/model.md#departures)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.config import load_panel
from dsfd.config.parameters import Param
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import FacadeOptics, Forcing, OpticalLoads, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.sim.openloop import run_lumped, summarize
from dsfd.sim.replay import load_weather
from tests.conftest import PANELS


def _forcing(*, t_out=0.0, t_in=22.0, beam=0.0, diffuse=0.0, wind=0.0, sky_drop=0.0,
             n=1) -> Forcing:
    """Constant façade boundary (°C, W/m2) at the winter-noon sun of
    docs/model.md#solar-geometry."""
    one = np.ones(n)
    return Forcing(time_s=0 * one, t_out_k=(t_out + T_ZERO) * one, t_in_k=(t_in + T_ZERO) * one,
                   t_mrt_k=(t_in + T_ZERO) * one, t_rad_out_k=(t_out - sky_drop + T_ZERO) * one,
                   p_atm_pa=101325.0 * one, wind_ms=wind * one, cp_bottom=0.3 * one,
                   cp_top=0.3 * one, zenith_deg=59.18 * one, azimuth_deg=168.79 * one,
                   aoi_deg=32.6 * one, profile_deg=31.3 * one, beam_wm2=beam * one,
                   diffuse_wm2=diffuse * one, ghi_wm2=0 * one, dni_wm2=0 * one,
                   dhi_wm2=0 * one, ground_wm2=0.5 * diffuse * one)  # uniform radiance


@pytest.fixture(scope="module")
def model(suwon):
    return LumpedModel(suwon)


@pytest.fixture(scope="module")
def optics(suwon):
    return FacadeOptics(suwon)


@pytest.mark.parametrize("regime", range(1, 11))
def test_no_sun_steady_state_lies_between_outdoor_and_room(model, optics, regime):
    """Maximum principle: without sources every node lies between the boundary temperatures.

    The exterior radiant temperature is set to T_out (no sky cooling), so the only
    boundary temperatures are 0 °C (outdoor) and 22 °C (room) for every regime.
    """
    f = _forcing(wind=3.0)
    inp = step_inputs(f, optics.loads(f, np.radians(np.array([0.0, 54.0, -90.0]))))
    inp = inp._replace(**{k: getattr(inp, k)[:, 0] for k in OpticalLoads._fields})
    x = model.steady_state(np.full(3, regime), 1.0, inp, model.default_theta())
    assert np.all(x >= T_ZERO - 1e-6) and np.all(x <= T_ZERO + 22.0 + 1e-6)
    # Steady means steady: one more step changes nothing.
    res = model.step(x, np.full(3, regime), 1.0, inp, model.default_theta())
    np.testing.assert_allclose(res.x_next, x, atol=1e-3)


def test_energy_balance_closes_over_a_real_day(suwon):
    """docs/model.md#energy-balance over the SURFRAD day: ΔU = ∫(S + boundary flows) dt to
    round-off."""
    series = load_weather("surfrad-alamosa-2016-01-01")
    for afr in (1, 3, 7, 9, 10):
        s = summarize(run_lumped(suwon, series, phi_deg=18.0, afr=afr, or_pct=60.0))
        eb = s["energy_balance"]
        assert eb["residual_rel"] < 1e-9, afr
        assert abs(eb["stored_j"]) > 0


def test_regime_ten_has_no_flow_and_no_air_gain(model, optics):
    f = _forcing(beam=600.0, diffuse=150.0, wind=5.0)
    inp = step_inputs(f, optics.loads(f, 0.0))
    th = model.default_theta()
    x = model.steady_state([10], 1.0, inp, th)
    res = model.step(x, [10], 1.0, inp, th)
    assert np.all(res.flow.m_dot == 0) and res.q_air_w[0] == 0 and res.v_cav_ms[0] == 0
    for afr in (3, 4):  # outside circulation: no air exchange with the room
        res = model.step(x, [afr], 1.0, inp, th)
        assert res.q_air_w[0] == 0 and abs(res.v_cav_ms[0]) > 0


def test_winter_sun_magnitudes_of_physics_8_5(model, optics):
    """docs/model.md#airflow [PROTO] case, within a factor 1.5: T_o 0 °C, T_i 22 °C, I_b 600, I_d
    150 W/m2.

    Regime 1 with f = 85: v 0.11–0.16 m/s, cavity air 28–35 °C, louver 36–61 °C over the
    louver angles; regime 10: cavity ≈ 67 °C, louver ≈ 82 °C (docs/model.md#parameters: 66.5 / 84
    °C).
    """
    f = _forcing(beam=600.0, diffuse=150.0, wind=1.0, sky_drop=12.0)
    angles = np.radians(np.array([-45.0, 0.0, 30.0, 60.0]))
    inp = step_inputs(f, optics.loads(f, angles))
    inp = inp._replace(**{k: getattr(inp, k)[:, 0] for k in OpticalLoads._fields})
    th = model.default_theta().copy()
    th[Param.F] = 85.0
    x1 = model.steady_state(np.ones(4, int), 1.0, inp, th)
    v = model.step(x1, np.ones(4, int), 1.0, inp, th).v_cav_ms
    assert 0.11 / 1.5 <= v.min() and v.max() <= 0.16 * 1.5
    t5, t4 = x1[:, 4] - T_ZERO, x1[:, 3] - T_ZERO
    assert 28 / 1.5 <= t5.min() and t5.max() <= 35 * 1.5
    assert 36 / 1.5 <= t4.min() and t4.max() <= 61 * 1.5
    x10 = model.steady_state(np.full(4, 10), 1.0, inp, th) - T_ZERO
    closed_t5 = x10[1, 4]  # φ = 0
    assert 67 / 1.5 <= closed_t5 <= 67 * 1.5
    assert 82 / 1.5 <= x10[1, 3] <= 82 * 1.5
    # A closed sunny cavity is far hotter than an open one, at every louver angle.
    assert np.all(x10[:, 4] > t5 + 10)


def _run_diagonal_supply(cfg, steps=40):
    m = LumpedModel(cfg)
    opt = FacadeOptics(cfg)
    f = _forcing(beam=150.0, diffuse=60.0, wind=0.0)
    inp = step_inputs(f, opt.loads(f, 0.0))
    x = np.full((1, 6), 22.0 + T_ZERO)
    v = []
    for _ in range(steps):
        r = m.step(x, [7], 1.0, inp, m.default_theta())
        x = r.x_next
        v.append(r.v_cav_ms[0])
    return np.array(v)


def test_chattering_case_gives_non_oscillating_flow(suwon):
    """docs/model.md#departures item 8 (regime 7 after docs/model.md#regimes: out → EB
    ↑ → IT → room), T_o 0, T_i 22, weak sun.

    The default implicit coupling gives a smooth flow; the paper's ping-pong at 60 s
    flips direction every step (the instability the spec warns about).
    """
    v = _run_diagonal_supply(suwon)[10:]
    assert np.all(np.sign(v) == np.sign(v[-1]))
    assert np.max(np.abs(np.diff(v))) < 0.005
    pp = dataclasses.replace(suwon, model=dataclasses.replace(suwon.model, coupling="ping_pong"))
    v_pp = _run_diagonal_supply(pp)[10:]
    assert np.sum(np.diff(np.sign(v_pp)) != 0) > 10


def test_batched_step_equals_single_steps(model, optics):
    f = _forcing(beam=300.0, diffuse=100.0, wind=2.0, sky_drop=10.0)
    rng = np.random.default_rng(4)
    n = 12
    phi = np.radians(rng.choice(np.arange(-90, 91, 18), n).astype(float))
    inp_all = step_inputs(f, optics.loads(f, phi))
    regimes = rng.integers(1, 11, n)
    ors = rng.uniform(0.1, 1, n)
    x = rng.uniform(270, 320, (n, 6))
    th = model.default_theta()
    flat = inp_all._replace(**{k: getattr(inp_all, k)[:, 0] for k in OpticalLoads._fields})
    batch = model.step(x, regimes, ors, flat, th)
    for i in range(n):
        one = flat._replace(**{k: getattr(flat, k)[i] for k in OpticalLoads._fields})
        single = model.step(x[i:i + 1], [regimes[i]], [ors[i]], one, th)
        np.testing.assert_allclose(single.x_next[0], batch.x_next[i], atol=1e-5)
        np.testing.assert_allclose(single.flow.m_dot[0], batch.flow.m_dot[i], atol=1e-7)


def test_expm_option_matches_eigen_route(suwon):
    series = load_weather("surfrad-alamosa-2016-01-01")
    slow = dataclasses.replace(suwon, model=dataclasses.replace(suwon.model, zoh="expm"))
    a = run_lumped(suwon, series, phi_deg=0.0, afr=1, or_pct=100.0, hours=2)
    b = run_lumped(slow, series, phi_deg=0.0, afr=1, or_pct=100.0, hours=2)
    np.testing.assert_allclose(a.trajectory.x, b.trajectory.x, atol=1e-5)


def test_panel_without_louver_runs_and_ignores_louver_angle():
    cfg = load_panel(PANELS / "suwon-south-no-louver.yaml")
    series = load_weather("surfrad-alamosa-2016-01-01")
    a = run_lumped(cfg, series, phi_deg=0.0, afr=3, or_pct=100.0, hours=6)
    b = run_lumped(cfg, series, phi_deg=72.0, afr=3, or_pct=100.0, hours=6)
    np.testing.assert_allclose(a.trajectory.x, b.trajectory.x, atol=1e-9)
    # Without a louver the node x4 follows the cavity air.
    x = a.trajectory.x[0]
    assert np.max(np.abs(x[:, 3] - x[:, 4])) < 0.2
