"""``dsfd bench TARGET``: speed (and accuracy) figures of one part of dsfd.

Targets are looked up in :data:`TARGETS` (name → function taking the parsed arguments and
returning a flat dict of figures with units in the key names). To add a target, write such
a function and add it to the dict; the common options below are passed to every target.
A human table is printed (the figures one a line, or the target's own tables for those in
:data:`OWN_TABLES`); ``--json PATH`` writes the same figures.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from dsfd.config import ConfigError, load_panel
from dsfd.sim.choices import BENCH_CONTROLLERS, OCCUPANCY_CHOICES

DEFAULT_PANEL = Path("config/panels/suwon-south.yaml")


def _bench_plant(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.plant import DEFAULT_WEATHER, bench_plant

    cfg = load_panel(args.config)
    return bench_plant(cfg, days=3.0 if args.days is None else args.days, seed=args.seed,
                       weather=args.weather or DEFAULT_WEATHER)


def _bench_plant_velocity(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.velocity import bench_plant_velocity

    seeds = 10 if args.seeds is None else args.seeds
    return bench_plant_velocity(load_panel(args.config), seeds=seeds, days=args.days,
                                weather=args.weather)


def _bench_daemon(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.daemon import DEFAULT_CYCLES, bench_daemon

    cycles = DEFAULT_CYCLES if args.days is None else round(args.days * 1440)
    return bench_daemon(args.config, cycles=cycles, seed=args.seed, weather=args.weather,
                        progress=True)


def _bench_mqtt(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.mqtt import DEFAULT_BACKLOG, DEFAULT_CYCLES, bench_mqtt
    from dsfd.integrations.mqtt.link import require_paho

    require_paho()
    return bench_mqtt(args.config, cycles=args.cycles or DEFAULT_CYCLES,
                      backlog=args.backlog or DEFAULT_BACKLOG, seed=args.seed)


def _bench_bacnet(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.integrations.bacnet import require_bacpypes3

    require_bacpypes3()
    from dsfd.bench.bacnet import DEFAULT_CYCLES, DEFAULT_READS, bench_bacnet

    return bench_bacnet(args.config, cycles=args.cycles or DEFAULT_CYCLES,
                        reads=args.reads or DEFAULT_READS, seed=args.seed)


def _bench_calibration(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.calibration import bench_calibration

    return bench_calibration(load_panel(args.config), seed=args.seed)


def _bench_model(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.model import bench_model

    return bench_model(args.config)


def _bench_control(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.control import bench_control

    return bench_control(args.config, cases=args.cases, seed=args.seed)


def _bench_paper_tables(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.paper_tables import (
        VALIDATION_DAYS,
        WEATHER,
        paper_tables,
        paper_tables_seeds,
        report,
        seeds_report,
    )

    if args.seeds is not None:
        figures = paper_tables_seeds(
            load_panel(args.config), args.seeds, weather=args.weather or WEATHER,
            validation_days=VALIDATION_DAYS if args.days is None else args.days,
            progress=lambda msg: print(msg, file=sys.stderr, flush=True))
        print(seeds_report(figures))
        print()
        return figures
    result = paper_tables(load_panel(args.config), seed=args.seed,
                          weather=args.weather or WEATHER,
                          validation_days=VALIDATION_DAYS if args.days is None else args.days,
                          centre=args.prior_centre,
                          progress=lambda msg: print(msg, file=sys.stderr, flush=True))
    print(report(result))
    print()
    return result.figures


def _bench_closed_loop(args: argparse.Namespace) -> dict[str, float]:
    from dsfd.bench.closed_loop import (
        CASES,
        CONTROLLERS,
        bench_closed_loop,
        bench_closed_loop_seeds,
        report,
        share_table,
    )
    from dsfd.bench.oracle_cache import OracleCache
    from dsfd.sim.plant.faults import parse_fault
    from dsfd.sim.replay import load_weather

    controllers = CONTROLLERS if args.controllers is None else tuple(
        c.strip() for c in args.controllers.split(",") if c.strip())
    options = dict(
        days=1.0 if args.days is None else args.days,
        cases=tuple(args.case) if args.case else CASES, controllers=controllers,
        progress=lambda msg: print(msg, file=sys.stderr, flush=True),
        on_figures=None if args.json is None else lambda fig: _write_json(
            args.json, args.target, {**fig, "partial": 1.0}),
        oracle_cache=None if args.oracle_cache is None else OracleCache(args.oracle_cache),
        faults=tuple(parse_fault(f) for f in args.fault),
        occupancy=args.occupancy or "office-every-day")
    cfg = load_panel(args.config)
    series = load_weather(args.weather or "rmis-golden-2022-01")
    if args.seeds is None:
        figures = bench_closed_loop(cfg, series, seed=args.seed, **options)
        print(report(figures))
    else:
        seeds = (range(args.seed, args.seed + args.seeds) if isinstance(args.seeds, int)
                 else args.seeds)
        counted = (f" (--seeds {args.seeds} is a count from --seed {args.seed}; name seeds as a "
                   "list, e.g. 1,2,3, or one as --seed N)") if isinstance(args.seeds, int) else ""
        options["progress"](f"closed loop: seed(s) {', '.join(map(str, seeds))}{counted}")
        figures = bench_closed_loop_seeds(cfg, series, seeds=tuple(seeds), **options)
        print(share_table(figures))
    print()
    return figures


def _bench_identify(args: argparse.Namespace) -> dict[str, Any]:
    from dsfd.bench.identify import bench_identify
    from dsfd.bench.identify_run import RunSpec
    from dsfd.daemon.runner import load_for_run
    from dsfd.sim.daemon_plant import DEFAULT_WEATHER

    cfg = load_for_run(args.config, simulated_plant=True, dry_run=True)
    days = IDENTIFY_DAYS if args.days is None else args.days
    cycles = round(days * 86400.0 / cfg.daemon.cycle_period_s)
    if cycles < 1:
        raise ValueError(f"--days {args.days}: less than one cycle "
                         f"({cfg.daemon.cycle_period_s:g} s)")
    spec = RunSpec(config_path=args.config, cfg=cfg, plant=args.plant or "lumped",
                   sensors=args.sensors or "realistic", protocol=args.protocol or "paper",
                   cycles=cycles, weather=args.weather or DEFAULT_WEATHER)
    n = IDENTIFY_SEEDS if args.seeds is None else args.seeds
    return bench_identify(
        spec, seeds=range(args.seed, args.seed + n),
        on_figures=None if args.json is None else lambda fig: _write_json(
            args.json, args.target, fig),
        progress=lambda msg: print(msg, file=sys.stderr, flush=True),
        keep_state=args.keep_state)


def _bench_diagnostics(args: argparse.Namespace) -> dict[str, Any]:
    from dsfd.bench.diagnostics import SEASONS, bench_diagnostics, report

    seeds = diagnostics_seeds(args.seeds, args.seed)
    figures = bench_diagnostics(
        args.config, seeds=seeds, clean_days=10.0 if args.days is None else args.days,
        seasons=SEASONS if args.seasons is None else tuple(
            s.strip() for s in args.seasons.split(",") if s.strip()),
        names=None if args.scenarios is None else tuple(
            s.strip() for s in args.scenarios.split(",") if s.strip()),
        keep=args.keep_state, aalborg=args.aalborg, rechecked=args.recheck,
        progress=lambda msg: print(msg, file=sys.stderr, flush=True),
        on_figures=None if args.json is None else lambda fig: _write_json(
            args.json, args.target, {**fig, "partial": 1.0}))
    print(report(figures))
    print()
    return figures


#: Benchmark targets: name → function(args) → flat figures.
TARGETS: dict[str, Callable[[argparse.Namespace], dict[str, Any]]] = {
    "model": _bench_model,
    "control": _bench_control,
    "plant": _bench_plant,
    "plant-velocity": _bench_plant_velocity,
    "daemon": _bench_daemon,
    "mqtt": _bench_mqtt,
    "bacnet": _bench_bacnet,
    "calibration": _bench_calibration,
    "paper-tables": _bench_paper_tables,
    "closed-loop": _bench_closed_loop,
    "identify": _bench_identify,
    "diagnostics": _bench_diagnostics,
}
#: Targets that print their own tables (their figures are too many to list one a line).
OWN_TABLES = frozenset({"identify", "diagnostics"})
#: ``identify`` defaults: the seeds and days of issue 35's targets.
IDENTIFY_SEEDS, IDENTIFY_DAYS = 5, 3.0
#: Options only ``identify`` takes (``keep_state``: and ``diagnostics``).
IDENTIFY_ONLY = ("plant", "sensors", "protocol")
#: Options only ``diagnostics`` takes.
DIAGNOSTICS_ONLY = ("seasons", "scenarios", "aalborg", "recheck")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="benchmark a part of dsfd",
                       description="Time one part of dsfd and print its figures (units in "
                       "the names); --json writes them as a flat JSON object.")
    p.add_argument("target", choices=sorted(TARGETS), help="what to benchmark")
    p.add_argument("--config", type=Path, default=DEFAULT_PANEL,
                   help=f"panel YAML (default {DEFAULT_PANEL})")
    p.add_argument("--days", type=float, default=None,
                   help="simulated duration where the target simulates (plant: 3; daemon: "
                   "10,000 one-minute cycles; paper-tables: 3 scored days after the "
                   "training day; plant-velocity: the paper's 8-11 Dec 2008, or with "
                   "--weather from the record's second day to its end; closed-loop: 1 scored "
                   "day per case; identify: 3 days per seed; diagnostics: the clean run's 10 days)")
    p.add_argument("--seed", type=int, default=None, help="seed of the target's "
                   "randomness (default 0; identify, closed-loop and diagnostics: the first "
                   "seed of a count --seeds; diagnostics alone: run that seed)")
    p.add_argument("--cases", type=int, default=200,
                   help="control: random decision problems judged against brute force")
    p.add_argument("--seeds", type=_seeds, default=None,
                   help="plant-velocity: seeded draws of the plant's true parameters (default "
                   "10); paper-tables: run seeds 0..N-1 and print the per-seed cavity-speed "
                   "table; identify and closed-loop: run seeds SEED..SEED+N-1 (identify: "
                   "default 5); closed-loop also takes a list such as 1,2,3, and prints the "
                   "share per case and seed; diagnostics: seeds 1..N (SEED..SEED+N-1 with "
                   "--seed) or a list (default 1,2,3)")
    p.add_argument("--oracle-cache", type=Path, default=None, metavar="FILE",
                   help="closed-loop: take the plant oracle's figures from FILE where it has "
                   "them for the case, seed, days, weather and panel, and store new ones there "
                   "(dsfd.bench.oracle_cache)")
    p.add_argument("--cycles", type=int, default=None,
                   help="mqtt, bacnet: daemon cycles whose publish / COV latency is measured "
                   "(default 200, bacnet 100)")
    p.add_argument("--reads", type=int, default=None,
                   help="bacnet: ReadPropertyMultiple requests timed (default 500)")
    p.add_argument("--backlog", type=int, default=None,
                   help="mqtt: stored cycles drained after an outage (default 5000)")
    p.add_argument("--weather", default=None, help="weather file or bundled name")
    p.add_argument("--prior-centre", action="store_true",
                   help="paper-tables: the plant at the centre of the true-parameter prior "
                   "(docs/model.md#true-parameters) (f_true ~ 200, the speeds of the paper's "
                   "Table 1) instead of the seed's draw")
    p.add_argument("--case", action="append", default=None,
                   help="closed-loop: one case <clear|mixed|overcast>-<heating|cooling> "
                   "(repeatable; default all six)")
    p.add_argument("--controllers", default=None,
                   help="closed-loop: comma-separated controllers (default "
                   f"{', '.join(BENCH_CONTROLLERS)})")
    p.add_argument("--fault", action="append", default=[], metavar="KIND:START:RATE",
                   help="closed-loop: a slow fault of the truth plant, START relative to "
                   "each case's run start (warm-up included) or ISO UTC (repeatable; grammar "
                   "in docs/faults.md#simulated-faults)")
    p.add_argument("--occupancy", choices=OCCUPANCY_CHOICES, default=None,
                   help="closed-loop: the schedule comfort is judged by (default "
                   "office-every-day: 08:00-18:00 local every day; office-weekdays: Monday to "
                   "Friday, which leaves the bundled record's clear and overcast days, a "
                   "Sunday and a Saturday at the Suwon site, unoccupied; panel: the panel's "
                   "occupancy:; none)")
    _identify_and_diagnostics_options(p)
    p.add_argument("--json", type=Path, default=None, help="write the figures as JSON "
                   "(identify: rewritten after every seed)")
    p.set_defaults(handler=run)


def _identify_and_diagnostics_options(p: argparse.ArgumentParser) -> None:
    """The options of the identify and diagnostics targets (refused by the others)."""
    p.add_argument("--plant", choices=("lumped", "truth"), default=None,
                   help="identify: lumped = the lumped-equivalent plant (the model's structure, "
                   "true parameters known; default), truth = the full-fidelity truth plant")
    p.add_argument("--sensors", choices=("ideal", "realistic"), default=None,
                   help="identify: the plant's sensors (default realistic: noise and biases)")
    p.add_argument("--protocol", choices=("paper", "closed-loop"), default=None,
                   help="identify: paper = the paper's random louver angle and regime every "
                   "30-90 min (default); closed-loop = the daemon's own decisions")
    p.add_argument("--keep-state", type=Path, default=None, metavar="DIR",
                   help="identify: keep each seed's daemon state directory as DIR/seed<N> "
                   "(for dsfd report; default: temporary); diagnostics: each run's as "
                   "DIR/<season>.<scenario>.seed<N>")
    p.add_argument("--seasons", default=None, metavar="LIST",
                   help="diagnostics: winter, cooling or both (default winter,cooling)")
    p.add_argument("--scenarios", default=None, metavar="LIST",
                   help="diagnostics: some of stuck-damper, louver-slip, tc-offset, tc-drift, "
                   "soiling, screen, clean (default all)")
    p.add_argument("--recheck", type=Path, default=None, metavar="DIR",
                   help="diagnostics: make no run; replay today's detectors over the runs an "
                   "earlier --keep-state DIR kept, and score them again")
    p.add_argument("--aalborg", type=Path, default=None, metavar="DIR",
                   help="diagnostics: also count the residual detector's findings on the real "
                   "Aalborg 'Cube' week in DIR (the dsfd convert-aalborg source folder), "
                   "replayed with the self-calibrating model")


def diagnostics_seeds(seeds: int | tuple[int, ...] | None, seed: int | None
                      ) -> tuple[int, ...]:
    """The seeds ``bench diagnostics`` runs: a list as given; a count N from ``--seed`` on
    (SEED..SEED+N-1, as closed-loop and identify take it), from 1 without it; ``--seed``
    alone, that seed; neither, 1, 2 and 3 (the issue's)."""
    if isinstance(seeds, tuple):
        return seeds
    first = 1 if seed is None else seed
    if seeds is None:
        return (1, 2, 3) if seed is None else (seed,)
    return tuple(range(first, first + seeds))


def _seeds(text: str) -> int | tuple[int, ...]:
    """``--seeds``: a count N (seeds 0..N-1) or a comma-separated list of seeds."""
    try:
        if "," in text:
            return tuple(int(s) for s in text.split(",") if s.strip())
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r}: a count (e.g. 5) or a list of seeds (e.g. 1,2,3)") from None


