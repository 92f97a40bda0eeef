"""Readers for measured and typical-year weather files into :class:`WeatherSeries`.

Every reader returns UTC times at the interval MIDPOINT of interval means
(docs/model.md#time-convention) and applies the same clean-up (documented once here):

* missing-value codes and bad QC flags become NaN;
* runs of at most :data:`~dsfd.weather.series.MAX_FILL_SAMPLES` consecutive missing samples
  with valid samples on both sides are filled by linear interpolation in time (wind
  direction on the circle); longer runs stay NaN; rows missing in every channel at the
  start or end of the file are dropped;
* negative irradiance (thermal offsets of the instruments at night) is clipped at 0;
* pressure is converted to Pa.
"""

from __future__ import annotations

import calendar
import csv
from importlib import resources
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from dsfd.weather.daily import read_kma_daily
from dsfd.weather.series import (
    CHANNELS,
    IRRADIANCE_CHANNELS,
    MAX_FILL_SAMPLES,
    WeatherSeries,
    fill_short_gaps,
)

FloatArray = NDArray[np.float64]

#: Bundled data sets: name -> file in dsfd/data/weather.
BUNDLED_WEATHER = {
    "surfrad-alamosa-2016-01-01": "surfrad-slv16001.dat",
    "rmis-golden-2022-01": "rmis_weather_data.csv",
    "kma-suwon-2008-12": "kma_asos_119_suwon_2008-12_2009-01.csv",
}
_SURFRAD_FIELDS = ("dw_solar", "uw_solar", "direct_n", "diffuse", "dw_ir", "dw_casetemp",
                   "dw_dometemp", "uw_ir", "uw_casetemp", "uw_dometemp", "uvb", "par",
                   "netsolar", "netir", "totalnet", "temp", "rh", "windspd", "winddir",
                   "pressure")
_RMIS_COLUMNS = {"t_out_c": "Ambient Temperature", "pressure_pa": "Barometric Pressure",
                 "dhi_wm2": "Diffuse Horizontal", "dni_wm2": "Direct Normal",
                 "ghi_wm2": "Global Horizontal", "rh_pct": "Relative Humidity",
                 "wind_dir_deg": "Wind Direction", "wind_speed_ms": "Wind Speed"}
#: EPW data fields (0-based) and the values at or above which the field is missing.
_EPW_FIELDS = {"t_out_c": (6, 99.9), "rh_pct": (8, 999.0), "pressure_pa": (9, 999999.0),
               "ghi_wm2": (13, 9999.0), "dni_wm2": (14, 9999.0), "dhi_wm2": (15, 9999.0),
               "wind_dir_deg": (20, 999.0), "wind_speed_ms": (21, 999.0)}
_TMY3_COLUMNS = {"t_out_c": "Dry-bulb (C)", "rh_pct": "RHum (%)", "pressure_pa": "Pressure (mbar)",
                 "ghi_wm2": "GHI (W/m^2)", "dni_wm2": "DNI (W/m^2)", "dhi_wm2": "DHI (W/m^2)",
                 "wind_dir_deg": "Wdir (degrees)", "wind_speed_ms": "Wspd (m/s)"}
#: Channels that hourly files give at the stamp (not as a mean over the past hour).
_POINT_CHANNELS = ("t_out_c", "rh_pct", "pressure_pa", "wind_speed_ms", "wind_dir_deg")


def _unix(year: int, month: int, day: int, hour: int = 0, minute: int = 0) -> float:
    """Unix seconds of a naive calendar time read as UTC (hour 24 allowed)."""
    return float(calendar.timegm((year, month, day, 0, minute, 0)) + 3600 * hour)


def _finish(
    time_s: FloatArray,
    channels: dict[str, FloatArray],
    *,
    source: str,
    latitude_deg: float,
    longitude_deg: float,
    elevation_m: float,
    attribution: str,
    notes: tuple[str, ...],
) -> WeatherSeries:
    """Apply the module's clean-up rules and build the series."""
    data = {name: np.asarray(channels[name], dtype=np.float64) for name in CHANNELS}
    present = np.zeros(time_s.size, dtype=bool)
    for values in data.values():
        present |= np.isfinite(values)
    if not present.any():
        raise ValueError(f"{source}: no valid values")
    keep = slice(int(np.argmax(present)), int(present.size - np.argmax(present[::-1])))
    time_s = time_s[keep]
    data = {name: values[keep] for name, values in data.items()}
    n_filled = {}
    for name in CHANNELS:
        if name != "wind_dir_deg":
            data[name], n_filled[name] = fill_short_gaps(time_s, data[name])
    rad = np.radians(data["wind_dir_deg"])  # fill on the circle
    east, _ = fill_short_gaps(time_s, np.sin(rad))
    north, n_filled["wind_dir_deg"] = fill_short_gaps(time_s, np.cos(rad))
    data["wind_dir_deg"] = np.mod(np.degrees(np.arctan2(east, north)), 360.0)
    for name in IRRADIANCE_CHANNELS:
        data[name] = np.where(data[name] < 0.0, 0.0, data[name])
    if sum(n_filled.values()):
        filled = ", ".join(f"{name} {n}" for name, n in n_filled.items() if n)
        notes = (*notes, f"filled short gaps (at most {MAX_FILL_SAMPLES} samples) by linear "
                         f"interpolation: {filled}")
    return WeatherSeries(
        time_s=time_s, **data, source=source, station_latitude_deg=latitude_deg,
        station_longitude_deg=longitude_deg, station_elevation_m=elevation_m,
        attribution=attribution, notes=notes,
    )


