"""One consistent simulation: what the plant uses is what a perfect sensor tells the daemon.

The simulated plant replays a weather record moved to the panel's site (longitude and, since
issue 35, elevation: the record's pressure at the site's standard atmosphere). With ideal
sensors, every boundary quantity the daemon derives from the readings (through the same
``measured_weather`` a real cycle uses) must equal the one the plant's own ODE integrates,
read from the plant's forcing tables. A channel that differs makes the calibration fit the
difference (the dry run's sea-level air put 85 W/m² on x2's offset and took h_ca3 from 2.7 to
9.0; session note of 2026-11-27).

Not compared, by design, because no station sensor measures them: the beam/diffuse split and
the façade irradiance (a station has a pyranometer, whose GHI the daemon splits with Erbs and
transposes with Hay–Davies, while the plant heats the façade with the record's measured DNI
and DHI through Perez; the GHI itself is compared), and the sky's radiant temperature (the
plant's sky is Clark–Allen's from the humidity, the model's default Swinbank's; with
``model.sky_model: clark_allen`` the daemon's equals the plant's, which checks the humidity).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.daemon.weather import measured_weather
from dsfd.drivers.base import Reading, Sample
from dsfd.physics.boundary import standard_pressure_pa
from dsfd.physics.solar import solar_position
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.plant import OPTIONAL_STATION_SIGNALS, Plant
from dsfd.sim.replay import at_site, move_pressure
from tests.sim.conftest import HOUR, day_start

#: Index of each boundary scalar in the plant's step tables (sim/plant/forcing.py ``_Knots``)
#: and the daemon's :class:`~dsfd.physics.forcing.Forcing` field that models it.
PLANT_SCALARS = {"t_out_k": 0, "t_in_k": 1, "t_mrt_k": 2, "p_atm_pa": 4, "wind_ms": 5,
                 "cp_bottom": 6, "cp_top": 7}
T_RAD = 3
#: Agreement asked of each (the plant's linear hold inside a minute against a midpoint value).
TOLERANCE = {"t_out_k": 0.05, "t_in_k": 1e-9, "t_mrt_k": 1e-9, "t_rad_out_k": 0.1,
             "p_atm_pa": 5.0, "wind_ms": 0.05, "cp_bottom": 0.02, "cp_top": 0.02}


def _plant_scalar(plant: Plant, index: int) -> float:
    """The plant's value of boundary scalar ``index`` over the interval that ends now: its step
    k − 1, whose midpoint value is the mean of the step's knots (a linear hold in a step)."""
    k = round((plant.time_s - plant.tables.start_s) / plant.tables.dt) - 1
    table, row = plant.tables.step(k)
    return float(0.5 * (table.a[row, index] + table.b[row, index]))


def _sample(time_s: float, readings: dict[str, float]) -> Sample:
    return Sample(time_s, {k: Reading.good(v, "sim") for k, v in readings.items()})


@pytest.fixture(scope="module")
def plant_at_noon(suwon, rmis_raw):
    """The full truth plant with ideal sensors, run to 12:30 local solar time of the clear day."""
    plant = Plant(suwon, PlantOptions(sensors="ideal"), seed=1, weather_series=rmis_raw)
    start = day_start(plant.series, 1) + 12.0 * HOUR
    solar_noon_offset = suwon.site.longitude_deg / 15.0 * HOUR  # UTC of local solar time 0
    start = start - (start + solar_noon_offset) % 86400.0 + 12.5 * HOUR
    plant.reset(start)
    plant.advance(180.0)
    return plant


@pytest.mark.parametrize("field", sorted(PLANT_SCALARS))
def test_every_boundary_quantity_the_plant_uses_is_what_the_daemon_models(
        suwon, plant_at_noon, field):
    plant = plant_at_noon
    readings = plant.read_sensors()
    daemon = measured_weather(suwon, _sample(plant.time_s, readings)).forcing
    assert getattr(daemon, field)[0] == pytest.approx(
        _plant_scalar(plant, PLANT_SCALARS[field]), abs=TOLERANCE[field])


