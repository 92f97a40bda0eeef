"""Settings of the safety pipeline that runs before every actuator write.

YAML shape (the ``safety:`` section of a panel file; every key is optional)::

    safety:
      safe_state: {phi_deg: 90, afr: 10, or_pct: 0}
      fault_signals: [t_out_c, ghi_wm2]
      wind_limit_ms: 15.0
      wind_hysteresis_ms: 3.0
      wind_release_cycles: 10
      wind_safe_angle_deg: 90
      min_louver_move_interval_s: 300

Stages, highest priority first (``dsfd.daemon.safety``): faults → wind → actuator limits →
louver quantisation → louver move interval → regimes the dampers allow. Errors name the key
path, e.g. ``safety.safe_state.afr``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from dsfd.config.loader import Problem, setting
from dsfd.signals import SENSORS

__all__ = ["SafeState", "Safety"]


@dataclass(frozen=True, kw_only=True)
class SafeState:
    """Command applied when the controller cannot decide (sensor or device faults)."""

    phi_deg: float = setting(90.0, doc="Louver angle (90: closed, the night position)",
                             unit="deg", ge=-90, le=90)
    afr: int = setting(10, doc="Airflow regime (10: all dampers closed)", ge=1, le=10)
    or_pct: float = setting(0.0, doc="Damper opening", unit="%", ge=0, le=100)


@dataclass(frozen=True, kw_only=True)
class Safety:
    """Limits and overrides applied to every command, in a fixed priority order."""

    safe_state: SafeState = setting(default_factory=SafeState, doc="The safe command")
    fault_signals: tuple[str, ...] = setting(
        ("t_out_c", "ghi_wm2"),
        doc="While any of these sensors is not GOOD the safe state is commanded (both the "
        "optimiser and the baseline need outdoor air and irradiance)")
    wind_limit_ms: float = setting(
        15.0, doc="Wind speed at the station above which the louver goes to the wind-safe "
        "angle and exterior dampers close", unit="m/s", gt=0, le=75)
    wind_hysteresis_ms: float = setting(
        3.0, doc="The override ends below wind_limit_ms minus this", unit="m/s", ge=0, le=30)
    wind_release_cycles: int = setting(
        10, doc="Consecutive cycles below the release speed before the override ends "
        "(gusts come back)", ge=1, le=1440)
    wind_safe_angle_deg: float = setting(
        90.0, doc="Louver angle during a wind override", unit="deg", ge=-90, le=90)
    wind_close_exterior: bool = setting(
        True, doc="During a wind override, regimes that open exterior dampers are replaced "
        "by the closed regime")
    wind_unknown: Literal["safe", "hold"] = setting(
        "safe", doc="Without a GOOD wind reading: act as in a wind override (safe) or keep "
        "the override state of the last known wind (hold)")
    phi_min_deg: float = setting(-90.0, doc="Mechanical lower limit of the louver angle",
                                 unit="deg", ge=-90, le=90)
    phi_max_deg: float = setting(90.0, doc="Mechanical upper limit of the louver angle",
                                 unit="deg", ge=-90, le=90)
    or_max_pct: float = setting(100.0, doc="Largest damper opening commanded", unit="%",
                                gt=0, le=100)
    or_step_pct: float = setting(
        1.0, doc="Resolution of the damper opening; commands are rounded to it", unit="%",
        gt=0, le=50)
    or_deadband_pct: float = setting(
        5.0, doc="Damper opening changes smaller than this are not commanded (actuator "
        "chatter); a regime change always is", unit="%", ge=0, le=50)
    min_louver_move_interval_s: float = setting(
        300.0, doc="Least time between two louver moves (motor wear, occupants); the fault "
        "and wind stages may move it at any time", unit="s", ge=0, le=86400)

    def check(self) -> list[Problem]:
        out = []
        if self.phi_min_deg > self.phi_max_deg:
            out.append(Problem("phi_min_deg", self.phi_min_deg,
                               f"above phi_max_deg {self.phi_max_deg}"))
        if self.wind_hysteresis_ms >= self.wind_limit_ms:
            out.append(Problem("wind_hysteresis_ms", self.wind_hysteresis_ms,
                               f"must be below wind_limit_ms {self.wind_limit_ms}"))
        for i, name in enumerate(self.fault_signals):
            if name not in SENSORS:
                out.append(Problem(f"fault_signals[{i}]", name,
                                   f"not a sensor signal; known: {', '.join(SENSORS)}"))
        if self.safe_state.afr == 10 and self.safe_state.or_pct != 0.0:
            out.append(Problem("safe_state.or_pct", self.safe_state.or_pct,
                               "regime 10 has every damper closed; use 0"))
        return out
