"""The occupancy override over MQTT, end to end (issue 36): ``mosquitto_pub`` → a real
Mosquitto → the real ``dsfd run --dry-run`` (simulated plant) → the next cycle's stored
occupancy, its decision trace, its state message and ``dsfd status``.

The simulated morning is Sunday 2022-01-02 08:30 in Suwon (UTC+9) and the panel's schedule
says Sundays 08:00-18:00, so before any command the room is occupied by the schedule:

1. ``unoccupied until 10:00`` makes the room unoccupied from the cycle that applies it
   (source ``override``, until 10:00 local = 01:00 UTC), the next decisions are taken
   without the comfort limits, and ``dsfd status`` shows it;
2. malformed occupancy commands (a wrong state, an impossible time, a time missing, JSON of
   the wrong shape) are answered on ``<base>/error``, filed nowhere, and change nothing;
3. ``auto`` ends the override: the schedule decides again;
4. an override a few simulated minutes long ends by itself at its time, with an event.

Cycles are paced (``--speed``): 60 simulated seconds every 0.25 s. Time limits are hang
guards.
"""

from __future__ import annotations

import asyncio
import datetime as dt
import json
import signal
from pathlib import Path
from typing import Any

from dsfd.integrations.mqtt.broker import LocalBroker
from tests.daemon.harness import DaemonProcess, query, run_dsfd
from tests.integrations.mqtt_harness import Subscriber, mqtt_panel, run_args
from tests.integrations.test_mqtt_commands import (
    BASE,
    SPEED,
    START,
    answered,
    commands,
    publish,
    states,
    wait_messages,
    within_one_cycle,
)

SEOUL = dt.timezone(dt.timedelta(hours=9))
#: 10:00 local on the simulated Sunday, as UTC seconds (from the calendar, not the code).
TEN_LOCAL_S = dt.datetime(2022, 1, 2, 10, 0, tzinfo=SEOUL).timestamp()
#: (subtopic, payload, what the answer must name): none of them is a command.
MALFORMED = [
    ("occupied", b"unoccupied until 10:00", "unknown command"),
    ("occupancy", b"busy until 10:00", "state: 'busy'"),
    ("occupancy", b"unoccupied until 25:00", "until: '25:00'"),
    ("occupancy", b"occupied", "needs an end time"),
    ("occupancy", b"unoccupied 10:00", "expected 'until TIME'"),
    ("occupancy", b'{"state": "unoccupied", "until": "soon"}', "until: 'soon'"),
    ("occupancy", b'{"state": "auto", "until": "10:00"}', "give no time"),
    ("occupancy", b'{"state": ["unoccupied"], "until": "10:00"}', "state: ['unoccupied']"),
    ("occupancy", b'{"state": "occupied", "until": "10:00"', "not JSON"),
]


def comfort(db: Path) -> dict[int, tuple[int, str]]:
    return {c: (o, s) for c, o, s in query(db, "SELECT cycle, occupied, occupancy_source "
                                               "FROM comfort ORDER BY cycle")}


def overrides(db: Path) -> dict[int, tuple[Any, ...]]:
    rows = query(db, "SELECT cycle, occupancy_override, occupancy_until_s, "
                     "occupancy_command_id, trace FROM decisions ORDER BY cycle")
    return {r[0]: (*r[1:4], json.loads(r[4])) for r in rows}


def occupancy_trace(trace: list[dict[str, Any]]) -> dict[str, Any]:
    (stage,) = [t for t in trace if t["stage"] == "occupancy"]
    return stage


def local_hhmm(time_s: float) -> str:
    return dt.datetime.fromtimestamp(time_s, SEOUL).strftime("%H:%M")


