"""Couples the simulated plant to the emulated devices, so the real daemon sees a façade.

::

    dsfd run (subprocess) ──Modbus TCP/RTU──▶ EmulatedModbusDevice ◀──┐
                          ◀──serial pty──── StationEmulator      ◀──┤ PlantBridge
                                                                     │  every tick:
                                             Plant (dsfd.sim) ◀──────┘  commands → plant,
                                                                        advance, sensors →
                                                                        registers and lines

The plant's time runs at ``speed`` × real time from the first tick (the daemon runs with
``dsfd run --speed`` at the same factor and ``--start`` at the same instant, so both clocks
agree to within the start-up delay — like a real façade, the plant does not wait for the
controller). Each tick:

1. the actuator registers are read; a changed command is applied to the plant (a command the
   plant refuses is counted, as a motor controller would ignore it);
2. the plant is advanced to the current simulated time (in a worker thread, so the Modbus
   server keeps answering);
3. the sensor readings are written into the input registers (a simulated dropout as the
   point's "no value" code), and the station emulator sends one protocol line with the
   outdoor air, irradiance and wind (humidity and pressure fields empty: the plant does not
   simulate them), with :attr:`PlantBridge.station_override` replacing plant values (a gale).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections import Counter
from collections.abc import Mapping

from dsfd.sim.plant.plant import Plant
from hil.modbus_device import EmulatedModbusDevice
from hil.station import StationEmulator

__all__ = ["PlantBridge"]

log = logging.getLogger(__name__)

#: Signals the station line carries from the plant.
STATION_FROM_PLANT = ("t_out_c", "ghi_wm2", "wind_speed_ms", "wind_dir_deg")


class PlantBridge:
    """Runs the plant at ``speed`` × real time against an I/O device and a station."""

    def __init__(self, plant: Plant, *, io: EmulatedModbusDevice,
                 station: StationEmulator | None = None, speed: float,
                 tick_s: float = 0.05) -> None:
        self.plant = plant
        self.io = io
        self.station = station
        self.speed = speed
        self.tick_s = tick_s
        #: ticks, commands_applied, commands_refused, lines_sent, dropouts, plant_failures.
        self.counters: Counter[str] = Counter()
        #: Commands the plant accepted, in order, as {phi_deg, afr, or_pct}.
        self.applied: list[dict[str, float]] = []
        #: Station values that replace the plant's (e.g. a storm: {"wind_speed_ms": 25}).
        self.station_override: dict[str, float] = {}
        self._last_registers: dict[str, float] | None = None
        actuators = {p.name for p in io.actuators}
        self._sensors = tuple(n for n in io.points if n not in actuators)
        self._task: asyncio.Task[None] | None = None
        self._start_s = plant.time_s
        self._real0: float | None = None

    @property
    def sim_time_s(self) -> float:
        """The plant's target time now [s, UTC]."""
        if self._real0 is None:
            return self._start_s
        return self._start_s + (time.monotonic() - self._real0) * self.speed

    async def start(self) -> None:
        """Publish the initial sensor values, then tick in the background."""
        await self._publish()
        self._real0 = time.monotonic()
        self._task = asyncio.create_task(self._run(), name="plant-bridge")

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None

    async def _run(self) -> None:
        while True:
            await self.tick()
            await asyncio.sleep(self.tick_s)

    async def tick(self) -> None:
        """One coupling step (see module docstring)."""
        self.counters["ticks"] += 1
        if self.io.running:
            await self._apply_commands()
        ahead = self.sim_time_s - self.plant.time_s
        try:
            if ahead > 1e-6:
                await asyncio.to_thread(self.plant.advance, ahead)
        except Exception as exc:  # a plant failure freezes the façade; the bridge lives on
            self.counters["plant_failures"] += 1
            if self.counters["plant_failures"] == 1:
                log.error("simulated plant failed: %s; sensor values frozen", exc)
            return
        await self._publish()

    async def _apply_commands(self) -> None:
        registers = await self.io.actuator_values()
        if registers == self._last_registers:
            return
        self._last_registers = registers
        try:
            self.plant.apply(registers)
        except ValueError:  # CommandError: e.g. the all-zero registers before the first write
            self.counters["commands_refused"] += 1
            return
        self.counters["commands_applied"] += 1
        self.applied.append(dict(registers))

    async def _publish(self) -> None:
        values = self.plant.read_sensors()
        if self.io.running:
            for name in self._sensors:
                if name in values:
                    await self._set(name, values[name])
        if self.station is not None:
            self.station.send({**_station_values(values), **self.station_override})
            self.counters["lines_sent"] += 1

    async def _set(self, name: str, value: float) -> None:
        if math.isfinite(value):
            await self.io.set_sensor(name, value)
        else:
            self.counters["dropouts"] += 1
            await self.io.serve_nan(name)


def _station_values(values: Mapping[str, float]) -> dict[str, float | None]:
    out: dict[str, float | None] = {}
    for name in STATION_FROM_PLANT:
        v = values.get(name, math.nan)
        out[name] = v if math.isfinite(v) else None
    return out
