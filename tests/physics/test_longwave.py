"""Long-wave radiation (docs/model.md#longwave, docs/model.md#sky)."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.physics.constants import SIGMA
from dsfd.physics.longwave import (
    cavity_conductances,
    cavity_exchange_matrix,
    exterior_radiant_temperature,
    h_rad,
    h_rad_gap,
    h_rad_room,
    parallel_plates_emissivity,
    sky_emissivity_clark_allen,
    sky_temperature_clark_allen,
    sky_temperature_swinbank,
)
from dsfd.physics.optics import slat_infrared

T20 = 293.15


def test_exchange_matrix_vectors():
    """[PROTO] vectors of docs/model.md#longwave, printed to 4 decimals."""
    got = cavity_exchange_matrix(0.10, 0.58, 0.399, 0.84)
    expected = [[-0.0995, 0.0644, 0.0351], [0.0644, -0.7482, 0.6838], [0.0351, 0.6838, -0.7189]]
    np.testing.assert_allclose(got, expected, atol=6e-5)
    got = cavity_exchange_matrix(0.84, 0.58, 0.399, 0.84)
    expected = [[-0.8069, 0.5223, 0.2846], [0.5223, -1.0446, 0.5223], [0.2846, 0.5223, -0.8069]]
    np.testing.assert_allclose(got, expected, atol=6e-5)


def test_exchange_matrix_uses_the_louver_ir_of_the_slat_cell():
    # The 0.58 / 0.399 of the test vector are the Suwon louver's IR properties at phi = 0.
    ir = slat_infrared(0.0, width=0.05, pitch=0.045, emissivity=0.9)
    assert float(ir.eps_L) == pytest.approx(0.58, abs=5e-4)
    assert float(ir.tau_L) == pytest.approx(0.399, abs=5e-4)
    phi = np.radians(np.arange(-90, 91, 18))
    ir = slat_infrared(phi, width=0.05, pitch=0.045, emissivity=0.9)
    exchange = cavity_exchange_matrix(0.10, ir.eps_L, ir.tau_L, 0.84)
    assert exchange.shape == (11, 3, 3)


def test_exchange_matrix_properties():
    rng = np.random.default_rng(11)
    n = 500
    eps_L = rng.uniform(0, 1, n)
    tau_L = rng.uniform(0, 1, n) * (1 - eps_L)
    exchange = cavity_exchange_matrix(rng.uniform(0.02, 1, n), eps_L, tau_L,
                                      rng.uniform(0.02, 1, n))
    assert exchange.shape == (n, 3, 3)
    np.testing.assert_allclose(exchange, np.swapaxes(exchange, -1, -2), atol=1e-14)
    np.testing.assert_allclose(exchange.sum(axis=-1), 0.0, atol=1e-14)
    off = exchange[:, [0, 0, 1], [1, 2, 2]]
    assert np.all(off >= -1e-15)
    # Broadcasting: louver arrays against scalar glass emissivities.
    assert cavity_exchange_matrix(0.1, eps_L[:, None], tau_L[:, None], 0.84).shape == (n, 1, 3, 3)


def test_no_louver_limit():
    exchange = cavity_exchange_matrix(0.10, 0.0, 1.0, 0.84)
    assert exchange[0, 2] == pytest.approx(1.0 / (1.0 / 0.10 + 1.0 / 0.84 - 1.0), rel=1e-14)
    assert exchange[0, 2] == pytest.approx(0.09813, abs=5e-6)
    np.testing.assert_allclose(exchange[1], 0.0, atol=1e-15)
    np.testing.assert_allclose(exchange[:, 1], 0.0, atol=1e-15)
    assert float(parallel_plates_emissivity(0.10, 0.84)) == pytest.approx(exchange[0, 2])
    # An opaque black louver splits the cavity into two parallel-plate gaps.
    split = cavity_exchange_matrix(0.3, 1.0, 0.0, 0.6)
    assert split[0, 2] == pytest.approx(0.0, abs=1e-15)
    assert split[0, 1] == pytest.approx(0.3, rel=1e-14)
    assert split[1, 2] == pytest.approx(0.6, rel=1e-14)


def test_conductances_reproduce_the_t4_exchange():
    exchange = cavity_exchange_matrix(0.10, 0.58, 0.399, 0.84)
    T = np.array([285.0, 310.0, 296.0])  # L1, louver, L2
    q = exchange @ (SIGMA * T**4)
    g = cavity_conductances(exchange, T[0], T[1], T[2])
    q1 = g.g_14 * (T[1] - T[0]) + g.g_12 * (T[2] - T[0])
    q4 = g.g_14 * (T[0] - T[1]) + g.g_42 * (T[2] - T[1])
    q2 = g.g_12 * (T[0] - T[2]) + g.g_42 * (T[1] - T[2])
    np.testing.assert_allclose([q1, q4, q2], q, rtol=1e-12)


def test_h_rad_values_at_20c():
    # Errata summary: h_r,23 = 0.561, h_r,in = 4.80 W/m2K.
    assert float(h_rad_gap(0.84, 0.10, T20, T20)) == pytest.approx(0.561, abs=5e-4)
    assert float(h_rad_room(0.84, T20, T20)) == pytest.approx(4.80, abs=5e-3)


def test_h_rad_is_the_exact_secant():
    T_a, T_b = np.array([250.0, 300.0, 350.0]), np.array([300.0, 300.0, 280.0])
    h = h_rad(0.7, T_a, T_b)
    np.testing.assert_allclose(h * (T_a - T_b), 0.7 * SIGMA * (T_a**4 - T_b**4), rtol=1e-13)


def test_sky_temperature():
    assert float(sky_temperature_swinbank(273.15)) == pytest.approx(0.0552 * 273.15**1.5)
    assert float(sky_temperature_swinbank(273.15)) == pytest.approx(273.15 - 24.0, abs=0.1)
    # Clark–Allen: clear sky at T_dp = 273 K has eps 0.787; cloud raises it.
    assert float(sky_emissivity_clark_allen(273.0, 0.0)) == pytest.approx(0.787)
    assert float(sky_emissivity_clark_allen(273.0, 10.0)) == pytest.approx(0.787 * 1.154)
    t_sky = sky_temperature_clark_allen(283.15, 278.15, np.arange(11.0))
    assert np.all(np.diff(t_sky) > 0) and np.all(t_sky < 283.15)


def test_exterior_radiant_temperature():
    T_o, T_sky = 283.15, 260.0
    beta = np.sqrt(0.5)
    expected = (0.5 * beta * T_sky**4 + (0.5 * (1 - beta) + 0.5) * T_o**4) ** 0.25
    assert float(exterior_radiant_temperature(T_o, T_sky)) == pytest.approx(expected, rel=1e-14)
    # Horizontal roof sees only the sky; the ground temperature can differ from the air.
    assert float(exterior_radiant_temperature(T_o, T_sky, tilt=0.0)) == pytest.approx(T_sky)
    warm_ground = exterior_radiant_temperature(T_o, T_sky, T_ground=300.0)
    assert float(warm_ground) > expected
