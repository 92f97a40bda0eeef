"""The ``occupied`` signal (issue 36) read like any other: from a coil, a discrete input or a
register of the pymodbus TCP server of hil.modbus_device, then through the quality checks."""

from __future__ import annotations

from typing import Any

import pytest

from dsfd.config.daemon import QualitySettings
from dsfd.daemon.quality import QualityChecker
from dsfd.drivers.base import Quality
from tests.drivers.test_drivers_modbus_tcp import io_entry, setup

# x1_c on input register 0 beside the occupied point, so the bit block is a second request.
X1 = {"signal": "x1_c", "address": 0, "data_type": "float32"}


def _entry(port: int, fast: dict[str, Any], occupied: dict[str, Any]) -> dict[str, Any]:
    return io_entry(port, fast, sensors=[X1, {"signal": "occupied", **occupied}])


@pytest.mark.parametrize("point", [
    {"table": "coil", "address": 5},
    {"table": "discrete_input", "address": 17},
    {"table": "holding", "address": 40, "data_type": "uint16"},
    {"table": "input", "address": 8, "data_type": "int16"},
    # a normally closed contact: 0 on the wire is "occupied" (raw · -1 + 1)
    {"table": "discrete_input", "address": 2, "scale": -1.0, "offset": 1.0},
])
def test_occupied_reads_as_the_device_serves_it(run, make_devices, fast, clock, tcp_port,
                                                point: dict[str, Any]) -> None:
    driver, emu = setup(make_devices, _entry(tcp_port, fast, point), clock)
    assert "occupied" in driver.sensor_names

    async def scenario() -> list[float | None]:
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensor("x1_c", 20.5)
        await driver.start()
        seen = []
        for value in (1.0, 0.0, 1.0):
            await emu.set_sensor("occupied", value)
            sample = await driver.read(clock())
            assert sample.good("x1_c") == 20.5
            seen.append(sample.good("occupied"))
        await driver.close()
        await emu.stop()
        return seen

    assert run(scenario()) == [1.0, 0.0, 1.0]


def test_a_register_that_is_no_bit_is_flagged_and_not_used(run, make_devices, fast, clock,
                                                           tcp_port) -> None:
    """A register reading 2 (a mis-mapped point) is read, then the quality checks flag it
    out of range, so the daemon falls back to the schedule."""
    point = {"table": "holding", "address": 40, "data_type": "uint16"}
    driver, emu = setup(make_devices, _entry(tcp_port, fast, point), clock)
    checker = QualityChecker(QualitySettings())

    async def scenario() -> Any:
        await emu.start_tcp(port=tcp_port)
        await emu.set_registers("occupied", [2])
        await driver.start()
        sample = await driver.read(clock())
        await driver.close()
        await emu.stop()
        return sample

    sample = run(scenario())
    assert sample.good("occupied") == 2.0  # the driver delivered what the device said
    report = checker.check(sample)
    assert report.flags == {"occupied": "range"}
    assert report.sample.good("occupied") is None
    assert report.sample.quality("occupied") is Quality.OUT_OF_RANGE


def test_a_device_that_is_down_flags_occupied(run, make_devices, fast, clock,
                                              tcp_port) -> None:
    driver, emu = setup(make_devices, _entry(tcp_port, fast, {"table": "coil", "address": 5}),
                        clock)

    async def scenario() -> Any:
        await emu.start_tcp(port=tcp_port)
        await driver.start()
        await emu.stop()
        sample = await driver.read(clock())
        await driver.close()
        return sample

    sample = run(scenario())
    assert sample.good("occupied") is None
    assert sample.quality("occupied") in (Quality.DISCONNECTED, Quality.TIMEOUT)
    assert "coil" in sample.readings["occupied"].detail
