"""Local thermal comfort near the panel: draught from supply air, radiant asymmetry of the pane.

docs/model.md#thermal-comfort, after ISO 7730:2005 §6 and Annex A (local thermal discomfort)
and ISO 7726:1998 (plane radiant temperature). Temperatures in °C at this module's edge
(limits are differences in K), as the config gives them.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.config.comfort import DRAUGHT_RATE_MAX_PCT, Comfort

__all__ = [
    "ASYMMETRY_WALL_MAX_K",
    "DRAUGHT_RATE_MAX_PCT",
    "asymmetry_limit_k",
    "draught_rate_pct",
    "draught_temperature_min_c",
    "plane_radiant_temperature_c",
    "radiant_asymmetry_k",
    "supply_air_min_c",
]

FloatArray = NDArray[np.float64]
Category = Literal["A", "B", "C"]

#: ISO 7730:2005 Table A.4, radiant temperature asymmetry [K] of a wall: (warm, cool).
ASYMMETRY_WALL_MAX_K: dict[str, tuple[float, float]] = {
    "A": (23.0, 10.0), "B": (23.0, 10.0), "C": (35.0, 13.0)}

_KELVIN = 273.15
#: Below this mean air speed ISO 7730 takes 0.05 m/s (the model's threshold of sensation).
_V_MIN_MS = 0.05
#: Above this local air temperature ISO 7730 takes 34 °C (no draught).
_T_MAX_C = 34.0


def _speed_factor(v_ms: FloatArray, turbulence_pct: FloatArray) -> FloatArray:
    v = np.maximum(v_ms, _V_MIN_MS)
    return (v - _V_MIN_MS) ** 0.62 * (0.37 * v * turbulence_pct + 3.14)


def draught_rate_pct(
    t_air_c: ArrayLike, v_ms: ArrayLike, turbulence_pct: ArrayLike
) -> FloatArray:
    """Draught rate DR, the percentage dissatisfied by draught [%] (ISO 7730:2005 §6.2).

    Notes
    -----
    docs/model.md#thermal-comfort::

        DR = (34 - t_a,l)(v_a,l - 0.05)^0.62 (0.37 v_a,l Tu + 3.14),   DR <= 100

    with v_a,l < 0.05 m/s taken as 0.05 and t_a,l > 34 °C as 34 (ISO 7730:2005 §6.2).
    """
    t = np.minimum(np.asarray(t_air_c, dtype=float), _T_MAX_C)
    v = np.asarray(v_ms, dtype=float)
    tu = np.asarray(turbulence_pct, dtype=float)
    return np.minimum((_T_MAX_C - t) * _speed_factor(v, tu), 100.0)


def draught_temperature_min_c(
    dr_max_pct: ArrayLike, v_ms: ArrayLike, turbulence_pct: ArrayLike
) -> FloatArray:
    """Coldest local air [°C] at which DR stays at ``dr_max_pct`` for that speed (the inverse).

    ``-inf`` when the speed is at or below 0.05 m/s (no draught at any temperature).
    """
    factor = _speed_factor(np.asarray(v_ms, dtype=float), np.asarray(turbulence_pct, float))
    with np.errstate(divide="ignore"):
        return _T_MAX_C - np.asarray(dr_max_pct, dtype=float) / factor


def supply_air_min_c(comfort: Comfort) -> float:
    """Coldest supply air allowed into an occupied room [°C] (docs/model.md#thermal-comfort).

    ``comfort.supply_air_min_c`` when set; otherwise the temperature at which air reaching
    the occupant at ``supply_air_speed_ms`` and ``turbulence_pct`` gives the draught rate
    limit of the ISO 7730 category (Table A.1: 10, 20, 30 %), as if unmixed (the worst seat).
    """
    if comfort.supply_air_min_c is not None:
        return comfort.supply_air_min_c
    return float(draught_temperature_min_c(DRAUGHT_RATE_MAX_PCT[comfort.category],
                                           comfort.supply_air_speed_ms,
                                           comfort.turbulence_pct))


def plane_radiant_temperature_c(
    view_factor: ArrayLike, t_window_c: ArrayLike, t_rest_c: ArrayLike
) -> FloatArray:
    """Plane radiant temperature [°C] of a small plane seeing the window and the room.

    Notes
    -----
    ISO 7726:1998 Annex B: t_pr⁴ = Σ F_i T_i⁴ over the half space the plane faces (black
    surfaces, kelvin); here the window with view factor F and the rest of the room::

        T_pr = (F T_w⁴ + (1 - F) T_rest⁴)^(1/4)
    """
    f = np.asarray(view_factor, dtype=float)
    tw = np.asarray(t_window_c, dtype=float) + _KELVIN
    tr = np.asarray(t_rest_c, dtype=float) + _KELVIN
    return (f * tw**4 + (1.0 - f) * tr**4) ** 0.25 - _KELVIN


def radiant_asymmetry_k(
    *, view_factor: ArrayLike, t_pane_c: ArrayLike, t_room_c: ArrayLike
) -> FloatArray:
    """Radiant temperature asymmetry across a plane facing the window [K], signed.

    Positive when the pane is warmer than the room. The side facing the window sees the
    pane (view factor F) and room surfaces; the opposite side sees room surfaces only, all at
    ``t_room_c`` (the room's mean radiant temperature): Δt_pr = t_pr,window − t_room.
    """
    return plane_radiant_temperature_c(view_factor, t_pane_c, t_room_c) - np.asarray(
        t_room_c, dtype=float)


def asymmetry_limit_k(category: Category, *, warm: bool) -> float:
    """ISO 7730:2005 Table A.4 limit of a warm (``warm=True``) or cool wall's asymmetry [K]."""
    warm_k, cool_k = ASYMMETRY_WALL_MAX_K[category]
    return warm_k if warm else cool_k
