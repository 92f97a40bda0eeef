"""Short-wave and long-wave properties of a venetian louver by the slat-cell method.

The louver is reduced to one periodic cell: two adjacent flat slats and two black, non-emitting
*fictitious* apertures spanning their tips (docs/model.md#slat-cell). Radiosity inside the cell is
solved with Hottel crossed-string view factors (:mod:`dsfd.physics.optics_slat_cell`); the
cell gives the layer properties that the multilayer balance (:mod:`dsfd.physics.optics`) and
the cavity long-wave exchange (:mod:`dsfd.physics.longwave`) use.

Conventions (docs/model.md#conventions, docs/model.md#slat-cell)
----------------------------------------------------------------
* ``phi`` [rad] is the slat angle: 0 horizontal, positive when the slat tip nearest the
  exterior glazing is raised (``phi = theta_E+ - pi/2`` with the EnergyPlus slat angle).
  Domain [-pi/2, pi/2]; the closed positions ±pi/2 are handled exactly.
* ``profile`` [rad] is the profile angle of a ray travelling from outdoors into the room,
  positive when it descends (sun above the horizon). It is clipped to
  ±(pi/2 - 1e-9) so that a grazing ray stays finite.
* x points from outdoors into the room, z up. The lower slat of the cell shows its **upper**
  face to the cell, the upper slat its **lower** face, hence separate ``reflectance_upper`` /
  ``reflectance_lower``.
* Properties for radiation travelling from the room outwards ("back side") are the same
  functions evaluated at ``-phi``: the mirror x -> -x keeps upper and lower faces.
* All properties are fractions of the power crossing the outer aperture of the cell, i.e. per
  m² of louver plane; they are dimensionless.

References
----------
EnergyPlus Engineering Reference, "Window Blinds" (slat-cell optics, ISO 15099 comparison);
ISO 15099:2003 §7; H. C. Hottel, A. F. Sarofim, *Radiative Transfer* (crossed strings).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dsfd.physics.optics_slat_cell import (
    MAX_PROFILE,
    cell_response,
    direct_transmittance,
    hit_fractions,
    slat_cell_hit_fractions,
    slat_cell_view_factors,
)

if TYPE_CHECKING:
    from dsfd.config.panel import Louver

__all__ = [
    "NO_LOUVER",
    "LouverOptics",
    "NoLouverOptics",
    "SlatBeam",
    "SlatDiffuse",
    "SlatInfrared",
    "SlatSkyGround",
    "direct_transmittance",
    "slat_beam",
    "slat_cell_hit_fractions",
    "slat_cell_view_factors",
    "slat_diffuse",
    "slat_infrared",
    "slat_sky_ground",
]

FloatArray = NDArray[np.float64]


class SlatBeam(NamedTuple):
    """Beam (direct) properties of the louver layer [-]; fields share one broadcast shape."""

    tau_bb: FloatArray  #: beam transmitted undeviated
    tau_bd: FloatArray  #: beam transmitted as diffuse
    rho_bd: FloatArray  #: beam reflected (diffusely) back outwards
    alpha_b: FloatArray  #: beam absorbed by the slats


class SlatDiffuse(NamedTuple):
    """Hemispherical (uniformly diffuse) properties of the louver layer [-]."""

    tau_dd: FloatArray  #: diffuse transmitted
    rho_dd: FloatArray  #: diffuse reflected
    alpha_d: FloatArray  #: diffuse absorbed


class SlatInfrared(NamedTuple):
    """Long-wave properties of the louver as an equivalent grey layer [-]."""

    eps_L: FloatArray  #: effective hemispherical emissivity (= absorptance)
    tau_L: FloatArray  #: effective IR transmittance
    rho_L: FloatArray  #: effective IR reflectance, 1 - eps_L - tau_L


class SlatSkyGround(NamedTuple):
    """Properties for sky diffuse (from above) and ground diffuse (from below) [-]."""

    tau_sky: FloatArray  #: sky diffuse transmitted (beam + diffuse parts)
    rho_sky: FloatArray  #: sky diffuse reflected
    alpha_sky: FloatArray  #: sky diffuse absorbed
    tau_gnd: FloatArray  #: ground diffuse transmitted
    rho_gnd: FloatArray  #: ground diffuse reflected
    alpha_gnd: FloatArray  #: ground diffuse absorbed


def _edge_fraction_beam(
    phi: FloatArray, profile: FloatArray, pitch: float, thickness: float
) -> FloatArray:
    # Projected height of the edge face facing the ray, per slat pitch (docs/model.md#slat-cell).
    edge = thickness * np.abs(np.cos(phi - profile)) / (pitch * np.cos(profile))
    return np.minimum(edge, 1.0)


def _check_thickness(thickness: float, pitch: float) -> None:
    if not 0.0 <= thickness < pitch:
        raise ValueError(f"slat thickness {thickness} must lie in [0, pitch={pitch})")


def slat_beam(
    phi: ArrayLike,
    profile: ArrayLike,
    *,
    width: float,
    pitch: float,
    reflectance_upper: float,
    reflectance_lower: float,
    segments: int = 5,
    thickness: float = 0.0,
    cache: bool = True,
) -> SlatBeam:
    """Beam properties of the louver for a ray entering from the outdoor side.

    Parameters
    ----------
    phi : array_like
        Slat angle [rad], 0 horizontal, + towards the sky. Use ``-phi`` for the room side.
    profile : array_like
        Profile angle of the ray [rad], + descending. Broadcast with ``phi``; for speed give
        ``phi`` the shape ``(n_phi, 1)`` and ``profile`` ``(n_steps,)``: the cell is then
        solved once per slat angle.
    width, pitch : float
        Slat width w and vertical pitch s [m].
    reflectance_upper, reflectance_lower : float
        Diffuse reflectance of the upper and lower slat faces [-], < 1. Slat transmittance 0.
    segments : int, default 5
        Segments per slat M (5 lumped model, 10 truth plant).
    thickness : float, default 0.0
        Slat thickness t [m] for the optional edge correction; 0 switches it off.
    cache : bool, default True
        Reuse the per-phi cell solution for repeated phi arrays (≤ 512 elements).

    Returns
    -------
    SlatBeam
        ``tau_bb, tau_bd, rho_bd, alpha_b`` [-], each of shape ``broadcast(phi, profile)``;
        they sum to 1.

    Notes
    -----
    docs/model.md#slat-cell. Powers per unit slat length, normalised by the aperture power:
    the beam first strikes segment k with fraction f_k (:func:`slat_cell_hit_fractions`),
    ``tau_bb = f_inner``. The reflected powers R of the 2M slat segments satisfy

        R = diag(rho) (f + F_ss^T R)

    and ``tau_bd = sum_j R_j F_j1``, ``rho_bd = sum_j R_j F_j0``,
    ``alpha_b = sum_k (1 - rho_k) G_k`` with ``G = f + F_ss^T R``. The linear functionals
    are evaluated through the adjoint system (one batched ``np.linalg.solve`` per phi).

    Edge correction (docs/model.md#slat-cell, EnergyPlus ER "Window Blinds"): the edge face of
    thickness t intercepts ``f_e = min(1, t |cos(phi - phi_s)| / (s cos phi_s))`` of the beam and
    reflects it outwards with the mean slat reflectance rho_e; then ``tau -> tau (1 - f_e)``,
    ``rho_bd -> rho_bd (1 - f_e) + f_e rho_e``, ``alpha_b -> alpha_b (1 - f_e) + f_e (1 - rho_e)``.
    """
    phi = np.asarray(phi, dtype=float)
    profile = np.clip(np.asarray(profile, dtype=float), -MAX_PROFILE, MAX_PROFILE)
    _check_thickness(thickness, pitch)
    resp = cell_response(phi, width, pitch, reflectance_upper, reflectance_lower, segments,
                         cache=cache)
    tau_bb, slat_hits = hit_fractions(resp.cell, phi, profile, pitch)
    # fate (..., 3, 2M) @ hits (..., 2M, 1): (to room, to outdoors, absorbed) in one product.
    split = (resp.fate @ slat_hits[..., None])[..., 0]
    tau_bd, rho_bd, alpha_b = split[..., 0], split[..., 1], split[..., 2]
    if thickness > 0.0:
        edge = _edge_fraction_beam(phi, profile, pitch, thickness)
        rho_edge = 0.5 * (reflectance_upper + reflectance_lower)
        keep = 1.0 - edge
        tau_bb, tau_bd = tau_bb * keep, tau_bd * keep
        rho_bd = rho_bd * keep + edge * rho_edge
        alpha_b = alpha_b * keep + edge * (1.0 - rho_edge)
    return SlatBeam(tau_bb, tau_bd, rho_bd, alpha_b)


def slat_diffuse(
    phi: ArrayLike,
    *,
    width: float,
    pitch: float,
    reflectance_upper: float,
    reflectance_lower: float,
    segments: int = 5,
    thickness: float = 0.0,
    cache: bool = True,
) -> SlatDiffuse:
    """Hemispherical (uniformly diffuse) properties of the louver, outdoor side incident.

    Parameters
    ----------
    phi : array_like
        Slat angle [rad]; ``-phi`` gives the room-side properties.
    width, pitch, reflectance_upper, reflectance_lower, segments, thickness, cache
        As for :func:`slat_beam`.

    Returns
    -------
    SlatDiffuse
        ``tau_dd, rho_dd, alpha_d`` [-], shape of ``phi``; they sum to 1.

    Notes
    -----
    docs/model.md#slat-cell: the outer aperture emits the incident diffuse power uniformly
    (R_0 = s), so the first-strike fractions are the view factors F_0k and

        tau_dd = F_01 + sum_j R_j F_j1,   rho_dd = sum_j R_j F_j0,
        alpha_d = sum_k (1 - rho_k) G_k.

    ``tau_dd`` is even in phi (reciprocity); ``rho_dd`` and ``alpha_d`` are even only for
    equal face reflectances. Edge correction (docs/model.md#slat-cell): the unclipped beam edge
    fraction averaged over the 2-D Lambertian aperture, ``(1/2) ∫ f_e cos(phi_s) dphi_s`` over
    [-pi/2, pi/2], equals ``t / s`` for every phi.
    """
    phi = np.asarray(phi, dtype=float)
    _check_thickness(thickness, pitch)
    resp = cell_response(phi, width, pitch, reflectance_upper, reflectance_lower, segments,
                         cache=cache)
    tau_dd, rho_dd, alpha_d = (resp.diffuse[..., i].copy() for i in range(3))
    if thickness > 0.0:
        edge = thickness / pitch
        rho_edge = 0.5 * (reflectance_upper + reflectance_lower)
        tau_dd = tau_dd * (1.0 - edge)
        rho_dd = rho_dd * (1.0 - edge) + edge * rho_edge
        alpha_d = alpha_d * (1.0 - edge) + edge * (1.0 - rho_edge)
    return SlatDiffuse(tau_dd, rho_dd, alpha_d)


def slat_infrared(
    phi: ArrayLike,
    *,
    width: float,
    pitch: float,
    emissivity: float,
    segments: int = 5,
    thickness: float = 0.0,
    cache: bool = True,
) -> SlatInfrared:
    """Long-wave properties of the louver layer (opaque grey slats, both faces alike).

    Parameters
    ----------
    phi : array_like
        Slat angle [rad].
    width, pitch : float
        Slat width and vertical pitch [m].
    emissivity : float
        Hemispherical IR emissivity of the slat faces [-], in (0, 1].
    segments, thickness, cache
        As for :func:`slat_beam`.

    Returns
    -------
    SlatInfrared
        ``eps_L, tau_L, rho_L`` [-], shape of ``phi``; even in phi, same from both sides.

    Notes
    -----
    docs/model.md#slat-cell: the diffuse case with rho_k = 1 - eps_slat and slat IR transmittance 0
    (EnergyPlus ER: the diffuse-to-diffuse calculation is repeated for the IR band);
    ``eps_L = alpha_d``, ``tau_L = tau_dd``, ``rho_L = rho_dd``.
    """
    rho = 1.0 - emissivity
    d = slat_diffuse(phi, width=width, pitch=pitch, reflectance_upper=rho,
                     reflectance_lower=rho, segments=segments, thickness=thickness, cache=cache)
    return SlatInfrared(d.alpha_d, d.tau_dd, d.rho_dd)


@lru_cache(maxsize=8)
def _profile_quadrature(n: int) -> tuple[FloatArray, FloatArray]:
    nodes, weights = np.polynomial.legendre.leggauss(n)
    profile = 0.25 * np.pi * (nodes + 1.0)  # map [-1, 1] -> [0, pi/2]
    weights = weights * np.cos(profile)
    return profile, weights / weights.sum()  # exact normalisation: ∫ cos = 1


def slat_sky_ground(
    phi: ArrayLike,
    *,
    width: float,
    pitch: float,
    reflectance_upper: float,
    reflectance_lower: float,
    segments: int = 5,
    thickness: float = 0.0,
    n_profile: int = 64,
) -> SlatSkyGround:
    """Louver properties for diffuse light from the sky and from the ground separately.

    Parameters
    ----------
    phi : array_like
        Slat angle [rad].
    width, pitch, reflectance_upper, reflectance_lower, segments, thickness
        As for :func:`slat_beam`.
    n_profile : int, default 64
        Gauss–Legendre nodes over each profile half-range.

    Returns
    -------
    SlatSkyGround
        ``tau_sky, rho_sky, alpha_sky, tau_gnd, rho_gnd, alpha_gnd`` [-], shape of ``phi``.
        Each triple sums to 1, and ``(x_sky + x_gnd) / 2`` tends to the uniform diffuse
        value of :func:`slat_diffuse` as ``n_profile`` grows.

    Notes
    -----
    docs/model.md#slat-cell (EnergyPlus ER "Window Blinds")::

        tau_sky = ∫_0^{pi/2} [tau_bb + tau_bd](phi, phi_s) cos(phi_s) dphi_s
        tau_gnd = the same over phi_s in [-pi/2, 0]

    ``rho`` and ``alpha`` likewise. The weights are normalised so ∫ cos = 1 exactly. The
    integrand has kinks where slat tips shadow each other, so the quadrature converges only
    algebraically: 64 nodes agree with the uniform diffuse values to about 1e-4. Meant for the
    truth plant and for tabulation.
    """
    phi = np.asarray(phi, dtype=float)
    profile, weights = _profile_quadrature(n_profile)
    kwargs = dict(width=width, pitch=pitch, reflectance_upper=reflectance_upper,
                  reflectance_lower=reflectance_lower, segments=segments, thickness=thickness,
                  cache=False)
    out = []
    for sign in (1.0, -1.0):
        b = slat_beam(phi[..., None], sign * profile, **kwargs)
        out += [(b.tau_bb + b.tau_bd) @ weights, b.rho_bd @ weights, b.alpha_b @ weights]
    return SlatSkyGround(*out)


# ------------------------------------------------------------------------------------------
# Layer objects used by the multilayer balance
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class LouverOptics:
    """Optical description of one louver in one band; hashable, so cheap to cache.

    Attributes
    ----------
    width, pitch : float
        Slat width w and vertical pitch s [m].
    reflectance_upper, reflectance_lower : float
        Diffuse reflectance of the upper / lower slat faces in this band [-].
    emissivity : float
        IR emissivity of the slat faces [-] (used by :meth:`infrared` only).
    segments : int
        Segments per slat (5 lumped model, 10 truth plant).
    thickness : float
        Slat thickness for the edge correction [m]; 0 (default) switches it off.

    Examples
    --------
    >>> lv = LouverOptics(width=0.05, pitch=0.045, reflectance_upper=0.07,
    ...                   reflectance_lower=0.07)
    >>> float(lv.beam(0.0, 0.0).tau_bb)
    1.0
    """

    width: float
    pitch: float
    reflectance_upper: float
    reflectance_lower: float
    emissivity: float = 0.9
    segments: int = 5
    thickness: float = 0.0

    @classmethod
    def from_config(
        cls,
        louver: Louver,
        *,
        band: Literal["solar", "visible"] = "solar",
        segments: int | None = None,
        edge_correction: bool = False,
    ) -> LouverOptics:
        """Build from the panel's :class:`dsfd.config.panel.Louver` for one band."""
        return cls(
            width=louver.slat_width_m,
            pitch=louver.slat_pitch_m,
            reflectance_upper=getattr(louver, f"{band}_reflectance_upper"),
            reflectance_lower=getattr(louver, f"{band}_reflectance_lower"),
            emissivity=louver.emissivity,
            segments=louver.segments if segments is None else segments,
            thickness=louver.slat_thickness_m if edge_correction else 0.0,
        )

    def _kwargs(self) -> dict[str, float | int]:
        return dict(width=self.width, pitch=self.pitch,
                    reflectance_upper=self.reflectance_upper,
                    reflectance_lower=self.reflectance_lower,
                    segments=self.segments, thickness=self.thickness)

    def beam(self, phi: ArrayLike, profile: ArrayLike) -> SlatBeam:
        """:func:`slat_beam` with this louver's data."""
        return slat_beam(phi, profile, **self._kwargs())

    def diffuse(self, phi: ArrayLike) -> SlatDiffuse:
        """:func:`slat_diffuse` with this louver's data (``-phi`` for the room side)."""
        return slat_diffuse(phi, **self._kwargs())

    def infrared(self, phi: ArrayLike) -> SlatInfrared:
        """:func:`slat_infrared` with this louver's geometry and emissivity."""
        return slat_infrared(phi, width=self.width, pitch=self.pitch,
                             emissivity=self.emissivity, segments=self.segments,
                             thickness=self.thickness)

    def sky_ground(self, phi: ArrayLike, *, n_profile: int = 64) -> SlatSkyGround:
        """:func:`slat_sky_ground` with this louver's data."""
        return slat_sky_ground(phi, n_profile=n_profile, **self._kwargs())


class NoLouverOptics:
    """Stand-in for a panel without a louver: a perfectly transparent, inert layer.

    Same methods as :class:`LouverOptics`: beam ``tau_bb = 1`` (everything else 0), diffuse
    ``tau_dd = 1``, IR ``tau_L = 1, eps_L = 0``. Shapes follow the inputs.
    """

    def beam(self, phi: ArrayLike, profile: ArrayLike) -> SlatBeam:
        one = np.ones(np.broadcast_shapes(np.shape(phi), np.shape(profile)))
        zero = np.zeros_like(one)
        return SlatBeam(one, zero, zero, zero)

    def diffuse(self, phi: ArrayLike) -> SlatDiffuse:
        one = np.ones(np.shape(phi))
        return SlatDiffuse(one, np.zeros_like(one), np.zeros_like(one))

    def infrared(self, phi: ArrayLike) -> SlatInfrared:
        one = np.ones(np.shape(phi))
        return SlatInfrared(np.zeros_like(one), one, np.zeros_like(one))

    def sky_ground(self, phi: ArrayLike, *, n_profile: int = 64) -> SlatSkyGround:
        one = np.ones(np.shape(phi))
        zero = np.zeros_like(one)
        return SlatSkyGround(one, zero, zero, one, zero, zero)

    def __repr__(self) -> str:
        return "NO_LOUVER"


#: The louver of a panel that has none.
NO_LOUVER = NoLouverOptics()