def _interval_midpoints(stamp_s: FloatArray) -> FloatArray:
    """Midpoints of intervals stamped at their END: stamp − ½ × median spacing."""
    step = float(np.median(np.diff(stamp_s))) if stamp_s.size > 1 else 0.0
    return stamp_s - 0.5 * step


def _point_to_midpoint(values: FloatArray, *, circular: bool = False) -> FloatArray:
    """Value halfway between consecutive stamps: mean of the two (first row: its own).

    With ``circular`` the values are directions [deg], averaged as unit vectors.
    """
    previous = np.concatenate([values[:1], values[:-1]])
    if not circular:
        return 0.5 * (previous + values)
    a, b = np.radians(previous), np.radians(values)
    mean = np.arctan2(np.sin(a) + np.sin(b), np.cos(a) + np.cos(b))
    return np.mod(np.degrees(mean), 360.0)


def read_surfrad(path: str | Path) -> WeatherSeries:
    """Read a NOAA GML SURFRAD daily ``.dat`` file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    WeatherSeries
        GHI = dw_solar, DNI = direct_n, DHI = diffuse, plus temp, rh, windspd, winddir and
        pressure (mbar → Pa). Values with a QC flag ≠ 0 or −9999.9 are NaN.

    Notes
    -----
    Header: station name, then "lat lon elev …" where the longitude is written west
    positive (all SURFRAD stations are in the western hemisphere; it is returned east
    positive, i.e. negative). Each row: year, day of year, month, day, hour, minute
    (UTC), decimal hour, solar zenith, then value/QC-flag pairs. The stamps mark the END
    of the averaging interval: the file's own zenith column equals the apparent zenith
    half an interval earlier (for slv16001: SPA at stamp − 30 s within 0.004°, against
    0.05° rms at the stamp), so the samples are placed at stamp − ½ interval.
    """
    path = Path(path)
    with path.open() as handle:
        station = handle.readline().strip()
        header = handle.readline().split()
    table = np.loadtxt(path, skiprows=2, ndmin=2)
    latitude, longitude_west, elevation = float(header[0]), float(header[1]), float(header[2])
    stamps = np.array([_unix(int(r[0]), 1, 1, int(r[4]), int(r[5])) + 86400.0 * (int(r[1]) - 1)
                       for r in table])
    raw = {}
    for k, name in enumerate(_SURFRAD_FIELDS):
        value, flag = table[:, 8 + 2 * k], table[:, 9 + 2 * k]
        raw[name] = np.where((flag == 0) & (value > -9999.0), value, np.nan)
    channels = {"t_out_c": raw["temp"], "ghi_wm2": raw["dw_solar"],
                "dni_wm2": raw["direct_n"], "dhi_wm2": raw["diffuse"],
                "wind_speed_ms": raw["windspd"], "wind_dir_deg": raw["winddir"],
                "pressure_pa": raw["pressure"] * 100.0, "rh_pct": raw["rh"]}
    return _finish(
        _interval_midpoints(stamps), channels,
        source=f"NOAA GML SURFRAD {station} ({path.name})",
        latitude_deg=latitude, longitude_deg=-abs(longitude_west), elevation_m=elevation,
        attribution=f"NOAA GML SURFRAD, {station} (public domain, US Government work)",
        notes=("times are interval midpoints (stamp − ½ interval)",),
    )


