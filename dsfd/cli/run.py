"""``dsfd run``: the controller daemon of one panel (what ``systemd/dsfd@.service`` starts).

Examples::

    dsfd run --config /etc/dsfd/suwon-south.yaml                 # hardware, real time
    dsfd run --config PANEL --dry-run                             # read and decide, never write
    dsfd run --config PANEL --dry-run --plant sim --cycles 1440   # a simulated winter day

Exit codes: 0 after the requested cycles or a stop signal, 2 for a bad configuration or bad
options (reported before any device is touched, naming the key path), 3 if another process
controls the state directory (its PID named; nothing was opened), 1 if the daemon failed.
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import json
import shutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from dsfd.config import ConfigError

if TYPE_CHECKING:
    from dsfd.config import PanelConfig
    from dsfd.daemon.runner import Integration, RunOptions

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_BUSY = 0, 1, 2, 3


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "run", help="run the controller daemon of one panel",
        description="Read sensors, calibrate, optimise and command one panel every cycle. "
        "Under systemd: Type=notify with watchdog pings, JSON logs on stdout, SIGTERM stops "
        "after the current cycle, SIGHUP reloads the configuration.")
    p.add_argument("--config", required=True, type=Path, metavar="PANEL",
                   help="panel YAML (validated before anything is opened)")
    p.add_argument("--dry-run", action="store_true",
                   help="read and decide but never write to actuators (with --plant sim the "
                   "simulated plant still follows the decisions in-process)")
    p.add_argument("--plant", choices=["sim"], default=None,
                   help="sim: the simulated truth plant on replayed real weather instead of "
                   "the configured devices")
    p.add_argument("--plant-fidelity", choices=["full", "lumped"], default="full",
                   help="with --plant sim: full = the stratified truth plant; lumped = the "
                   "same plant with the lumped model's switches (fast)")
    p.add_argument("--speed", type=float, default=None, metavar="X",
                   help="simulated clock at X times real time (default with --plant sim: as "
                   "fast as possible; without --plant: the real clock)")
    p.add_argument("--cycles", type=int, default=None, metavar="N",
                   help="stop after N cycles (default: run until stopped; with --plant sim "
                   "until the weather record ends)")
    p.add_argument("--state-dir", type=Path, default=None, metavar="DIR",
                   help="database and calibration state (default daemon.state_directory, "
                   "else $STATE_DIRECTORY; a temporary directory for --plant sim)")
    p.add_argument("--weather", default=None, metavar="NAME|FILE",
                   help="weather of the simulated plant (default rmis-golden-2022-01)")
    p.add_argument("--start", default=None, metavar="ISO",
                   help="UTC start of the simulated clock, e.g. 2022-01-01T15:00:00Z")
    p.add_argument("--seed", type=int, default=1, help="seed of the simulated plant")
    p.add_argument("--fault", action="append", default=[], metavar="KIND:START:RATE",
                   help="with --plant sim: a slow fault of the simulated plant, e.g. "
                   "soiling:+1d:1.5 (%% solar transmittance lost per day), "
                   "damper-stuck.EB:+2h:0, louver-slip:+0s:1, tc-drift.x3:+0s:0.5, "
                   "screen:+1d:1, tc-offset.x1:2022-01-02T06:00:00Z:1, anemometer:+0s:0.7 "
                   "(repeatable; grammar in docs/faults.md#simulated-faults)")
    p.add_argument("--summary-json", type=Path, default=None, metavar="OUT",
                   help="also write the end-of-run summary as JSON")
    p.add_argument("--log-format", choices=["auto", "json", "console"], default="auto",
                   help="json: one JSON object per line (journald, log shippers); console: "
                   "one aligned line per cycle with events marked, for a person; auto "
                   "(default): console when stdout is a terminal, else json")
    p.set_defaults(handler=run)


def _check_options(args: argparse.Namespace) -> str | None:
    if args.speed is not None and not args.speed > 0:
        return f"--speed {args.speed}: must be a positive factor"
    if args.cycles is not None and args.cycles < 1:
        return f"--cycles {args.cycles}: must be at least 1"
    if args.plant != "sim" and (args.weather is not None or args.plant_fidelity != "full"):
        return "--weather and --plant-fidelity only apply to --plant sim"
    if args.start is not None and args.plant != "sim" and args.speed is None:
        return "--start needs a simulated clock (--plant sim or --speed)"
    if args.fault and args.plant != "sim":
        return "--fault only applies to --plant sim (the simulated plant)"
    from dsfd.sim.plant.faults import FaultSpecError, parse_fault

    for text in args.fault:
        try:
            parse_fault(text)
        except FaultSpecError as exc:
            return f"--fault {exc}"
    return None


def _integrations(cfg: PanelConfig, config_path: Path) -> list[Integration]:
    """What runs beside the loop: the MQTT publisher if the panel has an ``mqtt:`` section,
    the BACnet/IP device if it has a ``bacnet:`` section."""
    from dsfd import __version__

    out: list[Integration] = []
    if cfg.mqtt is not None:
        from dsfd.integrations.mqtt import publisher_for_run

        out.append(publisher_for_run(cfg, config_path=config_path, version=__version__))
    if cfg.bacnet is not None:
        from dsfd.integrations.bacnet import device_for_run

        out.append(device_for_run(cfg, version=__version__))
    return out


def _until_the_weather_ends(cfg: PanelConfig, opts: RunOptions) -> RunOptions:
    """``--plant sim``: check the weather window; without ``--cycles`` the run lasts until
    the weather record ends. ``FileNotFoundError``/``ValueError`` for bad weather."""
    from dsfd.sim.daemon_plant import DEFAULT_WEATHER, cycles_covered, weather_window

    series, start = weather_window(cfg, weather=opts.weather or DEFAULT_WEATHER,
                                   start_s=opts.start_s)
    if opts.cycles is None:
        opts = dataclasses.replace(opts, cycles=cycles_covered(
            series, start_s=start, period_s=cfg.daemon.cycle_period_s))
    return opts


def _announce(cfg: PanelConfig, opts: RunOptions, state_dir: Path, *, temporary: bool
              ) -> None:
    """What is about to run, and whether anything is written to hardware."""
    print(f"dsfd run — panel {cfg.panel.id} ({opts.mode})")
    if opts.dry_run:
        print("  DRY RUN: commands are decided but NOTHING IS WRITTEN TO HARDWARE"
              + ("; the simulated plant follows the decisions in-process"
                 if opts.simulated_plant else ""))
    elif opts.simulated_plant:
        print("  simulated plant: nothing is written to hardware")
    print(f"  state directory: {state_dir}"
          + (" (temporary, removed at exit; --state-dir keeps it)" if temporary else ""))
    bn = cfg.bacnet
    if bn is not None:
        print(f"  BACnet/IP device {bn.device_instance} on UDP {bn.bind_address()}: "
              + ("WRITABLE (priority 1-15 writes hold the panel)" if bn.writable
                 else "read-only"))


def run(args: argparse.Namespace) -> int:
    from dsfd.daemon.logging_setup import configure_logging
    from dsfd.daemon.runner import RunOptions, load_for_run, serve
    from dsfd.daemon.startup import resolve_state_dir
    from dsfd.integrations.mqtt.link import MissingExtraError
    from dsfd.measured import parse_iso_utc

    problem = _check_options(args)
    start_s = None
    if problem is None and args.start is not None:
        try:
            start_s = parse_iso_utc(args.start)
        except ValueError as exc:
            problem = f"--start {args.start!r}: {exc}"
    if problem:
        print(f"dsfd run: {problem}", file=sys.stderr)
        return EXIT_USAGE
    opts = RunOptions(config_path=args.config, dry_run=args.dry_run, plant=args.plant,
                      plant_fidelity=args.plant_fidelity, speed=args.speed, cycles=args.cycles,
                      state_dir=args.state_dir, weather=args.weather, start_s=start_s,
                      seed=args.seed, faults=tuple(args.fault))
    try:
        cfg = load_for_run(args.config, simulated_plant=opts.simulated_plant,
                           dry_run=opts.dry_run)
        integrations = _integrations(cfg, args.config)
        state_dir, temporary = resolve_state_dir(opts, cfg)
    except ConfigError as exc:
        print(f"dsfd run: {args.config}: configuration rejected, nothing was started",
              file=sys.stderr)
        for issue in exc.issues:
            print(f"  {issue}", file=sys.stderr)
        return EXIT_USAGE
    except MissingExtraError as exc:
        print(f"dsfd run: {args.config}: {exc}; nothing was started", file=sys.stderr)
        return EXIT_USAGE
    plant = None
    if opts.simulated_plant:
        from dsfd.sim.daemon_plant import plant_for_run

        try:
            opts = _until_the_weather_ends(cfg, opts)
            plant = plant_for_run(cfg, opts)  # ValueError: e.g. louver-slip without a louver
        except (FileNotFoundError, ValueError) as exc:
            print(f"dsfd run: {exc}", file=sys.stderr)
            return EXIT_USAGE
    configure_logging(json={"auto": None, "json": True, "console": False}[args.log_format])
    _announce(cfg, opts, state_dir, temporary=temporary)
    import sqlite3

    from dsfd.storage.lock import StateDirBusyError
    from dsfd.storage.timeseries import SchemaTooNewError

    try:
        summary = asyncio.run(serve(opts, cfg, state_dir=state_dir, plant=plant,
                                    integrations=integrations))
    except StateDirBusyError as exc:
        print(f"dsfd run: {exc}; nothing was opened", file=sys.stderr)
        return EXIT_BUSY
    except (OSError, SchemaTooNewError, sqlite3.Error) as exc:  # e.g. a state directory the
        # service user cannot write, a full disk at start, or a database of a newer dsfd
        print(f"dsfd run: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    finally:
        if temporary:
            shutil.rmtree(state_dir, ignore_errors=True)
    for line in summary.lines():
        print(line)
    if opts.dry_run:
        print("  nothing was written to hardware (dry run)")
    if args.summary_json is not None:
        args.summary_json.write_text(json.dumps(summary.as_dict(), indent=1))
    return EXIT_OK
