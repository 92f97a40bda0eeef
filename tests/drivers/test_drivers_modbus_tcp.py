"""ModbusDriver against a real pymodbus 3.16 TCP server (hil.modbus_device) on 127.0.0.1."""

from __future__ import annotations

import asyncio
import logging
from typing import Any

import pytest
from pymodbus.client import AsyncModbusTcpClient
from pymodbus.exceptions import ConnectionException

from dsfd.drivers.base import Command, Quality
from dsfd.drivers.factory import build_drivers
from dsfd.drivers.modbus import ModbusDriver, configure_pymodbus_logging
from hil.modbus_device import EmulatedModbusDevice

CYCLE_S = 60.0

# Every data type in every word/byte order, with scale and offset, and two tables.
LAYOUT: list[tuple[dict[str, Any], float]] = [
    ({"signal": "x1_c", "address": 0, "data_type": "float32"}, 21.5),
    ({"signal": "x2_c", "address": 2, "data_type": "float32", "word_order": "little"}, -7.25),
    ({"signal": "x3_c", "address": 4, "data_type": "int32", "scale": 0.001}, 23.456),
    ({"signal": "x4_c", "address": 6, "data_type": "int32", "word_order": "little",
      "scale": 0.01}, -12.34),
    ({"signal": "x5_c", "address": 8, "data_type": "uint32", "scale": 0.001}, 30.5),
    ({"signal": "t_room_c", "address": 10, "data_type": "uint32", "word_order": "little",
      "scale": 0.1, "offset": -273.1}, 22.4),
    ({"signal": "t_out_c", "address": 12, "data_type": "int16", "scale": 0.1}, -3.4),
    ({"signal": "ghi_wm2", "address": 13, "data_type": "uint16"}, 812.0),
    ({"signal": "wind_speed_ms", "address": 14, "data_type": "uint16", "scale": 0.01}, 3.21),
    ({"signal": "wind_dir_deg", "address": 15, "data_type": "int16"}, 270.0),
    ({"signal": "v_cav_ms", "address": 30, "data_type": "float32"}, 0.375),  # gap: 2nd block
    ({"signal": "rh_pct", "address": 0, "table": "holding", "data_type": "uint16",
      "scale": 0.1}, 55.5),
    ({"signal": "pressure_hpa", "address": 1, "table": "holding", "data_type": "uint32",
      "scale": 0.01}, 1013.25),
]
ACTUATORS = [
    {"signal": "phi_deg", "address": 100, "data_type": "int16", "scale": 0.1},
    {"signal": "afr", "address": 101, "data_type": "uint16"},
    {"signal": "or_pct", "address": 110, "data_type": "float32", "word_order": "little"},
]


def io_entry(port: int, fast: dict[str, Any], *, byte_order: str = "big",
             **kw: Any) -> dict[str, Any]:
    sensors = [dict(p, byte_order=byte_order) for p, _ in LAYOUT]
    return {"name": "io", "kind": "modbus_tcp", "tcp": {"host": "127.0.0.1", "port": port},
            "device_id": 3, "sensors": sensors, "actuators": ACTUATORS, **fast, **kw}


def setup(make_devices: Any, entry: dict[str, Any], clock: Any, **emu: Any
          ) -> tuple[ModbusDriver, EmulatedModbusDevice]:
    devices = make_devices([entry])
    composite = build_drivers(devices, clock=clock)
    (driver,) = composite.drivers
    assert isinstance(driver, ModbusDriver)
    return driver, EmulatedModbusDevice.from_config(devices.entries[0], **emu)


