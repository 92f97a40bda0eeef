"""``dsfd bench bacnet``: COV latency and read rate of the panel's BACnet/IP device.

Runs the whole daemon in this process with its BACnet device on 127.0.0.1 (a free UDP port)
— simulated plant (lumped fidelity), observer, optimiser, safety pipeline, SQLite store — on
a simulated clock, and bacpypes3's client side in a process of its own
(:mod:`dsfd.bench.bacnet_client`) on another port.

1. **COV latency.** The client subscribes (SubscribeCOV, unconfirmed) to the "stored cycle"
   analog input, whose COV increment is one cycle. ``cycles`` cycles at ``speed`` × real time
   (default 200: a 60 s cycle every 0.3 s, which leaves the interpreter idle most of the
   time, as on a real panel; at 600 the loop's ~0.1 s of computing per cycle would take all
   of it, and the device, a thread of the same process, would wait for it). Latency of a
   cycle = time from its commit to the database (when the loop tells the device) to the
   arrival of its notification at the client, both on the host's monotonic clock: the
   device's wake-up, reading the cycle back, setting the points, COV detection, encoding,
   UDP, the client's decoding.
2. **Reads.** Then, with the daemon still cycling, ``reads`` ReadPropertyMultiple requests of
   the present value and status flags of every point, one after the other, as a BMS poller
   sends them: requests per second and property values per second.

Figures: ``cycles``, ``cov_latency_ms_p50``, ``cov_latency_ms_p99``, ``cov_latency_ms_max``,
``cov_missed`` (stored cycles without a notification), ``cycle_ms_median`` (the loop's stored
cycle time meanwhile), ``reads``, ``rpm_per_s``, ``property_values_per_s``. Wall-clock
figures from a shared machine: compare runs made on one machine at one time.
"""

from __future__ import annotations

import asyncio
import dataclasses
import json
import logging
import os
import queue
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from dsfd import __version__
from dsfd.bench.timed import TimedIntegration
from dsfd.config.bacnet import Bacnet
from dsfd.daemon.logging_setup import configure_logging
from dsfd.daemon.loop import CycleOutcome
from dsfd.daemon.runner import RunOptions, load_for_run, serve
from dsfd.integrations.bacnet import device_for_run
from dsfd.integrations.bacnet.points import points_for
from dsfd.sim.daemon_plant import plant_for_run

__all__ = ["DEFAULT_CYCLES", "DEFAULT_READS", "DEFAULT_SPEED", "bench_bacnet"]

DEFAULT_CYCLES = 100
DEFAULT_READS = 500
DEFAULT_SPEED = 200.0
START_ISO = "2022-01-01T23:30:00Z"
_LIMIT_S = 600.0
_TYPES = {"ai": "analog-input", "av": "analog-value", "msv": "multi-state-value",
          "bv": "binary-value", "csv": "characterstring-value"}


