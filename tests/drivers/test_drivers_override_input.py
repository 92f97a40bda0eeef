"""The override input (wall switch, BMS hand flag) and a device answering with the wrong
register count, against the pymodbus TCP server of hil.modbus_device."""

from __future__ import annotations

from typing import Any

import pytest

from dsfd.drivers.base import Quality
from tests.drivers.test_drivers_modbus_tcp import io_entry, setup


@pytest.mark.parametrize("table, invert", [("coil", False), ("discrete_input", False),
                                           ("holding", False), ("coil", True)])
def test_override_input_reads_as_the_switch_is_set(run, make_devices, fast, clock, tcp_port,
                                                   table: str, invert: bool) -> None:
    entry = io_entry(tcp_port, fast, override_input={"table": table, "address": 21,
                                                     "invert": invert})
    driver, emu = setup(make_devices, entry, clock)
    assert driver.override_input == f"io {table.replace('_', ' ')} 21"

    async def scenario() -> list[Any]:
        await emu.start_tcp(port=tcp_port)
        await driver.start()
        seen = []
        for active in (True, False, True):
            await emu.set_override_input(active)
            seen.append(await driver.read_override_input())
        await emu.stop()
        seen.append(await driver.read_override_input())  # device gone: unknown
        await driver.close()
        return seen

    assert run(scenario()) == [True, False, True, None]


def test_a_short_response_is_a_device_error_not_a_value(run, make_devices, fast, clock,
                                                        tcp_port) -> None:
    driver, emu = setup(make_devices, io_entry(tcp_port, fast), clock)

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensor("x1_c", 21.5)
        await driver.start()
        emu.short_reads = True
        sample = await driver.read(clock())
        assert {r.quality for r in sample.readings.values()} == {Quality.DEVICE_ERROR}
        assert "short response" in sample.readings["x1_c"].detail
        assert "input register 0" in sample.readings["x1_c"].detail
        emu.short_reads = False
        assert (await driver.read(clock())).good("x1_c") == 21.5
        await driver.close()
        await emu.stop()

    run(scenario())
