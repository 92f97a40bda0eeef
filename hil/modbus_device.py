"""Emulated Modbus device (pymodbus 3.16 server) serving a dsfd register map, with faults.

The device is a pymodbus ``SimDevice`` in the 4-block form (coils, discrete inputs, holding,
input as separate tables; the shared form would alias input register N with holding register
N). Each configured point gets its own ``SimData`` span, so reads of unmapped registers get
ILLEGAL_ADDRESS like a strict real device — unless ``fill_gaps=True``, which maps every
register between a table's first and last point.

Values are set in engineering units and encoded with the same :mod:`dsfd.registers`
map the driver decodes with. Faults:

* :meth:`EmulatedModbusDevice.stop` / :meth:`resume` — device down / back (register contents
  survive, as in a device whose network drops);
* ``busy = True`` — every client request gets exception 6 (DEVICE_BUSY);
* ``silent = True`` — requests are processed but no answer is sent (timeouts);
* ``frozen_actuators = True`` — writes are acknowledged but do not change the registers
  (a stuck motor; read-back verification must catch it);
* :meth:`serve_nan` — a float32 point serves NaN, an integer point its ``nan_value`` code;
* ``short_reads = True`` — register reads are answered with one register fewer than asked
  (a device with a wrong register map).

Motors: an actuator with a position feedback register (``feedback_points``) is driven by a
motor model while the server runs: the feedback follows the set-point register at
``motor_rates`` [signal unit/s] (a regime switches when its travel time has passed); without
a rate the feedback follows at once.

A person at the panel: :meth:`move_actuators` changes the actuator registers the way a
motor controller's local buttons would (not through a client request, so not counted in
``writes``); :meth:`set_override_input` flips the panel's hand/auto input (a coil, discrete
input or holding register, from the device's ``override_input``).

Run standalone against a panel file::

    python -m hil.modbus_device --config config/panels/PANEL.yaml --port 5020 [--device NAME]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import math
from collections import Counter
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from pymodbus.constants import ExcCodes
from pymodbus.pdu import ModbusPDU
from pymodbus.server import ModbusSerialServer, ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

from dsfd.registers import RegisterPoint, decode, encode, from_pattern
from dsfd.signals import ACTUATORS

if TYPE_CHECKING:
    from dsfd.config.devices import DeviceConfig, OverrideInput

__all__ = ["EmulatedModbusDevice"]

log = logging.getLogger(__name__)
_FC_READ = {"input": 4, "holding": 3, "coil": 1, "discrete_input": 2}
_OVERRIDE = "override_input"
_FEEDBACK = "feedback:"
#: Motor model time step [s].
_MOTOR_TICK_S = 0.005
_FC_WRITES = (6, 16)


class EmulatedModbusDevice:
    """A Modbus server for one device id, serving ``sensors`` and accepting ``actuators``."""

    def __init__(self, *, sensors: Sequence[RegisterPoint],
                 actuators: Sequence[RegisterPoint] = (), device_id: int = 1,
                 fill_gaps: bool = False, override_input: OverrideInput | None = None,
                 feedback_points: Sequence[RegisterPoint] = (),
                 motor_rates: Mapping[str, float] | None = None) -> None:
        self.device_id = device_id
        self.points: dict[str, RegisterPoint] = {p.name: p for p in (*sensors, *actuators)}
        #: Position feedback of the actuators, by actuator name (motor model, docstring).
        self.feedback = {p.name: p for p in feedback_points}
        for p in feedback_points:
            self.points[_FEEDBACK + p.name] = p
        self.motor_rates = dict(motor_rates or {})
        self._motor: asyncio.Task[None] | None = None
        self.actuators = tuple(actuators)
        self.fill_gaps = fill_gaps
        self.override_input = override_input
        if override_input is not None and override_input.table == "holding":
            self.points[_OVERRIDE] = RegisterPoint(name=_OVERRIDE, address=override_input.address,
                                                   table="holding", data_type="uint16")
        #: Fault switches (see module docstring).
        self.busy = False
        self.silent = False
        self.frozen_actuators = False
        self.short_reads = False
        #: Client requests received, by function code (also while busy or silent), and
        #: accepted client writes as (address, registers).
        self.requests: Counter[int] = Counter()
        self.writes: list[tuple[int, list[int]]] = []
        self._internal = False  # our own get/set also pass through the action hook
        self._server: ModbusTcpServer | ModbusSerialServer | None = None
        self._running = False
        self.device = SimDevice(id=device_id, simdata=self._tables(), action=self._action)

    @classmethod
    def from_config(cls, cfg: DeviceConfig, *, fill_gaps: bool = False,
                    motor_rates: Mapping[str, float] | None = None) -> EmulatedModbusDevice:
        """Emulator of a configured ``modbus_tcp``/``modbus_rtu`` device."""
        return cls(sensors=cfg.sensor_points(), actuators=cfg.actuator_points(),
                   device_id=cfg.device_id, fill_gaps=fill_gaps,
                   override_input=cfg.override_input, feedback_points=cfg.feedback_points(),
                   motor_rates=motor_rates)

    def _tables(self) -> tuple[list[SimData], list[SimData], list[SimData], list[SimData]]:
        # SimDevice rejects empty blocks; one invalid register keeps an unused table empty.
        def bits(table: str) -> list[SimData]:
            oi = self.override_input
            used = [p.address for p in self.points.values() if p.table == table]
            last = max([0, *used, *([oi.address] if oi is not None and oi.table == table
                                    else [])])
            return [SimData(0, count=16 * (last // 16 + 1), values=False,
                            datatype=DataType.BITS)]

        return (bits("coil"), bits("discrete_input"), self._table("holding"),
                self._table("input"))

    def _table(self, table: str) -> list[SimData]:
        pts = sorted((p for p in self.points.values() if p.table == table),
                     key=lambda p: p.address)
        if not pts:
            return [SimData(0, count=1, datatype=DataType.INVALID)]
        if self.fill_gaps:
            span = max(p.end for p in pts) - pts[0].address
            return [SimData(pts[0].address, values=[0] * span, datatype=DataType.REGISTERS)]
        return [SimData(p.address, values=[0] * p.count, datatype=DataType.REGISTERS)
                for p in pts]

    # ----------------------------------------------------------------------- lifecycle
    async def start_tcp(self, *, port: int, host: str = "127.0.0.1") -> None:
        """Serve Modbus TCP on ``host:port`` (must run inside the event loop)."""
        self._server = ModbusTcpServer(self.device, address=(host, port),
                                       trace_packet=self._trace_packet,
                                       trace_pdu=self._trace_pdu)
        await self.resume()

    async def start_rtu(self, *, port: str, baudrate: int = 19200, bytesize: int = 8,
                        parity: str = "N", stopbits: int = 1,
                        also: Sequence[EmulatedModbusDevice] = ()) -> None:
        """Serve Modbus RTU on serial ``port`` (a pty path from :class:`hil.pty_pair.PtyPair`).

        ``also``: further emulators (other device ids) on the same RS-485 line. They share
        this server: stop/resume the line and set ``silent`` through this emulator; ``busy``,
        ``frozen_actuators``, values and request counters stay per device.
        """
        line = {e.device_id: e for e in (self, *also)}

        def trace_pdu(sending: bool, pdu: ModbusPDU) -> ModbusPDU:
            owner = line.get(pdu.dev_id)
            return owner._trace_pdu(sending, pdu) if owner is not None else pdu

        self._server = ModbusSerialServer([e.device for e in line.values()], port=port,
                                          baudrate=baudrate, bytesize=bytesize, parity=parity,
                                          stopbits=stopbits, trace_packet=self._trace_packet,
                                          trace_pdu=trace_pdu)
        for other in also:
            other._server = self._server
        await self.resume()

    @property
    def running(self) -> bool:
        return self._running

    async def stop(self) -> None:
        """Device down: close the listener and every client connection."""
        if self._motor is not None:
            self._motor.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._motor
            self._motor = None
        if self._server is not None and self._running:
            await self._server.shutdown()
            self._running = False

    async def resume(self) -> None:
        """Device back, with the register contents it had."""
        if self._server is None:
            raise RuntimeError("call start_tcp() or start_rtu() first")
        if not self._running:
            await self._server.serve_forever(background=True)
            self._running = True
        if self.feedback and self._motor is None:
            self._motor = asyncio.create_task(self._run_motors())

    async def _run_motors(self) -> None:
        """Move each feedback toward its set-point at its rate (module docstring)."""
        clock = asyncio.get_running_loop().time
        moving: dict[str, tuple[float, float, float]] = {}  # name -> (from, to, start time)
        while True:
            for name in self.feedback:
                target = await self.value(name)
                position = await self.value(_FEEDBACK + name)
                start = moving.get(name)
                if start is None or start[1] != target:
                    if position == target:
                        moving.pop(name, None)
                        continue
                    start = moving[name] = (position, target, clock())
                await self.set_sensor(_FEEDBACK + name, _travel(
                    start, clock(), self.motor_rates.get(name), stepwise=_stepwise(name)))
                if await self.value(_FEEDBACK + name) == target:
                    moving.pop(name, None)
            await asyncio.sleep(_MOTOR_TICK_S)

    async def position(self, name: str) -> float:
        """The position actuator ``name``'s feedback register reports [signal unit]."""
        return await self.value(_FEEDBACK + name)

    async def set_position(self, name: str, value: float) -> None:
        """Put actuator ``name``'s motor at ``value`` (feedback and set-point registers)."""
        await self.set_sensor(name, value)
        await self.set_sensor(_FEEDBACK + name, value)

    # ----------------------------------------------------------------------- fault hooks
    async def _action(self, function_code: int, start_address: int, address: int, count: int,
                      registers: list[int], set_values: list[int] | list[bool] | None
                      ) -> ExcCodes | None:
        if self._internal:
            return None
        if self.busy:
            return ExcCodes.DEVICE_BUSY
        if function_code in _FC_WRITES and set_values is not None:
            self.writes.append((address, [int(v) for v in set_values]))
            if self.frozen_actuators:  # acknowledge, but keep the old contents
                first = address - start_address
                set_values[:] = registers[first:first + count]
        return None

    def _trace_packet(self, sending: bool, data: bytes) -> bytes:
        return b"" if sending and self.silent else data

    def _trace_pdu(self, sending: bool, pdu: ModbusPDU) -> ModbusPDU:
        # Count requests here, not in the action hook: pymodbus calls the action once per
        # datastore access, and FC 6 accesses it twice (set, then get for the echo).
        if not sending:
            self.requests[pdu.function_code] += 1
        elif self.short_reads and pdu.function_code in (3, 4) and len(pdu.registers) > 1:
            pdu.registers = pdu.registers[:-1]
        return pdu

    # ----------------------------------------------------------------------- values
    async def set_sensor(self, name: str, value: float) -> None:
        """Store engineering ``value`` [signal unit] in the point's registers."""
        p = self.points[name]
        await self.set_registers(name, encode(p, value))

    async def set_sensors(self, values: Mapping[str, float]) -> None:
        for name, value in values.items():
            await self.set_sensor(name, value)

    async def serve_nan(self, name: str) -> None:
        """Serve "no value": IEEE NaN for float32, else the point's ``nan_value`` code."""
        p = self.points[name]
        if p.data_type == "float32":
            await self.set_registers(name, encode(p, math.nan))
        elif p.nan_value is not None:
            await self.set_registers(name, from_pattern(p, p.nan_value))
        else:
            raise ValueError(f"{name}: integer point without nan_value cannot serve NaN")

    async def set_registers(self, name: str, registers: Sequence[int]) -> None:
        """Store raw ``registers`` in the point's address range."""
        p = self.points[name]
        if len(registers) != p.count:
            raise ValueError(f"{name} needs {p.count} registers")
        values: list[int] | list[bool] = list(registers)
        if p.is_bit:  # the bit tables hold booleans
            values = [bool(r) for r in registers]
        self._internal = True
        try:
            await self._require_server().async_setValues(self.device_id, _FC_READ[p.table],
                                                         p.address, values)
        finally:
            self._internal = False

    async def registers(self, name: str) -> list[int]:
        """Raw registers of point ``name``."""
        p = self.points[name]
        self._internal = True
        try:
            regs = await self._require_server().async_getValues(
                self.device_id, _FC_READ[p.table], p.address, p.count)
        finally:
            self._internal = False
        return [int(r) for r in regs]

    async def value(self, name: str) -> float:
        """Engineering value of point ``name``."""
        return decode(self.points[name], await self.registers(name))

    async def actuator_values(self) -> dict[str, float]:
        """Last commanded actuator values [signal units]."""
        return {p.name: await self.value(p.name) for p in self.actuators}

    async def move_actuators(self, values: Mapping[str, float]) -> None:
        """A person moves the panel at the motor controller: the actuator registers change
        without a client write (``writes`` does not count it)."""
        for name, value in values.items():
            if name not in {p.name for p in self.actuators}:
                raise KeyError(f"{name} is not an actuator of this device")
            await self.set_sensor(name, value)

    async def set_override_input(self, active: bool) -> None:
        """Set (True) or clear the hand/auto input as its wiring reads (``invert`` applied)."""
        oi = self.override_input
        if oi is None:
            raise RuntimeError("this device has no override_input")
        raw = active != oi.invert
        if oi.table == "holding":
            await self.set_registers(_OVERRIDE, [int(raw)])
            return
        self._internal = True
        try:
            await self._require_server().async_setValues(self.device_id, _FC_READ[oi.table],
                                                         oi.address, [raw])
        finally:
            self._internal = False

    def _require_server(self) -> ModbusTcpServer | ModbusSerialServer:
        if self._server is None:
            raise RuntimeError("call start_tcp() or start_rtu() first")
        return self._server


