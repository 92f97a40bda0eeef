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
      manual_hold_min: 120
      manual_reset_local: "22:00"

Stages, highest priority first (``dsfd.daemon.safety``): wind → manual hold → faults →
actuator limits → louver quantisation → louver move interval → regimes the dampers allow.
Errors name the key path, e.g. ``safety.safe_state.afr``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

from dsfd.config.loader import Problem, setting
from dsfd.signals import SENSORS

__all__ = ["SafeState", "Safety", "parse_local_time"]

_HH_MM = re.compile(r"^([01][0-9]|2[0-3]):([0-5][0-9])$")


def parse_local_time(text: str) -> int | None:
    """Minutes after midnight of a 24-hour ``"HH:MM"``, or None if ``text`` is not one."""
    m = _HH_MM.match(text)
    return None if m is None else int(m.group(1)) * 60 + int(m.group(2))


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
        "optimiser and the baseline need outdoor air and irradiance)", choices=tuple(SENSORS))
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
    manual_hold_min: float = setting(
        120.0, doc="How long the daemon leaves the actuators alone after a person moved them "
        "(detected) or an operator held them without --hold; wind protection still acts",
        unit="min", ge=1, le=10080)
    manual_reset_local: str | int | None = setting(
        None, doc="Daily time (24-hour \"HH:MM\", panel local time site.utc_offset_h) at which "
        "a detected hold, or an operator hold without --hold, ends at the latest; null: none")

    @property
    def manual_reset_minute(self) -> int | None:
        """The daily reset in minutes after local midnight, None if there is none."""
        reset = self.manual_reset_local
        return parse_local_time(reset) if isinstance(reset, str) else None

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
        reset = self.manual_reset_local
        if isinstance(reset, int):  # YAML 1.1 reads an unquoted 22:00 as the number 1320
            out.append(Problem("manual_reset_local", reset, 'expected a time in quotes, '
                               '"HH:MM" (YAML reads an unquoted 22:00 as a number)'))
        elif reset is not None and parse_local_time(reset) is None:
            out.append(Problem("manual_reset_local", reset,
                               'expected a 24-hour local time "HH:MM", e.g. "22:00"'))
        if self.safe_state.afr == 10 and self.safe_state.or_pct != 0.0:
            out.append(Problem("safe_state.or_pct", self.safe_state.or_pct,
                               "regime 10 has every damper closed; use 0"))
        return out
