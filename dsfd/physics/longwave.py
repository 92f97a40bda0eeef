"""Long-wave (thermal infrared) radiation of the DSF layers.

Pure functions over numpy arrays (docs/model.md#longwave, docs/model.md#sky): sky temperature, the
effective radiant temperature seen by the exterior pane, the three-layer exchange in the
cavity (L1 - louver - L2), and secant radiative conductances for the linear network.
Temperatures in kelvin, heat fluxes per m² of façade.

References
----------
EnergyPlus Engineering Reference, "Outside Surface Heat Balance — External Longwave
Radiation" and "Sky Radiation Model" (Clark–Allen); W. C. Swinbank (1963), Q. J. R. Meteorol.
Soc. 89, 339; ISO 15099:2003 §8.3 (radiosity of layers with IR transmittance).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.physics.constants import SIGMA

__all__ = [
    "CavityConductances",
    "cavity_conductances",
    "cavity_exchange_matrix",
    "exterior_radiant_temperature",
    "h_rad",
    "h_rad_gap",
    "h_rad_room",
    "parallel_plates_emissivity",
    "sky_emissivity_clark_allen",
    "sky_temperature_clark_allen",
    "sky_temperature_swinbank",
]

FloatArray = NDArray[np.float64]


def sky_temperature_swinbank(T_out: ArrayLike) -> FloatArray:
    """Clear-sky effective sky temperature after Swinbank.

    Parameters
    ----------
    T_out : array_like
        Outdoor air temperature [K].

    Returns
    -------
    ndarray
        Sky temperature [K].

    Notes
    -----
    ``T_sky = 0.0552 T_o^1.5`` (docs/model.md#sky), equivalent to
    ``eps_sky sigma T_o^4 = 5.31e-13 T_o^6``. About T_o - 24 K at 0 °C; clear sky only, so it
    overstates the night loss under cloud (docs/model.md#sky).
    """
    return 0.0552 * np.asarray(T_out, dtype=float) ** 1.5


def sky_emissivity_clark_allen(T_dew: ArrayLike, opaque_sky_cover: ArrayLike) -> FloatArray:
    """Sky emissivity after Clark & Allen with the cloud correction of EnergyPlus.

    Parameters
    ----------
    T_dew : array_like
        Dew-point temperature [K].
    opaque_sky_cover : array_like
        Opaque sky cover N [tenths], 0 (clear) … 10 (overcast).

    Returns
    -------
    ndarray
        Effective sky emissivity [-].

    Notes
    -----
    docs/model.md#sky (EnergyPlus ER "Sky Radiation Model")::

        eps_sky = (0.787 + 0.764 ln(T_dp / 273)) (1 + 0.0224 N - 0.0035 N² + 0.00028 N³)
    """
    n = np.asarray(opaque_sky_cover, dtype=float)
    clear = 0.787 + 0.764 * np.log(np.asarray(T_dew, dtype=float) / 273.0)
    return clear * (1.0 + n * (0.0224 + n * (-0.0035 + n * 0.00028)))


def sky_temperature_clark_allen(
    T_out: ArrayLike, T_dew: ArrayLike, opaque_sky_cover: ArrayLike
) -> FloatArray:
    """Effective sky temperature after Clark & Allen [K].

    Parameters
    ----------
    T_out : array_like
        Outdoor air temperature [K].
    T_dew : array_like
        Dew-point temperature [K].
    opaque_sky_cover : array_like
        Opaque sky cover [tenths], 0 … 10.

    Returns
    -------
    ndarray
        ``T_sky = eps_sky^(1/4) T_o`` [K], eps_sky from :func:`sky_emissivity_clark_allen`.
    """
    eps = sky_emissivity_clark_allen(T_dew, opaque_sky_cover)
    return eps**0.25 * np.asarray(T_out, dtype=float)


def exterior_radiant_temperature(
    T_out: ArrayLike,
    T_sky: ArrayLike,
    *,
    tilt: float = 0.5 * np.pi,
    T_ground: ArrayLike | None = None,
) -> FloatArray:
    """Effective radiant temperature of the surroundings of the exterior pane [K].

    Parameters
    ----------
    T_out : array_like
        Outdoor air temperature [K]; also the ground temperature unless ``T_ground`` is given.
    T_sky : array_like
        Sky temperature [K].
    tilt : float, default pi/2
        Surface tilt from horizontal [rad] (façade: vertical).
    T_ground : array_like, optional
        Ground surface temperature [K]; defaults to ``T_out`` (docs/model.md#sky).

    Returns
    -------
    ndarray
        ``T_rad,o`` such that ``q = eps sigma (T_rad,o^4 - T^4)`` [K].

    Notes
    -----
    EnergyPlus ER "External Longwave Radiation" (docs/model.md#sky)::

        F_sky = (1 + cos tilt) / 2,  F_gnd = (1 - cos tilt) / 2,  beta = sqrt((1 + cos tilt) / 2)
        T_rad,o^4 = F_sky beta T_sky^4 + F_sky (1 - beta) T_o^4 + F_gnd T_gnd^4

    The sky part ``F_sky (1 - beta)`` near the horizon radiates at air temperature. Vertical:
    F_sky = F_gnd = 0.5, beta = 0.707.
    """
    T_out = np.asarray(T_out, dtype=float)
    T_ground = T_out if T_ground is None else np.asarray(T_ground, dtype=float)
    cos_tilt = np.cos(tilt)
    view_sky = 0.5 * (1.0 + cos_tilt)
    view_ground = 0.5 * (1.0 - cos_tilt)
    beta = np.sqrt(view_sky)
    fourth = (view_sky * beta * np.asarray(T_sky, dtype=float) ** 4
              + view_sky * (1.0 - beta) * T_out**4 + view_ground * T_ground**4)
    return fourth**0.25


def parallel_plates_emissivity(eps_a: ArrayLike, eps_b: ArrayLike) -> FloatArray:
    """Exchange factor of two infinite parallel grey plates [-].

    ``1 / (1/eps_a + 1/eps_b - 1)``; the net flux is this times ``sigma (T_a^4 - T_b^4)``.
    """
    eps_a = np.asarray(eps_a, dtype=float)
    eps_b = np.asarray(eps_b, dtype=float)
    return 1.0 / (1.0 / eps_a + 1.0 / eps_b - 1.0)


def cavity_exchange_matrix(
    eps_1b: ArrayLike, eps_L: ArrayLike, tau_L: ArrayLike, eps_2f: ArrayLike
) -> FloatArray:
    """Long-wave exchange matrix of the cavity: L1 (cavity face), louver, L2 (cavity face).

    Parameters
    ----------
    eps_1b : array_like
        Emissivity of L1's cavity (back) face [-].
    eps_L, tau_L : array_like
        Effective IR emissivity and transmittance of the louver layer [-]
        (:func:`dsfd.physics.optics.slat_infrared`); ``eps_L = 0, tau_L = 1`` without louver.
    eps_2f : array_like
        Emissivity of L2's cavity (front) face [-].

    Returns
    -------
    ndarray, shape ``broadcast(inputs) + (3, 3)``
        R with ``q = R @ E``, q the absorbed long-wave flux of (L1, louver, L2) [W/m2] and
        ``E_k = sigma T_k^4``. Symmetric, rows summing to 0, off-diagonal ≥ 0.

    Notes
    -----
    Three infinite parallel layers, glass opaque, louver grey with
    ``rho_L = 1 - eps_L - tau_L`` (docs/model.md#longwave). Radiosities J_a (L1 -> louver), J_f
    (louver -> L1), J_b (louver -> L2), J_c (L2 -> louver)::

        J_a - (1 - eps_1b) J_f     = eps_1b E_1
        J_f - rho_L J_a - tau_L J_c = eps_L E_4
        J_b - tau_L J_a - rho_L J_c = eps_L E_4
        J_c - (1 - eps_2f) J_b     = eps_2f E_2
        q_1 = eps_1b (J_f - E_1),  q_4 = eps_L (J_a + J_c) - 2 eps_L E_4,  q_2 = eps_2f (J_b - E_2)

    The 4 x 4 system is solved (batched) for the unit emissive powers of L1, louver and L2.
    The louver counts both faces, so ``q_4`` is per m² of façade.
    """
    eps_1b, eps_L, tau_L, eps_2f = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (eps_1b, eps_L, tau_L, eps_2f))
    )
    rho_L = 1.0 - eps_L - tau_L
    shape = eps_L.shape
    system = np.zeros((*shape, 4, 4))
    system[..., [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    system[..., 0, 1] = -(1.0 - eps_1b)
    system[..., 1, 0] = -rho_L
    system[..., 1, 3] = -tau_L
    system[..., 2, 0] = -tau_L
    system[..., 2, 3] = -rho_L
    system[..., 3, 2] = -(1.0 - eps_2f)
    # Right-hand sides for E = unit vectors of (L1, louver, L2).
    emission = np.zeros((*shape, 4, 3))
    emission[..., 0, 0] = eps_1b
    emission[..., 1, 1] = eps_L
    emission[..., 2, 1] = eps_L
    emission[..., 3, 2] = eps_2f
    J_a, J_f, J_b, J_c = np.moveaxis(np.linalg.solve(system, emission), -2, 0)
    exchange = np.stack(
        [eps_1b[..., None] * J_f, eps_L[..., None] * (J_a + J_c), eps_2f[..., None] * J_b],
        axis=-2,
    )
    exchange[..., 0, 0] -= eps_1b
    exchange[..., 1, 1] -= 2.0 * eps_L
    exchange[..., 2, 2] -= eps_2f
    return exchange


def h_rad(eps_eff: ArrayLike, T_a: ArrayLike, T_b: ArrayLike) -> FloatArray:
    """Secant radiative conductance [W/(m2 K)].

    ``eps_eff sigma (T_a² + T_b²)(T_a + T_b)``, exact in the sense that
    ``h_rad (T_a - T_b) = eps_eff sigma (T_a^4 - T_b^4)``. Temperatures [K].
    """
    T_a = np.asarray(T_a, dtype=float)
    T_b = np.asarray(T_b, dtype=float)
    return np.asarray(eps_eff, dtype=float) * SIGMA * (T_a**2 + T_b**2) * (T_a + T_b)


def h_rad_gap(eps_a: ArrayLike, eps_b: ArrayLike, T_a: ArrayLike, T_b: ArrayLike) -> FloatArray:
    """Radiative conductance across a closed gap of two opaque panes, e.g. h_r,23 [W/(m2 K)].

    docs/model.md#longwave: ``sigma (T_a² + T_b²)(T_a + T_b) / (1/eps_a + 1/eps_b - 1)``; about
    0.56 for the DGU (eps 0.84 / 0.10) at 20 °C.
    """
    return h_rad(parallel_plates_emissivity(eps_a, eps_b), T_a, T_b)


def h_rad_room(eps_surface: ArrayLike, T_surface: ArrayLike, T_mrt: ArrayLike) -> FloatArray:
    """Radiative conductance from the room-side pane to the room, h_r,in [W/(m2 K)].

    docs/model.md#longwave: ``eps sigma (T3² + T_mrt²)(T3 + T_mrt)`` (room as a black enclosure);
    about 4.8 for eps = 0.84 at 20 °C.
    """
    return h_rad(eps_surface, T_surface, T_mrt)


class CavityConductances(NamedTuple):
    """Linearised long-wave conductances of the cavity per m² of façade [W/(m2 K)]."""

    g_14: FloatArray  #: L1 <-> louver
    g_12: FloatArray  #: L1 <-> L2 (through the louver's IR transmittance)
    g_42: FloatArray  #: louver <-> L2


def cavity_conductances(
    exchange: ArrayLike, T_1: ArrayLike, T_4: ArrayLike, T_2: ArrayLike
) -> CavityConductances:
    """Secant conductances of the cavity from the exchange matrix and the layer temperatures.

    Parameters
    ----------
    exchange : array_like, shape (..., 3, 3)
        Matrix of :func:`cavity_exchange_matrix` (order L1, louver, L2).
    T_1, T_4, T_2 : array_like
        Temperatures of L1, the louver and L2 [K].

    Returns
    -------
    CavityConductances
        ``g_14 = R_14 sigma (T1² + T4²)(T1 + T4)`` and likewise ``g_12``, ``g_42``
        (docs/model.md#longwave), so that ``g (T_i - T_j)`` is the exact net exchange.
    """
    exchange = np.asarray(exchange, dtype=float)
    return CavityConductances(
        g_14=h_rad(exchange[..., 0, 1], T_1, T_4),
        g_12=h_rad(exchange[..., 0, 2], T_1, T_2),
        g_42=h_rad(exchange[..., 1, 2], T_4, T_2),
    )
