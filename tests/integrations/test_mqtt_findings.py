"""Findings over MQTT, hardware in the loop (issue 38): a real ``dsfd run`` talking Modbus TCP
to the emulated I/O module and reading the emulated weather station on a pty, both coupled to
the simulated plant (:class:`hil.plant_bridge.PlantBridge`, as tests/hil/test_hil_daemon.py),
in which damper IT is stuck shut from 30 min in while the I/O module's position read-back
keeps reporting the command; beside a real Mosquitto.

* The daemon's own diagnostics find the stuck damper (IT, or "EB, IT" while the supply path
  is the only one tried) from what it reads over Modbus, and publish it, retained, on its
  Home Assistant problem sensor's topic ``<base>/finding/damper_no_flow`` (state ``ON``, the
  finding with its evidence as the attributes); the metrics file's
  ``dsfd_finding_open{kind="damper_no_flow"}`` is 1.
* ``dsfd ack`` of a finding that does not exist is rejected by the daemon and changes
  nothing; malformed ``<base>/cmd/ack`` payloads are answered on ``<base>/error`` and change
  nothing, and an ack of an id that is no finding is filed, rejected by the daemon and
  answered there with its command id.
* ``mosquitto_pub`` of the finding's id on ``<base>/cmd/ack`` closes it: the topic turns
  ``OFF``, the gauge 0, the row ``acknowledged``; and while the same evidence lasts (the
  damper stays stuck to the end of the run, the checks go on) it stays closed.

The plant and the daemon run at 480 × real time (60 simulated seconds every 0.125 s). Time
limits are hang guards.
"""

from __future__ import annotations

import asyncio
import json
import math
from pathlib import Path
from typing import Any

import pytest
from prometheus_client.parser import text_string_to_metric_families

from dsfd.config import load_panel
from dsfd.daemon.commands import CommandError, validate_command
from dsfd.integrations.mqtt.broker import LocalBroker
from dsfd.integrations.mqtt.commands import request_of
from dsfd.measured import parse_iso_utc
from dsfd.sim.daemon_plant import simulated_plant
from dsfd.sim.plant.faults import parse_fault
from hil.modbus_device import EmulatedModbusDevice
from hil.plant_bridge import PlantBridge
from hil.station import StationEmulator
from tests.daemon.harness import DaemonProcess, free_port, query, run_dsfd
from tests.hil.test_hil_daemon import HIL_PLANT
from tests.integrations.mqtt_harness import Message, Subscriber, mqtt_panel
from tests.integrations.test_mqtt_commands import commands, publish

START = "2022-01-01T23:30:00Z"  # 08:30 in Suwon, January (as the stuck-damper dry run)
PANEL = "suwon-south"
BASE = f"dsfd/{PANEL}"
TOPIC = f"{BASE}/finding/damper_no_flow"
#: Hang guards [s]: the finding needs about 105 cycles (26 s paced) after the start.
FIND_LIMIT_S = 150.0
POLL_LIMIT_S = 60.0
CYCLES = 200
SPEED = 480.0
STUCK = "damper-stuck.IT:+30min:0"


def _latest(messages: list[Message], topic: str) -> dict[str, Any] | None:
    found = [m for m in messages if m.topic == topic]
    return found[-1].json() if found else None


def _it_finding(messages: list[Message]) -> dict[str, Any] | None:
    """The open damper finding once it names IT (alone, or with the other damper of the
    only path tried so far)."""
    last = _latest(messages, TOPIC)
    if last is None or last["state"] != "ON":
        return None
    return next((f for f in last["findings"] if "IT" in f["subject"].split("+")), None)


def _gauge(prom: Path, kind: str) -> float | None:
    try:
        text = prom.read_text()
    except FileNotFoundError:
        return None
    for family in text_string_to_metric_families(text):
        for s in family.samples:
            if s.name == "dsfd_finding_open" and s.labels.get("kind") == kind:
                return s.value
    return None


async def _until(predicate: Any, limit_s: float = POLL_LIMIT_S) -> Any:
    async with asyncio.timeout(limit_s):
        while not (got := predicate()):
            await asyncio.sleep(0.1)
        return got


@pytest.mark.hil
def test_a_stuck_damper_is_published_as_a_problem_and_an_ack_over_mqtt_closes_it(
        broker: LocalBroker, tmp_path: Path) -> None:
    prom = tmp_path / "dsfd-test.prom"
    port = free_port()
    with StationEmulator() as station:
        panel = mqtt_panel(tmp_path / "panel.yaml", broker, tcp_port=port,
                           station_port=station.port,
                           extra={"daemon": {"metrics_file": str(prom)}})
        seen = _scenario(broker, panel, station, port, tmp_path)
    _check(seen, tmp_path / "state" / "timeseries.sqlite")


def _scenario(broker: LocalBroker, panel: Path, station: StationEmulator, port: int,
              tmp_path: Path) -> dict[str, Any]:
    """Run the HIL daemon with the stuck damper; what it published, filed and answered."""
    prom = tmp_path / "dsfd-test.prom"
    state = tmp_path / "state"
    cfg = load_panel(panel)
    plant = simulated_plant(cfg, start_s=parse_iso_utc(START), cycles=4 * CYCLES,
                            options=HIL_PLANT, faults=(parse_fault(STUCK),)).plant
    emulator = EmulatedModbusDevice.from_config(cfg.devices.entries[0])
    sub = Subscriber(broker, f"{BASE}/finding/#", f"{BASE}/error",
                     out=tmp_path / "sub.txt").start()
    seen: dict[str, Any] = {}

    async def scenario() -> None:
        await emulator.start_tcp(port=port)
        bridge = PlantBridge(plant, io=emulator, station=station, speed=SPEED)
        await bridge.start()
        try:
            await _operate(broker, panel, state, prom, sub, seen)
        finally:
            await bridge.stop()
            await emulator.stop()
        seen["applied"] = bridge.applied

    try:
        asyncio.run(scenario())
    finally:
        sub.stop()
    seen["messages"] = sub.messages()
    return seen


