"""Does a heat-transfer parameter's change show at night too? (docs/model.md#daylight-split).

Pure (no files, clocks or logging). A film coefficient or the glass unit's gap conductance is
a property of air and glass: what moves it moves it by day and by night alike (a failed edge
seal lets the gas out for good, a fan coil blows whether the sun shines or not). Less sun
than the model computes (dirt on the exterior glass, slats at another angle than their
read-back) is absent at night; yet by day the on-line calibration may take it up in a
coefficient instead of the heat-flux offsets (on the diagnostics bench's soiled winter
façade the glass unit's h_ca4 rose ×2 in the sunny windows and kept its value in the dark
ones). So when the parameter detector reports a heat-transfer coefficient, its estimates are
split by whether their calibration window saw the sun (:func:`window_dark`), and each half is
judged against its own past as the whole was
(:func:`~dsfd.estimation.parameter_shift.standardised_days` on the half's own daily values).
A change in the sunlit half alone is the sun's (:func:`daylight_only`), and the finding is
told as a change of the sun the façade takes (:func:`as_solar_finding`), its direction from
the solar detector's daily factor (:func:`dsfd.estimation.solar_response.solar_cause`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.parameter_shift import ParameterSettings, standardised_days
from dsfd.estimation.parameter_watch import daily_estimates
from dsfd.estimation.solar_response import SOLAR_SIGNAL, solar_action, solar_cause
from dsfd.physics.solar.position import solar_position

__all__ = ["HEAT_TRANSFER_NAMES", "MIN_HALF_SPAN_S", "DaylightSplit", "as_solar_finding",
           "daylight_only", "daylight_split", "told_by_daylight", "window_dark"]

#: The θ parameters that are properties of air and glass, not of the sun.
HEAT_TRANSFER_NAMES = ("h_out", "h_ca1", "h_ca2", "h_ca3", "h_ca4", "h_in")
#: A half's estimates of a day must span this long to make a daily value (a winter night's
#: dark windows span some 10 h, a summer night's about 5 h at 37° N with 4-h windows).
MIN_HALF_SPAN_S = 3 * 3600.0


@dataclass(frozen=True)
class DaylightSplit:
    """A parameter's change in the estimates of dark and of sunlit windows.

    Attributes
    ----------
    dark_z, lit_z : float
        Mean standardised distance from the half's own trailing reference over the days
        since the finding's start [posterior sd of the daily spread]; NaN where the half
        has no judged day there.
    dark_shift, lit_shift : float
        The same as the parameter's shift (its daily value minus the reference mean, in
        the fitting coordinate: ln θ).
    """

    dark_z: float
    lit_z: float
    dark_shift: float
    lit_shift: float


def window_dark(times_s: np.ndarray, window_s: float, *, latitude_deg: float,
                longitude_deg: float) -> np.ndarray:
    """Whether the calibration window [t − ``window_s``, t] of each estimate was all night.

    The sun below the horizon at both ends: a window shorter than the night (4 h, where
    the shortest night at 60° latitude lasts about 5.5 h) cannot span a day between them.
    """
    t = np.asarray(times_s, float)
    if not t.size:
        return np.zeros(0, bool)
    end = solar_position(t, latitude_deg, longitude_deg).elevation_deg
    start = solar_position(t - window_s, latitude_deg, longitude_deg).elevation_deg
    return (end < 0.0) & (start < 0.0)


def _half(t: np.ndarray, v: np.ndarray, sd: np.ndarray, *, since_s: float, end_s: float,
          settings: ParameterSettings) -> tuple[float, float]:
    days_t, days_v, days_sd = daily_estimates(t, v, sd, end_s=end_s, min_span_s=MIN_HALF_SPAN_S)
    z, ref = standardised_days(days_t, days_v, days_sd, settings)
    after = (days_t >= since_s) & np.isfinite(z)
    if not after.any():
        return math.nan, math.nan
    return float(np.mean(z[after])), float(np.mean(days_v[after] - ref[after]))


def daylight_split(times_s: np.ndarray, values: np.ndarray, sds: np.ndarray,
                   dark: np.ndarray, *, since_s: float, end_s: float,
                   settings: ParameterSettings | None = None) -> DaylightSplit:
    """The change since ``since_s`` of a parameter's estimates from dark windows and from
    sunlit ones, each half against its own past.

    Parameters
    ----------
    times_s, values, sds : array (n,)
        The on-line estimates (fitting coordinates, as the parameter detector reads them)
        and their posterior sd.
    dark : array (n,), bool
        The estimate's window saw no sun (:func:`window_dark`).
    since_s, end_s : float, [s]
        The finding's start, and the end of the last day (the check's time; later estimates
        are left out): the days are the detector's 24-h periods.
    """
    st = settings or ParameterSettings()
    t, v, sd = (np.asarray(a, float) for a in (times_s, values, sds))
    d = np.asarray(dark, bool)
    before_end = t < end_s
    t, v, sd, d = t[before_end], v[before_end], sd[before_end], d[before_end]
    dz, dshift = _half(t[d], v[d], sd[d], since_s=since_s, end_s=end_s, settings=st)
    lz, lshift = _half(t[~d], v[~d], sd[~d], since_s=since_s, end_s=end_s, settings=st)
    return DaylightSplit(dark_z=dz, lit_z=lz, dark_shift=dshift, lit_shift=lshift)


def daylight_only(split: DaylightSplit, *, side: int, k_sd: float) -> bool:
    """The change is in the sunlit half, beyond the allowance ``k_sd`` on the finding's side,
    and the dark half stays within it (both judged)."""
    if not (math.isfinite(split.dark_z) and math.isfinite(split.lit_z)):
        return False
    return side * split.lit_z >= k_sd and abs(split.dark_z) < k_sd


def as_solar_finding(f: Finding, split: DaylightSplit, *, factor_shift: float) -> Finding:
    """A parameter finding of a heat-transfer coefficient whose change is the sun's, told as
    a ``solar_gain_shift``: its evidence first (the parameter), then the two halves and the
    solar detector's daily factor's change ``factor_shift`` over the same days (< 0: less
    sun taken, signal ``solar_response``), from which the subject and the action follow."""
    head = f.evidence[0]
    name = head.signal.removeprefix("parameter:")
    halves = tuple(Evidence(signal=f"{head.signal}:{half}", shift=shift, shift_sd=z,
                            unit=head.unit, since_s=head.since_s, statistic=math.nan,
                            threshold=math.nan)
                   for half, shift, z in (("dark", split.dark_shift, split.dark_z),
                                          ("sunlit", split.lit_shift, split.lit_z)))
    solar = Evidence(signal=SOLAR_SIGNAL, shift=factor_shift, shift_sd=math.nan, unit="1",
                     since_s=head.since_s, statistic=math.nan, threshold=math.nan)
    cause = solar_cause(factor_shift, pane_shift=None, slat_shift=None)
    why = (f"{name} moved ×{math.exp(split.lit_shift):.2f} in the hours with sun and "
           f"×{math.exp(split.dark_shift):.2f} at night, which no change of air or glass "
           "does")
    return replace(f, kind="solar_gain_shift", subject=cause,
                   evidence=(head, *halves, solar, *f.evidence[1:]),
                   action=f"{why}: {solar_action(factor_shift, cause)}")


def told_by_daylight(kind: str, first_signal: str) -> bool:
    """Whether a finding of ``kind`` whose first evidence is ``first_signal`` is a
    coefficient's change told as the sun's (:func:`as_solar_finding`)."""
    return (kind == "solar_gain_shift" and first_signal.startswith("parameter:")
            and first_signal.removeprefix("parameter:") in HEAT_TRANSFER_NAMES)