@pytest.mark.parametrize("byte_order", ["big", "little"])
def test_block_reads_decode_every_type_and_order(run, make_devices, fast, clock, tcp_port,
                                                 byte_order) -> None:
    driver, emu = setup(make_devices, io_entry(tcp_port, fast, byte_order=byte_order), clock)
    # input 0..15, input 30..31, holding 0..2: three requests per cycle
    assert [(b.table, b.address, b.count) for b in driver.read_blocks] == [
        ("input", 0, 16), ("input", 30, 2), ("holding", 0, 3)]

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensors({p["signal"]: v for p, v in LAYOUT})
        await driver.start()
        sample = await driver.read(1.0)
        assert not sample.bad(), sample.bad()
        for p, value in LAYOUT:
            assert sample.good(p["signal"]) == pytest.approx(value, abs=1e-6), p
        assert sum(emu.requests.values()) == 3
        await driver.close()
        await emu.stop()

    run(scenario())


def test_device_down_at_start_is_flagged_at_once_and_connected_later(
        run, make_devices, fast, clock, tcp_port) -> None:
    driver, emu = setup(make_devices, io_entry(tcp_port, fast), clock)

    async def scenario() -> None:
        await driver.start()  # nothing listens: not an error
        assert driver.link.counters["connect_attempts"] == 1
        clock.advance(CYCLE_S)
        sample = await driver.read(clock())
        assert {r.quality for r in sample.readings.values()} == {Quality.DISCONNECTED}
        detail = sample.readings["x1_c"].detail
        assert "io" in detail and f"tcp://127.0.0.1:{tcp_port}" in detail
        # Bounded cost: one refused connect per cycle, no request was sent and none timed out.
        assert driver.link.counters["connect_attempts"] == 2
        assert driver.counters["requests"] == 0 and driver.counters["timeouts"] == 0
        # Within the backoff interval no further connect is tried.
        again = await driver.read(clock())
        assert "next connect attempt" in again.readings["x1_c"].detail
        assert driver.link.counters["connect_attempts"] == 2
        # The device comes up; the next cycle connects (pymodbus alone would never retry).
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensor("x1_c", 19.0)
        clock.advance(CYCLE_S)
        sample = await driver.read(clock())
        assert sample.good("x1_c") == 19.0 and not sample.bad()
        assert driver.link.counters["connects"] == 1
        await driver.close()
        await emu.stop()

    run(scenario())


def test_device_that_disappears_and_returns_is_recovered_within_two_cycles(
        run, make_devices, fast, clock, tcp_port) -> None:
    driver, emu = setup(make_devices, io_entry(tcp_port, fast), clock)

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensor("x1_c", 20.0)
        await driver.start()
        assert (await driver.read(clock())).good("x1_c") == 20.0
        await emu.stop()
        clock.advance(CYCLE_S)
        down = await driver.read(clock())
        assert down.quality("x1_c") in {Quality.DISCONNECTED, Quality.TIMEOUT}
        await emu.resume()
        await emu.set_sensor("x1_c", 21.0)
        outcomes = []
        for _ in range(2):
            clock.advance(CYCLE_S)
            outcomes.append((await driver.read(clock())).good("x1_c"))
        assert 21.0 in outcomes, outcomes
        assert outcomes[-1] == 21.0
        await driver.close()
        await emu.stop()

    run(scenario())


def test_busy_device_and_nan_values_are_flagged_naming_the_register(
        run, make_devices, fast, clock, tcp_port) -> None:
    entry = io_entry(tcp_port, fast)
    entry["sensors"][6].update(nan_value=-32768)  # t_out_c int16 at input register 12
    driver, emu = setup(make_devices, entry, clock)

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensors({p["signal"]: v for p, v in LAYOUT})
        await driver.start()
        emu.busy = True
        busy = await driver.read(clock())
        assert {r.quality for r in busy.readings.values()} == {Quality.DEVICE_ERROR}
        detail = busy.readings["x2_c"].detail
        assert "DEVICE_BUSY" in detail and "input register 2" in detail and "id 3" in detail
        assert "holding register 1" in busy.readings["pressure_hpa"].detail
        assert not driver.breaker.is_open  # a busy device answers: no breaker
        emu.busy = False
        await emu.serve_nan("x1_c")
        await emu.serve_nan("t_out_c")
        sample = await driver.read(clock())
        assert set(sample.bad()) == {"x1_c", "t_out_c"}
        assert sample.quality("x1_c") is Quality.NOT_FINITE
        assert "input register 0 (float32)" in sample.readings["x1_c"].detail
        assert "nan_value code (0x8000)" in sample.readings["t_out_c"].detail
        assert "input register 12" in sample.readings["t_out_c"].detail
        assert sample.good("x2_c") == -7.25
        assert driver.counters["not_finite"] == 2
        await driver.close()
        await emu.stop()

    run(scenario())


