"""Reading offsets: the output-disturbance model of the daemon's state update, per regime.

docs/model.md#reading-offsets. The lumped model's fast nodes misplace their quasi-steady
value by an amount that depends on the airflow regime: within a minute the cavity air
(time constant ≈ 10–30 s) forgets where the reading put it and relaxes to the balance of
its surfaces and inflow, and on the stratified truth plant that balance sits 1–3 K off the
mid-height probe in inside circulation and supply air, with opposite signs. A reading
offset d_r,i per commanded regime r and sensor i is the disturbance y_i = x_i + d_r,i of
offset-free estimation with an output-disturbance model (Muske & Badgwell 2002; Pannocchia &
Rawlings 2003): the predictions of the readings add it, the state update takes the reading
less it. It moves no heat, so the room-side heat the optimiser weighs is the model's own.

Pure: the caller keeps the table between steps.
"""

from __future__ import annotations

import numpy as np

__all__ = ["N_REGIMES", "initial_reading_offsets", "reading_offset", "track_reading_offsets"]

#: Airflow regimes 1..10 (docs/model.md#regimes): one row of offsets each.
N_REGIMES = 10


def initial_reading_offsets(n_sensors: int = 5) -> np.ndarray:
    """No offset known: zeros (10, ``n_sensors``) [K]."""
    return np.zeros((N_REGIMES, n_sensors))


def reading_offset(offsets: np.ndarray, regime: int) -> np.ndarray:
    """The offsets [K] of commanded ``regime`` (1..10), a copy; zeros for an unknown regime."""
    if 1 <= regime <= N_REGIMES:
        return np.array(offsets[regime - 1], float)
    return np.zeros(offsets.shape[1])


def track_reading_offsets(
    offsets: np.ndarray, *, regime: int, innovation_k: np.ndarray, step_s: float,
    tracking_s: np.ndarray, memory_s: float, clip_k: float,
) -> np.ndarray:
    """The offset table after one step in ``regime`` (a new array).

    Parameters
    ----------
    offsets : array (10, S), [K]
        Offsets per regime 1..10 and sensor before the step.
    regime : int
        Regime commanded during the step (1..10); another value only ages the table.
    innovation_k : array (S,), [K]
        Reading minus the predicted reading *including* the regime's offset; NaN where the
        sensor gave no GOOD reading (that offset is left as it is).
    step_s : float, [s]
    tracking_s : array (S,), [s]
        Time constant per sensor; 0 keeps that sensor's offsets at 0.
    memory_s : float, [s]
        Time constant of the decay towards 0 of the other regimes' offsets.
    clip_k : float, [K]
        Innovations are clipped to ±this (a spike moves an offset by at most a·clip).

    Returns
    -------
    ndarray (10, S), [K]

    Notes
    -----
    d_r ← d_r + a (clip(e) − 0), a = 1 − exp(−T/τ) — a first-order low-pass of the reading
    minus the offset-free prediction, i.e. d_r → mean(y − ŷ₀) with time constant τ; the
    other rows decay as d ← d exp(−T/τ_m) (docs/model.md#reading-offsets).
    """
    tau = np.asarray(tracking_s, float)
    out = np.asarray(offsets, float) * np.exp(-step_s / memory_s)
    on = tau > 0
    out[:, ~on] = 0.0
    if not 1 <= regime <= N_REGIMES:
        return out
    row = regime - 1
    e = np.clip(np.asarray(innovation_k, float), -clip_k, clip_k)
    a = np.where(on, -np.expm1(-step_s / np.where(on, tau, 1.0)), 0.0)
    seen = on & np.isfinite(e)
    out[row] = np.where(seen, offsets[row] + a * np.nan_to_num(e), np.where(on, offsets[row],
                                                                             0.0))
    return out
