"""``dsfd check-config FILE...``: validate panel configurations without touching devices.

``--run hardware|dry-run|sim`` adds the checks ``dsfd run`` makes before it opens anything
in that mode (:func:`dsfd.daemon.startup.runtime_problems`: the stage budgets against the
cycle, the metrics file, and against hardware the devices that deliver the safety sensors
and own the actuators), so a file that passes here also starts.

``dsfd check-config --explain KEY`` prints what one key of a panel file means (type, unit,
default, limits, allowed values), the entry of docs/configuration.md; an unknown key exits 2
and names the nearest documented keys.
"""

from __future__ import annotations

import argparse
import sys

from dsfd.config import ConfigError, load_panel

#: ``--run`` modes: (simulated plant, dry run) as ``dsfd run`` takes them.
RUN_MODES = {"hardware": (False, False), "dry-run": (False, True), "sim": (True, True)}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check-config", help="validate panel YAML files",
                       description="Print 'OK <file>' for each valid file or every error "
                       "(key path, bad value, reason). Exit 0 if all are valid, else 2. "
                       "With --explain KEY: what that key means (docs/configuration.md).")
    p.add_argument("files", nargs="*", metavar="FILE")
    p.add_argument("--run", choices=RUN_MODES, default=None,
                   help="also make the checks of `dsfd run` in that mode: hardware (the "
                   "default run: devices read and written), dry-run (hardware read, nothing "
                   "written: --dry-run) or sim (--plant sim); without it, the file alone")
    p.add_argument("--explain", metavar="KEY", default=None,
                   help="print the reference entry of KEY, e.g. calibration.min_window_h "
                   "(list items as devices.entries[].tcp.host or entries[0])")
    p.set_defaults(handler=run)


def explain(key: str) -> int:
    from dsfd.config.reference import entries, explain_text, find, nearest

    table = entries()
    entry = find(key, table)
    if entry is None:
        near = nearest(key, table)
        print(f"dsfd check-config: --explain {key!r}: no such key in a panel file"
              + (f"; nearest: {', '.join(near)}" if near else ""), file=sys.stderr)
        return 2
    print(explain_text(entry))
    return 0


def run(args: argparse.Namespace) -> int:
    if args.explain is None and not args.files:
        print("dsfd check-config: give FILE... to check, or --explain KEY", file=sys.stderr)
        return 2
    status = explain(args.explain) if args.explain is not None else 0
    bad = 0
    for path in args.files:
        try:
            _check(path, getattr(args, "run", None))
        except ConfigError as exc:
            bad += 1
            print(f"{path}: {len(exc.issues)} error(s)", file=sys.stderr)
            for issue in exc.issues:
                print(f"  {issue}", file=sys.stderr)
        else:
            print(f"OK {path}")
    return 2 if bad or status else 0


def _check(path: str, mode: str | None) -> None:
    """Load ``path``; with ``mode``, also the run-time checks of ``dsfd run`` in that mode."""
    if mode is None:
        load_panel(path)
        return
    from pathlib import Path

    from dsfd.daemon.startup import load_for_run

    simulated_plant, dry_run = RUN_MODES[mode]
    load_for_run(Path(path), simulated_plant=simulated_plant, dry_run=dry_run)
