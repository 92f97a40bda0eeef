"""Correlations of the truth plant (docs/model.md#plant-heat-transfer, docs/model.md#plant-airflow,
docs/model.md#truth-plant) and the fused hot path."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.physics.airflow import louver_flow_loss
from dsfd.sim.plant.advection import limiter
from dsfd.sim.plant.convection import ConvectionGeometry, coefficients
from dsfd.sim.plant.flow import SQRT_COEF, reg_power, reg_power_slope
from dsfd.sim.plant.physics import (
    DAMPER_Y_HIGH,
    DAMPER_Y_LOW,
    air_conductivity,
    churchill_chu_vertical,
    damper_loss_exponential,
    damper_loss_scalar,
    doe2_exterior,
    flat_plate_laminar,
    iso15099_gap,
    iso15099_room,
    lateral_open_fraction,
    mixed_convection,
    parallel_plates_developing,
)

P = 101325.0


def test_churchill_chu_for_air_is_the_physics_formula():
    dt, tf, h = 10.0, 300.0, 2.5
    k = air_conductivity(tf)
    mu = 3.723e-6 + 4.94e-8 * tf
    rho = P / (287.05 * tf)
    ra = 9.81 / tf * np.sqrt(dt**2 + 0.01) * h**3 / ((mu / rho) * k / (rho * 1006.0))
    factor = 0.387 / (1 + (0.492 / 0.71) ** (9 / 16)) ** (8 / 27)
    assert factor == pytest.approx(0.325, abs=1e-3)  # docs/model.md#plant-heat-transfer for air
    expected = (0.825 + factor * ra ** (1 / 6)) ** 2 * k / h
    assert churchill_chu_vertical(dt, tf, h, P) == pytest.approx(expected, rel=1e-9)
    assert 2.0 < float(churchill_chu_vertical(10.0, 300.0, 2.5, P)) < 4.0


def test_iso15099_magnitudes_of_physics_7_2():
    # closed 12 mm gap ≈ 2.2 W/m2K; room side ≈ 1.7 W/m2K at ΔT = 5 K, H = 2.5 m
    assert float(iso15099_gap(305.0, 295.0, 0.012, 2.5, P)) == pytest.approx(2.2, abs=0.15)
    assert float(iso15099_room(300.15, 295.15, 2.5, P)) == pytest.approx(1.7, abs=0.3)
    # no jump where the ISO branches meet (only kinks)
    t = 295.0 + np.linspace(0.0, 60.0, 4001)
    h = iso15099_gap(t, 295.0, 0.012, 2.5, P)
    assert np.max(np.abs(np.diff(h))) < 0.01


def test_forced_and_exterior_convection():
    # fully developed laminar limit 7.54 k/D_h at zero flow and far from the inlet
    k = float(air_conductivity(300.0))
    assert float(parallel_plates_developing(0.0, 1.0, 0.125, 300.0, P)) == pytest.approx(
        7.55 * k / 0.25)
    h_in = parallel_plates_developing(0.1, np.array([0.05, 2.0]), 0.125, 300.0, P)
    assert h_in[0] > h_in[1] > 7.55 * k / 0.25  # entrance enhancement
    assert float(flat_plate_laminar(0.05, 0.05, 300.0, P)) == pytest.approx(3.9, rel=0.2)
    assert float(mixed_convection(3.0, 4.0)) == pytest.approx(np.cbrt(91.0))
    ww, lw = doe2_exterior(5.0, 3.0, True), doe2_exterior(5.0, 3.0, False)
    assert float(ww) > float(lw) > 1.31 * 5 ** (1 / 3)


def test_exponential_damper_characteristic():
    assert float(damper_loss_exponential(1.0)) == pytest.approx(0.45)
    assert float(damper_loss_exponential(0.0)) == pytest.approx(1e6)
    y = np.linspace(0.0, 1.0, 2001)
    z = damper_loss_exponential(y)
    assert np.all(np.diff(z) < 0)  # closes monotonically
    for yk in (DAMPER_Y_LOW, DAMPER_Y_HIGH):  # continuous at the breakpoints
        assert float(damper_loss_exponential(yk - 1e-9)) == pytest.approx(
            float(damper_loss_exponential(yk + 1e-9)), rel=1e-6)
    for yk in (0.0, 0.1, 0.4, 0.8, 1.0):
        assert damper_loss_scalar(yk) == pytest.approx(float(damper_loss_exponential(yk)))


def test_louver_flow_loss_and_lateral_exchange():
    kw = dict(depth_m=0.25, slat_width_m=0.05, slat_pitch_m=0.045, height_m=2.5)
    assert float(louver_flow_loss(0.0, **kw)) == pytest.approx(3.47, abs=0.05)
    assert float(louver_flow_loss(np.pi / 2, **kw)) == pytest.approx(0.0, abs=1e-12)
    frac = lateral_open_fraction(np.radians([0.0, 36.0, 72.0, 90.0]), slat_width_m=0.05,
                                 slat_pitch_m=0.045)
    np.testing.assert_allclose(frac[[0, 2, 3]], [1.0, 0.0, 0.0])
    assert 0.0 < frac[1] < 1.0


def test_fused_coefficients_equal_the_pure_functions():
    rng = np.random.default_rng(0)
    n = 6
    t1, t2, t3, t4 = (280.0 + 30 * rng.random(n) for _ in range(4))
    to, ti = 285.0 + 20 * rng.random(n), 285.0 + 20 * rng.random(n)
    dz, h = 2.5 / n, 2.5
    lo, hi = np.arange(n) * dz, (np.arange(n) + 1) * dz
    geo = ConvectionGeometry(h, 0.125, 0.05, 0.012, dz, np.tile(np.r_[lo, hi], 2),
                             np.tile(np.r_[h - hi, h - lo], 2))
    wind = 1.0 + rng.random(n)
    c = coefficients(geo, t1, t2, t3, t4, to, ti, speed=0.08, upward=True, p=9e4,
                     t_out=275.0, t_in=295.0, wind=wind, windward=False, gap_model=True)

    def cell_avg(air):
        xh_lo = lo * parallel_plates_developing(0.08, lo, 0.125, air, 9e4)
        xh_hi = hi * parallel_plates_developing(0.08, hi, 0.125, air, 9e4)
        return (xh_hi - xh_lo) / dz

    slat = flat_plate_laminar(0.08, 0.05, 0.5 * (to + ti), 9e4)
    nat = lambda s, a: churchill_chu_vertical(s - a, 0.5 * (s + a), h, 9e4)  # noqa: E731
    np.testing.assert_allclose(c.h1, mixed_convection(nat(t1, to), cell_avg(to)), rtol=1e-12)
    np.testing.assert_allclose(c.h2o, mixed_convection(nat(t4, to), slat), rtol=1e-12)
    np.testing.assert_allclose(c.h2i, mixed_convection(nat(t4, ti), slat), rtol=1e-12)
    np.testing.assert_allclose(c.h3, mixed_convection(nat(t2, ti), cell_avg(ti)), rtol=1e-12)
    np.testing.assert_allclose(c.h_out, doe2_exterior(t1 - 275.0, wind, False), rtol=1e-12)
    np.testing.assert_allclose(c.h_in, iso15099_room(t3, 295.0, h, 9e4), rtol=1e-12)
    np.testing.assert_allclose(c.h_gap, iso15099_gap(t2, t3, 0.012, h, 9e4), rtol=1e-12)


def test_regularised_orifice_law_is_smooth_and_odd():
    dp_t = 0.01
    dp = np.linspace(-0.05, 0.05, 2001)
    m = np.array([reg_power(x, 2.0, 0.5, dp_t, SQRT_COEF) for x in dp])
    s = np.array([reg_power_slope(x, 2.0, 0.5, dp_t, SQRT_COEF) for x in dp])
    np.testing.assert_allclose(m, -m[::-1], atol=1e-15)
    assert np.all(s > 0)
    assert reg_power(dp_t, 2.0, 0.5, dp_t, SQRT_COEF) == pytest.approx(2.0 * dp_t**0.5)
    np.testing.assert_allclose(np.gradient(m, dp)[1:-1], s[1:-1], rtol=2e-2, atol=1e-3)


def test_van_albada_limiter():
    a = np.array([1.0, 1.0, 0.0, 2.0, -1.0])
    b = np.array([1.0, 0.0, 1.0, 2.0, -1.0])
    np.testing.assert_allclose(limiter(a, b), [1.0, 0.0, 0.0, 2.0, -1.0], atol=1e-9)


def test_pair_closed_form_equals_the_one_node_solver():
    """Two open dampers: the closed form (docs/model.md#path-flows) is the one-node solution
    (docs/model.md#one-node)."""
    from dsfd.sim.plant.flow import NETWORK, PAIR, FlowPiece, network_flows, pair_flow

    rho_b, rho_node = [1.27, 1.27, 1.19, 1.19], [1.15, 1.12, 1.15, 1.12]
    k = [60.0, 70.0, 65.0, 80.0]
    # (Inside the regularisation band, |Δp| < 0.01 Pa, the two differ by design: the path
    # law is regularised in the path ΔP, the solver per opening — docs/model.md#regularisation.)
    for head in ([0.3, -33.9, 0.0, -32.2], [0.0, -34.6, 0.0, -32.2], [0.5, 0.0, 0.0, 0.1]):
        for a, b in ((0, 1), (2, 3), (2, 1), (0, 3)):
            m_ab = pair_flow(FlowPiece(PAIR, a=a, b=b), head, rho_b, rho_node, k)
            m, _ = network_flows(FlowPiece(NETWORK, active=(a, b)), head, rho_b, rho_node, k,
                                 0.0)
            assert m[a] == pytest.approx(m_ab, rel=1e-9, abs=1e-12)
            assert m[b] == pytest.approx(-m_ab, rel=1e-9, abs=1e-12)


def test_pair_power_law_has_the_slats_in_series():
    """diagonal_flow='power_law' (lumped equivalence): the slats' loss ρ β Q² takes its share
    of the path's ΔP as in the lumped model (docs/model.md#louver-flow-loss); reference: the
    root of (Q/c)^(1/n) + ρ β Q² = ΔP by bisection."""
    from scipy.optimize import brentq

    from dsfd.sim.plant.flow import PAIR, FlowPiece, pair_flow, reg_coefficients

    rho_b, rho_node = [1.27, 1.27, 1.19, 1.19], [1.15, 1.12, 1.15, 1.12]
    c, n, beta = 0.12, 0.6, 3.4 / (2 * 0.5**2)
    fp = FlowPiece(PAIR, a=2, b=1, power=True, power_coef=c, n=n, abcd_n=reg_coefficients(n))
    for dp in (0.05, 0.8, 6.0):
        head = [0.0, -dp, 0.0, 0.0]
        q = brentq(lambda qq, dp=dp: (qq / c) ** (1 / n) + rho_node[1] * beta * qq * qq - dp,
                   0.0, c * dp**n, xtol=1e-16, rtol=1e-14)
        m = pair_flow(fp, head, rho_b, rho_node, [1.0] * 4, beta)
        assert m == pytest.approx(rho_b[2] * q, rel=3e-5)
        assert m < pair_flow(fp, head, rho_b, rho_node, [1.0] * 4)  # slower than without
        # reversed driving pressure: the mirror flow (inflow density of the other side)
        back = pair_flow(fp, [0.0, dp, 0.0, 0.0], rho_b, rho_node, [1.0] * 4, beta)
        assert back < 0
