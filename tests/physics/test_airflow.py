"""Airflow: closed forms vs the one-node solver, regimes, reversal, magnitudes
(docs/model.md#airflow)."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.physics.airflow import (
    EB,
    ET,
    IB,
    IT,
    AirflowBoundary,
    AirflowGeometry,
    air_density,
    boundary_state,
    opening_resistance,
    orifice_path_mass_flow,
    path_pressure,
    regularised_power,
)
from dsfd.physics.constants import GRAVITY
from dsfd.physics.one_node import _warm_rows, one_node_flows
from dsfd.physics.regimes import regime_flows


@pytest.fixture(scope="module")
def geom(suwon):
    return AirflowGeometry.from_sections(suwon.openings, suwon.facade)


def _bnd(t_out_c, t_in_c, wind, cp_b, cp_t, n=None):
    vals = [np.asarray(v, float) + 0.0 for v in (t_out_c, t_in_c)]
    return AirflowBoundary(vals[0] + 273.15, vals[1] + 273.15, np.full_like(vals[0], 101325.0),
                           np.asarray(wind, float), np.asarray(cp_b, float),
                           np.asarray(cp_t, float))


def test_one_node_solver_equals_corrected_closed_form(geom):
    """docs/model.md#path-flows: with two open orifices the one-node solver reproduces the closed
    form."""
    rng = np.random.default_rng(1)
    n = 400
    t_out = rng.uniform(-15, 35, n)
    t_in = rng.uniform(18, 26, n)
    t5 = rng.uniform(-10, 70, n) + 273.15
    wind = rng.uniform(0, 8, n)
    cp_b, cp_t = rng.uniform(-0.7, 0.7, n), rng.uniform(-0.7, 0.7, n)
    or_ = rng.uniform(0.05, 1, n)
    f = np.exp(rng.uniform(np.log(5), np.log(1e4), n))
    bnd = _bnd(t_out, t_in, wind, cp_b, cp_t)
    p_b, rho_b, _ = boundary_state(bnd, geom)
    rho_c = air_density(t5, bnd.p_atm_pa)
    k_all = opening_resistance(or_, f, geom)
    checked = 0
    for inlet, outlet in ((IB, IT), (EB, ET), (IB, ET), (IT, EB)):
        dp = path_pressure(p_b, geom.z_m, rho_c, inlet, outlet)
        fwd = dp >= 0
        rho_in = np.where(fwd, rho_b[:, inlet], rho_b[:, outlet])
        k_up = np.where(fwd, k_all[:, inlet], k_all[:, outlet])
        k_dn = np.where(fwd, k_all[:, outlet], k_all[:, inlet])
        closed = orifice_path_mass_flow(dp, k_up, k_dn, rho_in, rho_c, geom.dp_reg_pa)
        k_two = np.full_like(k_all, np.inf)
        k_two[:, inlet] = k_all[:, inlet]
        k_two[:, outlet] = k_all[:, outlet]
        m = one_node_flows(p_b, rho_b, geom.z_m, k_two, rho_c, geom.dp_reg_pa).m_dot
        # Outside the regularised band of both openings the two must agree exactly.
        drop_in = k_up * closed**2 / (2 * rho_in)
        drop_out = k_dn * closed**2 / (2 * rho_c)
        ok = (drop_in > 2 * geom.dp_reg_pa) & (drop_out > 2 * geom.dp_reg_pa)
        assert ok.sum() > 50
        np.testing.assert_allclose(m[ok, inlet], closed[ok], rtol=0, atol=1e-10)
        np.testing.assert_allclose(m[ok, outlet], -closed[ok], rtol=0, atol=1e-10)
        checked += ok.sum()
    assert checked > 400


def _random_cavities(geom, seed: int, or_min: float, n: int = 200):
    """Boundary pressures and densities, cavity densities and loss coefficients of ``n``
    random all-open cavities (openings from ``or_min`` to fully open)."""
    rng = np.random.default_rng(seed)
    bnd = _bnd(rng.uniform(-10, 30, n), 22.0 + 0 * rng.uniform(size=n), rng.uniform(0, 10, n),
               rng.uniform(-0.6, 0.7, n), rng.uniform(-0.7, 0.8, n))
    p_b, rho_b, _ = boundary_state(bnd, geom)
    rho_c = air_density(rng.uniform(260, 340, n), bnd.p_atm_pa)
    k = opening_resistance(rng.uniform(or_min, 1, n), rng.uniform(5, 3000, n), geom)
    return p_b, rho_b, rho_c, k


def test_one_node_conserves_mass_and_is_monotone(geom):
    p_b, rho_b, rho_c, k = _random_cavities(geom, seed=2, or_min=0.0)
    m, p_c, *_ = one_node_flows(p_b, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa)
    np.testing.assert_allclose(m.sum(axis=1), 0.0, atol=1e-12)
    # Raising the cavity pressure can only reduce every inflow.
    head = p_b + rho_c[:, None] * GRAVITY * geom.z_m
    for dpc in (-0.5, 0.5):
        dp = head - (p_c + dpc)[:, None]
        rho_up = np.where(dp > 0, rho_b, rho_c[:, None])
        m2 = regularised_power(dp, np.sqrt(2 * rho_up / k), 0.5, geom.dp_reg_pa)
        assert np.all(np.sign(m2.sum(axis=1)) == -np.sign(dpc))


def test_one_node_pressure_tangent_matches_a_re_solve(geom):
    """dP_c/dρ_c from implicit differentiation equals the central difference of two full
    solves; it is the warm start of the coupling's re-solves, so a wrong sign or factor
    would only cost iterations, but a right one has to predict P_c to second order."""
    p_b, rho_b, rho_c, k = _random_cavities(geom, seed=4, or_min=0.05)
    sol = one_node_flows(p_b, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa, tol_kgs=1e-15)
    h = 1e-5 * rho_c
    up, down = (one_node_flows(p_b, rho_b, geom.z_m, k, rho_c + s * h, geom.dp_reg_pa,
                               tol_kgs=1e-15).p_c for s in (1, -1))
    central = (up - down) / (2 * h)
    # Outside the regularised band (where the law has a kink in curvature) the two agree.
    dp = p_b + rho_c[:, None] * GRAVITY * geom.z_m - sol.p_c[:, None]
    clear = np.abs(dp).min(axis=1) > 10 * geom.dp_reg_pa
    assert clear.sum() > 100
    np.testing.assert_allclose(sol.dpc_drho[clear], central[clear], rtol=1e-4)
    # Predicting P_c along the tangent is second-order accurate: a 1 % change in density
    # is predicted far better than by holding P_c.
    big = 0.01 * rho_c
    moved = one_node_flows(p_b, rho_b, geom.z_m, k, rho_c + big, geom.dp_reg_pa,
                           tol_kgs=1e-15).p_c
    tangent_err = np.abs(sol.p_c + sol.dpc_drho * big - moved)[clear]
    hold_err = np.abs(sol.p_c - moved)[clear]
    assert np.median(tangent_err) < 0.02 * np.median(hold_err)


def test_one_node_boundary_sensitivity_matches_a_re_solve(geom):
    """∂P_c/∂p_B,k (the next step's warm start when the wind or the temperatures change)
    equals the central difference of full solves, and its rows sum to 1: raising every
    boundary pressure by the same amount raises the cavity pressure by exactly that."""
    p_b, rho_b, rho_c, k = _random_cavities(geom, seed=5, or_min=0.05)
    sol = one_node_flows(p_b, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa, tol_kgs=1e-15)
    np.testing.assert_allclose(sol.dpc_dpb.sum(axis=1), 1.0, rtol=1e-12)
    dp = p_b + rho_c[:, None] * GRAVITY * geom.z_m - sol.p_c[:, None]
    clear = np.abs(dp).min(axis=1) > 10 * geom.dp_reg_pa
    assert clear.sum() > 100
    h = 1e-4
    for opening in range(4):
        up, down = (p_b.copy(), p_b.copy())
        up[:, opening] += h
        down[:, opening] -= h
        central = (one_node_flows(up, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa,
                                  tol_kgs=1e-15).p_c
                   - one_node_flows(down, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa,
                                    tol_kgs=1e-15).p_c) / (2 * h)
        np.testing.assert_allclose(sol.dpc_dpb[clear, opening], central[clear], rtol=1e-4,
                                   atol=1e-9)


@pytest.mark.parametrize("scalar_max_rows", [0, 1000])
def test_one_node_warm_start_lands_on_the_cold_solution(geom, scalar_max_rows):
    """From a warm start the solver may stop at a Newton point it has not evaluated (its
    flows moved along their tangents); that point must still balance the cavity within
    the tolerance and agree with a cold, tight solve. Starts from slightly off to far off
    (beyond an opening's zero-flow point, where the bracketed iteration takes over); the
    vectorised iteration (0) and the row-by-row one on Python floats (1000) alike."""
    p_b, rho_b, rho_c, k = _random_cavities(geom, seed=6, or_min=0.02)
    ref = one_node_flows(p_b, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa, tol_kgs=1e-15)
    rng = np.random.default_rng(7)
    tol = 1e-12  # tight, so that a far looser acceptance bound shows (1e4x, tried)
    for scale in (1e-6, 1e-3, 0.1, 3.0):
        start = ref.p_c + scale * rng.normal(size=ref.p_c.size)
        sol = one_node_flows(p_b, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa, tol_kgs=tol,
                             p_c_start=start, scalar_max_rows=scalar_max_rows)
        # Mass balance of the returned flows, and the flows the law gives at that pressure.
        assert np.abs(sol.m_dot.sum(axis=1)).max() <= tol
        np.testing.assert_allclose(sol.m_dot, ref.m_dot, rtol=0, atol=1e-6)
        head = p_b + rho_c[:, None] * GRAVITY * geom.z_m
        dp = head - sol.p_c[:, None]
        law = regularised_power(dp, np.sqrt(2 * np.where(dp > 0, rho_b, rho_c[:, None]) / k),
                                0.5, geom.dp_reg_pa)
        assert np.abs(law - sol.m_dot).max() <= 10 * tol


def test_one_node_scalar_warm_start_matches_the_vectorised_one(geom):
    """The row-by-row warm iteration gives the vectorised one's flows, pressure and
    sensitivities, row by row (it is used for the few all-open rows of a rollout)."""
    p_b, rho_b, rho_c, k = _random_cavities(geom, seed=8, or_min=0.02, n=60)
    ref = one_node_flows(p_b, rho_b, geom.z_m, k, rho_c, geom.dp_reg_pa, tol_kgs=1e-15)
    start = ref.p_c + 1e-4 * np.random.default_rng(9).normal(size=ref.p_c.size)
    used = 0
    for i in range(p_b.shape[0]):
        row = slice(i, i + 1)
        args = (p_b[row], rho_b[row], geom.z_m, k[row], rho_c[row], geom.dp_reg_pa)
        scalar = _warm_rows(*args, 1e-10, start[row])
        if scalar is None:  # not accepted within the step limit: the vectorised path solves
            continue
        used += 1
        vec = one_node_flows(*args, tol_kgs=1e-10, p_c_start=start[row], scalar_max_rows=0)
        for a, b in zip(scalar, vec, strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)
    assert used >= 50


def test_regime_ten_gives_zero_flow(geom):
    rng = np.random.default_rng(3)
    n = 100
    bnd = _bnd(rng.uniform(-20, 40, n), 22.0 + 0 * rng.uniform(size=n), rng.uniform(0, 20, n),
               rng.uniform(-1, 1, n), rng.uniform(-1, 1, n))
    fs = regime_flows(np.full(n, 10), rng.uniform(0, 1, n), rng.uniform(250, 350, n), bnd, geom,
                      f=100.0, c=0.05, n=0.6)
    assert np.all(fs.m_dot == 0.0)
    assert np.all(fs.label == 10)


@pytest.mark.parametrize("regime", [1, 2])
def test_inside_circulation_reverses_with_stack_pressure(geom, regime):
    """Cavity warmer than the room: up through IB → IT (label 1); colder: down (label 2)."""
    bnd = _bnd([0.0, 0.0], [22.0, 22.0], [3.0, 3.0], [0.5, 0.5], [0.1, 0.1])
    fs = regime_flows(np.array([regime, regime]), 1.0, np.array([35.0, 12.0]) + 273.15, bnd,
                      geom, f=100.0, c=0.05, n=0.6)
    assert list(fs.label) == [1, 2]
    assert fs.m_dot[0, IB] > 0 > fs.m_dot[0, IT]
    assert fs.m_dot[1, IT] > 0 > fs.m_dot[1, IB]
    assert fs.q_cav[0] > 0 > fs.q_cav[1]
    # Equal cavity and room temperature: no stack pressure, no flow (regime 1).
    still = regime_flows(np.array([regime]), 1.0, np.array([295.15]), _bnd(0.0, 22.0, 3.0, 0.5,
                                                                           0.1), geom,
                         f=100.0, c=0.05, n=0.6)
    assert still.m_dot[0, IB] == 0.0


def test_outside_circulation_reverses_with_wind(geom):
    """Regime 3 at T5 = T_o: only the wind pressure difference drives the flow
    (docs/model.md#departures)."""
    t5 = np.full(3, 5.0 + 273.15)
    bnd = _bnd(np.full(3, 5.0), np.full(3, 22.0), np.array([4.0, 4.0, 0.0]),
               np.array([0.6, 0.1, 0.6]), np.array([0.1, 0.6, 0.1]))
    fs = regime_flows(np.full(3, 3), 1.0, t5, bnd, geom, f=100.0, c=0.05, n=0.6)
    assert fs.label[0] == 3 and fs.m_dot[0, EB] > 0
    assert fs.label[1] == 4 and fs.m_dot[1, ET] > 0
    assert fs.m_dot[2, EB] == 0.0


def test_diagonal_numbering_follows_errata_e1(geom):
    """Regime 5 is exhaust room → IB ↑ → ET → out; a pressurised room favours it."""
    bnd = _bnd(0.0, 22.0, 0.0, 0.0, 0.0)
    geom_p = AirflowGeometry(**{**geom.__dict__, "room_pressure_pa": 5.0})
    ex = regime_flows(np.array([5]), 1.0, np.array([298.15]), bnd, geom_p, f=100.0, c=0.05,
                      n=0.6)
    assert ex.label[0] == 5
    assert ex.m_dot[0, IB] > 0 > ex.m_dot[0, ET]
    # The same damper set with the room depressurised supplies outdoor air (label 8).
    geom_n = AirflowGeometry(**{**geom.__dict__, "room_pressure_pa": -5.0})
    sup = regime_flows(np.array([5]), 1.0, np.array([298.15]), bnd, geom_n, f=100.0, c=0.05,
                       n=0.6)
    assert sup.label[0] == 8 and sup.m_dot[0, ET] > 0
    # Power law: Q = c·OR·|ΔP|^n exactly (ΔP_5 from docs/model.md#regimes, well above Δp_t).
    rho_o, rho_c, rho_i = (air_density(t, 101325.0) for t in (273.15, 298.15, 295.15))
    dp5 = 5.0 + (rho_o - rho_c) * GRAVITY * geom.stack_height_m
    np.testing.assert_allclose(ex.m_dot[0, IB], rho_i * 0.05 * dp5**0.6, rtol=1e-12)


def test_regularisation_is_smooth_and_monotone():
    """docs/model.md#regularisation: value and slope continuous at Δp_t; monotone through zero."""
    dp_t = 0.01
    for m in (0.5, 0.6, 0.65, 1.0):
        eps = 1e-9
        for x in (dp_t, -dp_t):
            lo = regularised_power(np.array([x - eps]), 1.0, m, dp_t)[0]
            hi = regularised_power(np.array([x + eps]), 1.0, m, dp_t)[0]
            assert abs(hi - lo) < 1e-6
        grid = np.linspace(-3 * dp_t, 3 * dp_t, 2001)
        q = regularised_power(grid, 1.0, m, dp_t)
        assert np.all(np.diff(q) > 0)
        slope = np.gradient(q, grid)
        jump = np.abs(np.diff(slope)).max()
        assert jump < 0.05 * slope.max()


def test_orifice_only_magnitude_errata_e11():
    """docs/model.md#parameters: f = 0, C_d = 0.6, A_d = A_c = 0.5 m², ΔT = 10 K ⇒ ΔP ≈ 1.06 Pa,
    v ≈ 0.56 m/s."""
    t_in, t5 = 295.15, 305.15
    rho_i, rho_c = air_density(t_in, 101325.0), air_density(t5, 101325.0)
    dp = (rho_i - rho_c) * GRAVITY * 2.75
    assert dp == pytest.approx(1.06, abs=0.02)
    k = 1 / (0.6 * 0.5) ** 2
    m = orifice_path_mass_flow(np.array([dp]), k, k, rho_i, rho_c, 0.01)[0]
    v = m / rho_i / 0.5
    assert v == pytest.approx(0.56, abs=0.02)


def test_inside_circulation_velocity_in_paper_range(geom):
    """docs/model.md#airflow / docs/model.md#parameters: f = 100 gives a few cm/s to ~15 cm/s for
    cavity–room ΔT of 2–10 K."""
    dts = np.array([2.0, 5.0, 10.0])
    fs = regime_flows(np.full(3, 1), 1.0, 295.15 + dts, _bnd(np.zeros(3), np.full(3, 22.0),
                                                            np.zeros(3), np.zeros(3),
                                                            np.zeros(3)), geom,
                      f=100.0, c=0.05, n=0.6)
    v = fs.q_cav / geom.cavity_area_m2
    assert np.all(np.diff(v) > 0)
    assert v[0] >= 0.03
    assert v[-1] <= 0.15 * 1.5
