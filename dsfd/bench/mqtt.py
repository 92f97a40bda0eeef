"""``dsfd bench mqtt``: publish latency and backlog drain rate against a real local Mosquitto.

Starts Debian's ``mosquitto`` on a free loopback port (password file, persistence;
:class:`~dsfd.integrations.mqtt.broker.LocalBroker`) and runs the whole daemon in this process
with its MQTT publisher — simulated plant (lumped fidelity), observer, optimiser, safety
pipeline, SQLite store — on a simulated clock, while a paho subscriber in this process takes
the state messages (QoS 1).

1. **Latency.** ``cycles`` cycles at ``speed`` × real time (default 600: a 60 s cycle every
   0.1 s, so the publisher is idle between cycles as on a real panel). Latency of a cycle =
   time from its commit to the database (when the loop tells the publisher) to the arrival of
   its state message at the subscriber: wake-up, reading the cycle back from the database,
   JSON, PUBLISH, the broker, delivery.
2. **Backlog drain.** ``backlog`` stored cycles the broker never saw (copies of the measured
   cycles under a new run, as after a long outage) and a publisher for a new destination:
   messages per second from its start (connect, discovery configs) until the subscriber has
   the last one, in order, with at most :data:`~dsfd.integrations.mqtt.publisher.WINDOW`
   unacknowledged.

Figures: ``latency_ms_p50``, ``latency_ms_p99``, ``latency_ms_max``, ``cycles``,
``cycle_ms_median`` (the loop's own stored cycle time meanwhile), ``state_bytes_mean``,
``drain_messages``, ``drain_s``, ``drain_msgs_per_s``. Wall-clock figures from a shared
machine: compare runs made on one machine at one time.
"""

from __future__ import annotations

import asyncio
import dataclasses
import logging
import os
import sqlite3
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from dsfd import __version__
from dsfd.bench.timed import TimedIntegration
from dsfd.config.mqtt import Mqtt
from dsfd.daemon.logging_setup import configure_logging
from dsfd.daemon.loop import CycleOutcome
from dsfd.daemon.runner import RunOptions, load_for_run, serve
from dsfd.integrations.mqtt import publisher_for_run
from dsfd.integrations.mqtt.broker import LocalBroker
from dsfd.integrations.mqtt.link import BrokerLink, new_client
from dsfd.sim.daemon_plant import plant_for_run

__all__ = ["DEFAULT_BACKLOG", "DEFAULT_CYCLES", "DEFAULT_SPEED", "bench_mqtt"]

DEFAULT_CYCLES = 200
DEFAULT_BACKLOG = 5000
DEFAULT_SPEED = 600.0
#: Start of the simulated clock: a winter morning in Suwon (the controller is busy).
START_ISO = "2022-01-01T23:30:00Z"
_LIMIT_S = 600.0


class _Receiver:
    """A paho subscriber that timestamps each state message by (run, cycle)."""

    def __init__(self, broker: LocalBroker, topic: str) -> None:
        import json

        self.arrived: dict[tuple[int, int], float] = {}
        self.order: list[tuple[int, int]] = []
        self.sizes: list[int] = []
        self._subscribed = threading.Event()
        self.changed = threading.Event()
        link = BrokerLink(host="127.0.0.1", port=broker.port, client_id="",
                          username=broker.username, password=broker.password)
        self.client = new_client(link, client_id="")

        def on_connect(c: Any, _u: Any, _f: Any, _rc: Any, _p: Any) -> None:
            c.subscribe(topic, qos=1)

        def on_subscribe(*_: Any) -> None:
            self._subscribed.set()

        def on_message(_c: Any, _u: Any, msg: Any) -> None:
            now = time.perf_counter()
            if msg.retain:
                return  # a replay of the last state, not a delivery
            state = json.loads(msg.payload)
            key = (int(state["run"]), int(state["cycle"]))
            self.arrived.setdefault(key, now)
            self.order.append(key)
            self.sizes.append(len(msg.payload))
            self.changed.set()

        self.client.on_connect, self.client.on_subscribe = on_connect, on_subscribe
        self.client.on_message = on_message
        self.client.connect("127.0.0.1", broker.port)
        self.client.loop_start()
        if not self._subscribed.wait(10.0):
            raise TimeoutError("the bench subscriber could not subscribe")

    def wait_for(self, key: tuple[int, int], *, limit_s: float = _LIMIT_S) -> None:
        deadline = time.monotonic() + limit_s
        while key not in self.arrived:
            if time.monotonic() > deadline:
                raise TimeoutError(f"state of {key} did not arrive within {limit_s} s")
            self.changed.wait(0.2)
            self.changed.clear()

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


def bench_mqtt(config: Path, *, cycles: int = DEFAULT_CYCLES, backlog: int = DEFAULT_BACKLOG,
               speed: float = DEFAULT_SPEED, seed: int = 0) -> dict[str, float]:
    """Measure publish latency and backlog drain rate (see the module docstring)."""
    base_cfg = load_for_run(config, simulated_plant=True, dry_run=True)
    sink = open(os.devnull, "w")  # noqa: SIM115 - open for the whole run, closed below
    configure_logging(stream=sink, json=True, level=logging.WARNING)
    try:
        with tempfile.TemporaryDirectory(prefix="dsfd-bench-mqtt-") as tmp:
            work = Path(tmp)
            broker = LocalBroker(work / "broker").start()
            try:
                return _measure(base_cfg, config, work, broker, cycles=cycles,
                                backlog=backlog, speed=speed, seed=seed)
            finally:
                broker.stop()
    finally:
        sink.close()


