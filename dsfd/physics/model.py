"""The lumped double-skin façade model: ẋ = A(u,t)x + b(u,t) with exact ZOH (Eq. 1–2).

:class:`LumpedModel` is the public face of the physics: one coupled step for a batch of
states, a horizon rollout for a batch of control sequences (what the optimiser and the
calibrator call thousands of times), and the steady state used as initial condition
(docs/model.md#initial-state). The step itself lives in :mod:`dsfd.physics.coupling`; the exogenous
inputs (weather, sun, optics) are built by :mod:`dsfd.physics.forcing`.

States are x1..x6 [K] (L1, L2, L3, louver, cavity air, DGU gap gas); parameters
θ = (h_out, h_ca1, h_ca2, h_ca3, h_ca4, h_in, f, c, n) in the order of
:class:`dsfd.config.parameters.Param` (``theta[..., Param.F]``).
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import N_PARAMS, Param
from dsfd.physics.airflow import AirflowBoundary, AirflowGeometry
from dsfd.physics.coupling import (
    NO_LOUVER_CAPACITY,
    NetworkConstants,
    StepInputs,
    StepResult,
    coupled_step,
    frozen_network,
    with_flow,
)
from dsfd.physics.regimes import FlowSetup, flow_setup
from dsfd.physics.rootfind import solve_fixed_point
from dsfd.physics.slat_film import panel_equal_speed_ms


def _trajectory(xs: np.ndarray, cols: list) -> Trajectory:
    """The rollout's states ``xs`` (B, H + 1, 6) and its steps' results as a Trajectory."""
    nb = xs.shape[0]

    def stack(get) -> np.ndarray:
        return np.stack([get(r) for r in cols], axis=1)

    return Trajectory(
        x=xs,
        x_mean=stack(lambda r: r.x_mean),
        m_dot=stack(lambda r: r.flow.m_dot),
        label=stack(lambda r: r.flow.label),
        v_cav_ms=stack(lambda r: r.v_cav_ms),
        q_cv_rd_w=stack(lambda r: r.q_cv_rd_w),
        q_sol_w=stack(lambda r: r.q_sol_w),
        q_air_w=stack(lambda r: r.q_air_w),
        q_da_w=stack(lambda r: np.broadcast_to(r.q_da_w, (nb,))),
        heat_in_wm2=stack(lambda r: r.heat_in_wm2),
        evaluations=stack(lambda r: r.evaluations),
        x5_probe=stack(lambda r: r.x5_probe_k),
        coupling_slope=stack(lambda r: np.broadcast_to(r.coupling_slope, (nb,))),
    )


def _given_start(t5_k: np.ndarray, slope_k: np.ndarray | None, x: np.ndarray,
                 guess: np.ndarray | None, slope: np.ndarray | None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Start of step k's coupling: a caller's cavity temperature ``t5_k`` and slope where
    finite (:meth:`LumpedModel.rollout`), else the rollout's own warm start (x5 now and no
    slope when it has none)."""
    given = np.isfinite(t5_k)
    own_guess = x[:, 4] if guess is None else guess
    own_slope = np.full(x.shape[0], np.nan) if slope is None else slope
    given_slope = np.nan if slope_k is None else slope_k
    return np.where(given, t5_k, own_guess), np.where(given, given_slope, own_slope)


