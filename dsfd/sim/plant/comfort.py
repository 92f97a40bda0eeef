"""What the people behind the truth plant's glass get: direct sun, glare, supply air, asymmetry.

The plant measures the comfort quantities of docs/model.md#comfort from its *own* physics, not
the lumped model's (docs/model.md#plant-comfort):

* light from the plant's optics (``optics: fine``: the measured DNI/DHI transposed with
  Perez, the louver with ``optics_segments`` slat segments, the slat thickness correction and
  the sky/ground diffuse split; ``optics: lumped``: the model's own optics), at the louver's
  actual angle and the sun of the instant;
* the supply air as the mass-weighted temperature of the air leaving the cavity through the
  interior dampers, from the plant's stratified air path (None when no air enters the room);
* the inner pane as its N segment temperatures, each seen with its own view factor.

The formulas are the pure functions of :mod:`dsfd.physics.comfort_visual`,
:mod:`dsfd.physics.comfort_thermal` and :mod:`dsfd.physics.comfort_geometry`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from dsfd.control.comfort import view_factors
from dsfd.physics.comfort_geometry import window_view_factor
from dsfd.physics.comfort_thermal import radiant_asymmetry_k
from dsfd.physics.comfort_visual import dgp_simplified, eye_illuminance_lx
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import FacadeOptics, facade_forcing
from dsfd.physics.optics import NO_LOUVER, glass_triples, layer_absorption
from dsfd.sim.plant.config import drift_factors
from dsfd.sim.plant.flow import IB, IT
from dsfd.sim.plant.forcing import fine_irradiance, fine_louver, weather_at

if TYPE_CHECKING:
    from dsfd.config.panel import PanelConfig
    from dsfd.physics.boundary import WeatherInputs
    from dsfd.sim.plant.plant import Plant

__all__ = ["PlantComfort", "PlantComfortMeter", "supply_air_k"]


class PlantComfort(NamedTuple):
    """The comfort quantities of the truth plant at one instant (docs/model.md#plant-comfort).

    Computed whether or not the room is occupied; the closed loop judges them while occupied.
    """

    time_s: float  #: UTC [s]
    phi_deg: float  #: the louver's actual angle [deg]
    profile_deg: float  #: the sun's profile angle on the façade [deg]
    direct_sun_wm2: float  #: solar beam passing the louver unscattered into the room [W/m2]
    e_v_lx: float  #: vertical illuminance at the occupant's eye [lx]
    dgp: float  #: simplified daylight glare probability DGPs [-]
    supply_air_c: float | None  #: air entering the room from the cavity; None when none does
    t_pane_c: float  #: inner pane as the asymmetry point sees it (view-weighted, radiant) [°C]
    t_room_mrt_c: float  #: the room's mean radiant temperature [°C]
    asymmetry_k: float  #: radiant asymmetry of the pane, + warm [K]


def supply_air_k(m_dot_kgs: np.ndarray, t_opening_k: np.ndarray) -> float:
    """Mass-weighted temperature [K] of the air leaving the cavity into the room, NaN if none.

    ``m_dot_kgs`` are the flows through EB, ET, IB, IT, positive into the cavity, and
    ``t_opening_k`` the air temperatures at those openings (the plant's
    ``opening_temperatures``, the same air its Q_air counts, docs/model.md#q-air).
    """
    out = np.array([max(-float(m_dot_kgs[k]), 0.0) for k in (IB, IT)])
    if out.sum() <= 0.0:
        return math.nan
    return float(out @ np.asarray(t_opening_k, float)[[IB, IT]] / out.sum())


def _strip_view_factors(cfg: PanelConfig, n: int) -> np.ndarray:
    """View factors from the asymmetry point to each of the N pane segments (bottom first)."""
    c, fac = cfg.comfort, cfg.facade
    dz = fac.glazed_height_m / n
    z0 = c.asymmetry_height_m - c.sill_height_m  # above the glazing's lower edge
    return np.array([float(window_view_factor(
        distance_m=c.occupant_distance_m, width_m=fac.width_m, height_m=dz,
        lateral_m=0.5 * fac.width_m, elevation_m=z0 - k * dz)) for k in range(n)])


class PlantComfortMeter:
    """Evaluates :class:`PlantComfort` for one plant (what stays fixed is computed once)."""

    def __init__(self, plant: Plant) -> None:
        cfg = plant.cfg
        self.cfg, self.options = cfg, plant.options
        self.fine = plant.options.optics != "lumped"
        self.f_eye, _ = view_factors(cfg)
        self.f_strips = _strip_view_factors(cfg, plant.model.lay.n)
        self.glass = (glass_triples(cfg.glazing, band="solar"),
                      glass_triples(cfg.glazing, band="visible"))
        self._louvers: dict[tuple[float, float], tuple] = {}
        self._lumped = None if self.fine else FacadeOptics(cfg)

    def _louver_pair(self, d_rho: float, phi_rad: float) -> tuple:
        """(solar, visible) louvers and their sky/ground properties at ``phi_rad``, kept:
        the louver rests on a few angles, and these are most of the cost."""
        key = (d_rho, round(phi_rad, 9))
        if key not in self._louvers:
            if len(self._louvers) > 64:  # a drifting reflectance: a new key every call
                self._louvers.clear()
            pair = [NO_LOUVER if self.cfg.louver is None else
                    fine_louver(self.cfg.louver, self.options, d_rho, band=band)
                    for band in ("solar", "visible")]
            self._louvers[key] = tuple(
                (lv, None if lv is NO_LOUVER else lv.sky_ground(np.asarray(phi_rad)))
                for lv in pair)
        return self._louvers[key]

    def _light(self, plant: Plant, t: float, phi_rad: float, w: WeatherInputs) -> tuple:
        """(solar, visible) layer sources and the profile angle [rad] at ``t``."""
        if not self.fine:
            f = facade_forcing(self.cfg, w)
            sol, vis = self._lumped.layers(f, np.asarray(phi_rad))
            return sol, vis, float(np.radians(f.profile_deg[0]))
        fi = fine_irradiance(self.cfg, w)
        d_rho = drift_factors(self.options, t - plant.start_s)[0]
        common = dict(beam=fi.beam, diffuse=fi.sky + fi.ground, cos_aoi=fi.cos_aoi,
                      phi=phi_rad, profile=fi.profile_rad, diffuse_ground=fi.ground)
        sol, vis = (layer_absorption(**common, glass=glass, louver=lv, sky_ground=sg)
                    for glass, (lv, sg) in zip(self.glass, self._louver_pair(d_rho, phi_rad),
                                               strict=True))
        return sol, vis, float(fi.profile_rad[0])

    def measure(self, plant: Plant, ev: dict) -> PlantComfort:
        """The quantities at the plant's current instant from its evaluation ``ev``."""
        cfg, model = self.cfg, plant.model
        t = plant.time_s
        w = weather_at(plant.series, cfg, np.array([t]), plant.room_c(np.array([t])))
        phi_deg = float(ev["phi_deg"])
        sol, vis, profile = self._light(plant, t, math.radians(phi_deg), w)
        e_v = eye_illuminance_lx(transmitted_wm2=vis.transmitted,
                                 transmitted_beam_wm2=vis.transmitted_beam,
                                 view_factor=self.f_eye,
                                 luminous_efficacy_lmw=cfg.daylight.luminous_efficacy_lmw)
        fl = ev["flows"]
        t_open = model.opening_temperatures(fl, ev["face_out"], ev["m_cav"])
        supply = supply_air_k(np.asarray(fl["m"], float), t_open)
        # The pane as one surface of the same radiant power: sum F_k T_k^4 = F T_w^4.
        t3 = plant._y[model.lay.sl("g3")]
        f_pane = float(self.f_strips.sum())
        t_pane = float((self.f_strips @ t3**4 / f_pane) ** 0.25) - T_ZERO
        t_mrt = float(w.t_mrt_k[0]) - T_ZERO
        return PlantComfort(
            time_s=t, phi_deg=phi_deg, profile_deg=math.degrees(profile),
            direct_sun_wm2=float(np.ravel(sol.transmitted_beam)[0]),
            e_v_lx=float(np.ravel(e_v)[0]), dgp=float(np.ravel(dgp_simplified(e_v))[0]),
            supply_air_c=None if math.isnan(supply) else supply - T_ZERO,
            t_pane_c=t_pane, t_room_mrt_c=t_mrt,
            asymmetry_k=float(radiant_asymmetry_k(view_factor=f_pane, t_pane_c=t_pane,
                                                  t_room_c=t_mrt)))
