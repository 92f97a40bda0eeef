"""``dsfd simulate``: open-loop runs of the lumped model or the stratified truth plant, and
closed-loop runs of a controller against the truth plant (:mod:`dsfd.cli.closed_loop`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from dsfd.cli import closed_loop
from dsfd.config import ConfigError, load_panel
from dsfd.measured import iso_utc
from dsfd.sim.replay import load_weather

DEFAULT_WEATHER = "rmis-golden-2022-01"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="open-loop simulation on replayed weather",
                       description="Run the lumped model (default) or the truth plant with "
                       "fixed louver angle, regime and damper opening over a weather file "
                       "and print a summary. The truth plant without explicit controls "
                       "follows the paper's protocol (random angle and regime every "
                       "30-90 min).")
    p.add_argument("--config", required=True, type=Path, help="panel YAML")
    p.add_argument("--plant", choices=("lumped", "truth"), default="lumped",
                   help="lumped model (default) or the stratified truth plant")
    p.add_argument("--weather", default=DEFAULT_WEATHER,
                   help=f"weather file or bundled name (default {DEFAULT_WEATHER})")
    p.add_argument("--phi-deg", type=float, default=None, help="louver angle [deg] (0)")
    p.add_argument("--afr", type=int, default=None, help="airflow regime 1..10 (1)")
    p.add_argument("--or-pct", type=float, default=None, help="damper opening [%%] (100)")
    p.add_argument("--hours", type=float, default=None, help="simulate only this many hours")
    p.add_argument("--days", type=float, default=None, help="simulate this many days")
    p.add_argument("--seed", type=int, default=0,
                   help="truth plant: seed of its parameters, sensors and protocol")
    p.add_argument("--csv", type=Path, default=None,
                   help="truth plant: write the measured-data CSV (sensors, controls, "
                   "weather, truth_* columns)")
    p.add_argument("--json", type=Path, default=None, help="write figures and series as JSON")
    closed_loop.add_arguments(p)
    p.set_defaults(handler=run)


def _check(args: argparse.Namespace) -> str | None:
    if args.phi_deg is not None and not -90.0 <= args.phi_deg <= 90.0:
        return f"--phi-deg {args.phi_deg}: must lie in -90..90"
    if args.afr is not None and not 1 <= args.afr <= 10:
        return f"--afr {args.afr}: must be an airflow regime 1..10"
    if args.or_pct is not None and not 0.0 <= args.or_pct <= 100.0:
        return f"--or-pct {args.or_pct}: must lie in 0..100"
    if args.hours is not None and args.days is not None:
        return "give --hours or --days, not both"
    for name in ("hours", "days"):
        value = getattr(args, name)
        if value is not None and not value > 0:
            return f"--{name} {value}: must be positive"
    if args.csv is not None and args.plant != "truth":
        return "--csv needs --plant truth"
    return closed_loop.check(args)


def run(args: argparse.Namespace) -> int:
    problem = _check(args)
    if problem:
        print(f"dsfd simulate: {problem}", file=sys.stderr)
        return 2
    hours = args.hours if args.days is None else 24.0 * args.days
    try:
        cfg = load_panel(args.config)
        series = load_weather(args.weather)
        if args.controller is not None:
            return closed_loop.run(args, cfg, series, hours)
        if args.plant == "truth":
            return _run_truth(args, cfg, series, hours)
        return _run_lumped(args, cfg, series, hours)
    except ConfigError as exc:
        print(exc, file=sys.stderr)
        return 2
    except (FileNotFoundError, ValueError) as exc:
        print(f"dsfd simulate: {exc}", file=sys.stderr)
        return 2


def _print_weather(series) -> None:
    print(f"weather: {series.source}")
    for note in series.notes:
        print(f"  note: {note}")
    if series.attribution:
        print(f"  data: {series.attribution}")


def _write_json(path: Path, doc: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=1))
    print(f"wrote {path}")


def _run_lumped(args: argparse.Namespace, cfg, series, hours: float | None) -> int:
    from dsfd.sim.openloop import STATE_NAMES, run_lumped, series_table, summarize

    phi = 0.0 if args.phi_deg is None else args.phi_deg
    afr = 1 if args.afr is None else args.afr
    or_pct = 100.0 if args.or_pct is None else args.or_pct
    result = run_lumped(cfg, series, phi_deg=phi, afr=afr, or_pct=or_pct, hours=hours)
    s = summarize(result)
    n = s["steps"]
    end = result.start_s + n * result.step_s
    print(f"dsfd simulate — panel {cfg.panel.id}, lumped model, open loop")
    _print_weather(result.series)
    print(f"period: {iso_utc(result.start_s)} to {iso_utc(end)} ({n} steps of "
          f"{result.step_s:g} s)")
    print(f"controls: louver {phi:g} deg, regime {afr}, dampers {or_pct:g} %")
    print()
    print(f"{'state':<22}{'min':>8}{'mean':>8}{'max':>8}  [degC]")
    for i, name in enumerate(STATE_NAMES):
        st = s["states_c"][f"x{i + 1}"]
        print(f"{name:<22}{st['min']:8.1f}{st['mean']:8.1f}{st['max']:8.1f}")
    v = s["v_cav_ms"]
    print(f"{'cavity velocity |v|':<22}{'':8}{v['mean_abs'] * 100:8.2f}"
          f"{v['max_abs'] * 100:8.2f}  [cm/s]")
    print()
    e = s["energy"]
    print("heat into the room over the period [kWh]:")
    for label, key in (("Q_cv,rd (inner pane)", "q_cv_rd_kwh"),
                       ("Q_sol,trans (solar)", "q_sol_trans_kwh"),
                       ("Q_air (cavity air)", "q_air_kwh"), ("Q_DA (daylight)", "q_da_kwh"),
                       ("J_heat (Eq. 4)", "j_heat_kwh"), ("J_cool (Eq. 5)", "j_cool_kwh")):
        print(f"  {label:<24}{e[key]:10.3f}")
    print(f"realised regimes (steps): {s['realised_regimes']}")
    print(f"energy balance residual: {s['energy_balance']['residual_rel']:.2e} "
          "(relative to the boundary heat flows)")
    if args.json:
        _write_json(args.json, {
            "panel": cfg.panel.id, "model": "lumped",
            "weather": {"source": result.series.source, "notes": list(result.series.notes),
                        "attribution": result.series.attribution},
            "controls": result.controls, "summary": s, "series": series_table(result)})
    return 0


def _run_truth(args: argparse.Namespace, cfg, series, hours: float | None) -> int:
    from dsfd.sim.plant.actuators import Command, CommandError
    from dsfd.sim.truth_run import run_truth, summarize_truth
    from dsfd.storage.measured_csv import write_measured

    explicit = args.phi_deg is not None or args.afr is not None
    or_pct = 100.0 if args.or_pct is None else args.or_pct
    command = (Command(0.0 if args.phi_deg is None else args.phi_deg,
                       1 if args.afr is None else args.afr, or_pct) if explicit else None)
    try:
        result = run_truth(cfg, series, seed=args.seed, hours=hours, command=command,
                           or_pct=or_pct)
    except CommandError as exc:
        print(f"dsfd simulate: {exc}", file=sys.stderr)
        return 2
    s = summarize_truth(result)
    end = result.start_s + result.steps * result.step_s
    print(f"dsfd simulate — panel {cfg.panel.id}, truth plant (seed {args.seed}), open loop")
    _print_weather(result.series)
    print(f"period: {iso_utc(result.start_s)} to {iso_utc(end)} ({result.steps} steps of "
          f"{result.step_s:g} s)")
    if command is None:
        print(f"controls: paper protocol, {s['commands']} random settings, dampers "
              f"{or_pct:g} %")
    else:
        print(f"controls: louver {command.phi_deg:g} deg, regime {command.afr}, dampers "
              f"{command.or_pct:g} %")
    tp = s["true_parameters"]
    print("true parameters: h multipliers "
          + " ".join(f"{m:.2f}" for m in tp["h_multipliers"]) + f", f_true {tp['f']:.1f}")
    print()
    print(f"{'sensor (mid-height)':<22}{'min':>8}{'mean':>8}{'max':>8}  [degC]")
    for i in range(1, 6):
        st = s["states_c"][f"x{i}"]
        print(f"{'x' + str(i):<22}{st['min']:8.1f}{st['mean']:8.1f}{st['max']:8.1f}")
    print()
    print("mean cavity velocity per commanded regime [cm/s]:")
    print(f"  {'regime':>6}{'anemometer':>12}{'true |v|':>10}{'minutes':>9}")
    for regime, row in s["velocity_by_regime"].items():
        print(f"  {regime:>6}{row['anemometer_ms'] * 100:12.2f}{row['true_ms'] * 100:10.2f}"
              f"{row['samples']:9d}")
    print(f"realised regimes (steps): {s['realised_regimes']}")
    print(f"energy balance residual: {s['energy_balance']['residual_rel']:.2e} "
          "(relative to max(absorbed solar, boundary flows))")
    print(f"speed: {s['sim_speedup_x']:.0f} simulated s per wall s")
    if args.csv:
        write_measured(result.data, args.csv)
        print(f"wrote {args.csv}")
    if args.json:
        d = result.data
        series_doc = {"time_utc": [iso_utc(float(t)) for t in d.time_s]}
        series_doc.update({k: [None if v != v else round(float(v), 5) for v in col]
                           for k, col in d.columns.items()})
        _write_json(args.json, {
            "panel": cfg.panel.id, "model": "truth", "seed": args.seed,
            "weather": {"source": result.series.source, "notes": list(result.series.notes),
                        "attribution": result.series.attribution},
            "controls": "paper_protocol" if command is None else command.as_dict(),
            "summary": s, "series": series_doc})
    return 0