class Trajectory(NamedTuple):
    """A batch of horizon rollouts: leading shape (B, H) unless noted.

    Attributes
    ----------
    x : (B, H + 1, 6), [K]
        States at the step boundaries, x[:, 0] = x0.
    x_mean : (B, H, 6), [K]
        Exact step averages.
    m_dot : (B, H, 4), [kg/s]
        Opening mass flows (EB, ET, IB, IT), positive into the cavity.
    label : (B, H), int
        Realised regime labels.
    v_cav_ms : (B, H), [m/s]
        Signed mean cavity velocity.
    q_cv_rd_w, q_sol_w, q_air_w, q_da_w : (B, H), [W]
        Step-average heat flows into the room.
    heat_in_wm2 : (B, H), [W/m2]
        Net heat into the network (energy balance).
    evaluations : (B, H), int
    x5_probe : (B, H), [K]
        What the cavity-air probe reads at the end of each step (StepResult.x5_probe_k).
    coupling_slope : (B, H), [-]
        Last secant slope dh/dT5 of each step's coupling (StepResult.coupling_slope): with
        ``x[:, 1:, 4]``, the warm start of a later rollout of nearly the same θ.
    """

    x: np.ndarray
    x_mean: np.ndarray
    m_dot: np.ndarray
    label: np.ndarray
    v_cav_ms: np.ndarray
    q_cv_rd_w: np.ndarray
    q_sol_w: np.ndarray
    q_air_w: np.ndarray
    q_da_w: np.ndarray
    heat_in_wm2: np.ndarray
    evaluations: np.ndarray
    x5_probe: np.ndarray
    coupling_slope: np.ndarray | None = None

    def readings(self) -> np.ndarray:
        """What the x1..x5 sensors read at the end of each step (B, H, 5) [K]: the states,
        with the cavity-air probe's reading for x5 (docs/model.md#cavity-probe)."""
        out = np.array(self.x[:, 1:, :5])
        out[..., 4] = self.x5_probe
        return out


def network_constants(cfg: PanelConfig) -> NetworkConstants:
    """Heat capacities, emissivities and coupling options of a panel (docs/model.md#constants,
    docs/model.md#network)."""
    gl = cfg.glazing
    mo = cfg.model
    rho_a, cp_a = mo.air_density_kgm3, mo.air_heat_capacity_jkgk

    def pane(layer) -> float:
        return layer.density_kgm3 * layer.heat_capacity_jkgk * layer.thickness_m

    lv = cfg.louver
    if lv is not None:
        ratio = lv.slat_width_m / lv.slat_pitch_m
        c4 = lv.density_kgm3 * lv.heat_capacity_jkgk * lv.slat_thickness_m * ratio
        a_l = 2.0 * ratio
    else:
        c4, a_l = NO_LOUVER_CAPACITY, 0.0
    capacity = np.array([
        pane(gl.exterior),
        pane(gl.interior_outer),
        pane(gl.interior_inner),
        c4,
        rho_a * cp_a * cfg.facade.cavity_depth_m,
        rho_a * cp_a * gl.interior_gap_m,
    ])
    return NetworkConstants(
        capacity=capacity,
        slat_area_ratio=a_l,
        has_louver=lv is not None,
        eps_l1_front=gl.exterior.emissivity_front,
        eps_l3_back=gl.interior_inner.emissivity_back,
        h_r23_factor=1.0 / (1.0 / gl.interior_outer.emissivity_back
                            + 1.0 / gl.interior_inner.emissivity_front - 1.0),
        geom=AirflowGeometry.from_sections(cfg.openings, cfg.facade),
        dt=mo.step_s,
        cp_air=cp_a,
        coupling=mo.coupling,
        substeps=mo.ping_pong_substeps,
        tol_k=mo.coupling_tolerance_k,
        max_evals=mo.coupling_max_iterations,
        zoh=mo.zoh,
        q_air_basis=mo.q_air_basis,
        cavity_profile=mo.cavity_air_profile,
        probe_height_frac=0.5 if mo.cavity_air_probe == "mid_height" else None,
        slat_film_equal_ms=(panel_equal_speed_ms(cfg) if mo.slat_film == "speed_dependent"
                            else 0.0),
        slat_film_reference_ms=mo.slat_film_reference_speed_ms,
    )


