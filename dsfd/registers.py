"""Modbus register maps: encoding, decoding and block-read planning (pure, no I/O).

A :class:`RegisterPoint` says where one engineering value lives on a device, in the manner of
Home Assistant's modbus integration: ``address`` (0-based, as on the wire), ``table``
(``input`` registers, function code 4, or ``holding`` registers, 3/6/16), ``data_type``,
``word_order`` and ``byte_order``, and a linear ``scale``/``offset``::

    engineering value = raw · scale + offset

Byte and word order (the four layouts devices use for 32-bit values)::

    word_order  byte_order   registers of 0xAABBCCDD     usual name
    big         big          [0xAABB, 0xCCDD]            ABCD (Modbus default)
    little      big          [0xCCDD, 0xAABB]            CDAB ("word swap")
    big         little       [0xBBAA, 0xDDCC]            BADC ("byte swap")
    little      little       [0xDDCC, 0xBBAA]            DCBA

pymodbus' ``convert_from_registers`` has ``word_order`` but no byte order (issue #2616), so
the byte swap per register is done here by hand and the whole codec is plain ``struct``
(the tests check it agrees with pymodbus for the layouts pymodbus supports).

``nan_value`` is a device's "no value" code (an open thermocouple often reads 0x7FFF or
0x8000). It is compared with the *raw bit pattern* of the point, as an unsigned integer of
the point's width after word/byte order are undone; a negative number is taken as its two's
complement (``-32768`` ≡ ``0x8000`` for a 16-bit point). A float32 point also decodes IEEE
NaN/±inf; both cases come back from :func:`decode` as a non-finite value.

:func:`plan_reads` merges the points of one device into as few requests as possible: points of
the same table whose gap is at most ``max_gap`` registers go into one block of at most
:data:`MAX_READ_COUNT` registers. Gaps are read and discarded, so ``max_gap > 0`` is only safe
on devices that answer reads of unmapped registers (strict devices reply ILLEGAL_ADDRESS for
the whole block).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Literal, get_args

__all__ = [
    "BIT_TABLES",
    "MAX_READ_COUNT",
    "MAX_WRITE_COUNT",
    "DataType",
    "Order",
    "RegisterBlock",
    "RegisterPoint",
    "Table",
    "decode",
    "decode_raw",
    "encode",
    "from_pattern",
    "matches_nan_value",
    "overlaps",
    "plan_reads",
    "plan_writes",
    "quantise",
    "raw_pattern",
    "register_count",
]

Table = Literal["input", "holding", "coil", "discrete_input"]
#: Tables of single bits (FC 1 and 2): a point there is one bit, 0 or 1, before scale and
#: offset; ``data_type``, the orders and ``nan_value`` do not apply.
BIT_TABLES = frozenset({"coil", "discrete_input"})
DataType = Literal["int16", "uint16", "int32", "uint32", "float32"]
Order = Literal["big", "little"]

#: Largest register count of one read request (Modbus application protocol, FC 3/4).
MAX_READ_COUNT = 125
#: Largest register count of one write-multiple request (FC 16).
MAX_WRITE_COUNT = 123

# struct format character and number of 16-bit registers per data type
_LAYOUT: dict[str, tuple[str, int]] = {
    "int16": ("h", 1),
    "uint16": ("H", 1),
    "int32": ("i", 2),
    "uint32": ("I", 2),
    "float32": ("f", 2),
}
_UNSIGNED = {1: "H", 2: "I"}


def register_count(data_type: DataType) -> int:
    """Number of 16-bit registers a value of ``data_type`` occupies."""
    return _LAYOUT[data_type][1]


@dataclass(frozen=True, kw_only=True)
class RegisterPoint:
    """Where and how one engineering value is stored on a Modbus device.

    Attributes
    ----------
    name : str
        Signal name (``dsfd.signals``), used in error details.
    address : int
        First register, 0-based protocol address (0..65535).
    table : {"input", "holding", "coil", "discrete_input"}
        Register table (actuators live in holding registers), or a bit table: a coil
        (FC 1) or discrete input (FC 2) is one bit, read as 0 or 1.
    data_type : {"int16", "uint16", "int32", "uint32", "float32"}
        Raw type on the device.
    word_order, byte_order : {"big", "little"}
        Register order of a 32-bit value and byte order inside each register.
    scale, offset : float
        Engineering value = raw · scale + offset (scale ≠ 0).
    nan_value : int or None
        Raw "no value" code (bit pattern, see module docstring); stored normalised to
        the unsigned pattern.
    """

    name: str
    address: int
    table: Table = "input"
    data_type: DataType = "float32"
    word_order: Order = "big"
    byte_order: Order = "big"
    scale: float = 1.0
    offset: float = 0.0
    nan_value: int | None = None

    def __post_init__(self) -> None:
        if self.table not in get_args(Table):
            raise ValueError(f"{self.name}: unknown table {self.table!r}")
        if self.data_type not in _LAYOUT:
            raise ValueError(f"{self.name}: unknown data_type {self.data_type!r}")
        for key in ("word_order", "byte_order"):
            if getattr(self, key) not in get_args(Order):
                raise ValueError(f"{self.name}: {key} must be 'big' or 'little'")
        if not 0 <= self.address <= 0xFFFF - self.count + 1:
            raise ValueError(f"{self.name}: address {self.address} outside 0..65535")
        if not (math.isfinite(self.scale) and self.scale != 0.0):
            raise ValueError(f"{self.name}: scale must be finite and non-zero")
        if not math.isfinite(self.offset):
            raise ValueError(f"{self.name}: offset must be finite")
        if self.nan_value is not None and self.is_bit:
            raise ValueError(f"{self.name}: a {self.table} has no nan_value")
        if self.nan_value is not None:
            bits = 16 * self.count
            if not -(1 << (bits - 1)) <= self.nan_value < (1 << bits):
                raise ValueError(f"{self.name}: nan_value {self.nan_value} does not fit "
                                 f"{bits} bits")
            object.__setattr__(self, "nan_value", self.nan_value & ((1 << bits) - 1))

    @property
    def is_bit(self) -> bool:
        """True for a coil or discrete input (one bit, :data:`BIT_TABLES`)."""
        return self.table in BIT_TABLES

    @property
    def count(self) -> int:
        """Registers occupied (1 or 2); a bit point occupies one bit address."""
        return 1 if self.is_bit else _LAYOUT[self.data_type][1]

    @property
    def end(self) -> int:
        """One past the last register address."""
        return self.address + self.count

    def where(self) -> str:
        """Short location for error details, e.g. ``input register 10 (float32)``,
        ``discrete input 3``."""
        if self.is_bit:
            return f"{self.table.replace('_', ' ')} {self.address}"
        return f"{self.table} register {self.address} ({self.data_type})"


def _swap_bytes(register: int) -> int:
    return ((register & 0xFF) << 8) | (register >> 8)


def _to_wire(point: RegisterPoint, words_big_endian: list[int]) -> list[int]:
    """Apply the point's word and byte order to big-endian words (an involution)."""
    words = list(words_big_endian)
    if point.word_order == "little":
        words.reverse()
    if point.byte_order == "little":
        words = [_swap_bytes(w) for w in words]
    return words


