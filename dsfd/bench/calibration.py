"""``dsfd bench calibration``: time of one on-line self-calibration update.

The case: a 4 h window of 1-minute data (240 steps) produced by the lumped model with
parameters away from the defaults plus thermocouple-like noise, regimes 1, 3, 5, 6 and 10
and random louver angles, so all 9 parameters of the paper are free. Each repetition is
one :meth:`OnlineCalibrator.update` from the same prior (the panel defaults), i.e. the
worst case of a fresh start where the fit runs to ``max_nfev``. Wall time by the monotonic
performance counter; run on an idle machine (numpy's small-matrix kernels use one core).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import Param
from dsfd.estimation.calibration import OnlineCalibrator
from dsfd.estimation.observer import observe
from dsfd.estimation.stepdata import StepData
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, facade_forcing, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.sim.replay import at_site, load_weather, step_window, weather_inputs

WINDOW_H = 4.0
STEP_S = 60.0
TRUE_FACTORS = np.array([1.4, 0.8, 1.3, 1.25, 0.9, 1.2, 1.5, 0.7, 1.08])


def synthetic_window(cfg: PanelConfig, *, seed: int = 0, hours: float = WINDOW_H,
                     noise_k: float = 0.2, noise_v: float = 0.01) -> tuple[StepData, np.ndarray]:
    """A window of lumped-model data around noon on RMIS weather (StepData, true θ)."""
    rng = np.random.default_rng(seed)
    cfg = dataclasses.replace(cfg, model=dataclasses.replace(cfg.model, step_s=STEP_S))
    series = at_site(load_weather("rmis-golden-2022-01"), cfg)
    first, _ = step_window(series, STEP_S)
    start = first + 86400.0 + 10.0 * 3600.0
    n = round(hours * 3600.0 / STEP_S)
    w = weather_inputs(series, cfg, start_s=start, n_steps=n)
    forcing = facade_forcing(cfg, w)
    block = 30
    regimes = [r for r in (1, 3, 5, 6, 10) if r in cfg.openings.available_regimes()]
    reg = np.repeat(rng.choice(regimes, -(-n // block)), block)[:n]
    reg[: len(regimes) * block] = np.repeat(regimes, block)[:n]
    phi = np.repeat(rng.choice(np.arange(-90.0, 91.0, 18.0), -(-n // block)), block)[:n]
    if cfg.louver is None:
        phi[:] = 0.0
    column = Forcing(*(np.asarray(v)[:, None] for v in forcing))
    inp = step_inputs(column, FacadeOptics(cfg).loads(column, np.radians(phi)))
    inp = StepInputs(*(np.asarray(v)[:, 0] for v in inp))
    model = LumpedModel(cfg)
    theta = model.default_theta() * TRUE_FACTORS
    theta[Param.N] = min(theta[Param.N], cfg.parameters.n.upper)
    x0 = model.steady_state([reg[0]], 1.0, inp.at((slice(0, 1),)), theta)
    tr = model.rollout(x0, reg[None], np.ones((1, n)), inp, theta)
    y = tr.x[0, :, :5] + noise_k * rng.standard_normal((n + 1, 5))
    v = np.abs(np.concatenate([[0.0], tr.v_cav_ms[0]]) + noise_v * rng.standard_normal(n + 1))
    steps = StepData(time_s=start + STEP_S * np.arange(n + 1), step_s=STEP_S,
                     valid=np.ones(n, bool), regime=reg, or_=np.ones(n), phi_rad=np.radians(phi),
                     inputs=inp, y_k=y, v_ms=v, present=("x1", "x2", "x3", "x4", "x5", "v"))
    return steps, theta


def bench_calibration(cfg: PanelConfig, *, repeats: int = 7, seed: int = 0) -> dict[str, float]:
    """Median and maximum wall time of one on-line update (see module docstring)."""
    cal9 = dataclasses.replace(cfg.calibration, heat_offsets=False)
    cfg = dataclasses.replace(cfg, calibration=cal9,
                              model=dataclasses.replace(cfg.model, step_s=STEP_S))
    steps, _ = synthetic_window(cfg, seed=seed)
    model = LumpedModel(cfg)
    track = observe(model, steps, model.default_theta()[None])
    x_hat, x_pred = track.x_hat[0], track.x_pred[0]

    def one(settings) -> tuple[float, int, int, int]:
        cal = OnlineCalibrator(model, settings)
        t0 = time.perf_counter()
        rep = cal.update(steps, x_hat, x_pred)
        dt = time.perf_counter() - t0
        fit = rep.fit
        return dt, (fit.nfev if fit else 0), int(fit.free.sum()) if fit else 0, (
            fit.n_residuals if fit else 0)

    one(cal9)  # warm caches
    runs = [one(cal9) for _ in range(repeats)]
    with_q = dataclasses.replace(cfg.calibration, heat_offsets=True)
    runs_q = [one(with_q) for _ in range(max(3, repeats // 2))]
    times = np.array([r[0] for r in runs])
    times_q = np.array([r[0] for r in runs_q])
    return {
        "update_s_median": float(np.median(times)),
        "update_s_max": float(np.max(times)),
        "free_parameters": float(runs[0][2]),
        "residuals": float(runs[0][3]),
        "nfev_median": float(np.median([r[1] for r in runs])),
        "max_nfev": float(cfg.calibration.max_nfev),
        "window_steps": float(steps.n_steps),
        "update_with_offsets_s_median": float(np.median(times_q)),
        "update_with_offsets_s_max": float(np.max(times_q)),
        "free_parameters_with_offsets": float(runs_q[0][2]),
    }