def _measure(base_cfg: Any, config: Path, work: Path, broker: LocalBroker, *, cycles: int,
             backlog: int, speed: float, seed: int) -> dict[str, float]:
    secret = work / "password"
    secret.write_text(broker.password + "\n")

    def with_mqtt(base_topic: str) -> Any:
        return dataclasses.replace(base_cfg, mqtt=Mqtt(
            host="127.0.0.1", port=broker.port, username=broker.username,
            password_file=str(secret), base_topic=base_topic, discovery_prefix=None,
            backlog_max_age_h=24 * 31))

    cfg = with_mqtt("bench/live")
    state_dir = work / "state"
    receiver = _Receiver(broker, "bench/live/state")
    timed = TimedIntegration(publisher_for_run(cfg, config_path=config, version=__version__))
    cycle_ms: list[float] = []

    def on_cycle(out: CycleOutcome) -> None:
        cycle_ms.append(out.cycle_ms)

    from dsfd.measured import parse_iso_utc

    opts = RunOptions(config_path=config, dry_run=True, plant="sim", plant_fidelity="lumped",
                      cycles=cycles, seed=seed, speed=speed, start_s=parse_iso_utc(START_ISO),
                      on_cycle=on_cycle)
    asyncio.run(serve(opts, cfg, state_dir=state_dir, plant=plant_for_run(cfg, opts),
                      integrations=[timed], print_line=lambda _line: None))
    receiver.wait_for((1, cycles))
    latency = np.array([(receiver.arrived[(1, c)] - t) * 1e3 for c, t in timed.stored.items()
                        if (1, c) in receiver.arrived])
    sizes = list(receiver.sizes)
    receiver.close()

    database = state_dir / "timeseries.sqlite"
    run = _copy_as_backlog(database, backlog)
    drain_cfg = with_mqtt("bench/drain")
    receiver = _Receiver(broker, "bench/drain/state")
    publisher = publisher_for_run(drain_cfg, config_path=config, version=__version__)
    start = time.perf_counter()
    publisher.start(database=database)
    try:
        receiver.wait_for((run, backlog))
        drained = receiver.arrived[(run, backlog)] - start
    finally:
        publisher.stop()
        receiver.close()
    sent = [k for k in dict.fromkeys(receiver.order) if k[0] == run]
    if sent != [(run, c) for c in range(1, backlog + 1)]:
        raise RuntimeError("the backlog did not arrive complete and in order")
    return {
        "cycles": float(cycles),
        "latency_ms_p50": float(np.percentile(latency, 50)),
        "latency_ms_p99": float(np.percentile(latency, 99)),
        "latency_ms_max": float(latency.max()),
        "cycle_ms_median": float(np.median(cycle_ms)),
        "state_bytes_mean": float(np.mean(sizes)),
        "drain_messages": float(len(receiver.order)),
        "drain_s": drained,
        "drain_msgs_per_s": len(receiver.order) / drained,
    }


def _copy_as_backlog(database: Path, count: int) -> int:
    """Store ``count`` cycles under a new run, copies of the measured ones; its run_id."""
    conn = sqlite3.connect(database)
    try:
        with conn:
            cur = conn.execute("INSERT INTO runs (panel, mode, started_utc, pid, version, "
                               "config_path) SELECT panel, 'bench backlog', started_utc, pid, "
                               "version, config_path FROM runs WHERE run_id = 1")
            run = int(cur.lastrowid or 0)
            cols = [r[1] for r in conn.execute("PRAGMA table_info(decisions)")
                    if r[1] not in ("run_id", "cycle", "time_s")]
            rows = conn.execute(f"SELECT cycle, time_s, {', '.join(cols)} FROM decisions "
                                "WHERE run_id = 1 ORDER BY cycle").fetchall()
            samples = conn.execute("SELECT cycle, signal, value, quality, detail FROM samples "
                                   "WHERE run_id = 1").fetchall()
            by_cycle: dict[int, list[tuple[Any, ...]]] = {}
            for c, *rest in samples:
                by_cycle.setdefault(c, []).append(tuple(rest))
            t0 = rows[-1][1]
            decisions, sample_rows = [], []
            for k in range(count):
                src = rows[k % len(rows)]
                cycle, t = k + 1, t0 + 10.0 * (k + 1)
                decisions.append((run, cycle, t, *src[2:]))
                sample_rows += [(run, cycle, t, *s) for s in by_cycle.get(src[0], [])]
            conn.executemany(f"INSERT INTO decisions (run_id, cycle, time_s, {', '.join(cols)}) "
                             f"VALUES ({', '.join('?' * (len(cols) + 3))})", decisions)
            conn.executemany("INSERT INTO samples (run_id, cycle, time_s, signal, value, "
                             "quality, detail) VALUES (?, ?, ?, ?, ?, ?, ?)", sample_rows)
    finally:
        conn.close()
    return run