def _check_registers(point: RegisterPoint, registers: Sequence[int]) -> None:
    if len(registers) != point.count:
        raise ValueError(f"{point.name}: expected {point.count} registers, got {len(registers)}")
    if any(not 0 <= r <= 0xFFFF for r in registers):
        raise ValueError(f"{point.name}: register value outside 0..65535 in {list(registers)}")


def raw_pattern(point: RegisterPoint, registers: Sequence[int]) -> int:
    """The point's bit pattern as an unsigned integer, word/byte order undone."""
    _check_registers(point, registers)
    pattern = 0
    for word in _to_wire(point, list(registers)):  # the reordering is its own inverse
        pattern = (pattern << 16) | word
    return pattern


def from_pattern(point: RegisterPoint, pattern: int) -> list[int]:
    """Registers holding the unsigned bit ``pattern`` (inverse of :func:`raw_pattern`)."""
    bits = 16 * point.count
    if not 0 <= pattern < (1 << bits):
        raise ValueError(f"{point.name}: pattern {pattern:#x} does not fit {bits} bits")
    words = [(pattern >> (16 * i)) & 0xFFFF for i in reversed(range(point.count))]
    return _to_wire(point, words)


def decode_raw(point: RegisterPoint, registers: Sequence[int]) -> int | float:
    """The raw number stored in ``registers`` (before scale and offset)."""
    fmt, count = _LAYOUT[point.data_type]
    packed = struct.pack(f">{_UNSIGNED[count]}", raw_pattern(point, registers))
    return struct.unpack(f">{fmt}", packed)[0]


def matches_nan_value(point: RegisterPoint, registers: Sequence[int]) -> bool:
    """True if ``registers`` hold the point's configured ``nan_value`` code."""
    return point.nan_value is not None and raw_pattern(point, registers) == point.nan_value


def decode(point: RegisterPoint, registers: Sequence[int]) -> float:
    """Engineering value of ``registers`` [unit of the signal].

    Returns NaN for the ``nan_value`` code; a float32 NaN/±inf passes through as non-finite.
    The caller decides what a non-finite value means (dsfd: quality NOT_FINITE). A bit
    point's one value is 0 or 1 (any non-zero bit is 1).
    """
    if point.is_bit:
        _check_registers(point, registers)
        return float(registers[0] != 0) * point.scale + point.offset
    if matches_nan_value(point, registers):
        return math.nan
    return float(decode_raw(point, registers)) * point.scale + point.offset


