"""Settings of the devices dsfd talks to: Modbus TCP/RTU register maps and the weather station.

YAML shape (the ``devices:`` section of a panel file)::

    devices:
      read_budget_s: 15          # worst-case I/O time of all reads in one cycle
      write_budget_s: 10         # worst-case I/O time of all writes + read-backs
      entries:
        - name: facade-io
          kind: modbus_tcp       # modbus_tcp | modbus_rtu | serial_station
          tcp: {host: 192.168.10.20, port: 502}
          device_id: 1
          sensors:
            - {signal: x1_c, address: 0, data_type: float32}
          actuators:
            - {signal: phi_deg, address: 100, data_type: int16, scale: 0.1}
          override_input: {table: coil, address: 0}   # optional: wall switch / BMS hand flag

Errors name the key path, e.g. ``devices.entries[0].sensors[3].address``.

Worst-case I/O time per cycle (checked against the budgets, summed over all devices even
though drivers on different links run concurrently, so the check is conservative):

* Modbus read:  ``timeout_s · (1 + (retries + 1) · read_blocks)`` — one connect attempt plus
  every block timing out on every attempt; the driver enforces it as a hard cap. An
  ``override_input`` is one more block.
* Modbus write: ``timeout_s · (1 + (retries + 1) · (write_blocks + read_back_blocks))``.
* Station read: ``2 · timeout_s`` (drain deadline plus one serial read timeout).
"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import dataclass
from typing import Literal

from dsfd.config.loader import Problem, setting
from dsfd.registers import (
    BIT_TABLES,
    RegisterPoint,
    overlaps,
    plan_reads,
    plan_writes,
    register_count,
)
from dsfd.signals import ACTUATORS, SENSORS

__all__ = [
    "STATION_SIGNALS",
    "ActuatorPoint",
    "DeviceConfig",
    "Devices",
    "FeedbackPoint",
    "OverrideInput",
    "SensorPoint",
    "SerialLine",
    "TcpEndpoint",
]

#: Signals the serial weather station delivers, in line order (docs/weather-station-protocol.md).
STATION_SIGNALS: tuple[str, ...] = (
    "t_out_c", "ghi_wm2", "wind_speed_ms", "wind_dir_deg", "rh_pct", "pressure_hpa",
)

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")


@dataclass(frozen=True, kw_only=True)
class TcpEndpoint:
    host: str = setting(doc="Host name or IP address of the Modbus TCP device or gateway")
    port: int = setting(502, doc="TCP port", ge=1, le=65535)


@dataclass(frozen=True, kw_only=True)
class SerialLine:
    port: str = setting(doc="Serial device path (/dev/ttyUSB0) or pyserial URL (socket://, loop://)")
    baudrate: int = setting(19200, doc="Line speed", unit="bit/s", ge=300, le=921600)
    bytesize: Literal[7, 8] = setting(8, doc="Data bits per character")
    parity: Literal["N", "E", "O"] = setting("N", doc="Parity: none, even, odd")
    stopbits: Literal[1, 2] = setting(1, doc="Stop bits")


@dataclass(frozen=True, kw_only=True)
class _Register:
    signal: str = setting(doc="Signal name from dsfd.signals, unit in the name")
    address: int = setting(doc="First register, 0-based protocol address", ge=0, le=65535)
    data_type: Literal["int16", "uint16", "int32", "uint32", "float32"] = setting(
        "float32", doc="Raw type on the device")
    word_order: Literal["big", "little"] = setting(
        "big", doc="Register order of 32-bit values (little = CDAB word swap)")
    byte_order: Literal["big", "little"] = setting(
        "big", doc="Byte order inside each register (little = BADC byte swap)")
    scale: float = setting(1.0, doc="Engineering value = raw · scale + offset",
                           unit="signal unit per raw count")
    offset: float = setting(0.0, doc="Engineering value = raw · scale + offset",
                            unit="signal unit")

    def _register_problems(self, nan_value: int | None = None) -> list[Problem]:
        out: list[Problem] = []
        width = register_count(self.data_type)
        if self.address + width - 1 > 0xFFFF:
            out.append(Problem("address", self.address,
                               f"a {self.data_type} needs {width} registers below 65536"))
        if self.scale == 0.0:
            out.append(Problem("scale", self.scale, "must not be zero"))
        bits = 16 * width
        if nan_value is not None and not -(1 << (bits - 1)) <= nan_value < (1 << bits):
            out.append(Problem("nan_value", nan_value, f"does not fit {bits} bits"))
        return out

    def point(self) -> RegisterPoint:
        """The register-map entry of this point."""
        raise NotImplementedError


@dataclass(frozen=True, kw_only=True)
class SensorPoint(_Register):
    signal: str = setting(doc="Measured signal (dsfd.signals), unit in the name",
                          choices=tuple(SENSORS))
    table: Literal["input", "holding", "coil", "discrete_input"] = setting(
        "input", doc="Register table, or a bit (coil FC 1, discrete input FC 2) for a 0/1 "
        "signal such as occupied; a bit ignores data_type and the orders")
    nan_value: int | None = setting(
        None, doc="Raw 'no value' code, e.g. 0x7FFF (bit pattern; negative = two's complement)")

    def check(self) -> list[Problem]:
        if self.signal not in SENSORS:
            return [Problem("signal", self.signal,
                            f"not a sensor signal; known: {', '.join(SENSORS)}")]
        if self.table in BIT_TABLES:
            return self._bit_problems()
        return self._register_problems(self.nan_value)

    def _bit_problems(self) -> list[Problem]:
        binary = tuple(n for n, s in SENSORS.items() if s.integer and s.upper - s.lower == 1)
        if self.signal not in binary:
            return [Problem("table", self.table, f"a bit holds only a 0/1 signal "
                            f"({', '.join(binary)}); {self.signal} needs a register")]
        if self.nan_value is not None:
            return [Problem("nan_value", self.nan_value, f"a {self.table} has no 'no value' "
                            "code; remove it")]
        return [Problem("scale", self.scale, "must not be zero")] if self.scale == 0.0 else []

    def point(self) -> RegisterPoint:
        return RegisterPoint(name=self.signal, address=self.address, table=self.table,
                             data_type=self.data_type, word_order=self.word_order,
                             byte_order=self.byte_order, scale=self.scale, offset=self.offset,
                             nan_value=self.nan_value)


@dataclass(frozen=True, kw_only=True)
class FeedbackPoint:
    """Where an actuator reports the position it has reached (a motor controller's "actual
    position", distinct from its set-point). Read by ``dsfd commission``; the daemon verifies
    the set-point register."""

    table: Literal["input", "holding"] = setting("input", doc="Register table")
    address: int = setting(doc="First register, 0-based protocol address", ge=0, le=65535)
    data_type: Literal["int16", "uint16", "int32", "uint32", "float32"] = setting(
        "int16", doc="Raw type on the device")
    word_order: Literal["big", "little"] = setting("big", doc="Register order of 32-bit values")
    byte_order: Literal["big", "little"] = setting("big", doc="Byte order inside each register")
    scale: float = setting(1.0, doc="Position = raw · scale + offset",
                           unit="actuator unit per raw count")
    offset: float = setting(0.0, doc="Position = raw · scale + offset", unit="actuator unit")

    def check(self) -> list[Problem]:
        out = []
        if self.scale == 0.0:
            out.append(Problem("scale", self.scale, "must not be zero"))
        if self.address + register_count(self.data_type) - 1 > 0xFFFF:
            out.append(Problem("address", self.address, "registers beyond 65535"))
        return out

    def point(self, signal: str) -> RegisterPoint:
        """The register-map entry of the feedback of actuator ``signal``."""
        return RegisterPoint(name=signal, address=self.address, table=self.table,
                             data_type=self.data_type, word_order=self.word_order,
                             byte_order=self.byte_order, scale=self.scale, offset=self.offset)


@dataclass(frozen=True, kw_only=True)
class ActuatorPoint(_Register):
    signal: str = setting(doc="Commanded signal (dsfd.signals), unit in the name",
                          choices=tuple(ACTUATORS))
    table: Literal["holding"] = setting("holding", doc="Actuators live in holding registers")
    feedback: FeedbackPoint | None = setting(
        None, doc="Optional position feedback register (the position reached, as the motor "
        "controller reports it); dsfd commission checks it against the set-point")

    def check(self) -> list[Problem]:
        if self.signal not in ACTUATORS:
            return [Problem("signal", self.signal,
                            f"not an actuator signal; known: {', '.join(ACTUATORS)}")]
        return self._register_problems()

    def point(self) -> RegisterPoint:
        return RegisterPoint(name=self.signal, address=self.address, table="holding",
                             data_type=self.data_type, word_order=self.word_order,
                             byte_order=self.byte_order, scale=self.scale, offset=self.offset)


@dataclass(frozen=True, kw_only=True)
class OverrideInput:
    """A hand/auto signal: while it is active the daemon holds the panel (manual hold)."""

    table: Literal["coil", "discrete_input", "holding"] = setting(
        doc="Where the signal lives: a coil (FC 1), a discrete input (FC 2) or a holding "
        "register (FC 3, active while non-zero)")
    address: int = setting(doc="Coil, input or register address, 0-based", ge=0, le=65535)
    invert: bool = setting(False, doc="true: active while the signal reads 0 (a normally "
                           "closed contact)")

    def where(self) -> str:
        return f"{self.table.replace('_', ' ')} {self.address}"


@dataclass(frozen=True, kw_only=True)
class DeviceConfig:
    """One device: a Modbus server (TCP or an RTU slave) or the serial weather station."""

    name: str = setting(doc="Device name used in logs and reading details")
    kind: Literal["modbus_tcp", "modbus_rtu", "serial_station"] = setting(
        doc="Protocol: Modbus TCP, Modbus RTU on a serial line, or the serial weather station")
    tcp: TcpEndpoint | None = setting(None, doc="Endpoint of a modbus_tcp device")
    serial: SerialLine | None = setting(None, doc="Line of a modbus_rtu device or the station")
    device_id: int = setting(1, doc="Modbus device (slave/unit) id", ge=0, le=255)
    timeout_s: float = setting(1.0, doc="Per-attempt response timeout; station: read window",
                               unit="s", gt=0, le=30)
    retries: int = setting(1, doc="Extra attempts after a timeout (attempts = retries + 1)",
                           ge=0, le=10)
    reconnect_backoff_min_s: float = setting(1.0, doc="First delay after a failed connect",
                                             unit="s", gt=0, le=3600)
    reconnect_backoff_max_s: float = setting(60.0, doc="Delay cap, doubling from the minimum",
                                             unit="s", gt=0, le=3600)
    breaker_failures: int = setting(
        2, doc="Consecutive cycles with timeouts that open the circuit breaker", ge=1, le=100)
    breaker_cycles: int = setting(
        5, doc="Cycles a tripped device is skipped before one trial poll", ge=0, le=1000)
    max_read_gap: int = setting(
        0, doc="Unmapped registers a block read may span (0: contiguous only; >0 only for "
        "devices that answer reads of unmapped registers)", ge=0, le=124)
    sensors: tuple[SensorPoint, ...] = setting((), doc="Measured signals and their registers")
    actuators: tuple[ActuatorPoint, ...] = setting((), doc="Commanded signals and registers")
    override_input: OverrideInput | None = setting(
        None, doc="Optional wall switch or BMS hand flag: while it is set the daemon writes "
        "nothing (manual hold; wind protection still acts)")

    @property
    def is_modbus(self) -> bool:
        return self.kind != "serial_station"

    def sensor_points(self) -> tuple[RegisterPoint, ...]:
        return tuple(s.point() for s in self.sensors)

    def actuator_points(self) -> tuple[RegisterPoint, ...]:
        return tuple(a.point() for a in self.actuators)

    def feedback_points(self) -> tuple[RegisterPoint, ...]:
        """Position feedback registers, named after their actuators."""
        return tuple(a.feedback.point(a.signal) for a in self.actuators
                     if a.feedback is not None)

    def signal_names(self) -> tuple[str, ...]:
        """Sensor signals this device delivers (the station's are fixed by its protocol)."""
        if not self.is_modbus:
            return STATION_SIGNALS
        return tuple(s.signal for s in self.sensors)

    def link_key(self) -> str:
        """Identity of the physical link; devices with the same key share one client."""
        if self.tcp is not None and self.kind == "modbus_tcp":
            return f"tcp://{self.tcp.host}:{self.tcp.port}"
        return f"serial:{self.serial.port}" if self.serial is not None else f"?{self.name}"

    def worst_case_read_s(self) -> float:
        """Upper bound of one cycle's read time [s] (see module docstring)."""
        if not self.is_modbus:
            return 2.0 * self.timeout_s
        blocks = len(plan_reads(self.sensor_points(), max_gap=self.max_read_gap))
        blocks += self.override_input is not None
        if not blocks:
            return 0.0
        return self.timeout_s * (1 + (self.retries + 1) * blocks)

    def worst_case_write_s(self) -> float:
        """Upper bound of one write with read-back [s] (see module docstring)."""
        if not self.is_modbus or not self.actuators:
            return 0.0
        points = self.actuator_points()
        blocks = len(plan_writes(points)) + len(plan_reads(points))
        return self.timeout_s * (1 + (self.retries + 1) * blocks)

    def check(self) -> list[Problem]:
        out: list[Problem] = []
        if not _NAME.match(self.name):
            out.append(Problem("name", self.name, "use letters, digits, '_', '-', '.'"))
        if self.reconnect_backoff_min_s > self.reconnect_backoff_max_s:
            out.append(Problem("reconnect_backoff_min_s", self.reconnect_backoff_min_s,
                               f"above reconnect_backoff_max_s {self.reconnect_backoff_max_s}"))
        if self.kind == "modbus_tcp":
            if self.tcp is None:
                out.append(Problem("tcp", None, "required for kind modbus_tcp"))
            if self.serial is not None:
                out.append(Problem("serial", "...", "not used by kind modbus_tcp; remove it"))
        else:
            if self.serial is None:
                out.append(Problem("serial", None, f"required for kind {self.kind}"))
            if self.tcp is not None:
                out.append(Problem("tcp", "...", f"not used by kind {self.kind}; remove it"))
        if not self.is_modbus:
            for key in ("sensors", "actuators", "override_input"):
                if getattr(self, key):
                    out.append(Problem(key, "...", "a serial_station delivers the fixed "
                                       f"fields {', '.join(STATION_SIGNALS)}; remove {key}"))
            return out
        if not self.sensors and not self.actuators and self.override_input is None:
            out.append(Problem("sensors", (), "a Modbus device needs sensors, actuators or an "
                               "override_input"))
        seen: dict[str, str] = {}
        for key, points in (("sensors", self.sensors), ("actuators", self.actuators)):
            for i, p in enumerate(points):
                if p.signal in seen:
                    out.append(Problem(f"{key}[{i}].signal", p.signal,
                                       f"already mapped at {seen[p.signal]}"))
                seen.setdefault(p.signal, f"{key}[{i}]")
        if out:
            return out
        out += self._overlap_problems()
        return out + self._override_input_problems()

    def _override_input_problems(self) -> list[Problem]:
        oi = self.override_input
        if oi is None:
            return []
        what = f"holding register {oi.address}" if oi.table == "holding" else oi.where()
        for key, entries in (("sensors", self.sensors), ("actuators", self.actuators)):
            for i, entry in enumerate(entries):
                p = entry.point()
                if p.table == oi.table and p.address <= oi.address < p.end:
                    return [Problem("override_input.address", oi.address,
                                    f"{what} is already {key}[{i}] "
                                    f"({p.address}..{p.end - 1})")]
        return []

    def _overlap_problems(self) -> list[Problem]:
        # Runs only when every point passed its own check, so point() cannot fail here.
        where: dict[int, str] = {}
        points: list[RegisterPoint] = []
        for key, entries in (("sensors", self.sensors), ("actuators", self.actuators)):
            for i, entry in enumerate(entries):
                p = entry.point()
                where[id(p)] = f"{key}[{i}]"
                points.append(p)
                fb = getattr(entry, "feedback", None)
                if fb is not None:
                    q = fb.point(entry.signal)
                    where[id(q)] = f"{key}[{i}].feedback"
                    points.append(q)
        return [Problem(f"{where[id(b)]}.address", b.address,
                        f"{b.table} registers {b.address}..{b.end - 1} overlap "
                        f"{where[id(a)]} ({a.address}..{a.end - 1})")
                for a, b in overlaps(points)]


@dataclass(frozen=True, kw_only=True)
class Devices:
    """All devices of one panel and the per-cycle I/O time budgets."""

    read_budget_s: float = setting(15.0, doc="Worst-case read time allowed per cycle",
                                   unit="s", gt=0, le=3600)
    write_budget_s: float = setting(10.0, doc="Worst-case write + read-back time per cycle",
                                    unit="s", gt=0, le=3600)
    entries: tuple[DeviceConfig, ...] = setting(doc="The devices, Modbus and serial")

    def sensor_signals(self) -> frozenset[str]:
        """Sensor signals the devices deliver together."""
        return frozenset(s for d in self.entries for s in d.signal_names())

    def by_name(self, name: str) -> DeviceConfig:
        for d in self.entries:
            if d.name == name:
                return d
        raise KeyError(name)

    def check(self) -> list[Problem]:
        out: list[Problem] = []
        if not self.entries:
            return [Problem("entries", (), "list at least one device")]
        names: dict[str, int] = {}
        signal_at: dict[str, str] = {}
        links: dict[str, list[int]] = defaultdict(list)
        for i, d in enumerate(self.entries):
            if d.name in names:
                out.append(Problem(f"entries[{i}].name", d.name,
                                   f"duplicate of entries[{names[d.name]}].name"))
            names.setdefault(d.name, i)
            listed = [("sensors", j, n) for j, n in enumerate(d.signal_names())]
            listed += [("actuators", j, a.signal) for j, a in enumerate(d.actuators)]
            for key, j, sig in listed:
                here = f"entries[{i}].{key}[{j}].signal" if d.is_modbus else f"entries[{i}]"
                if sig in signal_at:
                    out.append(Problem(here if d.is_modbus else f"entries[{i}].kind", sig,
                                       f"{sig} is already delivered by {signal_at[sig]}"))
                signal_at.setdefault(sig, here)
            links[d.link_key()].append(i)
        with_input = [i for i, d in enumerate(self.entries) if d.override_input is not None]
        out += [Problem(f"entries[{i}].override_input", "...", f"entries[{with_input[0]}] "
                        "already has the panel's override input; give only one")
                for i in with_input[1:]]
        for members in links.values():
            out += self._shared_link_problems(members)
        out += self._budget_problems()
        return out

    def _shared_link_problems(self, members: list[int]) -> list[Problem]:
        if len(members) < 2:
            return []
        first = self.entries[members[0]]
        out: list[Problem] = []
        ids = {first.device_id: members[0]}
        for i in members[1:]:
            d = self.entries[i]
            if d.kind != first.kind or not d.is_modbus:
                out.append(Problem(f"entries[{i}].kind", d.kind,
                                   f"shares its port with entries[{members[0]}] "
                                   f"({first.kind}); only Modbus devices of one kind can"))
                continue
            for key in ("serial", "timeout_s", "retries", "reconnect_backoff_min_s",
                        "reconnect_backoff_max_s"):
                if getattr(d, key) != getattr(first, key):
                    out.append(Problem(f"entries[{i}].{key}", getattr(d, key),
                                       f"devices on one link share a client: must equal "
                                       f"entries[{members[0]}].{key}"))
            if d.device_id in ids:
                out.append(Problem(f"entries[{i}].device_id", d.device_id,
                                   f"same link and id as entries[{ids[d.device_id]}]"))
            ids.setdefault(d.device_id, i)
        return out

    def _budget_problems(self) -> list[Problem]:
        out: list[Problem] = []
        for key, cost in (("read_budget_s", DeviceConfig.worst_case_read_s),
                          ("write_budget_s", DeviceConfig.worst_case_write_s)):
            budget = getattr(self, key)
            parts = {d.name: cost(d) for d in self.entries}
            total = sum(parts.values())
            if total > budget:
                shown = ", ".join(f"{n} {s:.3g} s" for n, s in parts.items())
                out.append(Problem(key, budget,
                                   f"worst case {total:.3g} s exceeds the budget ({shown}); "
                                   f"lower timeout_s/retries or merge register blocks"))
        return out
