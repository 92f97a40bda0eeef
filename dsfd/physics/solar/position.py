"""Sun position, extraterrestrial irradiance, angles on a plane and air mass.

Times are UTC unix seconds; angles carry ``_deg`` in their names. Azimuths are clockwise
from north (south = 180°), surface tilt is from horizontal (vertical façade = 90°),
docs/model.md#conventions, docs/model.md#solar-geometry.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.physics.constants import STANDARD_PRESSURE_PA

FloatArray = NDArray[np.float64]

#: Solar constant of the Spencer extraterrestrial irradiance [W/m2] (pvlib default).
SOLAR_CONSTANT = 1366.1
#: J2000.0 epoch (2000-01-01 12:00 TT, taken as UTC) in unix seconds.
_J2000_UNIX_S = 946_728_000.0
#: Sun's geometric elevation below which Bennett's refraction is not applied [deg]
#: (solar semidiameter 0.26667° + refraction at the horizon 0.5667°, as in SPA).
_REFRACTION_CUTOFF_DEG = -(0.26667 + 0.5667)


class SolarPosition(NamedTuple):
    """Geocentric sun position (all arrays broadcast to the inputs' shape)."""

    zenith_deg: FloatArray  #: geometric (true) zenith, no refraction [deg]
    azimuth_deg: FloatArray  #: clockwise from north, [0, 360) [deg]
    elevation_deg: FloatArray  #: 90 − zenith [deg]
    declination_deg: FloatArray  #: [deg]
    equation_of_time_min: FloatArray  #: apparent − mean solar time [min]
    hour_angle_deg: FloatArray  #: 0 at solar noon, negative in the morning [deg]


def _as_float(x: ArrayLike) -> FloatArray:
    return np.asarray(x, dtype=np.float64)


def solar_position(
    unix_s: ArrayLike, latitude_deg: ArrayLike, longitude_deg: ArrayLike
) -> SolarPosition:
    """Sun position by the NOAA (Meeus) low-precision algorithm.

    Parameters
    ----------
    unix_s : array_like, [s]
        UTC unix time.
    latitude_deg : array_like, [deg]
        North positive.
    longitude_deg : array_like, [deg]
        East positive.

    Returns
    -------
    SolarPosition
        Geometric zenith, azimuth, elevation, declination, equation of time [min] and
        hour angle.

    Notes
    -----
    docs/model.md#solar-geometry. With Julian centuries ``jc`` since J2000.0 the sun's mean
    longitude L0, mean anomaly M, orbit eccentricity e, equation of centre C, apparent longitude λ
    and corrected obliquity ε give δ = asin(sin ε sin λ) and (y = tan²(ε/2))::

        EoT = 4·deg(y sin2L0 − 2e sinM + 4ey sinM cos2L0 − ½y² sin4L0 − 1.25e² sin2M)
        ω   = (minutes_UTC + EoT + 4·lon) mod 1440 / 4 − 180
        cosZ = sinφ sinδ + cosφ cosδ cosω

    The azimuth uses the atan2 form of Meeus' formula, identical to NOAA's arccos
    expression but regular at the zenith and the poles::

        γ = 180 + atan2(sinω cosδ, cosω cosδ sinφ − sinδ cosφ)

    ΔT (TT − UT, ~68 s in 2016) is ignored; it moves the sun by < 0.001°. No parallax and
    no refraction (see :func:`apparent_elevation`). Stated accuracy 0.0167° for
    |lat| < 72°; against pvlib's SPA the tests find ≤ 0.007° above 5° elevation.

    References: NOAA Global Monitoring Laboratory, "Solar Calculation Details" and
    spreadsheet calculator; J. Meeus, *Astronomical Algorithms*, 2nd ed., Willmann-Bell,
    1998, ch. 25 and 28.
    """
    t = _as_float(unix_s)
    lat = np.radians(_as_float(latitude_deg))
    decl, eot_min = _declination_and_equation_of_time(t)
    minutes_utc = np.mod(t, 86400.0) / 60.0
    true_solar_min = np.mod(minutes_utc + eot_min + 4.0 * _as_float(longitude_deg), 1440.0)
    hour_angle_deg = true_solar_min / 4.0 - 180.0
    omega = np.radians(hour_angle_deg)

    cos_zen = np.sin(lat) * np.sin(decl) + np.cos(lat) * np.cos(decl) * np.cos(omega)
    zenith = np.degrees(np.arccos(np.clip(cos_zen, -1.0, 1.0)))
    azimuth = np.mod(
        180.0 + np.degrees(np.arctan2(
            np.sin(omega) * np.cos(decl),
            np.cos(omega) * np.cos(decl) * np.sin(lat) - np.sin(decl) * np.cos(lat),
        )),
        360.0,
    )
    return SolarPosition(zenith, azimuth, 90.0 - zenith, np.degrees(decl), eot_min,
                         hour_angle_deg)


def _declination_and_equation_of_time(t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Solar declination [rad] and equation of time [min] at UTC unix times ``t`` [s]:
    the orbital part of :func:`solar_position` (its Notes)."""
    jc = (t - _J2000_UNIX_S) / 86400.0 / 36525.0
    mean_lon = np.radians(np.mod(280.46646 + jc * (36000.76983 + 0.0003032 * jc), 360.0))
    anomaly = np.radians(357.52911 + jc * (35999.05029 - 0.0001537 * jc))
    ecc = 0.016708634 - jc * (0.000042037 + 0.0000001267 * jc)
    centre = (
        np.sin(anomaly) * (1.914602 - jc * (0.004817 + 0.000014 * jc))
        + np.sin(2 * anomaly) * (0.019993 - 0.000101 * jc)
        + np.sin(3 * anomaly) * 0.000289
    )
    node = np.radians(125.04 - 1934.136 * jc)  # longitude of the moon's ascending node
    apparent_lon = mean_lon + np.radians(centre - 0.00569 - 0.00478 * np.sin(node))
    obliquity_mean = 23.0 + (26.0 + (21.448 - jc * (46.815 + jc * (0.00059 - 0.001813 * jc)))
                             / 60.0) / 60.0
    obliquity = np.radians(obliquity_mean + 0.00256 * np.cos(node))
    decl = np.arcsin(np.sin(obliquity) * np.sin(apparent_lon))

    y = np.tan(obliquity / 2.0) ** 2
    eot_min = 4.0 * np.degrees(
        y * np.sin(2 * mean_lon)
        - 2 * ecc * np.sin(anomaly)
        + 4 * ecc * y * np.sin(anomaly) * np.cos(2 * mean_lon)
        - 0.5 * y**2 * np.sin(4 * mean_lon)
        - 1.25 * ecc**2 * np.sin(2 * anomaly)
    )
    return decl, eot_min


def apparent_elevation(
    elevation_deg: ArrayLike, *, pressure_pa: ArrayLike = STANDARD_PRESSURE_PA,
    temp_c: ArrayLike = 12.0,
) -> FloatArray:
    """Sun elevation corrected for atmospheric refraction.

    Parameters
    ----------
    elevation_deg : array_like, [deg]
        Geometric elevation.
    pressure_pa : array_like, [Pa]
    temp_c : array_like, [degC]

    Returns
    -------
    ndarray, [deg]
        Apparent elevation; equal to the geometric one below −0.833° (sun set).

    Notes
    -----
    Bennett's formula with the usual pressure/temperature scaling (as used in the NREL
    SPA, Reda & Andreas 2004, eq. 42)::

        R [arcmin] = P/101000 · 283/(273 + T) · 1.02 / tan(h + 10.3/(h + 5.11))

    References: G. G. Bennett, "The calculation of astronomical refraction in marine
    navigation", J. Navigation 35 (1982) 255–259; I. Reda and A. Andreas, "Solar position
    algorithm for solar radiation applications", Solar Energy 76 (2004) 577–589.
    """
    h = _as_float(elevation_deg)
    applies = h >= _REFRACTION_CUTOFF_DEG
    h_safe = np.where(applies, h, 0.0)
    scale = (_as_float(pressure_pa) / 101000.0) * (283.0 / (273.0 + _as_float(temp_c)))
    refraction_arcmin = scale * 1.02 / np.tan(np.radians(h_safe + 10.3 / (h_safe + 5.11)))
    # the fit turns slightly negative within 0.11° of the zenith; refraction is never < 0
    refraction_arcmin = np.maximum(refraction_arcmin, 0.0)
    return np.where(applies, h + refraction_arcmin / 60.0, h)


def day_of_year(unix_s: ArrayLike) -> FloatArray:
    """UTC calendar day of year, 1…366 (NaN where the time is not finite)."""
    t = _as_float(unix_s)
    finite = np.isfinite(t)
    days = np.floor(np.where(finite, t, 0.0) / 86400.0).astype("int64").astype("datetime64[D]")
    first = days.astype("datetime64[Y]").astype("datetime64[D]")
    doy = (days - first).astype("int64") + 1.0
    return np.where(finite, doy, np.nan)


def extraterrestrial_irradiance(
    unix_s: ArrayLike, *, solar_constant: float = SOLAR_CONSTANT
) -> FloatArray:
    """Extraterrestrial normal irradiance I0 (Spencer 1971).

    Parameters
    ----------
    unix_s : array_like, [s]
        UTC unix time; only its UTC day of year is used.
    solar_constant : float, [W/m2]

    Returns
    -------
    ndarray, [W/m2]

    Notes
    -----
    docs/model.md#solar-geometry, with the day angle B = 2π(doy − 1)/365::

        I0 = S (1.00011 + 0.034221 cosB + 0.00128 sinB + 0.000719 cos2B + 0.000077 sin2B)

    Reference: J. W. Spencer, "Fourier series representation of the position of the sun",
    Search 2 (1971) 172.
    """
    b = 2.0 * np.pi * (day_of_year(unix_s) - 1.0) / 365.0
    return solar_constant * (1.00011 + 0.034221 * np.cos(b) + 0.00128 * np.sin(b)
                             + 0.000719 * np.cos(2 * b) + 0.000077 * np.sin(2 * b))


def incidence_and_profile(
    zenith_deg: ArrayLike,
    azimuth_deg: ArrayLike,
    surface_azimuth_deg: ArrayLike,
    *,
    surface_tilt_deg: ArrayLike = 90.0,
) -> tuple[FloatArray, FloatArray]:
    """Angle of incidence on a plane and the sun's profile angle for that plane.

    Parameters
    ----------
    zenith_deg, azimuth_deg : array_like, [deg]
        Sun position.
    surface_azimuth_deg : array_like, [deg]
        Azimuth of the outward surface normal (south façade = 180).
    surface_tilt_deg : array_like, [deg]
        Tilt from horizontal (vertical façade = 90).

    Returns
    -------
    aoi_deg : ndarray, [deg]
        Angle between the sun ray and the surface normal, 0…180.
    profile_deg : ndarray, [deg]
        Elevation of the sun ray projected onto the vertical plane that contains the
        surface normal's azimuth, −90…90 (independent of tilt). When the sun is behind
        that plane (cos Δγ ≤ 0) the projection is clipped to the plane's vertical axis:
        +90 with the sun above the horizon, −90 below it (0 exactly on the horizon). This
        is the limit approached from the front, so the value is continuous and never NaN;
        the beam on a vertical façade is zero there anyway.

    Notes
    -----
    docs/model.md#solar-geometry with Δγ = γ_s − γ_f and α = 90° − Z::

        cos θ = cos β cos Z + sin β sin Z cos Δγ
        φ_s   = atan2(cos Z, max(sin Z cos Δγ, 0))      (= atan(tan α / cos Δγ) in front)
    """
    zen = np.radians(_as_float(zenith_deg))
    tilt = np.radians(_as_float(surface_tilt_deg))
    cos_dgamma = np.cos(np.radians(_as_float(azimuth_deg) - _as_float(surface_azimuth_deg)))
    cos_aoi = np.cos(tilt) * np.cos(zen) + np.sin(tilt) * np.sin(zen) * cos_dgamma
    aoi = np.degrees(np.arccos(np.clip(cos_aoi, -1.0, 1.0)))
    horizontal_towards_normal = np.maximum(np.sin(zen) * cos_dgamma, 0.0)
    profile = np.degrees(np.arctan2(np.cos(zen), horizontal_towards_normal))
    return aoi, profile


def relative_airmass(zenith_deg: ArrayLike) -> FloatArray:
    """Relative optical air mass (Kasten & Young 1989).

    Parameters
    ----------
    zenith_deg : array_like, [deg]
        Apparent zenith in the original work; geometric zenith also accepted.

    Returns
    -------
    ndarray, [-]
        Finite up to Z = 90° (≈ 37.9 at the horizon) and NaN for Z > 90° (sun below the
        horizon), as in pvlib; no runtime warnings.

    Notes
    -----
    AM = 1 / (cos Z + 0.50572 (96.07995° − Z)^−1.6364).

    Reference: F. Kasten and A. T. Young, "Revised optical air mass tables and
    approximation formula", Applied Optics 28 (1989) 4735–4738.
    """
    z = _as_float(zenith_deg)
    up = z <= 90.0
    z_safe = np.where(up, z, 90.0)
    am = 1.0 / (np.cos(np.radians(z_safe)) + 0.50572 * (96.07995 - z_safe) ** -1.6364)
    return np.where(up, am, np.nan)


def _kasten1966_airmass(zenith_deg: FloatArray) -> FloatArray:
    """Kasten (1966) relative air mass, zenith clipped to 90° (used by DISC/DIRINT)."""
    z = np.minimum(zenith_deg, 90.0)
    return 1.0 / (np.cos(np.radians(z)) + 0.15 * (93.885 - z) ** -1.253)


