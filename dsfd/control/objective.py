"""Heating and cooling cost over the horizon (paper Eq. 4–5, docs/model.md#control-objective).

J_heat = −∫ (Q_cv,rd + Q_sol,trans + Q_air + Q_DA) dt
J_cool =  ∫ (Q_cv,rd + Q_sol,trans + Q_air − Q_DA) dt

with the step-average heat flows of the lumped model (exact step averages, docs/model.md#zoh) and
Q_air accounted as configured (docs/model.md#q-air). Costs are in joules; lower is better.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dsfd.config.control import Control
from dsfd.physics.constants import T_ZERO
from dsfd.physics.model import Trajectory

J_PER_WH = 3600.0


class CostTerms(NamedTuple):
    """Energy into the room over the horizon per candidate [J] and the cost J [J]."""

    q_cv_rd_j: np.ndarray
    q_sol_j: np.ndarray
    q_air_j: np.ndarray
    q_da_j: np.ndarray
    cost_j: np.ndarray


def is_heating(control: Control, t_out_k: float) -> bool:
    """Season of the objective: the configured mode, or heating below the auto threshold."""
    if control.mode == "auto":
        return bool(t_out_k - T_ZERO < control.auto_heating_below_c)
    return control.mode == "heating"


def horizon_cost(traj: Trajectory, *, dt: float, heating: bool) -> CostTerms:
    """Eq. 4 (heating) or Eq. 5 (cooling) for every rollout of a batch.

    Parameters
    ----------
    traj : Trajectory
        Rollouts of shape (B, H).
    dt : float, [s]
        Step length.
    heating : bool
        Heating objective (Eq. 4) if true, cooling (Eq. 5) otherwise.
    """
    cv = traj.q_cv_rd_w.sum(axis=1) * dt
    sol = traj.q_sol_w.sum(axis=1) * dt
    air = traj.q_air_w.sum(axis=1) * dt
    da = traj.q_da_w.sum(axis=1) * dt
    cost = -(cv + sol + air + da) if heating else cv + sol + air - da
    return CostTerms(cv, sol, air, da, cost)


def louver_move_penalty(phi_deg: np.ndarray, previous_deg: float | None, *, penalty_wh: float,
                        step_deg: float) -> np.ndarray:
    """Motor-wear penalty [J]: ``penalty_wh`` per louver step between previous and new angle."""
    phi_deg = np.asarray(phi_deg, float)
    if previous_deg is None or penalty_wh == 0.0:
        return np.zeros_like(phi_deg)
    steps = np.round(np.abs(phi_deg - previous_deg) / step_deg)
    return steps * penalty_wh * J_PER_WH
