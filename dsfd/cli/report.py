"""``dsfd report``: one self-contained HTML page of what a controller did (its own log).

Exit codes: 0 written; 1 no database or no cycle in the window; 2 bad options, or
matplotlib missing (``pip install 'dsfd[report]'``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from dsfd.cli.state_dir import add_state_arguments, history_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "report", help="an HTML report of what the controller did (KPIs and figures)",
        description="Read a state directory's database (read-only; the daemon may be running) "
        "and write one self-contained HTML file: key figures per day (heat into the room by "
        "term, moves, methods, flagged samples, write failures, decision times, calibration, "
        "prediction errors against persistence) and figures (measured vs predicted states, "
        "commands with the weather, regimes by sky condition, parameter history, prediction "
        "error over time, daily heat), and the diagnostics: each finding of the daemon's "
        "detectors in the period with a figure of its evidence. Needs matplotlib: "
        "pip install 'dsfd[report]'.")
    add_state_arguments(p)
    p.add_argument("--out", required=True, type=Path, help="HTML file to write")
    p.add_argument("--json", type=Path, default=None, metavar="OUT",
                   help="also write the key figures as JSON")
    p.add_argument("--dpi", type=int, default=90, help="figure resolution (default 90)")
    p.set_defaults(handler=run)


def report_available() -> str | None:
    """Why ``dsfd report`` cannot draw, or None."""
    from dsfd.report import INSTALL_HINT

    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return f"matplotlib is not installed: {INSTALL_HINT}"
    return None


def run(args: argparse.Namespace) -> int:
    from dsfd.report import ReportUnavailableError, build_report, write_report

    missing = report_available()
    if missing:
        print(f"dsfd report: {missing}", file=sys.stderr)
        return 2
    if not 30 <= args.dpi <= 400:
        print(f"dsfd report: --dpi {args.dpi}: choose 30..400", file=sys.stderr)
        return 2
    history, cfg, code = history_from_args(args, "report")
    if history is None:
        return code
    try:
        report = build_report(history, panel=cfg, dpi=args.dpi)
    except ReportUnavailableError as exc:
        print(f"dsfd report: {exc}", file=sys.stderr)
        return 2
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        write_report(report, args.out)
        if args.json is not None:
            doc = {"panel": history.panel, "cycles": len(history), **report.kpis.as_dict()}
            args.json.write_text(json.dumps(doc, indent=1, default=str) + "\n")
    except OSError as exc:
        print(f"dsfd report: {exc}", file=sys.stderr)
        return 1
    for note in report.notes:
        print(f"note: {note}")
    found = len(report.diagnostics.findings) if report.diagnostics is not None else 0
    print(f"wrote {args.out}: {len(history)} cycles, {len(report.figures)} figures, "
          f"{found} finding{'s' if found != 1 else ''}")
    return 0
