"""The configured devices for commissioning: the daemon's drivers, one per device, plus a
reader of the actuators' position feedback registers (edge: sockets and serial ports)."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Mapping
from dataclasses import dataclass

from dsfd.config.devices import DeviceConfig, Devices
from dsfd.drivers.base import CompositeDriver, Driver, Sample
from dsfd.drivers.factory import build_drivers
from dsfd.drivers.modbus import ModbusDriver
from dsfd.drivers.resilience import CircuitBreaker
from dsfd.registers import RegisterPoint

__all__ = ["Rig", "TimedSample", "describe_point"]


def describe_point(device: str, p: RegisterPoint) -> str:
    """Where a value lives, for a person: ``facade-io input 0 (int16 x0.1)``."""
    scale = f" x{p.scale:g}" if p.scale != 1.0 else ""
    offset = f" {p.offset:+g}" if p.offset else ""
    return f"{device} {p.table} {p.address} ({p.data_type}{scale}{offset})"


@dataclass(frozen=True)
class TimedSample:
    """One device's readings and how long the read took [s]."""

    device: str
    sample: Sample
    latency_s: float


class Rig:
    """The panel's devices, opened once for a commissioning session."""

    def __init__(self, devices: Devices) -> None:
        self.devices = devices
        self.composite: CompositeDriver = build_drivers(devices)
        self.by_device: dict[str, Driver] = {
            cfg.name: drv for cfg, drv in zip(devices.entries, self.composite.drivers,
                                              strict=True)}
        self.feedback: dict[str, tuple[DeviceConfig, ModbusDriver]] = {}
        for cfg in devices.entries:
            drv = self.by_device[cfg.name]
            points = cfg.feedback_points() if cfg.is_modbus else ()
            if points and isinstance(drv, ModbusDriver):
                reader = ModbusDriver(
                    name=cfg.name, link=drv.link, device_id=cfg.device_id, sensors=points,
                    timeout_s=cfg.timeout_s, retries=cfg.retries,
                    breaker=CircuitBreaker(failures=cfg.breaker_failures, open_cycles=0))
                for p in points:
                    self.feedback[p.name] = (cfg, reader)

    async def start(self) -> None:
        await self.composite.start()

    async def close(self) -> None:
        await self.composite.close()

    async def read_timed(self) -> list[TimedSample]:
        """One read of every device, concurrently, each timed."""
        async def one(name: str, drv: Driver) -> TimedSample:
            t0 = time.monotonic()
            sample = await drv.read(time.time())
            return TimedSample(name, sample, time.monotonic() - t0)

        return list(await asyncio.gather(*(one(n, d) for n, d in self.by_device.items()
                                           if d.sensor_names)))

    async def read_feedback(self) -> dict[str, float]:
        """Positions the actuators report [signal units]; unreadable ones are left out."""
        readers = {id(r): r for _, r in self.feedback.values()}
        out: dict[str, float] = {}
        for reader in readers.values():
            sample = await reader.read(time.time())
            out.update({k: r.value for k, r in sample.readings.items() if r.ok})
        return out

    def feedback_where(self, name: str) -> str:
        cfg, _ = self.feedback[name]
        (point,) = [p for p in cfg.feedback_points() if p.name == name]
        return describe_point(cfg.name, point)

    def set_point_where(self) -> Mapping[str, str]:
        """Where each actuator's set-point register is."""
        return {p.name: describe_point(cfg.name, p) for cfg in self.devices.entries
                if cfg.is_modbus for p in cfg.actuator_points()}
