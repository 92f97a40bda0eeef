"""``dsfd validate``: replay measured data and score the models (the paper's Tables 1 and 2)."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from dsfd.cli.calibrate import select_rows
from dsfd.cli.progress import Progress
from dsfd.config import ConfigError, load_panel
from dsfd.measured import iso_utc
from dsfd.storage.measured_csv import read_measured

if TYPE_CHECKING:
    from dsfd.estimation.validation import ReplayScores

MODELS = (("online", "self-calibrating"), ("offline", "off-line"),
          ("uncalibrated", "uncalibrated"), ("persistence", "persistence"))


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("validate", help="score self-calibrating, off-line and uncalibrated "
                       "models on measured data",
                       description="Replay a measured-data CSV: the self-calibrating model is "
                       "updated as the replay goes; the off-line model uses --params; the "
                       "uncalibrated model the panel defaults; persistence holds the last "
                       "measurement. Prints the mean absolute difference per state at each "
                       "horizon (Table 2) and of the cavity speed per regime (Table 1).")
    p.add_argument("--config", required=True, type=Path, help="panel YAML")
    p.add_argument("--data", required=True, type=Path, help="measured-data CSV")
    p.add_argument("--params", type=Path, default=None,
                   help="off-line parameters YAML (from 'dsfd calibrate')")
    p.add_argument("--start", default=None, help="first sample to use (ISO-8601 UTC)")
    p.add_argument("--end", default=None, help="last sample to use (ISO-8601 UTC)")
    p.add_argument("--horizons", default="1,15",
                   help="lead times in data steps, comma separated (default 1,15)")
    p.add_argument("--warmup-h", type=float, default=0.0,
                   help="hours at the start replayed but not scored")
    p.add_argument("--no-online", action="store_true",
                   help="skip the self-calibrating model (fast)")
    p.add_argument("--json", type=Path, default=None, help="write the figures as flat JSON")
    p.set_defaults(handler=run)


def _horizons(text: str) -> tuple[int, ...]:
    try:
        values = tuple(sorted({int(v) for v in text.split(",") if v.strip()}))
    except ValueError:
        raise ValueError(f"--horizons {text!r}: expected comma-separated step counts") from None
    if not values or min(values) < 1:
        raise ValueError(f"--horizons {text!r}: step counts must be >= 1")
    return values


def _replay_progress() -> Callable[[int, int, int], None]:
    bar = Progress("replay")
    return lambda row, rows, updates: bar(row, rows, f"{updates} updates")


#: Width of a model's column: its full name and a space.
COLUMN = max(len(label) for _, label in MODELS) + 2


def _cell(value: float | None, scale: float = 1.0) -> str:
    return f"{value * scale:{COLUMN}.2f}" if value is not None else f"{'-':>{COLUMN}}"


def print_tables(scores: ReplayScores, models: list[tuple[str, str]],
                 horizons: tuple[int, ...], step_s: float) -> None:
    """Table 2 (states) per horizon and Table 1 (cavity speed per regime)."""
    head = "".join(f"{label:>{COLUMN}}" for _, label in models)
    states = list(scores.measured_mean_c)  # the states measured, x1..x5 in order
    for h in horizons:
        print(f"\nTable 2 — mean absolute difference, predicted {h} step(s) = "
              f"{h * step_s / 60:g} min ahead vs measured [degC]")
        print(f"{'state':<8}{head}{'measured':>{COLUMN}}")
        for s in [*states, "mean"]:
            meas = (sum(scores.measured_mean_c[x] for x in states) / len(states)
                    if s == "mean" and states else scores.measured_mean_c.get(s))
            row = "".join(_cell(scores.mae_c(m, h, s)) for m, _ in models)
            print(f"{s:<8}{row}{_cell(meas)}")
    print_paired(scores, [m for m, _ in models if m != "online"], horizons, states)
    regimes = sorted(scores.velocity)
    if regimes:
        print("\nTable 1 — mean absolute difference of the cavity speed |v|, one step ahead "
              "[cm/s]")
        print(f"{'regime':<8}{head}{'measured':>{COLUMN}}{'samples':>9}")
        for r in regimes:
            v = scores.velocity[r]
            row = "".join(_cell(v.mae_cms.get(m)) for m, _ in models)
            print(f"{r:<8}{row}{_cell(v.measured_mean_cms)}{v.samples:9d}")
    else:
        print("\nTable 1 — no cavity speed (v_cav_ms) in the data: skipped")


def print_paired(scores: ReplayScores, others: list[str], horizons: tuple[int, ...],
                 states: list[str]) -> None:
    """Self-calibrating minus each other model: paired difference ± standard error [mK]."""
    others = [m for m in others if any(hs.paired.get(m) for hs in scores.horizons.values())]
    if not others:
        return
    print("\nSelf-calibrating minus other model, paired difference of the absolute errors "
          "± standard error (batch means) [mK]; negative: self-calibrating better, "
          "|diff| < 2 se: not distinguishable on this record")
    print(f"{'state':<8}" + "".join(f"{f'vs {m} h{h}':>20}" for h in horizons for m in others))
    for s in states:
        cells = []
        for h in horizons:
            for m in others:
                pair = scores.horizons[h].paired.get(m, {}).get(s)
                if pair is not None:
                    diff, se = pair[0] * 1e3, pair[1] * 1e3
                    cells.append(f"{diff:+10.1f} ± {se:6.1f}")
                else:
                    cells.append(f"{'-':>19}")
        print(f"{s:<8}" + "".join(f"{c:>20}" for c in cells))


def run(args: argparse.Namespace) -> int:
    from dsfd.estimation.params import ParameterSpace
    from dsfd.estimation.stepdata import step_data
    from dsfd.estimation.validation import replay_scores
    from dsfd.storage.calibration_file import read_params

    try:
        horizons = _horizons(args.horizons)
        cfg = load_panel(args.config)
        data = select_rows(read_measured(args.data), args.start, args.end)
        steps = step_data(cfg, data)
        offline = None
        if args.params is not None:
            offline = read_params(args.params, space=ParameterSpace.from_panel(cfg),
                                  panel_id=cfg.panel.id)
    except ConfigError as exc:
        print(exc, file=sys.stderr)
        return 2
    except (OSError, ValueError) as exc:
        print(f"dsfd validate: {exc}", file=sys.stderr)
        return 2
    if steps.n_steps <= max(horizons):
        print(f"dsfd validate: {args.data}: {steps.n_steps} steps, fewer than the longest "
              f"horizon {max(horizons)}", file=sys.stderr)
        return 2
    print(f"dsfd validate — panel {cfg.panel.id}")
    print(f"data: {args.data} ({steps.n_steps} steps of {steps.step_s:g} s, "
          f"{iso_utc(steps.time_s[0])} to {iso_utc(steps.time_s[-1])})")
    for note in steps.notes:
        print(f"  note: {note}")
    missing = [s for s in ("x1", "x2", "x3", "x4", "x5", "v") if s not in steps.present]
    if missing:
        print(f"  not measured (skipped): {', '.join(missing)}")
    out = replay_scores(cfg, steps, offline_theta=offline, horizons=horizons,
                        warmup_h=args.warmup_h, online=not args.no_online,
                        progress=None if args.no_online else _replay_progress())
    models = [(m, label) for m, label in MODELS
              if m in out.scored_models()]
    print(f"scored {out.scored_starts} start rows; self-calibration updates: "
          f"{out.online_updates}")
    print_tables(out, models, horizons, steps.step_s)
    if args.json:
        doc = {"panel": cfg.panel.id, "data": str(args.data), **out.flat()}
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(doc, indent=1))
        print(f"\nwrote {args.json}")
    return 0
