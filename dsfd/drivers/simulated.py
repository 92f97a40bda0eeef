"""A :class:`~dsfd.drivers.base.Driver` around the in-process simulated plant (dry runs, benches).

``dsfd run --plant sim`` replaces the panel's devices by this driver: the truth plant of
:mod:`dsfd.sim.plant.plant` replays real weather, and the daemon reads its sensors and commands its
actuators through the same :class:`Sample`/:class:`Quality` semantics as the Modbus and serial
drivers:

* ``read(time_s)`` first advances the plant to ``time_s`` (the daemon's clock drives the
  simulation), then turns each sensor value into a :class:`Reading`; a simulated dropout
  (NaN) is NOT_FINITE, and a plant failure (integration error, weather exhausted) makes every
  reading DEVICE_ERROR with the reason — the driver never raises for it;
* ``write(cmd)`` applies the command (the plant validates it like a real façade would; a
  rejected command is an error in the :class:`WriteResult`, not an exception) and verifies it
  by reading the executed command back (the plant quantises the damper opening to 1 %, so
  ``or_pct`` may read back differently — reported like a real read-back mismatch).

Nothing here touches hardware: :attr:`SimulatedDriver.hardware` is False, which is how the
daemon knows a dry run may still let the simulated plant follow its decisions.
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections import Counter
from collections.abc import Mapping
from typing import Protocol

from dsfd.drivers.base import Command, Quality, Reading, Sample, WriteResult, command_from_values
from dsfd.signals import ACTUATOR_NAMES

__all__ = ["PlantLike", "SimulatedDriver"]

log = logging.getLogger(__name__)

#: Plant times closer than this count as "now" [s].
_TIME_EPS_S = 1e-6


class PlantLike(Protocol):
    """What the driver needs of :class:`dsfd.sim.plant.plant.Plant`."""

    @property
    def time_s(self) -> float: ...

    def apply(self, command: Mapping[str, float]) -> object: ...

    def advance(self, seconds: float) -> None: ...

    def read_sensors(self) -> dict[str, float]: ...


class SimulatedDriver:
    """The simulated plant as one device named ``name`` (sensors and all three actuators)."""

    #: Never hardware: a dry run may write here (the plant follows the decisions).
    hardware = False

    def __init__(self, plant: PlantLike, *, name: str = "sim-plant",
                 sensor_names: frozenset[str] | None = None) -> None:
        self.name = name
        self.plant = plant
        if sensor_names is None:
            sensor_names = frozenset(plant.read_sensors())
        self._sensors = frozenset(sensor_names)
        #: reads, read_failures, dropouts, writes, write_errors, verify_failures.
        self.counters: Counter[str] = Counter()
        self._failing = False
        # The plant is not thread-safe: while an integration abandoned by the read budget is
        # still running, nothing else may touch the plant.
        self._busy: asyncio.Future[dict[str, float]] | None = None

    @property
    def busy(self) -> bool:
        """True while an earlier integration is still running in its thread."""
        return self._busy is not None and not self._busy.done()

    @property
    def sensor_names(self) -> frozenset[str]:
        return self._sensors

    @property
    def actuator_names(self) -> frozenset[str]:
        return frozenset(ACTUATOR_NAMES)

    async def start(self) -> None:
        return None

    def _advance_and_read(self, time_s: float) -> dict[str, float]:
        both = getattr(self.plant, "advance_and_read", None)  # one round trip to a process
        if both is not None:
            return both(time_s)
        ahead = time_s - self.plant.time_s
        if ahead > _TIME_EPS_S:
            self.plant.advance(ahead)
        return self.plant.read_sensors()

    async def read(self, time_s: float) -> Sample:
        self.counters["reads"] += 1
        if self.busy:
            self.counters["read_failures"] += 1
            why = f"{self.name}: simulated plant still integrating an earlier step"
            return Sample(time_s, {n: Reading.bad(Quality.TIMEOUT, self.name, why)
                                   for n in self._sensors})
        try:
            # The integration takes milliseconds per simulated minute: off the event loop,
            # so watchdog pings and signals are not delayed by it.
            self._busy = asyncio.ensure_future(asyncio.to_thread(self._advance_and_read,
                                                                 time_s))
            self._busy.add_done_callback(_retrieve)  # an abandoned failure is not "lost"
            values = await asyncio.shield(self._busy)
        except Exception as exc:  # a plant failure is a device fault here, never a crash
            self.counters["read_failures"] += 1
            if not self._failing:
                log.warning("simulated plant %s failed: %s", self.name, exc)
            self._failing = True
            why = f"{self.name}: simulated plant failed: {type(exc).__name__}: {exc}"
            return Sample(time_s, {n: Reading.bad(Quality.DEVICE_ERROR, self.name, why)
                                   for n in self._sensors})
        self._failing = False
        readings: dict[str, Reading] = {}
        for n in self._sensors:
            value = values.get(n, math.nan)
            if math.isfinite(value):
                readings[n] = Reading.good(value, self.name)
            else:
                self.counters["dropouts"] += 1
                readings[n] = Reading.bad(Quality.NOT_FINITE, self.name,
                                          f"{self.name}: sensor {n} dropout (no value)")
        return Sample(time_s, readings)

    async def write(self, cmd: Command) -> WriteResult:
        self.counters["writes"] += 1
        owned = self.actuator_names
        if self.busy:
            self.counters["write_errors"] += 1
            return WriteResult(requested=cmd, owned=owned, errors=(
                f"{self.name}: not written, simulated plant still integrating",))
        try:
            executed = self.plant.apply(cmd.as_dict())
        except ValueError as exc:  # CommandError: the plant refused, as a real façade might
            self.counters["write_errors"] += 1
            return WriteResult(requested=cmd, owned=owned,
                               errors=(f"{self.name}: command refused: {exc}",))
        back = _as_values(executed)
        requested = cmd.as_dict()
        verified = frozenset(n for n in owned if back.get(n) == requested[n])
        errors = tuple(f"{self.name}: {n}: read-back {back.get(n)!r} differs from written "
                       f"{requested[n]!r}" for n in sorted(owned - verified))
        if errors:
            self.counters["verify_failures"] += 1
        return WriteResult(requested=cmd, owned=owned, written=requested, verified=verified,
                           read_back=back, errors=errors)

    async def read_actuators(self) -> Mapping[str, float]:
        return _as_values(getattr(self.plant, "command", None))

    async def read_back(self) -> Command | None:
        return command_from_values(await self.read_actuators())

    @property
    def override_input(self) -> str | None:
        return None

    async def read_override_input(self) -> bool | None:
        return None

    async def close(self) -> None:
        return None


def _retrieve(future: asyncio.Future[dict[str, float]]) -> None:
    if not future.cancelled():
        future.exception()


def _as_values(command: object) -> dict[str, float]:
    """``{"phi_deg", "afr", "or_pct"}`` of a plant command object (empty if unknown)."""
    if command is None:
        return {}
    as_dict = getattr(command, "as_dict", None)
    if callable(as_dict):
        return {k: float(v) for k, v in as_dict().items()}
    return {k: float(getattr(command, k)) for k in ACTUATOR_NAMES if hasattr(command, k)}
