"""Local heat-transfer and flow-resistance correlations of the truth plant
(docs/model.md#truth-plant).

Pure, vectorised functions (any broadcastable arrays; SI units, kelvin). The truth plant
multiplies each convective coefficient by a hidden multiplier (docs/model.md#true-parameters).
Temperature differences enter through ``|ΔT|`` regularised as ``sqrt(ΔT² + δ²)`` with δ = 0.1 K, so
every coefficient is smooth in the states (the stiff integrator needs that).

References
----------
S. W. Churchill, H. H. S. Chu, "Correlating equations for laminar and turbulent free
convection from a vertical plate", Int. J. Heat Mass Transfer 18 (1975) 1323–1329.
ISO 15099:2003 §8.3 (room-side convection, closed cavities), as given in the EnergyPlus
Engineering Reference ("Window Heat Balance Calculation").
EnergyPlus Engineering Reference, "Outside Surface Heat Balance" (DOE-2, MoWiTT, TARP).
K. Stephan, "Wärmeübergang und Druckabfall bei nicht ausgebildeter Laminarströmung in Rohren
und ebenen Spalten", Chem.-Ing.-Tech. 31 (1959) 773–778 (VDI Heat Atlas, parallel plates).
IBPSA / Modelica Buildings library, ``Airflow.Multizone``/``Fluid.Actuators.Dampers``
(exponential damper characteristic, Wetter et al.).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.physics.constants import GRAVITY, R_AIR

FloatArray = NDArray[np.float64]

#: Prandtl number of air [-].
PR_AIR = 0.71
#: Specific heat capacity of air [J/(kg K)].
CP_AIR = 1006.0
#: Regularisation δ of |ΔT| [K].
DT_SMOOTH_K = 0.1
#: Churchill–Chu factor 0.387 / (1 + (0.492/Pr)^(9/16))^(8/27) for air.
_CC_FACTOR = 0.387 / (1.0 + (0.492 / PR_AIR) ** (9.0 / 16.0)) ** (8.0 / 27.0)
#: IBPSA exponential damper: a, b (per unit opening), y_L, y_U, ζ(open), ζ(closed).
DAMPER_A, DAMPER_B = -1.51, 0.105 * 90.0
DAMPER_Y_LOW, DAMPER_Y_HIGH = 15.0 / 90.0, 55.0 / 90.0
DAMPER_K_OPEN, DAMPER_K_CLOSED = 0.45, 1.0e6
_LOG_OPEN, _LOG_CLOSED = math.log(DAMPER_K_OPEN), math.log(DAMPER_K_CLOSED)
#: DOE-2 / MoWiTT forced-convection coefficients (a, b) for windward and leeward glass.
WINDWARD_AB, LEEWARD_AB = (3.26, 0.89), (3.55, 0.617)


def _abs_smooth(dt: ArrayLike) -> FloatArray:
    dt = np.asarray(dt, float)
    return np.sqrt(dt * dt + DT_SMOOTH_K * DT_SMOOTH_K)


def air_conductivity(t_k: ArrayLike) -> FloatArray:
    """Thermal conductivity of air k = 2.873e-3 + 7.76e-5 T [W/(m K)]
    (docs/model.md#plant-heat-transfer)."""
    return 2.873e-3 + 7.76e-5 * np.asarray(t_k, float)


def air_viscosity(t_k: ArrayLike) -> FloatArray:
    """Dynamic viscosity of air μ = 3.723e-6 + 4.94e-8 T [Pa s]
    (docs/model.md#plant-heat-transfer)."""
    return 3.723e-6 + 4.94e-8 * np.asarray(t_k, float)


def churchill_chu_vertical(dt_k: ArrayLike, t_film_k: ArrayLike, height_m: float,
                           p_pa: ArrayLike) -> FloatArray:
    """Natural convection from a vertical plate, Churchill & Chu (1975) [W/(m2 K)].

    Parameters
    ----------
    dt_k : array_like, [K]
        Surface − air temperature difference (sign irrelevant).
    t_film_k : array_like, [K]
        Film temperature for the properties and β = 1/T_f.
    height_m : float, [m]
        Plate height H.
    p_pa : array_like, [Pa]
        Air pressure (density ρ = p/(R T_f)).

    Notes
    -----
    Nu_H = (0.825 + 0.387 Ra^{1/6} / [1 + (0.492/Pr)^{9/16}]^{8/27})²,
    Ra = g β |ΔT| H³/(ν α), valid for all Ra; for air (Pr = 0.71) this is
    (0.825 + 0.325 Ra^{1/6})² as in docs/model.md#plant-heat-transfer. h = Nu k/H.
    """
    t_f = np.asarray(t_film_k, float)
    k = air_conductivity(t_f)
    rho = np.asarray(p_pa, float) / (R_AIR * t_f)
    # ν α = μ k / (ρ² c_p)
    ra = (GRAVITY * CP_AIR * height_m**3) * _abs_smooth(dt_k) * rho * rho / (
        t_f * air_viscosity(t_f) * k)
    nu_h = (0.825 + _CC_FACTOR * ra ** (1.0 / 6.0)) ** 2
    return nu_h * k / height_m


def parallel_plates_developing(speed_ms: ArrayLike, x_m: ArrayLike, gap_m: float,
                               t_k: ArrayLike, p_pa: ArrayLike) -> FloatArray:
    """Laminar forced convection between parallel plates with entrance effect [W/(m2 K)].

    Parameters
    ----------
    speed_ms : array_like, [m/s]
        Mean air speed in the gap (sign irrelevant).
    x_m : array_like, [m]
        Distance from the inlet of the gap.
    gap_m : float, [m]
        Plate spacing b; hydraulic diameter D_h = 2b.
    t_k, p_pa : array_like
        Air temperature [K] and pressure [Pa].

    Notes
    -----
    Mean Nusselt number of simultaneously developing laminar flow (Stephan 1959, VDI
    Heat Atlas), evaluated with the distance to the segment [ENG]::

        Nu = 7.55 + 0.024 G^{1.14} / (1 + 0.0358 Pr^{0.17} G^{0.64}),   G = D_h Re Pr / x

    which tends to the fully developed value 7.54 (docs/model.md#plant-heat-transfer) far from the
    inlet or at zero flow. h = Nu k/D_h.
    """
    t = np.asarray(t_k, float)
    k = air_conductivity(t)
    rho = np.asarray(p_pa, float) / (R_AIR * t)
    dh = 2.0 * gap_m
    re = np.abs(np.asarray(speed_ms, float)) * dh * rho / air_viscosity(t)
    g = dh * re * PR_AIR / np.maximum(np.asarray(x_m, float), 1e-3)
    nu = 7.55 + 0.024 * g**1.14 / (1.0 + 0.0358 * PR_AIR**0.17 * g**0.64)
    return nu * k / dh


def flat_plate_laminar(speed_ms: ArrayLike, length_m: float, t_k: ArrayLike,
                       p_pa: ArrayLike) -> FloatArray:
    """Mean laminar forced convection over a flat plate (slat) [W/(m2 K)].

    Notes
    -----
    Nu_L = 0.664 Re_L^{1/2} Pr^{1/3} (Pohlhausen), with Re_L regularised as
    (Re_L² + 1)^{1/2} so the slope stays finite at zero flow. L = slat width.
    """
    t = np.asarray(t_k, float)
    k = air_conductivity(t)
    rho = np.asarray(p_pa, float) / (R_AIR * t)
    re = np.abs(np.asarray(speed_ms, float)) * length_m * rho / air_viscosity(t)
    nu = 0.664 * (re * re + 1.0) ** 0.25 * PR_AIR ** (1.0 / 3.0)
    return nu * k / length_m


def mixed_convection(h_natural: ArrayLike, h_forced: ArrayLike) -> FloatArray:
    """Cubic blend h = (h_n³ + h_f³)^{1/3} [W/(m2 K)] (Churchill's mixed-convection rule)."""
    hn = np.asarray(h_natural, float)
    hf = np.asarray(h_forced, float)
    return np.cbrt(hn**3 + hf**3)


def doe2_exterior(dt_k: ArrayLike, wind_ms: ArrayLike, windward: ArrayLike) -> FloatArray:
    """Exterior convection of glass, DOE-2 model (EnergyPlus ER) [W/(m2 K)].

    Parameters
    ----------
    dt_k : array_like, [K]
        Surface − outdoor air temperature difference.
    wind_ms : array_like, [m/s]
        Local wind speed at the surface height (wind profile, docs/model.md#plant-heat-transfer).
    windward : array_like of bool
        Wind within 100° of the surface normal.

    Notes
    -----
    h = sqrt(h_n² + (a V_z^b)²), h_n = 1.31 |ΔT|^{1/3} (TARP, vertical), MoWiTT
    (a, b) = (3.26, 0.89) windward, (3.55, 0.617) leeward; glass has roughness factor 1.
    """
    hn = 1.31 * np.cbrt(_abs_smooth(dt_k))
    ww = np.asarray(windward, bool)
    a = np.where(ww, WINDWARD_AB[0], LEEWARD_AB[0])
    b = np.where(ww, WINDWARD_AB[1], LEEWARD_AB[1])
    hf = a * np.maximum(np.asarray(wind_ms, float), 0.0) ** b
    return np.sqrt(hn * hn + hf * hf)


def iso15099_room(t_surface_k: ArrayLike, t_air_k: ArrayLike, height_m: float,
                  p_pa: ArrayLike) -> FloatArray:
    """Room-side natural convection of a vertical window, ISO 15099 §8.3.2.2 [W/(m2 K)].

    Notes
    -----
    T_mf = T_i + ¼(T_s − T_i); Ra_H = ρ² H³ g c_p |T_s − T_i| / (T_mf μ k) with properties
    at T_mf; Nu = 0.56 Ra_H^{1/4} (laminar, the only branch reached by vertical glazing);
    h = Nu k/H (docs/model.md#plant-heat-transfer).
    """
    ts = np.asarray(t_surface_k, float)
    ti = np.asarray(t_air_k, float)
    t_mf = ti + 0.25 * (ts - ti)
    k = air_conductivity(t_mf)
    mu = air_viscosity(t_mf)
    rho = np.asarray(p_pa, float) / (R_AIR * t_mf)
    ra = rho * rho * height_m**3 * GRAVITY * CP_AIR * _abs_smooth(ts - ti) / (t_mf * mu * k)
    return 0.56 * ra**0.25 * k / height_m


def iso15099_gap(t_a_k: ArrayLike, t_b_k: ArrayLike, gap_m: float, height_m: float,
                 p_pa: ArrayLike) -> FloatArray:
    """Convective conductance across a closed vertical gap, ISO 15099 [W/(m2 K)].

    Notes
    -----
    Ra = g β |ΔT| d³/(ν α), β = 1/T_m (docs/model.md#plant-heat-transfer)::

        Nu1 = 0.0673838 Ra^{1/3}               Ra > 5·10⁴
        Nu1 = 0.028154 Ra^{0.4134}             10⁴ < Ra ≤ 5·10⁴
        Nu1 = 1 + 1.7596678e-10 Ra^{2.2984755} Ra ≤ 10⁴
        Nu2 = 0.242 (Ra d/H)^{0.272};   h_c = max(Nu1, Nu2) k/d

    This is the surface-to-surface conductance; each face ↔ gas link is 2 h_c.
    """
    ta = np.asarray(t_a_k, float)
    tb = np.asarray(t_b_k, float)
    tm = 0.5 * (ta + tb)
    k = air_conductivity(tm)
    rho = np.asarray(p_pa, float) / (R_AIR * tm)
    ra = (GRAVITY * CP_AIR * gap_m**3) * _abs_smooth(ta - tb) * rho * rho / (
        tm * air_viscosity(tm) * k)
    nu1 = np.where(ra > 5e4, 0.0673838 * np.cbrt(ra),
                   np.where(ra > 1e4, 0.028154 * ra**0.4134,
                            1.0 + 1.7596678e-10 * ra**2.2984755))
    nu2 = 0.242 * (ra * gap_m / height_m) ** 0.272
    return np.maximum(nu1, nu2) * k / gap_m


def damper_loss_exponential(opening: ArrayLike) -> FloatArray:
    """Loss coefficient ζ(y) of a damper, referenced to its face velocity [-].

    Parameters
    ----------
    opening : array_like, [-]
        Blade position y, 0 closed … 1 open.

    Notes
    -----
    IBPSA/Modelica Buildings exponential damper (docs/model.md#plant-airflow): ζ = exp(a + b(1 − y))
    for y_L ≤ y ≤ y_U with a = −1.51, b = 0.105·90, y_L = 15/90, y_U = 55/90; outside that
    range log ζ is interpolated linearly to ζ(1) = 0.45 and ζ(0) = 10⁶ [ENG]. The damper
    pressure drop is Δp = ζ ½ρ (Q/A_d)².
    """
    y = np.clip(np.asarray(opening, float), 0.0, 1.0)
    log_mid = DAMPER_A + DAMPER_B * (1.0 - y)
    log_lo = DAMPER_A + DAMPER_B * (1.0 - DAMPER_Y_LOW)
    log_hi = DAMPER_A + DAMPER_B * (1.0 - DAMPER_Y_HIGH)
    below = np.log(DAMPER_K_CLOSED) + (log_lo - np.log(DAMPER_K_CLOSED)) * y / DAMPER_Y_LOW
    above = log_hi + (np.log(DAMPER_K_OPEN) - log_hi) * (y - DAMPER_Y_HIGH) / (
        1.0 - DAMPER_Y_HIGH)
    return np.exp(np.where(y < DAMPER_Y_LOW, below, np.where(y > DAMPER_Y_HIGH, above,
                                                              log_mid)))


def damper_loss_scalar(y: float) -> float:
    """:func:`damper_loss_exponential` for one Python float (fast path of the plant)."""
    y = min(max(y, 0.0), 1.0)
    if y < DAMPER_Y_LOW:
        lo = DAMPER_A + DAMPER_B * (1.0 - DAMPER_Y_LOW)
        return math.exp(_LOG_CLOSED + (lo - _LOG_CLOSED) * y / DAMPER_Y_LOW)
    if y > DAMPER_Y_HIGH:
        hi = DAMPER_A + DAMPER_B * (1.0 - DAMPER_Y_HIGH)
        return math.exp(hi + (_LOG_OPEN - hi) * (y - DAMPER_Y_HIGH) / (1.0 - DAMPER_Y_HIGH))
    return math.exp(DAMPER_A + DAMPER_B * (1.0 - y))


def lateral_open_fraction(phi_rad: ArrayLike, *, slat_width_m: float,
                          slat_pitch_m: float) -> FloatArray:
    """Open fraction of the louver plane, max(0, 1 − (w/s)|sin φ|) [-]
    (docs/model.md#plant-layout)."""
    return np.maximum(0.0, 1.0 - slat_width_m / slat_pitch_m
                      * np.abs(np.sin(np.asarray(phi_rad, float))))