def read_rmis(
    path: str | Path,
    *,
    utc_offset_h: float = -7.0,
    latitude_deg: float = 39.742,
    longitude_deg: float = -105.18,
    elevation_m: float = 1829.0,
) -> WeatherSeries:
    """Read the NREL RMIS weather-station CSV (as shipped with pvanalytics).

    Parameters
    ----------
    path : str or Path
    utc_offset_h : float, [h]
        Clock of the naive timestamps (MST = UTC−7, no daylight saving).
    latitude_deg, longitude_deg, elevation_m : float
        Station: NREL RMIS, Golden, Colorado.

    Notes
    -----
    First column: naive "M/D/YYYY H:MM" stamps at the END of 5-minute intervals, then
    named columns (temperature [C], pressure [mbar], irradiances [W/m2], RH [%], wind
    direction [deg], wind speed [m/s]). Samples are placed at stamp − 2.5 min, converted
    to UTC. Empty cells are missing.
    """
    path = Path(path)
    with path.open(newline="") as handle:
        rows = list(csv.reader(handle))
    header, body = rows[0], [r for r in rows[1:] if r and r[0].strip()]
    stamps = []
    for row in body:
        date, clock = row[0].split()
        month, day, year = (int(x) for x in date.split("/"))
        hour, minute = (int(x) for x in clock.split(":"))
        stamps.append(_unix(year, month, day, hour, minute) - utc_offset_h * 3600.0)
    channels = {}
    for name, column in _RMIS_COLUMNS.items():
        k = header.index(column)
        channels[name] = np.array([float(r[k]) if r[k].strip() else np.nan for r in body])
    channels["pressure_pa"] = channels["pressure_pa"] * 100.0
    return _finish(
        _interval_midpoints(np.array(stamps)), channels,
        source=f"NREL RMIS weather station, Golden CO ({path.name})",
        latitude_deg=latitude_deg, longitude_deg=longitude_deg, elevation_m=elevation_m,
        attribution="NREL RMIS reference weather station, Golden CO; file from pvanalytics "
                    "(MIT licence)",
        notes=(f"times are interval midpoints (stamp − ½ interval), clock UTC{utc_offset_h:+g} h",),
    )


def _typical_year_times(
    years: list[int], months: list[int], days: list[int], hours: list[int], utc_offset_h: float
) -> tuple[FloatArray, list[str]]:
    """UTC midpoints of hour-ending local-standard-time stamps; one year if years jump."""
    notes = []

    def stamps(year_of: list[int]) -> FloatArray:
        return np.array([_unix(y, m, d, h) for y, m, d, h in
                         zip(year_of, months, days, hours, strict=True)])

    stamp = stamps(years)
    if np.any(np.diff(stamp) <= 0.0):
        stamp = stamps([years[0]] * len(years))
        notes.append(f"typical-year file: all records placed in {years[0]}")
    midpoints = stamp - 1800.0 - utc_offset_h * 3600.0
    notes.append("hourly means at the hour midpoints; point values averaged onto them")
    return midpoints, notes


def read_epw(path: str | Path) -> WeatherSeries:
    """Read an EnergyPlus weather (EPW) file.

    Notes
    -----
    Eight header records; LOCATION gives city, state, country, data source, WMO number,
    latitude, longitude (east positive), time zone [h from UTC] and elevation [m]. Data
    records: year, month, day, hour 1–24 (hour ENDING, local standard time), minute,
    flags, dry bulb [C], dew point, RH [%], station pressure [Pa], …, GHI, DNI, DHI
    (fields 13–15, Wh/m2 over the past hour = mean W/m2), …, wind direction [deg] and
    speed [m/s] (fields 20, 21). Missing: 99.9 (temperature), 999 (RH, wind), 999999
    (pressure), 9999 (radiation). Hourly files only.

    Radiation is placed at the hour midpoint (stamp − 30 min); temperature, RH, pressure
    and wind are values AT the stamp, so the mean of two consecutive stamps is used at
    the midpoint (the first record keeps its own value). Typical-year files mix source
    years; if the times are not increasing all records are placed in the first year.
    """
    path = Path(path)
    with path.open(newline="", encoding="latin-1") as handle:
        rows = list(csv.reader(handle))
    location = rows[0]
    if location[0].strip().upper() != "LOCATION":
        raise ValueError(f"{path}: not an EPW file (first record is not LOCATION)")
    city, country, data_source = location[1].strip(), location[3].strip(), location[4].strip()
    latitude, longitude = float(location[6]), float(location[7])
    utc_offset_h, elevation = float(location[8]), float(location[9])
    body = [r for r in rows[8:] if len(r) > 21]
    times, notes = _typical_year_times([int(r[0]) for r in body], [int(r[1]) for r in body],
                                       [int(r[2]) for r in body], [int(r[3]) for r in body],
                                       utc_offset_h)
    channels = {}
    for name, (k, missing_at) in _EPW_FIELDS.items():
        values = np.array([float(r[k]) for r in body])
        channels[name] = np.where(values >= missing_at, np.nan, values)
    for name in _POINT_CHANNELS:
        channels[name] = _point_to_midpoint(channels[name], circular=name == "wind_dir_deg")
    return _finish(
        times, channels,
        source=f"EnergyPlus weather file {city}, {country} ({path.name})",
        latitude_deg=latitude, longitude_deg=longitude, elevation_m=elevation,
        attribution=f"EPW data source: {data_source or 'not stated'}",
        notes=tuple(notes),
    )