def test_gap_reads_need_a_lenient_device(run, make_devices, fast, clock, tcp_port) -> None:
    entry = io_entry(tcp_port, fast, max_read_gap=20)  # input 0..31 in one request
    strict, strict_emu = setup(make_devices, entry, clock)
    assert [(b.address, b.count) for b in strict.read_blocks][:1] == [(0, 32)]

    async def scenario() -> None:
        await strict_emu.start_tcp(port=tcp_port)
        await strict.start()
        sample = await strict.read(clock())
        assert "2 (ILLEGAL_ADDRESS)" in sample.readings["v_cav_ms"].detail
        assert sample.good("rh_pct") is not None  # the holding block is unaffected
        await strict.close()
        await strict_emu.stop()
        lenient, lenient_emu = setup(make_devices, entry, clock, fill_gaps=True)
        await lenient_emu.start_tcp(port=tcp_port)
        await lenient_emu.set_sensor("v_cav_ms", 0.5)
        await lenient.start()
        sample = await lenient.read(clock())
        assert not sample.bad() and sample.good("v_cav_ms") == 0.5
        assert sum(lenient_emu.requests.values()) == 2
        await lenient.close()
        await lenient_emu.stop()

    run(scenario())


def test_commands_reach_the_holding_registers_and_are_verified(
        run, make_devices, fast, clock, tcp_port) -> None:
    driver, emu = setup(make_devices, io_entry(tcp_port, fast), clock)
    assert [(b.address, b.count) for b in driver.write_blocks] == [(100, 2), (110, 2)]

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await driver.start()
        cmd = Command(phi_deg=-54.0, afr=7, or_pct=62.5)
        result = await driver.write(cmd)
        assert result.ok, result.errors
        assert result.verified == result.owned == {"phi_deg", "afr", "or_pct"}
        assert dict(result.written) == {"phi_deg": -54.0, "afr": 7.0, "or_pct": 62.5}
        assert await emu.actuator_values() == {"phi_deg": -54.0, "afr": 7.0, "or_pct": 62.5}
        assert await emu.registers("phi_deg") == [(-540) & 0xFFFF]
        assert emu.requests[16] == 2  # one FC16 per contiguous block
        assert await driver.read_back() == cmd
        # A stuck actuator acknowledges the write but does not move: read-back catches it.
        emu.frozen_actuators = True
        stuck = await driver.write(Command(phi_deg=18.0, afr=2, or_pct=10.0))
        assert not stuck.ok and not stuck.verified and set(stuck.written) == stuck.owned
        assert any("read-back" in e and "holding register 100" in e for e in stuck.errors)
        assert stuck.read_back["phi_deg"] == -54.0
        emu.frozen_actuators = False
        emu.busy = True
        refused = await driver.write(cmd)
        assert not refused.written and any("DEVICE_BUSY" in e for e in refused.errors)
        await driver.close()
        await emu.stop()

    run(scenario())