def test_an_occupancy_command_over_mqtt_changes_the_next_cycles_occupancy(
        broker: LocalBroker, tmp_path: Path) -> None:
    panel = mqtt_panel(tmp_path / "panel.yaml", broker,
                       extra={"occupancy": {"sun": ["08:00-18:00"]}})
    state = tmp_path / "state"
    db = state / "timeseries.sqlite"
    sub = Subscriber(broker, f"{BASE}/state", f"{BASE}/error", out=tmp_path / "sub.txt").start()
    seen: dict[str, Any] = {}

    async def scenario() -> DaemonProcess:
        d = await DaemonProcess(run_args(panel, state, start=START, cycles=4000,
                                         speed=SPEED)).start()
        await d.wait_cycle(3)
        await wait_messages(sub, lambda m: bool(states(m)))  # connected and subscribed
        publish(broker, f"{BASE}/cmd/occupancy", "unoccupied until 10:00")
        (first,) = await answered(db, 1)
        await d.wait_cycle(first["cycle"] + 1)
        seen["status"] = await run_dsfd("status", "--state-dir", str(state))
        seen["status_json"] = await run_dsfd("status", "--state-dir", str(state), "--json")
        seen["before_bad"] = d.cycles_logged[-1]
        for sub_topic, payload, _ in MALFORMED:
            await asyncio.to_thread(publish, broker, f"{BASE}/cmd/{sub_topic}",
                                    payload.decode())
        await wait_messages(sub, lambda m: sum(x.topic == f"{BASE}/error" for x in m)
                            >= len(MALFORMED))
        seen["after_bad"] = d.cycles_logged[-1]
        await d.wait_cycle(seen["after_bad"] + 1)
        publish(broker, f"{BASE}/cmd/occupancy", "auto")
        auto = (await answered(db, 2))[1]
        await d.wait_cycle(auto["cycle"] + 1)
        # an override that ends by itself three simulated minutes on
        last_s = query(db, "SELECT MAX(time_s) FROM decisions")[0][0]
        until = local_hhmm(last_s + 180.0 + 60.0)  # the next whole minute after +3 min
        publish(broker, f"{BASE}/cmd/occupancy", json.dumps(
            {"state": "unoccupied", "until": until}))
        short = (await answered(db, 3))[2]
        await d.wait_for(lambda d: any(r.get("event", "").startswith(
            "occupancy override ended") for r in d.records))
        await d.wait_cycle(d.cycles_logged[-1] + 1)
        await wait_messages(sub, lambda m: d.cycles_logged[-2] in states(m))
        d.signal(signal.SIGTERM)
        assert await d.wait_exit() == 0, d.stderr
        seen["short"] = short
        return d

    try:
        d = asyncio.run(scenario())
    finally:
        sub.stop()
    cmds = commands(db)
    first, auto, short = cmds
    # Filed as the CLI files them, source mqtt, applied within one cycle; nothing else filed.
    assert [(c["kind"], c["source"], c["status"]) for c in cmds] == [
        ("occupancy", "mqtt", "applied")] * 3
    assert json.loads(first["args"]) == {"state": "unoccupied", "until": "10:00"}
    assert json.loads(auto["args"]) == {"state": "auto"}
    assert all(within_one_cycle(d, c) for c in cmds), (cmds, d.cycles_logged)
    occ, dec = comfort(db), overrides(db)
    assert list(occ) == d.cycles_logged  # a comfort row for every cycle
    # Before: occupied by the schedule. From the command's cycle: unoccupied by the override.
    assert all(occ[c] == (1, "schedule") for c in range(1, first["cycle"]))
    for c in range(first["cycle"], auto["cycle"]):
        assert occ[c] == (0, "override"), c
        assert dec[c][:3] == ("unoccupied", TEN_LOCAL_S, first["command_id"])
        why = occupancy_trace(dec[c][3])
        assert why["set"] == {"occupied": False, "source": "override"}
        assert "2022-01-02T01:00:00Z" in why["why"]
    # The decision follows: the optimiser's problem carries the comfort limits over the
    # occupied horizon steps before the command, none while the override says unoccupied.
    def limits_in_decision(c: int) -> bool:
        decide = [t for t in dec[c][3] if t["stage"].startswith("decide:")]
        return bool(decide) and "steps occupied" in decide[0]["why"]

    optimised = [c for c in range(1, auto["cycle"])
                 if any(t["stage"] == "decide:mpc" for t in dec[c][3])]
    before = [c for c in optimised if c < first["cycle"]]
    during = [c for c in optimised if c >= first["cycle"]]
    assert before and during, (before, during)
    assert all(limits_in_decision(c) for c in before)
    assert not any(limits_in_decision(c) for c in during)
    # The malformed ones changed nothing (the cycles during them kept the override)...
    assert all(occ[c] == (0, "override") for c in range(seen["before_bad"],
                                                        seen["after_bad"] + 1))
    # ...and each was answered on <base>/error, naming what is wrong.
    answers = [m.json() for m in sub.messages() if m.topic == f"{BASE}/error"]
    assert len(answers) == len(MALFORMED)
    by_payload = {a["payload"]: a["reason"] for a in answers}
    for _, payload, expected in MALFORMED:
        reason = by_payload[payload.decode()]
        assert expected in reason, (payload, reason)
    assert all(a["command_id"] is None for a in answers)
    # auto: the schedule decides again, occupied
    assert occ[auto["cycle"]] == (1, "schedule") and dec[auto["cycle"]][:3] == (None,) * 3
    # the short override ends by itself at its time
    ended = [c for c in range(short["cycle"], d.cycles_logged[-1] + 1)
             if occ[c] == (1, "schedule")]
    assert ended, "the short override never ended"
    until_s = dec[short["cycle"]][1]
    assert all(occ[c] == (0, "override") for c in range(short["cycle"], ended[0]))
    times = dict(query(db, "SELECT cycle, time_s FROM decisions"))
    assert times[ended[0] - 1] < until_s <= times[ended[0]]
    (n_ended,), = query(db, "SELECT COUNT(*) FROM events WHERE kind = 'occupancy_ended'")
    assert n_ended == 2  # ended by auto, then at its time
    # The state messages carry it (Home Assistant's occupancy binary_sensor).
    got = states(sub.messages())
    s = got[first["cycle"]]["occupancy"]
    assert s == {"occupied": False, "source": "override", "override": "unoccupied",
                 "override_until_utc": "2022-01-02T01:00:00Z",
                 "override_command_id": first["command_id"]}
    assert got[auto["cycle"]]["occupancy"]["source"] == "schedule"
    # dsfd status while the override held
    rc, text, err = seen["status"]
    assert rc == 0, err
    assert "occupancy:   unoccupied (by the override); override unoccupied until " \
           "2022-01-02T01:00:00Z" in text
    assert f"by mqtt {broker.address} {BASE}/cmd/occupancy" in text
    occ_json = json.loads(seen["status_json"][1])["occupancy"]
    assert occ_json["override"]["state"] == "unoccupied"
    assert occ_json["override"]["command_id"] == first["command_id"]
