"""Slat-cell geometry, crossed-string view factors, beam hit fractions and radiosity response.

The core of the louver optics of docs/model.md#slat-cell; the layer properties built on it
are in :mod:`dsfd.physics.optics_louver`. Angle conventions are documented there:
``phi`` slat angle [rad] (0 horizontal, + when the outdoor-side tip is raised),
``profile`` profile angle of a ray entering from outdoors [rad] (+ descending).

Cell (docs/model.md#slat-cell), with c_w = (w/2) cos phi, a_w = (w/2) sin phi and slat centres on
x = 0::

    lower slat: outer tip Lo = (-c_w, a_w)       inner tip Li = (c_w, -a_w)
    upper slat: outer tip Uo = (-c_w, s + a_w)   inner tip Ui = (c_w, s - a_w)

Segment order everywhere: 0 outer aperture (Uo -> Lo), 1 inner aperture (Li -> Ui),
2..M+1 lower slat (Lo -> Li, its upper face looks into the cell), M+2..2M+1 upper slat
(Uo -> Ui, its lower face looks into the cell).
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "MAX_PROFILE",
    "direct_transmittance",
    "slat_cell_hit_fractions",
    "slat_cell_view_factors",
]

FloatArray = NDArray[np.float64]

#: Largest |profile angle| used [rad]; keeps tan() and 1/cos() finite for grazing rays.
MAX_PROFILE = 0.5 * np.pi - 1e-9

#: +1 for the lower slat (struck when its projection rises), -1 for the upper slat.
_EXIT_SIGN = np.array([[1.0], [-1.0]])

#: Cell responses are cached for phi arrays up to this size (the controller's angle grid).
_CACHE_MAX_SIZE = 512


class Cell(NamedTuple):
    """Geometry of the slat cell for an array of slat angles (shapes ``phi.shape + ...``)."""

    z_points: FloatArray  # (..., 2, M+1): z of the lower / upper slat points, outer -> inner tip
    depth: FloatArray  # (..., M+1): x of those points measured from the outer aperture
    x_start: FloatArray  # (..., N) segment start points, N = 2M + 2
    z_start: FloatArray
    x_end: FloatArray  # (..., N) segment end points
    z_end: FloatArray
    length: FloatArray  # (N,) segment lengths [m]


def make_cell(phi: FloatArray, width: float, pitch: float, segments: int) -> Cell:
    """Boundary of the slat cell for slat angles ``phi`` [rad]."""
    half_depth = np.asarray(0.5 * width * np.cos(phi))
    half_rise = np.asarray(0.5 * width * np.sin(phi))
    t = np.linspace(0.0, 1.0, segments + 1)
    # One set of points per slat, shared by adjacent segments, so that the projected beam
    # intervals tile the aperture exactly (closure to round-off).
    x_slat = half_depth[..., None] * (2.0 * t - 1.0)
    z_low = half_rise[..., None] * (1.0 - 2.0 * t)
    z_up = pitch + z_low
    x_start = np.concatenate(
        [x_slat[..., :1], x_slat[..., -1:], x_slat[..., :-1], x_slat[..., :-1]], axis=-1
    )
    z_start = np.concatenate(
        [z_up[..., :1], z_low[..., -1:], z_low[..., :-1], z_up[..., :-1]], axis=-1
    )
    x_end = np.concatenate(
        [x_slat[..., :1], x_slat[..., -1:], x_slat[..., 1:], x_slat[..., 1:]], axis=-1
    )
    z_end = np.concatenate([z_low[..., :1], z_up[..., -1:], z_low[..., 1:], z_up[..., 1:]],
                           axis=-1)
    length = np.concatenate([np.full(2, float(pitch)), np.full(2 * segments, width / segments)])
    return Cell(np.stack([z_low, z_up], axis=-2), half_depth[..., None] * (2.0 * t),
                x_start, z_start, x_end, z_end, length)


def crossed_strings(cell: Cell) -> FloatArray:
    """View-factor matrix ``F[..., i, j]`` of the cell boundary (Hottel crossed strings)."""

    def dist(xa: FloatArray, za: FloatArray, xb: FloatArray, zb: FloatArray) -> FloatArray:
        return np.hypot(xa[..., :, None] - xb[..., None, :], za[..., :, None] - zb[..., None, :])

    xs, zs, xe, ze = cell.x_start, cell.z_start, cell.x_end, cell.z_end
    crossed_minus_uncrossed = (
        dist(xs, zs, xs, zs) + dist(xe, ze, xe, ze) - dist(xs, zs, xe, ze) - dist(xe, ze, xs, zs)
    )
    view = np.abs(crossed_minus_uncrossed) / (2.0 * cell.length[:, None])
    n = view.shape[-1]
    view[..., np.arange(n), np.arange(n)] = 0.0  # the formula gives 1 on the diagonal
    return view


def hit_fractions(
    cell: Cell, phi: FloatArray, profile: FloatArray, pitch: float
) -> tuple[FloatArray, FloatArray]:
    """First-strike fractions of a unit beam: ``(tau_bb, slat)``, slat of shape (..., 2M).

    ``profile`` must already be clipped to ±MAX_PROFILE.
    """
    tan_profile = np.tan(profile)[..., None, None]
    # Back-project the slat points along the ray onto the outer aperture plane x = -c_w and
    # clip them to the aperture [z(Lo), z(Uo)] = [a_w, s + a_w]. Along each slat the
    # projection is linear, so the clipped differences are the clipped segment intervals.
    z_ap = cell.z_points + cell.depth[..., None, :] * tan_profile
    bottom = cell.z_points[..., :1, :1]  # Lo
    top = cell.z_points[..., 1:, :1]  # Uo
    z_clip = np.minimum(np.maximum(z_ap, bottom), top)
    # Exit-side segments (outward normal . ray > 0) are struck first: the lower slat when
    # phi_s > phi, i.e. when its projection rises from Lo to Li; the upper slat when its
    # projection falls from Uo to Ui. The chain Lo..Li, Li->Ui, Ui..Uo then tiles the aperture
    # exactly; the other slat's projection lies outside the aperture and clips to zero length.
    rise = np.diff(z_clip, axis=-1) * _EXIT_SIGN
    slat = np.maximum(rise, 0.0) / pitch
    tau_bb = (z_clip[..., 1, -1] - z_clip[..., 0, -1]) / pitch  # inner aperture Li -> Ui
    return tau_bb, slat.reshape((*slat.shape[:-2], -1))


class Response(NamedTuple):
    """Per-phi cell response.

    ``fate[..., :, k]`` = (to room, to outdoors, absorbed) of a unit power first striking
    slat segment k, after all inter-reflections; the three sum to 1. ``diffuse`` is
    (tau_dd, rho_dd, alpha_d) for uniformly diffuse incidence on the outer aperture.
    """

    cell: Cell
    fate: FloatArray  # (..., 3, 2M)
    diffuse: FloatArray  # (..., 3)


def _solve_response(
    phi: FloatArray, width: float, pitch: float, rho_upper: float, rho_lower: float,
    segments: int,
) -> Response:
    cell = make_cell(phi, width, pitch, segments)
    view = crossed_strings(cell)
    rho = np.repeat([rho_upper, rho_lower], segments)  # the lower slat shows its upper face
    f_ss = view[..., 2:, 2:]
    # Radiosity of slat segments for first-strike powers P (docs/model.md#slat-cell):
    #   R = rho * (P + F_ss^T R)  =>  R = (I - diag(rho) F_ss^T)^-1 diag(rho) P.
    # Every output is a linear functional c.R, so solve the adjoint system once per phi:
    #   c.R = (rho * Y)^T P   with   (I - F_ss diag(rho)) Y = c,
    # for c = F_s1 (to room), F_s0 (to outdoors), F_ss (1 - rho) (absorbed after reflection).
    adjoint = np.eye(2 * segments) - f_ss * rho
    targets = np.stack([view[..., 2:, 1], view[..., 2:, 0], f_ss @ (1.0 - rho)], axis=-1)
    y = np.linalg.solve(adjoint, targets)
    fate = rho[:, None] * y
    fate[..., 2] += 1.0 - rho  # absorbed at the first strike
    fate = np.swapaxes(fate, -1, -2)
    # Diffuse incidence: the outer aperture emits uniformly, first strikes are F_0k.
    diffuse = np.einsum("...jk,...k->...j", fate, view[..., 0, 2:])
    diffuse[..., 0] += view[..., 0, 1]  # straight through aperture to aperture
    return Response(cell, fate, diffuse)


def _frozen_response(
    phi_bytes: bytes, shape: tuple[int, ...], width: float, pitch: float, rho_upper: float,
    rho_lower: float, segments: int,
) -> Response:
    phi = np.frombuffer(phi_bytes, dtype=float).reshape(shape)
    out = _solve_response(phi, width, pitch, rho_upper, rho_lower, segments)
    for array in (*out.cell, out.fate, out.diffuse):
        array.flags.writeable = False  # shared between calls
    return out


# Angle grids (the controller's 11 positions, a few entries reused every decision) and single
# angles (a continuous search such as paper-SQP: hundreds of new ones per decision) are cached
# apart, so that a continuous search cannot evict the grid.
_cached_grid = lru_cache(maxsize=64)(_frozen_response)
_cached_single = lru_cache(maxsize=256)(_frozen_response)


def cell_response(
    phi: FloatArray, width: float, pitch: float, rho_upper: float, rho_lower: float,
    segments: int, *, cache: bool = True,
) -> Response:
    """Solve (or fetch from the cache) the cell radiosity response for slat angles ``phi``.

    Repeated angles are solved once: a record's per-row louver angles (the calibration window,
    a measured file) hold a few grid positions many times, and are answered from the
    response of their distinct values — which is also what is cached, so that a window that
    slides every update does not fill the cache with responses of sequences never seen again.
    """
    if phi.size > 1:
        distinct, inverse = np.unique(phi.ravel(), return_inverse=True)
        if distinct.size < phi.size:
            once = cell_response(distinct, width, pitch, rho_upper, rho_lower, segments,
                                 cache=cache)
            return _expanded(once, inverse, phi.shape)
    if cache and phi.size <= _CACHE_MAX_SIZE:
        key = np.ascontiguousarray(phi.ravel(), dtype=float)  # ravel: keep 0-d via phi.shape
        cached = _cached_grid if phi.size > 1 else _cached_single
        return cached(key.tobytes(), phi.shape, float(width), float(pitch), float(rho_upper),
                      float(rho_lower), int(segments))
    return _solve_response(phi, width, pitch, rho_upper, rho_lower, segments)


def _expanded(resp: Response, index: np.ndarray, shape: tuple[int, ...]) -> Response:
    """``resp`` (for distinct angles) at the angles ``distinct[index]``, shaped ``shape``."""

    def take(a: FloatArray) -> FloatArray:
        return a[index].reshape(*shape, *a.shape[1:])

    cell = resp.cell._replace(**{name: take(getattr(resp.cell, name))
                                 for name in Cell._fields if name != "length"})
    return Response(cell, take(resp.fate), take(resp.diffuse))


def slat_cell_view_factors(
    phi: ArrayLike, *, width: float, pitch: float, segments: int = 5
) -> FloatArray:
    """View factors between the boundary segments of the slat cell.

    Parameters
    ----------
    phi : array_like
        Slat angle [rad], any shape.
    width, pitch : float
        Slat width w and vertical slat pitch s [m].
    segments : int, default 5
        Segments M per slat (ISO 15099: 5).

    Returns
    -------
    ndarray, shape ``phi.shape + (2M + 2, 2M + 2)``
        ``F[..., i, j]``, fraction of the diffuse power leaving segment i that reaches j [-],
        in the segment order of the module docstring.

    Notes
    -----
    Hottel's crossed strings for segments i = AB and j = CD of a convex enclosure
    (docs/model.md#slat-cell)::

        F_ij = |(|AC| + |BD|) - (|AD| + |BC|)| / (2 |AB|),   F_ii = 0

    Rows sum to 1 and ``L_i F_ij = L_j F_ji``. At phi = ±pi/2 the cell collapses onto a line:
    collinear end-to-end segments give 0 and overlapping ones their overlap fraction, which is
    the limit of the thin parallelogram, so the closed louver needs no special case.
    """
    return crossed_strings(make_cell(np.asarray(phi, dtype=float), width, pitch, segments))


def slat_cell_hit_fractions(
    phi: ArrayLike, profile: ArrayLike, *, width: float, pitch: float, segments: int = 5
) -> FloatArray:
    """Fractions of a unit beam entering the outer aperture that first strike each segment.

    Parameters
    ----------
    phi, profile : array_like
        Slat angle and profile angle [rad], broadcast together.
    width, pitch : float
        Slat width and vertical pitch [m].
    segments : int, default 5
        Segments per slat.

    Returns
    -------
    ndarray, shape ``broadcast(phi, profile).shape + (2M + 2,)``
        Segment order of :func:`slat_cell_view_factors`; entry 0 (the entry aperture) is 0,
        entry 1 is ``tau_bb``; the entries sum to 1.

    Notes
    -----
    docs/model.md#slat-cell: with ray direction d = (cos phi_s, -sin phi_s), the end points P of
    every exit-side segment are projected back onto the aperture line,
    ``z_ap(P) = P_z + (P_x + c_w) tan phi_s``, and the interval is clipped to the aperture
    ``[a_w, s + a_w]``.
    """
    phi = np.asarray(phi, dtype=float)
    profile = np.clip(np.asarray(profile, dtype=float), -MAX_PROFILE, MAX_PROFILE)
    tau_bb, slat = hit_fractions(make_cell(phi, width, pitch, segments), phi, profile, pitch)
    return np.concatenate([np.zeros_like(tau_bb)[..., None], tau_bb[..., None], slat], axis=-1)


def direct_transmittance(
    phi: ArrayLike, profile: ArrayLike, *, width: float, pitch: float
) -> FloatArray:
    """Beam-to-beam transmittance of flat zero-thickness slats [-].

    Parameters
    ----------
    phi, profile : array_like
        Slat angle and profile angle [rad], broadcast together.
    width, pitch : float
        Slat width w and vertical pitch s [m].

    Returns
    -------
    ndarray
        ``tau_bb`` in [0, 1], broadcast shape of the inputs.

    Notes
    -----
    docs/model.md#slat-cell (EnergyPlus ER "Window Blinds", in this document's angle convention)::

        tau_bb = max(0, 1 - (w/s) |sin(phi_s - phi)| / cos(phi_s))

    It equals the fraction of the outer aperture whose rays reach the inner aperture, which
    :func:`slat_cell_hit_fractions` computes geometrically.
    """
    phi = np.asarray(phi, dtype=float)
    profile = np.clip(np.asarray(profile, dtype=float), -MAX_PROFILE, MAX_PROFILE)
    blocked = (width / pitch) * np.abs(np.sin(profile - phi)) / np.cos(profile)
    return np.maximum(0.0, 1.0 - blocked)
