"""Vertical temperature profile of the ventilated cavity air (ISO 15099 ventilated gap).

The lumped model has one cavity-air node x5. Read as a *well-mixed* node (the paper's model,
docs/model.md#network) the air leaves the cavity at x5. Read as the *height-mean* of an air column
that warms (or cools) exponentially from its inlet towards the surfaces' temperature
(ISO 15099's ventilated-gap model), the air leaves hotter than its mean: the outlet's
excess over the inlet is k(a) > 1 times the mean's. This module gives that factor, so the
node x5 can stand for the mean column temperature, which sets the stack pressure, and the
factor p(a) of a probe at a given height (docs/model.md#cavity-probe): a thermocouple at
mid-height does not read the column's mean, it reads up to 15 % more of the excess over the
inlet (the profile is concave), and a model compared with it must say what it reads.
"""

from __future__ import annotations

import numpy as np

__all__ = ["outlet_excess_ratio", "probe_excess_ratio"]

#: Below this number of transfer units the closed form loses digits to cancellation; the
#: series 2 − a/3 + a²/18 − a³/270 is exact there to a⁴/3240 (3e-12 at the switch).
_SERIES_BELOW = 1e-2


def outlet_excess_ratio(ntu: np.ndarray | float) -> np.ndarray:
    """k(a) = (T_outlet − T_inlet)/(T_mean − T_inlet) of an exponential profile [-].

    Parameters
    ----------
    ntu : array, [-]
        Number of transfer units of the cavity air, a = H/H0 = Σ h_j A_j/(ṁ c_p): the
        conductance of the surfaces to the air over the advective conductance of the flow
        through it. ``inf`` (no flow) is allowed.

    Returns
    -------
    ndarray, [-]
        Between 1 (a → ∞: the air takes the surfaces' temperature at once, well mixed)
        and 2 (a → 0: linear profile, the outlet excess twice the mean's).

    Notes
    -----
    With the surfaces at a common (h-weighted) temperature T_av, the steady air column
    follows T(z) = T_av − (T_av − T_in) e^(−z/H0) with H0 = ṁ c_p/(W Σh) (ISO 15099:2003,
    the characteristic height of a ventilated gap). Over the height H, with a = H/H0:

        outlet excess  (T_out − T_in)/(T_av − T_in)  = 1 − e^(−a)
        mean excess    (T̄ − T_in)/(T_av − T_in)     = 1 − (1 − e^(−a))/a

    and k(a) is their ratio. The heat the flow carries away, ṁ c_p (T_out − T_in), is then
    k ṁ c_p (T̄ − T_in): the lumped node keeps its balance with the advective conductance
    scaled by k, and that balance still equals the surfaces' heat Σh A (T_j − T̄) at steady
    state.
    """
    a = np.asarray(ntu, float)
    closed = np.where(a >= _SERIES_BELOW, a, 1.0)
    outlet = -np.expm1(-closed)
    exact = outlet / (1.0 - outlet / closed)
    small = np.minimum(a, _SERIES_BELOW)
    series = 2.0 + small * (-1.0 / 3.0 + small * (1.0 / 18.0 - small / 270.0))
    return np.where(a >= _SERIES_BELOW, exact, series)


def probe_excess_ratio(ntu: np.ndarray | float, height_frac: float = 0.5) -> np.ndarray:
    """p(a) = (T_probe − T_inlet)/(T_mean − T_inlet) of an exponential profile [-].

    Parameters
    ----------
    ntu : array, [-]
        Number of transfer units a of the cavity air (:func:`outlet_excess_ratio`);
        ``inf`` (no flow) is allowed.
    height_frac : float, [-]
        Distance of the probe from the inlet over the cavity height, ζ (0.5: mid-height,
        the same for upward and downward flow).

    Returns
    -------
    ndarray, [-]
        p(a) → 2ζ as a → 0 (linear profile) and 1 as a → ∞ (well mixed); at mid-height
        p ≥ 1, largest (1.147) near a = 4.4.

    Notes
    -----
    With the profile of :func:`outlet_excess_ratio`, the excess at ζ is 1 − e^(−aζ) and the
    mean's 1 − (1 − e^(−a))/a, so the probe reads T_probe = T_in + p(a) (x5 − T_in) when x5
    is the column mean (ISO 15099:2003 §7.7, characteristic height of a ventilated gap).
    ζ = 1 gives k(a). Below a = 0.01 both excesses are divided by a and taken from their
    series (error O(a³)).
    """
    a = np.asarray(ntu, float)
    z = float(height_frac)
    closed = np.where(a >= _SERIES_BELOW, a, 1.0)
    exact = -np.expm1(-closed * z) / (1.0 + np.expm1(-closed) / closed)
    exact = np.where(np.isinf(a), 1.0, exact)
    small = np.minimum(a, _SERIES_BELOW)
    series = ((z - small * z * z / 2.0 + small * small * z ** 3 / 6.0)
              / (0.5 - small / 6.0 + small * small / 24.0))
    return np.where(a >= _SERIES_BELOW, exact, series)