def _write_json(path: Path, target: str, figures: dict[str, Any]) -> None:
    """``{"target": …, **figures}`` to ``path``, replaced atomically (a long bench rewrites
    it as it goes: a reader never sees half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps({"target": target, **figures}, indent=1))
    os.replace(tmp, path)


def run(args: argparse.Namespace) -> int:
    if args.seed is None and args.target != "diagnostics":  # diagnostics: see diagnostics_seeds
        args.seed = 0
    if isinstance(args.seeds, tuple):
        if args.target not in ("closed-loop", "diagnostics"):
            print(f"dsfd bench {args.target}: --seeds takes a count N (seeds 0..N-1); a list "
                  "of seeds is for closed-loop and diagnostics", file=sys.stderr)
            return 2
        if min(args.seeds, default=-1) < 0:
            print(f"dsfd bench: --seeds {args.seeds}: seeds are 0 or more", file=sys.stderr)
            return 2
    for name in ("days", "cycles", "backlog", "seeds", "reads"):
        value = getattr(args, name)
        if isinstance(value, tuple):
            continue  # a list of seeds, checked above
        if value is not None and not value > 0:
            print(f"dsfd bench: --{name} {value}: must be positive", file=sys.stderr)
            return 2
    if args.fault and args.target != "closed-loop":
        print("dsfd bench: --fault only applies to the closed-loop target", file=sys.stderr)
        return 2
    only = {"identify": IDENTIFY_ONLY, "diagnostics": DIAGNOSTICS_ONLY}
    if args.keep_state is not None and args.target not in only:
        print("dsfd bench: --keep-state only applies to the identify and diagnostics targets",
              file=sys.stderr)
        return 2
    for target, names in only.items():
        if args.target == target:
            continue
        for name in names:
            if getattr(args, name) is not None:
                print(f"dsfd bench: --{name.replace('_', '-')} only applies to the "
                      f"{target} target", file=sys.stderr)
                return 2
    try:
        figures = TARGETS[args.target](args)
    except ConfigError as exc:
        print(exc, file=sys.stderr)
        return 2
    except (FileNotFoundError, ValueError) as exc:
        print(f"dsfd bench: {exc}", file=sys.stderr)
        return 2
    except RuntimeError as exc:  # a missing optional extra (MissingExtraError) or tool
        print(f"dsfd bench: {exc}", file=sys.stderr)
        return 2
    if args.target not in OWN_TABLES:
        print(f"dsfd bench {args.target}")
        width = max(len(k) for k in figures)
        for key, value in figures.items():
            print(f"  {key:<{width}}  {value:14.4g}")
    if args.json:
        _write_json(args.json, args.target, figures)
        print(f"wrote {args.json}")
    return 0