def _free_port() -> int:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class _Client:
    """The client process: requests in, answers and notifications out (a reader thread)."""

    def __init__(self, device_port: int) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "dsfd.bench.bacnet_client", "--bind",
             f"127.0.0.1:{_free_port()}", "--device", f"127.0.0.1:{device_port}"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        self.answers: queue.Queue[dict[str, Any]] = queue.Queue()
        self.arrived: dict[int, float] = {}
        self.changed = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()
        self.answers.get(timeout=60.0)  # {"ready": true}

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            msg = json.loads(line)
            if "cov" in msg:
                if msg["property"] == "present-value":
                    self.arrived.setdefault(int(msg["value"]), msg["received_mono_s"])
                    self.changed.set()
            else:
                self.answers.put(msg)

    def send(self, request: dict[str, Any]) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()

    def ask(self, request: dict[str, Any], *, limit_s: float = _LIMIT_S) -> dict[str, Any]:
        self.send(request)
        return self.answers.get(timeout=limit_s)

    def wait_for(self, cycle: int, *, limit_s: float = _LIMIT_S) -> None:
        deadline = time.monotonic() + limit_s
        while cycle not in self.arrived:
            if time.monotonic() > deadline:
                raise TimeoutError(f"no COV notification of cycle {cycle} in {limit_s} s")
            self.changed.wait(0.2)
            self.changed.clear()

    def close(self) -> None:
        if self.proc.poll() is None:
            self.send({"op": "quit"})
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def bench_bacnet(config: Path, *, cycles: int = DEFAULT_CYCLES, reads: int = DEFAULT_READS,
                 speed: float = DEFAULT_SPEED, seed: int = 0) -> dict[str, float]:
    """Measure COV latency and ReadPropertyMultiple rate (see the module docstring)."""
    base = load_for_run(config, simulated_plant=True, dry_run=True)
    port = _free_port()
    cfg = dataclasses.replace(base, bacnet=Bacnet(device_instance=4190000,
                                                  address="127.0.0.1", port=port))
    sink = open(os.devnull, "w")  # noqa: SIM115 - open for the whole run, closed below
    configure_logging(stream=sink, json=True, level=logging.WARNING)
    client = _Client(port)
    try:
        with tempfile.TemporaryDirectory(prefix="dsfd-bench-bacnet-") as tmp:
            return _measure(cfg, config, Path(tmp), client, cycles=cycles, reads=reads,
                            speed=speed, seed=seed)
    finally:
        client.close()
        sink.close()


def _measure(cfg: Any, config: Path, work: Path, client: _Client, *, cycles: int, reads: int,
             speed: float, seed: int) -> dict[str, float]:
    timed = TimedIntegration(device_for_run(cfg, version=__version__), clock=time.monotonic)
    cycle_ms: list[float] = []
    first = 3  # the device is up and subscribed before this cycle
    result: dict[str, Any] = {}
    objects = [[f"{_TYPES[p.kind]},{p.instance}", ["present-value", "status-flags"]]
               for p in points_for(cfg)]

    def on_cycle(out: CycleOutcome) -> None:
        cycle_ms.append(out.cycle_ms)
        if out.cycle == first - 1:
            client.send({"op": "cov", "object": "analog-input,15", "process": 1})
            threading.Thread(target=reads_then_stop, daemon=True).start()

    def reads_then_stop() -> None:
        try:
            client.answers.get(timeout=_LIMIT_S)  # subscribed
            client.wait_for(first + cycles - 1)
            result["reads"] = client.ask({"op": "rpm-bench", "count": reads,
                                          "objects": objects})
        except Exception as exc:  # reported after the daemon stopped
            result["error"] = exc
        finally:
            os.kill(os.getpid(), signal.SIGTERM)  # the daemon's clean stop

    from dsfd.measured import parse_iso_utc

    opts = RunOptions(config_path=config, dry_run=True, plant="sim", plant_fidelity="lumped",
                      cycles=first + cycles + 100_000, seed=seed, speed=speed,
                      start_s=parse_iso_utc(START_ISO), on_cycle=on_cycle)
    asyncio.run(serve(opts, cfg, state_dir=work / "state", plant=plant_for_run(cfg, opts),
                      integrations=[timed], print_line=lambda _line: None))
    if "error" in result:
        raise RuntimeError(f"bench client failed: {result['error']}")
    measured = range(first, first + cycles)
    latency = np.array([(client.arrived[c] - timed.stored[c]) * 1e3 for c in measured
                        if c in client.arrived])
    answer = result["reads"]
    rpm_per_s = answer["count"] / answer["elapsed_s"]
    return {
        "cycles": float(cycles),
        "cov_latency_ms_p50": float(np.percentile(latency, 50)),
        "cov_latency_ms_p99": float(np.percentile(latency, 99)),
        "cov_latency_ms_max": float(latency.max()),
        "cov_missed": float(cycles - latency.size),
        "cycle_ms_median": float(np.median(cycle_ms)),
        "reads": float(answer["count"]),
        "rpm_per_s": rpm_per_s,
        "property_values_per_s": rpm_per_s * 2 * len(objects),
    }
