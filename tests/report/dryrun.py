"""A short dry run of the real daemon (``serve``: loop, quality checks, store, metrics) against
the simulated plant with sensor faults, in its own process, for the report, export and metrics
tests::

    python -m tests.report.dryrun PANEL STATE_DIR CYCLES START_ISO [--faults] [--seed N]

Faults (``--faults``), relative to the start: x3 drops out (NaN) from minute 20 to 23 and x1
spikes by 40 K with probability 0.3 from minute 30 to 40, so the log holds readings flagged
``not_finite`` and ``out_of_range`` (rate of change) — what the export must blank.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
from pathlib import Path

from dsfd.daemon.logging_setup import configure_logging
from dsfd.daemon.runner import RunOptions, load_for_run, serve
from dsfd.drivers.simulated import SimulatedDriver
from dsfd.measured import parse_iso_utc
from dsfd.sim.daemon_plant import SimulatedPlant, plant_options, weather_window
from dsfd.sim.plant.plant import Plant
from dsfd.sim.plant.sensors import SensorConfig, SensorFault

MINUTE = 60.0


def faults(start_s: float) -> tuple[SensorFault, ...]:
    return (SensorFault(sensor="x3_c", kind="dropout", start_s=start_s + 20 * MINUTE - 1,
                        end_s=start_s + 23 * MINUTE - 1),
            SensorFault(sensor="x1_c", kind="spikes", start_s=start_s + 30 * MINUTE - 1,
                        end_s=start_s + 40 * MINUTE - 1, magnitude=40.0, probability=0.3))


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("panel", type=Path)
    p.add_argument("state_dir", type=Path)
    p.add_argument("cycles", type=int)
    p.add_argument("start")
    p.add_argument("--faults", action="store_true")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()
    cfg = load_for_run(args.panel, simulated_plant=True, dry_run=True)
    opts = RunOptions(config_path=args.panel, dry_run=True, plant="sim",
                      plant_fidelity="lumped", cycles=args.cycles, seed=args.seed,
                      start_s=parse_iso_utc(args.start))
    series, start = weather_window(cfg, start_s=opts.start_s)
    sensors = SensorConfig(faults=faults(start) if args.faults else ())
    plant = Plant(cfg, plant_options("lumped"), seed=args.seed, weather_series=series,
                  sensors=sensors)
    plant.reset(start)
    sim = SimulatedPlant(SimulatedDriver(plant), plant, start, series, ())
    with open(os.devnull, "w") as sink:
        configure_logging(stream=sink, json=True, level=logging.WARNING)
        asyncio.run(serve(opts, cfg, state_dir=args.state_dir, plant=sim,
                          print_line=lambda _line: None))


if __name__ == "__main__":
    main()
