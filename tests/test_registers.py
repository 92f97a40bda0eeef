"""Register codec and block planning (pure)."""

from __future__ import annotations

import itertools
import math
import random

import pytest
from pymodbus.client.mixin import ModbusClientMixin

from dsfd.registers import (
    MAX_READ_COUNT,
    RegisterPoint,
    decode,
    decode_raw,
    encode,
    from_pattern,
    matches_nan_value,
    overlaps,
    plan_reads,
    plan_writes,
    quantise,
    raw_pattern,
)

TYPES = ("int16", "uint16", "int32", "uint32", "float32")
ORDERS = ("big", "little")


def pt(address: int = 0, data_type: str = "float32", **kw: object) -> RegisterPoint:
    return RegisterPoint(name=kw.pop("name", f"p{address}"), address=address,  # type: ignore[arg-type]
                         data_type=data_type, **kw)  # type: ignore[arg-type]


# ------------------------------------------------------------------ known vectors
@pytest.mark.parametrize(("word", "byte", "regs"), [
    ("big", "big", [16812, 0]),          # ABCD: 21.5 = 0x41AC0000
    ("little", "big", [0, 16812]),       # CDAB
    ("big", "little", [0xAC41, 0]),      # BADC
    ("little", "little", [0, 0xAC41]),   # DCBA
])
def test_float32_21_5_in_all_four_layouts(word: str, byte: str, regs: list[int]) -> None:
    p = pt(data_type="float32", word_order=word, byte_order=byte)
    assert encode(p, 21.5) == regs
    assert decode(p, regs) == 21.5


@pytest.mark.parametrize(("word", "byte", "regs"), [
    ("big", "big", [0x1234, 0x5678]),
    ("little", "big", [0x5678, 0x1234]),
    ("big", "little", [0x3412, 0x7856]),
    ("little", "little", [0x7856, 0x3412]),
])
def test_uint32_layouts(word: str, byte: str, regs: list[int]) -> None:
    p = pt(data_type="uint32", word_order=word, byte_order=byte)
    assert encode(p, 0x12345678) == regs
    assert decode_raw(p, regs) == 0x12345678
    assert raw_pattern(p, regs) == 0x12345678


@pytest.mark.parametrize(("data_type", "value", "regs"), [
    ("int16", -1, [0xFFFF]),
    ("int16", -32768, [0x8000]),
    ("int16", 32767, [0x7FFF]),
    ("uint16", 65535, [0xFFFF]),
    ("int32", -2, [0xFFFF, 0xFFFE]),
    ("int32", -(2**31), [0x8000, 0x0000]),
    ("uint32", 2**32 - 1, [0xFFFF, 0xFFFF]),
])
def test_integer_vectors_including_negative(data_type: str, value: int, regs: list[int]) -> None:
    p = pt(data_type=data_type)
    assert encode(p, value) == regs
    assert decode(p, regs) == value


def test_int16_byte_swap_and_word_order_is_ignored_for_one_register() -> None:
    p = pt(data_type="int16", byte_order="little", word_order="little")
    assert encode(p, -2) == [0xFEFF]
    assert decode(p, [0xFEFF]) == -2


def test_int32_negative_word_swapped() -> None:
    p = pt(data_type="int32", word_order="little")
    assert encode(p, -2) == [0xFFFE, 0xFFFF]
    assert decode(p, [0xFFFE, 0xFFFF]) == -2


def test_scale_and_offset() -> None:
    kelvin_tenths = pt(data_type="uint16", scale=0.1, offset=-273.1)  # raw in 0.1 K
    assert encode(kelvin_tenths, 0.0) == [2731]
    assert decode(kelvin_tenths, [2931]) == pytest.approx(20.0)
    tenths = pt(data_type="int16", scale=0.1)
    assert encode(tenths, -12.3) == [(-123) & 0xFFFF]
    assert decode(tenths, [(-123) & 0xFFFF]) == pytest.approx(-12.3)
    assert quantise(tenths, 36.04) == pytest.approx(36.0)
    negative_scale = pt(data_type="int16", scale=-2.0, offset=10.0)
    assert decode(negative_scale, encode(negative_scale, 4.0)) == 4.0


# ------------------------------------------------------------------ round trips
@pytest.mark.parametrize(("data_type", "word", "byte"),
                         list(itertools.product(TYPES, ORDERS, ORDERS)))
