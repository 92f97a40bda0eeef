"""BACnet/IP end to end: a third-party client (bacpypes3's client side, in a process of its
own, :mod:`dsfd.bench.bacnet_client`) → UDP on loopback → the real ``dsfd run`` (simulated
plant, dry run) with a ``bacnet:`` section → its database, ``dsfd status``.

* Who-Is is answered by an I-Am, Who-Has by an I-Have; a ReadPropertyMultiple of every
  object returns the values the database holds for the cycle the "stored cycle" point names
  (samples, decision, model rows, queried here independently) and the state message of that
  cycle on the MQTT state topic (a real Mosquitto, mosquitto_sub); a read-only device
  refuses writes (write-access-denied) and files nothing.
* A write of the louver at priority 8 is an operator hold from the next cycle; ``dsfd
  status`` names the BACnet requester; relinquishing it ends the hold and the controller
  decides again; a COV subscriber is notified of every stored cycle, and of the device
  going out of service when the daemon stops.
* A signal the quality checks flag sets its analog input's fault flag and reliability.
* With ``foreign_device``, the device registers with the BBMD (a raw socket stands in).
Bad writes and malformed datagrams: test_bacnet_robustness.py. Cycles are paced
(``--speed``): 60 simulated seconds every 0.25 s. Time limits are hang guards.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import socket
from pathlib import Path
from typing import Any

import pytest

from dsfd.config.panel import REGIME_NAMES
from dsfd.integrations.mqtt.broker import LocalBroker
from tests.daemon.harness import DaemonProcess, query, run_dsfd, suwon_mapping
from tests.integrations.bacnet_harness import (
    DEVICE_INSTANCE,
    ask,
    bacnet_section,
    camel,
    f32,
    rpm_values,
    run_with_client,
    setup,
    write,
)
from tests.integrations.mqtt_harness import Subscriber, mqtt_panel
from tests.integrations.test_mqtt_commands import answered, commands

pytest.importorskip("bacpypes3", reason="needs the bacnet extra: pip install 'dsfd[bacnet]'")

SENSORS = {1: "x1_c", 2: "x2_c", 3: "x3_c", 4: "x4_c", 5: "x5_c", 6: "v_cav_ms",
           7: "t_out_c", 8: "ghi_wm2"}
HEAT = {9: "q_sol_trans_w", 10: "q_cv_rd_w", 11: "q_air_w", 12: "q_da_w"}
#: Units a BMS expects for each quantity (BACnetEngineeringUnits names).
UNITS = {**{i: "degreesCelsius" for i in (1, 2, 3, 4, 5, 7)}, 6: "metersPerSecond",
         8: "wattsPerSquareMeter", **{i: "watts" for i in HEAT}, 13: "milliseconds",
         14: "seconds"}
ALL_OBJECTS = [*(f"analog-input,{i}" for i in range(1, 16)), "analog-value,1",
               "analog-value,2", "multi-state-value,1", "multi-state-value,2",
               "binary-value,1", "characterstring-value,1"]
DEVICE_REQUIRED = ["object-identifier", "object-name", "object-type", "system-status",
                   "vendor-name", "vendor-identifier", "model-name", "firmware-revision",
                   "application-software-version", "protocol-version", "protocol-revision",
                   "protocol-services-supported", "object-list",
                   "max-apdu-length-accepted", "segmentation-supported", "apdu-timeout",
                   "number-of-apdu-retries", "device-address-binding", "database-revision"]


def broadcast_who_is(port: int) -> bytes:
    """A Who-Is without limits as a BACnet/IP broadcast (Original-Broadcast-NPDU) from a raw
    socket; the answer's datagram."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
        s.bind(("127.0.0.1", 0))
        s.settimeout(10.0)
        s.sendto(bytes([0x81, 0x0B, 0x00, 0x08, 0x01, 0x00, 0x10, 0x08]),
                 ("127.255.255.255", port))
        return s.recv(1500)


