"""Measured or forecast weather → the model's weather inputs, every default stated once.

Every source of weather — a station reading of one daemon cycle, a measured-data CSV, a
weather file replayed for the simulation or the truth plant — goes through
:func:`model_weather`, which converts it to SI units and kelvin and fills what was not
measured. The defaults, here and nowhere else:

=====================  ==================================================================
not measured           taken as
=====================  ==================================================================
wind speed             calm, 0 m/s
wind direction         normal to the façade (the façade azimuth)
station pressure       the standard atmosphere at the site's elevation
                       (:func:`standard_pressure_pa`; sea level when not given)
DNI, DHI               NaN: :func:`~dsfd.physics.forcing.facade_forcing` splits GHI (Erbs)
relative humidity      dew point NaN; the Clark–Allen sky then takes
                       t_out − :data:`DEW_POINT_DEPRESSION_K` (:func:`sky_dew_point_k`)
room air temperature   ``room.t_in_c`` of the panel
mean radiant temp.     ``room.t_mrt_c``, or the room air temperature when that is null
=====================  ==================================================================

"Not measured" is ``None`` for a whole channel and NaN (or ±inf) for single values.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from dsfd.config.panel import Room
from dsfd.physics.constants import STANDARD_PRESSURE_PA, T_ZERO

__all__ = ["DEW_POINT_DEPRESSION_K", "STANDARD_PRESSURE_PA", "WeatherInputs", "dew_point_k",
           "model_weather", "sky_dew_point_k", "standard_pressure_pa"]

#: Dew-point depression assumed by the Clark–Allen sky when no humidity is measured [K].
DEW_POINT_DEPRESSION_K = 5.0
#: Magnus-formula coefficients over water (Alduchov & Eskridge 1996): a [-], b [°C].
MAGNUS_A, MAGNUS_B_C = 17.625, 243.04


class WeatherInputs(NamedTuple):
    """Weather at the step midpoints (arrays (n,), SI units, kelvin).

    Attributes
    ----------
    time_s : [s]
        UTC unix time of each step's midpoint.
    t_out_k : [K]
    ghi_wm2, dni_wm2, dhi_wm2 : [W/m2]
        NaN in DNI/DHI means "not measured": Erbs decomposes GHI there.
    wind_speed_ms : [m/s]
        At the 10 m met mast.
    wind_dir_deg : [deg]
        Direction the wind comes from, clockwise from north.
    pressure_pa : [Pa]
    t_in_k, t_mrt_k : [K]
        Room air and mean radiant temperature.
    t_dew_k : [K]
        Dew point (NaN if unknown; only the Clark–Allen sky model uses it).
    poa_global_wm2, poa_diffuse_wm2 : [W/m2], optional
        Measured total and diffuse irradiance on the façade plane. Where both are finite
        they replace the decomposition and transposition of GHI/DNI/DHI: beam on the
        façade = total − diffuse (0 with the sun behind the façade, which then counts as
        diffuse). ``None`` (default) or NaN: computed from GHI/DNI/DHI as before.
    """

    time_s: np.ndarray
    t_out_k: np.ndarray
    ghi_wm2: np.ndarray
    dni_wm2: np.ndarray
    dhi_wm2: np.ndarray
    wind_speed_ms: np.ndarray
    wind_dir_deg: np.ndarray
    pressure_pa: np.ndarray
    t_in_k: np.ndarray
    t_mrt_k: np.ndarray
    t_dew_k: np.ndarray
    poa_global_wm2: np.ndarray | None = None
    poa_diffuse_wm2: np.ndarray | None = None


def dew_point_k(t_c: ArrayLike, rh_pct: ArrayLike) -> np.ndarray:
    """Dew point [K] from air temperature [°C] and relative humidity [%]; NaN where RH is NaN.

    Notes
    -----
    Magnus formula with the coefficients of Alduchov & Eskridge (1996), J. Appl. Meteor.
    35, 601: γ = ln(RH/100) + a t/(b + t), T_d = b γ/(a − γ). RH is clipped into
    [0.001, 100] %.
    """
    t_c = np.asarray(t_c, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma = (np.log(np.clip(rh_pct, 1e-3, 100.0) / 100.0)
                 + MAGNUS_A * t_c / (MAGNUS_B_C + t_c))
        return MAGNUS_B_C * gamma / (MAGNUS_A - gamma) + T_ZERO


def sky_dew_point_k(w: WeatherInputs) -> np.ndarray:
    """Dew point the sky model uses [K]: the measured one, else t_out − 5 K."""
    return np.where(np.isfinite(w.t_dew_k), w.t_dew_k, w.t_out_k - DEW_POINT_DEPRESSION_K)


def _channel(value: ArrayLike | None, n: int) -> np.ndarray:
    """A channel as a float array (n,): NaN if not measured, a scalar repeated."""
    if value is None:
        return np.full(n, np.nan)
    a = np.asarray(value, float)
    return a if a.shape == (n,) else np.full(n, a)


def _or_default(a: np.ndarray, default: float) -> np.ndarray:
    return np.where(np.isfinite(a), a, default)


def standard_pressure_pa(elevation_m: float) -> float:
    """Pressure of the standard atmosphere at ``elevation_m`` [m] above sea level [Pa].

    Notes
    -----
    The troposphere of the ICAO/ISO standard atmosphere: p = p0 (1 − 2.25577·10⁻⁵ z)^5.25588
    with p0 = 101 325 Pa (ISO 2533:1975; the same form in the ASHRAE Handbook —
    Fundamentals, ch. 1, eq. 3). It is what a panel without a barometer is modelled at: at
    Golden CO (1829 m) 812 hPa, where sea level would make the air 25 % too dense.
    """
    return STANDARD_PRESSURE_PA * (1.0 - 2.25577e-5 * elevation_m) ** 5.25588


def model_weather(*, time_s: ArrayLike, t_out_c: ArrayLike, ghi_wm2: ArrayLike | None,
                  room: Room, facade_azimuth_deg: float, elevation_m: float = 0.0,
                  dni_wm2: ArrayLike | None = None, dhi_wm2: ArrayLike | None = None,
                  wind_speed_ms: ArrayLike | None = None, wind_dir_deg: ArrayLike | None = None,
                  pressure_pa: ArrayLike | None = None, rh_pct: ArrayLike | None = None,
                  t_in_c: ArrayLike | None = None, poa_global_wm2: ArrayLike | None = None,
                  poa_diffuse_wm2: ArrayLike | None = None,
                  clip_negative: bool = True) -> WeatherInputs:
    """The model's weather inputs from measured or forecast weather (module docstring).

    Parameters
    ----------
    time_s : array (n,), [s]
        UTC unix time each value stands for (a step midpoint for the lumped model).
    t_out_c : array (n,) or float, [degC]
        Outdoor air temperature (required).
    ghi_wm2, dni_wm2, dhi_wm2 : array (n,) or float, [W/m2], optional
        Global horizontal, direct normal, diffuse horizontal irradiance.
    room : Room
        The panel's room section (room air when not measured, mean radiant temperature).
    facade_azimuth_deg : float, [deg]
        The façade's outward normal, the wind direction when none is measured.
    elevation_m : float, [m]
        The site's elevation: the standard atmosphere there is the pressure when none is
        measured (:func:`standard_pressure_pa`).
    wind_speed_ms, wind_dir_deg : array (n,) or float, optional
        At the met mast [m/s]; the direction the wind comes from [deg from north].
    pressure_pa : array (n,) or float, [Pa], optional
        Station pressure.
    rh_pct : array (n,) or float, [%], optional
        Relative humidity, for the dew point.
    t_in_c : array (n,) or float, [degC], optional
        Measured room air temperature.
    poa_global_wm2, poa_diffuse_wm2 : array (n,), [W/m2], optional
        Measured total and diffuse irradiance on the façade plane (passed through).
    clip_negative : bool
        Clip negative wind speed and irradiance at 0 (readings straight from the instruments:
        thermal offsets of pyranometers at night, anemometer offsets). The weather files'
        readers clip irradiance themselves and leave wind as recorded; their callers pass
        False.

    Returns
    -------
    WeatherInputs
        Arrays (n,), kelvin.
    """
    time_s = np.asarray(time_s, float)
    n = time_s.shape[0]
    t_out_c = _channel(t_out_c, n)
    ghi, dni, dhi = (_channel(v, n) for v in (ghi_wm2, dni_wm2, dhi_wm2))
    wind = _channel(wind_speed_ms, n)
    if clip_negative:
        ghi, dni, dhi, wind = (np.clip(v, 0.0, None) for v in (ghi, dni, dhi, wind))
    t_in_k = _channel(room.t_in_c if t_in_c is None else t_in_c, n) + T_ZERO
    t_mrt_k = t_in_k if room.t_mrt_c is None else np.full(n, room.t_mrt_c + T_ZERO)
    return WeatherInputs(
        time_s=time_s,
        t_out_k=t_out_c + T_ZERO,
        ghi_wm2=ghi,
        dni_wm2=dni,
        dhi_wm2=dhi,
        wind_speed_ms=_or_default(wind, 0.0),
        wind_dir_deg=_or_default(_channel(wind_dir_deg, n), facade_azimuth_deg),
        pressure_pa=_or_default(_channel(pressure_pa, n), standard_pressure_pa(elevation_m)),
        t_in_k=t_in_k,
        t_mrt_k=t_mrt_k,
        t_dew_k=np.full(n, np.nan) if rh_pct is None else dew_point_k(t_out_c, rh_pct),
        poa_global_wm2=None if poa_global_wm2 is None else np.asarray(poa_global_wm2, float),
        poa_diffuse_wm2=None if poa_diffuse_wm2 is None else np.asarray(poa_diffuse_wm2, float),
    )
