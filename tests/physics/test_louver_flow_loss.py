"""The louver's flow loss K_L(φ) in the lumped model: where it acts and where it does not."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from dsfd.config import load_panel
from dsfd.config.parameters import Param
from dsfd.physics.airflow import louver_flow_loss, louver_series_factor
from dsfd.physics.constants import R_AIR, T_ZERO
from dsfd.physics.forcing import FacadeOptics, Forcing, OpticalLoads, step_inputs
from dsfd.physics.model import LumpedModel
from tests.conftest import PANELS

ANGLES_DEG = np.array([0.0, 36.0, -72.0, 90.0])


def _night(n_angles: int) -> Forcing:
    """A still winter night (0 °C out, 22 °C room), one step per louver angle."""
    one = np.ones(n_angles)
    return Forcing(time_s=0 * one, t_out_k=T_ZERO * one, t_in_k=(22.0 + T_ZERO) * one,
                   t_mrt_k=(22.0 + T_ZERO) * one, t_rad_out_k=T_ZERO * one,
                   p_atm_pa=101325.0 * one, wind_ms=0 * one, cp_bottom=0.3 * one,
                   cp_top=0.3 * one, zenith_deg=90.0 * one, azimuth_deg=180.0 * one,
                   aoi_deg=90.0 * one, profile_deg=0 * one, beam_wm2=0 * one,
                   diffuse_wm2=0 * one, ghi_wm2=0 * one, dni_wm2=0 * one, dhi_wm2=0 * one,
                   ground_wm2=0 * one)


def _with_loss(cfg, on: bool):
    return dataclasses.replace(cfg, model=dataclasses.replace(cfg.model, louver_flow_loss=on))


def _speeds(cfg, regime: int, theta: np.ndarray) -> np.ndarray:
    """Cavity speed [m/s] of one step per angle of ANGLES_DEG from the same state."""
    return _steps(cfg, regime, theta).v_cav_ms


def _steps(cfg, regime: int, theta: np.ndarray):
    """One model step per angle of ANGLES_DEG from the same state (a StepResult)."""
    model = LumpedModel(cfg)
    f = _night(len(ANGLES_DEG))
    loads = FacadeOptics(cfg).loads(f, np.radians(ANGLES_DEG))
    inp = step_inputs(f, loads)
    # one step per angle: take the diagonal (angle i at step i)
    i = np.arange(len(ANGLES_DEG))
    inp = inp._replace(**{k: np.asarray(getattr(inp, k))[i, i] for k in OpticalLoads._fields})
    x = np.array([[5.0, 12.0, 19.0, 10.0, 10.0, 15.5]]) + T_ZERO
    x = np.repeat(x, len(ANGLES_DEG), axis=0)
    return model.step(x, np.full(len(i), regime), 1.0, inp, theta)


def _k_l(cfg) -> np.ndarray:
    """K_L(φ) [-] of the panel's louver at each angle of ANGLES_DEG."""
    lv, fac = cfg.louver, cfg.facade
    return louver_flow_loss(np.radians(ANGLES_DEG), depth_m=fac.cavity_depth_m,
                            slat_width_m=lv.slat_width_m, slat_pitch_m=lv.slat_pitch_m,
                            height_m=fac.glazed_height_m)


@pytest.fixture(scope="module")
def suwon_loss(suwon):
    return _with_loss(suwon, True)


def test_the_loss_is_the_form_loss_it_adds_to(suwon):
    # K_L on top of f is the same path as a model without K_L whose f is f + K_L(φ)
    theta = LumpedModel(suwon).default_theta()
    on = _speeds(_with_loss(suwon, True), 1, theta)
    k_l = _k_l(suwon)
    off_cfg = _with_loss(suwon, False)
    for j, k in enumerate(k_l):
        th = theta.copy()
        th[Param.F] += k
        assert _speeds(off_cfg, 1, th)[j] == pytest.approx(on[j], rel=1e-9)
    assert k_l[0] > 1.0 and k_l[-1] == pytest.approx(0.0, abs=1e-12)


