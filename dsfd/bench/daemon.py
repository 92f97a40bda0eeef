"""``dsfd bench daemon``: memory, CPU and cycle time of the daemon over a long accelerated run.

The daemon runs in this process — quality checks, observer, calibration, optimiser, safety
pipeline, SQLite store — against the simulated truth plant on replayed real weather
(repeated when the run is longer than the record), with the simulated clock running as
fast as possible, so 10,000 cycles (6.9 days) take minutes instead of a week. The plant
runs in a child process of its own (:mod:`dsfd.sim.remote_plant`), as the façade is not
inside a deployed daemon either: this process's memory and CPU time are the daemon's.

Figures (flat, units in the names):

* ``rss_mb_start``, ``rss_mb_end``, ``rss_mb_max`` — resident set size of the daemon at the
  first and the last sample and the largest sampled during the run (every 50 cycles);
* ``rss_growth_mb`` — growth over the second half of the run: mean RSS over its last 10 %
  of the cycles minus the mean over the 10 % before the half-way point. A daemon that leaks
  shows it here; a flat one reads ≈ 0;
* ``anon_mb_end``, ``file_mb_end`` — the resident memory at the end split into anonymous
  pages (each daemon's own) and file-backed pages (code and read-only data of the
  interpreter and the libraries, shared by all daemons of a machine);
* ``import_rss_mb.<group>`` — resident memory each group of modules adds when imported in a
  fresh interpreter in the order a daemon loads them (``python`` is the bare interpreter,
  ``total`` all of them together), and then what the daemon does not load, each on top:
  ``import_rss_mb.scipy_optimize`` (SciPy's optimiser, with scipy.linalg: only the
  ``paper-sqp`` optimiser option) and ``import_rss_mb.plant`` (the simulated plant);
* ``cpu_s_per_cycle`` — the daemon process's CPU time (user + system) per cycle, and
  ``plant_cpu_s_per_cycle`` that of the plant process (a deployment does not pay it);
* ``plant_rss_mb_max`` — resident memory of the plant process;
* ``cycle_ms_median``, ``cycle_ms_p99`` — wall time of one cycle (all stages, including the
  wait for the plant's integration);
* ``decide_ms_median``, ``calibrate_ms_p99``, ``read_ms_median`` — the main stages;
* ``panels_per_4gb_2core`` — how many panel daemons a 2-core, 4 GB controller runs, the
  smaller of the memory bound ⌊(4096 − 512) / rss_mb_max⌋ (512 MB left to the OS; every
  daemon counted with all its resident pages, shared library pages too, so a lower bound)
  and the CPU bound ⌊0.5 × 2 × 60 / cpu_s_per_cycle⌋ (half of two cores, one cycle a
  minute); ``panels_per_4gb_memory`` and ``panels_per_2core_cpu`` are the two bounds;
* ``cycles``, ``calibration_updates``, ``fallback_cycles``, ``wall_s``.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from dsfd.daemon.logging_setup import configure_logging
from dsfd.daemon.loop import CycleOutcome
from dsfd.daemon.runner import RunOptions, load_for_run, serve

__all__ = ["DEFAULT_CYCLES", "IMPORT_GROUPS", "NOT_LOADED_GROUPS", "bench_daemon",
           "import_rss_mb", "resident_split_mb", "rss_mb"]

DEFAULT_CYCLES = 10_000
#: The controller of ``panels_per_4gb_2core``: memory left to the daemons [MB] and the share
#: of its two cores they may use.
CONTROLLER_MB, OS_RESERVE_MB, CONTROLLER_CORES, CPU_SHARE = 4096.0, 512.0, 2, 0.5
#: RSS is sampled every this many cycles.
RSS_EVERY = 50
_PAGE_MB = os.sysconf("SC_PAGE_SIZE") / 2**20
#: Module groups in the order a daemon loads them (each adds to the ones before it).
IMPORT_GROUPS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("numpy", ("numpy",)),
    ("asyncio", ("asyncio",)),
    ("stdlib_and_small", ("sqlite3", "yaml", "structlog", "logging.handlers")),
    ("pymodbus", ("pymodbus", "pymodbus.client", "serial")),
    ("dsfd_core", ("dsfd.physics.model", "dsfd.control.optimiser", "dsfd.estimation")),
    ("dsfd_daemon", ("dsfd.daemon.runner", "dsfd.drivers.factory", "dsfd.drivers.modbus")),
    ("dsfd_cli", ("dsfd.cli",)),
)

#: What a daemon does NOT load, measured on top of the daemon's modules: SciPy's optimiser
#: (only with ``control.optimiser: paper-sqp``; it brings scipy.linalg and SciPy's own
#: OpenBLAS) and the simulated plant (SciPy's integrator; dry runs only).
NOT_LOADED_GROUPS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("scipy_optimize", ("scipy.optimize",)),
    ("plant", ("dsfd.sim.plant.plant",)),
)


def rss_mb() -> float:
    """Resident set size of this process now [MB] (Linux ``/proc/self/statm``)."""
    with open("/proc/self/statm", encoding="ascii") as fh:
        return int(fh.read().split()[1]) * _PAGE_MB


def resident_split_mb() -> tuple[float, float]:
    """(anonymous, file-backed) resident memory of this process [MB] (Linux smaps_rollup).

    Anonymous pages (heap, Python objects, arrays) are each daemon's own; file-backed ones
    (the interpreter's and the libraries' code and read-only data) are shared by every
    daemon on the machine that maps the same files.
    """
    fields: dict[str, float] = {}
    with open("/proc/self/smaps_rollup", encoding="ascii") as fh:
        for line in fh:
            name, _, value = line.partition(":")
            if value.strip().endswith("kB"):
                fields[name] = float(value.split()[0]) / 1024.0
    anon = fields.get("Anonymous", float("nan"))
    return anon, fields.get("Rss", float("nan")) - anon


_IMPORT_SCRIPT = """
import importlib, json, os, sys
def rss():
    with open('/proc/self/statm') as fh:
        return int(fh.read().split()[1]) * os.sysconf('SC_PAGE_SIZE') / 2**20
