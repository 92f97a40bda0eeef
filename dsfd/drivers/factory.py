"""Build the drivers of a panel from its ``devices:`` configuration."""

from __future__ import annotations

import time
from collections.abc import Callable

from dsfd.config.devices import Devices
from dsfd.drivers.base import CompositeDriver, Driver
from dsfd.drivers.modbus import ModbusDriver
from dsfd.drivers.modbus_link import ModbusLink
from dsfd.drivers.station import StationDriver

__all__ = ["build_drivers"]


def build_drivers(devices: Devices, *, clock: Callable[[], float] = time.monotonic
                  ) -> CompositeDriver:
    """One driver per configured device behind a :class:`CompositeDriver`.

    Modbus devices on the same TCP endpoint or serial line share one :class:`ModbusLink`
    (one pymodbus client). ``clock`` [s, monotonic] drives the reconnect backoff; tests
    inject a fake one. Nothing is opened here: call ``await driver.start()`` in the loop.
    """
    links: dict[str, ModbusLink] = {}
    drivers: list[Driver] = []
    for cfg in devices.entries:
        if cfg.is_modbus:
            key = cfg.link_key()
            if key not in links:
                links[key] = ModbusLink.for_device(cfg, clock=clock)
            drivers.append(ModbusDriver.from_config(cfg, links[key]))
        else:
            drivers.append(StationDriver.from_config(cfg, clock=clock))
    return CompositeDriver(drivers)
