"""``dsfd commission`` on the HIL rig: the real ``dsfd`` process against the emulated I/O module
(Modbus TCP on loopback, with a motor model behind the actuators' position feedback) and the
weather station on a pty.

The emulator is built from the *correct* panel file: it is the façade as wired. A second panel
file with mistakes an integrator makes (two thermocouple registers swapped, a scale off by ten,
the louver's sign inverted) is read through that same façade.

The values served are a winter night at the Suwon panel (00:00 local time, 2 January): the
room warm, outdoors near freezing, no sun, and the panel's temperatures ordered along the
heat path from the room out (room > x3 > x2 > x4, x5 > x1 ≳ outdoors), as heat conduction
with no source inside requires.
"""

from __future__ import annotations

import asyncio
import copy
import json
import re
import signal
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import yaml

from dsfd.config import load_panel
from hil.modbus_device import EmulatedModbusDevice
from hil.station import StationEmulator
from tests.daemon.harness import (
    MORNING_ISO,
    DaemonProcess,
    UntouchedDevice,
    free_port,
    run_dsfd,
    write_panel,
)

pytestmark = [pytest.mark.hil]

#: 00:00 local standard time (UTC+9) in Suwon, 2 January: the sun is far below the horizon.
NIGHT_ISO = "2022-01-01T15:00:00Z"
NIGHT_IO = {"x1_c": 2.6, "x2_c": 9.3, "x3_c": 16.8, "x4_c": 4.4, "x5_c": 5.1,
            "t_room_c": 21.4, "v_cav_ms": 0.05}
# A thermopile pyranometer reads a few W/m2 below zero at night.
NIGHT_STATION = {"t_out_c": 1.0, "ghi_wm2": -2.0, "wind_speed_ms": 2.0, "wind_dir_deg": 200.0,
                 "rh_pct": 70.0, "pressure_hpa": 1015.0}
#: The position the panel is in before commissioning (louver, regime, damper opening).
START = {"phi_deg": 36.0, "afr": 3.0, "or_pct": 40.0}
#: Motor speeds of the emulated actuators [unit/s]: fast, so a stroke takes seconds.
RATES = {"phi_deg": 180.0, "afr": 20.0, "or_pct": 250.0}
#: Position feedback registers of the actuators (input registers 10..12).
FEEDBACK = {"phi_deg": {"address": 10, "data_type": "int16"},
            "afr": {"address": 11, "data_type": "uint16"},
            "or_pct": {"address": 12, "data_type": "uint16", "scale": 0.1}}
FAST_OPTIONS = ["--reads", "3", "--interval", "0.2", "--at", NIGHT_ISO]


def panel_doc(path: Path, port: int, station: StationEmulator) -> dict[str, Any]:
    write_panel(path, tcp_port=port, station_port=station.port)
    doc = yaml.safe_load(path.read_text())
    for act in doc["devices"]["entries"][0]["actuators"]:
        act["feedback"] = FEEDBACK[act["signal"]]
    return doc


