"""``dsfd bench plant``: how fast the truth plant runs the daemon's cycle.

The daemon advances the plant by one step and reads every sensor, thousands of times. The
benchmark does exactly that over the bundled RMIS winter weather (3 days by default, paper
protocol, default options) and reports simulated seconds per wall second.
"""

from __future__ import annotations

import time

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.plant import Plant
from dsfd.sim.protocol import paper_protocol
from dsfd.sim.replay import at_site, load_weather, step_window

DEFAULT_WEATHER = "rmis-golden-2022-01"


def bench_plant(cfg: PanelConfig, *, days: float = 3.0, seed: int = 0,
                weather: str = DEFAULT_WEATHER, options: PlantOptions | None = None
                ) -> dict[str, float]:
    """Run ``days`` of 1-step cycles (advance + read_sensors) and time them.

    Returns
    -------
    dict
        Flat figures with units in the keys; ``sim_speedup_x`` = simulated s / wall s.
    """
    series = at_site(load_weather(weather), cfg)
    dt = float(cfg.model.step_s)
    start, n = step_window(series, dt, hours=24.0 * days)
    schedule = paper_protocol(cfg, seed=seed, start_s=start, duration_s=n * dt)
    options = options or PlantOptions()
    plant = Plant(cfg, options, seed=seed, weather_series=series)
    t_reset = time.perf_counter()
    plant.reset(start, command=schedule.at(start))
    t_reset = time.perf_counter() - t_reset
    adv = np.empty(n)
    read = np.empty(n)
    wall = time.perf_counter()
    for k in range(n):
        cmd = schedule.at(start + k * dt)
        if cmd != plant.command:
            plant.apply(cmd)
        t0 = time.perf_counter()
        plant.advance(dt)
        t1 = time.perf_counter()
        plant.read_sensors()
        adv[k] = t1 - t0
        read[k] = time.perf_counter() - t1
    wall = time.perf_counter() - wall
    eb = plant.energy_balance()
    simulated = n * dt
    return {
        "sim_speedup_x": simulated / wall,
        "simulated_s": simulated,
        "wall_s": wall,
        "reset_s": t_reset,
        "cycles": float(n),
        "step_s": dt,
        "advance_ms_mean": 1e3 * float(adv.mean()),
        "advance_ms_p99": 1e3 * float(np.percentile(adv, 99)),
        "advance_ms_max": 1e3 * float(adv.max()),
        "read_sensors_ms_mean": 1e3 * float(read.mean()),
        "rhs_evaluations": float(plant.stats.rhs_evaluations),
        "rhs_per_cycle": plant.stats.rhs_evaluations / n,
        "solver_steps_per_cycle": plant.stats.steps / n,
        "commands": float(len(schedule)),
        "n_segments": float(options.n_segments),
        "n_states": float(plant.model.nn),
        "energy_residual_rel": abs(eb["residual_j"]) / max(eb["scale_j"], 1e-9),
        "seed": float(seed),
    }
