"""Exogenous inputs of the lumped model: weather → façade boundary and optical loads.

Two stages, both pure and vectorised over time steps:

* :func:`facade_forcing` turns measured weather at the step midpoints
  (docs/model.md#time-convention) into the façade boundary: sun position, plane-of-façade beam and
  diffuse irradiance (Erbs decomposition where DNI/DHI are not measured, Hay–Davies or isotropic
  transposition, docs/model.md#solar; or measured plane-of-façade total and diffuse irradiance), the
  exterior radiant temperature (sky model, docs/model.md#sky), the local wind speed (power-law
  profile, docs/model.md#convection) and the wind pressure coefficients of the openings
  (docs/model.md#driving-pressures).
* :class:`FacadeOptics` adds what depends on the louver angle φ: absorbed short-wave per
  node (docs/model.md#multilayer), the cavity long-wave exchange factors (docs/model.md#longwave),
  the transmitted solar gain and the daylighting benefit Q_DA (docs/model.md#q-da), for any array of
  louver angles at once.

:func:`step_inputs` joins the two into the :class:`~dsfd.physics.coupling.StepInputs` the
model steps with.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.physics.airflow import AirflowGeometry, louver_flow_loss
from dsfd.physics.boundary import WeatherInputs, sky_dew_point_k
from dsfd.physics.constants import T_ZERO
from dsfd.physics.coupling import StepInputs
from dsfd.physics.longwave import (
    cavity_exchange_matrix,
    exterior_radiant_temperature,
    sky_temperature_clark_allen,
    sky_temperature_swinbank,
)
from dsfd.physics.optics import (
    NO_LOUVER,
    LayerSources,
    LouverOptics,
    SlatSkyGround,
    glass_triples,
    layer_absorption,
)
from dsfd.physics.solar import (
    disc,
    erbs,
    extraterrestrial_irradiance,
    facade_irradiance,
    solar_position,
)

#: Wind-profile exponent a and boundary-layer thickness δ [m] by terrain (EnergyPlus
#: Engineering Reference, "Local Wind Speed Calculations"); the met station is "flat".
TERRAIN_PROFILE = {"ocean": (0.10, 210.0), "flat": (0.14, 270.0), "rough": (0.22, 370.0),
                   "city": (0.33, 460.0)}
MET_HEIGHT_M = 10.0


class Forcing(NamedTuple):
    """Façade boundary per step (arrays (n,)), independent of the controls."""

    time_s: np.ndarray
    t_out_k: np.ndarray
    t_in_k: np.ndarray
    t_mrt_k: np.ndarray
    t_rad_out_k: np.ndarray
    p_atm_pa: np.ndarray
    wind_ms: np.ndarray  # local, façade height [m/s]
    cp_bottom: np.ndarray
    cp_top: np.ndarray
    zenith_deg: np.ndarray
    azimuth_deg: np.ndarray
    aoi_deg: np.ndarray
    profile_deg: np.ndarray
    beam_wm2: np.ndarray  # on the façade plane
    diffuse_wm2: np.ndarray  # sky + ground on the façade plane
    ghi_wm2: np.ndarray
    dni_wm2: np.ndarray
    dhi_wm2: np.ndarray
    ground_wm2: np.ndarray  # the ground-reflected part of diffuse_wm2

    def window(self, start: int, stop: int) -> Forcing:
        """Steps ``start`` … ``stop − 1``."""
        return Forcing(*(v[start:stop] for v in self))


def local_wind_speed(u_met: np.ndarray, *, terrain: str, height_m: float) -> np.ndarray:
    """Wind speed at façade height from the met-mast speed [m/s].

    Notes
    -----
    V_z = U_met (δ_met/z_met)^a_met (z/δ)^a with the met station in flat open country
    (a_met = 0.14, δ_met = 270 m, z_met = 10 m) and the site's terrain class (EnergyPlus
    Engineering Reference, "Local Wind Speed Calculations"; docs/model.md#convection).
    """
    a_met, d_met = TERRAIN_PROFILE["flat"]
    a, d = TERRAIN_PROFILE[terrain]
    return np.asarray(u_met, float) * (d_met / MET_HEIGHT_M) ** a_met * (height_m / d) ** a


def _decompose(method: str, ghi: np.ndarray, zenith_deg: np.ndarray, dni_extra: np.ndarray,
               w: WeatherInputs) -> tuple[np.ndarray, np.ndarray]:
    """DNI and DHI [W/m2] from GHI by ``model.decomposition`` (docs/model.md#decomposition);
    both keep GHI = DHI + DNI cos Z."""
    if method == "erbs":
        split = erbs(ghi, zenith_deg, dni_extra)
        return split.dni, split.dhi
    cos_z = np.cos(np.radians(zenith_deg))
    up = cos_z > 0.0
    dni = disc(ghi, zenith_deg, w.time_s, pressure_pa=w.pressure_pa).dni
    # (DISC knows no GHI bound: near kt = 1 its beam alone can exceed the global)
    dni = np.where(up, np.minimum(dni, ghi / np.where(up, cos_z, 1.0)), 0.0)
    return dni, ghi - dni * np.where(up, cos_z, 0.0)


def facade_forcing(cfg: PanelConfig, w: WeatherInputs, *,
                   transposition: str | None = None) -> Forcing:
    """Façade boundary conditions of every step (docs/model.md#solar, docs/model.md#sky,
    docs/model.md#convection, docs/model.md#driving-pressures).

    Parameters
    ----------
    cfg : PanelConfig
    w : WeatherInputs
    transposition : {"haydavies", "isotropic", "perez"}, optional
        Defaults to ``cfg.model.transposition``.
    """
    site, fac = cfg.site, cfg.facade
    sun = solar_position(w.time_s, site.latitude_deg, site.longitude_deg)
    dni_extra = extraterrestrial_irradiance(w.time_s)
    poa = _plane_of_array(w)
    ghi = np.clip(np.asarray(w.ghi_wm2, float), 0.0, None)
    if poa is not None:  # façade-plane data only: GHI may be absent
        ghi = np.where(np.isfinite(ghi), ghi, 0.0)
    split_dni, split_dhi = _decompose(cfg.model.decomposition, ghi, sun.zenith_deg, dni_extra, w)
    dni = np.where(np.isfinite(w.dni_wm2), w.dni_wm2, split_dni)
    dhi = np.where(np.isfinite(w.dhi_wm2), w.dhi_wm2, split_dhi)
    below = sun.zenith_deg >= 90.0  # no beam from a sun below the horizon
    dni = np.where(below, 0.0, np.clip(dni, 0.0, None))
    dhi = np.clip(dhi, 0.0, None)
    fi = facade_irradiance(dni=dni, dhi=dhi, ghi=ghi, zenith_deg=sun.zenith_deg,
                           azimuth_deg=sun.azimuth_deg, surface_azimuth_deg=fac.azimuth_deg,
                           albedo=site.albedo, dni_extra=dni_extra,
                           model=transposition or cfg.model.transposition)
    if cfg.model.sky_model == "clark_allen":
        t_sky = sky_temperature_clark_allen(w.t_out_k, sky_dew_point_k(w), 0.0)
    else:
        t_sky = sky_temperature_swinbank(w.t_out_k)
    beam, diffuse, ground = fi.beam, fi.sky_diffuse + fi.ground_diffuse, fi.ground_diffuse
    if poa is not None:
        use, total, diff = poa
        front = (fi.aoi_deg < 90.0) & ~below
        beam = np.where(use, np.where(front, np.clip(total - diff, 0.0, None), 0.0), beam)
        diffuse = np.where(use, np.where(front, diff, total), diffuse)
        # The ground's share of measured façade diffuse: from GHI and the albedo where GHI
        # is measured too, else half, which is what uniform diffuse radiance gives.
        has_ghi = np.isfinite(np.asarray(w.ghi_wm2, float))
        ground = np.where(use, np.where(has_ghi, np.minimum(ground, diffuse), 0.5 * diffuse),
                          ground)
    geom = AirflowGeometry.from_sections(cfg.openings, cfg.facade)
    cp_b, cp_t = geom.wind_pressure_coefficients(w.wind_dir_deg, fac.azimuth_deg)
    return Forcing(
        time_s=np.asarray(w.time_s, float),
        t_out_k=np.asarray(w.t_out_k, float),
        t_in_k=np.asarray(w.t_in_k, float),
        t_mrt_k=np.asarray(w.t_mrt_k, float),
        t_rad_out_k=exterior_radiant_temperature(w.t_out_k, t_sky),
        p_atm_pa=np.asarray(w.pressure_pa, float),
        wind_ms=local_wind_speed(w.wind_speed_ms, terrain=site.terrain,
                                 height_m=site.facade_height_m),
        cp_bottom=cp_b,
        cp_top=cp_t,
        zenith_deg=sun.zenith_deg,
        azimuth_deg=sun.azimuth_deg,
        aoi_deg=fi.aoi_deg,
        profile_deg=fi.profile_deg,
        beam_wm2=beam,
        diffuse_wm2=diffuse,
        ghi_wm2=ghi,
        dni_wm2=dni,
        dhi_wm2=dhi,
        ground_wm2=ground,
    )


def _plane_of_array(w: WeatherInputs) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(use, total, diffuse) of measured façade-plane irradiance [W/m2], or None if absent."""
    if w.poa_global_wm2 is None or w.poa_diffuse_wm2 is None:
        return None
    total = np.asarray(w.poa_global_wm2, float)
    diff = np.asarray(w.poa_diffuse_wm2, float)
    use = np.isfinite(total) & np.isfinite(diff)
    if not use.any():
        return None
    total = np.clip(np.where(use, total, 0.0), 0.0, None)
    diff = np.minimum(np.clip(np.where(use, diff, 0.0), 0.0, None), total)
    return use, total, diff


class OpticalLoads(NamedTuple):
    """What the louver angle changes, shape (..., n) for angles (...) and n steps.

    Attributes
    ----------
    sources : (..., n, 4), [W/m2]
        Absorbed short-wave in L1, L2, L3, louver (node order, docs/model.md#multilayer).
    lw_exchange : (..., n, 3), [-]
        Cavity long-wave exchange factors R_14, R_12, R_42 (docs/model.md#longwave).
    q_trans_wm2 : (..., n), [W/m2]
        Solar short-wave transmitted into the room.
    q_da_w : (..., n), [W]
        Daylighting benefit Q_DA (docs/model.md#q-da).
    cavity_loss : (..., n), [-]
        Flow loss K_L of the slats, referenced to the cavity velocity
        (:func:`dsfd.physics.airflow.louver_flow_loss`; 0 without a louver or with
        ``model.louver_flow_loss`` off).
    """

    sources: np.ndarray
    lw_exchange: np.ndarray
    q_trans_wm2: np.ndarray
    q_da_w: np.ndarray
    cavity_loss: np.ndarray


#: Nodes of the louver's sky / ground table: every degree from -90° to +90°.
SKY_GROUND_NODES = 181


@lru_cache(maxsize=8)
def sky_ground_table(louver: LouverOptics) -> np.ndarray:
    """``louver.sky_ground`` at every whole degree from −90° to +90° → (181, 6).

    Each angle costs 128 slat-cell beam evaluations (docs/model.md#louver-diffuse), too many
    for every decision; a process builds the table once per louver and band.
    """
    table = np.stack(louver.sky_ground(np.radians(np.arange(SKY_GROUND_NODES) - 90.0)), axis=-1)
    table.flags.writeable = False
    return table


class FacadeOptics:
    """Short- and long-wave optics of one panel, evaluated for arrays of louver angles."""

    def __init__(self, cfg: PanelConfig) -> None:
        self.cfg = cfg
        gl = cfg.glazing
        self.glass_solar = glass_triples(gl, band="solar")
        self.glass_visible = glass_triples(gl, band="visible")
        if cfg.louver is None:
            self.louver_solar = self.louver_visible = NO_LOUVER
        else:
            self.louver_solar = LouverOptics.from_config(cfg.louver, band="solar")
            self.louver_visible = LouverOptics.from_config(cfg.louver, band="visible")
        self.eps_1b = gl.exterior.emissivity_back
        self.eps_2f = gl.interior_outer.emissivity_front
        self.area = cfg.facade.width_m * cfg.facade.glazed_height_m
        self.floor = cfg.facade.width_m * cfg.room.floor_depth_m
        self.split_diffuse = (cfg.louver is not None
                              and cfg.model.louver_diffuse == "sky_ground")

    def sky_ground(self, phi_rad: np.ndarray) -> tuple[SlatSkyGround, SlatSkyGround]:
        """Sky / ground properties of the slats at ``phi_rad`` [rad] (solar, visible), shape
        of ``phi_rad``: linear in φ between the 1° nodes of :func:`sky_ground_table` (exact
        on the 18° motor grid; within 4e-4 of the direct quadrature between nodes)."""
        deg = np.clip(np.degrees(np.asarray(phi_rad, float)), -90.0, 90.0) + 90.0
        i = np.minimum(deg.astype(int), SKY_GROUND_NODES - 2)
        w = (deg - i)[..., None]
        out = []
        for louver in (self.louver_solar, self.louver_visible):
            table = sky_ground_table(louver)
            out.append(SlatSkyGround(*np.moveaxis((1.0 - w) * table[i] + w * table[i + 1],
                                                  -1, 0)))
        return out[0], out[1]

    def lw_exchange(self, phi_rad: np.ndarray) -> np.ndarray:
        """(R_14, R_12, R_42) for louver angles ``phi_rad`` [rad] → shape (..., 3)."""
        ir = self.louver_solar.infrared(np.asarray(phi_rad, float))
        r = cavity_exchange_matrix(self.eps_1b, ir.eps_L, ir.tau_L, self.eps_2f)
        return np.stack([r[..., 0, 1], r[..., 0, 2], r[..., 1, 2]], axis=-1)

    def layers(self, forcing: Forcing,
               phi_rad: np.ndarray) -> tuple[LayerSources, LayerSources]:
        """The multilayer balance (solar, visible) for louver angles ``phi_rad`` [rad],
        broadcast against the steps (docs/model.md#multilayer, docs/model.md#louver-diffuse)."""
        common = dict(beam=forcing.beam_wm2, diffuse=forcing.diffuse_wm2,
                      cos_aoi=np.cos(np.radians(forcing.aoi_deg)), phi=phi_rad,
                      profile=np.radians(forcing.profile_deg))
        split_sol = split_vis = None
        if self.split_diffuse:
            split_sol, split_vis = self.sky_ground(phi_rad)
            common["diffuse_ground"] = forcing.ground_wm2
        sol = layer_absorption(**common, glass=self.glass_solar, louver=self.louver_solar,
                               sky_ground=split_sol)
        vis = layer_absorption(**common, glass=self.glass_visible, louver=self.louver_visible,
                               sky_ground=split_vis)
        return sol, vis

    def loads(self, forcing: Forcing, phi_rad: np.ndarray | float) -> OpticalLoads:
        """Loads for louver angles ``phi_rad`` [rad] (scalar or shape (m,)) over all steps.

        Returns arrays of shape (n, ...) for a scalar angle and (m, n, ...) for m angles.
        """
        phi = np.asarray(phi_rad, float)
        phi_b = phi[..., None]  # broadcast against the step axis
        sol, vis = self.layers(forcing, phi_b)
        shape = np.broadcast_shapes(phi_b.shape, forcing.beam_wm2.shape)
        sources = np.stack([np.broadcast_to(s, shape) for s in (sol.s1, sol.s2, sol.s3,
                                                                  sol.s4)], axis=-1)
        lw = np.broadcast_to(self.lw_exchange(phi)[..., None, :], (*shape, 3))
        d = self.cfg.daylight
        e_wp = d.luminous_efficacy_lmw * d.utilisation * self.area * vis.transmitted / self.floor
        q_da = d.lighting_power_wm2 * self.floor * np.minimum(1.0, e_wp / d.illuminance_setpoint_lx)
        lv = self.cfg.louver
        if lv is None or not self.cfg.model.louver_flow_loss:
            k_l = np.zeros(shape)
        else:
            fac = self.cfg.facade
            k_l = np.broadcast_to(louver_flow_loss(
                phi_b, depth_m=fac.cavity_depth_m, slat_width_m=lv.slat_width_m,
                slat_pitch_m=lv.slat_pitch_m, height_m=fac.glazed_height_m), shape)
        return OpticalLoads(sources, lw, np.broadcast_to(sol.transmitted, shape),
                            np.broadcast_to(q_da, shape), k_l)


def step_inputs(forcing: Forcing, loads: OpticalLoads) -> StepInputs:
    """Join the boundary and the optical loads into model inputs of shape (..., n)."""
    return StepInputs(
        t_out_k=forcing.t_out_k,
        t_in_k=forcing.t_in_k,
        t_mrt_k=forcing.t_mrt_k,
        t_rad_out_k=forcing.t_rad_out_k,
        p_atm_pa=forcing.p_atm_pa,
        wind_ms=forcing.wind_ms,
        cp_bottom=forcing.cp_bottom,
        cp_top=forcing.cp_top,
        sources=loads.sources,
        lw_exchange=loads.lw_exchange,
        q_trans_wm2=loads.q_trans_wm2,
        q_da_w=loads.q_da_w,
        cavity_loss=loads.cavity_loss,
    )


def celsius(t_k: np.ndarray) -> np.ndarray:
    """Kelvin → degrees Celsius (for the boundary of the package)."""
    return np.asarray(t_k) - T_ZERO
