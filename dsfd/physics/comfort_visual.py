"""Visual comfort from the model's own optics: direct sun, cut-off angle, glare (DGPs).

docs/model.md#visual-comfort. Angles follow docs/model.md#slat-cell: ``phi`` the slat angle
[rad] (+ when the outdoor-side tip is raised), ``profile`` the sun's profile angle [rad]
(+ when the ray descends).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.physics.optics import GlassTriple, LouverOptics, NoLouverOptics, layer_absorption
from dsfd.physics.optics_slat_cell import MAX_PROFILE

__all__ = [
    "DGP_INTERCEPT",
    "DGP_SLOPE_PER_LX",
    "EN17037_GLARE_CLASSES",
    "CutOff",
    "cutoff_angles",
    "dgp_simplified",
    "direct_sun_wm2",
    "dni_bound_wm2",
    "eye_illuminance_lx",
    "glare_class",
    "illuminance_for_dgp",
]

FloatArray = NDArray[np.float64]

#: Wienold (2009), simplified daylight glare probability DGPs = a E_v + b.
DGP_SLOPE_PER_LX = 6.22e-5
DGP_INTERCEPT = 0.184
#: EN 17037:2018, protection from glare: the DGP that its three levels allow to be exceeded in
#: no more than 5 % of the occupied time, best level first.
EN17037_GLARE_CLASSES: tuple[tuple[str, float], ...] = (
    ("high", 0.35), ("medium", 0.40), ("minimum", 0.45))


class CutOff(NamedTuple):
    """Slat angles [rad] at which flat slats just block the direct beam.

    The beam is blocked for ``phi <= lower`` and for ``phi >= upper``; ``lower`` is the
    cut-off that sun-tracking shading follows (slats tilted against the sun, the view out
    kept). NaN where no angle in [-pi/2, pi/2] on that side blocks it (slats narrower than
    the gap the beam sees).
    """

    lower: FloatArray
    upper: FloatArray


def cutoff_angles(profile: ArrayLike, *, width: float, pitch: float) -> CutOff:
    """Cut-off slat angles of flat, thin slats for a sun profile angle.

    Parameters
    ----------
    profile : array_like
        Profile angle [rad].
    width, pitch : float
        Slat width w and vertical pitch s [m].

    Notes
    -----
    docs/model.md#visual-comfort. A slat's shadow along the ray, projected on the vertical
    aperture, is w |sin(phi_s - phi)| / cos phi_s; the beam is blocked when it covers the
    pitch s (the zero of tau_bb, docs/model.md#slat-cell)::

        |sin(phi_s - phi)| >= (s/w) cos phi_s
        phi_lower = phi_s - asin((s/w) cos phi_s),   phi_upper = phi_s + asin((s/w) cos phi_s)
    """
    phi_s = np.clip(np.asarray(profile, dtype=float), -MAX_PROFILE, MAX_PROFILE)
    k = (pitch / width) * np.cos(phi_s)
    with np.errstate(invalid="ignore"):
        half = np.arcsin(np.where(k <= 1.0, k, np.nan))
    lower = phi_s - half
    upper = phi_s + half
    lower = np.where(lower >= -0.5 * np.pi, lower, np.nan)
    upper = np.where(upper <= 0.5 * np.pi, upper, np.nan)
    return CutOff(lower, upper)


def direct_sun_wm2(
    *, beam_wm2: ArrayLike, cos_aoi: ArrayLike, phi: ArrayLike, profile: ArrayLike,
    glass: tuple[GlassTriple, GlassTriple, GlassTriple],
    louver: LouverOptics | NoLouverOptics | None,
) -> FloatArray:
    """Solar beam passing the louver unscattered and the DGU into the room [W/m2 façade].

    Parameters
    ----------
    beam_wm2 : array_like
        Beam irradiance on the façade plane I_b,v [W/m2].
    cos_aoi, phi, profile : array_like
        Incidence cosine, slat angle [rad] and profile angle [rad].
    glass, louver :
        Solar-band pane triples and louver, as for :func:`dsfd.physics.optics.layer_absorption`.

    Notes
    -----
    docs/model.md#multilayer: T_DGU(theta) tau_bb(phi, phi_s) T_1(theta) I_b,v, the part of
    the beam that no slat scattered. The diffuse that the slats make of the rest is not
    "direct sun" (it counts in the glare instead).
    """
    return layer_absorption(beam=beam_wm2, diffuse=0.0, cos_aoi=cos_aoi, phi=phi,
                            profile=profile, glass=glass, louver=louver).transmitted_beam


def dni_bound_wm2(*, ghi_wm2: ArrayLike, zenith_deg: ArrayLike,
                  dni_extra_wm2: ArrayLike) -> FloatArray:
    """The largest direct normal irradiance a global horizontal reading allows [W/m2].

    Parameters
    ----------
    ghi_wm2 : array_like
        Global horizontal irradiance [W/m2] (negative readings count as 0).
    zenith_deg : array_like
        Solar zenith angle [deg].
    dni_extra_wm2 : array_like
        Extraterrestrial normal irradiance I0 [W/m2].

    Notes
    -----
    docs/model.md#direct-sun-bound. The closure GHI = DNI cos Z + DHI with DHI >= 0 gives
    DNI <= GHI / cos Z, and the atmosphere only attenuates the beam, DNI <= I0::

        DNI_max = min(I0, GHI / cos Z)     (0 with the sun at or below the horizon)

    Unlike a decomposition (Erbs gives no beam at all above Z = 87°,
    docs/model.md#decomposition), this is no estimate: the true beam never exceeds it.
    """
    cos_z = np.cos(np.radians(np.asarray(zenith_deg, dtype=float)))
    up = cos_z > 0.0
    ghi = np.clip(np.asarray(ghi_wm2, dtype=float), 0.0, None)
    ratio = ghi / np.where(up, cos_z, 1.0)
    return np.where(up, np.minimum(np.asarray(dni_extra_wm2, dtype=float), ratio), 0.0)


def eye_illuminance_lx(
    *, transmitted_wm2: ArrayLike, transmitted_beam_wm2: ArrayLike, view_factor: ArrayLike,
    luminous_efficacy_lmw: float,
) -> FloatArray:
    """Vertical illuminance at an occupant's eye facing the façade [lx].

    Parameters
    ----------
    transmitted_wm2, transmitted_beam_wm2 : array_like
        Visible-band irradiance transmitted into the room per m² façade, all and its
        unscattered beam part [W/m2] (``layer_absorption(...).transmitted`` and
        ``.transmitted_beam`` with the visible-band glass and louver).
    view_factor : array_like
        View factor from the eye's vertical plane to the window [-]
        (:func:`dsfd.physics.comfort_geometry.window_view_factor`).
    luminous_efficacy_lmw : float
        K [lm/W] (``daylight.luminous_efficacy_lmw``, as for Q_DA).

    Notes
    -----
    docs/model.md#visual-comfort: the scattered part leaves the inner pane as a uniform,
    Lambertian source of exitance K E_diffuse, so it gives K E_diffuse F at the eye; the beam
    is counted in full, as if the eye sat in the sun patch (the worst seat)::

        E_v = K [ E_beam + F (E_trans - E_beam) ]
    """
    beam = np.asarray(transmitted_beam_wm2, dtype=float)
    diffuse = np.asarray(transmitted_wm2, dtype=float) - beam
    return luminous_efficacy_lmw * (beam + np.asarray(view_factor, dtype=float) * diffuse)


def dgp_simplified(e_v_lx: ArrayLike) -> FloatArray:
    """Simplified daylight glare probability DGPs = 6.22e-5 E_v + 0.184 [-] (Wienold 2009).

    Capped at 1, a probability (the line passes 1 at 13 100 lx, far outside the range the
    formula was fitted on, which excludes the sun in view).
    """
    return np.minimum(DGP_SLOPE_PER_LX * np.asarray(e_v_lx, dtype=float) + DGP_INTERCEPT, 1.0)


def illuminance_for_dgp(dgp: ArrayLike) -> FloatArray:
    """The vertical eye illuminance [lx] at which DGPs reaches ``dgp`` (the inverse)."""
    return (np.asarray(dgp, dtype=float) - DGP_INTERCEPT) / DGP_SLOPE_PER_LX


def glare_class(dgp: float) -> str:
    """EN 17037 glare-protection class that a DGP meets: high, medium, minimum or none."""
    for name, limit in EN17037_GLARE_CLASSES:
        if dgp <= limit:
            return name
    return "none"
