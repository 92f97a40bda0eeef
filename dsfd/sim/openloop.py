"""Open-loop runs of the lumped model on replayed weather (``dsfd simulate``).

Fixed controls, the whole weather window, the steady state of the first step as initial
condition (docs/model.md#initial-state), and a summary in engineering units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.physics.constants import T_ZERO
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, facade_forcing, step_inputs
from dsfd.physics.model import LumpedModel, Trajectory
from dsfd.sim.replay import at_site, step_window, weather_inputs
from dsfd.weather import WeatherSeries

STATE_NAMES = ("x1 exterior pane", "x2 DGU outer pane", "x3 DGU inner pane", "x4 louver",
               "x5 cavity air", "x6 DGU gap gas")
J_PER_KWH = 3.6e6


@dataclass(frozen=True)
class LumpedRun:
    """Result of an open-loop lumped run."""

    cfg: PanelConfig
    series: WeatherSeries
    start_s: float
    forcing: Forcing
    trajectory: Trajectory
    controls: dict[str, float]

    @property
    def step_s(self) -> float:
        return self.cfg.model.step_s


def first_step(inputs: StepInputs) -> StepInputs:
    """The inputs of step 0 of a horizon of per-step arrays (trailing vector axes kept)."""
    out = []
    for name, v in zip(inputs._fields, inputs, strict=True):
        v = np.asarray(v, float)
        vector = name in ("sources", "lw_exchange")
        out.append(v[..., :1, :] if vector else v[..., :1])
    return StepInputs(*out)


def run_lumped(cfg: PanelConfig, series: WeatherSeries, *, phi_deg: float, afr: int,
               or_pct: float, hours: float | None = None) -> LumpedRun:
    """Simulate the panel with fixed controls over the weather window."""
    if afr not in cfg.openings.available_regimes():
        raise ValueError(f"regime {afr} needs dampers this panel does not have "
                         f"(available: {cfg.openings.available_regimes()})")
    series = at_site(series, cfg)
    start, n = step_window(series, cfg.model.step_s, hours=hours)
    w = weather_inputs(series, cfg, start_s=start, n_steps=n)
    forcing = facade_forcing(cfg, w)
    loads = FacadeOptics(cfg).loads(forcing, np.radians(phi_deg))
    inputs = step_inputs(forcing, loads)
    model = LumpedModel(cfg)
    theta = model.default_theta()
    or_ = or_pct / 100.0
    x0 = model.steady_state([afr], or_, first_step(inputs), theta)
    traj = model.rollout(x0, np.full((1, n), afr), np.full((1, n), or_), inputs, theta)
    return LumpedRun(cfg, series, start, forcing, traj,
                     {"phi_deg": phi_deg, "afr": afr, "or_pct": or_pct})


def summarize(run: LumpedRun) -> dict:
    """Figures of a run in engineering units (°C, m/s, kWh), JSON-ready."""
    tr = run.trajectory
    x_c = tr.x[0] - T_ZERO
    dt = run.step_s
    energy = {
        name: float(np.sum(getattr(tr, key)[0]) * dt / J_PER_KWH)
        for name, key in (("q_cv_rd_kwh", "q_cv_rd_w"), ("q_sol_trans_kwh", "q_sol_w"),
                          ("q_air_kwh", "q_air_w"), ("q_da_kwh", "q_da_w"))
    }
    total = energy["q_cv_rd_kwh"] + energy["q_sol_trans_kwh"] + energy["q_air_kwh"]
    area = run.cfg.facade.width_m * run.cfg.facade.glazed_height_m
    stored = float((tr.x[0, -1] - tr.x[0, 0]) @ LumpedModel(run.cfg).capacity) * area
    boundary = float(np.sum(tr.heat_in_wm2[0]) * dt) * area
    scale = float(np.sum(np.abs(tr.heat_in_wm2[0])) * dt) * area
    labels, counts = np.unique(tr.label[0], return_counts=True)
    return {
        "states_c": {
            f"x{i + 1}": {"min": float(x_c[:, i].min()), "mean": float(x_c[:, i].mean()),
                          "max": float(x_c[:, i].max())}
            for i in range(6)
        },
        "v_cav_ms": {"mean_abs": float(np.mean(np.abs(tr.v_cav_ms[0]))),
                     "max_abs": float(np.max(np.abs(tr.v_cav_ms[0])))},
        "energy": {**energy,
                   "j_heat_kwh": -(total + energy["q_da_kwh"]),
                   "j_cool_kwh": total - energy["q_da_kwh"]},
        "energy_balance": {"stored_j": stored, "boundary_j": boundary,
                           "residual_rel": abs(stored - boundary) / max(scale, 1e-9)},
        "realised_regimes": {str(int(k)): int(c) for k, c in zip(labels, counts, strict=True)},
        "weather": {"t_out_c_mean": float(np.mean(run.forcing.t_out_k) - T_ZERO),
                    "facade_irradiation_kwh_m2": float(
                        np.sum(run.forcing.beam_wm2 + run.forcing.diffuse_wm2) * dt / J_PER_KWH)},
        "steps": int(tr.label.shape[1]),
        "step_s": dt,
    }


def series_table(run: LumpedRun) -> dict[str, list]:
    """Per-step series for JSON output (step end times, °C, m/s, W)."""
    from dsfd.measured import iso_utc

    tr = run.trajectory
    n = tr.label.shape[1]
    t_end = run.start_s + (np.arange(n) + 1) * run.step_s
    out: dict[str, list] = {"time_utc": [iso_utc(float(t)) for t in t_end]}
    for i in range(6):
        out[f"x{i + 1}_c"] = np.round(tr.x[0, 1:, i] - T_ZERO, 4).tolist()
    out["v_cav_ms"] = np.round(tr.v_cav_ms[0], 5).tolist()
    out["label"] = tr.label[0].astype(int).tolist()
    for key in ("q_cv_rd_w", "q_sol_w", "q_air_w", "q_da_w"):
        out[key] = np.round(getattr(tr, key)[0], 3).tolist()
    out["t_out_c"] = np.round(run.forcing.t_out_k - T_ZERO, 3).tolist()
    out["facade_beam_wm2"] = np.round(run.forcing.beam_wm2, 2).tolist()
    out["facade_diffuse_wm2"] = np.round(run.forcing.diffuse_wm2, 2).tolist()
    return out
