"""Canonical names of the signals that cross the edge of dsfd, with units and plausible ranges.

Every measurement a driver delivers and every actuator value the controller commands is
named here, once. The unit is part of the name (``x1_c`` is in °C, ``ghi_wm2`` in W/m²),
so a value never travels without it. Each signal carries a *physical plausibility* range:
values outside it cannot be real for a façade panel in service (a broken thermocouple, a
mis-scaled register) and are flagged by the quality checks later in the cycle. The ranges are
deliberately wide; they catch nonsense, not unusual weather.

States ``x1``..``x5`` keep the paper's names (docs/model.md#states); ``x6`` (the gas in the
DGU gap) is estimated, never measured, so it has no signal.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Literal

__all__ = [
    "ACTUATORS",
    "ACTUATOR_NAMES",
    "SENSORS",
    "SENSOR_NAMES",
    "SIGNALS",
    "Signal",
    "is_actuator",
    "is_sensor",
    "signal",
]


@dataclass(frozen=True, kw_only=True)
class Signal:
    """One named quantity at the boundary of dsfd.

    Attributes
    ----------
    name : str
        Canonical name with the unit as suffix, e.g. ``t_out_c``.
    role : {"sensor", "actuator"}
        Whether dsfd reads it or writes it.
    unit : str
        Human-readable unit (``degC``, ``W/m2``, ``m/s``, ``deg``, ``%``, ``hPa``, ``1``).
    lower, upper : float
        Inclusive physical plausibility range, in ``unit``. For actuators this is the
        command range the device accepts.
    integer : bool
        True if only whole numbers are meaningful (the airflow regime).
    doc : str
        What the signal is.
    """

    name: str
    role: Literal["sensor", "actuator"]
    unit: str
    lower: float
    upper: float
    doc: str
    integer: bool = False

    def plausible(self, value: float) -> bool:
        """True if ``value`` [unit] lies inside the plausibility range (NaN is not) and,
        for an integer signal, is a whole number."""
        return self.lower <= value <= self.upper and (not self.integer or value == int(value))


def _sensor(name: str, unit: str, lower: float, upper: float, doc: str, *,
            integer: bool = False) -> Signal:
    return Signal(name=name, role="sensor", unit=unit, lower=lower, upper=upper, doc=doc,
                  integer=integer)


# Glass and slat temperatures: a dark slat or an absorbing pane in summer sun reaches 70-90 °C;
# -40 °C covers a winter night anywhere dsfd is likely to run.
_SENSORS = (
    _sensor("x1_c", "degC", -40.0, 100.0, "Exterior single pane, cavity-side surface (x1)"),
    _sensor("x2_c", "degC", -40.0, 100.0, "Interior DGU outer pane (x2)"),
    _sensor("x3_c", "degC", -40.0, 100.0, "Interior DGU inner pane (x3)"),
    _sensor("x4_c", "degC", -40.0, 110.0, "Louver slat (x4)"),
    _sensor("x5_c", "degC", -40.0, 90.0, "Cavity air (x5)"),
    _sensor("t_room_c", "degC", 0.0, 50.0, "Room air behind the panel"),
    _sensor("t_out_c", "degC", -50.0, 60.0, "Outdoor air (weather station)"),
    # Thermopile pyranometers read a few W/m2 below zero at night (thermal offset); cloud
    # enhancement can exceed the solar constant briefly.
    _sensor("ghi_wm2", "W/m2", -10.0, 1600.0, "Global horizontal irradiance"),
    _sensor("wind_speed_ms", "m/s", 0.0, 75.0, "Wind speed at the station"),
    _sensor("wind_dir_deg", "deg", 0.0, 360.0, "Wind direction, from north clockwise, 'from'"),
    _sensor("v_cav_ms", "m/s", 0.0, 10.0, "Cavity air speed (anemometer, unsigned)"),
    _sensor("rh_pct", "%", 0.0, 100.0, "Outdoor relative humidity"),
    _sensor("pressure_hpa", "hPa", 800.0, 1100.0, "Station air pressure"),
    # A presence sensor or the BMS's occupancy flag; while GOOD it overrides the schedule
    # (docs/model.md#occupancy). A register reading 0.5 or 2 is a mis-mapping, not a state.
    _sensor("occupied", "1", 0.0, 1.0, "Room behind the panel occupied: 1 yes, 0 no "
            "(presence sensor or BMS flag)", integer=True),
)

_ACTUATORS = (
    Signal(name="phi_deg", role="actuator", unit="deg", lower=-90.0, upper=90.0,
           doc="Louver slat angle, 0 = horizontal"),
    Signal(name="afr", role="actuator", unit="1", lower=1.0, upper=10.0, integer=True,
           doc="Airflow regime number 1..10 (docs/model.md#regimes)"),
    Signal(name="or_pct", role="actuator", unit="%", lower=0.0, upper=100.0,
           doc="Damper opening ratio of the open damper set"),
)

#: Sensor signals by name.
SENSORS: MappingProxyType[str, Signal] = MappingProxyType({s.name: s for s in _SENSORS})
#: Actuator signals by name.
ACTUATORS: MappingProxyType[str, Signal] = MappingProxyType({s.name: s for s in _ACTUATORS})
#: All signals by name.
SIGNALS: MappingProxyType[str, Signal] = MappingProxyType({**SENSORS, **ACTUATORS})
#: Sensor names in declaration order.
SENSOR_NAMES: tuple[str, ...] = tuple(SENSORS)
#: Actuator names in declaration order (also the field order of :class:`Command`).
ACTUATOR_NAMES: tuple[str, ...] = tuple(ACTUATORS)


def signal(name: str) -> Signal:
    """The :class:`Signal` called ``name``; ``KeyError`` naming the known ones otherwise."""
    try:
        return SIGNALS[name]
    except KeyError:
        raise KeyError(f"unknown signal {name!r}; known: {', '.join(SIGNALS)}") from None


def is_sensor(name: str) -> bool:
    """True if ``name`` is a known sensor signal."""
    return name in SENSORS


def is_actuator(name: str) -> bool:
    """True if ``name`` is a known actuator signal."""
    return name in ACTUATORS
