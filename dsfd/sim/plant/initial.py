"""Initial temperatures of the truth plant (docs/model.md#initial-state)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from dsfd.physics.forcing import FacadeOptics, facade_forcing, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.sim.openloop import first_step
from dsfd.sim.plant.actuators import Command
from dsfd.sim.replay import weather_inputs

if TYPE_CHECKING:
    from dsfd.sim.plant.plant import Plant


def lumped_steady_state(plant: Plant, cmd: Command) -> np.ndarray:
    """Steady state x* of the lumped model with the plant's θ for the first step [K] (6,).

    The lumped forcing (Erbs, Hay–Davies) of the first model step and the lumped θ that
    the plant's parameters map to (:meth:`TrueParameters.lumped_theta`).
    """
    cfg = plant.cfg
    t0 = plant.time_s
    dt = float(cfg.model.step_s)
    w = weather_inputs(plant.series, cfg, start_s=t0, n_steps=1,
                       t_in_c=plant.room_c(np.array([t0 + 0.5 * dt])))
    forcing = facade_forcing(cfg, w)
    inputs = step_inputs(forcing, FacadeOptics(cfg).loads(forcing, np.radians(cmd.phi_deg)))
    model = LumpedModel(cfg)
    theta = plant.params.lumped_theta(cfg)
    return model.steady_state([cmd.afr], cmd.or_pct / 100.0, first_step(inputs), theta)[0]


def initial_state(plant: Plant, cmd: Command, x0: np.ndarray | None) -> np.ndarray:
    """Node temperatures [K] from six lumped states (default: their steady state) or as given.

    Six states are replicated over the segments: x1..x4 to the panes and the louver, x5 to
    every cavity air node (sub-cavities and plenums), x6 to the DGU gap.
    """
    model = plant.model
    lay = model.lay
    if x0 is not None:
        x0 = np.asarray(x0, float)
        if x0.shape == (model.nn,):
            return x0.copy()
        if x0.shape != (6,):
            raise ValueError(f"x0 must have 6 lumped states or {model.nn} node values, got "
                             f"shape {x0.shape}")
        x6 = x0
    else:
        x6 = lumped_steady_state(plant, cmd)
    T = np.empty(model.nn)
    for kind, j in (("g1", 0), ("g2", 1), ("g3", 2), ("lv", 3), ("ao", 4), ("ai", 4),
                    ("g6", 5)):
        T[lay.sl(kind)] = x6[j]
    if lay.plenums:
        T[[lay.pb, lay.pt]] = x6[4]
    return T