def test_single_register_actuator_uses_write_single_register(
        run, make_devices, fast, clock, tcp_port) -> None:
    entry = {"name": "louver", "kind": "modbus_tcp",
             "tcp": {"host": "127.0.0.1", "port": tcp_port}, **fast,
             "actuators": [{"signal": "phi_deg", "address": 7, "data_type": "int16"}]}
    driver, emu = setup(make_devices, entry, clock)

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await driver.start()
        result = await driver.write(Command(phi_deg=72.0, afr=1, or_pct=0.0))
        assert result.ok and result.owned == {"phi_deg"}
        assert emu.requests[6] == 1 and emu.requests[16] == 0
        assert emu.writes == [(7, [72])]
        assert await driver.read_back() is None  # afr/or_pct are owned by no one here
        assert dict(await driver.read_actuators()) == {"phi_deg": 72.0}
        await driver.close()
        await emu.stop()

    run(scenario())


def test_silent_device_is_bounded_then_skipped_by_the_breaker(
        run, make_devices, fast, clock, tcp_port) -> None:
    driver, emu = setup(make_devices, io_entry(tcp_port, fast), clock)  # 2 fails, skip 3
    attempts = fast["retries"] + 1

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensor("x1_c", 20.0)
        await driver.start()
        emu.silent = True
        qualities = []
        requests_seen = []
        for _ in range(6):
            clock.advance(CYCLE_S)
            before = sum(emu.requests.values())
            sample = await driver.read(clock())
            requests_seen.append(sum(emu.requests.values()) - before)
            qualities.append(sample.quality("x1_c"))
        # Cycles 1-2 time out: only the first of three blocks is tried, retries+1 times.
        # Cycles 3-5: breaker open, no I/O at all. Cycle 6: one half-open trial, fails again.
        assert qualities == [Quality.TIMEOUT] * 2 + [Quality.SKIPPED] * 3 + [Quality.TIMEOUT]
        assert requests_seen == [attempts, attempts, 0, 0, 0, attempts]
        assert driver.breaker.trips == 2
        assert "not polled" in sample.readings["rh_pct"].detail
        emu.silent = False
        for _ in range(fast["breaker_cycles"] + 1):  # skipped cycles, then a good trial
            clock.advance(CYCLE_S)
            sample = await driver.read(clock())
        assert sample.good("x1_c") == 20.0 and not driver.breaker.is_open
        await driver.close()
        await emu.stop()

    run(scenario())


def test_pymodbus_does_not_retry_a_failed_first_connect(run, tcp_port) -> None:
    """Pins the pymodbus 3.16.1 behaviour that makes the application own reconnects."""

    async def scenario() -> None:
        emu = EmulatedModbusDevice(sensors=[], actuators=[], device_id=1)
        client = AsyncModbusTcpClient("127.0.0.1", port=tcp_port, timeout=0.2, retries=0,
                                      reconnect_delay=0.05, reconnect_delay_max=0.1)
        assert await client.connect() is False
        await emu.start_tcp(port=tcp_port)
        # Give a background retry (if any) many reconnect_delay periods to happen.
        for _ in range(10):
            await client_idle()
        assert not client.connected
        with pytest.raises(ConnectionException):
            await client.read_holding_registers(0, count=1, device_id=1)
        assert await client.connect() is True  # an explicit connect works
        client.close()
        await emu.stop()

    run(scenario())


async def client_idle() -> None:
    await asyncio.sleep(0.05)


def test_pymodbus_logs_flow_through_stdlib_logging(run, make_devices, fast, clock, tcp_port,
                                                   caplog) -> None:
    driver, _ = setup(make_devices, io_entry(tcp_port, fast), clock)
    pymodbus_logger = logging.getLogger("pymodbus")
    handlers_before = list(pymodbus_logger.handlers)
    configure_pymodbus_logging(level=logging.WARNING)
    try:
        with caplog.at_level(logging.WARNING):
            run(driver.read(clock()))
        assert pymodbus_logger.handlers == handlers_before  # no handler of its own
        by_logger = {r.name for r in caplog.records if r.levelno >= logging.WARNING}
        assert "pymodbus.logging" in by_logger  # "Failed to connect ..."
        assert "dsfd.drivers.modbus_link" in by_logger
    finally:
        pymodbus_logger.setLevel(logging.NOTSET)
