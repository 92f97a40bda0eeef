"""What crosses the device edge: readings with quality flags, commands, write results, drivers.

A driver turns one device (or one serial line) into :class:`Sample` objects and accepts
:class:`Command` objects. The contract that keeps the daemon alive: ``read`` and ``write``
**never raise for device faults**. A dead, busy or garbled device yields readings with a bad
:class:`Quality` whose ``detail`` names the device, table/address or port, so the quality
checks, the safety pipeline and the log can say exactly what is wrong. Exceptions are for
programming errors only.

:class:`CompositeDriver` puts several drivers behind the same interface: it reads them
concurrently, merges their samples and routes each actuator value to the driver that owns it.
"""

from __future__ import annotations

import asyncio
import enum
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Protocol, runtime_checkable

from dsfd.signals import ACTUATOR_NAMES, ACTUATORS

__all__ = [
    "Command",
    "CompositeDriver",
    "Driver",
    "Quality",
    "Reading",
    "Sample",
    "WriteResult",
    "command_from_values",
]


class Quality(enum.Enum):
    """Why a reading can or cannot be used. Only ``GOOD`` carries a usable value."""

    GOOD = "good"
    #: No driver delivers this signal, or the source sent "no value" for it.
    MISSING = "missing"
    #: The device did not answer within timeout·(retries+1).
    TIMEOUT = "timeout"
    #: The link is down (connect refused/failed, port absent); nothing was asked.
    DISCONNECTED = "disconnected"
    #: The circuit breaker skips a device that kept timing out; nothing was asked.
    SKIPPED = "skipped"
    #: The device answered with a Modbus exception (busy, illegal address, ...).
    DEVICE_ERROR = "device_error"
    #: Garbled data: bad checksum, partial line, wrong field count, non-numeric field.
    FRAMING = "framing"
    #: NaN/±inf or the point's ``nan_value`` code.
    NOT_FINITE = "not_finite"
    #: Outside the physical plausibility range (set by quality checks, not by drivers).
    OUT_OF_RANGE = "out_of_range"
    #: No fresh value this cycle (set by drivers that receive pushed data, and by checks).
    STALE = "stale"
    #: Value did not change over a window (set by quality checks).
    STUCK = "stuck"


@dataclass(frozen=True)
class Reading:
    """One value of one signal with its quality.

    ``value`` is in the signal's unit and is NaN whenever ``quality`` is not GOOD.
    ``source`` names the device (config ``name``); ``detail`` says what went wrong and where.
    """

    value: float
    quality: Quality
    source: str
    detail: str = ""

    @property
    def ok(self) -> bool:
        """True if the value may be used."""
        return self.quality is Quality.GOOD

    @classmethod
    def good(cls, value: float, source: str) -> Reading:
        """A GOOD reading; a non-finite ``value`` becomes NOT_FINITE instead."""
        if not math.isfinite(value):
            return cls(math.nan, Quality.NOT_FINITE, source, f"{source}: value {value!r}")
        return cls(float(value), Quality.GOOD, source)

    @classmethod
    def bad(cls, quality: Quality, source: str, detail: str) -> Reading:
        """A reading without a usable value."""
        if quality is Quality.GOOD:
            raise ValueError("a bad reading cannot have quality GOOD")
        return cls(math.nan, quality, source, detail)


@dataclass(frozen=True)
class Sample:
    """All readings taken in one cycle, stamped with ``time_s`` [s, as given by the caller;
    the daemon passes UTC epoch seconds]."""

    time_s: float
    readings: Mapping[str, Reading] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # Freeze the mapping too, so a Sample can be shared with the store and the log safely.
        object.__setattr__(self, "readings", MappingProxyType(dict(self.readings)))

    def good(self, name: str) -> float | None:
        """Value of ``name`` if present and GOOD, else None."""
        r = self.readings.get(name)
        return r.value if r is not None and r.ok else None

    def quality(self, name: str) -> Quality:
        """Quality of ``name``; MISSING if no driver delivered it."""
        r = self.readings.get(name)
        return r.quality if r is not None else Quality.MISSING

    def bad(self) -> dict[str, Reading]:
        """The readings that are not GOOD."""
        return {k: r for k, r in self.readings.items() if not r.ok}

    def merged(self, other: Sample) -> Sample:
        """Readings of both samples (``other`` wins on a name clash), stamped ``self.time_s``."""
        return Sample(self.time_s, {**self.readings, **other.readings})