def test_round_trip_random_values(data_type: str, word: str, byte: str) -> None:
    rng = random.Random(hash((data_type, word, byte)) & 0xFFFF)
    p = pt(data_type=data_type, word_order=word, byte_order=byte, scale=0.5, offset=-3.0)
    lo, hi = {"int16": (-32768, 32767), "uint16": (0, 65535), "int32": (-(2**31), 2**31 - 1),
              "uint32": (0, 2**32 - 1), "float32": (-1e6, 1e6)}[data_type]
    for _ in range(200):
        raw = rng.uniform(lo, hi) if data_type == "float32" else rng.randint(lo, hi)
        value = raw * 0.5 - 3.0
        regs = encode(p, value)
        assert len(regs) == p.count and all(0 <= r <= 0xFFFF for r in regs)
        assert decode(p, regs) == pytest.approx(quantise(p, value), rel=1e-7, abs=1e-9)
        assert encode(p, decode(p, regs)) == regs
        assert from_pattern(p, raw_pattern(p, regs)) == regs


@pytest.mark.parametrize(("data_type", "word"), list(itertools.product(TYPES, ORDERS)))
def test_agrees_with_pymodbus_convert(data_type: str, word: str) -> None:
    # pymodbus has word order but no byte order: compare the layouts it supports.
    dt = getattr(ModbusClientMixin.DATATYPE, data_type.upper())
    p = pt(data_type=data_type, word_order=word)
    rng = random.Random(7)
    for _ in range(100):
        regs = [rng.randrange(65536) for _ in range(p.count)]
        theirs = ModbusClientMixin.convert_from_registers(regs, dt, word_order=word)
        ours = decode_raw(p, regs)
        if isinstance(theirs, float) and math.isnan(theirs):
            assert math.isnan(ours)
        else:
            assert ours == theirs
        if not (isinstance(ours, float) and not math.isfinite(ours)):
            assert encode(p, ours) == ModbusClientMixin.convert_to_registers(
                theirs, dt, word_order=word)


# ------------------------------------------------------------------ bad values, NaN
@pytest.mark.parametrize(("data_type", "value"), [
    ("int16", 32768), ("int16", -32769), ("uint16", -1), ("uint16", 65536),
    ("int32", 2**31), ("uint32", -1), ("float32", 1e39), ("int16", math.nan),
    ("uint16", math.inf),
])
def test_encode_refuses_values_that_do_not_fit(data_type: str, value: float) -> None:
    with pytest.raises(ValueError, match="p0"):
        encode(pt(data_type=data_type), value)


def test_float32_nan_and_inf_decode_as_non_finite() -> None:
    p = pt()
    assert math.isnan(decode(p, encode(p, math.nan)))
    assert decode(p, [0x7F80, 0]) == math.inf
    assert decode(p, [0xFF80, 0]) == -math.inf


def test_nan_value_matches_bit_pattern_after_reordering() -> None:
    p16 = pt(data_type="int16", nan_value=-32768)
    assert p16.nan_value == 0x8000  # two's complement normalised
    assert matches_nan_value(p16, [0x8000]) and math.isnan(decode(p16, [0x8000]))
    assert decode(p16, [0x7FFF]) == 32767  # only the configured code is "no value"
    swapped = pt(data_type="uint16", byte_order="little", nan_value=0x7FFF)
    assert matches_nan_value(swapped, [0xFF7F])
    assert not matches_nan_value(swapped, [0x7FFF])
    p32 = pt(data_type="int32", word_order="little", nan_value=0x80000000)
    assert from_pattern(p32, 0x80000000) == [0x0000, 0x8000]
    assert math.isnan(decode(p32, [0x0000, 0x8000]))


@pytest.mark.parametrize("kw", [
    {"address": -1}, {"address": 65535, "data_type": "float32"}, {"scale": 0.0},
    {"scale": math.inf}, {"offset": math.nan}, {"nan_value": 0x10000, "data_type": "int16"},
    {"table": "register"}, {"data_type": "float64"}, {"word_order": "middle"},
    {"table": "coil", "nan_value": 0},  # a bit has no "no value" code
])
def test_point_validation(kw: dict[str, object]) -> None:
    args: dict[str, object] = {"name": "bad", "address": 0}
    args.update(kw)
    with pytest.raises(ValueError, match="bad"):
        RegisterPoint(**args)  # type: ignore[arg-type]


