"""Decomposition of global horizontal irradiance into direct normal and diffuse parts.

Erbs (lumped model, docs/model.md#decomposition), DISC and DIRINT (truth plant). All expect the
geometric (true) zenith.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from dsfd.physics.constants import STANDARD_PRESSURE_PA
from dsfd.physics.solar.position import (
    FloatArray,
    _as_float,
    _kasten1966_airmass,
    extraterrestrial_irradiance,
)

#: Solar constant used by Maxwell's DISC model [W/m2].
DISC_SOLAR_CONSTANT = 1370.0

#: DIRINT bin edges (Perez et al. 1992): kt′, zenith [deg] and Δkt′.
DIRINT_KT_PRIME_EDGES = np.array([0.24, 0.4, 0.56, 0.7, 0.8])
DIRINT_ZENITH_EDGES_DEG = np.array([25.0, 40.0, 55.0, 70.0, 80.0])
DIRINT_DELTA_KT_PRIME_EDGES = np.array([0.015, 0.035, 0.07, 0.15, 0.3])
#: DIRINT correction factors X[kt′ bin, zenith bin, Δkt′ bin] for "precipitable water
#: unknown", as published by Perez et al. (1992) (the same numbers pvlib carries). The
#: last Δkt′ column (index 6) is "Δkt′ unknown".
DIRINT_COEFFICIENTS = np.array([
    [  # kt' bin 1
        [0.31744, 0.50365, 0.26944, 0.45737, 1.03637, 1.97654, 0.56995],
        [0.12794, 0.19394, 0.24461, 0.57944, 1.05227, 2.31692, 0.66497],
        [0.83249, 0.68164, 0.35047, 0.98379, 1.99263, 3.31082, 0.89873],
        [0.12697, 0.81082, 2.29144, 1.96557, 8.79239, 21.74424, 2.33162],
        [0.12697, 0.81082, 2.29144, 1.96557, 8.79239, 21.74424, 2.33162],
        [0.12697, 0.81082, 2.29144, 1.96557, 8.79239, 21.74424, 2.33162],
    ],
    [  # kt' bin 2
        [1.11608, 0.62390, 0.90848, 1.28930, 1.85283, 2.11723, 1.47640],
        [0.79694, 0.64930, 0.68546, 0.78537, 1.33559, 2.51867, 0.98658],
        [0.66529, 0.58259, 0.61228, 0.80260, 1.29295, 2.17710, 0.95873],
        [0.60760, 0.50280, 0.49051, 0.68111, 0.97843, 2.39418, 0.73541],
        [0.41351, 0.44246, 0.46161, 0.67149, 1.02383, 2.13399, 0.80450],
        [0.80092, 0.23704, 0.58199, 0.89857, 3.40039, 2.50878, 1.40938],
    ],
    [  # kt' bin 3
        [1.24221, 0.92516, 1.20530, 1.23334, 1.41184, 1.67160, 1.29467],
        [0.94583, 1.06662, 1.09731, 1.09611, 1.19806, 1.91159, 1.11933],
        [0.81360, 0.92884, 0.91100, 0.98809, 1.04238, 1.08295, 1.00458],
        [0.66574, 0.66914, 0.70904, 0.84435, 0.93691, 0.97513, 0.82922],
        [0.59718, 0.71855, 0.69430, 0.84767, 0.94702, 0.88858, 0.82388],
        [0.62979, 0.65814, 0.58278, 0.89826, 0.88561, 1.12039, 0.79613],
    ],
    [  # kt' bin 4
        [1.17809, 1.13169, 1.11460, 1.12632, 1.01793, 1.13226, 1.12711],
        [1.09659, 1.04242, 1.05006, 1.01578, 0.96996, 0.89910, 1.03231],
        [1.00970, 1.03647, 1.00014, 0.95210, 0.89369, 0.91792, 0.97299],
        [0.98024, 1.03825, 0.99984, 0.91523, 0.85156, 0.64671, 0.94795],
        [0.93284, 1.03015, 1.04490, 0.94447, 0.81819, 0.66930, 0.97997],
        [0.85399, 0.95501, 1.04164, 0.96633, 0.72683, 0.49805, 0.96021],
    ],
    [  # kt' bin 5
        [1.06922, 1.04620, 1.01274, 0.98444, 0.96218, 0.96155, 1.03780],
        [1.04562, 1.02206, 0.98177, 0.94656, 0.88342, 0.84513, 1.01724],
        [1.02424, 0.99961, 0.94971, 0.91310, 0.85346, 0.68905, 0.98790],
        [1.01745, 1.00725, 0.95273, 0.87153, 0.79589, 0.71566, 0.98164],
        [1.01116, 1.03484, 0.98987, 0.82105, 0.73855, 0.69651, 0.99149],
        [0.99847, 0.98856, 0.94726, 0.72523, 0.54863, 0.53994, 0.93768],
    ],
    [  # kt' bin 6
        [1.04951, 0.99653, 0.97194, 0.95184, 0.92873, 0.77395, 1.03456],
        [1.03578, 0.97746, 0.95168, 0.88385, 0.83987, 0.78841, 1.01168],
        [1.03294, 0.97815, 0.93032, 0.86531, 0.82714, 0.65120, 1.00165],
        [1.03525, 0.98255, 0.91781, 0.86304, 0.78312, 0.71566, 0.99518],
        [1.00588, 0.98372, 0.92428, 0.84452, 0.73350, 0.62885, 0.94903],
        [0.95632, 0.95011, 0.85611, 0.69578, 0.56015, 0.52023, 0.79439],
    ],
])

class ErbsResult(NamedTuple):
    dni: FloatArray  #: [W/m2]
    dhi: FloatArray  #: [W/m2]
    kt: FloatArray  #: clearness index [-]


class DiscResult(NamedTuple):
    dni: FloatArray  #: [W/m2]
    kt: FloatArray  #: clearness index, clipped to [0, 1] [-]
    airmass: FloatArray  #: pressure-corrected Kasten (1966) air mass, ≤ max_airmass [-]


def clearness_index(
    ghi: ArrayLike,
    zenith_deg: ArrayLike,
    dni_extra: ArrayLike,
    *,
    min_cos_zenith: float = 0.065,
    max_clearness_index: float = 2.0,
) -> FloatArray:
    """Clearness index kt = GHI / (I0 · max(cos Z, min_cos_zenith)), clipped to [0, max]."""
    cos_zen = np.maximum(np.cos(np.radians(_as_float(zenith_deg))), min_cos_zenith)
    return np.clip(_as_float(ghi) / (_as_float(dni_extra) * cos_zen), 0.0, max_clearness_index)


def erbs(
    ghi: ArrayLike,
    zenith_deg: ArrayLike,
    dni_extra: ArrayLike,
    *,
    min_cos_zenith: float = 0.065,
    max_zenith_deg: float = 87.0,
) -> ErbsResult:
    """Split GHI into DNI and DHI with the Erbs et al. (1982) diffuse fraction.

    Parameters
    ----------
    ghi : array_like, [W/m2]
    zenith_deg : array_like, [deg]
        Geometric (true) zenith.
    dni_extra : array_like, [W/m2]
        Extraterrestrial irradiance, see :func:`extraterrestrial_irradiance`.
    min_cos_zenith : float, [-]
        Floor on cos Z in kt (0.065 ≈ 86.27°).
    max_zenith_deg : float, [deg]
        DNI is set to 0 above this zenith.

    Returns
    -------
    ErbsResult
        dni, dhi [W/m2] and kt [-]. Where DNI is forced to 0 (Z > max_zenith_deg,
        GHI < 0 or a negative split) DHI = GHI, so GHI = DHI + DNI cos Z always holds.

    Notes
    -----
    docs/model.md#decomposition; kt is clipped to [0, 2] here (pvlib 0.16.1 clips to
    [0, 1]; the split is the same because DF is constant above kt = 0.8)::

        DF = 1 − 0.09 kt                                              kt ≤ 0.22
        DF = 0.9511 − 0.1604 kt + 4.388 kt² − 16.638 kt³ + 12.336 kt⁴     0.22 < kt ≤ 0.8
        DF = 0.165                                                    kt > 0.8
        DHI = DF·GHI,   DNI = (GHI − DHI)/cos Z

    Reference: D. G. Erbs, S. A. Klein and J. A. Duffie, "Estimation of the diffuse
    radiation fraction for hourly, daily and monthly-average global radiation", Solar
    Energy 28 (1982) 293–302.
    """
    ghi_a, zen = _as_float(ghi), _as_float(zenith_deg)
    kt = clearness_index(ghi_a, zen, dni_extra, min_cos_zenith=min_cos_zenith)
    df = np.where(kt <= 0.22, 1.0 - 0.09 * kt,
                  0.9511 + kt * (-0.1604 + kt * (4.388 + kt * (-16.638 + 12.336 * kt))))
    df = np.where(kt > 0.8, 0.165, df)
    dhi = df * ghi_a
    cos_zen = np.cos(np.radians(zen))
    dni = (ghi_a - dhi) / np.where(cos_zen > 0.0, cos_zen, 1.0)
    bad = (zen > max_zenith_deg) | (cos_zen <= 0.0) | (ghi_a < 0.0) | (dni < 0.0)
    return ErbsResult(np.where(bad, 0.0, dni), np.where(bad, ghi_a, dhi), kt)


def disc(
    ghi: ArrayLike,
    zenith_deg: ArrayLike,
    unix_s: ArrayLike,
    *,
    pressure_pa: ArrayLike = STANDARD_PRESSURE_PA,
    min_cos_zenith: float = 0.065,
    max_zenith_deg: float = 87.0,
    max_airmass: float = 12.0,
) -> DiscResult:
    """DNI from GHI with Maxwell's DISC model (1987).

    Parameters
    ----------
    ghi : array_like, [W/m2]
    zenith_deg : array_like, [deg]
        Geometric (true) zenith.
    unix_s : array_like, [s]
        UTC time, for the extraterrestrial irradiance (Spencer, S = 1370 W/m2 as Maxwell).
    pressure_pa : array_like, [Pa]
        Station pressure for the absolute air mass.
    min_cos_zenith, max_zenith_deg : float
        As in :func:`erbs`.
    max_airmass : float, [-]
        Upper limit of the air mass inside the model.

    Returns
    -------
    DiscResult
        dni [W/m2] (0 where Z > max_zenith_deg, GHI < 0 or the model goes negative), kt
        and the air mass used.

    Notes
    -----
    kt as :func:`clearness_index` clipped to [0, 1]; AM = Kasten (1966) relative air mass
    × p/101325, ≤ max_airmass::

        Knc = 0.866 − 0.122 AM + 0.0121 AM² − 0.000653 AM³ + 0.000014 AM⁴
        ΔKn = a(kt) + b(kt) exp(c(kt) AM)          (cubic polynomials a, b, c for
                                                    kt ≤ 0.6 and kt > 0.6)
        DNI = I0 (Knc − ΔKn)

    Reference: E. L. Maxwell, "A quasi-physical model for converting hourly global
    horizontal to direct normal insolation", SERI/TR-215-3087, Solar Energy Research
    Institute, Golden CO, 1987.
    """
    ghi_a, zen = _as_float(ghi), _as_float(zenith_deg)
    i0 = extraterrestrial_irradiance(unix_s, solar_constant=DISC_SOLAR_CONSTANT)
    kt = clearness_index(ghi_a, zen, i0, min_cos_zenith=min_cos_zenith, max_clearness_index=1.0)
    am = np.minimum(_kasten1966_airmass(zen) * _as_float(pressure_pa) / STANDARD_PRESSURE_PA,
                    max_airmass)
    cloudy = kt <= 0.6
    a = np.where(cloudy, 0.512 + kt * (-1.56 + kt * (2.286 - 2.222 * kt)),
                 -5.743 + kt * (21.77 + kt * (-27.49 + 11.56 * kt)))
    b = np.where(cloudy, 0.37 + 0.962 * kt, 41.4 + kt * (-118.5 + kt * (66.05 + 31.9 * kt)))
    c = np.where(cloudy, -0.28 + kt * (0.932 - 2.048 * kt),
                 -47.01 + kt * (184.2 + kt * (-222.0 + 73.81 * kt)))
    knc = 0.866 + am * (-0.122 + am * (0.0121 + am * (-0.000653 + 0.000014 * am)))
    dni = i0 * (knc - (a + b * np.exp(c * am)))
    bad = (zen > max_zenith_deg) | (ghi_a < 0.0) | (dni < 0.0)
    return DiscResult(np.where(bad, 0.0, dni), kt, am)


def _delta_kt_prime(kt_prime: FloatArray) -> FloatArray:
    """Perez eq. 2/3 stability index along the last axis; NaN kt' counts as missing.

    Mean of |kt'_i − kt'_{i±1}| over the available neighbours; −1 ("unknown" bin) where
    a sample has no valid neighbour.
    """
    pad = np.full((*kt_prime.shape[:-1], 1), np.nan)
    prev = np.concatenate([pad, kt_prime[..., :-1]], axis=-1)
    nxt = np.concatenate([kt_prime[..., 1:], pad], axis=-1)
    total = np.zeros_like(kt_prime)
    count = np.zeros_like(kt_prime)
    for neighbour in (prev, nxt):
        ok = np.isfinite(neighbour) & np.isfinite(kt_prime)
        total += np.where(ok, np.abs(kt_prime - np.where(ok, neighbour, 0.0)), 0.0)
        count += ok
    return np.where(count > 0, total / np.maximum(count, 1.0), -1.0)


def dirint(
    ghi: ArrayLike,
    zenith_deg: ArrayLike,
    unix_s: ArrayLike,
    *,
    pressure_pa: ArrayLike = STANDARD_PRESSURE_PA,
    use_delta_kt_prime: bool = True,
    min_cos_zenith: float = 0.065,
    max_zenith_deg: float = 87.0,
) -> FloatArray:
    """DNI from GHI with the DIRINT model of Perez et al. (1992), without dew point.

    Parameters
    ----------
    ghi, zenith_deg, unix_s, pressure_pa :
        As in :func:`disc`. With ``use_delta_kt_prime`` the LAST axis must be a time
        series of consecutive samples.
    use_delta_kt_prime : bool
        Use the persistence index Δkt′ from the neighbouring samples; otherwise (or for a
        sample with no valid neighbour) the "Δkt′ unknown" coefficients are used.

    Returns
    -------
    ndarray, [W/m2]
        0 where DISC gives 0; NaN where GHI or zenith is NaN.

    Notes
    -----
    With kt and AM from :func:`disc`::

        kt′  = kt / (1.031 exp(−1.4 / (0.9 + 9.4/AM)) + 0.1),  clipped to [0, 1]
        Δkt′ = ½(|kt′_i − kt′_{i+1}| + |kt′_i − kt′_{i−1}|)   (one neighbour at the ends)
        DNI  = DNI_DISC · X(kt′, Z, Δkt′, W unknown)

    X is the published 6×6×7 table (precipitable-water column "unknown"). Samples with the
    sun below the horizon (Z > 90°) or NaN GHI count as missing neighbours, so the first
    and last daylight samples use their one neighbour (Perez eq. 3); a sample with no
    valid neighbour uses the "Δkt′ unknown" column (pvlib returns NaN there).

    Reference: R. Perez, P. Ineichen, E. Maxwell, R. Seals and A. Zelenka, "Dynamic
    global-to-direct irradiance conversion models", ASHRAE Transactions 98(1) (1992)
    354–369.
    """
    ghi_a, zen = _as_float(ghi), _as_float(zenith_deg)
    out = disc(ghi_a, zen, unix_s, pressure_pa=pressure_pa, min_cos_zenith=min_cos_zenith,
               max_zenith_deg=max_zenith_deg)
    ghi_a, zen, dni_disc, kt, am = np.broadcast_arrays(ghi_a, zen, *out)
    kt_prime = np.clip(kt / (1.031 * np.exp(-1.4 / (0.9 + 9.4 / am)) + 0.1), 0.0, 1.0)
    valid = np.isfinite(kt_prime) & (zen <= 90.0)
    if use_delta_kt_prime and kt_prime.ndim > 0:
        delta = _delta_kt_prime(np.where(valid, kt_prime, np.nan))
    else:
        delta = np.full(kt_prime.shape, -1.0)
    kt_bin = np.digitize(np.where(valid, kt_prime, 0.0), DIRINT_KT_PRIME_EDGES)
    zen_bin = np.digitize(np.where(np.isfinite(zen), zen, 0.0), DIRINT_ZENITH_EDGES_DEG)
    delta_bin = np.where(delta < 0.0, 6, np.digitize(delta, DIRINT_DELTA_KT_PRIME_EDGES))
    dni = dni_disc * DIRINT_COEFFICIENTS[kt_bin, zen_bin, delta_bin]
    return np.where(np.isfinite(ghi_a) & np.isfinite(zen), dni, np.nan)


