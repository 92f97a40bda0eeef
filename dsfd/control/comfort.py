"""Which comfort limits a command would break: the comfort quantities of one step.

docs/model.md#comfort. Pure: the caller gives the forcing, the command, whether the room is
occupied (:func:`dsfd.control.occupancy.occupied`) and the temperatures of the inner pane and
of the air a regime blows into the room. This names limits; it does not change decisions.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from dsfd.physics.comfort_geometry import window_view_factor
from dsfd.physics.comfort_thermal import asymmetry_limit_k, radiant_asymmetry_k, supply_air_min_c
from dsfd.physics.comfort_visual import dgp_simplified, eye_illuminance_lx

if TYPE_CHECKING:
    from dsfd.config.panel import PanelConfig
    from dsfd.physics.forcing import FacadeOptics, Forcing

__all__ = ["INFLOW_REGIMES", "ComfortCheck", "comfort_check", "view_factors"]

#: Regimes whose open dampers let cavity air into the room (docs/model.md#regimes): inside
#: circulation (1, 2), supply (7, 8) and all open (9); exhaust and curtains do not.
INFLOW_REGIMES = frozenset({1, 2, 7, 8, 9})


class ComfortCheck(NamedTuple):
    """Comfort quantities of one step and the limits they break while occupied."""

    occupied: bool
    direct_sun_wm2: float  #: solar beam passing the louver unscattered into the room
    dgp: float  #: simplified daylight glare probability at the occupant's eye
    supply_air_c: float | None  #: air blown into the room, None when none is
    asymmetry_k: float  #: radiant asymmetry of the pane, + warm
    violations: tuple[str, ...]  #: one phrase per broken limit; empty if none or unoccupied
    #: What comfort did to the decision (``Decision.comfort``, docs/model.md#comfort-trace).
    bound: str = ""

    def describe(self) -> str:
        """One line for the decision trace."""
        state = "occupied" if self.occupied else "unoccupied (no limit)"
        air = "none" if self.supply_air_c is None else f"{self.supply_air_c:.1f} °C"
        seen = (f"{state}; direct sun {self.direct_sun_wm2:.0f} W/m2, DGPs {self.dgp:.2f}, "
                f"supply air {air}, asymmetry {self.asymmetry_k:+.1f} K")
        if self.violations:
            seen = f"{seen}; would violate: {'; '.join(self.violations)}"
        return f"{seen}; decision: {self.bound}" if self.bound else seen


def view_factors(cfg: PanelConfig) -> tuple[float, float]:
    """(eye, asymmetry point) view factors of the window for the configured occupant."""
    c, fac = cfg.comfort, cfg.facade

    def at(height_m: float) -> float:
        return float(window_view_factor(
            distance_m=c.occupant_distance_m, width_m=fac.width_m,
            height_m=fac.glazed_height_m, lateral_m=0.5 * fac.width_m,
            elevation_m=height_m - c.sill_height_m))

    return at(c.eye_height_m), at(c.asymmetry_height_m)


def comfort_check(
    cfg: PanelConfig, optics: FacadeOptics, forcing: Forcing, *, phi_deg: float, afr: int,
    or_pct: float, occupied: bool, t_pane_c: float, t_supply_c: float,
) -> ComfortCheck:
    """The comfort quantities of ``forcing``'s first step under a command.

    ``t_pane_c`` is the inner pane's room face (x3) [°C], set against the forcing's room mean
    radiant temperature; ``t_supply_c`` [°C] is the air the regime would blow into the room
    (the cavity air), used only for regimes in :data:`INFLOW_REGIMES` with an opening.
    Outside occupancy the quantities are computed and no limit is named.
    """
    f = forcing.window(0, 1)
    solar, vis = optics.layers(f, np.asarray(math.radians(phi_deg)))
    f_eye, f_body = view_factors(cfg)
    e_v = eye_illuminance_lx(transmitted_wm2=vis.transmitted,
                             transmitted_beam_wm2=vis.transmitted_beam, view_factor=f_eye,
                             luminous_efficacy_lmw=cfg.daylight.luminous_efficacy_lmw)
    t_room_c = float(f.t_mrt_k[0]) - 273.15
    supply = t_supply_c if afr in INFLOW_REGIMES and or_pct > 0.0 else None
    check = ComfortCheck(
        occupied=occupied, direct_sun_wm2=float(solar.transmitted_beam[0]),
        dgp=float(dgp_simplified(e_v)[0]), supply_air_c=supply,
        asymmetry_k=float(radiant_asymmetry_k(view_factor=f_body, t_pane_c=t_pane_c,
                                              t_room_c=t_room_c)),
        violations=())
    return check._replace(violations=_violations(cfg, check)) if occupied else check


def _violations(cfg: PanelConfig, c: ComfortCheck) -> tuple[str, ...]:
    lim = cfg.comfort
    out = []
    if c.direct_sun_wm2 > lim.direct_sun_max_wm2:
        out.append(f"direct sun {c.direct_sun_wm2:.0f} > {lim.direct_sun_max_wm2:g} W/m2")
    if c.dgp > lim.dgp_max:
        out.append(f"DGPs {c.dgp:.2f} > {lim.dgp_max:g}")
    air_min = supply_air_min_c(lim)
    if c.supply_air_c is not None and c.supply_air_c < air_min:
        out.append(f"supply air {c.supply_air_c:.1f} < {air_min:.1f} °C")
    warm = c.asymmetry_k > 0.0
    asym_max = asymmetry_limit_k(lim.category, warm=warm)
    if abs(c.asymmetry_k) > asym_max:
        wall = "warm" if warm else "cool"
        out.append(f"{wall}-pane asymmetry {abs(c.asymmetry_k):.1f} > {asym_max:g} K "
                   f"(category {lim.category})")
    return tuple(out)