async def _operate(broker: LocalBroker, panel: Path, state: Path, prom: Path,
                   sub: Subscriber, seen: dict[str, Any]) -> None:
    """The daemon's run, the finding, the bad and the good acks, the closed finding."""
    d = await DaemonProcess(["run", "--config", str(panel), "--speed", str(SPEED), "--start",
                             START, "--cycles", str(CYCLES), "--state-dir", str(state)]).start()
    try:
        finding = await _until(lambda: _it_finding(sub.messages()), FIND_LIMIT_S)
        seen["finding"] = finding
        seen["open_gauge"] = await _until(lambda: _gauge(prom, "damper_no_flow") == 1.0)
        # a finding that does not exist: the daemon answers, nothing changes
        seen["bad_ack"] = await run_dsfd("ack", "--config", str(panel), "--state-dir",
                                         str(state), "999", "--wait", "30")
        # malformed payloads: answered on <base>/error, nothing filed
        for payload in ("abc", '{"finding": 0}', "2.5", '{"finding": 1, "x": 2}'):
            publish(broker, f"{BASE}/cmd/ack", payload)
        await _until(lambda: len([m for m in sub.messages()
                                  if m.topic == f"{BASE}/error"]) >= 4)
        # well-formed, but no such finding: filed, rejected by the loop, answered
        publish(broker, f"{BASE}/cmd/ack", "999")
        await _until(lambda: len([m for m in sub.messages()
                                  if m.topic == f"{BASE}/error"]) >= 5)
        publish(broker, f"{BASE}/cmd/ack", str(finding["id"]))
        seen["closed"] = await _until(lambda: (_latest(sub.messages(), TOPIC) or {}).get(
            "state") == "OFF")
        seen["closed_gauge"] = await _until(lambda: _gauge(prom, "damper_no_flow") == 0.0)
        assert await d.wait_exit() == 0, d.stderr_now()  # the run ends by itself
    finally:
        if d.proc.returncode is None:  # a failed check: no daemon left behind
            d.proc.kill()
            await d.proc.wait()


def _check(seen: dict[str, Any], db: Path) -> None:
    f = seen["finding"]
    # the finding as Home Assistant's attributes show it: id, damper, action, evidence
    named = ", ".join(f["subject"].split("+"))
    assert f"check damper {named}" in f["action"] and 0.5 <= f["confidence"] <= 1.0
    assert f["evidence"] and all("IT" in e["signal"] and e["unit"] == "m/s"
                                 for e in f["evidence"])
    rc, out, err = seen["bad_ack"]
    assert rc == 1 and "rejected" in out and "finding: 999: no such finding" in out, (out, err)
    errors = [json.loads(m.payload) for m in seen["messages"] if m.topic == f"{BASE}/error"]
    assert [e["payload"] for e in errors] == ["abc", '{"finding": 0}', "2.5",
                                              '{"finding": 1, "x": 2}', "999"]
    assert all(e["topic"] == f"{BASE}/cmd/ack" and e["reason"] for e in errors)
    assert [e["command_id"] is None for e in errors] == [True] * 4 + [False]
    assert "no such finding" in errors[-1]["reason"]
    cmds = commands(db)
    assert [(c["kind"], c["source"], c["status"]) for c in cmds] == [
        ("ack", "cli", "rejected"), ("ack", "mqtt", "rejected"), ("ack", "mqtt", "applied")]
    assert errors[-1]["command_id"] == cmds[1]["command_id"]
    ack = cmds[2]
    assert json.loads(ack["args"]) == {"finding": f["id"]}
    # closed by that command, and still closed at the end although the damper stayed stuck
    # and the checks went on seeing it (no new start: the same evidence)
    row = query(db, "SELECT state, ack_command_id, end_reason FROM findings WHERE "
                    "finding_id = ?", f["id"])[0]
    assert row[:2] == ("acknowledged", ack["command_id"]) and "mqtt" in row[2]
    assert query(db, "SELECT COUNT(*) FROM findings WHERE kind = 'damper_no_flow' AND "
                     "state = 'open'") == [(0,)]
    last_check = query(db, "SELECT MAX(time_s) FROM decisions")[0][0]
    assert last_check - query(db, "SELECT time_s FROM decisions WHERE cycle = ?",
                              ack["cycle"])[0][0] >= 20 * 60  # two checks or more after it
    assert _latest(seen["messages"], TOPIC)["state"] == "OFF"
    # the commands travelled over Modbus to the I/O module and on to the plant
    assert seen["applied"]


def test_ack_payloads_map_to_requests_and_malformed_ones_name_the_problem() -> None:
    assert request_of("ack", b"3") == {"command": "ack", "finding": 3}
    assert request_of("ack", b'{"finding": 12}') == {"command": "ack", "finding": 12}
    # the one validation of every source: a whole number from 1, nothing else
    assert validate_command(None, {"command": "ack", "finding": "7"}).finding == 7  # the CLI
    for bad in (0, -1, 2.5, True, math.nan, math.inf, None, "x", [], 2**63, "9" * 30):
        with pytest.raises(CommandError, match="finding"):
            validate_command(None, {"command": "ack", "finding": bad})
    with pytest.raises(CommandError, match="unknown field"):
        validate_command(None, {"command": "ack", "finding": 1, "hold": "2h"})