def _stepwise(name: str) -> bool:
    """True for an actuator of whole numbers (the regime): it switches, it does not glide."""
    return name in ACTUATORS and ACTUATORS[name].integer


def _travel(move: tuple[float, float, float], now: float, rate: float | None, *,
            stepwise: bool) -> float:
    """Position of a motor moving from ``move[0]`` to ``move[1]`` since ``move[2]`` at
    ``rate`` [unit/s]; a ``stepwise`` one switches on arrival."""
    start, target, t0 = move
    if rate is None or rate <= 0:
        return target
    span = target - start
    done = min(1.0, (now - t0) * rate / abs(span))
    if done >= 1.0:
        return target
    if stepwise:
        return start  # a damper set: the regime changes when the dampers have travelled
    return start + done * span


_DEMO_VALUES = {
    "x1_c": 18.0, "x2_c": 21.0, "x3_c": 22.5, "x4_c": 25.0, "x5_c": 20.0, "t_room_c": 22.0,
    "t_out_c": 12.0, "ghi_wm2": 450.0, "wind_speed_ms": 3.0, "wind_dir_deg": 200.0,
    "v_cav_ms": 0.3, "rh_pct": 55.0, "pressure_hpa": 1012.0,
}


async def _serve(config: str, device: str | None, host: str, port: int) -> None:
    from dsfd.config import load_panel

    panel = load_panel(config)
    if panel.devices is None:
        raise SystemExit(f"{config}: no devices: section")
    modbus = [d for d in panel.devices.entries
              if d.is_modbus and (device is None or d.name == device)]
    if not modbus:
        raise SystemExit(f"{config}: no Modbus device {device or ''}".rstrip())
    cfg = modbus[0]
    emulator = EmulatedModbusDevice.from_config(cfg)
    await emulator.start_tcp(host=host, port=port)
    await emulator.set_sensors({n: _DEMO_VALUES[n] for n in cfg.signal_names()})
    log.info("emulating %s (id %d) on %s:%d", cfg.name, cfg.device_id, host, port)
    last: dict[str, float] = {}
    while True:
        now = await emulator.actuator_values()
        if now != last:
            log.info("actuators %s", now)
            last = now
        await asyncio.sleep(1.0)


def main(argv: Sequence[str] | None = None) -> None:
    """Serve one configured Modbus device over TCP until interrupted."""
    parser = argparse.ArgumentParser(prog="python -m hil.modbus_device", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", required=True, help="panel YAML with a devices: section")
    parser.add_argument("--device", help="device name (default: the first Modbus device)")
    parser.add_argument("--host", default="127.0.0.1", help="listen address")
    parser.add_argument("--port", type=int, required=True, help="TCP port")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(_serve(args.config, args.device, args.host, args.port))


if __name__ == "__main__":
    main()