def test_who_is_and_a_read_of_every_object_match_the_database_and_the_state_topic(
        broker: LocalBroker, tmp_path: Path) -> None:
    port, _, state, db, client = setup(tmp_path, writable=False)
    panel = mqtt_panel(tmp_path / "panel.yaml", broker,
                       extra={"bacnet": bacnet_section(port, writable=False,
                                                       address="127.0.0.1/8")})
    sub = Subscriber(broker, "dsfd/suwon-south/state", out=tmp_path / "sub.txt").start()
    seen: dict[str, Any] = {}

    async def body(d: DaemonProcess) -> None:
        seen["broadcast"] = await asyncio.to_thread(broadcast_who_is, port)
        seen["who_is"] = await ask(client, "who-is")
        seen["who_has"] = await ask(client, "who-has", name="louver angle")
        props = ["object-name", "present-value", "status-flags", "out-of-service"]
        seen["rpm"] = await ask(client, "rpm", objects=[
            *([o, [*props, "units", "cov-increment"]] for o in ALL_OBJECTS if "analog" in o),
            *([o, [*props, "state-text", "number-of-states"]] for o in ALL_OBJECTS
              if "multi" in o),
            *([o, props] for o in ALL_OBJECTS if "binary" in o or "string" in o),
            [f"device,{DEVICE_INSTANCE}", DEVICE_REQUIRED]])
        for i, o in enumerate(ALL_OBJECTS):  # SubscribeCOV on every object
            await ask(client, "cov", object=o, process=100 + i)
        await asyncio.to_thread(client.wait_for, lambda c: all(
            c.cov_values(o) for o in ALL_OBJECTS))
        seen["read_only"] = await write(client, "analog-value,1", 36.0)
        seen["objective_read_only"] = await write(client, "multi-state-value,2", 2,
                                                  kind="unsigned", priority=None)

    try:
        run_with_client(panel, state, client, body, first_cycle=40)  # after a calibration
        cycle = int(rpm_values(seen["rpm"])[("analogInput,15", "presentValue")])
        messages = sub.wait_for(lambda m: any(x.topic.endswith("/state") and
                                              x.json()["cycle"] == cycle for x in m))
    finally:
        sub.stop()
    # Who-Is → I-Am, Who-Has → I-Have. A broadcast Who-Is reaches the device on the
    # subnet's broadcast address (127.255.255.255 for 127.0.0.1/8); bacpypes3 answers the
    # requester: Original-Unicast-NPDU, unconfirmed I-Am (clause 16.10) with the device
    # identifier (object type 8), max APDU 1024, segmented-both, vendor 999.
    assert seen["broadcast"] == bytes([
        0x81, 0x0A, 0x00, 0x15, 0x01, 0x00, 0x10, 0x00, 0xC4,
        *((8 << 22) | DEVICE_INSTANCE).to_bytes(4, "big"), 0x22, 0x04, 0x00, 0x91, 0x00,
        0x22, 0x03, 0xE7])
    assert seen["who_is"]["i_am"] == [{"device": f"device,{DEVICE_INSTANCE}", "vendor": 999,
                                       "source": f"127.0.0.1:{port}"}]
    assert seen["who_has"]["i_have"] == [{"device": f"device,{DEVICE_INSTANCE}",
                                          "object": "analogValue,1", "name": "louver angle"}]
    got = rpm_values(seen["rpm"])
    dev = f"device,{DEVICE_INSTANCE}"
    assert all((dev, camel(p)) in got for p in DEVICE_REQUIRED), sorted(got)
    assert got[(dev, "objectName")] == "dsfd-suwon-south"
    assert len(got[(dev, "objectList")]) == 2 + len(ALL_OBJECTS)  # + device, network port
    # The cycle the device showed, and the database's values of that cycle.
    cycle = int(got[("analogInput,15", "presentValue")])
    ((time_s, phi, afr, or_pct, timings, objective),) = query(
        db, "SELECT time_s, phi_deg, afr, or_pct, timings_ms, objective_mode FROM decisions "
        "WHERE run_id = 1 AND cycle = ?", cycle)
    samples = dict(query(db, "SELECT signal, value FROM samples WHERE run_id = 1 AND "
                         "cycle = ? AND quality = 'good'", cycle))
    model = dict(zip(HEAT.values(), query(db, f"SELECT {', '.join(HEAT.values())} FROM model "
                                          "WHERE run_id = 1 AND cycle = ?", cycle)[0],
                     strict=True))
    (cal_s,) = query(db, "SELECT MAX(time_s) FROM parameters WHERE source = 'online' AND "
                     "time_s <= ?", time_s)[0]
    # A value the cycle does not have (a flagged reading, a NULL model figure) is shown as
    # the last one with the fault flag; every other one is the cycle's, without it.
    expected = {**{i: samples.get(name) for i, name in SENSORS.items()},
                **{i: model[col] for i, col in HEAT.items()}}
    faulty = {f"analog-input,{i}" for i, v in expected.items() if v is None}
    for i, value in expected.items():
        point = (f"analogInput,{i}", "presentValue")
        if value is None:
            assert got[(f"analogInput,{i}", "statusFlags")] == [0, 1, 0, 0], i
        else:
            assert got[point] == f32(value), i
    assert got[("analogInput,13", "presentValue")] == f32(json.loads(timings)["decide"])
    assert cal_s is not None
    assert got[("analogInput,14", "presentValue")] == f32(time_s - cal_s)
    assert got[("analogValue,1", "presentValue")] == f32(phi)
    assert got[("analogValue,2", "presentValue")] == f32(or_pct)
    assert got[("multiStateValue,1", "presentValue")] == afr
    assert got[("multiStateValue,1", "stateText")] == [REGIME_NAMES[r] for r in range(1, 11)]
    assert got[("multiStateValue,2", "stateText")][got[("multiStateValue,2",
                                                        "presentValue")] - 1] == objective
    for o in ALL_OBJECTS:
        key = camel(o)
        if o not in faulty:
            assert got[(key, "statusFlags")] == [0, 0, 0, 0], o  # no fault, in service
        assert got[(key, "outOfService")] is False
    for i, unit in UNITS.items():
        assert got[(f"analogInput,{i}", "units")] == unit
    assert (got[("analogValue,1", "units")], got[("analogValue,2", "units")]) == (
        "degreesAngular", "percent")
    doc = suwon_mapping()
    assert got[("analogValue,1", "covIncrement")] == f32(doc["louver"]["step_deg"])
    # The same cycle's message on the MQTT state topic (the daemon published it).
    (msg,) = [m.json() for m in messages if m.json()["cycle"] == cycle and not m.retained]
    topic = {**{i: msg["measured"][name] for i, name in SENSORS.items()},
             **{i: msg["heat_w"][term] for i, term in zip(
                 HEAT, ("q_sol_trans", "q_cv_rd", "q_air", "q_da"), strict=True)}}
    assert topic == expected  # the topic and the database agree (None: null)
    for i, value in topic.items():
        if value is not None:
            assert got[(f"analogInput,{i}", "presentValue")] == f32(value)
    assert got[("analogInput,14", "presentValue")] == f32(msg["calibration_age_s"])
    assert (got[("analogValue,1", "presentValue")], got[("analogValue,2", "presentValue")],
            got[("multiStateValue,1", "presentValue")]) == (
        msg["command"]["louver_deg"], msg["command"]["damper_pct"], msg["command"]["regime"])
    assert got[("characterstringValue,1", "presentValue")] == msg["set_by"]
    assert got[("binaryValue,1", "presentValue")] == ("active" if msg["fault"] else "inactive")
    assert got[("analogInput,7", "presentValue")] == f32(msg["measured"]["t_out_c"])
    assert got[("analogInput,13", "presentValue")] == f32(msg["decision_ms"])
    # Read-only: every write is refused and nothing is filed.
    denied = {"error": "Error(write-property)", "errorClass": "property",
              "errorCode": "writeAccessDenied"}
    assert seen["read_only"] == denied
    assert seen["objective_read_only"] == denied
    assert commands(db) == []


