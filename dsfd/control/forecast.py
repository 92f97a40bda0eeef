"""Weather over the prediction horizon.

Default: persistence of the latest measurement with the solar term following geometry —
air temperature, wind, pressure and the room held; the clearness index
kt = GHI / (I0 cos Z) (and the diffuse fraction, where DHI is measured) held, so the
forecast irradiance follows the sun's path over the 15 minutes instead of freezing it.
A supplied forecast (e.g. the simulated plant's perfect one) can be used instead.
"""

from __future__ import annotations

import numpy as np

from dsfd.physics.boundary import WeatherInputs
from dsfd.physics.solar import extraterrestrial_irradiance, solar_position

#: Below this cos Z the clearness index is not persisted (sun too low to measure it).
MIN_COS_ZENITH = 0.05
#: Upper bound on the persisted clearness index (cloud-edge enhancement aside).
MAX_KT = 1.2


def persistence_forecast(last: WeatherInputs, *, latitude_deg: float, longitude_deg: float,
                         start_s: float, step_s: float, n_steps: int) -> WeatherInputs:
    """Forecast ``n_steps`` model steps from the latest measured interval ``last``.

    Parameters
    ----------
    last : WeatherInputs
        The most recent measured values (arrays of length ≥ 1; the last element is used).
    latitude_deg, longitude_deg : float, [deg]
        Site (north, east positive).
    start_s : float, [s]
        UTC start of the first forecast step; step k is evaluated at its midpoint.
    step_s : float, [s]
    n_steps : int

    Returns
    -------
    WeatherInputs
        Arrays of length ``n_steps``; DNI/DHI are NaN (decomposed downstream) unless DHI
        was measured, in which case the diffuse fraction is persisted too.
    """
    def latest(v: np.ndarray) -> float:
        return float(np.asarray(v, float).reshape(-1)[-1])

    t_mid = start_s + (np.arange(n_steps) + 0.5) * step_s
    now = latest(last.time_s)
    sun_now = solar_position(np.array([now]), latitude_deg, longitude_deg)
    cos_now = float(np.cos(np.radians(sun_now.zenith_deg[0])))
    i0_now = float(extraterrestrial_irradiance(np.array([now]))[0])
    ghi_now = max(latest(last.ghi_wm2), 0.0)
    kt = min(ghi_now / (i0_now * cos_now), MAX_KT) if cos_now > MIN_COS_ZENITH else 0.0
    sun = solar_position(t_mid, latitude_deg, longitude_deg)
    cos_z = np.clip(np.cos(np.radians(sun.zenith_deg)), 0.0, None)
    ghi = kt * extraterrestrial_irradiance(t_mid) * cos_z
    if cos_now <= MIN_COS_ZENITH:  # dawn or dusk: keep what was measured, it is tiny
        ghi = np.full(n_steps, ghi_now) * (cos_z > 0)
    dhi_now = latest(last.dhi_wm2)
    if np.isfinite(dhi_now) and ghi_now > 0:
        diffuse_fraction = min(max(dhi_now / ghi_now, 0.0), 1.0)
        dhi = diffuse_fraction * ghi
        dni = np.where(cos_z > MIN_COS_ZENITH, (ghi - dhi) / np.maximum(cos_z, MIN_COS_ZENITH),
                       0.0)
    else:
        dhi = np.full(n_steps, np.nan)
        dni = np.full(n_steps, np.nan)

    # Everything but the sun-following irradiance is held; façade-plane readings are not
    # forecast (the horizon is decomposed from GHI).
    held = WeatherInputs(*(None if v is None else np.full(n_steps, latest(v)) for v in last))
    return held._replace(time_s=t_mid, ghi_wm2=ghi, dni_wm2=dni, dhi_wm2=dhi,
                         poa_global_wm2=None, poa_diffuse_wm2=None)
