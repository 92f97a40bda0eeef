"""Exact zero-order-hold discretisation of ẋ = A x + b (docs/model.md#zoh).

The node network is C ẋ = L x + q with C diagonal positive (heat capacities) and L
symmetric negative definite (a weighted graph Laplacian plus boundary conductances), so
A = C⁻¹L is similar to the symmetric matrix S = C^-½ L C^-½. Its eigen-decomposition
S = V Λ Vᵀ (λ < 0) gives the exact step in closed form:

    x* = −L⁻¹ q                                   (steady state of the frozen step)
    x(t) = x* + C^-½ V e^{Λt} Vᵀ C^½ (x_k − x*)
    x̄    = x* + C^-½ V φ₁(ΛT) Vᵀ C^½ (x_k − x*),   φ₁(z) = (e^z − 1)/z

This is the same exact ZOH as the paper's G = e^{AT}, H = A⁻¹(e^{AT} − I) b and the
Van Loan augmented exponential (kept here as the reference, ``zoh_vanloan``), at a
fraction of the cost, and it is batched over a leading dimension. Stiff nodes (the DGU
gap air, τ ≈ 2 s) are handled exactly.

References: C. Van Loan, "Computing integrals involving the matrix exponential",
IEEE TAC 23(3), 1978; G. Franklin, J. Powell, M. Workman, Digital Control of Dynamic
Systems, 3rd ed., §4.3 (ZOH equivalent).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class ZohStep(NamedTuple):
    """Result of one exact ZOH step (all arrays (..., n), [K])."""

    x_next: np.ndarray
    x_mean: np.ndarray
    x_steady: np.ndarray


class Modal(NamedTuple):
    """Eigen-decomposition of one frozen step (see module docstring).

    Attributes
    ----------
    lam : (..., n), [1/s]
        Eigenvalues of C^-½ L C^-½ (all negative).
    vec : (..., n, n)
        Orthonormal eigenvectors V.
    r : (n,), [(m2 K/J)^½]
        C^-½ (broadcasts against the batch).
    x_steady : (..., n), [K]
        Frozen steady state x* = −L⁻¹q.
    """

    lam: np.ndarray
    vec: np.ndarray
    r: np.ndarray
    x_steady: np.ndarray


def modal(lap: np.ndarray, q: np.ndarray, cap: np.ndarray) -> Modal:
    """Decompose C ẋ = L x + q (L symmetric negative definite, C = diag(cap) > 0).

    Parameters
    ----------
    lap : array (..., n, n), [W/(m2 K)]
    q : array (..., n), [W/m2]
    cap : array (n,), [J/(m2 K)]
    """
    r = 1.0 / np.sqrt(cap)
    lam, vec = np.linalg.eigh(lap * (r[:, None] * r))
    w = ((r * q)[..., None, :] @ vec)[..., 0, :]  # Vᵀ C^-½ q
    x_star = -r * (vec @ (w / lam)[..., None])[..., 0]
    return Modal(lam, vec, r, x_star)


def modal_state(m: Modal, x0: np.ndarray, dt: float, *, node: int | None = None) -> np.ndarray:
    """State after ``dt`` from ``x0`` (all nodes, or only ``node`` when given) [K]."""
    y0 = (((x0 - m.x_steady) / m.r)[..., None, :] @ m.vec)[..., 0, :]  # Vᵀ C^½ (x0 − x*)
    g = np.exp(m.lam * dt) * y0
    if node is not None:
        return m.x_steady[..., node] + m.r[..., node] * (m.vec[..., node, :] * g).sum(axis=-1)
    return m.x_steady + m.r * (m.vec @ g[..., None])[..., 0]


def modal_step(m: Modal, x0: np.ndarray, dt: float) -> ZohStep:
    """Exact ZOH step from ``x0``: end state and exact step average (docs/model.md#zoh)."""
    y0 = (((x0 - m.x_steady) / m.r)[..., None, :] @ m.vec)[..., 0, :]
    z = m.lam * dt
    both = np.stack([np.exp(z) * y0, np.expm1(z) / z * y0], axis=-1)  # (..., n, 2)
    xs = m.vec @ both
    x_next = m.x_steady + m.r * xs[..., 0]
    x_mean = m.x_steady + m.r * xs[..., 1]
    return ZohStep(x_next, x_mean, m.x_steady)


def zoh_symmetric(lap: np.ndarray, q: np.ndarray, cap: np.ndarray, x0: np.ndarray,
                  dt: float) -> ZohStep:
    """Exact step of C ẋ = L x + q held constant over ``dt``.

    Parameters
    ----------
    lap : array (..., n, n), [W/(m2 K)]
        Symmetric, negative definite conductance matrix L.
    q : array (..., n), [W/m2]
        Source vector (boundary conductance × boundary temperature + absorbed solar).
    cap : array (n,), [J/(m2 K)]
        Node heat capacities (positive).
    x0 : array (..., n), [K]
        State at the start of the step.
    dt : float, [s]
        Step length T.

    Returns
    -------
    ZohStep
        ``x_next`` at t + T, exact step average ``x_mean`` (docs/model.md#zoh) and the frozen
        steady state ``x_steady``.
    """
    return modal_step(modal(lap, q, cap), x0, dt)


def zoh_vanloan(a: np.ndarray, b: np.ndarray, x0: np.ndarray, dt: float) -> ZohStep:
    """Reference exact step via the augmented matrix exponential (docs/model.md#zoh).

    M = [[A, b], [0, 0]], E = expm(M T): G = E[:n, :n], H = E[:n, n]; the step average is
    A⁻¹((x_{k+1} − x_k)/T − b) (docs/model.md#zoh). Batched over leading dimensions.
    """
    # imported here: only model.zoh = 'expm' (the reference) needs scipy.linalg, ~20 MB a daemon
    from scipy.linalg import expm

    n = a.shape[-1]
    batch = np.broadcast_shapes(a.shape[:-2], b.shape[:-1], x0.shape[:-1])
    m = np.zeros((*batch, n + 1, n + 1))
    m[..., :n, :n] = a
    m[..., :n, n] = b
    e = expm(m * dt)
    x_next = np.einsum("...ij,...j->...i", e[..., :n, :n], x0) + e[..., :n, n]
    x_mean = np.linalg.solve(a, ((x_next - x0) / dt - b)[..., None])[..., 0]
    x_star = -np.linalg.solve(a, b[..., None])[..., 0]
    return ZohStep(x_next, x_mean, x_star)


def step_integral_vanloan(a: np.ndarray, b: np.ndarray, x0: np.ndarray, dt: float) -> np.ndarray:
    """∫₀ᵀ x dt by the 14×14 Van Loan form (for a 6-state system); reference for tests.

    N = [[M, I], [0, 0]] with M = [[A, b], [0, 0]]; F = expm(N T); ∫ z dt = F[:7, 7:] z_k with
    z = [x; 1] (docs/model.md#zoh; the block is the integral, divide by T for the average).
    """
    from scipy.linalg import expm  # a reference path only (see zoh_vanloan)

    n = a.shape[-1]
    k = n + 1
    big = np.zeros((2 * k, 2 * k))
    big[:n, :n] = a
    big[:n, n] = b
    big[:k, k:] = np.eye(k)
    f = expm(big * dt)
    z0 = np.append(x0, 1.0)
    return (f[:k, k:] @ z0)[:n]
