"""Random decision problems on real weather, for judging optimisers (tests and benchmarks).

Each case: a random 15-minute window of the bundled RMIS winter days (some shifted to
summer-like temperatures to exercise the cooling objective), a random plausible state
(the steady state of a random control, perturbed) and parameters drawn around the
panel's defaults.
"""

from __future__ import annotations

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.control.objective import is_heating
from dsfd.control.optimiser import ControlProblem
from dsfd.physics.forcing import FacadeOptics, Forcing, facade_forcing, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.sim.openloop import first_step
from dsfd.sim.replay import at_site, load_weather, step_window, weather_inputs

COOLING_SHIFT_K = 24.0
#: Beam on the façade [W/m2] above which a window counts as sunny.
SUNNY_BEAM_WM2 = 30.0


def day_forcing(cfg: PanelConfig, weather: str = "rmis-golden-2022-01") -> Forcing:
    """Façade boundary of the whole bundled weather file at the panel's site."""
    series = at_site(load_weather(weather), cfg)
    start, n = step_window(series, cfg.model.step_s)
    return facade_forcing(cfg, weather_inputs(series, cfg, start_s=start, n_steps=n))


def random_problems(cfg: PanelConfig, n: int, *, seed: int = 0, cooling_share: float = 0.3,
                    horizon: int | None = None, sunny: bool = False) -> list[ControlProblem]:
    """``n`` random decision problems (see module docstring); ``sunny``: only windows that
    start with more than :data:`SUNNY_BEAM_WM2` of beam on the façade."""
    rng = np.random.default_rng(seed)
    horizon = horizon or cfg.control.horizon_steps
    full = day_forcing(cfg)
    model = LumpedModel(cfg)
    optics = FacadeOptics(cfg)
    lo, hi = model.theta_bounds()
    default = model.default_theta()
    angles = cfg.louver.angles_deg() if cfg.louver is not None else (0.0,)
    regimes = cfg.openings.available_regimes()
    starts = np.arange(full.time_s.shape[0] - horizon)
    if sunny:
        starts = starts[full.beam_wm2[starts] > SUNNY_BEAM_WM2]
    out = []
    for _ in range(n):
        k = int(starts[rng.integers(0, starts.size)])
        win = full.window(k, k + horizon)
        if rng.random() < cooling_share:
            shift = COOLING_SHIFT_K
            win = win._replace(
                t_out_k=win.t_out_k + shift, t_rad_out_k=win.t_rad_out_k + shift,
                t_in_k=win.t_in_k + 2.0, t_mrt_k=win.t_mrt_k + 2.0)
        # Parameters: log-uniform between the default and a random point of the bounds.
        w = rng.uniform(0.0, 0.5, default.size)
        target = np.exp(rng.uniform(np.log(lo), np.log(hi)))
        theta = np.exp((1 - w) * np.log(default) + w * np.log(target))
        phi0 = float(rng.choice(angles))
        regime0 = int(rng.choice(regimes))
        or0 = float(rng.uniform(0.2, 1.0))
        inp = step_inputs(win, optics.loads(win, np.radians(phi0)))
        x0 = model.steady_state([regime0], or0, first_step(inp), theta)[0]
        x0 = x0 + rng.normal(0.0, 1.5, 6)
        out.append(ControlProblem(
            x0=x0, forcing=win, theta=theta,
            heating=is_heating(cfg.control, float(win.t_out_k[0])),
            previous_phi_deg=phi0, previous_afr=regime0, previous_or_pct=or0 * 100.0))
    return out
