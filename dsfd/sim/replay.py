"""Real-weather replay: pick a weather file, move it to the panel's site, cut it into steps.

The bundled files were measured in Colorado; a panel elsewhere replays them at the same
local solar time at its own longitude (:func:`dsfd.weather.shift_to_site`), so measured
irradiance and the sun position computed for the site agree, and with the air pressure of
its own elevation (:func:`move_pressure`), so the simulated plant breathes the air that a
station at the site would measure and that the daemon models (docs/model.md#inputs). Every
shift is recorded in the series' notes, which callers print.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from dsfd.config.panel import Facade, PanelConfig, Room
from dsfd.physics.boundary import WeatherInputs, model_weather, standard_pressure_pa
from dsfd.weather import (
    BUNDLED_WEATHER,
    CHANNELS,
    WeatherSeries,
    bundled_weather,
    read_weather,
    resample,
)
from dsfd.weather import shift_to_site as _shift

#: Shift weather when station and site longitudes differ by more than this [deg].
SHIFT_THRESHOLD_DEG = 0.5


def load_weather(spec: str | Path) -> WeatherSeries:
    """Read a weather file, or a bundled one by name (see ``dsfd.weather.BUNDLED_WEATHER``)."""
    if str(spec) in BUNDLED_WEATHER:
        return read_weather(bundled_weather(str(spec)))
    path = Path(spec)
    if not path.is_file():
        names = ", ".join(sorted(BUNDLED_WEATHER))
        raise FileNotFoundError(f"weather file {str(spec)!r} not found (bundled names: {names})")
    return read_weather(path)


#: Move the pressure when its elevation and the site's differ by more than this [m].
ELEVATION_THRESHOLD_M = 1.0


def at_site(series: WeatherSeries, cfg: PanelConfig) -> WeatherSeries:
    """The series replayed at the panel's longitude and elevation if it was measured elsewhere.

    Idempotent: a series already at the site is returned as it is.
    """
    if abs(series.station_longitude_deg - cfg.site.longitude_deg) > SHIFT_THRESHOLD_DEG:
        series = _shift(series, longitude_deg=cfg.site.longitude_deg)
    return move_pressure(series, elevation_m=cfg.site.elevation_m)


def move_pressure(series: WeatherSeries, *, elevation_m: float) -> WeatherSeries:
    """The series with its pressure moved to ``elevation_m`` [m] above sea level.

    Notes
    -----
    The record's pressure is scaled by the ratio of the standard atmosphere's pressures at
    the two elevations (ISO 2533 troposphere,
    :func:`~dsfd.physics.boundary.standard_pressure_pa`),
    so its weather-driven variation is kept in proportion: the Golden CO record's 817 hPa
    (mean of 1–4 January 2022, 1829 m) becomes 1015 hPa at Suwon's 40 m. Only the pressure
    moves; the temperatures, the irradiance and the wind stay as measured (the record's
    climate, not the site's).
    """
    current = (series.station_elevation_m if series.pressure_elevation_m is None
               else series.pressure_elevation_m)
    if abs(current - elevation_m) <= ELEVATION_THRESHOLD_M:
        return series
    ratio = standard_pressure_pa(elevation_m) / standard_pressure_pa(current)
    note = (f"pressure moved from {current:g} m to {elevation_m:g} m above sea level "
            f"(x{ratio:.4f}, standard atmosphere)")
    kept = tuple(n for n in series.notes if not n.startswith("pressure moved from "))
    return dataclasses.replace(series, pressure_pa=series.pressure_pa * ratio,
                               pressure_elevation_m=float(elevation_m), notes=(*kept, note))


def step_window(series: WeatherSeries, step_s: float, *, start_s: float | None = None,
                hours: float | None = None) -> tuple[float, int]:
    """Start (aligned to whole minutes) and step count covering the data or ``hours`` of it."""
    first, last = series.coverage_s
    start = math.ceil((first if start_s is None else start_s) / 60.0) * 60.0
    avail = int((last - start) // step_s)
    n = avail if hours is None else min(avail, round(hours * 3600.0 / step_s))
    if n < 1:
        raise ValueError(f"weather {series.source!r} has no complete {step_s:g} s step "
                         f"after the requested start")
    return start, n


def weather_inputs(series: WeatherSeries, cfg: PanelConfig, *, start_s: float, n_steps: int,
                   t_in_c: float | np.ndarray | None = None) -> WeatherInputs:
    """Model-step weather (midpoints, kelvin) for the panel, room from config unless given."""
    rs = resample(series, start_s=start_s, step_s=cfg.model.step_s, n_steps=n_steps)
    return series_inputs(rs.time_s, {name: getattr(rs, name) for name in CHANNELS},
                         room=cfg.room, facade=cfg.facade, t_in_c=t_in_c)


def series_inputs(time_s: np.ndarray, channels: Mapping[str, np.ndarray], *, room: Room,
                  facade: Facade, t_in_c: float | np.ndarray | None = None) -> WeatherInputs:
    """:func:`~dsfd.physics.boundary.model_weather` of a weather series' channels.

    ``channels`` maps the names of :data:`dsfd.weather.series.CHANNELS` to values at
    ``time_s`` (a resampled series, or :func:`dsfd.weather.series.interpolate`). The readers
    clip negative irradiance and keep wind speeds as recorded, so nothing more is clipped.
    """
    return model_weather(
        time_s=time_s, t_out_c=channels["t_out_c"], ghi_wm2=channels["ghi_wm2"],
        dni_wm2=channels["dni_wm2"], dhi_wm2=channels["dhi_wm2"],
        wind_speed_ms=channels["wind_speed_ms"], wind_dir_deg=channels["wind_dir_deg"],
        pressure_pa=channels["pressure_pa"], rh_pct=channels["rh_pct"], t_in_c=t_in_c,
        room=room, facade_azimuth_deg=facade.azimuth_deg, clip_negative=False)
