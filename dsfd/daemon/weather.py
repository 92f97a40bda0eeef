"""Measured weather of one cycle → model forcing, and the forecast over the horizon.

What the panel measures is less than what the model was written for: the station gives
outdoor air, **global horizontal** irradiance (Erbs splits it into beam and diffuse inside
:func:`~dsfd.physics.forcing.facade_forcing`), wind speed and direction, humidity and
pressure. Per cycle at time t_k:

* the weather of the interval that ends at t_k is evaluated at its midpoint t_k − T/2
  (docs/model.md#time-convention) — it drives the observer's prediction of the step that just ended,
  and the baseline's sun rules;
* the horizon forecast is :func:`~dsfd.control.forecast.persistence_forecast` of that
  interval from t_k (air, wind and room held, clearness index held along the sun's path);
* outdoor air and GHI are required (without them neither the optimiser nor the baseline can
  decide); a missing wind reading is taken as calm, a missing direction as wind normal to the
  façade, a missing pressure as the standard atmosphere of the site's elevation, a missing
  humidity as the sky model's default dew point — each wind assumption is returned as a note
  for the decision trace;
* the room air temperature comes from the ``t_room_c`` sensor or ``room.t_in_c`` per
  ``daemon.room_temperature_source``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import PanelConfig, Room
from dsfd.control.forecast import persistence_forecast
from dsfd.drivers.base import Sample
from dsfd.physics.boundary import WeatherInputs, model_weather
from dsfd.physics.forcing import Forcing, facade_forcing

__all__ = ["REQUIRED_WEATHER", "CycleWeather", "forecast_forcing", "measured_weather",
           "room_temperature"]

#: Signals without which no decision is possible.
REQUIRED_WEATHER: tuple[str, ...] = ("t_out_c", "ghi_wm2")


@dataclass(frozen=True)
class CycleWeather:
    """The measured weather of the interval ending at the sample time.

    Attributes
    ----------
    inputs : WeatherInputs or None
        One interval (arrays of length 1, SI, kelvin); None when a required signal is bad.
    forcing : Forcing or None
        Its façade boundary (sun position, beam/diffuse on the façade, sky, wind).
    missing : tuple of str
        Required signals that are not GOOD.
    notes : tuple of str
        Assumptions made for optional signals.
    t_room_c : float, [degC]
        Room air temperature used.
    room_source : str
        ``sensor`` or ``config``.
    """

    inputs: WeatherInputs | None
    forcing: Forcing | None
    missing: tuple[str, ...]
    notes: tuple[str, ...]
    t_room_c: float
    room_source: str


def room_temperature(sample: Sample, *, source: str, room: Room) -> tuple[float, str]:
    """Room air temperature [degC] and where it came from (``sensor`` or ``config``), by
    ``daemon.room_temperature_source`` (``source``) and the panel's ``room`` section."""
    measured = sample.good("t_room_c")
    if source != "config" and measured is not None:
        return measured, "sensor"
    return room.t_in_c, "config"


def measured_weather(cfg: PanelConfig, sample: Sample) -> CycleWeather:
    """Weather of the interval ending at ``sample.time_s`` (see module docstring)."""
    t_room_c, room_source = room_temperature(
        sample, source=cfg.daemon.room_temperature_source, room=cfg.room)
    missing = tuple(n for n in REQUIRED_WEATHER if sample.good(n) is None)
    if missing:
        return CycleWeather(None, None, missing, (), t_room_c, room_source)
    notes: list[str] = []
    if room_source == "config" and cfg.daemon.room_temperature_source == "sensor":
        notes.append(f"room sensor t_room_c not GOOD: room at {t_room_c:g} degC (config)")
    wind = sample.good("wind_speed_ms")
    if wind is None:
        notes.append("wind speed unknown: calm assumed in the model")
    wind_dir = sample.good("wind_dir_deg")
    if wind_dir is None:
        notes.append("wind direction unknown: normal to the facade assumed")
    pressure_hpa = sample.good("pressure_hpa")
    w = model_weather(
        time_s=np.array([sample.time_s - 0.5 * cfg.model.step_s]),
        t_out_c=sample.good("t_out_c"), ghi_wm2=sample.good("ghi_wm2"),
        wind_speed_ms=wind, wind_dir_deg=wind_dir,
        pressure_pa=None if pressure_hpa is None else pressure_hpa * 100.0,
        rh_pct=sample.good("rh_pct"), t_in_c=t_room_c, room=cfg.room,
        facade_azimuth_deg=cfg.facade.azimuth_deg,
        elevation_m=cfg.site.elevation_m)
    return CycleWeather(w, facade_forcing(cfg, w), (), tuple(notes), t_room_c, room_source)


def forecast_forcing(cfg: PanelConfig, last: WeatherInputs, *, start_s: float) -> Forcing:
    """Façade boundary of the next ``control.horizon_steps`` steps from ``start_s`` [s, UTC]."""
    fc = persistence_forecast(last, latitude_deg=cfg.site.latitude_deg,
                              longitude_deg=cfg.site.longitude_deg, start_s=start_s,
                              step_s=cfg.model.step_s, n_steps=cfg.control.horizon_steps)
    return facade_forcing(cfg, fc)

