"""Transposition of beam and diffuse irradiance onto a tilted (façade) plane.

Isotropic, Hay–Davies (lumped model default) and Perez 1990 (truth plant) sky models,
docs/model.md#transposition. The zenith may be geometric or apparent (the pvlib reference tables use
the apparent zenith; the difference matters only within ~5° of the horizon).
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from dsfd.physics.solar.position import (
    FloatArray,
    _as_float,
    incidence_and_profile,
    relative_airmass,
)

#: Upper edges of the Perez sky-clearness (ε) bins 1…7; bin 8 is ε ≥ 6.2.
PEREZ_EPSILON_EDGES = np.array([1.065, 1.23, 1.5, 1.95, 2.8, 4.5, 6.2])
#: Perez et al. (1990) "all sites composite" coefficients per ε bin: F11, F12, F13 …
PEREZ_F1 = np.array([
    [-0.008, 0.588, -0.062],
    [0.130, 0.683, -0.151],
    [0.330, 0.487, -0.221],
    [0.568, 0.187, -0.295],
    [0.873, -0.392, -0.362],
    [1.132, -1.237, -0.412],
    [1.060, -1.600, -0.359],
    [0.678, -0.327, -0.250],
])
#: … and F21, F22, F23.
PEREZ_F2 = np.array([
    [-0.060, 0.072, -0.022],
    [-0.019, 0.066, -0.029],
    [0.055, -0.064, -0.026],
    [0.109, -0.152, -0.014],
    [0.226, -0.462, 0.001],
    [0.288, -0.823, 0.056],
    [0.264, -1.127, 0.131],
    [0.156, -1.377, 0.251],
])

class SkyDiffuse(NamedTuple):
    """Sky diffuse on the plane and its parts (total = isotropic + circumsolar + horizon)."""

    total: FloatArray  #: [W/m2]
    isotropic: FloatArray  #: [W/m2]
    circumsolar: FloatArray  #: [W/m2]
    horizon: FloatArray  #: horizon brightening (may be negative) [W/m2]


class FacadeIrradiance(NamedTuple):
    beam: FloatArray  #: [W/m2]
    sky_diffuse: FloatArray  #: [W/m2]
    ground_diffuse: FloatArray  #: [W/m2]
    aoi_deg: FloatArray  #: angle of incidence [deg]
    profile_deg: FloatArray  #: profile angle (see incidence_and_profile) [deg]


def beam_on_surface(dni: ArrayLike, aoi_deg: ArrayLike) -> FloatArray:
    """Beam irradiance on the plane, DNI · max(cos θ, 0) [W/m2] (docs/model.md#transposition)."""
    return _as_float(dni) * np.maximum(np.cos(np.radians(_as_float(aoi_deg))), 0.0)


def ground_diffuse(
    ghi: ArrayLike, albedo: ArrayLike, *, surface_tilt_deg: ArrayLike = 90.0
) -> FloatArray:
    """Ground-reflected irradiance, GHI · ρ_g · (1 − cos β)/2 [W/m2] (isotropic ground)."""
    tilt = np.radians(_as_float(surface_tilt_deg))
    return _as_float(ghi) * _as_float(albedo) * 0.5 * (1.0 - np.cos(tilt))


def sky_diffuse_isotropic(dhi: ArrayLike, *, surface_tilt_deg: ArrayLike = 90.0) -> FloatArray:
    """Isotropic sky diffuse, DHI (1 + cos β)/2 [W/m2].

    Reference: B. Y. H. Liu and R. C. Jordan, Solar Energy 7 (1963) 53–74.
    """
    return _as_float(dhi) * 0.5 * (1.0 + np.cos(np.radians(_as_float(surface_tilt_deg))))


def sky_diffuse_haydavies(
    dhi: ArrayLike,
    dni: ArrayLike,
    dni_extra: ArrayLike,
    *,
    zenith_deg: ArrayLike,
    aoi_deg: ArrayLike,
    surface_tilt_deg: ArrayLike = 90.0,
) -> SkyDiffuse:
    """Sky diffuse on a plane with the Hay & Davies (1980) anisotropic model.

    Parameters
    ----------
    dhi, dni, dni_extra : array_like, [W/m2]
    zenith_deg, aoi_deg : array_like, [deg]
    surface_tilt_deg : array_like, [deg]

    Returns
    -------
    SkyDiffuse
        total, isotropic and circumsolar parts (horizon part 0), each ≥ 0 [W/m2].

    Notes
    -----
    docs/model.md#transposition, with the anisotropy index A_i = DNI/I0::

        I_sky = DHI [A_i R_b + (1 − A_i)(1 + cos β)/2],   R_b = max(cos θ, 0)/max(cos Z, 0.01745)

    Reference: J. E. Hay and J. A. Davies, "Calculation of the solar radiation incident on
    an inclined surface", Proc. First Canadian Solar Radiation Data Workshop (1980) 59–72.
    """
    dhi_a = _as_float(dhi)
    anisotropy = _as_float(dni) / _as_float(dni_extra)
    rb = np.maximum(np.cos(np.radians(_as_float(aoi_deg))), 0.0) / np.maximum(
        np.cos(np.radians(_as_float(zenith_deg))), 0.01745)
    iso = np.maximum(dhi_a * (1.0 - anisotropy) * 0.5
                     * (1.0 + np.cos(np.radians(_as_float(surface_tilt_deg)))), 0.0)
    circ = np.maximum(dhi_a * anisotropy * rb, 0.0)
    return SkyDiffuse(iso + circ, iso, circ, np.zeros_like(iso))


def sky_diffuse_perez(
    dhi: ArrayLike,
    dni: ArrayLike,
    dni_extra: ArrayLike,
    airmass: ArrayLike,
    *,
    zenith_deg: ArrayLike,
    aoi_deg: ArrayLike,
    surface_tilt_deg: ArrayLike = 90.0,
) -> SkyDiffuse:
    """Sky diffuse on a plane with the Perez et al. (1990) model (all-sites composite).

    Parameters
    ----------
    dhi, dni, dni_extra : array_like, [W/m2]
    airmass : array_like, [-]
        Relative (not pressure-corrected) air mass, see :func:`relative_airmass`. Where it
        is NaN (sun below the horizon) all parts are 0.
    zenith_deg, aoi_deg, surface_tilt_deg : array_like, [deg]

    Returns
    -------
    SkyDiffuse
        total (≥ 0), isotropic, circumsolar and horizon parts [W/m2]; where the total is
        clipped to 0 the parts are 0 too.

    Notes
    -----
    With Z in radians, κ = 1.041, sky clearness ε and brightness Δ::

        ε = ((DHI + DNI)/DHI + κZ³)/(1 + κZ³),     Δ = DHI · AM / I0
        F1 = max(F11 + F12 Δ + F13 Z, 0),          F2 = F21 + F22 Δ + F23 Z
        I_sky = DHI [(1 − F1)(1 + cos β)/2 + F1 max(cos θ, 0)/max(cos Z, cos 85°) + F2 sin β]

    F_ij per ε bin (edges 1.065, 1.23, 1.5, 1.95, 2.8, 4.5, 6.2) from the 1990 paper's
    "all sites composite" table.

    Reference: R. Perez, P. Ineichen, R. Seals, J. Michalsky and R. Stewart, "Modeling
    daylight availability and irradiance components from direct and global irradiance",
    Solar Energy 44 (1990) 271–289.
    """
    dhi_a, dni_a, am = _as_float(dhi), _as_float(dni), _as_float(airmass)
    z = np.radians(_as_float(zenith_deg))
    kz3 = 1.041 * z**3
    has_diffuse = dhi_a > 0.0
    eps = ((dhi_a + dni_a) / np.where(has_diffuse, dhi_a, 1.0) + kz3) / (1.0 + kz3)
    eps_bin = np.digitize(np.where(has_diffuse & np.isfinite(eps), eps, 1.0), PEREZ_EPSILON_EDGES)
    brightness = dhi_a * np.where(np.isfinite(am), am, 0.0) / _as_float(dni_extra)
    f11, f12, f13 = (PEREZ_F1[eps_bin, k] for k in range(3))
    f21, f22, f23 = (PEREZ_F2[eps_bin, k] for k in range(3))
    f1 = np.maximum(f11 + f12 * brightness + f13 * z, 0.0)
    f2 = f21 + f22 * brightness + f23 * z
    tilt = np.radians(_as_float(surface_tilt_deg))
    cos_aoi = np.maximum(np.cos(np.radians(_as_float(aoi_deg))), 0.0)
    iso = dhi_a * (1.0 - f1) * 0.5 * (1.0 + np.cos(tilt))
    circ = dhi_a * f1 * cos_aoi / np.maximum(np.cos(z), np.cos(np.radians(85.0)))
    hor = dhi_a * f2 * np.sin(tilt)
    total = np.maximum(iso + circ + hor, 0.0)
    keep = np.isfinite(am) & (total > 0.0)
    nan_in = np.isnan(total) | (has_diffuse & ~np.isfinite(eps))
    parts = [np.where(nan_in, np.nan, np.where(keep, p, 0.0)) for p in (total, iso, circ, hor)]
    return SkyDiffuse(*parts)


def facade_irradiance(
    *,
    dni: ArrayLike,
    dhi: ArrayLike,
    ghi: ArrayLike,
    zenith_deg: ArrayLike,
    azimuth_deg: ArrayLike,
    surface_azimuth_deg: ArrayLike,
    surface_tilt_deg: ArrayLike = 90.0,
    albedo: ArrayLike,
    dni_extra: ArrayLike,
    model: Literal["haydavies", "isotropic", "perez"] = "haydavies",
    airmass: ArrayLike | None = None,
) -> FacadeIrradiance:
    """Beam, sky-diffuse and ground-diffuse irradiance on a (façade) plane.

    Parameters
    ----------
    dni, dhi, ghi : array_like, [W/m2]
    zenith_deg, azimuth_deg : array_like, [deg]
        Sun position (apparent zenith in the pvlib reference; true zenith is fine).
    surface_azimuth_deg, surface_tilt_deg : array_like, [deg]
    albedo : array_like, [-]
        Ground reflectance ρ_g (default 0.2, docs/model.md#transposition).
    dni_extra : array_like, [W/m2]
    model : {"haydavies", "isotropic", "perez"}
        Sky-diffuse model; Hay–Davies is the lumped-model default (docs/model.md#transposition).
    airmass : array_like, optional, [-]
        Relative air mass for Perez; default :func:`relative_airmass` of ``zenith_deg``.

    Returns
    -------
    FacadeIrradiance
        beam, sky_diffuse, ground_diffuse [W/m2], aoi_deg, profile_deg [deg].
    """
    aoi, profile = incidence_and_profile(zenith_deg, azimuth_deg, surface_azimuth_deg,
                                         surface_tilt_deg=surface_tilt_deg)
    if model == "isotropic":
        sky = sky_diffuse_isotropic(dhi, surface_tilt_deg=surface_tilt_deg)
    elif model == "haydavies":
        sky = sky_diffuse_haydavies(dhi, dni, dni_extra, zenith_deg=zenith_deg, aoi_deg=aoi,
                                    surface_tilt_deg=surface_tilt_deg).total
    elif model == "perez":
        am = relative_airmass(zenith_deg) if airmass is None else airmass
        sky = sky_diffuse_perez(dhi, dni, dni_extra, am, zenith_deg=zenith_deg, aoi_deg=aoi,
                                surface_tilt_deg=surface_tilt_deg).total
    else:
        raise ValueError(f"unknown sky diffuse model {model!r}; "
                         "use 'haydavies', 'isotropic' or 'perez'")
    beam = beam_on_surface(dni, aoi)
    ground = ground_diffuse(ghi, albedo, surface_tilt_deg=surface_tilt_deg)
    beam, sky, ground, aoi, profile = np.broadcast_arrays(beam, sky, ground, aoi, profile)
    return FacadeIrradiance(beam, sky, ground, aoi, profile)
