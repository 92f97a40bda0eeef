"""The exponential cavity-air profile (ISO 15099 ventilated gap) of the lumped x5 balance.

References independent of the closed form: the profile ODE integrated numerically, the
limits of a well-mixed node and of a linear profile, and the energy balance of the network.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from dsfd.config.parameters import Param
from dsfd.physics.cavity_profile import outlet_excess_ratio, probe_excess_ratio
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import FacadeOptics, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.physics.slat_film import film_factor
from tests.physics.test_louver_flow_loss import _night


def _k_by_ode(a: float) -> float:
    """k from dT/dz = (T_av − T)/H0 (H0 = 1, height a) and the running integral of T."""
    sol = solve_ivp(lambda z, y: [1.0 - y[0], y[0]], (0.0, a), [0.0, 0.0],
                    rtol=1e-11, atol=1e-14, method="DOP853")
    outlet, integral = sol.y[0, -1], sol.y[1, -1]
    return outlet / (integral / a)


@pytest.mark.parametrize("a", [1e-4, 5e-3, 0.02, 0.3, 1.0, 3.0, 20.0])
def test_ratio_matches_the_integrated_profile(a):
    assert float(outlet_excess_ratio(a)) == pytest.approx(_k_by_ode(a), rel=1e-7)


def test_ratio_limits_and_shape():
    a = np.geomspace(1e-8, 1e3, 400)
    k = outlet_excess_ratio(a)
    assert np.all(np.diff(k) < 0)  # more transfer units, more nearly well mixed
    assert float(outlet_excess_ratio(0.0)) == 2.0  # linear profile
    assert float(outlet_excess_ratio(np.inf)) == 1.0  # no flow: well mixed
    assert float(outlet_excess_ratio(1e3)) == pytest.approx(1.0, abs=2e-3)
    # no step where the series hands over to the closed form
    lo, hi = outlet_excess_ratio([1e-2 * (1 - 1e-9), 1e-2])
    assert abs(lo - hi) < 1e-9


def _profiles(cfg):
    return {p: LumpedModel(dataclasses.replace(
        cfg, model=dataclasses.replace(cfg.model, cavity_air_profile=p)))
        for p in ("well_mixed", "exponential")}


def _one_step(cfg, regime: int):
    """One step per profile from a warm cavity on a still night: (model, inputs, x, result)."""
    f = _night(1)
    inp = step_inputs(f, FacadeOptics(cfg).loads(f, np.radians([0.0])))
    inp = inp._replace(**{k: np.asarray(getattr(inp, k))[0] for k in inp._fields})
    x = np.array([[5.0, 18.0, 20.0, 35.0, 30.0, 19.0]]) + T_ZERO  # cavity above the room
    out = {}
    for name, model in _profiles(cfg).items():
        out[name] = (model, inp, x, model.step(x, np.array([regime]), 1.0, inp,
                                               model.default_theta()))
    return out


@pytest.mark.parametrize("regime", [1, 3])
def test_step_conserves_energy_with_either_profile(suwon, regime):
    # ΔU over the step equals the boundary heat at the exact step mean
    # (docs/model.md#energy-balance), whichever outlet temperature the x5 balance uses.
    for model, _, x, res in _one_step(suwon, regime).values():
        du = (model.capacity * (res.x_next - x)).sum() / model.nc.dt
        assert du == pytest.approx(float(res.heat_in_wm2[0]), rel=1e-6, abs=1e-6)


def _surface_over_flow(model: LumpedModel, res, m_in: float) -> float:
    """a = (h_ca1 + a_L h_ca2 F(v) + h_ca3)/(c_p ṁ/A_f) of a step from the default θ, F the
    slat film's factor at the step's cavity speed (docs/model.md#slat-film)."""
    theta, nc = model.default_theta(), model.nc
    film = film_factor(res.v_cav_ms, equal_speed_ms=nc.slat_film_equal_ms,
                       reference_speed_ms=nc.slat_film_reference_ms)[0]
    assert nc.slat_film_equal_ms > 0 and film != pytest.approx(1.0)
    return float((theta[Param.H_CA1] + nc.slat_area_ratio * theta[Param.H_CA2] * film
                  + theta[Param.H_CA3]) / (nc.cp_air * m_in / nc.geom.facade_area_m2))


def test_room_gets_the_heat_the_flow_takes_from_the_cavity(suwon):
    # Regime 1 exhausts cavity air into the room and draws room air in. Q_air is c_p ṁ times
    # the outlet's excess over the room: x̄5 − T_i when well mixed, k(a) times that with the
    # profile, a = (h_ca1 + a_L h_ca2 F(v) + h_ca3)/(c_p ṁ/A_f) (_surface_over_flow).
    q = {}
    for name, (model, inp, _, res) in _one_step(suwon, 1).items():
        m_in = float(np.clip(res.flow.m_dot, 0, None).sum())
        assert m_in > 0
        a = _surface_over_flow(model, res, m_in)
        k = 1.0 if name == "well_mixed" else float(outlet_excess_ratio(a))
        excess = float(res.x_mean[0, 4] - inp.t_in_k)
        q[name] = float(res.q_air_w[0])
        assert q[name] == pytest.approx(model.nc.cp_air * m_in * k * excess, rel=1e-9)
        assert 1.0 < float(outlet_excess_ratio(a)) < 2.0
    # a hotter outlet for the same kind of step: the room gets more of the cavity's heat
    assert q["exponential"] > q["well_mixed"] > 0


@pytest.mark.parametrize("a", [1e-4, 5e-3, 0.02, 0.5, 2.0, 4.4, 10.0, 40.0])
@pytest.mark.parametrize("zeta", [0.25, 0.5, 0.8])
def test_the_probe_reads_the_profile_at_its_height(a, zeta):
    """p(a) against the profile itself: excess at ζ over the excess of a numerically
    averaged column (midpoint rule, 20 000 slices), independent of the closed form."""
    z = (np.arange(20_000) + 0.5) / 20_000
    excess = 1.0 - np.exp(-a * z)  # T(z) − T_in over T_av − T_in
    expected = (1.0 - np.exp(-a * zeta)) / excess.mean()
    assert probe_excess_ratio(a, zeta) == pytest.approx(expected, rel=1e-6)


def test_the_mid_height_probe_limits():
    assert probe_excess_ratio(0.0) == pytest.approx(1.0)  # linear profile: mid = mean
    assert probe_excess_ratio(np.inf) == 1.0  # well mixed
    a = np.linspace(0.01, 30.0, 3000)
    p = probe_excess_ratio(a)
    assert np.all(p >= 1.0) and p.max() == pytest.approx(1.1466, abs=1e-3)
    assert probe_excess_ratio(3.0, 1.0) == pytest.approx(outlet_excess_ratio(3.0))


def test_the_model_reads_its_probe_where_the_air_crosses_the_cavity(suwon):
    """x5_probe_k = T_in + p(a)(x5 − T_in) in a through-cavity regime (7: outdoor air in at
    the exterior bottom, out at the interior top, or the reverse where the stack wins), with
    a and T_in from the step's own flow;
    the reading is x5 itself where the air runs along one side (1) or without flow (10)."""
    mid = dataclasses.replace(suwon, model=dataclasses.replace(
        suwon.model, cavity_air_probe="mid_height"))
    for regime in (7, 1, 10):
        model, inp, _, res = _one_step(mid, regime)["exponential"]
        x5, probe = float(res.x_next[0, 4]), float(res.x5_probe_k[0])
        if regime != 7:
            assert probe == x5
            continue
        m_in = float(np.clip(res.flow.m_dot, 0, None).sum())
        assert m_in > 0
        a = _surface_over_flow(model, res, m_in)
        # supply air comes from outdoors; reversed by the stack, the room's air comes in
        t_in = float(inp.t_out_k if res.flow.m_dot[0, 0] > 0 else inp.t_in_k)
        assert probe == pytest.approx(t_in + float(probe_excess_ratio(a)) * (x5 - t_in),
                                      rel=1e-9)
        assert abs(probe - x5) > 0.05  # the correction is there, not a rounding
