"""Comfort limits as constraints of the horizon problem: the normalised violation of candidates.

docs/model.md#comfort-constraints. While a horizon step is occupied, a candidate (louver
position, damper set, opening held over the horizon) is to keep, at every occupied step,

* the solar beam passing the louver unscattered into the room ≤ ``direct_sun_max_wm2``, judged
  under the largest beam the forecast's GHI allows (:func:`direct_sun_bound_wm2`), not under
  the decomposition's estimate;
* the simplified daylight glare probability DGPs at the occupant's eye ≤ ``dgp_max``;
* the air it blows into the room (x̄5 of its rollout, when cavity air enters the room) ≥ the
  supply-air limit (:func:`dsfd.physics.comfort_thermal.supply_air_min_c`);
* the radiant asymmetry of its inner pane (x̄3 of its rollout) within the category's limit.

Each limit's excess is made relative (so that limits of different units add up) and averaged
over the horizon's steps, unoccupied steps counting zero: a candidate's *violation* is the sum
of the four, zero when it meets them all. Pure: the occupied mask, the forcing and the
rollouts are given.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

import numpy as np

from dsfd.control.comfort import view_factors
from dsfd.physics.comfort_thermal import asymmetry_limit_k, radiant_asymmetry_k, supply_air_min_c
from dsfd.physics.comfort_visual import (
    dgp_simplified,
    direct_sun_wm2,
    dni_bound_wm2,
    eye_illuminance_lx,
)
from dsfd.physics.constants import T_ZERO
from dsfd.physics.solar import extraterrestrial_irradiance

if TYPE_CHECKING:
    from dsfd.config.panel import PanelConfig
    from dsfd.control.horizon import Best
    from dsfd.physics.forcing import FacadeOptics, Forcing
    from dsfd.physics.model import Trajectory

__all__ = ["INFLOW_MIN_KGS", "LEAST_VIOLATION", "LIMIT_NAMES", "THERMAL_LIMITS",
           "VIOLATION_BAND", "VISUAL_LIMITS",
           "HorizonComfort", "acceptable", "block_any", "comfort_note", "direct_sun_bound_wm2",
           "equally_violating", "limits_line"]

#: The limits in the order of the excess columns, as the trace names them.
LIMIT_NAMES = ("direct sun cut-off", "glare (DGPs)", "draught (supply air)",
               "radiant asymmetry")
#: The columns of the limits that depend on the louver position and the forcing alone, and
#: of those that depend on the rollout.
VISUAL_LIMITS = slice(0, 2)
THERMAL_LIMITS = slice(2, 4)
#: Cavity air entering the room below this rate [kg/s] (≈ 0.3 m³/h) is no supply: the flow
#: laws' regularisation leaves such rates where the dampers are all but shut.
INFLOW_MIN_KGS = 1e-4
#: Direct sun is made relative to the limit, but never to less than this [W/m2] (a limit of 0).
_DIRECT_SUN_SCALE_MIN_WM2 = 1.0
#: The draught rate of ISO 7730 vanishes at 34 °C; its relative excess is scaled by
#: 34 °C − limit, never by less than this [K] (a limit at or above 34 °C).
_DRAUGHT_SCALE_MIN_K = 1.0
_T_NO_DRAUGHT_C = 34.0
#: When no candidate meets every limit, those within this much normalised violation of the
#: least count as equally violating, and the cheapest of them is taken: one limit exceeded by
#: 1 % of itself over the whole horizon (docs/model.md#comfort-constraints). Absolute, so that
#: a violation no candidate can change (the sun through a panel without a louver) does not
#: widen it.
VIOLATION_BAND = 0.01
#: How the trace starts a least-violation note.
LEAST_VIOLATION = "no candidate meets every limit"


def equally_violating(v_a: float, v_b: float) -> bool:
    """Whether two violations count as the same (:data:`VIOLATION_BAND`; zero only
    matches zero)."""
    lo, hi = sorted((v_a, v_b))
    return hi == 0.0 if lo == 0.0 else hi - lo <= VIOLATION_BAND


def acceptable(violation: np.ndarray) -> np.ndarray:
    """The candidates a decision may take: those meeting every limit, or when none does,
    those within :data:`VIOLATION_BAND` of the least violation."""
    v = np.asarray(violation, float)
    if not v.size:
        return np.zeros(0, bool)
    least = float(v.min())
    return v == 0.0 if least == 0.0 else v <= least + VIOLATION_BAND


def block_any(mask: np.ndarray, factor: int) -> np.ndarray:
    """Whether any step of each block of ``factor`` consecutive steps is set (the occupied
    mask of a screening pass with ``factor`` times the step)."""
    mask = np.asarray(mask, bool)
    return np.logical_or.reduceat(mask, np.arange(0, mask.size, factor)) if mask.size else mask


def direct_sun_bound_wm2(optics: FacadeOptics, forcing: Forcing,
                         phi_rad: np.ndarray) -> np.ndarray:
    """Direct sun [W/m2] of louver angles ``phi_rad`` (broadcast against the steps) under the
    largest beam the forecast allows (docs/model.md#direct-sun-bound).

    The direct normal irradiance is bounded by the GHI of each step,
    DNI <= min(I0, GHI / cos Z) (:func:`~dsfd.physics.comfort_visual.dni_bound_wm2`), and the
    largest bound of the horizon is held over it, as the forecast holds the clearness index
    (its dawn and dusk branch holds GHI instead, whose bound falls as the sun rises while the
    true beam grows). The façade beam judged is that bound on the façade plane (zero with the
    sun below the horizon or behind the façade), never less than the forecast's own estimate
    (e.g. a beam from façade-plane readings). With the sun's geometry exact, this is the
    cut-off the louver needs over the whole horizon whatever the decomposition believes:
    Erbs gives no beam above Z = 87° and too little on a clear winter day
    (docs/model.md#decomposition), which let the sun through the slats in the closed loop.
    """
    dni = np.nan_to_num(dni_bound_wm2(
        ghi_wm2=forcing.ghi_wm2, zenith_deg=forcing.zenith_deg,
        dni_extra_wm2=extraterrestrial_irradiance(forcing.time_s)))
    held = float(dni.max()) if dni.size else 0.0
    cos_aoi = np.cos(np.radians(np.asarray(forcing.aoi_deg, float)))
    facing = (np.asarray(forcing.zenith_deg, float) < 90.0) & (cos_aoi > 0.0)
    beam = np.maximum(np.where(facing, held * cos_aoi, 0.0), forcing.beam_wm2)
    return direct_sun_wm2(beam_wm2=beam, cos_aoi=cos_aoi, phi=phi_rad,
                          profile=np.radians(forcing.profile_deg), glass=optics.glass_solar,
                          louver=optics.louver_solar)


class HorizonComfort:
    """The comfort limits of one decision's horizon (module docstring).

    The visual quantities depend on the louver position and the forcing alone, so they are
    evaluated once per decision for every position (``angles_deg``, H steps); the thermal
    ones come from each candidate's rollout.
    """

    def __init__(self, cfg: PanelConfig, optics: FacadeOptics, forcing: Forcing,
                 angles_deg: np.ndarray, occupied: np.ndarray) -> None:
        lim = cfg.comfort
        self.occupied = np.asarray(occupied, bool)
        h = forcing.time_s.shape[0]
        if self.occupied.shape != (h,):
            raise ValueError(f"occupied mask of shape {self.occupied.shape}, the horizon has "
                             f"{h} steps")
        phi = np.radians(np.asarray(angles_deg, float))[:, None]
        _, vis = optics.layers(forcing, phi)
        f_eye, self.f_body = view_factors(cfg)
        e_v = eye_illuminance_lx(transmitted_wm2=vis.transmitted,
                                 transmitted_beam_wm2=vis.transmitted_beam,
                                 view_factor=f_eye,
                                 luminous_efficacy_lmw=cfg.daylight.luminous_efficacy_lmw)
        shape = (len(angles_deg), h)
        self.direct_sun_wm2 = np.broadcast_to(direct_sun_bound_wm2(optics, forcing, phi), shape)
        self.dgp = np.broadcast_to(dgp_simplified(e_v), shape)
        self.t_room_c = np.asarray(forcing.t_mrt_k, float) - T_ZERO
        self.sun_max_wm2 = lim.direct_sun_max_wm2
        self.dgp_max = lim.dgp_max
        self.supply_min_c = supply_air_min_c(lim)
        self.warm_max_k = asymmetry_limit_k(lim.category, warm=True)
        self.cool_max_k = asymmetry_limit_k(lim.category, warm=False)
        self._weights = self.occupied / max(h, 1)

    @property
    def any_occupied(self) -> bool:
        return bool(self.occupied.any())

    def coarsened(self, factor: int, forcing: Forcing) -> HorizonComfort:
        """The same limits on a screening pass's coarse steps (``forcing`` its block means):
        a coarse step is occupied if any of its steps is, and sees the worst direct sun and
        glare of its steps (the screening must not admit what the full resolution rejects)."""
        out = copy.copy(self)
        starts = np.arange(0, self.occupied.size, factor)
        out.occupied = block_any(self.occupied, factor)
        out.direct_sun_wm2 = np.maximum.reduceat(self.direct_sun_wm2, starts, axis=1)
        out.dgp = np.maximum.reduceat(self.dgp, starts, axis=1)
        out.t_room_c = np.asarray(forcing.t_mrt_k, float) - T_ZERO
        out._weights = out.occupied / max(out.occupied.size, 1)
        return out

    def excess(self, angle_idx: np.ndarray, traj: Trajectory) -> np.ndarray:
        """Relative excess of each limit per candidate, averaged over the horizon's steps
        (unoccupied steps count zero) → (C, 4) in :data:`LIMIT_NAMES` order, >= 0."""
        angle_idx = np.asarray(angle_idx, int)
        sun = np.maximum(self.direct_sun_wm2[angle_idx] - self.sun_max_wm2, 0.0) / max(
            self.sun_max_wm2, _DIRECT_SUN_SCALE_MIN_WM2)
        glare = np.maximum(self.dgp[angle_idx] - self.dgp_max, 0.0) / self.dgp_max
        # Cavity air enters the room where an interior opening (IB, IT) flows out of the cavity.
        inflow = np.maximum(-traj.m_dot[:, :, 2:4], 0.0).sum(axis=2) > INFLOW_MIN_KGS
        t_supply_c = traj.x_mean[:, :, 4] - T_ZERO
        draught = np.where(inflow, np.maximum(self.supply_min_c - t_supply_c, 0.0), 0.0) / max(
            _T_NO_DRAUGHT_C - self.supply_min_c, _DRAUGHT_SCALE_MIN_K)
        asym = radiant_asymmetry_k(view_factor=self.f_body,
                                   t_pane_c=traj.x_mean[:, :, 2] - T_ZERO,
                                   t_room_c=self.t_room_c)
        limit = np.where(asym > 0.0, self.warm_max_k, self.cool_max_k)
        radiant = np.maximum(np.abs(asym) - limit, 0.0) / limit
        per_step = np.stack([sun, glare, draught, radiant], axis=-1)  # (C, H, 4)
        return np.einsum("chl,h->cl", per_step, self._weights)


def limits_line(comfort: HorizonComfort) -> str:
    """The trace line of the limits in force: which steps are occupied, and the limits."""
    occ = np.flatnonzero(comfort.occupied)
    return (f"comfort: {occ.size} of {comfort.occupied.size} steps occupied (steps "
            f"{occ[0] + 1}-{occ[-1] + 1}); limits: direct sun <= {comfort.sun_max_wm2:g} W/m2, "
            f"DGPs <= {comfort.dgp_max:g}, supply air >= {comfort.supply_min_c:.1f} °C, "
            f"asymmetry within +{comfort.warm_max_k:g}/-{comfort.cool_max_k:g} K")


def _broken(excess: tuple[float, ...]) -> list[str]:
    return [f"{name} {e:.3g}" for name, e in zip(LIMIT_NAMES, excess, strict=True) if e > 0.0]


def comfort_note(best: Best, cheapest: Best, angles_deg: np.ndarray) -> str:
    """What comfort did to the choice: the limits that bound it (those the cheapest
    candidate, energy alone, breaks and the chosen one does not), the moves they forced and
    what they cost; or, when no candidate met them all, the least violation taken."""
    moves = []
    if best.angle_idx != cheapest.angle_idx:
        moves.append(f"louver {angles_deg[cheapest.angle_idx]:+.0f} -> "
                     f"{angles_deg[best.angle_idx]:+.0f} deg")
    if best.regime != cheapest.regime:
        moves.append(f"regime {cheapest.label} -> {best.label}")
    if best.regime == cheapest.regime and not np.isclose(best.or_, cheapest.or_):
        moves.append(f"OR {cheapest.or_ * 100:.0f} -> {best.or_ * 100:.0f} %")
    price = (f"; comfort costs {(best.cost - cheapest.cost) / 3600.0:+.2f} Wh"
             if moves else "")
    if best.violation > 0.0:
        head = (f"{LEAST_VIOLATION}: least violation {best.violation:.3g} "
                f"({', '.join(_broken(best.excess))})")
        return head + (f", by {', '.join(moves)}{price}" if moves else "")
    if not moves:
        return "every limit met; none bound the choice (energy alone chooses the same)"
    bound = [name for name, e in zip(LIMIT_NAMES, cheapest.excess, strict=True) if e > 0.0]
    return f"{', '.join(bound)} bound the choice: {', '.join(moves)}{price}"
