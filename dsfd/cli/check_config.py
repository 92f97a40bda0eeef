"""``dsfd check-config FILE...``: validate panel configurations without touching devices.

``dsfd check-config --explain KEY`` prints what one key of a panel file means (type, unit,
default, limits, allowed values), the entry of docs/configuration.md; an unknown key exits 2
and names the nearest documented keys.
"""

from __future__ import annotations

import argparse
import sys

from dsfd.config import ConfigError, load_panel


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check-config", help="validate panel YAML files",
                       description="Print 'OK <file>' for each valid file or every error "
                       "(key path, bad value, reason). Exit 0 if all are valid, else 2. "
                       "With --explain KEY: what that key means (docs/configuration.md).")
    p.add_argument("files", nargs="*", metavar="FILE")
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
            load_panel(path)
        except ConfigError as exc:
            bad += 1
            print(f"{path}: {len(exc.issues)} error(s)", file=sys.stderr)
            for issue in exc.issues:
                print(f"  {issue}", file=sys.stderr)
        else:
            print(f"OK {path}")
    return 2 if bad or status else 0