def first_cycle_after(d: DaemonProcess, time_s: float) -> int:
    return min(c for c in d.cycles_logged if d.cycle_ended_s(c) > time_s)


def test_a_write_at_priority_8_holds_the_louver_and_relinquishing_it_resumes(
        tmp_path: Path) -> None:
    _, panel, state, db, client = setup(tmp_path, writable=True)
    seen: dict[str, Any] = {}

    async def body(d: DaemonProcess) -> None:
        await ask(client, "cov", object="analog-input,15", process=1)
        await ask(client, "cov", object="analog-value,1", process=2, confirmed=True)
        seen["cov_property"] = [
            await ask(client, "cov-property", object="analog-value,1", process=3),
            await ask(client, "cov-property", object="analog-input,8", increment=2.0,
                      process=4, confirmed=True),
            await ask(client, "cov-property", object="characterstring-value,1", process=5)]
        await d.wait_cycle(d.cycles_logged[-1] + 2)
        seen["write"] = await write(client, "analog-value,1", 36.0, priority=8)
        (override,) = await answered(db, 1)
        await d.wait_cycle(override["cycle"] + 2)
        await asyncio.to_thread(client.wait_for, lambda c: 36.0 in c.cov_values(
            "analog-value,1"))
        seen["held"] = await ask(client, "rpm", objects=[["analog-value,1", [
            "present-value", "priority-array", "current-command-priority",
            "relinquish-default"]], ["characterstring-value,1", ["present-value"]]])
        seen["status"] = await run_dsfd("status", "--config", str(panel), "--state-dir",
                                        str(state))
        seen["status_json"] = await run_dsfd("status", "--state-dir", str(state), "--json")
        seen["relinquish"] = await write(client, "analog-value,1", None, kind="null",
                                         priority=8)
        resume = (await answered(db, 2))[1]
        await d.wait_cycle(resume["cycle"] + 3)
        seen["mode"] = await write(client, "multi-state-value,2", 2, kind="unsigned",
                                   priority=None)  # the objective: cooling
        mode = (await answered(db, 3))[2]
        await d.wait_cycle(mode["cycle"] + 1)
        seen["after"] = await ask(client, "rpm", objects=[["analog-value,1", [
            "present-value", "priority-array", "current-command-priority"]],
            ["multi-state-value,2", ["present-value"]]])
        last = d.cycles_logged[-1]
        await asyncio.to_thread(client.wait_for, lambda c: last in c.cov_values(
            "analog-input,15"))

    async def after_stop(d: DaemonProcess) -> None:
        await asyncio.to_thread(client.wait_for, lambda c: any(
            f[3] == 1 for f in c.cov_values("analog-input,15", "status-flags")))

    d = run_with_client(panel, state, client, body, after_stop=after_stop)
    override, resume, mode = commands(db)
    who = f"127.0.0.1:{client.bind_port} priority 8"
    # The objective's multi-state value: a mode command, as dsfd mode cooling.
    assert seen["mode"] == "ack"
    assert (mode["kind"], json.loads(mode["args"]), mode["source"], mode["status"]) == (
        "mode", {"mode": "cooling"}, "bacnet", "applied")
    assert mode["requester"] == f"127.0.0.1:{client.bind_port} objective"
    assert query(db, "SELECT objective_mode FROM decisions WHERE cycle = ?",
                 mode["cycle"]) == [("cooling",)]
    assert seen["write"] == "ack" and seen["relinquish"] == "ack"
    # Filed as dsfd override / resume are, with the BACnet source address and priority.
    assert (override["kind"], override["source"], override["requester"], override["status"]
            ) == ("override", "bacnet", who, "applied")
    assert json.loads(override["args"]) == {"louver_deg": 36.0}
    assert (resume["kind"], resume["source"], resume["requester"], resume["status"]) == (
        "resume", "bacnet", who, "applied")
    # Held from the first cycle after the write (at the latest the one after).
    assert override["cycle"] <= first_cycle_after(d, override["requested_s"]) + 1
    assert resume["cycle"] <= first_cycle_after(d, resume["requested_s"]) + 1
    rows = {c: (m, phi, src, cid) for c, m, phi, src, cid in query(
        db, "SELECT cycle, method, phi_deg, hold_source, hold_command_id FROM decisions")}
    for c in range(override["cycle"], resume["cycle"]):
        assert rows[c] == ("manual", 36.0, "operator", override["command_id"]), c
    assert rows[override["cycle"] - 1][2] is None
    # The hold lasts safety.manual_hold_min (120 min; the 22:00 reset is later), as others.
    assert query(db, "SELECT hold_expires_s - time_s FROM decisions WHERE cycle = ?",
                 override["cycle"]) == [(120 * 60.0,)]
    # Relinquished: the controller decides again.
    for c in range(resume["cycle"], max(rows) + 1):
        assert rows[c][0] in {"mpc", "rule"} and rows[c][2] is None, (c, rows[c])
    held = rpm_values(seen["held"])
    assert held[("analogValue,1", "presentValue")] == 36.0
    assert held[("analogValue,1", "currentCommandPriority")] == 8
    assert held[("analogValue,1", "priorityArray")] == [None] * 7 + [36.0] + [None] * 8
    assert held[("characterstringValue,1", "presentValue")] == \
        f"operator hold (bacnet {who})"
    after = rpm_values(seen["after"])
    assert after[("multiStateValue,2", "presentValue")] == 2
    assert after[("analogValue,1", "priorityArray")] == [None] * 16
    assert after[("analogValue,1", "currentCommandPriority")] is None
    # dsfd status names the BACnet requester.
    rc, text, err = seen["status"]
    assert rc == 0, err
    assert f"hold:        operator by bacnet {who} until" in text
    hold = json.loads(seen["status_json"][1])["hold"]
    assert (hold["source"], hold["command_id"]) == ("operator", override["command_id"])
    # COV: a notification for every stored cycle since the subscription, then the device
    # goes out of service at the daemon's stop.
    notified = [int(v) for v in client.cov_values("analog-input,15")]
    stored = [c for (c,) in query(db, "SELECT cycle FROM decisions ORDER BY cycle")]
    assert notified == sorted(notified)  # in order (the last one again: out of service)
    assert set(stored) >= set(notified) >= {c for c in stored if c >= notified[0]}
    assert client.cov_values("analog-input,15", "status-flags")[-1] == [0, 0, 0, 1]
    assert 36.0 in client.cov_values("analog-value,1")
    # SubscribeCOVProperty: the louver with its object's increment (one motor step), the
    # irradiance with the subscriber's 2 W/m2 (confirmed), the set-by text at any change.
    assert [a["answer"] for a in seen["cov_property"]] == ["ack"] * 3
    louver = client.cov_values("analog-value,1", process=3)
    assert 36.0 in louver
    assert all(abs(b - a) >= 18.0 for a, b in itertools.pairwise(louver))
    ghi = client.cov_values("analog-input,8", process=4)
    assert len(ghi) >= 3  # the morning sun: irradiance rises
    assert all(abs(b - a) >= 2.0 for a, b in itertools.pairwise(ghi))
    texts = client.cov_values("characterstring-value,1", process=5)
    assert f"operator hold (bacnet {who})" in texts and texts[-1] in {"mpc", "rule"}


