"""The weather time series handed to the controller and the plant, and its time handling.

A :class:`WeatherSeries` holds one value per channel at each instant ``time_s`` (UTC unix
seconds). Logger values are interval means; the readers stamp them at the interval
MIDPOINT, so a value and the sun position computed at ``time_s`` belong together.
:func:`resample` evaluates a series at model-step midpoints (docs/model.md#time-convention) and
:func:`shift_to_site` replays foreign weather at the same local solar time elsewhere.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from datetime import UTC, datetime

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: Channels with one value per sample, in field order.
CHANNELS = ("t_out_c", "ghi_wm2", "dni_wm2", "dhi_wm2", "wind_speed_ms", "wind_dir_deg",
            "pressure_pa", "rh_pct")
#: Channels that are irradiances (clipped at 0 by the readers).
IRRADIANCE_CHANNELS = ("ghi_wm2", "dni_wm2", "dhi_wm2")
#: Longest run of consecutive missing samples that is filled by interpolation.
MAX_FILL_SAMPLES = 3


@dataclass(frozen=True, eq=False)
class WeatherSeries:
    """Measured or typical-year weather on a common time axis (SI units, degrees by name).

    Attributes
    ----------
    time_s : ndarray (n,), [s]
        UTC unix time of the instant each value represents (interval midpoint for
        interval means); strictly increasing.
    t_out_c : ndarray (n,), [degC]
        Outdoor air temperature.
    ghi_wm2, dni_wm2, dhi_wm2 : ndarray (n,), [W/m2]
        Global horizontal, direct normal and diffuse horizontal irradiance; NaN where
        not measured.
    wind_speed_ms : ndarray (n,), [m/s]
    wind_dir_deg : ndarray (n,), [deg]
        Direction the wind comes from, clockwise from north.
    pressure_pa : ndarray (n,), [Pa]
        Station (not sea-level) pressure.
    rh_pct : ndarray (n,), [%]
    source : str
        What the data are (station, file).
    station_latitude_deg, station_longitude_deg : float, [deg]
        North and east positive.
    station_elevation_m : float, [m]
    attribution : str
        Citation / licence line to show wherever the data are used.
    shift_s : float, [s]
        Time shift applied by :func:`shift_to_site` (0 for the station's own clock).
    pressure_elevation_m : float or None, [m]
        Elevation that ``pressure_pa`` refers to: None for the station's own, else the
        elevation :func:`dsfd.sim.replay.at_site` moved it to.
    notes : tuple of str
        Human-readable processing history.
    """

    time_s: FloatArray
    t_out_c: FloatArray
    ghi_wm2: FloatArray
    dni_wm2: FloatArray
    dhi_wm2: FloatArray
    wind_speed_ms: FloatArray
    wind_dir_deg: FloatArray
    pressure_pa: FloatArray
    rh_pct: FloatArray
    source: str
    station_latitude_deg: float
    station_longitude_deg: float
    station_elevation_m: float
    attribution: str = ""
    shift_s: float = 0.0
    notes: tuple[str, ...] = field(default_factory=tuple)
    pressure_elevation_m: float | None = None

    def __post_init__(self) -> None:
        time = np.array(self.time_s, dtype=np.float64).reshape(-1)
        if time.size == 0:
            raise ValueError(f"weather series {self.source!r} has no samples")
        if not np.all(np.isfinite(time)) or np.any(np.diff(time) <= 0.0):
            raise ValueError(f"weather series {self.source!r}: time_s must be finite and "
                             "strictly increasing")
        time.flags.writeable = False
        object.__setattr__(self, "time_s", time)
        for name in CHANNELS:
            values = np.array(getattr(self, name), dtype=np.float64).reshape(-1)
            if values.shape != time.shape:
                raise ValueError(f"weather series {self.source!r}: {name} has "
                                 f"{values.size} values for {time.size} times")
            values.flags.writeable = False
            object.__setattr__(self, name, values)
        object.__setattr__(self, "notes", tuple(self.notes))

    def __len__(self) -> int:
        return int(self.time_s.size)

    @property
    def nominal_step_s(self) -> float:
        """Median spacing of the samples [s] (0 for a single sample)."""
        return float(np.median(np.diff(self.time_s))) if len(self) > 1 else 0.0

    @property
    def coverage_s(self) -> tuple[float, float]:
        """Start and end of the time span the samples represent [s].

        Each sample stands for the interval of one nominal step centred on it, so the
        coverage extends half a step beyond the first and the last sample.
        """
        half = 0.5 * self.nominal_step_s
        return float(self.time_s[0] - half), float(self.time_s[-1] + half)


def utc_text(unix_s: float) -> str:
    """ISO-8601 UTC text of a unix time, for messages and notes."""
    return datetime.fromtimestamp(unix_s, UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


def fill_short_gaps(
    time_s: ArrayLike, values: ArrayLike, *, max_samples: int = MAX_FILL_SAMPLES
) -> tuple[FloatArray, int]:
    """Fill runs of missing (NaN) samples by linear interpolation in time.

    A run is filled only if it has at most ``max_samples`` samples and valid samples on
    both sides; longer runs and runs at either end of the record stay NaN.

    Returns
    -------
    filled : ndarray
    n_filled : int
        Number of samples that were filled.
    """
    t = np.asarray(time_s, dtype=np.float64)
    v = np.array(values, dtype=np.float64)
    missing = np.isnan(v)
    if not missing.any() or missing.all():
        return v, 0
    edges = np.diff(np.concatenate([[0], missing.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    inside = (starts > 0) & (stops < v.size) & (stops - starts <= max_samples)
    fill = np.zeros_like(missing)
    for start, stop in zip(starts[inside], stops[inside], strict=True):
        fill[start:stop] = True
    good = ~missing
    v[fill] = np.interp(t[fill], t[good], v[good])
    return v, int(fill.sum())


def _interp_wind_direction(
    t_eval: FloatArray, time_s: FloatArray, speed: FloatArray, direction_deg: FloatArray
) -> FloatArray:
    """Interpolate a direction on the circle via speed-weighted u/v components.

    Calm stretches (both neighbours at zero speed) fall back to unweighted unit vectors,
    so the direction stays defined.
    """
    rad = np.radians(direction_deg)
    east = np.interp(t_eval, time_s, speed * np.sin(rad))
    north = np.interp(t_eval, time_s, speed * np.cos(rad))
    calm = np.hypot(east, north) < 1e-9
    if np.any(calm):
        east = np.where(calm, np.interp(t_eval, time_s, np.sin(rad)), east)
        north = np.where(calm, np.interp(t_eval, time_s, np.cos(rad)), north)
    return np.mod(np.degrees(np.arctan2(east, north)), 360.0)


def interpolate(series: WeatherSeries, times_s: ArrayLike) -> dict[str, FloatArray]:
    """The channels at instants ``times_s`` (name → values), held beyond the data ends.

    Scalars are interpolated linearly in time, the wind direction on the circle
    (speed-weighted u/v components); NaN where a neighbouring sample is NaN.
    """
    t_eval = np.clip(np.asarray(times_s, float), series.time_s[0], series.time_s[-1])
    values = {
        name: np.interp(t_eval, series.time_s, getattr(series, name))
        for name in CHANNELS if name != "wind_dir_deg"
    }
    values["wind_dir_deg"] = _interp_wind_direction(
        t_eval, series.time_s, series.wind_speed_ms, series.wind_dir_deg)
    return values


def resample(
    series: WeatherSeries, *, start_s: float, step_s: float, n_steps: int
) -> WeatherSeries:
    """Evaluate a series at the midpoints of equal model steps.

    Step k covers [start_s + k·step_s, start_s + (k+1)·step_s] and is represented by its
    midpoint ``start_s + (k + 0.5)·step_s`` (docs/model.md#time-convention).

    Parameters
    ----------
    series : WeatherSeries
    start_s : float, [s]
        UTC unix time of the start of the first step.
    step_s : float, [s]
    n_steps : int

    Returns
    -------
    WeatherSeries
        ``n_steps`` samples at the step midpoints; scalars interpolated linearly in time,
        wind direction on the circle (speed-weighted u/v), NaN where a neighbouring
        source sample is NaN. Metadata, ``shift_s`` and notes are kept.

    Raises
    ------
    ValueError
        If the requested window [start_s, start_s + n_steps·step_s] is not inside
        ``series.coverage_s``. Within half a source interval of the first/last sample
        that sample's value is held (it is the mean over that interval).
    """
    if not step_s > 0.0 or n_steps < 1:
        raise ValueError(f"resample needs step_s > 0 and n_steps >= 1, got step_s={step_s}, "
                         f"n_steps={n_steps}")
    end_s = start_s + n_steps * step_s
    first, last = series.coverage_s
    tolerance = 1e-6
    if start_s < first - tolerance or end_s > last + tolerance:
        raise ValueError(
            f"requested weather window {utc_text(start_s)} to {utc_text(end_s)} "
            f"({n_steps} steps of {step_s:g} s) is outside the data of {series.source!r}, "
            f"which cover {utc_text(first)} to {utc_text(last)}"
        )
    midpoints = start_s + (np.arange(n_steps) + 0.5) * step_s
    values = interpolate(series, midpoints)
    note = f"resampled to {n_steps} step midpoints, step {step_s:g} s, from {utc_text(start_s)}"
    return dataclasses.replace(series, time_s=midpoints, notes=(*series.notes, note), **values)


def _longitude_text(longitude_deg: float) -> str:
    return f"{abs(longitude_deg):.1f}°{'E' if longitude_deg >= 0.0 else 'W'}"


def shift_to_site(series: WeatherSeries, *, longitude_deg: float) -> WeatherSeries:
    """Replay a station's weather at the same local solar time at another longitude.

    Parameters
    ----------
    series : WeatherSeries
    longitude_deg : float, [deg]
        Site longitude, east positive.

    Returns
    -------
    WeatherSeries
        ``time_s`` moved by ``shift_s = (station_lon − site_lon)/15 h``, so the sun
        stands at the same hour angle at the site as it did at the station. The shift is
        taken from the station's own clock (a previous shift is undone first), is recorded
        in ``shift_s`` and as a note. The longitude difference is not wrapped, which
        keeps the local calendar date (Alamosa → Suwon: −15.53 h, not +8.47 h). Only
        the clock moves: the declination is that of the original date (≤ 0.4°/day
        apart), and the station's latitude, climate and elevation stay what they are.
    """
    shift_s = (series.station_longitude_deg - longitude_deg) / 15.0 * 3600.0
    time = series.time_s - series.shift_s + shift_s
    hours = f"{shift_s / 3600.0:+.2f}".replace("-", "−")
    note = (f"shifted by {hours} h: replayed at the same local solar time at "
            f"{_longitude_text(longitude_deg)}")
    kept = tuple(n for n in series.notes if not n.startswith("shifted by "))
    return dataclasses.replace(series, time_s=time, shift_s=shift_s, notes=(*kept, note))
