"""Angular and hemispherical solar properties of glass panes and of the interior DGU.

Pure functions over numpy arrays (docs/model.md#glass-optics). "Front" faces outdoors. All
properties are dimensionless fractions of the incident power; angles are given as
``cos_aoi``, the cosine of the angle of incidence on the pane [-].

References
----------
EnergyPlus Engineering Reference, "Window Calculation Module — Angular Properties for Coated
Glass" (curve sets and hemispherical averaging); ISO 15099:2003 §6 (multiple reflections in a
specular layer pair).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "DGUBeam",
    "GlassAngular",
    "dgu_beam",
    "glass_angular",
    "glass_hemispherical",
]

FloatArray = NDArray[np.float64]

# Polynomial coefficients in cos θ, lowest order first (EnergyPlus ER, coated glass).
_T_CLEAR = np.array([-0.0015, 3.355, -3.840, 1.460, 0.0288])
_R_CLEAR = np.array([0.999, -0.563, 2.043, -2.532, 1.054])
_T_BRONZE = np.array([-0.002, 2.813, -2.341, -0.05725, 0.599])
_R_BRONZE = np.array([0.997, -1.868, 6.513, -7.862, 3.225])
_EXPONENTS = np.arange(5)
#: Normal-incidence transmittance above which the "clr" curve set is used.
CLEAR_CURVE_THRESHOLD = 0.645


def _hemispherical_weights() -> tuple[FloatArray, FloatArray]:
    """Quadrature nodes θ = 0°, 10°, …, 90° and weights for 2∫ P cosθ sinθ dθ."""
    theta = np.radians(np.arange(0.0, 91.0, 10.0))
    h = np.radians(10.0)
    # Nine intervals: composite Simpson 1/3 on 0–60° and Simpson 3/8 on 60–90°.
    weights = np.zeros(theta.size)
    weights[:7] += h / 3.0 * np.array([1, 4, 2, 4, 2, 4, 1])
    weights[6:] += 3.0 * h / 8.0 * np.array([1, 3, 3, 1])
    weights *= np.sin(2.0 * theta)
    # The rule integrates sin 2θ to 1.00011; normalising makes a constant property map to
    # itself, so T + R + A = 1 also holds for the separately integrated hemispherical values.
    return np.cos(theta), weights / weights.sum()


_HEMI_COS, _HEMI_WEIGHTS = _hemispherical_weights()


class GlassAngular(NamedTuple):
    """Solar properties of one pane [-]; ``T + R_x + A_x = 1`` for x = f, b."""

    T: FloatArray  #: transmittance (same both ways)
    R_f: FloatArray  #: reflectance, front (outdoor) side incident
    R_b: FloatArray  #: reflectance, back (room) side incident
    A_f: FloatArray  #: absorptance, front side incident
    A_b: FloatArray  #: absorptance, back side incident


class DGUBeam(NamedTuple):
    """Beam properties of the DGU (L2 + L3) for incidence from the cavity side [-]."""

    T: FloatArray  #: transmitted to the room
    R_f: FloatArray  #: reflected back into the cavity
    A_2: FloatArray  #: absorbed in L2 (cavity-side pane)
    A_3: FloatArray  #: absorbed in L3 (room-side pane)


def glass_angular(
    T0: ArrayLike, R_f0: ArrayLike, R_b0: ArrayLike, cos_aoi: ArrayLike
) -> GlassAngular:
    """Angular solar properties of a (coated) glass pane.

    Parameters
    ----------
    T0, R_f0, R_b0 : array_like
        Transmittance and front/back reflectance at normal incidence [-].
    cos_aoi : array_like
        Cosine of the angle of incidence [-]; clipped to [0, 1].

    Returns
    -------
    GlassAngular
        ``T, R_f, R_b, A_f, A_b`` [-], broadcast shape of the inputs.

    Notes
    -----
    EnergyPlus ER "Angular Properties for Coated Glass" (docs/model.md#glass-optics), c = cos θ::

        tau(c) = sum_i t_i c^i,   rho(c) = sum_i r_i c^i - tau(c)
        T(θ)   = T(0) tau(c)
        R_x(θ) = R_x(0) (1 - rho(c)) + rho(c)
        A_x(θ) = 1 - T(θ) - R_x(θ)

    with the "clr" coefficient set when T(0) > 0.645, else "bnz". ``tau`` and ``rho`` are
    clipped to [0, 1]: the fitted polynomials overshoot by about 1e-3 at c = 0 and c = 1; the
    clip makes normal incidence return T(0), R(0) exactly and grazing incidence T = 0
    (R = 1 for "clr", 0.999 + 0.001 R(0) for "bnz"). A ≥ 0 to round-off was checked for
    T(0) in [0.05, 0.92] and R(0) in [0, 0.3].
    """
    T0, R_f0, R_b0 = (np.asarray(v, dtype=float) for v in (T0, R_f0, R_b0))
    c = np.minimum(np.maximum(np.asarray(cos_aoi, dtype=float), 0.0), 1.0)
    powers = c[..., None] ** _EXPONENTS
    if T0.ndim == 0:  # one pane: evaluate only its curve set
        t_coef, r_coef = (_T_CLEAR, _R_CLEAR) if T0 > CLEAR_CURVE_THRESHOLD else (
            _T_BRONZE, _R_BRONZE)
        tau = powers @ t_coef
        rho = powers @ r_coef - tau
    else:
        clear = T0 > CLEAR_CURVE_THRESHOLD
        tau = np.where(clear, powers @ _T_CLEAR, powers @ _T_BRONZE)
        rho = np.where(clear, powers @ _R_CLEAR, powers @ _R_BRONZE) - tau
    tau = np.minimum(np.maximum(tau, 0.0), 1.0)
    rho = np.minimum(np.maximum(rho, 0.0), 1.0)
    T = T0 * tau
    R_f = R_f0 + (1.0 - R_f0) * rho
    R_b = R_b0 + (1.0 - R_b0) * rho
    return GlassAngular(T, R_f, R_b, 1.0 - T - R_f, 1.0 - T - R_b)


def glass_hemispherical(T0: ArrayLike, R_f0: ArrayLike, R_b0: ArrayLike) -> GlassAngular:
    """Hemispherical (uniformly diffuse) solar properties of a glass pane.

    Parameters
    ----------
    T0, R_f0, R_b0 : array_like
        Normal-incidence transmittance and front/back reflectance [-].

    Returns
    -------
    GlassAngular
        Hemispherical ``T, R_f, R_b, A_f, A_b`` [-], broadcast shape of the inputs.

    Notes
    -----
    docs/model.md#glass-optics: ``P_dif = 2 ∫_0^{pi/2} P(θ) cos θ sin θ dθ`` on the nodes
    0°, 10°, …, 90°. Nine intervals do not suit plain Simpson, so composite Simpson 1/3
    (0–60°) is joined to Simpson 3/8 (60–90°); the weights are normalised to integrate
    sin 2θ exactly (a 1.1e-4 correction). Each property is integrated separately, and the
    closure T + R + A = 1 holds to round-off.
    """
    T0, R_f0, R_b0 = (np.asarray(v, dtype=float)[..., None] for v in (T0, R_f0, R_b0))
    props = glass_angular(T0, R_f0, R_b0, _HEMI_COS)
    return GlassAngular(*(p @ _HEMI_WEIGHTS for p in props))


def dgu_beam(outer: GlassAngular, inner: GlassAngular) -> DGUBeam:
    """Beam properties of a specular pane pair (the DGU) for incidence from the cavity side.

    Parameters
    ----------
    outer : GlassAngular
        Properties of the cavity-side pane L2 ("a") at the incidence angle.
    inner : GlassAngular
        Properties of the room-side pane L3 ("b") at the same angle.

    Returns
    -------
    DGUBeam
        ``T, R_f, A_2, A_3`` [-], broadcast shape of the inputs;
        ``T + R_f + A_2 + A_3 = 1`` identically.

    Notes
    -----
    Net radiation for two specular layers (docs/model.md#glass-optics), k = 1 / (1 - R_a,b R_b,f)
    sums the inter-reflections in the gap::

        T_DGU   = T_a T_b k
        R_DGU,f = R_a,f + T_a² R_b,f k
        A_2     = A_a,f + T_a R_b,f A_a,b k
        A_3     = T_a A_b,f k
    """
    # At grazing incidence both reflectances reach 1 and the denominator 0; every term that
    # k multiplies then carries T_a = 0 or A_a,b = 0, so any finite k gives the exact limit.
    den = 1.0 - outer.R_b * inner.R_f
    k = 1.0 / np.where(den > 0.0, den, 1.0)
    return DGUBeam(
        T=outer.T * inner.T * k,
        R_f=outer.R_f + outer.T**2 * inner.R_f * k,
        A_2=outer.A_f + outer.T * inner.R_f * outer.A_b * k,
        A_3=outer.T * inner.A_f * k,
    )
