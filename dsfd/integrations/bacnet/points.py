"""The BACnet points of a panel: which object shows what, and each one's value for a cycle.

Pure (no bacpypes3, no I/O). :data:`POINTS` is the object table docs/bacnet.md lists;
:func:`point_values` maps one cycle's state — the same mapping the MQTT state topic
publishes (:func:`dsfd.integrations.mqtt.messages.state_message`) — to each point's present
value and fault flag, so the two views of a cycle cannot disagree.

Engineering units are BACnet's ``BACnetEngineeringUnits`` names (ASHRAE 135-2020 clause 21);
a point's COV increment is the smallest change of its present value that is notified to a
SubscribeCOV subscriber (clause 13.1.3), chosen near each signal's resolution: 0.1 K for
temperatures, 0.05 m/s, 5 W/m2, 5 W, one louver motor step, one damper step.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from dsfd.config import PanelConfig
from dsfd.config.panel import REGIME_NAMES
from dsfd.daemon.commands import OBJECTIVE_MODES

__all__ = ["COMMAND_FIELDS", "OBJECTIVE_STATES", "POINTS", "Point", "PointValue", "point_values",
           "points_for", "regime_states"]

#: The multi-state value of the control objective: state 1, 2, 3.
OBJECTIVE_STATES: tuple[str, ...] = OBJECTIVE_MODES
#: Commandable point key → the field of an ``override`` request it commands.
COMMAND_FIELDS: dict[str, str] = {"louver": "louver_deg", "regime": "regime",
                                  "damper": "or_pct"}


@dataclass(frozen=True)
class Point:
    """One BACnet object of the panel's device.

    ``path`` is where its value is in the state message (dotted); ``kind`` is ``ai``
    (analog input), ``av`` (analog value), ``msv`` (multi-state value), ``bv`` (binary
    value) or ``csv`` (character string value); ``commandable``: has a priority array.
    """

    key: str
    kind: str
    instance: int
    name: str
    path: str
    units: str | None = None
    cov_increment: float | None = None
    writable: bool = False
    commandable: bool = False
    #: The sample signal whose quality sets the fault flag (None: the point's own rule).
    signal: str | None = None


def _ai(instance: int, key: str, name: str, path: str, units: str, inc: float,
        signal: str | None = None) -> Point:
    return Point(key, "ai", instance, name, path, units, inc, signal=signal)


#: Every object but the device and its network port, in object-list order.
POINTS: tuple[Point, ...] = (
    _ai(1, "x1", "x1 exterior pane", "measured.x1_c", "degreesCelsius", 0.1, "x1_c"),
    _ai(2, "x2", "x2 interior DGU outer pane", "measured.x2_c", "degreesCelsius", 0.1, "x2_c"),
    _ai(3, "x3", "x3 interior DGU inner pane", "measured.x3_c", "degreesCelsius", 0.1, "x3_c"),
    _ai(4, "x4", "x4 louver slat", "measured.x4_c", "degreesCelsius", 0.1, "x4_c"),
    _ai(5, "x5", "x5 cavity air", "measured.x5_c", "degreesCelsius", 0.1, "x5_c"),
    _ai(6, "v_cav", "cavity air speed", "measured.v_cav_ms", "metersPerSecond", 0.05,
        "v_cav_ms"),
    _ai(7, "t_out", "outdoor air", "measured.t_out_c", "degreesCelsius", 0.1, "t_out_c"),
    _ai(8, "ghi", "global horizontal irradiance", "measured.ghi_wm2", "wattsPerSquareMeter",
        5.0, "ghi_wm2"),
    _ai(9, "q_sol_trans", "heat into room solar transmitted", "heat_w.q_sol_trans", "watts",
        5.0),
    _ai(10, "q_cv_rd", "heat into room convective and long-wave", "heat_w.q_cv_rd", "watts",
        5.0),
    _ai(11, "q_air", "heat into room ventilation air", "heat_w.q_air", "watts", 5.0),
    _ai(12, "q_da", "heat into room daylight credit", "heat_w.q_da", "watts", 5.0),
    _ai(13, "decision_time", "decision time", "decision_ms", "milliseconds", 50.0),
    _ai(14, "calibration_age", "calibration age", "calibration_age_s", "seconds", 60.0),
    _ai(15, "cycle", "stored cycle", "cycle", "noUnits", 1.0),
    Point("louver", "av", 1, "louver angle", "command.louver_deg", "degreesAngular", None,
          writable=True, commandable=True),
    Point("damper", "av", 2, "damper opening", "command.damper_pct", "percent", None,
          writable=True, commandable=True),
    Point("regime", "msv", 1, "airflow regime", "command.regime", writable=True,
          commandable=True),
    Point("objective", "msv", 2, "control objective", "objective_mode", writable=True),
    Point("fault", "bv", 1, "fault", "fault"),
    Point("set_by", "csv", 1, "command set by", "set_by"),
)


def points_for(cfg: PanelConfig) -> tuple[Point, ...]:
    """The panel's points, with the COV increments of its motor grid (a louver step, a damper
    step); a panel without a louver has no louver object."""
    out = []
    for p in POINTS:
        if p.key == "louver":
            if cfg.louver is None:
                continue
            p = Point(**{**p.__dict__, "cov_increment": cfg.louver.step_deg})
        elif p.key == "damper":
            p = Point(**{**p.__dict__, "cov_increment": cfg.safety.or_step_pct})
        out.append(p)
    return tuple(out)


def regime_states() -> list[str]:
    """State texts of the regime multi-state value: state N is airflow regime N."""
    return [REGIME_NAMES[n] for n in range(1, 11)]


@dataclass(frozen=True)
class PointValue:
    """A point's present value for one cycle (None: no value this cycle, keep the last one)
    and whether its fault flag is set."""

    value: float | int | bool | str | None
    fault: bool


def _at(message: Mapping[str, Any], path: str) -> Any:
    value: Any = message
    for part in path.split("."):
        value = value.get(part) if isinstance(value, Mapping) else None
    return value


def _set_by(message: Mapping[str, Any]) -> str:
    if message.get("hold"):
        by = message.get("hold_by") or ""
        return f"{message.get('hold_source')} hold" + (f" ({by})" if by else "")
    return str(message.get("set_by") or "")


def point_values(points: tuple[Point, ...], message: Mapping[str, Any]
                 ) -> dict[str, PointValue]:
    """Each point's value in one cycle's state message."""
    flagged = message.get("flagged") or {}
    write_failed = message.get("write") == "failed"
    out: dict[str, PointValue] = {}
    for p in points:
        raw = _at(message, p.path)
        if p.key == "objective":
            value: Any = OBJECTIVE_STATES.index(raw) + 1 if raw in OBJECTIVE_STATES else None
            out[p.key] = PointValue(value, False)
        elif p.key == "set_by":
            out[p.key] = PointValue(_set_by(message), False)
        elif p.kind == "bv":
            out[p.key] = PointValue(bool(raw), False)
        elif p.kind == "msv":
            out[p.key] = PointValue(None if raw is None else int(raw), write_failed)
        else:
            fault = (p.signal in flagged) if p.signal is not None else (
                write_failed if p.commandable else raw is None)
            out[p.key] = PointValue(None if raw is None else float(raw), fault)
    return out
