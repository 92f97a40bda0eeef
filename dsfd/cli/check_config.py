"""``dsfd check-config FILE...``: validate panel configurations without touching devices."""

from __future__ import annotations

import argparse
import sys

from dsfd.config import ConfigError, load_panel


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check-config", help="validate panel YAML files",
                       description="Print 'OK <file>' for each valid file or every error "
                       "(key path, bad value, reason). Exit 0 if all are valid, else 2.")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
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
    return 2 if bad else 0
