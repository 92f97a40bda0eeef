"""Serial ASCII weather station: the line protocol (pure) and its driver (pyserial).

Protocol (full text: ``docs/weather-station-protocol.md``). The station pushes one line every
few seconds, NMEA style::

    $WXDSF,<seq>,<t_out_c>,<ghi_wm2>,<wind_speed_ms>,<wind_dir_deg>,<rh_pct>,<pressure_hpa>*HH\\r\\n

``seq`` counts lines modulo 65536; the six values are decimal numbers in the units of their
names (°C, W/m², m/s, degrees from north, %, hPa); an empty field means "sensor has no value";
``HH`` is the XOR of every byte between ``$`` and ``*`` as two hex digits. ASCII only, at most
:data:`MAX_LINE_BYTES` bytes including the terminator (LF, optionally preceded by CR).

Parsing (:func:`parse_line`) is strict: a line without terminator (pyserial's ``read_until``
returns what it has on timeout), a bad checksum, a wrong sentence or field count, a
non-decimal number (``nan``, ``1e3``, ``0x10`` included) raise :class:`FramingError`, which the
driver counts per kind and never turns into a value. Bytes before the last ``$`` of a line are
counted as garbage and the rest is parsed, so a line after line noise is not lost.

The driver (:class:`StationDriver`) opens the port with ``serial.serial_for_url`` (device
paths, ptys, ``loop://``, ``socket://``), flushes what was buffered before start, and once per
cycle drains the port in a worker thread (``asyncio.to_thread``): it keeps the newest valid
line received since the last cycle. No valid line ⇒ every station signal is STALE for that
cycle; the previous value is never repeated. Worst-case time per cycle: ``2 · timeout_s``.
"""

from __future__ import annotations

import asyncio
import logging
import re
import time
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import serial

from dsfd.config.devices import STATION_SIGNALS
from dsfd.drivers.base import Command, Quality, Reading, Sample, WriteResult
from dsfd.drivers.resilience import Backoff

if TYPE_CHECKING:
    from dsfd.config.devices import DeviceConfig

__all__ = [
    "MAX_LINE_BYTES",
    "SENTENCE",
    "STATION_SIGNALS",
    "FramingError",
    "StationDriver",
    "StationLine",
    "checksum",
    "format_line",
    "parse_line",
]

log = logging.getLogger(__name__)

#: Sentence identifier after ``$``.
SENTENCE = "WXDSF"
#: Longest accepted line including CR LF [bytes].
MAX_LINE_BYTES = 128
_NUMBER = re.compile(r"^[+-]?(?:\d+(?:\.\d*)?|\.\d+)$")
_HEX2 = re.compile(r"^[0-9A-Fa-f]{2}$")


class FramingError(ValueError):
    """A line that is not a valid protocol line; ``kind`` classifies it for counters."""

    def __init__(self, kind: str, detail: str) -> None:
        super().__init__(f"{kind}: {detail}")
        self.kind = kind


@dataclass(frozen=True)
class StationLine:
    """One valid line: sequence number and values (None = station sent no value)."""

    seq: int
    values: Mapping[str, float | None]

    def __post_init__(self) -> None:
        object.__setattr__(self, "values", MappingProxyType(dict(self.values)))


def checksum(payload: bytes) -> int:
    """XOR of all bytes of ``payload`` (the text between ``$`` and ``*``)."""
    out = 0
    for b in payload:
        out ^= b
    return out


def format_line(seq: int, values: Mapping[str, float | None], *, decimals: int = 2) -> bytes:
    """The protocol line for ``values`` (missing or None ⇒ empty field), CR LF terminated."""
    fields = [SENTENCE, str(seq % 65536)]
    for name in STATION_SIGNALS:
        v = values.get(name)
        fields.append("" if v is None else f"{v:.{decimals}f}")
    body = ",".join(fields).encode("ascii")
    return b"$" + body + f"*{checksum(body):02X}\r\n".encode("ascii")