class LumpedModel:
    """Lumped 6-state façade model of one panel (batched; pure, no I/O).

    Parameters
    ----------
    cfg : PanelConfig
        Panel description; model options come from ``cfg.model``.
    """

    def __init__(self, cfg: PanelConfig) -> None:
        self.cfg = cfg
        self.nc = network_constants(cfg)
        self.geom = self.nc.geom
        self.dt = self.nc.dt
        self.area = self.geom.facade_area_m2

    @property
    def capacity(self) -> np.ndarray:
        """Node heat capacities per m² façade [J/(m2 K)]."""
        return self.nc.capacity

    def default_theta(self) -> np.ndarray:
        """Parameter defaults θ (indexed by :class:`~dsfd.config.parameters.Param`)."""
        return np.array(self.cfg.parameters.values("default"))

    def theta_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper calibration bounds of θ."""
        p = self.cfg.parameters
        return np.array(p.values("lower")), np.array(p.values("upper"))

    # ------------------------------------------------------------------ preparation
    def _flow_setup(self, regime: np.ndarray, or_: np.ndarray, inp: StepInputs,
                    theta: np.ndarray) -> FlowSetup:
        shape = regime.shape
        air = AirflowBoundary(inp.t_out_k, inp.t_in_k, inp.p_atm_pa, inp.wind_ms,
                              inp.cp_bottom, inp.cp_top)
        setup = flow_setup(regime.ravel(), or_.ravel(),
                           AirflowBoundary(*(np.ravel(v) for v in air)), self.geom,
                           f=(theta[..., Param.F] + inp.cavity_loss).ravel(),
                           c=theta[..., Param.C].ravel(), n=theta[..., Param.N].ravel(),
                           k_louver=np.broadcast_to(inp.cavity_loss, shape).ravel(),
                           diagonal_orifice=self.cfg.model.diagonal_flow == "orifice")
        return setup.reshape(shape)

    def _batch(self, shape: tuple[int, ...], regime, or_, inputs: StepInputs, theta):
        regime = np.broadcast_to(np.asarray(regime, int), shape)
        or_ = np.broadcast_to(np.asarray(or_, float), shape)
        theta = np.broadcast_to(np.asarray(theta, float), (*shape, N_PARAMS))
        inp = inputs.broadcast(shape)
        return regime, or_, inp, theta

    # ------------------------------------------------------------------ public API
    def step(self, x: np.ndarray, regime: np.ndarray, or_: np.ndarray, inputs: StepInputs,
             theta: np.ndarray) -> StepResult:
        """Advance a batch of states by one step.

        Parameters
        ----------
        x : array (B, 6), [K]
            States x1..x6 at the start of the step.
        regime : int array (B,) or scalar
            Commanded airflow regime 1..10.
        or_ : array (B,) or scalar, [-]
            Damper opening ratio 0..1.
        inputs : StepInputs
            Exogenous inputs (the louver angle enters through ``sources``, ``lw_exchange``
            and ``cavity_loss``).
        theta : array (9,) or (B, 9)
            Parameters (h_out, h_ca1..h_ca4, h_in [W/(m2 K)], f [-], c [m3/(s Pa^n)], n [-]).

        Returns
        -------
        StepResult
        """
        x = np.atleast_2d(np.asarray(x, float))
        regime, or_, inp, theta = self._batch((x.shape[0],), regime, or_, inputs, theta)
        setup = self._flow_setup(regime, or_, inp, theta)
        return coupled_step(self.nc, x, inp, theta, setup)

    def rollout(self, x0: np.ndarray, regime: np.ndarray, or_: np.ndarray,
                inputs: StepInputs, theta: np.ndarray, *,
                coupling_tol_k: float | None = None, t5_guess: np.ndarray | None = None,
                slope_guess: np.ndarray | None = None) -> Trajectory:
        """Roll a batch of control sequences out over a horizon.

        Parameters
        ----------
        x0 : array (B, 6) or (6,), [K]
            Initial states.
        regime, or_ : arrays broadcastable to (B, H)
            Commanded regime and opening ratio per step.
        inputs : StepInputs
            Fields broadcastable to (B, H) (typically (H,) weather with (B, H) optics).
        theta : array broadcastable to (B, H, 9)
        coupling_tol_k : float, optional, [K]
            Override of the coupling fixed-point tolerance (a screening pass of the
            optimiser can afford a looser one).
        t5_guess, slope_guess : arrays (B, H), optional, [K] and [-]
            Where finite, the start of each step's coupling and its slope dh/dT5 instead of
            the rollout's own warm start: the end-of-step x5 and ``coupling_slope`` of an
            earlier rollout of nearly the same θ (a finite-difference Jacobian's base point
            starts the perturbed rows within a few millikelvin of their roots).

        Returns
        -------
        Trajectory
        """
        x = np.atleast_2d(np.asarray(x0, float))
        regime = np.asarray(regime, int)
        horizon = regime.shape[-1] if regime.ndim else 1
        nb = max(x.shape[0], regime.shape[0] if regime.ndim == 2 else 1)
        shape = (nb, horizon)
        regime, or_, inp, theta = self._batch(shape, regime, or_, inputs, theta)
        setup = self._flow_setup(regime, or_, inp, theta)
        x = np.array(np.broadcast_to(x, (nb, 6)))
        nc = self.nc if coupling_tol_k is None else dataclasses.replace(self.nc,
                                                                         tol_k=coupling_tol_k)
        xs = np.empty((nb, horizon + 1, 6))
        xs[:, 0] = x
        cols = []
        guess = slope = None
        last_slope = np.full(nb, np.nan)
        ahead, predicted = np.zeros(nb), np.zeros(nb, bool)
        for k in range(horizon):
            if t5_guess is not None:
                guess, slope = _given_start(
                    t5_guess[:, k], None if slope_guess is None else slope_guess[:, k], x,
                    guess, slope)
            res = coupled_step(nc, x, inp.at((slice(None), k)), theta[:, k],
                               setup.at((slice(None), k)), guess, slope)
            cols.append(res)
            # Warm start: under unchanged controls the cavity air moves as this step's
            # network predicts, corrected by how far that prediction missed this step
            # (the weather and the linearisation drift smoothly), and the coupling's slope
            # follows its drift over the last two steps; after a control change start
            # from the state.
            if k + 1 < horizon:
                same = (regime[:, k + 1] == regime[:, k]) & (or_[:, k + 1] == or_[:, k])
                # (the miss counts only if step k was predicted under its own controls)
                miss = np.where(same & predicted, res.x_next[:, 4] - ahead, 0.0)
                ahead, predicted = res.t5_ahead_k, same
                guess = np.where(same, ahead + miss, res.x_next[:, 4])
                trend = res.coupling_slope - last_slope
                trend = np.where(np.isfinite(trend), trend, 0.0)
                slope = np.where(same, res.coupling_slope + trend, np.nan)
                last_slope = np.where(same, res.coupling_slope, np.nan)
                if setup.any_all_open:  # the all-open cavity pressure changes little too
                    setup.p_c_warm[:, k + 1] = setup.p_c_warm[:, k]
            x = res.x_next
            xs[:, k + 1] = x

        return _trajectory(xs, cols)

    def steady_state(self, regime: np.ndarray, or_: np.ndarray, inputs: StepInputs,
                     theta: np.ndarray, *, iterations: int = 50, tol_k: float = 1e-5,
                     x_guess: np.ndarray | None = None) -> np.ndarray:
        """Steady state x* = −L⁻¹q for constant inputs (initial condition,
        docs/model.md#initial-state).

        Outer iterations refresh the linearised radiative conductances at the current
        state; inside each, the cavity temperature that sets the airflow is solved as the
        fixed point T = x*_5(ṁ(T)) with the same solver as the step coupling (a plain
        iteration would chatter in the diagonal regimes). Stops when the state moves by
        less than ``tol_k`` [K].

        Returns
        -------
        x : ndarray (B, 6), [K]
        """
        regime = np.atleast_1d(np.asarray(regime, int))
        nb = regime.shape[0]
        regime, or_, inp, theta = self._batch((nb,), regime, or_, inputs, theta)
        setup = self._flow_setup(regime, or_, inp, theta)
        if x_guess is None:
            t_mid = 0.5 * (inp.t_out_k + inp.t_in_k)
            x = np.repeat(t_mid[:, None], 6, axis=1)
        else:
            x = np.array(np.broadcast_to(x_guess, (nb, 6)), float)
        for _ in range(iterations):
            lap0, q0, _ = frozen_network(self.nc, x, inp, theta)
            x_new = np.empty_like(x)

            def phi(t5: np.ndarray, rows: np.ndarray, lap0=lap0, q0=q0, x_new=x_new):
                sub = setup if rows.size == nb else setup.take(rows)
                lap, q, *_ = with_flow(self.nc, t5, sub, lap0[rows], q0[rows])
                x_new[rows] = -np.linalg.solve(lap, q[..., None])[..., 0]
                return x_new[rows, 4]

            solve_fixed_point(phi, x[:, 4], tol=tol_k * 0.1, max_evals=60)
            moved = np.max(np.abs(x_new - x))
            x = x_new
            if moved < tol_k:
                break
        return x


__all__ = ["LumpedModel", "StepInputs", "StepResult", "Trajectory", "network_constants"]
