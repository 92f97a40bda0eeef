"""``dsfd simulate``: open-loop runs of the lumped model (and the truth plant, later)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from dsfd.config import ConfigError, load_panel
from dsfd.measured import iso_utc
from dsfd.sim.replay import load_weather

DEFAULT_WEATHER = "rmis-golden-2022-01"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="open-loop simulation on replayed weather",
                       description="Run the lumped model with fixed louver angle, regime and "
                       "damper opening over a weather file and print a summary.")
    p.add_argument("--config", required=True, type=Path, help="panel YAML")
    p.add_argument("--weather", default=DEFAULT_WEATHER,
                   help=f"weather file or bundled name (default {DEFAULT_WEATHER})")
    p.add_argument("--phi-deg", type=float, default=0.0, help="louver angle [deg]")
    p.add_argument("--afr", type=int, default=1, help="airflow regime 1..10")
    p.add_argument("--or-pct", type=float, default=100.0, help="damper opening [%%]")
    p.add_argument("--hours", type=float, default=None, help="simulate only this many hours")
    p.add_argument("--json", type=Path, default=None, help="write figures and series as JSON")
    p.set_defaults(handler=run)


def _check_controls(args: argparse.Namespace) -> str | None:
    if not -90.0 <= args.phi_deg <= 90.0:
        return f"--phi-deg {args.phi_deg}: must lie in -90..90"
    if not 1 <= args.afr <= 10:
        return f"--afr {args.afr}: must be an airflow regime 1..10"
    if not 0.0 <= args.or_pct <= 100.0:
        return f"--or-pct {args.or_pct}: must lie in 0..100"
    return None


def run(args: argparse.Namespace) -> int:
    from dsfd.sim.openloop import STATE_NAMES, run_lumped, series_table, summarize

    problem = _check_controls(args)
    if problem:
        print(f"dsfd simulate: {problem}", file=sys.stderr)
        return 2
    try:
        cfg = load_panel(args.config)
        series = load_weather(args.weather)
        result = run_lumped(cfg, series, phi_deg=args.phi_deg, afr=args.afr,
                            or_pct=args.or_pct, hours=args.hours)
    except ConfigError as exc:
        print(exc, file=sys.stderr)
        return 2
    except (FileNotFoundError, ValueError) as exc:
        print(f"dsfd simulate: {exc}", file=sys.stderr)
        return 2
    s = summarize(result)
    n = s["steps"]
    end = result.start_s + n * result.step_s
    print(f"dsfd simulate — panel {cfg.panel.id}, lumped model, open loop")
    print(f"weather: {result.series.source}")
    for note in result.series.notes:
        print(f"  note: {note}")
    if result.series.attribution:
        print(f"  data: {result.series.attribution}")
    print(f"period: {iso_utc(result.start_s)} to {iso_utc(end)} ({n} steps of "
          f"{result.step_s:g} s)")
    print(f"controls: louver {args.phi_deg:g} deg, regime {args.afr}, dampers "
          f"{args.or_pct:g} %")
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
        doc = {"panel": cfg.panel.id, "model": "lumped",
               "weather": {"source": result.series.source, "notes": list(result.series.notes),
                           "attribution": result.series.attribution},
               "controls": result.controls, "summary": s, "series": series_table(result)}
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(doc, indent=1))
        print(f"wrote {args.json}")
    return 0
