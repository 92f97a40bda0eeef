"""``dsfd calibrate``: the off-line baseline — one batch fit of θ over a measured record."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dsfd.cli.progress import Progress
from dsfd.config import ConfigError, load_panel
from dsfd.measured import (
    MeasuredData,
    MeasuredDataError,
    iso_utc,
    parse_iso_utc,
)
from dsfd.storage.measured_csv import read_measured


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="off-line calibration of the model on measured data",
                       description="Fit the model parameters (Eq. 3 without forgetting, "
                       "multi-step residuals, robust loss, bounds) once over a measured-data "
                       "CSV and write them as YAML for 'dsfd validate --params'.")
    p.add_argument("--config", required=True, type=Path, help="panel YAML")
    p.add_argument("--data", required=True, type=Path, help="measured-data CSV")
    p.add_argument("--out", required=True, type=Path, help="parameters YAML to write")
    p.add_argument("--start", default=None, help="first sample to use (ISO-8601 UTC)")
    p.add_argument("--end", default=None, help="last sample to use (ISO-8601 UTC)")
    p.add_argument("--max-nfev", type=int, default=None,
                   help="residual evaluations (default calibration.offline_max_nfev)")
    p.add_argument("--passes", type=int, default=1,
                   help="re-run the observer with the fitted θ and refit this many times")
    p.set_defaults(handler=run)


def select_rows(data: MeasuredData, start: str | None, end: str | None) -> MeasuredData:
    """Rows between ISO-8601 times ``start`` and ``end`` (inclusive; None = open)."""
    import numpy as np

    t = data.time_s
    try:
        lo = parse_iso_utc(start) if start else -np.inf
        hi = parse_iso_utc(end) if end else np.inf
    except ValueError as exc:
        raise MeasuredDataError(f"--start/--end: {exc}") from None
    rows = np.flatnonzero((t >= lo) & (t <= hi))
    if rows.size < 2:
        raise MeasuredDataError(f"{data.source}: fewer than two rows between "
                                f"{start or 'start'} and {end or 'end'}")
    return data.window(int(rows[0]), int(rows[-1]) + 1)


def run(args: argparse.Namespace) -> int:
    from dsfd.estimation.calibration import offline_fit
    from dsfd.estimation.params import FIT_NAMES, ParameterSpace
    from dsfd.estimation.stepdata import model_config, step_data
    from dsfd.physics.model import LumpedModel
    from dsfd.storage.calibration_file import write_params

    if args.max_nfev is not None and args.max_nfev < 1:
        print(f"dsfd calibrate: --max-nfev {args.max_nfev}: must be >= 1", file=sys.stderr)
        return 2
    try:
        cfg = load_panel(args.config)
        data = select_rows(read_measured(args.data), args.start, args.end)
        steps = step_data(cfg, data)
    except ConfigError as exc:
        print(exc, file=sys.stderr)
        return 2
    except (OSError, ValueError) as exc:
        print(f"dsfd calibrate: {exc}", file=sys.stderr)
        return 2
    model = LumpedModel(model_config(cfg, steps.step_s))
    space = ParameterSpace.from_panel(model.cfg)
    print(f"dsfd calibrate — panel {cfg.panel.id}, off-line fit")
    print(f"data: {args.data} ({steps.n_steps} steps of {steps.step_s:g} s, "
          f"{iso_utc(steps.time_s[0])} to {iso_utc(steps.time_s[-1])})")
    for note in steps.notes:
        print(f"  note: {note}")
    bar = Progress("fitting")
    try:
        state, fit = offline_fit(model, steps, max_nfev=args.max_nfev, passes=args.passes,
                                 progress=lambda done, total, cost: bar(done, total,
                                                                        f"cost {cost:.4g}"))
    finally:
        bar.close()
    se = state.std_error(space)
    print(f"{fit.message} ({fit.nfev} residual and {fit.njev} Jacobian evaluations, "
          f"{fit.n_residuals} residuals, cost {fit.cost_start:.4g} -> {fit.cost:.4g})")
    print(f"{'parameter':<10}{'value':>12}{'std err':>12}{'default':>12}  fitted")
    for i, name in enumerate(FIT_NAMES):
        if space.fixed[i] and state.theta[i] == space.default[i] and name.startswith("q_"):
            continue
        print(f"{name:<10}{state.theta[i]:12.4g}{se[i]:12.3g}{space.default[i]:12.4g}  "
              f"{'yes' if fit.free[i] else 'no'}")
    write_params(args.out, state, space, provenance={
        "data": str(args.data), "start_utc": iso_utc(steps.time_s[0]),
        "end_utc": iso_utc(steps.time_s[-1]), "steps": steps.n_steps, "step_s": steps.step_s,
        "config": str(args.config)})
    print(f"wrote {args.out}")
    return 0
