"""Exact ZOH against an independent fine ODE solution and the Van Loan forms (docs/model.md#zoh)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from dsfd.physics.network import LINKS, Boundary, assemble
from dsfd.physics.zoh import step_integral_vanloan, zoh_symmetric, zoh_vanloan

CAP = np.array([12600.0, 12600.0, 12600.0, 2333.0, 299.3, 14.4])  # Suwon, J/(m2 K)


def _network(rng: np.random.Generator, g_adv: float = 8.0):
    """A realistic frozen network: random conductances in physical ranges, stiff x6."""
    cond = rng.uniform([1, 2, 1, 2, 2, 0.5, 0.1, 0.05, 2], [15, 40, 15, 8, 8, 1.0, 1.5, 0.6, 6])
    assert cond.shape == (len(LINKS),)
    bnd = Boundary(h_out=rng.uniform(3, 40), h_rad_out=4.0, h_in=rng.uniform(1, 8), h_rad_in=4.8,
                   g_adv=g_adv, t_out=270.0, t_rad_out=255.0, t_in=295.0, t_mrt=296.0,
                   t_inflow=295.0)
    sources = rng.uniform(0, 300, 4)
    return assemble(cond, bnd, sources)


@pytest.mark.parametrize("seed", range(4))
def test_zoh_matches_fine_radau_integration(seed):
    rng = np.random.default_rng(seed)
    lap, q = _network(rng)
    a = lap / CAP[:, None]
    b = q / CAP
    x0 = rng.uniform(260, 330, 6)
    ref = solve_ivp(lambda t, x: a @ x + b, (0, 60.0), x0, method="Radau", rtol=1e-8,
                    atol=1e-9, jac=a, dense_output=True)
    st = zoh_symmetric(lap, q, CAP, x0, 60.0)
    np.testing.assert_allclose(st.x_next, ref.y[:, -1], atol=1e-6, rtol=0)
    # Step average against the quadrature of the dense ODE solution.
    ts = np.linspace(0, 60.0, 6001)
    mean = np.trapezoid(ref.sol(ts), ts, axis=1) / 60.0
    np.testing.assert_allclose(st.x_mean, mean, atol=1e-5, rtol=0)


@pytest.mark.parametrize("seed", range(4))
def test_eigen_route_equals_augmented_exponential(seed):
    rng = np.random.default_rng(10 + seed)
    lap, q = _network(rng, g_adv=rng.uniform(0, 40))
    x0 = rng.uniform(260, 330, 6)
    fast = zoh_symmetric(lap, q, CAP, x0, 60.0)
    ref = zoh_vanloan(lap / CAP[:, None], q / CAP, x0, 60.0)
    np.testing.assert_allclose(fast.x_next, ref.x_next, atol=1e-9)
    np.testing.assert_allclose(fast.x_mean, ref.x_mean, atol=1e-9)
    np.testing.assert_allclose(fast.x_steady, ref.x_steady, atol=1e-9)


def test_exact_average_agrees_with_14x14_van_loan():
    """docs/model.md#zoh: x̄ = A⁻¹((x_{k+1} − x_k)/T − b) equals F[:7, 7:] z_k / T."""
    rng = np.random.default_rng(7)
    lap, q = _network(rng)
    a, b = lap / CAP[:, None], q / CAP
    x0 = rng.uniform(260, 330, 6)
    integral = step_integral_vanloan(a, b, x0, 60.0)
    st = zoh_symmetric(lap, q, CAP, x0, 60.0)
    np.testing.assert_allclose(st.x_mean, integral / 60.0, atol=1e-8)


def test_long_step_reaches_steady_state_and_batches():
    rng = np.random.default_rng(3)
    laps, qs = zip(*(_network(rng) for _ in range(5)), strict=True)
    lap, q = np.stack(laps), np.stack(qs)
    x0 = rng.uniform(260, 330, (5, 6))
    st = zoh_symmetric(lap, q, CAP, x0, 1e6)
    np.testing.assert_allclose(st.x_next, st.x_steady, atol=1e-9)
    np.testing.assert_allclose(lap @ st.x_steady[..., None] + q[..., None], 0, atol=1e-8)
    for i in range(5):
        single = zoh_symmetric(lap[i], q[i], CAP, x0[i], 60.0)
        batch = zoh_symmetric(lap, q, CAP, x0, 60.0)
        np.testing.assert_allclose(single.x_next, batch.x_next[i], atol=1e-12)


def test_network_is_symmetric_and_conserves_heat():
    rng = np.random.default_rng(5)
    lap, _ = _network(rng, g_adv=0.0)
    np.testing.assert_allclose(lap, lap.T, atol=0)
    assert np.all(np.linalg.eigvalsh(lap) < 0)
    # Internal links move heat without creating it: column sums equal minus the boundary
    # conductances (nodes 1, 3 only with g_adv = 0).
    col = lap.sum(axis=0)
    assert col[1] == pytest.approx(0, abs=1e-12)
    assert col[3] == pytest.approx(0, abs=1e-12)
    assert col[5] == pytest.approx(0, abs=1e-12)
