"""Command-line entry point: ``dsfd <command> ...``.

Each command lives in its own module exposing ``register(subparsers)``; this module only
assembles the parser and maps exceptions to exit codes (2 = bad input/configuration).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from dsfd import __version__

#: Command modules, in the order they appear in ``dsfd --help``.
COMMANDS = ("check_config", "simulate", "run", "operator", "status", "fleet", "report",
            "export", "commission", "bench", "calibrate", "validate", "convert_aalborg")

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="dsfd",
        description="Self-calibrating model-predictive controller for double-skin façade panels",
    )
    parser.add_argument("--version", action="version", version=f"dsfd {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        module = importlib.import_module(f"dsfd.cli.{name}")
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args))
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