def test_horizontal_slats_slow_the_stack_flow_and_closed_ones_do_not(suwon_loss, suwon):
    theta = LumpedModel(suwon).default_theta()
    on = np.abs(_speeds(suwon_loss, 1, theta))
    off = np.abs(_speeds(_with_loss(suwon, False), 1, theta))
    assert on[0] < on[1] < on[3]           # |cos φ| 1 > 0.81 > 0: less free section, slower
    assert on[3] == pytest.approx(off[3], rel=1e-9)
    assert np.all(on[:3] < off[:3])


@pytest.mark.parametrize("regime", [5, 6, 7, 8])
def test_power_law_regimes_have_the_slats_in_series(suwon, regime):
    # With n = 0.5 the power law is a quadratic loss ΔP = Q²/c², and two quadratic losses in
    # series add: a model without the slats' loss whose c is 1/sqrt(1/c² + ρ_c K_L/(2 A_c²))
    # carries the same flow (ρ_c of the cavity air the coupling converged to).
    theta = LumpedModel(suwon).default_theta()
    theta[Param.N] = 0.5
    on_cfg, off_cfg = _with_loss(suwon, True), _with_loss(suwon, False)
    on = _speeds(on_cfg, regime, theta)
    model = LumpedModel(on_cfg)
    a_c = model.geom.cavity_area_m2
    x5_end = _steps(on_cfg, regime, theta).x_next[:, 4]
    rho_c = 101325.0 / (R_AIR * x5_end)
    for j, k in enumerate(_k_l(suwon)):
        th = theta.copy()
        th[Param.C] = 1.0 / np.sqrt(1.0 / theta[Param.C] ** 2 + rho_c[j] * k / (2 * a_c**2))
        assert _speeds(off_cfg, regime, th)[j] == pytest.approx(on[j], rel=1e-5)
    off = _speeds(off_cfg, regime, theta)
    assert np.all(np.abs(on[:3]) < np.abs(off[:3]))  # the slats' loss slows the path
    assert on[3] == pytest.approx(off[3], rel=1e-9)  # vertical slats (K_L = 0) do not


@pytest.mark.parametrize("n", [0.5, 0.6, 0.8, 1.0])
def test_series_factor_solves_the_series_path(n):
    # Independent reference: the root of (Q/c)^(1/n) + ρ β Q² = ΔP by bisection (brentq)
    rho, beta = 1.2, 3.4 / (2 * 0.5**2)
    for c in (0.002, 0.05, 0.12, 0.5):
        for dp in np.geomspace(0.02, 20.0, 12):
            q = c * dp**n
            exact = brentq(lambda qq, c=c, dp=dp: (qq / c) ** (1 / n) + rho * beta * qq * qq - dp,
                           0.0, q, xtol=1e-16, rtol=1e-14)
            s = float(louver_series_factor(np.array(q), np.array(dp), n, rho, beta))
            assert s * q == pytest.approx(exact, rel=3e-5)
            # the reverse direction is the mirror image
            assert float(louver_series_factor(np.array(-q), np.array(-dp), n, rho, beta)) == s


def test_series_factor_is_one_without_slats_or_flow():
    q = np.array([0.0, 1e-9, 0.05])
    dp = np.array([0.0, 1e-8, 2.0])
    np.testing.assert_array_equal(louver_series_factor(q, dp, 0.6, 1.2, 0.0), 1.0)
    assert louver_series_factor(np.array(0.0), np.array(0.0), 0.6, 1.2, 6.8) == 1.0


def test_a_panel_without_louver_has_no_slat_loss():
    cfg = load_panel(PANELS / "suwon-south-no-louver.yaml")
    f = _night(3)
    loads = FacadeOptics(cfg).loads(f, np.radians([0.0, 45.0, 90.0]))
    assert np.all(loads.cavity_loss == 0.0)
