"""Nothing is lost while the broker is away, and the loop never waits for it.

The real ``dsfd run`` publishes to a real Mosquitto. The broker hangs (SIGSTOP: connections
stay open, nothing is answered — the case that would stall a publisher on the loop's path),
is then stopped, for more than ten cycles in all; the daemon is restarted while it is still
away, then the broker comes back: control
goes on throughout, and a persistent third-party subscriber (``mosquitto_sub -c``) receives
every stored cycle's state in order. QoS 1 allows a message to arrive twice (the PUBACK of a
message the broker had already taken was lost with the connection); such duplicates are
counted, never gaps. A second daemon without MQTT runs the same cycles at the same time: the
stored cycle times during the outage are compared with its.
"""

from __future__ import annotations

import asyncio
import signal
from pathlib import Path

from dsfd.integrations.mqtt.broker import LocalBroker
from tests.daemon.harness import DaemonProcess, query, write_panel
from tests.integrations.mqtt_harness import (
    Subscriber,
    mqtt_panel,
    run_args,
    state_keys,
)

START = "2022-01-01T23:30:00Z"
SPEED = 240.0  # 60 s cycles every 0.25 s
HUNG_CYCLES = 4
OUTAGE_CYCLES = 12


def test_broker_outage_and_restart_lose_no_state_and_delay_no_cycle(
        broker: LocalBroker, tmp_path: Path) -> None:
    panel = mqtt_panel(tmp_path / "panel.yaml", broker)
    plain = write_panel(tmp_path / "plain.yaml", devices=False)
    state, db = tmp_path / "state", tmp_path / "state" / "timeseries.sqlite"
    sub = Subscriber(broker, "dsfd/+/state", out=tmp_path / "sub.txt",
                     persistent_id="bms-1").start()

    def received_through(last: tuple[int, int]) -> bool:
        return last in state_keys(sub.messages())

    async def scenario() -> tuple[DaemonProcess, DaemonProcess, list[int]]:
        args = run_args(panel, state, start=START, cycles=500, speed=SPEED)
        baseline = await DaemonProcess(run_args(plain, tmp_path / "plain-state", start=START,
                                                cycles=500, speed=SPEED)).start()
        first = await DaemonProcess(args).start()
        await first.wait_cycle(4)
        await asyncio.to_thread(sub.wait_for, lambda m: (1, 4) in state_keys(m))
        broker.pause()
        down_from = first.cycles_logged[-1]
        await first.wait_cycle(down_from + HUNG_CYCLES)
        broker.stop()  # SIGTERM: the broker saves the subscriber's session
        await first.wait_cycle(down_from + OUTAGE_CYCLES)
        first.signal(signal.SIGTERM)
        assert await first.wait_exit() == 0, first.stderr
        second = await DaemonProcess(args).start()  # restarted while the broker is away
        await second.wait_cycle(4)
        broker.start()
        # the restarted daemon reconnects and drains its backlog; on a loaded machine its
        # reconnect back-off can outlast a few cycles, and a daemon stopped before it
        # reconnects leaves its backlog for its next start, which this test has none of
        await second.wait_for(lambda d: bool(d.events("MQTT connected")))
        back = second.cycles_logged[-1]
        await asyncio.to_thread(sub.wait_for, lambda m: (2, back) in state_keys(m))
        await second.wait_cycle(back + 4)
        second.signal(signal.SIGTERM)
        baseline.signal(signal.SIGTERM)
        assert await second.wait_exit() == 0, second.stderr
        assert await baseline.wait_exit() == 0, baseline.stderr
        outage = [c for c in first.cycles_logged if c > down_from]
        return first, second, outage

    first, second, outage = asyncio.run(scenario())
    stored = [(r, c) for r, c in query(db, "SELECT run_id, cycle FROM decisions "
                                           "ORDER BY run_id, cycle")]
    sub.wait_for(lambda m: received_through(stored[-1]))
    sub.stop()

    # Control went on while the broker was away: every cycle ran and was stored.
    assert len(outage) >= OUTAGE_CYCLES
    assert stored == [(1, c) for c in first.cycles_logged] + [(2, c) for c in
                                                              second.cycles_logged]
    # Every stored cycle arrived, first arrivals in stored order; duplicates only.
    live = state_keys(sub.messages())
    firsts = list(dict.fromkeys(live))
    assert firsts == stored
    duplicates = len(live) - len(firsts)
    print(f"{len(stored)} cycles, {len(live)} live state messages, {duplicates} QoS-1 "
          "duplicate(s)")
    # The broker's state was logged once per change, not per reconnect attempt.
    warnings = [r for r in first.records + second.records
                if r.get("logger") == "dsfd.mqtt" and r.get("level") in ("warning", "error")]
    assert any("lost" in r["event"] for r in first.records if r.get("logger") == "dsfd.mqtt")
    assert len(warnings) < 10, [w["event"] for w in warnings]
    (run, cycle, backlog, connected, error), = query(
        db, "SELECT run_id, cycle, backlog, connected, last_error FROM mqtt_cursor")
    assert (run, cycle) == stored[-1] and backlog == 0 and connected == 0
    assert "cannot connect" in error or "lost" in error

    # No cycle took longer than without MQTT: stored cycle times of the outage against
    # those of the daemon without MQTT over the same cycles (both ran at once, same load).
    with_mqtt = dict(query(db, "SELECT cycle, cycle_ms FROM decisions WHERE run_id = 1"))
    without = dict(query(tmp_path / "plain-state" / "timeseries.sqlite",
                         "SELECT cycle, cycle_ms FROM decisions"))
    during = [with_mqtt[c] for c in outage]
    same = [without[c] for c in outage if c in without]
    print("cycle_ms during the outage", sorted(during), "without MQTT", sorted(same))
    # A publisher on the loop's path would wait for the hung broker (seconds: connect and
    # publish time-outs); the margin only absorbs scheduling noise of a shared machine.
    assert max(during) <= 2.0 * max(same) + 20.0
