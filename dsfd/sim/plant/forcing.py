"""Exogenous forcing of the truth plant, tabulated per model step for every louver angle.

The plant integrates continuously but reads its forcing from tables built once per block of
model steps (one day by default): for every step k the boundary at its start (``a``) and
end (``b``), and the absorbed short-wave of every louver position on the motor grid.
Inside a step the right-hand side interpolates linearly between ``a`` and ``b`` (and in φ
while the louver moves). The four combinations of the switches (docs/model.md#plant-switches):

============================  ==========================================================
``weather_hold``/``solar_time`` what ``a`` and ``b`` hold
============================  ==========================================================
zoh / step                    both: weather and sun at the step midpoint (lumped model)
linear / continuous           weather and sun at the start and at the end of the step
zoh / continuous              midpoint weather; sun at the start / end
linear / step                 weather at the start / end; sun at the midpoint
============================  ==========================================================

Optics (docs/model.md#plant-switches): ``lumped`` reuses the lumped model's forcing
(Erbs + Hay–Davies, M = 5, the model's ``louver_diffuse``) so the N = 1 equivalence
(docs/model.md#plant-switches) holds by construction; ``fine`` uses the measured DNI/DHI where
the file has them (else DIRINT), Perez 1990, M = 10 segments with the slat thickness correction
and the sky/ground diffuse split (docs/model.md#plant-forcing, docs/model.md#plant-heat-transfer).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from dsfd.config.panel import Facade, Louver, PanelConfig, Site
from dsfd.physics.airflow import AirflowGeometry
from dsfd.physics.boundary import WeatherInputs, sky_dew_point_k
from dsfd.physics.forcing import FacadeOptics, facade_forcing, local_wind_speed
from dsfd.physics.longwave import (
    cavity_exchange_matrix,
    exterior_radiant_temperature,
    sky_temperature_clark_allen,
    sky_temperature_swinbank,
)
from dsfd.physics.optics import NO_LOUVER, LouverOptics, glass_triples, layer_absorption
from dsfd.physics.solar import (
    beam_on_surface,
    dirint,
    extraterrestrial_irradiance,
    facade_irradiance,
    solar_position,
)
from dsfd.sim.plant.config import PlantOptions, drift_factors
from dsfd.sim.replay import series_inputs, weather_inputs
from dsfd.weather import WeatherSeries, interpolate

#: Scalar boundary fields, in the column order of :attr:`StepTable.a`.
FIELDS = ("t_out_k", "t_in_k", "t_mrt_k", "t_rad_out_k", "p_atm_pa", "wind_ms", "cp_bottom",
          "cp_top")
#: Wind within this angle of the façade normal is windward (EnergyPlus ER) [deg].
WINDWARD_LIMIT_DEG = 100.0
BLOCK_STEPS = 1440


class StepTable(NamedTuple):
    """Forcing of a block of steps (n steps, m louver angles).

    Attributes
    ----------
    a, b : (n, 8)
        :data:`FIELDS` at the start and end of each step (SI, K).
    src_a, src_b : (n, m, 6), [W/m2]
        Absorbed short-wave per m² façade in L1, L2, L3, louver (node order,
        docs/model.md#multilayer), then the solar power transmitted into the room and the
        daylighting benefit Q_DA (docs/model.md#room-heat, docs/model.md#q-da), both per m² façade
        (:data:`ROOM_COLUMNS`).
    windward : (n,) bool
    poa_wm2 : (n,), [W/m2]
        Façade-plane global irradiance at the step midpoint (for reports).
    """

    a: np.ndarray
    b: np.ndarray
    src_a: np.ndarray
    src_b: np.ndarray
    windward: np.ndarray
    poa_wm2: np.ndarray


#: Columns of the source tables after the four absorbed ones: transmitted solar, Q_DA/A_f.
ROOM_COLUMNS = ("q_trans", "q_da")


class _Knots(NamedTuple):
    scalars: np.ndarray  # (n, 8)
    sources: np.ndarray  # (n, m, 6): absorbed in the 4 layers, transmitted, Q_DA per m²
    windward: np.ndarray
    poa: np.ndarray


def weather_at(series: WeatherSeries, cfg: PanelConfig, times_s: np.ndarray,
               t_in_c: np.ndarray) -> WeatherInputs:
    """Weather interpolated linearly at instants ``times_s`` (held beyond the data ends).

    Wind direction is interpolated on the circle (speed-weighted components); what is
    missing gets the defaults of :func:`dsfd.physics.boundary.model_weather`, as in
    :func:`dsfd.sim.replay.weather_inputs`.
    """
    return series_inputs(np.asarray(times_s, float), interpolate(series, times_s),
                         room=cfg.room, facade=cfg.facade, t_in_c=np.asarray(t_in_c, float))


def station_ghi(site: Site, w: WeatherInputs) -> np.ndarray:
    """Global horizontal irradiance of the plant's own sky [W/m2], what its pyranometer sees.

    Parameters
    ----------
    site : Site
        The panel's site (where the sun is).
    w : WeatherInputs
        Weather at the plant (:func:`weather_at`).

    Returns
    -------
    ghi : ndarray, [W/m2]
        DNI max(cos Z, 0) + DHI where the record has both; the record's GHI elsewhere.

    Notes
    -----
    The plant heats the façade with the measured beam and diffuse (both optics switches),
    so a pyranometer on its site must read their closure, not the record's separate GHI
    channel. On the bundled RMIS January record the GHI channel falls short of the closure
    on the afternoons (mean over the local-solar hour: −25 W/m2 at 14 h, −28 W/m2 at 15 h,
    about −9 % and −20 %; within 1.5 % from 9 to 12 h), so a station fed that channel would
    tell the controller of a weaker sun than the one heating the plant.
    """
    sun = solar_position(w.time_s, site.latitude_deg, site.longitude_deg)
    # a horizontal plane's angle of incidence is the zenith angle
    closure = beam_on_surface(w.dni_wm2, sun.zenith_deg) + np.asarray(w.dhi_wm2, float)
    ghi = np.where(np.isfinite(closure), closure, np.asarray(w.ghi_wm2, float))
    return np.clip(np.nan_to_num(ghi), 0.0, None)


def fine_louver(lv: Louver | None, options: PlantOptions, d_rho: float = 0.0,
                band: str = "solar") -> LouverOptics | None:
    """The louver with M = ``options.optics_segments`` and the slat thickness correction."""
    if lv is None:
        return None
    base = LouverOptics.from_config(lv, band=band, segments=options.optics_segments,
                                    edge_correction=True)
    return dataclasses.replace(
        base, reflectance_upper=float(np.clip(base.reflectance_upper + d_rho, 0.0, 0.95)),
        reflectance_lower=float(np.clip(base.reflectance_lower + d_rho, 0.0, 0.95)))


def lw_exchange_table(cfg: PanelConfig, options: PlantOptions,
                      phis_deg: np.ndarray) -> np.ndarray:
    """Cavity long-wave factors (R_14, R_12, R_42) per louver angle, shape (m, 3) [-].

    ``radiation='three_layer'``: the lumped model's IR properties (M from the config, no
    thickness); ``'three_layer_fine'``: M = ``optics_segments`` with the thickness
    correction (docs/model.md#plant-heat-transfer). docs/model.md#longwave.
    """
    phi = np.radians(np.asarray(phis_deg, float))
    if options.radiation == "three_layer" or cfg.louver is None:
        return FacadeOptics(cfg).lw_exchange(phi)
    ir = fine_louver(cfg.louver, options).infrared(phi)
    gl = cfg.glazing
    r = cavity_exchange_matrix(gl.exterior.emissivity_back, ir.eps_L, ir.tau_L,
                               gl.interior_outer.emissivity_front)
    return np.stack([r[..., 0, 1], r[..., 0, 2], r[..., 1, 2]], axis=-1)


def _sky(cfg: PanelConfig, options: PlantOptions, w: WeatherInputs) -> np.ndarray:
    if "clark_allen" in (options.sky_model, cfg.model.sky_model):
        t_sky = sky_temperature_clark_allen(w.t_out_k, sky_dew_point_k(w), 0.0)
    else:
        t_sky = sky_temperature_swinbank(w.t_out_k)
    return exterior_radiant_temperature(w.t_out_k, t_sky)


def _windward(facade: Facade, w: WeatherInputs) -> np.ndarray:
    rel = np.asarray(w.wind_dir_deg, float) - facade.azimuth_deg
    return np.abs((rel + 180.0) % 360.0 - 180.0) <= WINDWARD_LIMIT_DEG


def _knots_lumped(cfg: PanelConfig, options: PlantOptions, w: WeatherInputs,
                  phis_rad: np.ndarray) -> _Knots:
    f = facade_forcing(cfg, w)
    optics = FacadeOptics(cfg)
    loads = optics.loads(f, phis_rad)  # sources (m, n, 4)
    t_rad = f.t_rad_out_k if options.sky_model == "lumped" else _sky(cfg, options, w)
    scalars = np.stack([f.t_out_k, f.t_in_k, f.t_mrt_k, t_rad, f.p_atm_pa, f.wind_ms,
                        f.cp_bottom, f.cp_top], axis=-1)
    sources = np.concatenate([loads.sources, loads.q_trans_wm2[..., None],
                              loads.q_da_w[..., None] / optics.area], axis=-1)
    return _Knots(scalars, np.moveaxis(sources, 0, 1), _windward(cfg.facade, w),
                  f.beam_wm2 + f.diffuse_wm2)


class FineIrradiance(NamedTuple):
    """Irradiance on the façade plane of the plant's fine optics [W/m2] and the sun's angles."""

    beam: np.ndarray
    sky: np.ndarray
    ground: np.ndarray
    cos_aoi: np.ndarray
    profile_rad: np.ndarray


def fine_irradiance(cfg: PanelConfig, w: WeatherInputs) -> FineIrradiance:
    """The façade irradiance of ``optics: fine`` (docs/model.md#plant-forcing): the measured
    DNI/DHI where the record has both (else DIRINT), transposed with Perez 1990."""
    site, fac = cfg.site, cfg.facade
    sun = solar_position(w.time_s, site.latitude_deg, site.longitude_deg)
    dni_extra = extraterrestrial_irradiance(w.time_s)
    ghi = np.clip(np.nan_to_num(np.asarray(w.ghi_wm2, float), nan=0.0), 0.0, None)
    cos_z = np.cos(np.radians(sun.zenith_deg))
    measured = np.isfinite(w.dni_wm2) & np.isfinite(w.dhi_wm2)
    if np.all(measured):
        dni, dhi = np.asarray(w.dni_wm2, float), np.asarray(w.dhi_wm2, float)
    else:
        dni_m = np.nan_to_num(dirint(ghi, sun.zenith_deg, w.time_s, pressure_pa=w.pressure_pa))
        dhi_m = np.clip(ghi - dni_m * np.maximum(cos_z, 0.0), 0.0, None)
        dni = np.where(measured, w.dni_wm2, dni_m)
        dhi = np.where(measured, w.dhi_wm2, dhi_m)
    dni = np.where(sun.zenith_deg >= 90.0, 0.0, np.clip(dni, 0.0, None))
    dhi = np.clip(dhi, 0.0, None)
    fi = facade_irradiance(dni=dni, dhi=dhi, ghi=ghi, zenith_deg=sun.zenith_deg,
                           azimuth_deg=sun.azimuth_deg, surface_azimuth_deg=fac.azimuth_deg,
                           albedo=site.albedo, dni_extra=dni_extra, model="perez")
    return FineIrradiance(fi.beam, np.nan_to_num(fi.sky_diffuse), fi.ground_diffuse,
                          np.cos(np.radians(fi.aoi_deg)), np.radians(fi.profile_deg))


def _knots_fine(cfg: PanelConfig, options: PlantOptions, w: WeatherInputs,
                phis_rad: np.ndarray, louver: LouverOptics | None) -> _Knots:
    site, fac = cfg.site, cfg.facade
    fi = fine_irradiance(cfg, w)
    sky, ground = fi.sky, fi.ground
    sol = layer_absorption(beam=fi.beam, diffuse=sky + ground, cos_aoi=fi.cos_aoi,
                           phi=phis_rad[:, None], profile=fi.profile_rad,
                           glass=glass_triples(cfg.glazing, band="solar"),
                           louver=NO_LOUVER if louver is None else louver,
                           diffuse_ground=ground)
    m, n = phis_rad.size, fi.beam.size
    # Q_DA is a lighting proxy (docs/model.md#q-da [ENG]): the lumped visible optics serve it,
    # with the sky and ground diffuse split like the solar band here, whatever the model does.
    optics = FacadeOptics(dataclasses.replace(
        cfg, model=dataclasses.replace(cfg.model, louver_diffuse="sky_ground")))
    q_da = optics.loads(facade_forcing(cfg, w), phis_rad).q_da_w / optics.area
    sources = np.stack([np.broadcast_to(s, (m, n)) for s in (sol.s1, sol.s2, sol.s3, sol.s4,
                                                             sol.transmitted, q_da)], axis=-1)
    geom = AirflowGeometry.from_sections(cfg.openings, cfg.facade)
    cp_b, cp_t = geom.wind_pressure_coefficients(w.wind_dir_deg, fac.azimuth_deg)
    wind = local_wind_speed(w.wind_speed_ms, terrain=site.terrain,
                            height_m=site.facade_height_m)
    scalars = np.stack([w.t_out_k, w.t_in_k, w.t_mrt_k, _sky(cfg, options, w), w.pressure_pa,
                        wind, cp_b, cp_t], axis=-1)
    return _Knots(scalars, np.moveaxis(sources, 0, 1), _windward(cfg.facade, w),
                  fi.beam + sky + ground)


class ForcingTables:
    """Per-step forcing of one plant run, computed lazily in blocks of model steps.

    Parameters
    ----------
    cfg : PanelConfig
    options : PlantOptions
    series : WeatherSeries
        Weather already replayed at the panel's site.
    room_c : callable
        Room air temperature [°C] at unix times (vectorised).
    start_s : float, [s]
        Start of step 0; steps are ``cfg.model.step_s`` long.
    phis_deg : array (m,), [deg]
        Louver grid of the tables.
    """

    def __init__(self, cfg: PanelConfig, options: PlantOptions, series: WeatherSeries,
                 room_c: Callable[[np.ndarray], np.ndarray], start_s: float,
                 phis_deg: np.ndarray) -> None:
        self.cfg, self.options, self.series = cfg, options, series
        self.room_c = room_c
        self.start_s = float(start_s)
        self.dt = float(cfg.model.step_s)
        self.phis_rad = np.radians(np.asarray(phis_deg, float))
        first, last = series.coverage_s
        if self.start_s < first - 1e-6:
            raise ValueError(f"plant start {self.start_s:.0f} s is before the weather data "
                             f"of {series.source!r} (from {first:.0f} s)")
        #: Number of whole steps the weather covers from ``start_s``.
        self.n_steps = int(np.floor((last - self.start_s) / self.dt + 1e-9))
        self._blocks: dict[int, StepTable] = {}

    def step(self, k: int) -> tuple[StepTable, int]:
        """The block table containing step ``k`` and the row of ``k`` in it."""
        if not 0 <= k < self.n_steps:
            raise ValueError(f"step {k} is outside the weather data of {self.series.source!r}"
                             f" ({self.n_steps} steps of {self.dt:g} s from the start)")
        block, row = divmod(k, BLOCK_STEPS)
        if block not in self._blocks:
            if len(self._blocks) > 3:
                self._blocks.pop(min(self._blocks))
            k0 = block * BLOCK_STEPS
            self._blocks[block] = self._build(k0, min(BLOCK_STEPS, self.n_steps - k0))
        return self._blocks[block], row

    def _knots(self, w: WeatherInputs, d_rho: float) -> _Knots:
        cfg, opt = self.cfg, self.options
        if d_rho and cfg.louver is not None:
            lv = cfg.louver
            cfg = dataclasses.replace(cfg, louver=dataclasses.replace(
                lv, solar_reflectance_upper=float(np.clip(lv.solar_reflectance_upper + d_rho,
                                                          0.0, 0.95)),
                solar_reflectance_lower=float(np.clip(lv.solar_reflectance_lower + d_rho,
                                                      0.0, 0.95))))
        if opt.optics == "lumped":
            return _knots_lumped(cfg, opt, w, self.phis_rad)
        return _knots_fine(cfg, opt, w, self.phis_rad, fine_louver(cfg.louver, opt))

    def _weather(self, sun_t: np.ndarray, weather_t: np.ndarray | None,
                 mid: WeatherInputs | None) -> WeatherInputs:
        """Weather with the sun at ``sun_t``: instantaneous at ``weather_t`` or ``mid``."""
        if mid is not None:
            return mid._replace(time_s=sun_t)
        return weather_at(self.series, self.cfg, weather_t, self.room_c(weather_t))

    def _build(self, k0: int, n: int) -> StepTable:
        dt, opt = self.dt, self.options
        t_start = self.start_s + (k0 + np.arange(n)) * dt
        t_mid, t_end = t_start + 0.5 * dt, t_start + dt
        mid = None
        if opt.weather_hold == "zoh":
            mid = weather_inputs(self.series, self.cfg, start_s=float(t_start[0]), n_steps=n,
                                 t_in_c=self.room_c(t_mid))
        drift = opt.drift_reflectance_per_day != 0.0
        first = drift_factors(opt, float(t_start[0] - self.start_s))[0]
        last = drift_factors(opt, float(t_end[-1] - self.start_s))[0]
        def knots(w: WeatherInputs) -> _Knots:
            kn = self._knots(w, first)
            if drift and last != first:
                lam = np.clip((w.time_s - t_start[0]) / (t_end[-1] - t_start[0]), 0.0, 1.0)
                lam = lam[:, None, None]
                src = (1.0 - lam) * kn.sources + lam * self._knots(w, last).sources
                kn = kn._replace(sources=src)
            return kn

        if opt.weather_hold == "zoh" and opt.solar_time == "step":
            ka = kb = knots(mid)
        elif opt.weather_hold == "linear" and opt.solar_time == "continuous":
            t_all = np.append(t_start, t_end[-1])
            k_all = knots(self._weather(t_all, t_all, None))
            ka = _Knots(*(v[:-1] for v in k_all))
            kb = _Knots(*(v[1:] for v in k_all))
        else:
            sun_a = t_mid if opt.solar_time == "step" else t_start
            sun_b = t_mid if opt.solar_time == "step" else t_end
            ka = knots(self._weather(sun_a, t_start, mid))
            kb = knots(self._weather(sun_b, t_end, mid))
        return StepTable(a=ka.scalars, b=kb.scalars, src_a=ka.sources, src_b=kb.sources,
                         windward=ka.windward, poa_wm2=0.5 * (ka.poa + kb.poa))