def encode(point: RegisterPoint, value: float) -> list[int]:
    """Registers holding engineering ``value`` (inverse of :func:`decode`); a bit point's
    one value 0 or 1.

    Integer types round to the nearest raw step; a value whose raw number does not fit
    the type raises ``ValueError`` naming the point. Float32 accepts NaN (emulators use it).
    """
    fmt, count = _LAYOUT[point.data_type]
    raw = (value - point.offset) / point.scale
    if point.is_bit:
        if raw not in (0.0, 1.0):
            raise ValueError(f"{point.name}: {value!r} is no bit (raw {raw!r}, expected 0 or 1)")
        return [int(raw)]
    try:
        if fmt == "f":
            packed = struct.pack(">f", raw)
        else:
            if not math.isfinite(raw):
                raise ValueError(f"{point.name}: cannot encode {value!r} as {point.data_type}")
            packed = struct.pack(f">{fmt}", round(raw))
    except (struct.error, OverflowError) as exc:
        raise ValueError(f"{point.name}: {value!r} (raw {raw!r}) does not fit "
                         f"{point.data_type}") from exc
    words = [int.from_bytes(packed[i:i + 2], "big") for i in range(0, 2 * count, 2)]
    return _to_wire(point, words)


def quantise(point: RegisterPoint, value: float) -> float:
    """The engineering value the device will actually hold after :func:`encode` of ``value``."""
    return float(decode_raw(point, encode(point, value))) * point.scale + point.offset


def overlaps(points: Iterable[RegisterPoint]) -> list[tuple[RegisterPoint, RegisterPoint]]:
    """Pairs of points in the same table whose register ranges intersect."""
    out: list[tuple[RegisterPoint, RegisterPoint]] = []
    for table in get_args(Table):
        ordered = sorted((p for p in points if p.table == table), key=lambda p: p.address)
        reach: RegisterPoint | None = None  # the point reaching furthest so far
        for p in ordered:
            if reach is not None and p.address < reach.end:
                out.append((reach, p))
            if reach is None or p.end > reach.end:
                reach = p
    return out


@dataclass(frozen=True)
class RegisterBlock:
    """One read or write request: ``count`` registers of ``table`` from ``address``."""

    table: Table
    address: int
    count: int
    points: tuple[RegisterPoint, ...]

    @property
    def end(self) -> int:
        """One past the last register of the block."""
        return self.address + self.count

    def registers_of(self, point: RegisterPoint, registers: Sequence[int]) -> list[int]:
        """The slice of a block response that belongs to ``point``."""
        start = point.address - self.address
        return list(registers[start:start + point.count])

    def where(self) -> str:
        """E.g. ``input registers 0..11``, ``coils 4..5``."""
        what = {"coil": "coils", "discrete_input": "discrete inputs"}.get(
            self.table, f"{self.table} registers")
        return f"{what} {self.address}..{self.end - 1}"


def plan_reads(points: Iterable[RegisterPoint], *, max_gap: int = 0,
               max_count: int = MAX_READ_COUNT) -> tuple[RegisterBlock, ...]:
    """Fewest read blocks covering ``points`` (input table first, then by address).

    Points of one table merge while the gap to the block is ≤ ``max_gap`` registers and the
    block stays ≤ ``max_count`` registers. Greedy left-to-right is optimal here: each block
    starts at the lowest uncovered point and takes the longest prefix that fits.
    """
    if max_gap < 0 or not 1 <= max_count <= MAX_READ_COUNT:
        raise ValueError("need max_gap >= 0 and 1 <= max_count <= 125")
    blocks: list[RegisterBlock] = []
    for table in get_args(Table):
        ordered = sorted((p for p in points if p.table == table), key=lambda p: (p.address, p.end))
        current: list[RegisterPoint] = []
        start = end = 0
        for p in ordered:
            if current and p.address - end <= max_gap and max(end, p.end) - start <= max_count:
                current.append(p)
                end = max(end, p.end)
                continue
            if current:
                blocks.append(RegisterBlock(table, start, end - start, tuple(current)))
            current, start, end = [p], p.address, p.end
        if current:
            blocks.append(RegisterBlock(table, start, end - start, tuple(current)))
    return tuple(blocks)


def plan_writes(points: Iterable[RegisterPoint], *,
                max_count: int = MAX_WRITE_COUNT) -> tuple[RegisterBlock, ...]:
    """Write blocks of exactly contiguous holding points (a gap would overwrite a register
    dsfd does not own). Overlapping or non-holding points raise ``ValueError``."""
    pts = list(points)
    if any(p.table != "holding" for p in pts):
        raise ValueError("only holding registers can be written")
    if overlaps(pts):
        raise ValueError("overlapping actuator registers")
    return plan_reads(pts, max_gap=0, max_count=max_count)