def test_the_humidity_gives_the_daemon_the_plant_sky(suwon, plant_at_noon):
    """With the Clark–Allen sky (the plant's), the measured humidity gives the plant's sky."""
    clark = dataclasses.replace(suwon, model=dataclasses.replace(suwon.model,
                                                                 sky_model="clark_allen"))
    readings = plant_at_noon.read_sensors()
    daemon = measured_weather(clark, _sample(plant_at_noon.time_s, readings)).forcing
    assert daemon.t_rad_out_k[0] == pytest.approx(_plant_scalar(plant_at_noon, T_RAD),
                                                  abs=TOLERANCE["t_rad_out_k"])
    no_rh = {k: v for k, v in readings.items() if k != "rh_pct"}
    without = measured_weather(clark, _sample(plant_at_noon.time_s, no_rh)).forcing
    # without the reading (the default dew-point depression) it would not agree
    assert abs(without.t_rad_out_k[0] - daemon.t_rad_out_k[0]) > 2 * TOLERANCE["t_rad_out_k"]


def test_the_station_ghi_is_the_plant_sky(suwon, plant_at_noon):
    """The pyranometer reads the horizontal closure of the beam and diffuse heating the plant."""
    plant = plant_at_noon
    t_mid = plant.time_s - 30.0
    w = {n: np.interp(t_mid, plant.series.time_s, getattr(plant.series, n))
         for n in ("dni_wm2", "dhi_wm2")}
    zenith = solar_position(np.array([t_mid]), suwon.site.latitude_deg,
                            suwon.site.longitude_deg).zenith_deg[0]
    closure = w["dni_wm2"] * np.cos(np.radians(zenith)) + w["dhi_wm2"]
    assert closure > 300.0  # a sunny minute, so the comparison means something
    assert plant.read_sensors()["ghi_wm2"] == pytest.approx(closure, rel=0.01)


def test_the_record_breathes_the_air_of_the_site(suwon, rmis_raw):
    """Golden's 1.8 km air is moved to Suwon's 40 m: about 1015 hPa, not 817."""
    site = at_site(rmis_raw, suwon)
    ratio = site.pressure_pa / rmis_raw.pressure_pa
    expected = standard_pressure_pa(suwon.site.elevation_m) / standard_pressure_pa(
        rmis_raw.station_elevation_m)
    assert np.allclose(ratio, expected)
    assert 1.2 < expected < 1.3
    # the site's weather stays within the synoptic range of a sea-level barometer …
    assert 980e2 < np.nanmin(site.pressure_pa) and np.nanmax(site.pressure_pa) < 1050e2
    # … and moving it again changes nothing (Plant and the benches call at_site again)
    again = at_site(site, suwon)
    assert np.array_equal(again.pressure_pa, site.pressure_pa)
    assert sum(n.startswith("pressure moved") for n in again.notes) == 1
    back = move_pressure(site, elevation_m=rmis_raw.station_elevation_m)
    assert np.allclose(back.pressure_pa, rmis_raw.pressure_pa)


def test_a_panel_without_a_barometer_models_nearly_the_plant_air(suwon, rmis_raw):
    """No pressure signal: the simulated station reports none, and the daemon's standard
    atmosphere at the site is within the record's weather variation of the plant's air."""
    devices = dataclasses.replace(suwon.devices, entries=tuple(
        d for d in suwon.devices.entries if d.kind != "serial_station"))
    bare = dataclasses.replace(suwon, devices=devices)
    plant = Plant(bare, PlantOptions.lumped_equivalent(None, sensors="ideal",
                                                       actuators="ideal"),
                  seed=1, weather_series=rmis_raw)
    plant.reset(day_start(plant.series, 1) + 4.0 * HOUR)
    plant.advance(120.0)
    readings = plant.read_sensors()
    assert not set(OPTIONAL_STATION_SIGNALS) & set(readings)
    daemon_pa = measured_weather(bare, _sample(plant.time_s, readings)).forcing.p_atm_pa[0]
    assert daemon_pa == pytest.approx(standard_pressure_pa(bare.site.elevation_m))
    assert daemon_pa == pytest.approx(float(np.mean(plant.series.pressure_pa)), rel=0.02)


def test_the_configured_station_reports_pressure_and_humidity(suwon, plant_at_noon):
    readings = plant_at_noon.read_sensors()
    assert readings["pressure_hpa"] == pytest.approx(
        float(np.interp(plant_at_noon.time_s - 30.0, plant_at_noon.series.time_s,
                        plant_at_noon.series.pressure_pa)) / 100.0, abs=0.01)
    assert 0.0 <= readings["rh_pct"] <= 100.0