@dataclass(frozen=True)
class Command:
    """Actuator set-points for one cycle.

    ``phi_deg`` louver angle [deg, −90..90], ``afr`` airflow regime [1..10],
    ``or_pct`` damper opening ratio [%, 0..100]. Out-of-range or non-finite values raise
    ``ValueError``: the safety pipeline must never hand such a command to a driver.
    """

    phi_deg: float
    afr: int
    or_pct: float

    def __post_init__(self) -> None:
        for name, value in self.as_dict().items():
            sig = ACTUATORS[name]
            if not (math.isfinite(value) and sig.plausible(value)):
                raise ValueError(f"{name}={value!r} outside {sig.lower}..{sig.upper} {sig.unit}")
        if isinstance(self.afr, bool) or int(self.afr) != self.afr:
            raise ValueError(f"afr={self.afr!r} must be a whole regime number")
        object.__setattr__(self, "afr", int(self.afr))
        object.__setattr__(self, "phi_deg", float(self.phi_deg))
        object.__setattr__(self, "or_pct", float(self.or_pct))

    def as_dict(self) -> dict[str, float]:
        """``{"phi_deg": ..., "afr": ..., "or_pct": ...}``."""
        return {"phi_deg": self.phi_deg, "afr": self.afr, "or_pct": self.or_pct}


def command_from_values(values: Mapping[str, float]) -> Command | None:
    """A :class:`Command` from read-back values, or None if one is missing or invalid."""
    if any(name not in values for name in ACTUATOR_NAMES):
        return None
    try:
        return Command(phi_deg=float(values["phi_deg"]), afr=round(values["afr"]),
                       or_pct=float(values["or_pct"]))
    except (ValueError, OverflowError):
        return None


@dataclass(frozen=True)
class WriteResult:
    """Outcome of writing one :class:`Command`.

    Attributes
    ----------
    requested : Command
        What the controller asked for.
    owned : frozenset of str
        Actuators the driver(s) are responsible for (the others were not touched).
    written : Mapping[str, float]
        Actuators whose write the device acknowledged, with the value actually stored
        (after the register's scale/rounding) [signal unit].
    verified : frozenset of str
        Actuators whose read-back registers equal the written registers.
    read_back : Mapping[str, float]
        Values read back after the write [signal unit].
    errors : tuple of str
        One line per failure, naming device, table and address.
    """

    requested: Command
    owned: frozenset[str] = frozenset()
    written: Mapping[str, float] = field(default_factory=dict)
    verified: frozenset[str] = frozenset()
    read_back: Mapping[str, float] = field(default_factory=dict)
    errors: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "written", MappingProxyType(dict(self.written)))
        object.__setattr__(self, "read_back", MappingProxyType(dict(self.read_back)))

    @property
    def ok(self) -> bool:
        """True if every owned actuator was written and verified, without errors."""
        return not self.errors and self.verified == self.owned

    def merged(self, other: WriteResult) -> WriteResult:
        """Union of two results for the same command (from different drivers)."""
        return WriteResult(
            requested=self.requested,
            owned=self.owned | other.owned,
            written={**self.written, **other.written},
            verified=self.verified | other.verified,
            read_back={**self.read_back, **other.read_back},
            errors=self.errors + other.errors,
        )


