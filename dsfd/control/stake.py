"""The energy at stake in a change of the façade (docs/model.md#energy-at-stake).

When a calibrated parameter has moved (a clogging screen raises the path resistance f, dirt
changes what the panes absorb), the question an operator asks is what it costs. The model
answers it with what it already has: the controller's cost J (Eq. 4 heating, Eq. 5 cooling,
:func:`dsfd.control.objective.horizon_cost`) over the last days' weather and the commands that
were really applied, once with the parameters before the change and once with those now.
The difference, scaled to a week, is the energy at stake: positive when the change costs.

Pure: a :class:`~dsfd.estimation.stepdata.StepData` of the stored record in, figures out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dsfd.control.objective import J_PER_WH, is_heating
from dsfd.estimation.observer import initial_state
from dsfd.estimation.params import N_PARAMS, full_vector, with_offsets
from dsfd.estimation.stepdata import StepData
from dsfd.physics.coupling import StepInputs
from dsfd.physics.model import LumpedModel

__all__ = ["EnergyAtStake", "energy_at_stake", "solar_energy_at_stake"]

SECONDS_PER_WEEK = 7 * 86400.0
J_PER_KWH = 1000.0 * J_PER_WH


@dataclass(frozen=True, kw_only=True)
class EnergyAtStake:
    """J of the same record with two parameter vectors.

    Attributes
    ----------
    j_before_kwh, j_now_kwh : float, [kWh]
        The cost J over the record with the parameters before the change and now (J < 0 is
        heat gained in heating, Eq. 4).
    days : float, [d]
        The record's length in steps that were simulated.
    per_week_kwh : float, [kWh/week]
        (J_now − J_before) scaled to seven days: positive, the change costs that much a week
        under weather and commands like the record's.
    """

    j_before_kwh: float
    j_now_kwh: float
    days: float
    per_week_kwh: float


def _segments(valid: np.ndarray) -> list[tuple[int, int]]:
    """Runs [a, b) of consecutive valid steps."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], valid.astype(np.int8), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def energy_at_stake(model: LumpedModel, steps: StepData, theta_before: np.ndarray,
                    theta_now: np.ndarray) -> EnergyAtStake:
    """Simulate ``steps`` (weather and applied commands) with both parameter vectors.

    Parameters
    ----------
    model : LumpedModel
        Built with the record's step (:func:`dsfd.estimation.stepdata.model_config`).
    steps : StepData
        The record; each run of valid steps is simulated from the observer's initial state
        (the steady state of its first step with the readings put in,
        docs/model.md#initial-state), open loop: the model's own states, not the readings,
        carry each vector's consequences through the days.
    theta_before, theta_now : array (9,) or (13,)
        θ, optionally with the heat-flux offsets q (docs/model.md#parameters).

    Notes
    -----
    The season of each step is that of the controller (:func:`is_heating` on the step's
    outdoor air), so a record that crosses the auto threshold is costed as it was controlled.
    """
    theta = np.vstack([np.atleast_2d(theta_before), np.atleast_2d(theta_now)])
    return _costed(model, steps, theta, np.ones(2))


def solar_energy_at_stake(model: LumpedModel, steps: StepData, theta: np.ndarray,
                          share_change: float) -> EnergyAtStake:
    """What a change of the share of the computed sun the façade takes costs: ``steps``
    simulated with ``theta`` (which took the change up as it came, docs/model.md#diagnostics-solar)
    and the sun as the model computes it, against the same with the sun the change took
    given back.

    Parameters
    ----------
    model, steps
        As :func:`energy_at_stake`.
    theta : array (9,) or (13,)
        θ now, optionally with its heat-flux offsets.
    share_change : float, [-]
        The change of the share of the computed sun the façade takes (the solar detector's
        b, −0.1: a tenth less). "Before" scales every solar term the façade takes — what the
        panes and the slats absorb, what reaches the room, and the daylight benefit, all
        behind the same exterior glass — by (1 − ``share_change``).
    """
    theta = np.vstack([np.atleast_2d(theta)] * 2)
    return _costed(model, steps, theta, np.array([1.0 - share_change, 1.0]))


def _costed(model: LumpedModel, steps: StepData, theta: np.ndarray, sun: np.ndarray
            ) -> EnergyAtStake:
    """J of the record for the pair ``theta`` (2, 9 or 13) with the solar terms of each
    scaled by ``sun`` (2,): "before" first, "now" second."""
    theta = full_vector(theta)
    cost_j = np.zeros(2)
    simulated = 0
    for a, b in _segments(np.asarray(steps.valid, bool)):
        part = steps.window(a, b)
        x0 = initial_state(model, part, 0, theta)
        inp = _sun_scaled(part.inputs, sun)
        inp = with_offsets(inp, theta[:, None, N_PARAMS:])
        traj = model.rollout(x0, np.broadcast_to(part.regime, (2, b - a)),
                             np.broadcast_to(part.or_, (2, b - a)), inp,
                             theta[:, None, :N_PARAMS])
        heating = np.array([is_heating(model.cfg.control, float(t))
                            for t in np.asarray(part.inputs.t_out_k)])
        gained = traj.q_cv_rd_w + traj.q_sol_w + traj.q_air_w
        step_cost = np.where(heating, -(gained + traj.q_da_w), gained - traj.q_da_w)
        cost_j += step_cost.sum(axis=1) * steps.step_s
        simulated += b - a
    j_kwh = cost_j / J_PER_KWH
    seconds = simulated * steps.step_s
    per_week = (j_kwh[1] - j_kwh[0]) * SECONDS_PER_WEEK / seconds if seconds > 0 else np.nan
    return EnergyAtStake(j_before_kwh=float(j_kwh[0]), j_now_kwh=float(j_kwh[1]),
                         days=seconds / 86400.0, per_week_kwh=float(per_week))


def _sun_scaled(inputs: StepInputs, sun: np.ndarray) -> StepInputs:
    """``inputs`` with a batch axis of ``sun``'s length, the solar terms scaled by it."""
    if np.all(sun == 1.0):
        return inputs
    k = sun[:, None]
    return inputs._replace(sources=np.asarray(inputs.sources)[None] * k[..., None],
                           q_trans_wm2=np.asarray(inputs.q_trans_wm2)[None] * k,
                           q_da_w=np.asarray(inputs.q_da_w)[None] * k)
