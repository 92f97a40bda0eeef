"""Commands over MQTT, end to end: ``mosquitto_pub`` (a BMS, Home Assistant) → a real
Mosquitto with a password file → the real ``dsfd run`` (simulated plant, dry run) → its
database, its state messages, ``dsfd status`` and its metrics file.

* An override published with ``mosquitto_pub`` holds the panel from the first cycle that
  starts after it arrived (at the latest the one after), resume ends the hold; both are in
  the ``commands`` table (source ``mqtt``) and the held cycles in ``decisions`` (method
  ``manual``), and the state messages, ``dsfd status`` and the metrics say so.
* More than a thousand malformed or impossible command payloads (random bytes, text that is
  not a command, wrong JSON, wrong types, huge and out-of-range values, unknown subtopics,
  retained commands, payloads of up to 8 MiB) during an operator hold change nothing: the
  hold and the position stay, nothing new is filed, every cycle is stored, each payload is
  answered on ``<base>/error``; a good command afterwards still works.
* The payloads of Home Assistant's select, number and button entities — taken from the
  discovery configs the daemon published, sent the way Home Assistant sends them — command
  the panel, and the entities' ``value_template`` render what was commanded.

Cycles are paced (``--speed``): 60 simulated seconds every 0.25 s. Time limits are hang
guards.
"""

from __future__ import annotations

import asyncio
import json
import random
import signal
import sqlite3
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

from prometheus_client.parser import text_string_to_metric_families

from dsfd.integrations.mqtt.broker import LocalBroker, find_mosquitto
from dsfd.integrations.mqtt.messages import utc_iso
from tests.daemon.harness import DaemonProcess, query, run_dsfd
from tests.integrations.mqtt_harness import Message, Subscriber, mqtt_panel, run_args
from tests.integrations.test_mqtt_publish import render

START = "2022-01-01T23:30:00Z"  # 08:30 in Suwon, January: the auto objective is heating
SPEED = 240.0
PANEL = "suwon-south"
BASE = f"dsfd/{PANEL}"
#: Hang guard for one command's answer from the daemon [s].
ANSWER_LIMIT_S = 60.0


def publish(broker: LocalBroker, topic: str, payload: str | None = None, *,
            lines: bytes | None = None, file: Path | None = None, qos: int = 1,
            retain: bool = False) -> None:
    """``mosquitto_pub``: one message (``payload``), one per line of ``lines`` (``-l``) or
    a file's bytes as one message (``-f``)."""
    cmd = [find_mosquitto("mosquitto_pub") or "mosquitto_pub", "-h", "127.0.0.1",
           "-p", str(broker.port), "-u", broker.username, "-P", broker.password,
           "-q", str(qos), "-t", topic]
    if retain:
        cmd.append("-r")
    if lines is not None:
        cmd.append("-l")
    elif file is not None:
        cmd += ["-f", str(file)]
    else:
        cmd += ["-m", payload or ""]
    subprocess.run(cmd, input=lines, capture_output=True, check=True, timeout=120)


def commands(db: Path) -> list[dict[str, Any]]:
    cols = ("command_id", "kind", "args", "source", "requester", "requested_s", "status",
            "reason", "cycle")
    return [dict(zip(cols, r, strict=True)) for r in
            query(db, f"SELECT {', '.join(cols)} FROM commands ORDER BY command_id")]


def decisions(db: Path) -> dict[int, dict[str, Any]]:
    cols = ("cycle", "time_s", "method", "phi_deg", "afr", "or_pct", "heating", "write_status",
            "hold_source", "hold_expires_s", "hold_command_id", "objective_mode",
            "mode_command_id")
    rows = query(db, f"SELECT {', '.join(cols)} FROM decisions ORDER BY cycle")
    return {r[0]: dict(zip(cols, r, strict=True)) for r in rows}


async def answered(db: Path, count: int) -> list[dict[str, Any]]:
    """Until ``count`` commands are in the table and none is pending."""
    async with asyncio.timeout(ANSWER_LIMIT_S):
        while True:
            try:
                rows = commands(db)
            except sqlite3.OperationalError:  # busy for a moment
                rows = []
            if len(rows) >= count and all(r["status"] != "pending" for r in rows):
                return rows
            await asyncio.sleep(0.1)


async def cursor_moved(db: Path) -> None:
    """Until the publisher has saved a delivered cycle in ``mqtt_cursor``."""
    async with asyncio.timeout(ANSWER_LIMIT_S):
        while not query(db, "SELECT cycle FROM mqtt_cursor WHERE cycle > 0"):
            await asyncio.sleep(0.1)


