"""Sky condition of a time series of global horizontal irradiance: clear, mixed, overcast or
night — the classes of the paper's Figure 11 discussion (clear vs overcast days)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from dsfd.physics.solar import extraterrestrial_irradiance, solar_position
from dsfd.physics.solar.decomposition import clearness_index

__all__ = ["SKY_CONDITIONS", "sky_conditions"]

#: The classes, in the order reports show them.
SKY_CONDITIONS: tuple[str, ...] = ("clear", "mixed", "overcast", "night")


def sky_conditions(time_s: ArrayLike, ghi_wm2: ArrayLike, latitude_deg: float,
                   longitude_deg: float, *, night_elevation_deg: float = 5.0,
                   night_ghi_wm2: float = 20.0, clear_kt: float = 0.55,
                   overcast_kt: float = 0.3) -> np.ndarray:
    """Sky condition at each time (array of str).

    Parameters
    ----------
    time_s : array, [s]
        UTC unix times (the middle of each averaging interval).
    ghi_wm2 : array, [W/m2]
        Global horizontal irradiance; NaN gives ``""`` (unknown).
    latitude_deg, longitude_deg : float, [deg]

    Returns
    -------
    ndarray of str
        ``night`` (sun below ``night_elevation_deg`` or GHI below ``night_ghi_wm2``), else by
        the clearness index k_t = GHI / (E_0 cos Z): ``clear`` (> ``clear_kt``),
        ``overcast`` (< ``overcast_kt``) or ``mixed``.

    Notes
    -----
    k_t thresholds after the usual sky classes of decomposition models (Erbs, Klein and
    Duffie 1982: diffuse fraction ≈ 1 below k_t ≈ 0.22-0.3, mostly beam above ≈ 0.55-0.8).
    """
    t = np.asarray(time_s, float)
    ghi = np.asarray(ghi_wm2, float)
    sun = solar_position(t, latitude_deg, longitude_deg)
    kt = clearness_index(np.nan_to_num(ghi), sun.zenith_deg, extraterrestrial_irradiance(t))
    night = (sun.elevation_deg < night_elevation_deg) | (ghi < night_ghi_wm2)
    out = np.where(night, "night", np.where(kt > clear_kt, "clear",
                                            np.where(kt < overcast_kt, "overcast", "mixed")))
    return np.where(np.isfinite(ghi), out, "")