def test_a_flagged_signal_sets_its_fault_flag(tmp_path: Path) -> None:
    # x1 flagged RATE whenever it moves by more than 0.001 K a minute: every cycle.
    _, panel, state, db, client = setup(tmp_path, writable=False, extra={
        "daemon": {"quality": {"max_rate_k_per_min": 0.001, "rate_signals": ["x1_c"]}}})
    seen: dict[str, Any] = {}

    async def body(d: DaemonProcess) -> None:
        seen["rpm"] = await ask(client, "rpm", objects=[
            [o, ["present-value", "status-flags", "reliability"]] for o in (
                "analog-input,1", "analog-input,2", "binary-value,1", "analog-input,15")])

    run_with_client(panel, state, client, body, first_cycle=5)
    got = rpm_values(seen["rpm"])
    cycle = int(got[("analogInput,15", "presentValue")])
    quality = dict(query(db, "SELECT signal, quality FROM samples WHERE run_id = 1 AND "
                         "cycle = ?", cycle))
    assert quality["x1_c"] != "good" and quality["x2_c"] == "good"
    assert got[("analogInput,1", "statusFlags")] == [0, 1, 0, 0]
    assert got[("analogInput,1", "reliability")] == "unreliableOther"
    assert got[("analogInput,2", "statusFlags")] == [0, 0, 0, 0]
    assert got[("analogInput,2", "reliability")] == "noFaultDetected"
    assert got[("binaryValue,1", "presentValue")] == "active"  # the panel's fault point


