"""``dsfd bench model``: speed of the lumped model's coupled step and horizon rollouts.

Timings use the monotonic performance counter and report medians over repetitions; run
on an idle machine (one core is used: numpy's small-matrix kernels are single-threaded).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from dsfd.config import load_panel
from dsfd.physics.forcing import FacadeOptics, OpticalLoads, facade_forcing, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.sim.openloop import first_step
from dsfd.sim.replay import at_site, load_weather, step_window, weather_inputs

DEFAULT_PANEL = Path(__file__).resolve().parents[2] / "config" / "panels" / "suwon-south.yaml"
HORIZON = 15


def _median_time(fn: Callable[[], object], repeats: int) -> float:
    fn()  # warm caches
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return float(np.median(samples))


def bench_model(panel: Path | None = None, *, repeats: int = 60) -> dict[str, float]:
    """Measure one coupled step and 15-step rollouts on a sunny winter noon (SURFRAD day)."""
    cfg = load_panel(panel or DEFAULT_PANEL)
    series = at_site(load_weather("surfrad-alamosa-2016-01-01"), cfg)
    start, n = step_window(series, cfg.model.step_s)
    w = weather_inputs(series, cfg, start_s=start, n_steps=n)
    forcing = facade_forcing(cfg, w)
    noon = int(np.argmax(forcing.beam_wm2))
    window = forcing.window(noon, noon + HORIZON)
    optics = FacadeOptics(cfg)
    model = LumpedModel(cfg)
    theta = model.default_theta()
    angles = np.radians(np.array(cfg.louver.angles_deg() if cfg.louver else (0.0,)))
    one = step_inputs(window, optics.loads(window, angles[5 % len(angles)]))
    x0 = model.steady_state([1], 1.0, first_step(one), theta)
    warm = model.rollout(x0, np.ones((1, HORIZON), int), np.ones((1, HORIZON)), one,
                         theta).x[:, 5]
    step_in = first_step(one)
    regimes = np.arange(1, 11)
    n_cand = len(angles) * len(regimes)
    loads_all = optics.loads(window, angles)  # (n_angles, 15, ...)
    batch_in = step_inputs(window, loads_all)
    batch_in = batch_in._replace(**{
        k: np.repeat(getattr(batch_in, k), len(regimes), axis=0)
        for k in OpticalLoads._fields})  # the fields that depend on the louver angle
    reg_b = np.tile(regimes, len(angles))[:, None].repeat(HORIZON, axis=1)
    t_step = _median_time(lambda: model.step(warm, [1], 1.0, step_in, theta), repeats * 5)
    t_h1 = _median_time(
        lambda: model.rollout(warm, np.ones((1, HORIZON), int), np.ones((1, HORIZON)), one,
                              theta), repeats)
    t_batch = _median_time(
        lambda: model.rollout(warm, reg_b, np.ones((n_cand, HORIZON)), batch_in, theta),
        max(5, repeats // 10))
    t_loads = _median_time(lambda: optics.loads(window, angles), repeats)
    return {
        "step_us_median": t_step * 1e6,
        "horizon15_ms_median": t_h1 * 1e3,
        "horizon15_batched_ms_per_rollout": t_batch * 1e3 / n_cand,
        "horizon15_batch_size": float(n_cand),
        "horizon15_batch_ms_total": t_batch * 1e3,
        "optics_loads_15x11_ms_median": t_loads * 1e3,
    }