async def wait_messages(sub: Subscriber, predicate: Callable[[list[Message]], bool]
                        ) -> list[Message]:
    return await asyncio.to_thread(sub.wait_for, predicate)


def states(messages: list[Message]) -> dict[int, dict[str, Any]]:
    return {m.json()["cycle"]: m.json() for m in messages if m.topic == f"{BASE}/state"}


def within_one_cycle(d: DaemonProcess, row: dict[str, Any]) -> bool:
    """Applied at the first cycle that started after it was filed, or the one after (the
    first may have read the table just before)."""
    first_after = min(c for c in d.cycles_logged if d.cycle_ended_s(c) > row["requested_s"])
    return row["cycle"] <= first_after + 1


def metrics(path: Path) -> dict[str, list[Any]]:
    return {f.name: f.samples for f in text_string_to_metric_families(path.read_text())}


def test_an_override_over_mqtt_holds_within_one_cycle_and_resume_ends_it(
        broker: LocalBroker, tmp_path: Path) -> None:
    prom = tmp_path / "dsfd-test.prom"
    panel = mqtt_panel(tmp_path / "panel.yaml", broker,
                       extra={"daemon": {"metrics_file": str(prom)}})
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"
    sub = Subscriber(broker, f"{BASE}/state", f"{BASE}/error", out=tmp_path / "sub.txt").start()
    seen: dict[str, Any] = {}

    async def scenario() -> DaemonProcess:
        d = await DaemonProcess(run_args(panel, state, start=START, cycles=2000,
                                         speed=SPEED)).start()
        await d.wait_cycle(3)
        await wait_messages(sub, lambda m: bool(states(m)))  # connected and subscribed
        publish(broker, f"{BASE}/cmd/override", '{"hold": "30min", "louver_deg": 54}')
        (override,) = await answered(db, 1)
        await cursor_moved(db)  # saved every 2 s while messages flow
        seen["status"] = await run_dsfd("status", "--config", str(panel), "--state-dir",
                                        str(state))
        seen["status_json"] = await run_dsfd("status", "--state-dir", str(state), "--json")
        seen["metrics"] = metrics(prom)
        await d.wait_cycle(override["cycle"] + 2)
        publish(broker, f"{BASE}/cmd/resume", "resume")
        resume = (await answered(db, 2))[1]
        await d.wait_cycle(resume["cycle"] + 1)
        await wait_messages(sub, lambda m: resume["cycle"] in states(m))
        d.signal(signal.SIGTERM)
        assert await d.wait_exit() == 0, d.stderr
        return d

    try:
        d = asyncio.run(scenario())
    finally:
        sub.stop()
    override, resume = commands(db)
    rows = decisions(db)
    # Filed as the CLI files them, with MQTT as the source, and applied within one cycle.
    for row, kind in ((override, "override"), (resume, "resume")):
        assert (row["kind"], row["source"], row["status"]) == (kind, "mqtt", "applied")
        assert row["requester"] == f"{broker.address} {BASE}/cmd/{kind}"
        assert within_one_cycle(d, row), (row, d.cycles_logged)
    assert json.loads(override["args"]) == {"hold": "30min", "louver_deg": 54}
    held = range(override["cycle"], resume["cycle"])
    assert len(held) >= 2
    for c in held:
        r = rows[c]
        assert (r["method"], r["hold_source"], r["hold_command_id"]) == (
            "manual", "operator", override["command_id"])
        assert r["phi_deg"] == 54.0
    assert rows[override["cycle"]]["hold_expires_s"] - rows[override["cycle"]]["time_s"] == \
        30 * 60
    assert rows[override["cycle"] - 1]["hold_source"] is None
    after = rows[resume["cycle"]]
    assert after["hold_source"] is None and after["method"] in {"mpc", "rule"}
    # The state messages carry the hold (Home Assistant's hold sensor, dsfd fleet).
    got = states(sub.messages())
    s = got[override["cycle"]]
    assert (s["hold"], s["hold_source"], s["set_by"]) == (True, "operator", "manual")
    assert s["hold_until_utc"] == utc_iso(rows[override["cycle"]]["hold_expires_s"])
    assert s["hold_by"] == f"mqtt {broker.address} {BASE}/cmd/override"
    assert got[resume["cycle"]]["hold"] is False
    assert not [m for m in sub.messages() if m.topic == f"{BASE}/error"]
    # dsfd status: the hold and who gave it, and the broker's state.
    rc, text, err = seen["status"]
    assert rc == 0, err
    assert f"hold:        operator by mqtt {broker.address} {BASE}/cmd/override until" in text
    assert f"mqtt:        {broker.address} {BASE}: connected;" in text
    (m,) = json.loads(seen["status_json"][1])["mqtt"]
    assert m["connected"] is True and m["last_error"] == ""
    assert m["last_delivered"]["run_id"] == 1 and m["last_delivered"]["cycle"] >= 1
    # The metrics file: connected, no error, the command counted.
    fam = seen["metrics"]
    value = {name: samples[0].value for name, samples in fam.items() if samples}
    assert value["dsfd_mqtt_connected"] == 1.0
    assert [(x.labels["reason"], x.value) for x in fam["dsfd_mqtt_error"]] == [("", 0.0)]
    queued = {x.labels["result"]: x.value for x in fam["dsfd_mqtt_commands"]
              if x.name == "dsfd_mqtt_commands_total"}
    assert queued["queued"] == 1.0 and queued["refused"] == 0.0
    assert value["dsfd_mqtt_delivered_cycle"] >= 1 and value["dsfd_hold_active"] == 1.0


