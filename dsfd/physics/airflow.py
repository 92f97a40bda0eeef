"""Cavity airflow: openings, driving pressures, the ten damper regimes and flow solvers.

Everything is vectorised over a leading batch dimension (candidate controls, time steps).
Openings are indexed ``EB, ET, IB, IT`` = 0..3 (exterior/interior skin, bottom/top); the
bottom row sits at z = 0 and the top row at z = Δz (the stack height). Mass flows
``m_dot[..., k]`` are positive INTO the cavity.

References: docs/model.md#airflow, docs/model.md#regimes (regime numbering),
docs/model.md#path-flows (closed form with the outlet at cavity density),
docs/model.md#regularisation (IBPSA regularisation), docs/model.md#cavity-velocity (reported
velocity), docs/model.md#one-node, docs/model.md#openings (regime 9 and OR scaling, both [ENG]).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from dsfd.config.panel import Facade, Openings
from dsfd.physics.constants import GRAVITY, R_AIR

EB, ET, IB, IT = 0, 1, 2, 3
OPENING_NAMES = ("exterior_bottom", "exterior_top", "interior_bottom", "interior_top")
#: Opening height index: 0 = bottom row (z = 0), 1 = top row (z = Δz).
IS_TOP = np.array([False, True, False, True])
IS_EXTERIOR = np.array([True, True, False, False])

#: Positive-direction path of each two-opening damper set (docs/model.md#regimes):
#: commanded regime -> (inlet, outlet, label if ΔP > 0, label if ΔP < 0, law).
PATHS: dict[int, tuple[int, int, int, int, str]] = {
    1: (IB, IT, 1, 2, "orifice"),
    2: (IB, IT, 1, 2, "orifice"),
    3: (EB, ET, 3, 4, "orifice"),
    4: (EB, ET, 3, 4, "orifice"),
    5: (IB, ET, 5, 8, "power"),
    8: (IB, ET, 5, 8, "power"),
    6: (IT, EB, 6, 7, "power"),
    7: (IT, EB, 6, 7, "power"),
}
ALL_OPEN, CLOSED = 9, 10

#: Shape parameter γ of the IBPSA regularisation (slope at 0 relative to the secant).
_GAMMA = 1.5


@dataclass(frozen=True)
class AirflowGeometry:
    """Fixed airflow data of one panel (SI units).

    Attributes
    ----------
    area_m2 : ndarray (4,), [m2]
        Free area of each fully open damper; 0 where the panel has no such damper.
    discharge : ndarray (4,), [-]
        Discharge coefficients C_d.
    stack_height_m : float, [m]
        Δz between the bottom and top damper centres.
    cavity_area_m2 : float, [m2]
        Cavity cross-section A_c = D·W.
    facade_area_m2 : float, [m2]
        Glazed area A_f = W·H_g.
    min_opening_ratio : float, [-]
        Floor on OR for an open damper set (docs/model.md#openings).
    dp_reg_pa : float, [Pa]
        Regularisation threshold Δp_t (docs/model.md#regularisation).
    room_pressure_pa : float, [Pa]
        Room pressure P_i at z = 0 relative to outdoor static pressure.
    """

    area_m2: np.ndarray
    discharge: np.ndarray
    stack_height_m: float
    cavity_area_m2: float
    facade_area_m2: float
    min_opening_ratio: float
    dp_reg_pa: float
    room_pressure_pa: float
    cp_incidence_deg: np.ndarray
    cp_bottom: np.ndarray
    cp_top: np.ndarray

    @classmethod
    def from_sections(cls, openings: Openings, facade: Facade) -> AirflowGeometry:
        """The geometry of a panel's ``openings`` and ``facade`` sections."""
        ops = openings
        area = np.zeros(4)
        cd = np.full(4, 0.6)
        for k, name in enumerate(OPENING_NAMES):
            op = getattr(ops, name)
            if op is not None:
                area[k] = op.area_m2
                cd[k] = op.discharge_coefficient
        wp = ops.wind_pressure
        return cls(
            area_m2=area,
            discharge=cd,
            stack_height_m=ops.stack_height_m,
            cavity_area_m2=facade.cavity_depth_m * facade.width_m,
            facade_area_m2=facade.width_m * facade.glazed_height_m,
            min_opening_ratio=ops.min_opening_ratio,
            dp_reg_pa=ops.regularisation_pa,
            room_pressure_pa=ops.room_pressure_pa,
            cp_incidence_deg=np.asarray(wp.incidence_deg, float),
            cp_bottom=np.asarray(wp.cp_bottom, float),
            cp_top=np.asarray(wp.cp_top, float),
        )

    @property
    def z_m(self) -> np.ndarray:
        """Height of each opening centre above the bottom row [m]."""
        return np.where(IS_TOP, self.stack_height_m, 0.0)

    def wind_pressure_coefficients(
        self, wind_dir_deg: np.ndarray, facade_azimuth_deg: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """C_p of the bottom and top openings for a wind from ``wind_dir_deg``.

        Parameters
        ----------
        wind_dir_deg : array, [deg]
            Direction the wind comes FROM, clockwise from north.
        facade_azimuth_deg : float, [deg]
            Outward normal of the façade.

        Returns
        -------
        cp_bottom, cp_top : arrays, [-]
            Interpolated in the incidence table, incidence = |θ_w − γ_f| wrapped to 0…180°.
        """
        rel = np.asarray(wind_dir_deg, float) - facade_azimuth_deg
        inc = np.abs((rel + 180.0) % 360.0 - 180.0)
        return (
            np.interp(inc, self.cp_incidence_deg, self.cp_bottom),
            np.interp(inc, self.cp_incidence_deg, self.cp_top),
        )


class AirflowBoundary(NamedTuple):
    """Boundary conditions of one step, broadcastable over the batch (SI, K)."""

    t_out_k: np.ndarray
    t_in_k: np.ndarray
    p_atm_pa: np.ndarray
    wind_ms: np.ndarray
    cp_bottom: np.ndarray
    cp_top: np.ndarray


class FlowState(NamedTuple):
    """Airflow through the cavity for one step.

    Attributes
    ----------
    m_dot : ndarray (..., 4), [kg/s]
        Mass flow through EB, ET, IB, IT, positive into the cavity.
    label : ndarray (...,), int
        Realised regime label 1..10 (direction follows the driving pressure).
    q_cav : ndarray (...,), [m3/s]
        Net upward cavity flow (ṁ_EB + ṁ_IB)/ρ_c (docs/model.md#cavity-velocity).
    """

    m_dot: np.ndarray
    label: np.ndarray
    q_cav: np.ndarray


def air_density(t_k: np.ndarray, p_pa: np.ndarray | float) -> np.ndarray:
    """Ideal-gas density of dry air, ρ = p / (R T) [kg/m3] (t_k in [K], p_pa in [Pa])."""
    return np.asarray(p_pa) / (R_AIR * np.asarray(t_k))


def regularised_power(dp: np.ndarray, coef: np.ndarray, m: np.ndarray | float,
                      dp_t: float) -> np.ndarray:
    """Flow ``coef·sgn(Δp)|Δp|^m`` made C²-smooth below ``dp_t`` (IBPSA ``powerLawFixedM``).

    Parameters
    ----------
    dp : array, [Pa]
        Pressure difference.
    coef : array
        Flow coefficient (units of flow per Pa^m).
    m : float or array, [-]
        Exponent, 0.5 (orifice) … 1 (laminar).
    dp_t : float, [Pa]
        Threshold below which the odd polynomial replaces the power law.

    Notes
    -----
    For π = Δp/Δp_t, |π| < 1: Q = C Δp_t^m π (a + π²(b + π²(c + π² d))) with a = γ = 1.5,
    b = m²/8 − 3γ − 3m/2 + 35/8, c = −m²/4 + 3γ + 5m/2 − 21/4, d = m²/8 − γ − m + 15/8,
    which matches value, slope and curvature of the power law at |π| = 1
    (docs/model.md#regularisation; Wetter, IBPSA Modelica library,
    ``Airflow.Multizone.BaseClasses.powerLawFixedM``).
    """
    dp = np.asarray(dp, float)
    mag = np.abs(dp)
    if mag.size and mag.min() >= dp_t:  # common case: no sample near ΔP = 0
        return coef * np.copysign(mag**m, dp)
    a, b, c, d = _poly_coefficients(np.asarray(m, float))
    big = mag >= dp_t
    outer = np.copysign(np.where(big, mag, dp_t) ** m, dp)
    p = dp / dp_t
    p2 = p * p
    inner = dp_t**m * p * (a + p2 * (b + p2 * (c + p2 * d)))
    return coef * np.where(big, outer, inner)


def _poly_coefficients(m: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """IBPSA coefficients a, b, c, d of the regularising polynomial for exponent m
    (docs/model.md#regularisation)."""
    if m.ndim == 0:
        return _poly_coefficients_scalar(float(m))
    b = m * m / 8 - 3 * _GAMMA - 1.5 * m + 35 / 8
    c = -m * m / 4 + 3 * _GAMMA + 2.5 * m - 21 / 4
    d = m * m / 8 - _GAMMA - m + 15 / 8
    return _GAMMA, b, c, d


@functools.lru_cache(maxsize=32)
def _poly_coefficients_scalar(m: float) -> tuple[float, float, float, float]:
    b = m * m / 8 - 3 * _GAMMA - 1.5 * m + 35 / 8
    c = -m * m / 4 + 3 * _GAMMA + 2.5 * m - 21 / 4
    d = m * m / 8 - _GAMMA - m + 15 / 8
    return _GAMMA, b, c, d


def _regularised_power_slope(dp: np.ndarray, coef: np.ndarray, m: float,
                             dp_t: float) -> np.ndarray:
    """d/dΔp of :func:`regularised_power` (always > 0 where coef > 0)."""
    a, b, c, d = _poly_coefficients(np.asarray(m, float))
    mag = np.abs(dp)
    big = mag >= dp_t
    p2 = (dp / dp_t) ** 2
    inner = dp_t ** (m - 1) * (a + p2 * (3 * b + p2 * (5 * c + p2 * 7 * d)))
    outer = m * np.power(np.where(big, mag, dp_t), m - 1)
    return np.asarray(coef) * np.where(big, outer, inner)


def boundary_state(bnd: AirflowBoundary, geom: AirflowGeometry) -> tuple[np.ndarray, ...]:
    """Static pressure, density and temperature of the air outside each opening.

    Returns
    -------
    p_b : ndarray (..., 4), [Pa]
        Outdoor openings: −ρ_o g z + ½ ρ_o C_p U²; room openings: P_i − ρ_i g z
        (docs/model.md#driving-pressures).
    rho_b : ndarray (..., 4), [kg/m3]
    t_b : ndarray (..., 4), [K]
    """
    rho_o = air_density(bnd.t_out_k, bnd.p_atm_pa)
    rho_i = air_density(bnd.t_in_k, bnd.p_atm_pa)
    z = geom.z_m
    dyn = 0.5 * rho_o * np.asarray(bnd.wind_ms) ** 2
    p_eb = dyn * bnd.cp_bottom
    p_et = -rho_o * GRAVITY * z[ET] + dyn * bnd.cp_top
    p_ib = geom.room_pressure_pa + 0.0 * rho_i
    p_it = geom.room_pressure_pa - rho_i * GRAVITY * z[IT]
    p_b = np.stack(np.broadcast_arrays(p_eb, p_et, p_ib, p_it), axis=-1)
    rho_b = np.stack(np.broadcast_arrays(rho_o, rho_o, rho_i, rho_i), axis=-1)
    t_o, t_i = np.broadcast_arrays(np.asarray(bnd.t_out_k, float), np.asarray(bnd.t_in_k, float))
    t_b = np.stack((t_o, t_o, t_i, t_i), axis=-1)
    return p_b, rho_b, t_b


def opening_resistance(or_: np.ndarray, f: np.ndarray, geom: AirflowGeometry) -> np.ndarray:
    """Per-opening loss coefficient K_k = 1/(C_d A_k OR)² + f/(2 A_c²) [1/m4]
    (docs/model.md#openings).

    Absent dampers get K = inf. OR is floored at ``min_opening_ratio`` (docs/model.md#openings).
    """
    or_eff = np.maximum(np.asarray(or_, float), geom.min_opening_ratio)[..., None]
    area = geom.area_m2 * or_eff
    with np.errstate(divide="ignore"):
        damper = np.where(area > 0, 1.0 / (geom.discharge * np.where(area > 0, area, 1.0)) ** 2,
                          np.inf)
    return damper + (np.asarray(f, float)[..., None] / (2.0 * geom.cavity_area_m2**2))


#: The two diagonal paths (inlet, outlet) in their exhaust direction: regimes 5/8 and 6/7.
DIAGONAL_PATHS = tuple(PATHS[r][:2] for r in (5, 6))


def diagonal_path_resistance(f: np.ndarray | float, geom: AirflowGeometry) -> np.ndarray:
    """Series loss coefficient K_in + K_out of each diagonal path at OR = 1 [1/m4]
    (docs/model.md#c-follows-f).

    Returns
    -------
    ndarray (..., 2), [1/m4]
        The IB + ET path (regimes 5 and 8) and the IT + EB path (6 and 7); inf where an
        opening is absent.
    """
    f = np.asarray(f, float)
    k = opening_resistance(np.ones(f.shape), f, geom)
    return np.stack([k[..., a] + k[..., b] for a, b in DIAGONAL_PATHS], axis=-1)


def path_pressure(p_b: np.ndarray, z: np.ndarray, rho_c: np.ndarray, inlet: int,
                  outlet: int) -> np.ndarray:
    """Driving pressure of a two-opening path at zero flow, positive inlet → outlet [Pa].

    ΔP = p_B,in − p_B,out + ρ_c g (z_in − z_out): the boundary pressures and the cavity's
    hydrostatic column between the two openings (docs/model.md#regimes,
    docs/model.md#plant-airflow).
    """
    return p_b[..., inlet] - p_b[..., outlet] + rho_c * GRAVITY * (z[inlet] - z[outlet])


def orifice_path_mass_flow(dp: np.ndarray, k_in: np.ndarray, k_out: np.ndarray,
                           rho_in: np.ndarray, rho_c: np.ndarray, dp_t: float) -> np.ndarray:
    """Closed-form mass flow of two orifices in series [kg/s] (docs/model.md#path-flows).

    ṁ = sgn(ΔP) sqrt(2|ΔP| / (K_in/ρ_in + K_out/ρ_c)): the inlet passes boundary air,
    the outlet passes cavity air. Regularised below ``dp_t`` with m = 0.5.
    """
    # K > 0 always (inf for a closed opening), so 2/ΣK/ρ is finite or 0 and no warning can
    # arise; the isfinite guard is for NaN inputs.
    coef = np.sqrt(2.0 / (k_in / rho_in + k_out / rho_c))
    coef = np.where(np.isfinite(coef), coef, 0.0)
    return regularised_power(dp, coef, 0.5, dp_t)


def louver_series_factor(q_m3s: np.ndarray, dp_pa: np.ndarray, n: np.ndarray,
                         rho_c: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Flow ratio s [-] of a power-law path with the louver's loss in series
    (docs/model.md#louver-flow-loss): the path carries s·Q.

    Parameters
    ----------
    q_m3s : array, [m3/s]
        Flow of the power law alone, Q = c·OR·sgn(ΔP)|ΔP|^n (regularised).
    dp_pa : array, [Pa]
        The path's driving pressure ΔP.
    n : array, [-]
        Power-law exponent.
    rho_c : array, [kg/m3]
        Density of the air passing the slats (the cavity air).
    beta : array, [1/m4]
        K_L / (2 A_c²): the louver loss K_L(φ) [-] referred to the cavity section.

    Notes
    -----
    The slats take ρ_c β (sQ)² of the driving pressure and the power law the rest, which
    passes sQ when it gets s^(1/n) of ΔP:

        s^(1/n) + w s² = 1,        w = ρ_c β Q² / |ΔP|.

    s₀ = 1/sqrt(1 + w) solves it for n = 0.5 (two quadratic losses in series); two Newton
    steps from there solve it to 2·10⁻⁵ of the flow for n ≤ 1 at the Suwon louver and
    c ≤ 0.5 (tested against a bracketing root finder). Written relative to the point
    (Q, ΔP), the equation also holds inside the regularisation, where Q is linear in ΔP,
    so w → 0 and s → 1 as ΔP → 0.
    """
    mag = np.abs(dp_pa)
    w = rho_c * beta * np.divide(q_m3s * q_m3s, mag,
                                 out=np.zeros(np.broadcast(q_m3s, mag).shape), where=mag > 0)
    s = 1.0 / np.sqrt(1.0 + w)
    inv_n = 1.0 / np.asarray(n, float)
    for _ in range(2):
        s_pow = s ** inv_n
        s = s - (s_pow - 1.0 + w * s * s) / (inv_n * s_pow / s + 2.0 * w * s)
    return s


def louver_flow_loss(phi_rad: np.ndarray | float, *, depth_m: float, slat_width_m: float,
                     slat_pitch_m: float, height_m: float) -> np.ndarray:
    """Cavity loss K_L(φ) of the louver, referenced to the cavity velocity [-].

    Parameters
    ----------
    phi_rad : array, [rad]
        Louver slat angle (0 = horizontal slats, ±π/2 = slats vertical, in the glass plane).
    depth_m, slat_width_m, slat_pitch_m, height_m : float, [m]
        Cavity depth D, slat width w, vertical slat spacing s and glazed height H_g.

    Notes
    -----
    Each slat row contracts the cavity to the free section D − w|cos φ| and the flow
    expands again behind it; the Borda–Carnot loss of that sudden expansion is
    ζ_row = (D/(D − w|cos φ|) − 1)² referenced to the cavity velocity, and the H_g/s rows
    add up: K_L = (H_g/s) ζ_row (docs/model.md#louver-flow-loss [ENG, order of magnitude]; the
    sudden-expansion loss of Idelchik, *Handbook of Hydraulic Resistance*, referred to the wide
    section). About 3.4 at φ = 0 and 0 at ±90° for the Suwon panel. It adds to the form loss f of
    the orifice regimes.
    """
    free = depth_m - slat_width_m * np.abs(np.cos(np.asarray(phi_rad, float)))
    zeta = (depth_m / np.maximum(free, 1e-3 * depth_m) - 1.0) ** 2
    return height_m / slat_pitch_m * zeta