def save(path: Path, doc: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def miswired(doc: dict[str, Any]) -> dict[str, Any]:
    """x1 and x3 registers exchanged, the room sensor's scale 0.01 for 0.1, and the louver
    set-point's sign inverted."""
    out = copy.deepcopy(doc)
    io = out["devices"]["entries"][0]
    by = {s["signal"]: s for s in io["sensors"]}
    by["x1_c"]["address"], by["x3_c"]["address"] = by["x3_c"]["address"], by["x1_c"]["address"]
    by["t_room_c"]["scale"] = 0.01
    (phi,) = [a for a in io["actuators"] if a["signal"] == "phi_deg"]
    phi["scale"] = -1.0
    return out


@dataclass
class Rig:
    io: EmulatedModbusDevice
    station: StationEmulator
    doc: dict[str, Any]
    panel: Path
    state: Path


@asynccontextmanager
async def rig(tmp_path: Path, station: StationEmulator) -> AsyncIterator[Rig]:
    port = free_port()
    doc = panel_doc(tmp_path / "panel.yaml", port, station)
    panel = save(tmp_path / "panel.yaml", doc)
    io = EmulatedModbusDevice.from_config(load_panel(panel).devices.entries[0],
                                          motor_rates=RATES)
    await io.start_tcp(port=port)
    await io.set_sensors(NIGHT_IO)
    for name, value in START.items():
        await io.set_position(name, value)
    station.start_periodic(0.05, lambda: NIGHT_STATION)
    try:
        yield Rig(io, station, doc, panel, tmp_path / "state")
    finally:
        station.stop_periodic()
        await io.stop()


async def commission(r: Rig, panel: Path, *options: str) -> tuple[int, str, str, dict[str, Any]]:
    """Run ``dsfd commission``; exit status, stdout, stderr and the newest JSON record."""
    rc, out, err = await run_dsfd("commission", "--config", str(panel), "--state-dir",
                                  str(r.state), *options)
    records = sorted((r.state / "commissioning").glob("commission-*.json"))
    doc = json.loads(records[-1].read_text()) if records else {}
    return rc, out, err, doc


def test_signals_on_a_correct_panel_every_row_good(tmp_path: Path,
                                                    station: StationEmulator) -> None:
    async def scenario() -> None:
        async with rig(tmp_path, station) as r:
            rc, out, err, doc = await commission(r, r.panel, "--signals", *FAST_OPTIONS)
            assert rc == 0, out + err
            rows = {row["signal"]: row for row in doc["signals"]["rows"]}
            assert set(rows) == {*NIGHT_IO, *NIGHT_STATION}
            for name, row in rows.items():
                assert row["quality"] == "good" and row["good_reads"] == 3, row
                served = {**NIGHT_IO, **NIGHT_STATION}[name]
                assert row["value"] == pytest.approx(served, abs=1e-6), row
                assert row["latency_ms"] > 0
            # Raw values are the register numbers: the thermocouples count 0.1 degC.
            assert rows["x3_c"]["raw"] == pytest.approx(168)
            assert rows["x3_c"]["source"] == "facade-io input 2 (int16 x0.1)"
            assert doc["night"] is True and doc["findings"] == []
            acts = {a["signal"]: a for a in doc["signals"]["actuators"]}
            assert {k: (a["set_point"], a["feedback"]) for k, a in acts.items()} == {
                k: (v, v) for k, v in START.items()}
            assert "verdict: every signal and move checked out" in out
            (page,) = (r.state / "commissioning").glob("commission-*.html")
            html = page.read_text()
            assert "Every signal and move checked out" in html
            # Self-contained: nothing to fetch, no script.
            assert re.findall(r'(?:src|href)="', html) == [] and "<script" not in html

    asyncio.run(scenario())


def test_signals_name_swapped_registers_wrong_scale_and_inverted_louver_sign(
        tmp_path: Path, station: StationEmulator) -> None:
    async def scenario() -> None:
        async with rig(tmp_path, station) as r:
            wrong = save(tmp_path / "miswired.yaml", miswired(r.doc))
            rc, out, err, doc = await commission(r, wrong, "--signals", *FAST_OPTIONS)
            assert rc == 1, out + err
            by = {}
            for f in doc["findings"]:
                by.setdefault(f["check"], []).append(f)
            assert set(by) == {"swap", "scale", "sign"}, doc["findings"]
            (swap,) = by["swap"]
            assert set(swap["signals"]) == {"x1_c", "x3_c"}
            assert "swapped" in swap["likely"] and "input 0" in swap["likely"]
            (scale,) = by["scale"]
            assert scale["signals"] == ["t_room_c"]
            assert "x10" in scale["likely"] and "0.01 -> 0.1" in scale["likely"]
            (sign,) = by["sign"]
            assert sign["signals"] == ["phi_deg"] and "inverted sign" in sign["likely"]
            # The console names them too.
            for text in ("x1_c and x3_c swapped", "wrong scale", "inverted sign"):
                assert text in out, out

    asyncio.run(scenario())


def test_stroke_reaches_every_louver_step_and_regime_and_returns(
        tmp_path: Path, station: StationEmulator) -> None:
    async def scenario() -> None:
        async with rig(tmp_path, station) as r:
            rc, out, err, doc = await commission(
                r, r.panel, "--stroke", "--yes-move-actuators", "--settle-s", "0.5",
                "--poll-s", "0.02", "--at", NIGHT_ISO)
            assert rc == 0, out + err
            moves = doc["stroke"]["moves"]
            assert all(m["verified"] and m["reached"] for m in moves), moves
            louver = [m["target"]["phi_deg"] for m in moves if m["stage"] == "louver"]
            assert louver == [18.0 * k for k in range(-5, 6)]
            regimes = [m["target"]["afr"] for m in moves if m["stage"] == "regime"]
            assert regimes == list(range(1, 11))
            dampers = [m["target"]["or_pct"] for m in moves if m["stage"] == "damper"]
            assert dampers == [0.0, 25.0, 50.0, 75.0, 100.0]
            # Read back through the feedback (the motor model's position), and timed: no
            # move can end before the motor has travelled, less the slack at both ends. The
            # slack is the tolerance and half the feedback register's step (the register
            # rounds the position): a move ends when its feedback reads within 2°, so the
            # motor may still be up to that slack short of the previous target when the next
            # one is written (on a loaded run the louver's -90° → -72° move took 0.0851 s,
            # less than 15.5° at 180°/s: it had set off from about -89.8°).
            previous = START
            for m in moves:
                for name, target in m["target"].items():
                    assert m["feedback"][name] == pytest.approx(target, abs=2.0), m
                    slack = 2.0 + 0.5 * FEEDBACK[name].get("scale", 1.0) if name != "afr" else 0.0
                    travel = abs(target - previous[name]) - 2.0 * slack
                    assert m["time_s"] >= max(0.0, travel) / RATES[name] * 0.999, m
                previous = m["target"]
            # The Modbus server saw each louver step written (FC 6 to holding 100).
            written = {regs[0] - (1 << 16) if regs[0] >= 1 << 15 else regs[0]
                       for address, regs in r.io.writes if address == 100}
            assert {18 * k for k in range(-5, 6)} <= written
            assert moves[-1]["stage"] == "return" and doc["stroke"]["returned"] is True
            assert await r.io.actuator_values() == START
            assert {k: await r.io.position(k) for k in START} == START

    asyncio.run(scenario())


def test_stroke_refused_while_a_daemon_holds_the_state_directory(
        tmp_path: Path, station: StationEmulator) -> None:
    async def scenario() -> None:
        async with rig(tmp_path, station) as r:
            daemon = await DaemonProcess(["run", "--config", str(r.panel), "--speed", "200",
                                          "--start", MORNING_ISO, "--cycles", "2000",
                                          "--state-dir", str(r.state)]).start()
            untouched = UntouchedDevice()
            try:
                await daemon.wait_cycle(1)
                other = copy.deepcopy(r.doc)
                other["devices"]["entries"][0]["tcp"]["port"] = untouched.port
                panel = save(tmp_path / "other.yaml", other)
                rc, out, err, _ = await commission(r, panel, "--stroke",
                                                   "--yes-move-actuators", "--at", NIGHT_ISO)
                assert rc == 3, out + err
                assert "refusing to move the actuators" in err
                assert daemon.proc is not None and f"PID {daemon.proc.pid}" in err
                assert not (r.state / "commissioning").exists()
                # Reading the signals is refused too: the daemon owns the serial lines.
                rc, _, err, _ = await commission(r, panel, "--signals", "--at", NIGHT_ISO)
                assert rc == 3 and f"PID {daemon.proc.pid}" in err
                # Without the confirmation it is refused before anything else.
                rc, _, err, _ = await commission(r, panel, "--stroke", "--at", NIGHT_ISO)
                assert rc == 2 and "--yes-move-actuators" in err
                assert not untouched.contacted()  # none of the three opened a device
            finally:
                daemon.signal(signal.SIGTERM)
                assert await daemon.wait_exit() == 0, daemon.stderr

    asyncio.run(scenario())


def test_stroke_stopped_by_wind_leaves_the_louver_at_its_safe_angle(
        tmp_path: Path, station: StationEmulator) -> None:
    weather = dict(NIGHT_STATION)

    async def scenario() -> None:
        async with rig(tmp_path, station) as r:
            station.start_periodic(0.05, lambda: weather)
            run = asyncio.create_task(commission(
                r, r.panel, "--stroke", "--yes-move-actuators", "--settle-s", "0.5",
                "--at", NIGHT_ISO))
            async with asyncio.timeout(60):  # hang guard
                while await r.io.value("phi_deg") != -54.0:
                    await asyncio.sleep(0.005)
            weather["wind_speed_ms"] = 22.0  # above safety.wind_limit_ms (15)
            rc, out, err, doc = await run
            assert rc == 1, out + err
            moves = doc["stroke"]["moves"]
            louver = [m["target"]["phi_deg"] for m in moves if m["stage"] == "louver"]
            assert louver[:3] == [-90.0, -72.0, -54.0] and len(louver) < 11
            assert moves[-1]["stage"] == "wind-safe" and moves[-1]["reached"]
            assert "wind 22.0 m/s" in doc["stroke"]["stopped"]
            assert doc["stroke"]["returned"] is False
            assert [f["check"] for f in doc["findings"]] == ["wind"]
            safe = {"phi_deg": 90.0, "afr": 10.0, "or_pct": 0.0}
            assert await r.io.actuator_values() == safe
            assert {k: await r.io.position(k) for k in safe} == safe

    asyncio.run(scenario())


def test_signals_flag_a_register_the_device_does_not_have(tmp_path: Path,
                                                          station: StationEmulator) -> None:
    async def scenario() -> None:
        async with rig(tmp_path, station) as r:
            doc = copy.deepcopy(r.doc)
            (v_cav,) = [s for s in doc["devices"]["entries"][0]["sensors"]
                        if s["signal"] == "v_cav_ms"]
            v_cav["address"] = 40  # the emulated module answers ILLEGAL_ADDRESS there
            rc, out, err, rec = await commission(r, save(tmp_path / "p.yaml", doc),
                                                 "--signals", *FAST_OPTIONS)
            assert rc == 1, out + err
            (f,) = rec["findings"]
            assert f["check"] == "quality" and f["signals"] == ["v_cav_ms"]
            assert "device_error" in f["message"] and "ILLEGAL_ADDRESS" in f["message"]
            assert "input register 40" in f["message"]
            bad = [row["signal"] for row in rec["signals"]["rows"] if row["quality"] != "good"]
            assert bad == ["v_cav_ms"]

    asyncio.run(scenario())
