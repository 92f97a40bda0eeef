"""Modbus TCP and RTU devices through pymodbus 3.16 async clients.

Layout: one :class:`ModbusLink` per physical link (TCP endpoint or serial line) owns one
pymodbus client, because a client serialises its requests and an RS-485 line carries one
request at a time; one :class:`ModbusDriver` per device (device id) on it.

Time bound for a dead device, per cycle (``T`` = ``timeout_s``, ``R`` = ``retries``)::

    read   ≤ T · (1 + (R + 1) · read_blocks)
    write  ≤ T · (1 + (R + 1) · (write_blocks + read_back_blocks))

(one connect attempt, bounded by pymodbus' ``timeout``, plus ``R + 1`` attempts of ``T`` per
request). The driver enforces the bound with ``asyncio.timeout`` as a hard cap, stops polling
a device's remaining blocks after the first timeout, and after ``breaker_failures``
consecutive cycles with timeouts skips it for ``breaker_cycles`` cycles (zero I/O). A refused
connection costs next to nothing and is retried with exponential backoff, at most once per
backoff interval. So a device that is down costs at most one read bound per cycle, and usually
~0 s.

Reconnects and the shared client: :mod:`dsfd.drivers.modbus_link`.

Faults never raise: exception responses (``ExceptionResponse`` is *returned*, not raised),
timeouts (``ModbusIOException``), a closed link (``ConnectionException``) and NaN/``nan_value``
decodes become readings of bad quality whose detail names device, id, link, table and address.
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections import Counter
from collections.abc import Awaitable, Callable, Mapping, Sequence
from functools import partial
from typing import TYPE_CHECKING, Any

from pymodbus.constants import ExcCodes
from pymodbus.exceptions import ConnectionException, ModbusException, ModbusIOException

from dsfd.drivers.base import Command, Quality, Reading, Sample, WriteResult, command_from_values
from dsfd.drivers.modbus_link import ModbusLink, configure_pymodbus_logging
from dsfd.drivers.resilience import CircuitBreaker
from dsfd.registers import (
    BIT_TABLES,
    RegisterBlock,
    RegisterPoint,
    decode,
    encode,
    matches_nan_value,
    plan_reads,
    plan_writes,
)

if TYPE_CHECKING:
    from dsfd.config.devices import DeviceConfig, OverrideInput

__all__ = ["ModbusDriver", "ModbusLink", "configure_pymodbus_logging"]

log = logging.getLogger(__name__)
#: The pymodbus client call that reads each table (FC 4, 3, 1, 2).
_READ_CALL = {"input": "read_input_registers", "holding": "read_holding_registers",
              "coil": "read_coils", "discrete_input": "read_discrete_inputs"}


class ModbusDriver:
    """One Modbus device (device id) on a :class:`ModbusLink`: sensors in, actuators out."""

    def __init__(self, *, name: str, link: ModbusLink, device_id: int,
                 sensors: Sequence[RegisterPoint] = (), actuators: Sequence[RegisterPoint] = (),
                 timeout_s: float, retries: int, breaker: CircuitBreaker,
                 max_read_gap: int = 0, override_input: OverrideInput | None = None) -> None:
        self.name = name
        self.link = link
        self.device_id = device_id
        self.timeout_s = timeout_s
        self.retries = retries
        self.breaker = breaker
        self._sensors = tuple(sensors)
        self._actuators = tuple(actuators)
        self.read_blocks = plan_reads(self._sensors, max_gap=max_read_gap)
        self.write_blocks = plan_writes(self._actuators)
        self.readback_blocks = plan_reads(self._actuators)
        #: Upper bounds of one read / one write with read-back [s] (module docstring).
        self.read_bound_s = self._bound(len(self.read_blocks))
        self.write_bound_s = self._bound(len(self.write_blocks) + len(self.readback_blocks))
        #: requests, timeouts, device_errors, not_finite, cycles_failed, cycles_skipped,
        #: writes, write_errors, verify_failures.
        self.counters: Counter[str] = Counter()
        self._label = f"{name} (id {device_id} on {link.key})"
        self._failing = False
        self._override = override_input

    @classmethod
    def from_config(cls, cfg: DeviceConfig, link: ModbusLink) -> ModbusDriver:
        return cls(name=cfg.name, link=link, device_id=cfg.device_id,
                   sensors=cfg.sensor_points(), actuators=cfg.actuator_points(),
                   timeout_s=cfg.timeout_s, retries=cfg.retries, max_read_gap=cfg.max_read_gap,
                   override_input=cfg.override_input,
                   breaker=CircuitBreaker(failures=cfg.breaker_failures,
                                          open_cycles=cfg.breaker_cycles))

    def _bound(self, requests: int) -> float:
        return 0.0 if requests == 0 else self.timeout_s * (1 + (self.retries + 1) * requests)

    @property
    def sensor_names(self) -> frozenset[str]:
        return frozenset(p.name for p in self._sensors)

    @property
    def actuator_names(self) -> frozenset[str]:
        return frozenset(p.name for p in self._actuators)

    async def start(self) -> None:
        async with self.link.lock:
            await self.link.ensure_connected()

    async def close(self) -> None:
        self.link.close()

    # ----------------------------------------------------------------------------- reading
    async def read(self, time_s: float) -> Sample:
        if not self._sensors:
            return Sample(time_s)
        if self.breaker.should_skip():
            self.counters["cycles_skipped"] += 1
            why = (f"{self._label}: not polled, circuit breaker open after repeated timeouts "
                   f"({self.breaker.skip_remaining} more cycles)")
            return Sample(time_s, {p.name: Reading.bad(Quality.SKIPPED, self.name, why)
                                   for p in self._sensors})
        readings: dict[str, Reading] = {}

        def got(block: RegisterBlock, regs: list[int]) -> None:
            for p in block.points:
                readings[p.name] = self._decode(p, block.registers_of(p, regs))

        def failed(block: RegisterBlock, quality: Quality, why: str) -> None:
            for p in block.points:
                readings[p.name] = Reading.bad(quality, self.name,
                                               f"{self._label}: {p.where()}: {why}")

        outcome = await self._locked(self.read_blocks, self.read_bound_s, got, failed, "read")
        self._account(outcome, readings)
        return Sample(time_s, readings)

    def _decode(self, p: RegisterPoint, regs: list[int]) -> Reading:
        value = decode(p, regs)
        if math.isfinite(value):
            return Reading.good(value, self.name)
        self.counters["not_finite"] += 1
        raw = " ".join(f"0x{r:04X}" for r in regs)
        what = "nan_value code" if matches_nan_value(p, regs) else "non-finite value"
        return Reading.bad(Quality.NOT_FINITE, self.name,
                           f"{self._label}: {p.where()}: {what} ({raw})")

    async def _locked(self, blocks: Sequence[RegisterBlock], bound_s: float,
                      got: Callable[[RegisterBlock, list[int]], None],
                      failed: Callable[[RegisterBlock, Quality, str], None], what: str) -> str:
        """Poll ``blocks`` holding the link lock, under the hard cap ``bound_s``."""
        done: set[int] = set()

        def got_once(block: RegisterBlock, regs: list[int]) -> None:
            done.add(id(block))
            got(block, regs)

        def failed_once(block: RegisterBlock, quality: Quality, why: str) -> None:
            done.add(id(block))
            failed(block, quality, why)

        async with self.link.lock:
            try:
                async with asyncio.timeout(bound_s):
                    return await self._poll(blocks, got_once, failed_once)
            except TimeoutError:
                self.link.drop()
                for b in blocks:
                    if id(b) not in done:
                        failed(b, Quality.TIMEOUT,
                               f"{b.where()}: {what} exceeded its bound of {bound_s:.3g} s")
                return "timeout"

    async def _poll(self, blocks: Sequence[RegisterBlock],
                    got: Callable[[RegisterBlock, list[int]], None],
                    failed: Callable[[RegisterBlock, Quality, str], None]) -> str:
        """Read ``blocks``; return ``responded``, ``timeout`` or ``disconnected``."""
        reason = await self.link.ensure_connected()
        if reason is not None:
            for b in blocks:
                failed(b, Quality.DISCONNECTED, reason)
            return "disconnected"
        for i, block in enumerate(blocks):
            fn = getattr(self.link.client, _READ_CALL[block.table])
            pdu, quality, why = await self._request(
                partial(fn, block.address, count=block.count, device_id=self.device_id))
            regs = _values(pdu, block)
            if pdu is not None and len(regs) != block.count:
                pdu, quality, why = None, Quality.DEVICE_ERROR, (
                    f"short response, {len(regs)} of {block.count} "
                    + ("bits" if block.table in BIT_TABLES else "registers"))
            if pdu is not None:
                got(block, regs)
                continue
            failed(block, quality, f"{block.where()}: {why}")
            if quality is Quality.DEVICE_ERROR:
                continue  # the device answered; its other blocks may be fine
            for rest in blocks[i + 1:]:  # timed out or link lost: stop spending time here
                failed(rest, quality, f"{rest.where()}: not polled, {block.where()} failed")
            if quality is Quality.TIMEOUT:
                self.link.drop()
                return "timeout"
            return "disconnected"
        return "responded"

    async def _request(self, call: Callable[[], Awaitable[Any]]) -> tuple[Any, Quality, str]:
        """Run one pymodbus request; (pdu, GOOD, "") or (None, bad quality, why)."""
        self.counters["requests"] += 1
        try:
            pdu = await call()
        except ConnectionException as exc:
            return None, Quality.DISCONNECTED, f"link lost ({exc})"
        except ModbusIOException as exc:
            if "No response" in str(exc):
                self.counters["timeouts"] += 1
                return None, Quality.TIMEOUT, (f"no response to {self.retries + 1} attempt(s) "
                                               f"of {self.timeout_s:g} s")
            self.counters["device_errors"] += 1
            return None, Quality.DEVICE_ERROR, f"I/O error ({exc})"
        except ModbusException as exc:
            self.counters["device_errors"] += 1
            return None, Quality.DEVICE_ERROR, f"protocol error ({exc})"
        if pdu is None or pdu.isError():
            self.counters["device_errors"] += 1
            code = getattr(pdu, "exception_code", None)
            return None, Quality.DEVICE_ERROR, f"device exception {_exception_name(code)}"
        return pdu, Quality.GOOD, ""

    def _account(self, outcome: str, readings: Mapping[str, Reading]) -> None:
        """Feed the breaker and log transitions: first failure loud, repeats quiet."""
        if outcome == "timeout":
            self.breaker.record_failure()
        elif outcome == "responded":
            self.breaker.record_success()
        bad = [r for r in readings.values() if not r.ok]
        if bad and outcome != "responded":
            self.counters["cycles_failed"] += 1
        if bad and not self._failing:
            log.warning("modbus device %s: %s", self.name, bad[0].detail)
        elif not bad and self._failing:
            log.info("modbus device %s: all readings good again", self.name)
        self._failing = bool(bad)

    # ----------------------------------------------------------------------------- writing
    async def write(self, cmd: Command) -> WriteResult:
        owned = self.actuator_names
        if not owned:
            return WriteResult(requested=cmd)
        values = cmd.as_dict()
        errors: list[str] = []
        encoded: dict[str, list[int]] = {}
        for p in self._actuators:
            try:
                encoded[p.name] = encode(p, values[p.name])
            except ValueError as exc:
                errors.append(f"{self._label}: {p.where()}: cannot encode: {exc}")
        if self.breaker.is_open:
            errors.append(f"{self._label}: not written, circuit breaker open")
            return WriteResult(requested=cmd, owned=owned, errors=tuple(errors))
        written: dict[str, float] = {}
        verified: set[str] = set()
        read_back: dict[str, float] = {}

        def failed(block: RegisterBlock, quality: Quality, why: str) -> None:
            errors.append(f"{self._label}: {why}")

        def got(block: RegisterBlock, regs: list[int]) -> None:
            for p in block.points:
                mine = block.registers_of(p, regs)
                read_back[p.name] = decode(p, mine)
                if p.name in written and mine == encoded[p.name]:
                    verified.add(p.name)
                elif p.name in written:
                    self.counters["verify_failures"] += 1
                    errors.append(f"{self._label}: {p.where()}: read-back {mine} differs from "
                                  f"written {encoded[p.name]}")

        async with self.link.lock:
            try:
                async with asyncio.timeout(self.write_bound_s):
                    outcome = await self._write_blocks(encoded, values, written, failed)
                    if written:
                        outcome = await self._poll(self.readback_blocks, got, failed)
            except TimeoutError:
                self.link.drop()
                outcome = "timeout"
                errors.append(f"{self._label}: write exceeded its bound of "
                              f"{self.write_bound_s:.3g} s")
        if outcome == "timeout":
            self.breaker.record_failure()
        self.counters["writes"] += 1
        if errors:
            self.counters["write_errors"] += 1
            log.warning("modbus device %s: write: %s", self.name, errors[0])
        return WriteResult(requested=cmd, owned=owned, written=written,
                           verified=frozenset(verified), read_back=read_back,
                           errors=tuple(errors))

    async def _write_blocks(self, encoded: Mapping[str, list[int]],
                            values: Mapping[str, float], written: dict[str, float],
                            failed: Callable[[RegisterBlock, Quality, str], None]) -> str:
        reason = await self.link.ensure_connected()
        if reason is not None:
            failed(self.write_blocks[0], Quality.DISCONNECTED, f"not written: {reason}")
            return "disconnected"
        client = self.link.client
        for block in self.write_blocks:
            if any(p.name not in encoded for p in block.points):
                continue  # encoding error already reported
            regs = [r for p in block.points for r in encoded[p.name]]
            # FC 6 for a single register: some actuators accept nothing else for it.
            call = (partial(client.write_register, block.address, regs[0],
                            device_id=self.device_id) if block.count == 1
                    else partial(client.write_registers, block.address, regs,
                                 device_id=self.device_id))
            pdu, quality, why = await self._request(call)
            if pdu is None:
                failed(block, quality, f"write {block.where()}: {why}")
                if quality is not Quality.DEVICE_ERROR:
                    return "timeout" if quality is Quality.TIMEOUT else "disconnected"
                continue
            for p in block.points:
                written[p.name] = decode(p, encoded[p.name])
        return "responded"

    async def read_actuators(self) -> Mapping[str, float]:
        if not self._actuators or self.breaker.is_open:
            return {}
        values: dict[str, float] = {}

        def got(block: RegisterBlock, regs: list[int]) -> None:
            for p in block.points:
                values[p.name] = decode(p, block.registers_of(p, regs))

        await self._locked(self.readback_blocks, self._bound(len(self.readback_blocks)), got,
                           lambda b, q, w: None, "read-back")
        return values

    async def read_back(self) -> Command | None:
        return command_from_values(await self.read_actuators())

    # ----------------------------------------------------------------------------- override
    @property
    def override_input(self) -> str | None:
        oi = self._override
        return None if oi is None else f"{self.name} {oi.where()}"

    async def read_override_input(self) -> bool | None:
        """The hand/auto input: a coil (FC 1), discrete input (FC 2) or holding register
        (FC 3, active while non-zero), inverted if configured; None if unreadable."""
        oi = self._override
        if oi is None or self.breaker.is_open:
            return None
        client_call = {"coil": "read_coils", "discrete_input": "read_discrete_inputs",
                       "holding": "read_holding_registers"}[oi.table]
        async with self.link.lock:
            try:
                async with asyncio.timeout(self._bound(1)):
                    if await self.link.ensure_connected() is not None:
                        return None
                    fn = getattr(self.link.client, client_call)
                    pdu, _, why = await self._request(
                        partial(fn, oi.address, count=1, device_id=self.device_id))
            except TimeoutError:
                self.link.drop()
                return None
        if pdu is None:
            log.debug("modbus device %s: override input %s: %s", self.name, oi.where(), why)
            return None
        values = list(getattr(pdu, "registers" if oi.table == "holding" else "bits", []) or [])
        if not values:
            return None
        return bool(values[0]) != oi.invert


def _values(pdu: Any, block: RegisterBlock) -> list[int]:
    """The block's registers, or its bits as 0/1 (a bit response is padded to whole bytes,
    so only the first ``count`` bits are the block's)."""
    if block.table not in BIT_TABLES:
        return list(getattr(pdu, "registers", []) or [])
    return [int(bool(b)) for b in list(getattr(pdu, "bits", []) or [])[:block.count]]


def _exception_name(code: int | None) -> str:
    try:
        return f"{int(code)} ({ExcCodes(code).name})"  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return str(code)