groups, extras = json.loads(sys.argv[1]), json.loads(sys.argv[2])
out = {'python': rss()}
last = out['python']
for name, mods in groups:
    for m in mods:
        importlib.import_module(m)
    if name == 'dsfd_cli':
        from dsfd.cli import build_parser
        build_parser()
    now = rss()
    out[name], last = now - last, now
out['total'] = last
for name, mods in extras:
    for m in mods:
        importlib.import_module(m)
    now = rss()
    out[name], last = now - last, now
print(json.dumps(out))
"""


def import_rss_mb() -> dict[str, float]:
    """What each module group of :data:`IMPORT_GROUPS` adds to a fresh interpreter [MB]."""
    proc = subprocess.run([sys.executable, "-c", _IMPORT_SCRIPT,
                           json.dumps([[n, list(m)] for n, m in IMPORT_GROUPS]),
                           json.dumps([[n, list(m)] for n, m in NOT_LOADED_GROUPS])],
                          capture_output=True, text=True, timeout=120, check=True)
    return {k: float(v) for k, v in json.loads(proc.stdout).items()}


def bench_daemon(config: Path, *, cycles: int = DEFAULT_CYCLES, seed: int = 0,
                 weather: str | None = None, fidelity: str = "full",
                 progress: bool = False) -> dict[str, float]:
    """Run ``cycles`` dry-run cycles against the simulated plant and measure them."""
    from dsfd.sim.remote_plant import PlantProcess  # (the plant itself: in the child)

    imports = import_rss_mb()
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
    plant = PlantProcess(cfg=cfg, cycles=cycles, seed=seed, fidelity=fidelity,
                         **({} if weather is None else {"weather": weather}))
    start = time.perf_counter()
    cpu0 = os.times()
    with tempfile.TemporaryDirectory(prefix="dsfd-bench-") as state:
        try:
            summary = asyncio.run(serve(opts, cfg, state_dir=Path(state), plant=plant,
                                        print_line=lambda _line: None))
        finally:
            sink.close()
            plant.close()
    cpu1 = os.times()
    anon_mb, file_mb = resident_split_mb()
    wall = time.perf_counter() - start
    n = summary.cycles
    cpu_s = (cpu1.user - cpu0.user) + (cpu1.system - cpu0.system)
    memory = _memory_figures(rss, n)
    return {
        "cycles": float(n),
        **memory,
        "anon_mb_end": anon_mb,
        "file_mb_end": file_mb,
        **{f"import_rss_mb.{k}": v for k, v in imports.items()},
        "cpu_s_per_cycle": cpu_s / n if n else float("nan"),
        **_panels_per_controller(memory["rss_mb_max"], n, cpu_s),
        "plant_cpu_s_per_cycle": plant.cpu_s / n if n else float("nan"),
        "plant_rss_mb_max": plant.rss_mb_max,
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


def _memory_figures(rss: list[tuple[int, float]], n: int) -> dict[str, float]:
    """``rss_mb_start/end/max`` and ``rss_growth_mb`` from the (cycle, RSS) samples."""
    at = np.array([c for c, _ in rss], float)
    mb = np.array([m for _, m in rss], float)
    if not mb.size:
        now = rss_mb()
        return {"rss_mb_start": now, "rss_mb_end": now, "rss_mb_max": now,
                "rss_growth_mb": float("nan")}
    tenth = max(n // 10, RSS_EVERY)
    before = mb[(at > n // 2 - tenth) & (at <= n // 2)]
    late = mb[at > n - tenth]
    return {"rss_mb_start": float(mb[0]), "rss_mb_end": float(mb[-1]),
            "rss_mb_max": float(mb.max()),
            "rss_growth_mb": float(late.mean() - before.mean()) if before.size and late.size
            else float("nan")}


def _panels_per_controller(rss_max: float, n: int, cpu_s: float) -> dict[str, float]:
    """The ``panels_per_*`` figures (module docstring) from the largest RSS [MB] and the
    CPU seconds of ``n`` cycles."""
    by_memory = float(np.floor((CONTROLLER_MB - OS_RESERVE_MB) / rss_max))
    by_cpu = (float(np.floor(CPU_SHARE * CONTROLLER_CORES * 60.0 / (cpu_s / n)))
              if n and cpu_s > 0 else float("nan"))
    return {"panels_per_4gb_memory": by_memory, "panels_per_2core_cpu": by_cpu,
            "panels_per_4gb_2core": float(np.nanmin([by_memory, by_cpu]))}