def read_tmy3(path: str | Path) -> WeatherSeries:
    """Read an NSRDB TMY3 CSV file.

    Notes
    -----
    Line 1: USAF number, site name, state, time zone [h from UTC], latitude, longitude
    (east positive), elevation [m]. Line 2: column names ("Date (MM/DD/YYYY)", "Time
    (HH:MM)" with 01:00…24:00 hour ENDING local standard time, "GHI (W/m^2)", "Dry-bulb
    (C)", "Pressure (mbar)", "Wspd (m/s)", …). Irradiance is the mean over the past hour,
    the meteorological values are at the stamp; both are placed at the hour midpoint as
    in :func:`read_epw`. Values ≤ −9900 are missing.
    """
    path = Path(path)
    with path.open(newline="", encoding="latin-1") as handle:
        rows = list(csv.reader(handle))
    site, header = rows[0], [name.strip() for name in rows[1]]
    usaf, name = site[0].strip(), site[1].strip()
    utc_offset_h, latitude, longitude, elevation = (float(x) for x in site[3:7])
    body = [r for r in rows[2:] if r and r[0].strip()]
    date_col, time_col = header.index("Date (MM/DD/YYYY)"), header.index("Time (HH:MM)")
    dates = [[int(x) for x in r[date_col].split("/")] for r in body]
    hours = [int(r[time_col].split(":")[0]) for r in body]
    times, notes = _typical_year_times([d[2] for d in dates], [d[0] for d in dates],
                                       [d[1] for d in dates], hours, utc_offset_h)
    channels = {}
    for channel, column in _TMY3_COLUMNS.items():
        k = header.index(column)
        values = np.array([float(r[k]) for r in body])
        channels[channel] = np.where(values <= -9900.0, np.nan, values)
    channels["pressure_pa"] = channels["pressure_pa"] * 100.0
    for channel in _POINT_CHANNELS:
        channels[channel] = _point_to_midpoint(channels[channel],
                                               circular=channel == "wind_dir_deg")
    return _finish(
        times, channels,
        source=f"NSRDB TMY3 {usaf} {name} ({path.name})",
        latitude_deg=latitude, longitude_deg=longitude, elevation_m=elevation,
        attribution="NREL National Solar Radiation Database, TMY3",
        notes=tuple(notes),
    )


def read_weather(path: str | Path) -> WeatherSeries:
    """Read any supported weather file, chosen by extension and first line.

    ``.epw`` → :func:`read_epw`; ``.dat`` → :func:`read_surfrad`; ``.csv`` whose second
    line starts with "Date (MM/DD/YYYY)" → :func:`read_tmy3`, whose first line names
    "Global Horizontal" → :func:`read_rmis`, whose first line names the KMA daily columns
    "minTa" and "sumGsr" → :func:`dsfd.weather.daily.read_kma_daily`.
    """
    path = Path(path)
    with path.open(encoding="latin-1") as handle:
        first, second = handle.readline(), handle.readline()
    suffix = path.suffix.lower()
    if suffix == ".epw" or first.upper().startswith("LOCATION,"):
        return read_epw(path)
    if second.startswith("Date (MM/DD/YYYY)"):
        return read_tmy3(path)
    if "Global Horizontal" in first:
        return read_rmis(path)
    if "sumGsr" in first and "minTa" in first:
        return read_kma_daily(path)
    if suffix == ".dat":
        return read_surfrad(path)
    raise ValueError(f"{path}: unknown weather file format (supported: SURFRAD .dat, "
                     "NREL RMIS .csv, EPW, TMY3 .csv, KMA ASOS daily .csv)")


def bundled_weather(name: str) -> Path:
    """Path of a weather file shipped in ``dsfd/data/weather`` (see dsfd/data/README.md).

    Names: ``"surfrad-alamosa-2016-01-01"`` (1-min, clear winter day, UTC),
    ``"rmis-golden-2022-01"`` (5-min, 1–4 Jan 2022, MST) and ``"kma-suwon-2008-12"``
    (daily statistics of Suwon, 1 Dec 2008 – 31 Jan 2009, KST: the period of the paper's
    experiments, disaggregated on reading). Read any with :func:`read_weather`. Requires
    the package to be installed as files (not zipped).
    """
    try:
        filename = BUNDLED_WEATHER[name]
    except KeyError:
        raise ValueError(f"unknown bundled weather {name!r}; "
                         f"available: {', '.join(sorted(BUNDLED_WEATHER))}") from None
    path = Path(str(resources.files("dsfd.data").joinpath("weather", filename)))
    if not path.is_file():
        raise FileNotFoundError(f"bundled weather file missing: {path}")
    return path