def test_wrong_register_count_or_value_is_rejected() -> None:
    with pytest.raises(ValueError):
        decode(pt(), [1])
    with pytest.raises(ValueError):
        decode(pt(data_type="uint16"), [70000])


# ------------------------------------------------------------------ planning
def test_contiguous_points_merge_into_one_block() -> None:
    points = [pt(0), pt(2), pt(4, "int16"), pt(5, "uint32")]
    (block,) = plan_reads(points)
    assert (block.table, block.address, block.count) == ("input", 0, 7)
    assert block.registers_of(points[3], list(range(7))) == [5, 6]


def test_gap_splits_unless_allowed() -> None:
    points = [pt(0), pt(10)]
    assert [(b.address, b.count) for b in plan_reads(points)] == [(0, 2), (10, 2)]
    assert [(b.address, b.count) for b in plan_reads(points, max_gap=8)] == [(0, 12)]
    assert len(plan_reads(points, max_gap=7)) == 2


def test_tables_never_merge_and_input_comes_first() -> None:
    points = [pt(0, table="holding"), pt(2, table="input"), pt(4, table="holding")]
    blocks = plan_reads(points, max_gap=10)
    assert [(b.table, b.address, b.count) for b in blocks] == [
        ("input", 2, 2), ("holding", 0, 6)]


def test_blocks_respect_the_125_register_limit() -> None:
    points = [pt(2 * i) for i in range(100)]  # 200 contiguous registers
    blocks = plan_reads(points)
    assert [b.count for b in blocks] == [124, 76]  # a float32 is never split
    assert all(b.count <= MAX_READ_COUNT for b in blocks)
    assert sum(len(b.points) for b in blocks) == 100
    singles = [pt(i, "uint16") for i in range(130)]
    assert [b.count for b in plan_reads(singles)] == [125, 5]
    assert [b.count for b in plan_reads(singles, max_count=50)] == [50, 50, 30]


def test_unsorted_and_overlapping_points_are_covered() -> None:
    points = [pt(10), pt(0), pt(1, "uint16", name="inner")]
    blocks = plan_reads(points)
    assert [(b.address, b.count) for b in blocks] == [(0, 2), (10, 2)]
    assert [(a.name, b.name) for a, b in overlaps(points)] == [("p0", "inner")]


def test_plan_writes_only_merges_exactly_contiguous_holding_points() -> None:
    acts = [pt(100, "int16", table="holding"), pt(101, "uint16", table="holding"),
            pt(103, "float32", table="holding")]
    assert [(b.address, b.count) for b in plan_writes(acts)] == [(100, 2), (103, 2)]
    with pytest.raises(ValueError, match="holding"):
        plan_writes([pt(0)])
    with pytest.raises(ValueError, match="overlapping"):
        plan_writes([pt(0, table="holding"), pt(1, table="holding")])


@pytest.mark.parametrize("table", ["coil", "discrete_input"])
def test_a_bit_point_is_one_bit_whatever_its_data_type(table: str) -> None:
    """Coils and discrete inputs (FC 1, 2) hold one bit: 0 or 1, any non-zero bit is 1;
    a linear map inverts a normally closed contact (issue 36's occupied signal)."""
    p = RegisterPoint(name="occupied", address=7, table=table)  # data_type float32 ignored
    assert p.is_bit and p.count == 1 and p.end == 8
    assert p.where() == f"{table.replace('_', ' ')} 7"
    assert [decode(p, [b]) for b in (0, 1, True)] == [0.0, 1.0, 1.0]
    assert encode(p, 1.0) == [1] and encode(p, 0.0) == [0]
    with pytest.raises(ValueError, match="no bit"):
        encode(p, 0.5)
    nc = RegisterPoint(name="occupied", address=7, table=table, scale=-1.0, offset=1.0)
    assert decode(nc, [0]) == 1.0 and decode(nc, [1]) == 0.0 and encode(nc, 1.0) == [0]
    # bits of one table merge into one read, apart from the registers
    blocks = plan_reads([p, RegisterPoint(name="b", address=8, table=table),
                         RegisterPoint(name="r", address=7, table="holding",
                                       data_type="uint16")])
    assert [(b.table, b.address, b.count) for b in blocks] == [("holding", 7, 1),
                                                               (table, 7, 2)]