def malformed_lines(rng: random.Random) -> dict[str, list[bytes]]:
    """Per command subtopic, payloads none of which is a command (by construction: the
    docs/mqtt.md's payload rules, not the code, say why each fails)."""
    def random_bytes() -> bytes:  # starts with a byte no UTF-8 text starts with
        body = bytes(b for b in rng.randbytes(rng.randint(1, 300)) if b not in b"\0\n")
        return bytes([rng.randint(0x80, 0xBF)]) + body

    def random_text() -> bytes:  # "~" starts no JSON, number, option, mode or "resume"
        return ("~" + "".join(rng.choice("abcdefxyz 0123456789{}[]:,.\"'-+eE")
                              for _ in range(rng.randint(0, 80)))).encode()

    crafted = {
        "override": [b"hold 2h", b"[36]", b"null", b"42", b'"2h"', b'{"louver_deg": "36"}',
                     b'{"louver_deg": 45}', b'{"louver_deg": 1e400}', b'{"louver_deg": NaN}',
                     b'{"louver_deg": ' + b"9" * 600 + b"}", b'{"regime": 11}',
                     b'{"regime": 0}', b'{"regime": 2.5}', b'{"or_pct": 150}',
                     b'{"or_pct": -10}', b'{"or_pct": 42.5}', b'{"regime": 10, "or_pct": 30}',
                     b'{"hold": "10s"}', b'{"hold": "9d"}', b'{"hold": 1e308}',
                     b'{"hold": "soon"}', b'{"hold": true}', b'{"speed": 3}',
                     b'{"command": "resume"}', b"{" * 200, b"[" * 500 + b"]" * 500,
                     b'{"louver_deg": 36', b"{'louver_deg': 36}"],
        "regime": [b"11", b"0", b"-3", b"7.5", b"seven", b"7: all dampers open",
                   b"3: outdoor air curtain down", b'{"regime": 3}', b"1e3"],
        "louver_deg": [b"45", b"1e999", b"NaN", b"-Infinity", b"99999999999999999999999",
                       b"36.5", b"true", b'"36"', b"[36]", b"0x24", b"108", b"-108"],
        "damper_pct": [b"101", b"42.5", b"-1", b"1e9", b"open", b"null"],
        "resume": [b"RESUME", b"PRESS", b'{"hold": "2h"}', b"resume please", b"[]", b"1"],
        "mode": [b"summer", b"HEATING", b'{"mode": 1}', b'{"mode": "cooling", "x": 1}',
                 b"heat", b"auto!"],
        "explode": [b"{}", b"1"], "override/now": [b"{}"], "": [b"{}"],
    }
    out = {topic: [*lines] for topic, lines in crafted.items()}
    subtopics = ["override", "regime", "louver_deg", "damper_pct", "resume", "mode"]
    for k in range(700):
        out[subtopics[k % len(subtopics)]].append(random_bytes() if k % 2 else random_text())
    while sum(len(v) for v in out.values()) < 1100:  # the crafted ones again
        for topic in ("override", "regime", "louver_deg"):
            out[topic] += crafted[topic]
    return out


