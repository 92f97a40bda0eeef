"""Open-loop runs of the truth plant (``dsfd simulate --plant truth``) and their summary.

A run samples the plant every model step like the real data logger: at each row time the
sensors are read, then the command in force from that time on is applied (fixed controls
or the paper protocol), then the plant advances one step. Rows become a
:class:`~dsfd.measured.MeasuredData` with the ``truth_*`` extras.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.measured import MeasuredData
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.config import PlantOptions, TrueParameters
from dsfd.sim.plant.plant import Plant
from dsfd.sim.plant.sensors import SensorConfig
from dsfd.sim.protocol import Schedule, paper_protocol
from dsfd.sim.replay import at_site, step_window
from dsfd.weather import WeatherSeries

CONTROL_KEYS = ("phi_deg", "afr", "or_pct")


@dataclass(frozen=True)
class TruthRun:
    """Result of an open-loop truth-plant run."""

    cfg: PanelConfig
    plant: Plant
    series: WeatherSeries
    schedule: Schedule
    data: MeasuredData
    start_s: float
    steps: int
    wall_s: float
    protocol: bool

    @property
    def step_s(self) -> float:
        return float(self.cfg.model.step_s)


def run_truth(cfg: PanelConfig, series: WeatherSeries, *, seed: int,
              options: PlantOptions | None = None, hours: float | None = None,
              command: Command | None = None, or_pct: float = 100.0,
              start_s: float | None = None, params: TrueParameters | None = None,
              sensors: SensorConfig | None = None) -> TruthRun:
    """Run the truth plant over the weather window with fixed controls or the protocol.

    Parameters
    ----------
    cfg : PanelConfig
    series : WeatherSeries
    seed : int
        Plant (true parameters, sensors) and protocol seed.
    options : PlantOptions, optional
    hours : float, optional
        Simulated duration (default: all the weather).
    command : Command, optional
        Fixed controls; default the paper protocol (:func:`paper_protocol`) at ``or_pct``.
    start_s : float, optional, [s]
        UTC start (default: the first whole minute of the weather at the site).
    params, sensors : optional
        Override the seeded true parameters / the sensor configuration.
    """
    site = at_site(series, cfg)
    dt = float(cfg.model.step_s)
    start, n = step_window(site, dt, start_s=start_s, hours=hours)
    if command is None:
        schedule = paper_protocol(cfg, seed=seed, start_s=start, duration_s=n * dt,
                                  or_pct=or_pct)
    else:
        schedule = Schedule((start,), (command,))
    plant = Plant(cfg, options, seed=seed, weather_series=site, params=params, sensors=sensors)
    plant.reset(start, command=schedule.at(start))
    rows: dict[str, list[float]] = {}
    times = start + np.arange(n + 1) * dt
    wall = time.perf_counter()
    for j, t in enumerate(times):
        cmd = schedule.at(float(t))
        if cmd != plant.command:
            cmd = plant.apply(cmd)
        row = {**plant.command.as_dict(), **plant.read_sensors(),
               **plant.true_state().truth_columns()}
        for key, value in row.items():
            rows.setdefault(key, []).append(float(value))
        if j < n:
            plant.advance(dt)
    wall = time.perf_counter() - wall
    p = plant.params
    notes = (
        f"simulated truth plant (dsfd.sim), panel {cfg.panel.id}, seed {seed}",
        f"weather {series.source}" + (f"; {site.notes[-1]}" if site.notes else ""),
        "controls: " + ("paper protocol (random louver angle and regime every 30-90 min)"
                        if command is None else f"fixed {command.as_dict()}"),
        "true parameters: h multipliers " + ", ".join(f"{m:.3f}" for m in p.h_multipliers)
        + f"; f_true {p.f:.1f}",
    )
    columns = {k: np.asarray(v, float) for k, v in rows.items()}
    data = MeasuredData(times, columns, source="dsfd simulate --plant truth", notes=notes)
    return TruthRun(cfg, plant, site, schedule, data, start, n, wall, command is None)


def velocity_table(data: MeasuredData) -> dict[int, dict[str, float]]:
    """Mean cavity speed per commanded regime [m/s]: anemometer and true (|v|), and count.

    Rows are attributed to the regime commanded in the previous row (the one the plant ran
    in up to the row's time).
    """
    afr = data.get("afr")[:-1]
    measured = data.get("v_cav_ms")[1:]
    true = np.abs(data.get("truth_v_cav_ms")[1:])
    out = {}
    for r in sorted({int(a) for a in afr if np.isfinite(a)}):
        sel = afr == r
        out[r] = {"anemometer_ms": float(np.nanmean(measured[sel])),
                  "true_ms": float(np.nanmean(true[sel])), "samples": int(sel.sum())}
    return out


def summarize_truth(run: TruthRun) -> dict:
    """Figures of a truth run in engineering units, JSON-ready (flat where possible)."""
    d = run.data
    eb = run.plant.energy_balance()
    simulated = run.steps * run.step_s
    labels, counts = np.unique(d.get("truth_label")[:-1].astype(int), return_counts=True)
    states = {}
    for i in range(1, 6):
        col = d.get(f"x{i}_c")
        states[f"x{i}"] = {"min": float(np.nanmin(col)), "mean": float(np.nanmean(col)),
                           "max": float(np.nanmax(col))}
    return {
        "states_c": states,
        "velocity_by_regime": {str(k): v for k, v in velocity_table(d).items()},
        "realised_regimes": {str(int(k)): int(c) for k, c in zip(labels, counts, strict=True)},
        "energy_balance": {**eb, "residual_rel": abs(eb["residual_j"]) / max(eb["scale_j"],
                                                                          1e-9)},
        "commands": len(run.schedule),
        "steps": run.steps,
        "step_s": run.step_s,
        "simulated_s": simulated,
        "wall_s": run.wall_s,
        "sim_speedup_x": simulated / max(run.wall_s, 1e-9),
        "true_parameters": {"h_multipliers": list(run.plant.params.h_multipliers),
                            "f": run.plant.params.f},
    }
