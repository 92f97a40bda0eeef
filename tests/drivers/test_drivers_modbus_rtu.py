"""Modbus RTU over an in-process pty null-modem: two slaves on one line, faults on the line."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from dsfd.drivers.base import Command, CompositeDriver, Quality
from dsfd.drivers.factory import build_drivers
from dsfd.drivers.modbus import ModbusDriver
from hil.modbus_device import EmulatedModbusDevice
from hil.pty_pair import PtyPair

CYCLE_S = 60.0


@pytest.fixture
def line() -> Iterator[PtyPair]:
    with PtyPair() as pair:
        yield pair


def rtu_entries(port: str, fast: dict[str, Any], **kw: Any) -> list[dict[str, Any]]:
    # Parity N: this kernel's ptys refuse some settings (8E1 gives EINVAL in tcsetattr).
    serial = {"port": port, "baudrate": 19200, "parity": "N"}
    return [
        {"name": "tc-module", "kind": "modbus_rtu", "serial": serial, "device_id": 1, **fast,
         **kw,
         "sensors": [{"signal": "x1_c", "address": 0, "word_order": "little"},
                     {"signal": "x5_c", "address": 2, "data_type": "int16", "scale": 0.1}],
         "actuators": [{"signal": "phi_deg", "address": 10, "data_type": "int16"},
                       {"signal": "afr", "address": 11, "data_type": "uint16"},
                       {"signal": "or_pct", "address": 12, "data_type": "uint16",
                        "scale": 0.5}]},
        {"name": "anemometer", "kind": "modbus_rtu", "serial": serial, "device_id": 7, **fast,
         **kw,
         "sensors": [{"signal": "v_cav_ms", "address": 0, "table": "holding",
                      "data_type": "uint16", "scale": 0.01}]},
    ]


def setup(make_devices: Any, line: PtyPair, fast: dict[str, Any], clock: Any, **kw: Any
          ) -> tuple[CompositeDriver, list[EmulatedModbusDevice]]:
    devices = make_devices(rtu_entries(line.port_a, fast, **kw))
    composite = build_drivers(devices, clock=clock)
    emulators = [EmulatedModbusDevice.from_config(d) for d in devices.entries]
    return composite, emulators


async def start_line(emulators: list[EmulatedModbusDevice], line: PtyPair) -> None:
    first, *rest = emulators
    await first.start_rtu(port=line.port_b, baudrate=19200, parity="N", also=rest)
    await first.set_sensors({"x1_c": 23.75, "x5_c": 19.4})
    await rest[0].set_sensor("v_cav_ms", 0.42)


def test_two_slaves_share_one_line_and_one_client(run, make_devices, line, fast, clock) -> None:
    composite, emulators = setup(make_devices, line, fast, clock)
    tc, anemometer = composite.drivers
    assert isinstance(tc, ModbusDriver) and isinstance(anemometer, ModbusDriver)
    assert tc.link is anemometer.link  # one pymodbus client per serial line

    async def scenario() -> None:
        await start_line(emulators, line)
        await composite.start()
        sample = await composite.read(clock())  # both devices polled concurrently
        assert not sample.bad(), sample.bad()
        assert sample.good("x1_c") == 23.75
        assert sample.good("x5_c") == pytest.approx(19.4)
        assert sample.good("v_cav_ms") == pytest.approx(0.42)
        cmd = Command(phi_deg=-36.0, afr=9, or_pct=37.5)
        result = await composite.write(cmd)
        assert result.ok and result.owned == {"phi_deg", "afr", "or_pct"}, result.errors
        assert await emulators[0].actuator_values() == {"phi_deg": -36.0, "afr": 9.0,
                                                        "or_pct": 37.5}
        assert await composite.read_back() == cmd
        assert emulators[1].requests[16] == 0  # the command went to device 1 only
        await composite.close()
        await emulators[0].stop()

    run(scenario())


def test_unplugged_line_times_out_boundedly_and_recovers(
        run, make_devices, line, fast, clock) -> None:
    composite, emulators = setup(make_devices, line, fast, clock, breaker_failures=5)
    tc = composite.drivers[0]
    assert isinstance(tc, ModbusDriver)

    async def scenario() -> None:
        await start_line(emulators, line)
        await composite.start()
        assert not (await composite.read(clock())).bad()
        line.unplug()
        clock.advance(CYCLE_S)
        requests_before = tc.counters["requests"]
        cut = await composite.read(clock())
        assert {r.quality for r in cut.readings.values()} == {Quality.TIMEOUT}
        assert f"on serial:{line.port_a}" in cut.readings["v_cav_ms"].detail
        assert "holding register 0" in cut.readings["v_cav_ms"].detail
        # One request (pymodbus retries inside it), then the device is given up this cycle.
        assert tc.counters["requests"] - requests_before == 1
        assert tc.link.connected  # a serial port stays open; only the far end is gone
        line.plug()
        clock.advance(CYCLE_S)
        back = await composite.read(clock())
        assert not back.bad() and back.good("x1_c") == 23.75
        await composite.close()
        await emulators[0].stop()

    run(scenario())


def test_restarted_slave_is_polled_again(run, make_devices, line, fast, clock) -> None:
    composite, emulators = setup(make_devices, line, fast, clock)

    async def scenario() -> None:
        await start_line(emulators, line)
        await composite.start()
        await emulators[0].stop()  # the line's server closes its port: nobody answers
        clock.advance(CYCLE_S)
        down = await composite.read(clock())
        assert down.quality("x1_c") is Quality.TIMEOUT
        await emulators[0].resume()
        await emulators[0].set_sensor("x1_c", 24.5)
        clock.advance(CYCLE_S)
        back = await composite.read(clock())
        assert back.good("x1_c") == 24.5 and not back.bad()
        await composite.close()
        await emulators[0].stop()

    run(scenario())


def test_missing_serial_port_is_disconnected_and_tried_once_per_backoff(
        run, make_devices, fast, clock, tmp_path) -> None:
    port = str(tmp_path / "ttyUSB9")  # adapter not plugged in
    composite = build_drivers(make_devices(rtu_entries(port, fast)), clock=clock)
    tc = composite.drivers[0]
    assert isinstance(tc, ModbusDriver)

    async def scenario() -> None:
        await composite.start()  # two devices, one shared link: one failed attempt
        sample = await composite.read(clock())
        assert {r.quality for r in sample.readings.values()} == {Quality.DISCONNECTED}
        assert "ttyUSB9" in sample.readings["v_cav_ms"].detail
        assert tc.link.counters["connect_attempts"] == 1
        assert tc.counters["requests"] == 0
        clock.advance(CYCLE_S)
        await composite.read(clock())
        assert tc.link.counters["connect_attempts"] == 2
        await composite.close()

    run(scenario())