def parse_line(raw: bytes) -> StationLine:
    """Parse one line including its terminator; raise :class:`FramingError` if invalid."""
    if not raw.endswith(b"\n"):
        if len(raw) >= MAX_LINE_BYTES:
            raise FramingError("too_long", f"no terminator within {MAX_LINE_BYTES} bytes")
        raise FramingError("partial", f"incomplete line {raw[:40]!r} (no terminator)")
    text = raw[:-2] if raw.endswith(b"\r\n") else raw[:-1]
    if not text:
        raise FramingError("empty", "empty line")
    if any(not 0x20 <= b <= 0x7E for b in text):
        raise FramingError("garbage", f"non-printable bytes in {text[:40]!r}")
    if not text.startswith(b"$"):
        raise FramingError("start", f"line does not start with '$': {text[:40]!r}")
    body, star, given = text[1:].partition(b"*")
    if not star or not _HEX2.match(given.decode("ascii")):
        raise FramingError("checksum", f"missing or malformed '*HH' in {text[:40]!r}")
    if checksum(body) != int(given, 16):
        raise FramingError("checksum",
                           f"checksum {given.decode()} != computed {checksum(body):02X}")
    fields = body.decode("ascii").split(",")
    if fields[0] != SENTENCE:
        raise FramingError("sentence", f"sentence {fields[0]!r}, expected {SENTENCE!r}")
    if len(fields) != 2 + len(STATION_SIGNALS):
        raise FramingError("fields", f"{len(fields) - 2} values, expected "
                           f"{len(STATION_SIGNALS)}")
    seq_text = fields[1]
    if not seq_text.isdigit() or not seq_text.isascii() or int(seq_text) > 65535:
        raise FramingError("seq", f"sequence number {seq_text!r}")
    values: dict[str, float | None] = {}
    for name, text_value in zip(STATION_SIGNALS, fields[2:], strict=True):
        if text_value == "":
            values[name] = None
        elif _NUMBER.match(text_value):
            values[name] = float(text_value)
        else:
            raise FramingError("number", f"{name} field {text_value!r} is not a decimal number")
    return StationLine(seq=int(seq_text), values=values)


@dataclass
class _Drain:
    """What one drain of the port found (built in the worker thread)."""

    newest: StationLine | None = None
    seqs: list[int] = field(default_factory=list)
    framing: Counter[str] = field(default_factory=Counter)
    last_framing: str = ""

    def take(self, raw: bytes) -> None:
        start = raw.rfind(b"$")
        if start > 0:  # line noise before a start character: count it, parse the rest
            self.framing["garbage"] += 1
            self.last_framing = f"garbage: {start} bytes before '$'"
            raw = raw[start:]
        try:
            line = parse_line(raw)
        except FramingError as exc:
            self.framing[exc.kind] += 1
            self.last_framing = str(exc)
            return
        self.newest = line
        self.seqs.append(line.seq)


