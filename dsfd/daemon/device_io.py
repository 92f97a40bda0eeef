"""The loop's two stages at the devices: **read** and **write**.

* read — all drivers concurrently with the actuator read-back and the override input, under
  the devices' read budget (``devices.read_budget_s``). A driver fault is a bad reading,
  never an exception out of here: on a failure or a timeout every sensor is flagged
  (``device_error`` / ``timeout``) and the positions are unknown for this cycle.
* write — the command under the write budget (``devices.write_budget_s``), verified by
  read-back; a dry run writes nothing (``dry-run``).

:class:`DeviceIO` also keeps where the actuators should be (:attr:`DeviceIO.expected`: the
last verified write, or the position a manual hold took over), which the manual-move
detection compares the read-back with (:mod:`dsfd.daemon.hold`).
"""

from __future__ import annotations

import asyncio
import logging
from dataclasses import dataclass

from dsfd.config.devices import Devices
from dsfd.daemon.logging_setup import get_logger
from dsfd.daemon.startup import DEFAULT_READ_BUDGET_S, DEFAULT_WRITE_BUDGET_S
from dsfd.drivers.base import (
    Command,
    Driver,
    Quality,
    Reading,
    Sample,
    WriteResult,
    command_from_values,
)

__all__ = ["DeviceIO", "DeviceReading"]

log = get_logger("dsfd.daemon.loop")


@dataclass
class DeviceReading:
    """What the read stage brought in."""

    sample: Sample
    read_back: Command | None
    input_active: bool | None


class DeviceIO:
    """Reads and verified writes of one panel's drivers (budgets from ``devices:``)."""

    def __init__(self, driver: Driver, *, write_enabled: bool) -> None:
        self.driver = driver
        self.write_enabled = write_enabled
        self.read_budget_s = DEFAULT_READ_BUDGET_S
        self.write_budget_s = DEFAULT_WRITE_BUDGET_S
        self.last_written: Command | None = None
        #: Where the actuators should be: the last verified write, or the position a hold
        #: took over; None after an unverified write (no manual-move detection then).
        self.expected: Command | None = None
        self._writes_failing = 0  # consecutive failed writes: the first is logged loudly

    def configure(self, devices: Devices | None) -> None:
        """The read and write budgets of ``devices`` (the defaults without a section)."""
        self.read_budget_s = devices.read_budget_s if devices else DEFAULT_READ_BUDGET_S
        self.write_budget_s = devices.write_budget_s if devices else DEFAULT_WRITE_BUDGET_S

    async def read(self, now_s: float) -> DeviceReading:
        """Sample, actuator position now, and the override input."""
        try:
            async with asyncio.timeout(self.read_budget_s):
                sample, actuators, active = await asyncio.gather(
                    self.driver.read(now_s), self.driver.read_actuators(),
                    self.driver.read_override_input())
        except Exception as exc:  # the drivers should not raise; the loop must not die
            if isinstance(exc, TimeoutError):
                why, quality = f"read exceeded its budget of {self.read_budget_s:g} s", \
                    Quality.TIMEOUT
            else:
                log.exception("read failed")
                why, quality = f"read failed: {type(exc).__name__}: {exc}", Quality.DEVICE_ERROR
            sample = Sample(now_s, {n: Reading.bad(quality, "daemon", why)
                                    for n in self.driver.sensor_names})
            actuators, active = {}, None
        return DeviceReading(sample, command_from_values(actuators), active)

    async def write(self, cmd: Command) -> tuple[WriteResult | None, str]:
        """Write ``cmd`` and verify it: (result, ``verified`` / ``failed`` / ``dry-run``)."""
        if not self.write_enabled:
            return None, "dry-run"
        try:
            async with asyncio.timeout(self.write_budget_s):
                result = await self.driver.write(cmd)
        except Exception as exc:
            if not isinstance(exc, TimeoutError):
                log.exception("write failed")
            why = (f"write exceeded its budget of {self.write_budget_s:g} s"
                   if isinstance(exc, TimeoutError) else f"write failed: {exc}")
            result = WriteResult(requested=cmd, owned=self.driver.actuator_names, errors=(why,))
        self.last_written = cmd
        if result.ok:
            if self._writes_failing:
                log.info("commands verified again after %d failed write(s)",
                         self._writes_failing)
            self._writes_failing = 0
            self.expected = cmd
            return result, "verified"
        # A failed verification is not a manual override: forget the expected position, so
        # the next read-back is not compared with a command that may never have arrived.
        self.expected = None
        self._writes_failing += 1
        log.log(logging.WARNING if self._writes_failing == 1 else logging.DEBUG,
                "command %s not verified: %s", cmd.as_dict(),
                "; ".join(result.errors) or "read-back incomplete",
                failed_writes=self._writes_failing)
        return result, "failed"
