"""Measured-data tables produced by the lumped model itself (known parameters, noise).

Rows follow the measured-data CSV conventions (dsfd.measured): controls of row k apply
over step k, weather of step k sits in row k + 1, states are readings at the row time.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import Param
from dsfd.measured import MeasuredData
from dsfd.physics.constants import T_ZERO
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, facade_forcing, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.sim.replay import at_site, load_weather, step_window, weather_inputs

#: True parameters as multiples of the panel defaults (n replaced by TRUE_N).
TRUE_FACTORS = np.array([1.4, 0.8, 1.3, 1.25, 0.9, 1.2, 1.5, 0.7, 1.0])
TRUE_N = 0.65


def suwon_diagonal_k(f: float) -> float:
    """K_in + K_out of a Suwon diagonal path at OR = 1 by hand [1/m4]: two 0.25 m x 2 m
    dampers (A = 0.5 m2, C_d 0.6) and the cavity (A_c = 0.25 m x 2 m), each opening
    1/(C_d A)^2 + f/(2 A_c^2) (docs/model.md#c-follows-f)."""
    return 2.0 / (0.6 * 0.5) ** 2 + 2.0 * f / (2.0 * 0.5**2)


def with_calibration(cfg: PanelConfig, **changes) -> PanelConfig:
    """``cfg`` with the given ``calibration.*`` settings replaced."""
    return dataclasses.replace(cfg, calibration=dataclasses.replace(cfg.calibration, **changes))


def true_theta(cfg: PanelConfig) -> np.ndarray:
    theta = LumpedModel(cfg).default_theta() * TRUE_FACTORS
    theta[Param.N] = TRUE_N
    return theta


def lumped_record(cfg: PanelConfig, theta: np.ndarray, *, step_s: float = 120.0,
                  hours: float = 8.0, start_h: float = 8.0, noise_k: float = 0.1,
                  noise_v: float = 0.003, seed: int = 0,
                  regimes: tuple[int, ...] = (1, 3, 5, 6, 10),
                  block_min: float = 30.0) -> tuple[MeasuredData, np.ndarray]:
    """A record of the lumped model with ``theta`` on RMIS weather (day 2, from ``start_h``).

    Returns the table and the true states (n + 1, 6) [K].
    """
    rng = np.random.default_rng(seed)
    cfg = dataclasses.replace(cfg, model=dataclasses.replace(cfg.model, step_s=step_s))
    series = at_site(load_weather("rmis-golden-2022-01"), cfg)
    first, _ = step_window(series, step_s)
    start = first + 86400.0 + start_h * 3600.0
    n = round(hours * 3600.0 / step_s)
    w = weather_inputs(series, cfg, start_s=start, n_steps=n)
    forcing = facade_forcing(cfg, w)
    per_block = max(1, round(block_min * 60.0 / step_s))
    blocks = -(-n // per_block)
    avail = [r for r in regimes if r in cfg.openings.available_regimes()]
    reg = np.repeat(np.resize(rng.permutation(avail), blocks), per_block)[:n]
    phi = np.repeat(rng.choice(np.arange(-90.0, 91.0, 18.0), blocks), per_block)[:n]
    if cfg.louver is None:
        phi[:] = 0.0
    or_ = np.repeat(rng.choice([0.6, 1.0], blocks), per_block)[:n]
    column = Forcing(*(np.asarray(v)[:, None] for v in forcing))
    inp = step_inputs(column, FacadeOptics(cfg).loads(column, np.radians(phi)))
    inp = StepInputs(*(np.asarray(v)[:, 0] for v in inp))
    model = LumpedModel(cfg)
    x0 = model.steady_state([reg[0]], or_[0], inp.at((slice(0, 1),)), theta)
    traj = model.rollout(x0, reg[None], or_[None], inp, theta)
    x = traj.x[0]
    # the sensors read what the model says they read: the probe's value for x5 (row 0, the
    # steady start, keeps the state)
    readings = np.array(x[:, :5])
    readings[1:] = traj.readings()[0]
    cols: dict[str, np.ndarray] = {
        "phi_deg": np.append(phi, phi[-1]),
        "afr": np.append(reg, reg[-1]).astype(float),
        "or_pct": np.append(or_, or_[-1]) * 100.0,
    }
    for i in range(5):
        cols[f"x{i + 1}_c"] = readings[:, i] - T_ZERO + noise_k * rng.standard_normal(n + 1)
    v = np.concatenate([[traj.v_cav_ms[0, 0]], traj.v_cav_ms[0]])
    cols["v_cav_ms"] = np.abs(np.abs(v) + noise_v * rng.standard_normal(n + 1))
    cols["t_room_c"] = np.full(n + 1, cfg.room.t_in_c)

    def weather(a: np.ndarray) -> np.ndarray:  # row k+1 carries the mean of step k
        return np.concatenate([[np.nan], a])

    cols["t_out_c"] = weather(w.t_out_k - T_ZERO)
    cols["ghi_wm2"] = weather(w.ghi_wm2)
    cols["dni_wm2"] = weather(w.dni_wm2)
    cols["dhi_wm2"] = weather(w.dhi_wm2)
    cols["wind_speed_ms"] = weather(w.wind_speed_ms)
    cols["wind_dir_deg"] = weather(w.wind_dir_deg)
    cols["pressure_hpa"] = weather(w.pressure_pa / 100.0)
    times = start + step_s * np.arange(n + 1)
    return MeasuredData(times, cols, "synthetic lumped record"), x