class StationDriver:
    """Reads the serial weather station; delivers :data:`STATION_SIGNALS`, writes nothing."""

    def __init__(self, *, name: str, url: str, baudrate: int = 9600, bytesize: int = 8,
                 parity: str = "N", stopbits: int = 1, timeout_s: float = 1.0,
                 backoff: Backoff | None = None, clock: Callable[[], float] = time.monotonic,
                 ) -> None:
        self.name = name
        self.url = url
        self.timeout_s = timeout_s
        self.backoff = backoff or Backoff(min_s=1.0, max_s=60.0)
        #: lines_ok, framing_errors, framing_<kind>, seq_gaps, seq_repeats, seq_resets,
        #: cycles_stale, open_attempts, open_failures, port_errors.
        self.counters: Counter[str] = Counter()
        #: Newest valid line ever received (for diagnostics only, never used as a value).
        self.last_line: StationLine | None = None
        self._settings: dict[str, Any] = {"baudrate": baudrate, "bytesize": bytesize,
                                          "parity": parity, "stopbits": stopbits}
        self._clock = clock
        self._port: serial.SerialBase | None = None
        self._label = f"{name} on {url}"

    @classmethod
    def from_config(cls, cfg: DeviceConfig, *, clock: Callable[[], float] = time.monotonic
                    ) -> StationDriver:
        assert cfg.serial is not None
        line = cfg.serial
        return cls(name=cfg.name, url=line.port, baudrate=line.baudrate,
                   bytesize=line.bytesize, parity=line.parity, stopbits=line.stopbits,
                   timeout_s=cfg.timeout_s, clock=clock,
                   backoff=Backoff(min_s=cfg.reconnect_backoff_min_s,
                                   max_s=cfg.reconnect_backoff_max_s))

    @property
    def sensor_names(self) -> frozenset[str]:
        return frozenset(STATION_SIGNALS)

    @property
    def actuator_names(self) -> frozenset[str]:
        return frozenset()

    async def start(self) -> None:
        await self._ensure_open()

    async def _ensure_open(self) -> str | None:
        if self._port is not None:
            return None
        now = self._clock()
        if not self.backoff.ready(now):
            return f"port closed, next open attempt in {self.backoff.wait_s(now):.1f} s"
        self.counters["open_attempts"] += 1
        try:
            self._port = await asyncio.to_thread(self._open)
        except (serial.SerialException, OSError, ValueError) as exc:
            delay = self.backoff.failed(now)
            self.counters["open_failures"] += 1
            log.warning("station %s: cannot open: %s; retry in %.1f s", self._label, exc, delay)
            return f"cannot open port: {exc}"
        self.backoff.succeeded()
        return None

    def _open(self) -> serial.SerialBase:
        port = serial.serial_for_url(self.url, timeout=self.timeout_s, exclusive=True,
                                     **self._settings)
        port.reset_input_buffer()  # lines buffered before start are not "since the last cycle"
        return port

    def _drain(self, port: serial.SerialBase) -> _Drain:
        """Read every complete line waiting on the port (worker thread)."""
        found = _Drain()
        deadline = time.monotonic() + self.timeout_s
        while True:
            raw = port.read_until(b"\n", MAX_LINE_BYTES)
            if not raw:
                break  # read timeout: nothing (more) was sent
            found.take(raw)
            if raw.endswith(b"\n") and port.in_waiting == 0:
                break  # drained up to a line boundary
            if time.monotonic() >= deadline:
                break  # a chattering line must not hold the cycle
        return found

    async def read(self, time_s: float) -> Sample:
        reason = await self._ensure_open()
        port = self._port
        if reason is not None or port is None:
            return self._all_bad(time_s, Quality.DISCONNECTED, f"{self._label}: {reason}")
        try:
            found = await asyncio.to_thread(self._drain, port)
        except (serial.SerialException, OSError) as exc:
            self.counters["port_errors"] += 1
            await self.close()
            log.warning("station %s: port error %s; reopening", self._label, exc)
            return self._all_bad(time_s, Quality.DISCONNECTED, f"{self._label}: port error {exc}")
        self._count(found)
        if found.newest is None:
            self.counters["cycles_stale"] += 1
            n_bad = sum(found.framing.values())
            last = f"; last: {found.last_framing}" if found.last_framing else ""
            return self._all_bad(time_s, Quality.STALE,
                                 f"{self._label}: no valid line since the last cycle "
                                 f"({n_bad} framing errors{last})")
        line = found.newest
        self.last_line = line
        readings: dict[str, Reading] = {}
        for name in STATION_SIGNALS:
            value = line.values.get(name)
            readings[name] = (Reading.good(value, self.name) if value is not None else
                              Reading.bad(Quality.MISSING, self.name,
                                          f"{self._label}: line {line.seq} has no {name}"))
        return Sample(time_s, readings)

    def _count(self, found: _Drain) -> None:
        self.counters["lines_ok"] += len(found.seqs)
        for kind, n in found.framing.items():
            self.counters["framing_errors"] += n
            self.counters[f"framing_{kind}"] += n
        if found.framing:
            log.debug("station %s: %d framing errors, last: %s", self._label,
                      sum(found.framing.values()), found.last_framing)
        previous = self.last_line.seq if self.last_line is not None else None
        for seq in found.seqs:
            step = None if previous is None else (seq - previous) % 65536
            if step == 0:
                self.counters["seq_repeats"] += 1
            elif step is not None and step < 32768:
                self.counters["seq_gaps"] += step - 1  # lines lost on the way
            elif step is not None:
                self.counters["seq_resets"] += 1  # jumped back: station restarted
            previous = seq

    def _all_bad(self, time_s: float, quality: Quality, detail: str) -> Sample:
        return Sample(time_s, {n: Reading.bad(quality, self.name, detail)
                               for n in STATION_SIGNALS})

    async def write(self, cmd: Command) -> WriteResult:
        return WriteResult(requested=cmd)

    async def read_actuators(self) -> Mapping[str, float]:
        return {}

    async def read_back(self) -> Command | None:
        return None

    @property
    def override_input(self) -> str | None:
        return None

    async def read_override_input(self) -> bool | None:
        return None

    async def close(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            await asyncio.to_thread(port.close)
