"""``dsfd simulate --plant truth --controller ...``: closed-loop runs and their report.

The options live here so ``dsfd simulate`` stays an open-loop command with one branch to
this module; :mod:`dsfd.sim.closed_loop` does the work.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import tempfile
from pathlib import Path

import numpy as np

from dsfd.cli.progress import Progress
from dsfd.config.panel import PanelConfig
from dsfd.measured import iso_utc, parse_iso_utc
from dsfd.weather import WeatherSeries


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The closed-loop options of ``dsfd simulate``."""
    from dsfd.sim.choices import CALIBRATIONS, CONTROLLERS

    g = p.add_argument_group("closed loop (with --plant truth)")
    g.add_argument("--controller", choices=CONTROLLERS, default=None,
                   help="run calibration and control against the truth plant: the optimiser "
                   "(mpc), the paper's SQP (paper-sqp), the rule-based baseline (rule), one "
                   "fixed command (fixed: --phi-deg/--afr/--or-pct, default 0 deg, regime 10)"
                   ", the optimiser with perfect information (oracle), an offline reference "
                   "that plans by rollouts on the truth plant itself (plant-oracle), or mpc "
                   "given only the true weather, only the true state or only the plant's "
                   "parameters (mpc-true-weather, mpc-true-state, mpc-true-params)")
    g.add_argument("--calibration", choices=CALIBRATIONS, default="online",
                   help="on-line self-calibration (default), frozen --params (offline) or the "
                   "panel defaults (none)")
    g.add_argument("--params", type=Path, default=None,
                   help="parameters file of dsfd calibrate (for --calibration offline)")
    g.add_argument("--mode", choices=("heating", "cooling", "auto"), default=None,
                   help="override control.mode of the panel")
    g.add_argument("--room-c", type=float, default=None,
                   help="override the room air temperature room.t_in_c [degC]")
    g.add_argument("--t-out-offset-k", type=float, default=0.0,
                   help="add this to the measured outdoor air [K]: a synthetic warmer (or "
                   "colder) period on real irradiance; the report says so")
    g.add_argument("--start", default=None, help="UTC start, e.g. 2022-01-01T00:00:00Z")
    g.add_argument("--report", type=Path, default=None, metavar="OUT.html",
                   help="also write the run's dsfd report (the daemon's log of the closed loop, "
                   "with the plant's own heat); needs pip install 'dsfd[report]'")
    g.add_argument("--fidelity", choices=("full", "lumped"), default="full",
                   help="truth plant switches: full stratified plant (default) or its lumped "
                   "equivalent with realistic sensors and actuators (fast)")


def check(args: argparse.Namespace) -> str | None:
    """Why the closed-loop options cannot run, or None."""
    if args.controller is None:
        closed_only = ("params", "mode", "room_c", "start", "report")
        used = [n for n in closed_only if getattr(args, n) is not None]
        if used or args.t_out_offset_k or args.fidelity != "full":
            return "closed-loop options need --controller"
        return None
    if args.plant != "truth":
        return "--controller needs --plant truth"
    if args.csv is not None:
        return "--csv is for open-loop truth runs"
    if args.report is not None and args.controller == "fixed":
        return "--report needs a controller that runs the daemon's cycle (not fixed)"
    if args.report is not None:
        from dsfd.cli.report import report_available

        missing = report_available()
        if missing:
            return f"--report: {missing}"
    if args.calibration == "offline" and args.params is None \
            and args.controller not in ("fixed", "oracle", "plant-oracle"):
        return "--calibration offline needs --params PARAMS.yaml (made by dsfd calibrate)"
    return None


def panel_for_run(cfg: PanelConfig, args: argparse.Namespace) -> PanelConfig:
    """The panel with the run's overrides of mode and room temperature."""
    if args.mode is not None:
        cfg = dataclasses.replace(cfg, control=dataclasses.replace(cfg.control, mode=args.mode))
    if args.room_c is not None:
        cfg = dataclasses.replace(cfg, room=dataclasses.replace(cfg.room, t_in_c=args.room_c))
    return cfg


def shifted(series: WeatherSeries, offset_k: float) -> WeatherSeries:
    """``series`` with the outdoor air shifted by ``offset_k`` [K] (noted in the series)."""
    if not offset_k:
        return series
    note = f"SYNTHETIC: measured outdoor air shifted by {offset_k:+g} K"
    return dataclasses.replace(series, t_out_c=series.t_out_c + offset_k,
                               notes=(*series.notes, note))


