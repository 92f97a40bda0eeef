"""The louver slats' convective film against the cavity speed (docs/model.md#slat-film).

The paper's model has one slat–air coefficient h_ca2 for every regime. On the slats two
mechanisms add: natural convection (the warm slats' own buoyant flow) and forced convection
(the cavity flow across the slat width). Their mixed-convection blend is cubic,
h = (h_n³ + h_f³)^⅓ (Churchill & Usagi 1972; the rule of Churchill 1977 for assisting
flows), with

* h_f = C_f √v, the laminar flat plate over the slat width L: Nu_L = 0.664 Re_L^½ Pr^⅓
  (Pohlhausen; Incropera & DeWitt, eq. 7.30), so C_f = 0.664 k Pr^⅓ / √(ν L);
* h_n from Churchill & Chu (1975) for a vertical plate of the cavity's height at a
  ``excess_k`` slat excess.

The two parts are equal at v_e = (h_n / C_f)², about 0.03 m/s for 50 mm slats in a 2 m
cavity. The lumped model keeps h_ca2 as the coefficient at a reference speed v_ref and
scales it by

    F(v) = ∛[(1 + (v / v_e)^{3/2}) / (1 + (v_ref / v_e)^{3/2})]

(F(v_ref) = 1; F ∝ √v well above v_e; F(0) = the natural part alone), so the calibrated
h_ca2 keeps its meaning and its prior while a faster regime cools the slats more: between
0.033 m/s (supply air) and 0.139 m/s (room air up the cavity) F grows 1.7-fold.

Pure functions (no I/O). Air properties at 300 K from Incropera & DeWitt, Table A.4.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from dsfd.physics.constants import GRAVITY

if TYPE_CHECKING:
    from dsfd.config.panel import PanelConfig

__all__ = ["equal_speed_ms", "film_factor", "panel_equal_speed_ms"]

#: Air at 300 K (Incropera & DeWitt, Table A.4): conductivity [W/(m K)], kinematic
#: viscosity [m²/s], Prandtl number [-].
K_AIR, NU_AIR, PR_AIR = 0.0263, 15.89e-6, 0.707


def equal_speed_ms(*, slat_width_m: float, height_m: float, excess_k: float = 10.0,
                   t_film_k: float = 300.0) -> float:
    """v_e [m/s]: the cavity speed at which forced and natural convection on the slats are
    equal (module docstring).

    Parameters
    ----------
    slat_width_m : float, [m]
        Slat width L (the forced flow's run length).
    height_m : float, [m]
        Height of the cavity (the natural convection's plate).
    excess_k : float, [K]
        Slat temperature over the cavity air.
    t_film_k : float, [K]
        Film temperature of the buoyancy coefficient β = 1/T.
    """
    alpha = NU_AIR / PR_AIR
    ra = GRAVITY / t_film_k * excess_k * height_m ** 3 / (NU_AIR * alpha)
    cc = 0.387 / (1.0 + (0.492 / PR_AIR) ** (9.0 / 16.0)) ** (8.0 / 27.0)
    h_n = (0.825 + cc * ra ** (1.0 / 6.0)) ** 2 * K_AIR / height_m
    c_f = 0.664 * K_AIR * PR_AIR ** (1.0 / 3.0) / math.sqrt(NU_AIR * slat_width_m)
    return (h_n / c_f) ** 2


def panel_equal_speed_ms(cfg: PanelConfig) -> float:
    """v_e [m/s] of the panel's slats over its glazed height (:func:`equal_speed_ms`);
    0 for a panel without louver (no slat film to scale)."""
    lv = cfg.louver
    if lv is None:
        return 0.0
    return equal_speed_ms(slat_width_m=lv.slat_width_m, height_m=cfg.facade.glazed_height_m)


def film_factor(speed_ms: np.ndarray, *, equal_speed_ms: float,
                reference_speed_ms: float) -> np.ndarray:
    """F(v) [-]: the slat film at cavity speed ``speed_ms`` [m/s] over the film at
    ``reference_speed_ms`` (module docstring); ``equal_speed_ms`` v_e [m/s]."""
    v = np.abs(np.asarray(speed_ms, float))
    ref = 1.0 + (reference_speed_ms / equal_speed_ms) ** 1.5
    return np.cbrt((1.0 + (v / equal_speed_ms) ** 1.5) / ref)