def test_a_thousand_malformed_commands_change_nothing_and_are_answered(
        broker: LocalBroker, tmp_path: Path) -> None:
    panel = mqtt_panel(tmp_path / "panel.yaml", broker)
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"
    flood = malformed_lines(random.Random(22))
    big = []
    for size in (64 * 1024, 1024 * 1024, 8 * 1024 * 1024):
        big.append(tmp_path / f"big-{size}.bin")
        big[-1].write_bytes(random.Random(size).randbytes(size))
    sent = sum(len(v) for v in flood.values()) + len(big) + 1  # + the retained override
    errors = Subscriber(broker, f"{BASE}/error", out=tmp_path / "errors.txt").start()
    # Given while no daemon listened: the plain one is gone (clean session: nothing is kept
    # for the daemon), the retained one is replayed at the daemon's subscription, flagged
    # retained, and refused as old.
    publish(broker, f"{BASE}/cmd/override", '{"regime": 10}')
    publish(broker, f"{BASE}/cmd/override", "{}", retain=True)
    seen: dict[str, Any] = {}

    async def scenario() -> DaemonProcess:
        d = await DaemonProcess(run_args(panel, state, start=START, cycles=4000,
                                         speed=SPEED)).start()
        await d.wait_for(lambda d: any(r.get("event") == "MQTT connected"
                                       for r in d.records))
        await d.wait_cycle(3)
        publish(broker, f"{BASE}/cmd/override", '{"regime": 3, "louver_deg": -36}')
        (held,) = await answered(db, 1)
        seen["held"] = held
        await d.wait_cycle(held["cycle"] + 1)
        seen["before"] = d.cycles_logged[-1]
        for topic, lines in flood.items():
            await asyncio.to_thread(publish, broker, f"{BASE}/cmd/{topic}",
                                    lines=b"\n".join(lines) + b"\n")
        for path in big:
            await asyncio.to_thread(publish, broker, f"{BASE}/cmd/override", file=path)
        await asyncio.to_thread(errors.wait_for, lambda m: answers_for(m) >= sent)
        seen["after"] = d.cycles_logged[-1]
        await d.wait_cycle(seen["after"] + 2)
        publish(broker, f"{BASE}/cmd/resume", "resume")  # the receiver still works
        seen["resume"] = (await answered(db, 2))[1]
        await d.wait_cycle(seen["resume"]["cycle"] + 1)
        d.signal(signal.SIGTERM)
        assert await d.wait_exit() == 0, d.stderr
        return d

    try:
        d = asyncio.run(scenario())
    finally:
        errors.stop()
        publish(broker, f"{BASE}/cmd/override", retain=True)  # clear the retained one
    held, resume = seen["held"], seen["resume"]
    # Nothing was filed but the two good commands.
    assert [(c["kind"], c["status"]) for c in commands(db)] == [("override", "applied"),
                                                                ("resume", "applied")]
    # Every cycle ran and was stored; during the flood the hold and the position stayed.
    rows = decisions(db)
    assert list(rows) == d.cycles_logged == list(range(1, d.cycles_logged[-1] + 1))
    assert not [r for r in d.records if r.get("event") == "cycle failed"]
    during = range(held["cycle"], resume["cycle"])
    assert seen["after"] - seen["before"] >= 1 and resume["cycle"] > seen["after"]
    assert {(rows[c]["method"], rows[c]["hold_source"], rows[c]["hold_command_id"],
             rows[c]["phi_deg"], rows[c]["afr"]) for c in during} == {
        ("manual", "operator", held["command_id"], -36.0, 3)}
    # Each payload was answered on <base>/error (or counted in a 'dropped' answer).
    got = [m.json() for m in errors.messages()]
    assert answers_for(errors.messages()) == sent
    assert all(set(a) == {"topic", "reason", "payload", "payload_bytes", "command_id"}
               for a in got)
    assert all(len(a["payload"]) <= 200 + len("… (8388608 bytes)") for a in got)
    sizes = sorted(a["payload_bytes"] for a in got if "longer than" in a["reason"])
    assert sizes[-3:] == [64 * 1024, 1024 * 1024, 8 * 1024 * 1024]
    assert any("retained command" in a["reason"] for a in got)
    assert {a["topic"] for a in got} >= {f"{BASE}/cmd/{t}" for t in flood}
    assert all(a["command_id"] is None for a in got)
    # Logged with the payload cut, at most 50 a minute at warning level.
    refused = [r for r in d.records if r.get("event", "").startswith("MQTT command refused")]
    assert 0 < len(refused) <= 50 * (1 + len(d.cycles_logged) // 240)
    assert all(len(r["payload"]) <= 200 + len("… (8388608 bytes)") for r in refused)


def answers_for(messages: list[Message]) -> int:
    """Payloads answered: one per answer, or the count a 'dropped' answer names."""
    n = 0
    for m in messages:
        reason = m.json()["reason"]
        n += int(reason.split()[0]) if "dropped unread" in reason else 1
    return n


def test_home_assistant_select_number_and_button_payloads_command_the_panel(
        broker: LocalBroker, tmp_path: Path) -> None:
    panel = mqtt_panel(tmp_path / "panel.yaml", broker)
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"
    sub = Subscriber(broker, "homeassistant/#", f"{BASE}/state", f"{BASE}/error",
                     out=tmp_path / "sub.txt").start()
    sent: list[tuple[str, str, str]] = []

    async def scenario() -> DaemonProcess:
        d = await DaemonProcess(run_args(panel, state, start=START, cycles=2000,
                                         speed=SPEED)).start()
        got = await wait_messages(sub, lambda m: bool(states(m)) and len(configs(m)) > 20)
        cfgs = configs(got)
        regime, objective = cfgs["select/dsfd_suwon-south_regime"], \
            cfgs["select/dsfd_suwon-south_objective"]
        louver, damper = cfgs["number/dsfd_suwon-south_louver"], \
            cfgs["number/dsfd_suwon-south_damper"]
        button = cfgs["button/dsfd_suwon-south_resume"]
        # What Home Assistant sends: the option's text, the number (an integer when whole),
        # payload_press; with the entity's qos, not retained.
        for entity, payload in ((regime, next(o for o in regime["options"]
                                              if o.startswith("3:"))),
                                (louver, str(int(louver["min"] + 2 * louver["step"]))),
                                (damper, str(int(damper["max"] - 6 * damper["step"]))),
                                (objective, "cooling"),
                                (button, button["payload_press"])):
            publish(broker, entity["command_topic"], payload, qos=entity["qos"],
                    retain=entity["retain"])
            await answered(db, len(sent) + 1)
            sent.append((entity["unique_id"], entity["command_topic"], payload))
        last = commands(db)[-1]["cycle"]
        await d.wait_cycle(last + 1)
        await wait_messages(sub, lambda m: last in states(m))
        d.signal(signal.SIGTERM)
        assert await d.wait_exit() == 0, d.stderr
        return d

    try:
        asyncio.run(scenario())
    finally:
        sub.stop()
    got = sub.messages()
    cfgs, by_cycle = configs(got), states(got)
    rows = commands(db)
    assert [(r["kind"], r["source"], r["status"]) for r in rows] == [
        (kind, "mqtt", "applied") for kind in ("override", "override", "override", "mode",
                                               "resume")]
    dec = decisions(db)
    regime_at, louver_at, damper_at, mode_at, resume_at = (r["cycle"] for r in rows)
    louver_cfg = cfgs["number/dsfd_suwon-south_louver"]
    damper_cfg = cfgs["number/dsfd_suwon-south_damper"]
    assert (dec[regime_at]["afr"], dec[regime_at]["hold_source"]) == (3, "operator")
    assert dec[louver_at]["phi_deg"] == louver_cfg["min"] + 2 * louver_cfg["step"]
    assert dec[damper_at]["or_pct"] == damper_cfg["max"] - 6 * damper_cfg["step"]
    # The objective: cooling although the January morning would make auto heat.
    assert dec[mode_at - 1]["objective_mode"] == "auto" and dec[mode_at - 1]["heating"] == 1
    assert (dec[mode_at]["objective_mode"], dec[mode_at]["heating"]) == ("cooling", 0)
    assert dec[resume_at]["hold_source"] is None
    assert dec[resume_at]["objective_mode"] == "cooling"  # resume ends holds, not the mode
    # Each entity's value_template renders what was commanded (Home Assistant's view).
    for (uid, _, payload), cycle in zip(sent, (regime_at, louver_at, damper_at, mode_at),
                                        strict=False):
        component = next(k for k in cfgs if k.endswith("/" + uid))
        shown = render(cfgs[component]["value_template"], by_cycle[cycle])
        assert shown == payload if component.startswith("select") else \
            float(shown) == float(payload), (uid, shown, payload)
    hold = cfgs["sensor/dsfd_suwon-south_hold"]
    assert render(hold["value_template"], by_cycle[damper_at]) == "operator"
    assert render(hold["value_template"], by_cycle[resume_at]) == "None"  # unknown
    assert not [m for m in got if m.topic == f"{BASE}/error"]


def configs(messages: list[Message]) -> dict[str, dict[str, Any]]:
    """Discovery configs by ``component/object_id``."""
    return {"/".join(m.topic.split("/")[1:3]): m.json() for m in messages
            if m.topic.startswith("homeassistant/")}
