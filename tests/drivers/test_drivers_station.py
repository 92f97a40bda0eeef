"""Weather-station line protocol (pure) and StationDriver over a pty (hil.station)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from dsfd.drivers.base import Command, Quality
from dsfd.drivers.factory import build_drivers
from dsfd.drivers.resilience import Backoff
from dsfd.drivers.station import (
    MAX_LINE_BYTES,
    STATION_SIGNALS,
    FramingError,
    StationDriver,
    checksum,
    format_line,
    parse_line,
)
from hil.modbus_device import EmulatedModbusDevice
from hil.station import StationEmulator

WEATHER = {"t_out_c": 12.5, "ghi_wm2": 450.0, "wind_speed_ms": 3.2, "wind_dir_deg": 200.0,
           "rh_pct": 55.0, "pressure_hpa": 1012.0}
#: The example line of docs/weather-station-protocol.md.
DOC_LINE = b"$WXDSF,1,12.50,450.00,3.20,200.00,55.00,1012.00*75\r\n"


# ------------------------------------------------------------------ protocol (pure)
def test_documented_example_line() -> None:
    assert format_line(1, WEATHER) == DOC_LINE
    assert checksum(b"WXDSF,1,12.50,450.00,3.20,200.00,55.00,1012.00") == 0x75
    line = parse_line(DOC_LINE)
    assert line.seq == 1 and dict(line.values) == WEATHER


def test_lenient_only_where_no_value_can_be_wrong() -> None:
    winter = b"$WXDSF,2,-3.50,0.00,11.00,315.00,,998.40*4E\r\n"
    assert format_line(2, WEATHER | {"t_out_c": -3.5, "ghi_wm2": 0.0, "wind_speed_ms": 11.0,
                                     "wind_dir_deg": 315.0, "rh_pct": None,
                                     "pressure_hpa": 998.4}) == winter
    lenient = parse_line(winter.replace(b"*4E\r\n", b"*4e\n"))  # LF only, lower-case hex
    assert lenient.seq == 2 and lenient.values["rh_pct"] is None
    body = b"WXDSF,65535,-3.5,,+0.5,.5,100,"
    line = parse_line(b"$" + body + f"*{checksum(body):02X}\r\n".encode())
    assert line.seq == 65535
    assert line.values["t_out_c"] == -3.5 and line.values["wind_dir_deg"] == 0.5
    assert line.values["ghi_wm2"] is None and line.values["pressure_hpa"] is None


def framed(body: str) -> bytes:
    raw = body.encode()
    return b"$" + raw + f"*{checksum(raw):02X}\r\n".encode()


@pytest.mark.parametrize(("raw", "kind"), [
    (DOC_LINE[:-2], "partial"),
    (DOC_LINE[:20], "partial"),
    (b"$" + b"1" * (MAX_LINE_BYTES - 1), "too_long"),
    (b"\r\n", "empty"),
    (DOC_LINE.replace(b"12.50", b"12\x0050"), "garbage"),
    (DOC_LINE[1:], "start"),
    (DOC_LINE.replace(b"*75", b"*74"), "checksum"),
    (DOC_LINE.replace(b"*75", b""), "checksum"),
    (DOC_LINE.replace(b"*75", b"*7"), "checksum"),
    (DOC_LINE.replace(b"*75", b"*7G"), "checksum"),
    (DOC_LINE.replace(b"3.20", b"3.21"), "checksum"),  # one flipped digit
    (framed("GPGGA,1,12.5,450,3.2,200,55,1012"), "sentence"),
    (framed("WXDSF,1,12.5,450,3.2,200,55"), "fields"),
    (framed("WXDSF,1,12.5,450,3.2,200,55,1012,7"), "fields"),
    (framed("WXDSF,-1,12.5,450,3.2,200,55,1012"), "seq"),
    (framed("WXDSF,65536,12.5,450,3.2,200,55,1012"), "seq"),
    (framed("WXDSF,x,12.5,450,3.2,200,55,1012"), "seq"),
    (framed("WXDSF,1,nan,450,3.2,200,55,1012"), "number"),
    (framed("WXDSF,1,12.5,inf,3.2,200,55,1012"), "number"),
    (framed("WXDSF,1,12.5,450,1e3,200,55,1012"), "number"),
    (framed("WXDSF,1,12.5,450,3.2,0x10,55,1012"), "number"),
    (framed("WXDSF,1,12.5,450,3.2,200, 55,1012"), "number"),
    (framed("WXDSF,1,12.5.1,450,3.2,200,55,1012"), "number"),
])
def test_invalid_lines_are_framing_errors(raw: bytes, kind: str) -> None:
    with pytest.raises(FramingError) as err:
        parse_line(raw)
    assert err.value.kind == kind


# ------------------------------------------------------------------ driver over a pty
@pytest.fixture
def station() -> Iterator[StationEmulator]:
    with StationEmulator() as emu:
        yield emu


def make_driver(url: str, clock: Any) -> StationDriver:
    return StationDriver(name="wx", url=url, baudrate=9600, timeout_s=0.3, clock=clock,
                         backoff=Backoff(min_s=1.0, max_s=30.0))


def test_newest_valid_line_since_the_last_cycle(run, station, clock) -> None:
    driver = make_driver(station.port, clock)

    async def scenario() -> None:
        station.send(WEATHER)  # before start: flushed at open, not "since the last cycle"
        await driver.start()
        sent = b"".join(station.send(WEATHER | {"t_out_c": t}) for t in (10.0, 11.0, 12.0))
        station.wait_queued(len(sent))
        sample = await driver.read(60.0)
        assert sample.good("t_out_c") == 12.0 and not sample.bad()
        assert {n: sample.good(n) for n in STATION_SIGNALS} == WEATHER | {"t_out_c": 12.0}
        assert driver.counters["lines_ok"] == 3 and driver.counters["framing_errors"] == 0
        assert driver.counters["seq_gaps"] == 0
        await driver.close()

    run(scenario())


def test_framing_errors_are_counted_and_never_become_values(run, station, clock) -> None:
    driver = make_driver(station.port, clock)

    async def scenario() -> None:
        await driver.start()
        sent = station.send_garbage(30)                            # merges into next line
        sent += station.send(WEATHER | {"t_out_c": 1.0})           # valid after the noise
        sent += station.send_bad_checksum(WEATHER | {"t_out_c": 99.0})
        sent += station.send_framed("WXDSF,9,nan,1,1,1,1,1")      # checksum ok, not a number
        sent += station.send_framed("WXDSF,9,1,1,1,1,1")          # checksum ok, field count
        station.wait_queued(len(sent))
        sample = await driver.read(60.0)
        assert sample.good("t_out_c") == 1.0  # the only valid line; 99 and nan never appear
        c = driver.counters
        assert (c["framing_garbage"], c["framing_checksum"], c["framing_number"],
                c["framing_fields"]) == (1, 1, 1, 1)
        assert c["framing_errors"] == 4 and c["lines_ok"] == 1
        # A cycle with nothing but bad lines: STALE everywhere, not the previous value.
        sent = station.send_bad_checksum(WEATHER) + station.send_raw(b"\xff\xfe\r\n")
        station.wait_queued(len(sent))
        stale = await driver.read(120.0)
        assert {r.quality for r in stale.readings.values()} == {Quality.STALE}
        assert all(math.isnan(r.value) for r in stale.readings.values())
        assert "2 framing errors" in stale.readings["t_out_c"].detail
        assert station.port in stale.readings["t_out_c"].detail
        assert c["framing_errors"] == 6 and c["cycles_stale"] == 1
        await driver.close()

    run(scenario())


def test_a_line_split_across_cycles_is_framing_not_a_value(run, station, clock) -> None:
    driver = make_driver(station.port, clock)

    async def scenario() -> None:
        await driver.start()
        rest = station.send_split(WEATHER, at=20)  # the station stalls mid-line
        sample = await driver.read(60.0)           # read_until returns the part on timeout
        assert sample.quality("t_out_c") is Quality.STALE
        assert driver.counters["framing_partial"] == 1
        sent = station.send_raw(rest) + station.send(WEATHER | {"rh_pct": 60.0})
        station.wait_queued(len(sent))
        sample = await driver.read(120.0)
        assert sample.good("rh_pct") == 60.0
        assert driver.counters["framing_start"] == 1  # the orphaned tail
        await driver.close()

    run(scenario())


def test_silence_is_stale_and_missing_fields_are_missing(run, station, clock) -> None:
    driver = make_driver(station.port, clock)

    async def scenario() -> None:
        await driver.start()
        station.wait_queued(len(station.send(WEATHER | {"ghi_wm2": None}, seq=5)))
        sample = await driver.read(60.0)
        assert sample.quality("ghi_wm2") is Quality.MISSING
        assert "no ghi_wm2" in sample.readings["ghi_wm2"].detail
        assert sample.good("t_out_c") == 12.5
        silent = await driver.read(120.0)
        assert set(silent.bad()) == set(STATION_SIGNALS)
        assert silent.quality("t_out_c") is Quality.STALE
        station.wait_queued(len(station.send(WEATHER, seq=9)))
        await driver.read(180.0)
        assert driver.counters["seq_gaps"] == 3  # lines 6, 7, 8 never arrived
        await driver.close()

    run(scenario())


def test_absent_port_is_disconnected_and_opened_once_it_appears(
        run, station, clock, tmp_path: Path) -> None:
    link = tmp_path / "ttyWX"  # e.g. a USB adapter that is not plugged in yet
    driver = make_driver(str(link), clock)

    async def scenario() -> None:
        await driver.start()
        sample = await driver.read(60.0)
        assert sample.quality("t_out_c") is Quality.DISCONNECTED
        assert str(link) in sample.readings["t_out_c"].detail
        await driver.read(60.0)  # within the backoff: no new attempt
        assert driver.counters["open_attempts"] == 1 and driver.counters["open_failures"] == 1
        link.symlink_to(station.port)
        clock.advance(60.0)
        assert (await driver.read(120.0)).quality("t_out_c") is Quality.STALE  # open, silent
        station.wait_queued(len(station.send(WEATHER)))
        assert (await driver.read(180.0)).good("t_out_c") == 12.5
        await driver.close()

    run(scenario())


def test_loop_url_opens_like_a_port(run, clock) -> None:
    driver = make_driver("loop://", clock)

    async def scenario() -> None:
        await driver.start()
        assert (await driver.read(1.0)).quality("wind_speed_ms") is Quality.STALE
        assert driver.counters["open_failures"] == 0
        await driver.close()

    run(scenario())


def test_whole_edge_from_config(run, station, make_devices, fast, clock, tcp_port) -> None:
    """Modbus sensors + actuators and the station behind one CompositeDriver."""
    devices = make_devices([
        {"name": "io", "kind": "modbus_tcp", "tcp": {"host": "127.0.0.1", "port": tcp_port},
         **fast, "sensors": [{"signal": "x1_c", "address": 0}],
         "actuators": [{"signal": "phi_deg", "address": 10, "data_type": "int16"},
                       {"signal": "afr", "address": 11, "data_type": "uint16"},
                       {"signal": "or_pct", "address": 12, "data_type": "uint16"}]},
        {"name": "wx", "kind": "serial_station", "serial": {"port": station.port},
         "timeout_s": 0.3},
    ])
    edge = build_drivers(devices, clock=clock)
    emu = EmulatedModbusDevice.from_config(devices.entries[0])

    async def scenario() -> None:
        await emu.start_tcp(port=tcp_port)
        await emu.set_sensor("x1_c", 17.0)
        await edge.start()
        station.wait_queued(len(station.send(WEATHER)))
        sample = await edge.read(60.0)
        assert not sample.bad()
        assert set(sample.readings) == {"x1_c", *STATION_SIGNALS}
        assert sample.good("x1_c") == 17.0 and sample.good("ghi_wm2") == 450.0
        assert (await edge.write(Command(phi_deg=0.0, afr=10, or_pct=0.0))).ok
        await edge.close()
        await emu.stop()

    run(scenario())