def run(args: argparse.Namespace, cfg: PanelConfig, series: WeatherSeries,
        hours: float | None) -> int:
    from dsfd.estimation.params import ParameterSpace
    from dsfd.sim.closed_loop import DEFAULT_FIXED, ClosedLoopSettings, run_closed_loop
    from dsfd.sim.plant.actuators import Command
    from dsfd.sim.plant.config import PlantOptions
    from dsfd.storage.calibration_file import read_params

    cfg = panel_for_run(cfg, args)
    series = shifted(series, args.t_out_offset_k)
    offline = None
    if args.params is not None:
        offline = read_params(args.params, space=ParameterSpace.from_panel(cfg),
                              panel_id=cfg.panel.id)
    fixed = Command(DEFAULT_FIXED.phi_deg if args.phi_deg is None else args.phi_deg,
                    DEFAULT_FIXED.afr if args.afr is None else args.afr,
                    DEFAULT_FIXED.or_pct if args.or_pct is None else args.or_pct)
    options = (PlantOptions.lumped_equivalent(cfg.model, sensors="realistic",
                                                actuators="realistic")
               if args.fidelity == "lumped" else None)
    settings = ClosedLoopSettings(
        controller=args.controller, calibration=args.calibration, seed=args.seed, hours=hours,
        start_s=None if args.start is None else parse_iso_utc(args.start),
        offline_theta=offline, fixed_command=fixed, options=options)
    bar = Progress("closed loop, cycles")
    with tempfile.TemporaryDirectory(prefix="dsfd-closed-loop-") as tmp:
        result = run_closed_loop(cfg, series, settings, progress=bar, state_dir=Path(tmp))
        if args.report is not None:
            write_closed_loop_report(Path(tmp), cfg, args.report)
    s = result.summary()
    end = result.start_s + result.cycles * result.step_s
    print(f"dsfd simulate — panel {cfg.panel.id}, truth plant (seed {args.seed}), closed loop: "
          f"controller {args.controller}, calibration {args.calibration}")
    print(f"weather: {series.source}")
    for note in series.notes:
        print(f"  {note}")
    print(f"period: {iso_utc(result.start_s)} to {iso_utc(end)} ({result.cycles} cycles of "
          f"{result.step_s:g} s); mode {cfg.control.mode}, heating in "
          f"{s['heating_fraction']:.0%} of cycles; room {cfg.room.t_in_c:g} degC")
    print()
    print("heat into the room [kWh] (docs/model.md#room-heat; Q_air by "
          f"{cfg.model.q_air_basis}):")
    for key, label in (("q_cv_rd", "Q_cv,rd  inner pane"), ("q_sol_trans", "Q_sol    transmitted"),
                       ("q_air", "Q_air    cavity air"), ("q_da", "Q_DA     daylight")):
        print(f"  {label:<24}{s[key + '_kwh']:10.3f}")
    print(f"  {'J (objective, Eq. 4-5)':<24}{s['J_kwh']:10.3f}")
    print()
    print(f"louver moves per day: {s['louver_moves_per_day']:.1f}")
    print("regime share: " + ", ".join(f"{r}: {v:.0%}" for r, v in s["regime_share"].items()))
    print("decisions: " + ", ".join(f"{m} {n}" for m, n in s["methods"].items()))
    if np.isfinite(s["decide_ms_median"]):
        print(f"decision time: median {s['decide_ms_median']:.1f} ms, "
              f"p99 {s['decide_ms_p99']:.1f} ms")
    print("by sky condition (cf. the paper's Figure 11):")
    for name, row in s["by_condition"].items():
        shares = ", ".join(f"{r}: {v:.0%}" for r, v in row["regime_share"].items())
        corr = row.get("phi_vs_elevation_corr")
        extra = "" if corr is None else f"; louver vs solar elevation r = {corr:+.2f}"
        print(f"  {name:<9}{row['cycles']:6d} cycles, mean louver {row['phi_deg_mean']:+6.1f} "
              f"deg; regimes {shares}{extra}")
    print(f"calibration updates: {s['calibration_updates']}")
    for line in comfort_lines(s["comfort"], scheduled=cfg.occupancy is not None):
        print(line)
    print(f"wall time: {s['wall_s']:.1f} s")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        doc = {**s, "weather": {"source": series.source, "notes": list(series.notes)},
               "mode": cfg.control.mode, "room_c": cfg.room.t_in_c,
               "start_utc": iso_utc(result.start_s)}
        args.json.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {args.json}")
    return 0


def comfort_lines(c: dict, *, scheduled: bool) -> list[str]:
    """The comfort figures of a closed-loop summary (``summary()["comfort"]``) as text."""
    head = "comfort on the plant while occupied (docs/model.md#plant-comfort):"
    if not scheduled:
        return [head, "  the panel has no occupancy: schedule: never occupied, nothing judged"]
    if not c.get("occupied_min"):
        return [head, "  no occupied minute in the run"]
    return [head,
            f"  occupied {c['occupied_min']:.0f} min; direct sun above "
            f"{c['direct_sun_limit_wm2']:g} W/m2: {c['direct_sun_min']:.0f} min",
            f"  DGPs p50 {c['dgp_p50']:.2f}, p95 {c['dgp_p95']:.2f}, max {c['dgp_max']:.2f}; "
            f"above {c['dgp_limit']:g} in {c['dgp_above_limit_share']:.0%} of occupied minutes",
            f"  cavity air into the room {c['supply_air_in_min']:.0f} min"
            + (f" (coldest {c['supply_air_coldest_c']:.1f} degC)" if c["supply_air_in_min"]
               else "") + "; below the supply limit "
            f"{c['supply_air_limit_c']:.1f} degC: {c['supply_air_below_min']:.0f} min",
            f"  radiant asymmetry beyond "
            f"{c['asymmetry_limit_warm_k']:g} K warm / {c['asymmetry_limit_cool_k']:g} K cool: "
            f"{c['asymmetry_beyond_min']:.0f} min"]


def write_closed_loop_report(state_dir: Path, cfg: PanelConfig, out: Path) -> None:
    """The dsfd report of a closed loop's state directory, written to ``out``."""
    from dsfd.report import build_report, write_report
    from dsfd.storage.history import read_history

    report = build_report(read_history(state_dir), panel=cfg)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_report(report, out)
    print(f"wrote {out} (dsfd report of the {len(report.history)} cycles)")
