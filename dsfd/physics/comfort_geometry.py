"""How much of an occupant's view the window fills: the view factor of a parallel rectangle.

Glare (the eye's vertical illuminance) and radiant asymmetry (the plane radiant temperature)
both need the view factor from a small plane facing the window, parallel to it, to the
window rectangle (docs/model.md#comfort-geometry).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["corner_view_factor", "window_view_factor"]

FloatArray = NDArray[np.float64]


def corner_view_factor(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """View factor from a plane element to a parallel rectangle above one of its corners [-].

    Parameters
    ----------
    a, b : array_like
        Rectangle sides divided by the distance between the planes [-], >= 0; the element's
        normal passes through one corner of the rectangle.

    Notes
    -----
    docs/model.md#comfort-geometry; J. R. Howell, *A Catalog of Radiation Heat Transfer
    Configuration Factors* ("plane element to a parallel rectangle, the element's normal
    through a corner"), the factor ISO 7726 uses for the plane radiant temperature::

        F = 1/(2 pi) [ a/sqrt(1+a^2) atan(b/sqrt(1+a^2)) + b/sqrt(1+b^2) atan(a/sqrt(1+b^2)) ]

    It tends to 1/4 for an infinite quadrant and is 0 when either side is 0.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    ra = np.sqrt(1.0 + a * a)
    rb = np.sqrt(1.0 + b * b)
    return (a / ra * np.arctan(b / ra) + b / rb * np.arctan(a / rb)) / (2.0 * np.pi)


def _signed_corner(x: FloatArray, z: FloatArray) -> FloatArray:
    return np.sign(x) * np.sign(z) * corner_view_factor(np.abs(x), np.abs(z))


def window_view_factor(
    *, distance_m: ArrayLike, width_m: float, height_m: float, lateral_m: ArrayLike,
    elevation_m: ArrayLike,
) -> FloatArray:
    """View factor from a plane element facing a window, parallel to it, to the window [-].

    Parameters
    ----------
    distance_m : array_like
        Distance of the element from the window plane [m], > 0.
    width_m, height_m : float
        Window size [m].
    lateral_m, elevation_m : array_like
        Position of the element's foot point on the window plane, from the window's lower
        left corner [m]; it may lie outside the window.

    Notes
    -----
    The rectangle [0, W] x [0, H] seen from the foot point (x0, z0) is a signed sum of four
    rectangles with a corner at the foot point (docs/model.md#comfort-geometry)::

        F = G(W - x0, H - z0) - G(-x0, H - z0) - G(W - x0, -z0) + G(-x0, -z0),
        G(x, z) = sign(x) sign(z) F_corner(|x|/d, |z|/d)
    """
    d = np.asarray(distance_m, dtype=float)
    x0 = np.asarray(lateral_m, dtype=float)
    z0 = np.asarray(elevation_m, dtype=float)
    xs = ((width_m - x0) / d, -x0 / d)
    zs = ((height_m - z0) / d, -z0 / d)
    return (_signed_corner(xs[0], zs[0]) - _signed_corner(xs[1], zs[0])
            - _signed_corner(xs[0], zs[1]) + _signed_corner(xs[1], zs[1]))
