"""``dsfd bench daemon``: memory and cycle time of the daemon over a long accelerated dry run.

The whole daemon runs in this process — simulated plant on replayed real weather (repeated
when the run is longer than the record), quality checks, observer, calibration, optimiser,
safety pipeline, SQLite store — with the simulated clock running as fast as possible, so
10,000 cycles (6.9 days) take minutes instead of a week.

Figures (flat, units in the names):

* ``rss_mb_start``, ``rss_mb_end``, ``rss_mb_max`` — resident set size at the first and
  the last sample and the largest sampled during the run (every 50 cycles);
* ``rss_growth_mb`` — mean RSS over the last 10 % of the cycles minus the mean over the
  second 10 % (after warm-up: imports, caches, the first optimiser and calibration runs).
  A daemon that leaks shows it here; a flat one reads ≈ 0;
* ``cycle_ms_median``, ``cycle_ms_p99`` — wall time of one cycle (all stages, including the
  plant's integration, which a real deployment does not pay);
* ``decide_ms_median``, ``calibrate_ms_p99``, ``read_ms_median`` — the main stages;
* ``cycles``, ``calibration_updates``, ``fallback_cycles``, ``wall_s``.
"""

from __future__ import annotations

import asyncio
import logging
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from dsfd.daemon.logging_setup import configure_logging
from dsfd.daemon.loop import CycleOutcome
from dsfd.daemon.runner import RunOptions, load_for_run, serve
from dsfd.sim.daemon_plant import plant_for_run

__all__ = ["DEFAULT_CYCLES", "bench_daemon", "rss_mb"]

DEFAULT_CYCLES = 10_000
#: RSS is sampled every this many cycles.
RSS_EVERY = 50
_PAGE_MB = os.sysconf("SC_PAGE_SIZE") / 2**20


def rss_mb() -> float:
    """Resident set size of this process now [MB] (Linux ``/proc/self/statm``)."""
    with open("/proc/self/statm", encoding="ascii") as fh:
        return int(fh.read().split()[1]) * _PAGE_MB


def bench_daemon(config: Path, *, cycles: int = DEFAULT_CYCLES, seed: int = 0,
                 weather: str | None = None, fidelity: str = "full",
                 progress: bool = False) -> dict[str, float]:
    """Run ``cycles`` dry-run cycles against the simulated plant and measure them."""
    cfg = load_for_run(config, simulated_plant=True, dry_run=True)
    cycle_ms = np.full(cycles, np.nan)
    decide_ms = np.full(cycles, np.nan)
    read_ms = np.full(cycles, np.nan)
    calibrate_ms: list[float] = []
    rss: list[tuple[int, float]] = []
    counts = {"calibration_updates": 0, "fallback_cycles": 0}

    def on_cycle(out: CycleOutcome) -> None:
        i = out.cycle - 1
        t = out.timings_ms
        cycle_ms[i], decide_ms[i], read_ms[i] = t["total"], t["decide"], t["read"]
        if out.calibration is not None:
            calibrate_ms.append(t["calibrate"])
            counts["calibration_updates"] += out.calibration.updated
        counts["fallback_cycles"] += bool(out.fallback)
        if out.cycle % RSS_EVERY == 0:
            rss.append((out.cycle, rss_mb()))
            if progress and out.cycle % (RSS_EVERY * 20) == 0:
                print(f"  cycle {out.cycle}/{cycles}: RSS {rss[-1][1]:.1f} MB, median cycle "
                      f"{np.nanmedian(cycle_ms[:out.cycle]):.1f} ms", flush=True)

    # The per-cycle log lines would be 10,000 lines of JSON: keep warnings only, discarded.
    sink = open(os.devnull, "w")  # noqa: SIM115 - open for the whole run, closed below
    configure_logging(stream=sink, json=True, level=logging.WARNING)
    opts = RunOptions(config_path=config, dry_run=True, plant="sim", plant_fidelity=fidelity,
                      cycles=cycles, seed=seed, weather=weather, on_cycle=on_cycle)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="dsfd-bench-") as state:
        try:
            summary = asyncio.run(serve(opts, cfg, state_dir=Path(state),
                                        plant=plant_for_run(cfg, opts),
                                        print_line=lambda _line: None))
        finally:
            sink.close()
    wall = time.perf_counter() - start
    n = summary.cycles
    at = np.array([c for c, _ in rss], float)
    mb = np.array([m for _, m in rss], float)
    tenth = max(n // 10, RSS_EVERY)
    early = mb[(at > tenth) & (at <= 2 * tenth)]
    late = mb[at > n - tenth]
    return {
        "cycles": float(n),
        "rss_mb_start": float(mb[0]) if mb.size else float("nan"),
        "rss_mb_end": float(mb[-1]) if mb.size else float("nan"),
        "rss_mb_max": float(mb.max()) if mb.size else rss_mb(),
        "rss_growth_mb": float(late.mean() - early.mean()) if early.size and late.size
        else float("nan"),
        "cycle_ms_median": float(np.nanmedian(cycle_ms[:n])),
        "cycle_ms_p99": float(np.nanpercentile(cycle_ms[:n], 99)),
        "decide_ms_median": float(np.nanmedian(decide_ms[:n])),
        "read_ms_median": float(np.nanmedian(read_ms[:n])),
        "calibrate_ms_p99": float(np.percentile(calibrate_ms, 99)) if calibrate_ms
        else float("nan"),
        "calibration_updates": float(counts["calibration_updates"]),
        "fallback_cycles": float(counts["fallback_cycles"]),
        "wall_s": wall,
    }