@runtime_checkable
class Driver(Protocol):
    """One device (or line) at the edge. ``read``/``write`` never raise for device faults."""

    name: str

    @property
    def sensor_names(self) -> frozenset[str]:
        """Signals this driver delivers in every :class:`Sample`."""
        ...

    @property
    def actuator_names(self) -> frozenset[str]:
        """Actuators this driver writes."""
        ...

    async def start(self) -> None:
        """Open ports / first connect. A device that is down is not an error here."""
        ...

    async def read(self, time_s: float) -> Sample:
        """One reading per sensor signal, stamped ``time_s`` [s]."""
        ...

    async def write(self, cmd: Command) -> WriteResult:
        """Write the owned actuators of ``cmd`` and verify them by read-back."""
        ...

    async def read_actuators(self) -> Mapping[str, float]:
        """Current values of the owned actuators that could be read [signal units]."""
        ...

    async def read_back(self) -> Command | None:
        """The device's current command if all three actuators are readable, else None."""
        ...

    @property
    def override_input(self) -> str | None:
        """Where this driver reads the panel's hand/auto input (None: it has none)."""
        ...

    async def read_override_input(self) -> bool | None:
        """True while the override input is active, False if not, None if it could not be
        read (or there is none)."""
        ...

    async def close(self) -> None:
        """Release ports and connections; idempotent."""
        ...


class CompositeDriver:
    """Several drivers behind one :class:`Driver` interface.

    Reads run concurrently (a dead TCP device does not delay the weather station), so the
    read time of a cycle is the slowest driver's, not the sum. A signal delivered by two
    drivers is a configuration error and raises ``ValueError`` at construction.
    """

    def __init__(self, drivers: Sequence[Driver], *, name: str = "composite") -> None:
        self.name = name
        self.drivers: tuple[Driver, ...] = tuple(drivers)
        self._sensor_owner = _owners(self.drivers, "sensor_names")
        self._actuator_owner = _owners(self.drivers, "actuator_names")

    @property
    def sensor_names(self) -> frozenset[str]:
        return frozenset(self._sensor_owner)

    @property
    def actuator_names(self) -> frozenset[str]:
        return frozenset(self._actuator_owner)

    def driver_for(self, signal_name: str) -> Driver | None:
        """The driver that delivers or writes ``signal_name``."""
        return self._sensor_owner.get(signal_name) or self._actuator_owner.get(signal_name)

    async def start(self) -> None:
        await asyncio.gather(*(d.start() for d in self.drivers))

    async def read(self, time_s: float) -> Sample:
        samples = await asyncio.gather(*(d.read(time_s) for d in self.drivers))
        merged = Sample(time_s)
        for s in samples:
            merged = merged.merged(s)
        return merged

    async def write(self, cmd: Command) -> WriteResult:
        writers = [d for d in self.drivers if d.actuator_names]
        results = await asyncio.gather(*(d.write(cmd) for d in writers))
        out = WriteResult(requested=cmd)
        for r in results:
            out = out.merged(r)
        return out

    async def read_actuators(self) -> Mapping[str, float]:
        parts = await asyncio.gather(
            *(d.read_actuators() for d in self.drivers if d.actuator_names))
        values: dict[str, float] = {}
        for p in parts:
            values.update(p)
        return values

    async def read_back(self) -> Command | None:
        return command_from_values(await self.read_actuators())

    @property
    def override_input(self) -> str | None:
        labels = [label for d in self.drivers if (label := d.override_input)]
        return labels[0] if labels else None

    async def read_override_input(self) -> bool | None:
        for d in self.drivers:  # the configuration allows one override input per panel
            if d.override_input:
                return await d.read_override_input()
        return None

    async def close(self) -> None:
        # Close every driver even if one fails, then report the first failure.
        results = await asyncio.gather(*(d.close() for d in self.drivers),
                                       return_exceptions=True)
        for r in results:
            if isinstance(r, BaseException):
                raise r


def _owners(drivers: Iterable[Driver], attr: str) -> dict[str, Driver]:
    owner: dict[str, Driver] = {}
    for d in drivers:
        for sig in getattr(d, attr):
            if sig in owner:
                raise ValueError(f"signal {sig!r} delivered by both {owner[sig].name!r} "
                                 f"and {d.name!r}")
            owner[sig] = d
    return owner
