"""Real-weather replay: pick a weather file, move it to the panel's site, cut it into steps.

The bundled files were measured in Colorado; a panel elsewhere replays them at the same
local solar time at its own longitude (:func:`dsfd.weather.shift_to_site`), so measured
irradiance and the sun position computed for the site agree. Every shift is recorded in
the series' notes, which callers print.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import WeatherInputs
from dsfd.weather import BUNDLED_WEATHER, WeatherSeries, bundled_weather, read_weather, resample
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


def at_site(series: WeatherSeries, cfg: PanelConfig) -> WeatherSeries:
    """The series replayed at the panel's longitude if it was measured elsewhere."""
    if abs(series.station_longitude_deg - cfg.site.longitude_deg) > SHIFT_THRESHOLD_DEG:
        return _shift(series, longitude_deg=cfg.site.longitude_deg)
    return series


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
    room = cfg.room
    t_in = np.broadcast_to(room.t_in_c if t_in_c is None else t_in_c, (n_steps,)) + T_ZERO
    t_mrt = t_in if room.t_mrt_c is None else np.full(n_steps, room.t_mrt_c + T_ZERO)
    pressure = np.where(np.isfinite(rs.pressure_pa), rs.pressure_pa, 101325.0)
    return WeatherInputs(
        time_s=rs.time_s,
        t_out_k=rs.t_out_c + T_ZERO,
        ghi_wm2=rs.ghi_wm2,
        dni_wm2=rs.dni_wm2,
        dhi_wm2=rs.dhi_wm2,
        wind_speed_ms=np.nan_to_num(rs.wind_speed_ms, nan=0.0),
        wind_dir_deg=np.nan_to_num(rs.wind_dir_deg, nan=cfg.facade.azimuth_deg),
        pressure_pa=pressure,
        t_in_k=np.asarray(t_in, float),
        t_mrt_k=np.asarray(t_mrt, float),
        t_dew_k=_dew_point_k(rs.t_out_c, rs.rh_pct),
    )


def _dew_point_k(t_c: np.ndarray, rh_pct: np.ndarray) -> np.ndarray:
    """Magnus-formula dew point [K] (Alduchov & Eskridge 1996 coefficients); NaN if no RH."""
    a, b = 17.625, 243.04
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma = np.log(np.clip(rh_pct, 1e-3, 100.0) / 100.0) + a * t_c / (b + t_c)
        return b * gamma / (a - gamma) + T_ZERO