def test_a_hold_until_relinquished_lasts_a_week(tmp_path: Path) -> None:
    _, panel, state, db, client = setup(tmp_path, writable=True, bacnet={
        "hold_until_relinquished": True})
    seen: dict[str, Any] = {}

    async def body(d: DaemonProcess) -> None:
        seen["write"] = await write(client, "multi-state-value,1", 3, kind="unsigned",
                                    priority=5)
        seen["command"] = (await answered(db, 1))[0]

    run_with_client(panel, state, client, body)
    cmd = seen["command"]
    assert seen["write"] == "ack" and cmd["status"] == "applied"
    assert cmd["requester"] == f"127.0.0.1:{client.bind_port} priority 5"
    assert query(db, "SELECT afr, hold_source, hold_expires_s - time_s FROM decisions "
                 "WHERE cycle = ?", cmd["cycle"]) == [(3, "operator", 7 * 86400.0)]


def test_the_device_registers_as_a_foreign_device_with_the_bbmd(tmp_path: Path) -> None:
    """A raw socket stands in for the BBMD: it receives Register-Foreign-Device (Annex
    J.2.6: BVLL function 0x05 with the time-to-live) and acknowledges it (BVLC-Result 0)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as bbmd:
        bbmd.bind(("127.0.0.1", 0))
        bbmd.settimeout(30.0)
        _, panel, state, _, client = setup(tmp_path, writable=False, bacnet={
            "foreign_device": {"bbmd": f"127.0.0.1:{bbmd.getsockname()[1]}", "ttl_s": 120}})
        seen: dict[str, Any] = {}

        async def body(d: DaemonProcess) -> None:
            data, source = await asyncio.to_thread(bbmd.recvfrom, 1500)
            bbmd.sendto(bytes([0x81, 0x00, 0x00, 0x06, 0x00, 0x00]), source)
            seen["register"], seen["source"] = data, source
            seen["who_is"] = await ask(client, "who-is")  # still answers directly

        run_with_client(panel, state, client, body)
    assert seen["register"] == bytes([0x81, 0x05, 0x00, 0x06, 0x00, 120])
    assert seen["source"] == ("127.0.0.1", client.device_port)
    assert [a["device"] for a in seen["who_is"]["i_am"]] == [f"device,{DEVICE_INSTANCE}"]
