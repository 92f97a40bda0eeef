"""The ten airflow regimes: damper sets, realised labels and the per-step flow problem.

docs/model.md#regimes (regimes 5–8 renumbered: 5 is exhaust room → IB ↑ → ET → out).
A :class:`FlowSetup` holds everything about a batch's flow problem that does not depend on
the cavity temperature, so the thermal–airflow fixed point only re-evaluates
:func:`path_flows`. Mass flows are positive INTO the cavity; openings EB, ET, IB, IT.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dsfd.physics.airflow import (
    ALL_OPEN,
    CLOSED,
    EB,
    ET,
    IB,
    IT,
    PATHS,
    AirflowBoundary,
    AirflowGeometry,
    FlowState,
    boundary_state,
    louver_series_factor,
    opening_resistance,
    orifice_path_mass_flow,
    regularised_power,
)
from dsfd.physics.constants import GRAVITY, R_AIR
from dsfd.physics.one_node import one_node_flows

_EMPTY4 = np.zeros((0, 4))
#: Mass-balance tolerance of the regime-9 cavity pressure inside the coupling [kg/s]: the
#: flows are 1e-3..1e-1 kg/s, so this is 1e-5 relative or better, and the heat it leaves
#: unbalanced (c_p × 1e-8 kg/s × 20 K = 0.2 mW) is far below what the coupling tolerance on
#: T5 moves (c_p ṁ × 1e-4 K ≈ 5 mW). It saves the last Newton iterations.
ONE_NODE_TOL_KGS = 1e-8
#: Columns of :attr:`FlowSetup.p_c_warm`: P_c, ρ_c, dP_c/dρ_c, p_B (4), ∂P_c/∂p_B (4).
_W_PC, _W_RHO, _W_DRHO, _W_PB, _W_DPB = 0, 1, 2, slice(3, 7), slice(7, 11)
WARM_COLUMNS = _W_DPB.stop

# Lookup tables indexed by commanded regime (0 unused): positive-direction inlet/outlet,
# flow law (0 orifice, 1 power law, 2 all open, 3 closed) and realised labels.
_LAW_ORIFICE, _LAW_POWER, _LAW_ALL, _LAW_CLOSED = 0, 1, 2, 3
_INLET = np.zeros(11, dtype=int)
_OUTLET = np.zeros(11, dtype=int)
_LAW = np.full(11, _LAW_CLOSED)
_LABEL_POS = np.full(11, CLOSED)
_LABEL_NEG = np.full(11, CLOSED)
for _r, (_i, _o, _p, _n, _law) in PATHS.items():
    _INLET[_r], _OUTLET[_r], _LABEL_POS[_r], _LABEL_NEG[_r] = _i, _o, _p, _n
    _LAW[_r] = _LAW_ORIFICE if _law == "orifice" else _LAW_POWER
_LAW[ALL_OPEN] = _LAW_ALL
_LABEL_POS[ALL_OPEN] = _LABEL_NEG[ALL_OPEN] = ALL_OPEN


class FlowSetup(NamedTuple):
    """The part of the flow problem that does not depend on the cavity temperature.

    Built once per step by :func:`flow_setup`; :func:`flows_at` then evaluates the flows
    cheaply for any cavity temperature inside the coupling fixed point. 1-D batch (B,).
    """

    regime: np.ndarray
    inlet: np.ndarray
    outlet: np.ndarray
    law: np.ndarray
    path_gain: np.ndarray  # 1 where a two-opening path exists and carries flow, else 0
    label_pos: np.ndarray
    label_neg: np.ndarray
    any_orifice: bool
    any_power: bool
    any_all_open: bool
    rows_all_open: np.ndarray  # indices of the all-open rows (flat batch)
    # Warm start of the all-open rows' cavity pressure, (B, 11): the last solution P_c [Pa],
    # the cavity density it was solved at [kg/m3], dP_c/dρ_c there [Pa m3/kg], the
    # boundary pressures p_B (4) [Pa] and ∂P_c/∂p_B (4) [-] (NaN: none).
    p_c_warm: np.ndarray
    dp_boundary: np.ndarray  # p_B,in − p_B,out [Pa]
    dz: np.ndarray  # z_in − z_out [m]
    rho_fwd: np.ndarray  # inflow density, positive direction [kg/m3]
    rho_bwd: np.ndarray  # inflow density, negative direction
    k_in: np.ndarray  # loss coefficient of the positive-direction inlet [1/m4]
    k_out: np.ndarray
    power_coef: np.ndarray  # c·OR [m3/(s Pa^n)]
    n: np.ndarray
    louver_beta: np.ndarray  # K_L/(2 A_c²) in series with the power law [1/m4]
    any_louver: bool
    p_atm: np.ndarray
    t_out: np.ndarray  # [K]
    t_in: np.ndarray  # [K]
    t_fwd: np.ndarray  # inflow temperature, positive direction [K]
    t_bwd: np.ndarray  # inflow temperature, negative direction [K]
    p_b: np.ndarray  # (B, 4), for the all-open regime
    rho_b: np.ndarray
    k_all: np.ndarray

    def take(self, rows: np.ndarray) -> FlowSetup:
        """The setup of batch elements ``rows`` (flags are kept: they only enable work)."""
        return self.at(rows)

    def at(self, index) -> FlowSetup:
        """Index every per-row field (e.g. ``(slice(None), k)`` for step k of a horizon)."""
        out = FlowSetup._make([
            v[index] if per_row and isinstance(v, np.ndarray) else v
            for v, per_row in zip(self, _PER_ROW, strict=True)
        ])
        return out._relabel()

    def reshape(self, shape: tuple[int, ...]) -> FlowSetup:
        """Give the flat batch the leading ``shape`` (trailing opening axes kept)."""
        return FlowSetup._make([
            v.reshape(*shape, *v.shape[1:]) if per_row and isinstance(v, np.ndarray) else v
            for v, per_row in zip(self, _PER_ROW, strict=True)
        ])

    def _relabel(self) -> FlowSetup:
        """Recompute the all-open row index after selecting rows (1-D batches only)."""
        if not self.any_all_open or self.law.ndim != 1:
            return self
        rows = np.flatnonzero(self.law == _LAW_ALL)
        return self._replace(rows_all_open=rows, any_all_open=bool(rows.size))


#: Which FlowSetup fields are indexed per batch row (arrays, except the all-open row index).
_PER_ROW = tuple(
    name not in ("any_orifice", "any_power", "any_all_open", "any_louver", "rows_all_open")
    for name in FlowSetup._fields
)


def flow_setup(
    regime: np.ndarray,
    or_: np.ndarray,
    bnd: AirflowBoundary,
    geom: AirflowGeometry,
    *,
    f: np.ndarray,
    c: np.ndarray,
    n: np.ndarray,
    k_louver: np.ndarray | float = 0.0,
    diagonal_orifice: bool = False,
) -> FlowSetup:
    """Precompute the cavity-temperature-independent flow data of a batch (see flows_at).

    ``f`` is the whole form loss of the orifice regimes (the louver's K_L included);
    ``k_louver`` [-] is K_L(φ) alone, put in series with the power law of regimes 5–8
    (docs/model.md#louver-flow-loss). ``diagonal_orifice``: regimes 5–8 are orifice paths
    too (docs/model.md#diagonal-flow; c and n unused).
    """
    regime = np.asarray(regime, dtype=int).ravel()
    nb = regime.size

    def flat(v: np.ndarray | float) -> np.ndarray:
        return np.broadcast_to(np.asarray(v, float), (nb,))

    or_b, f_b, c_b, n_b, kl_b = (flat(v) for v in (or_, f, c, n, k_louver))
    bnd_b = AirflowBoundary(*(flat(v) for v in bnd))
    p_b, rho_b, t_b = boundary_state(bnd_b, geom)
    k_all = opening_resistance(or_b, f_b, geom)
    inlet, outlet, law = _INLET[regime], _OUTLET[regime], _LAW[regime]
    if diagonal_orifice:
        law = np.where(law == _LAW_POWER, _LAW_ORIFICE, law)
    rows = np.arange(nb)
    z = geom.z_m
    or_eff = np.maximum(or_b, geom.min_opening_ratio)
    path_gain = ((law <= _LAW_POWER) & (geom.area_m2[inlet] > 0)
                 & (geom.area_m2[outlet] > 0)).astype(float)
    return FlowSetup(
        regime=regime,
        inlet=inlet,
        outlet=outlet,
        law=law,
        path_gain=path_gain,
        label_pos=_LABEL_POS[regime],
        label_neg=_LABEL_NEG[regime],
        any_orifice=bool(np.any(law == _LAW_ORIFICE)),
        any_power=bool(np.any(law == _LAW_POWER)),
        any_all_open=bool(np.any(law == _LAW_ALL)) and bool(np.all(geom.area_m2 > 0)),
        rows_all_open=np.flatnonzero(law == _LAW_ALL) if np.all(geom.area_m2 > 0)
        else np.zeros(0, dtype=int),
        p_c_warm=np.full((nb, WARM_COLUMNS), np.nan),
        # Rows without a two-opening path (closed, all open) get a dummy 1 Pa: their path
        # flow is multiplied by 0, and a zero there would send the whole batch through the
        # regularised branch of the flow laws at every evaluation.
        dp_boundary=np.where(path_gain > 0, p_b[rows, inlet] - p_b[rows, outlet], 1.0),
        dz=z[inlet] - z[outlet],
        rho_fwd=rho_b[rows, inlet],
        rho_bwd=rho_b[rows, outlet],
        k_in=k_all[rows, inlet],
        k_out=k_all[rows, outlet],
        power_coef=c_b * or_eff,
        n=n_b,
        louver_beta=kl_b / (2.0 * geom.cavity_area_m2**2),
        any_louver=bool(np.any((kl_b > 0) & (law == _LAW_POWER))),
        p_atm=bnd_b.p_atm_pa,
        t_out=bnd_b.t_out_k,
        t_in=bnd_b.t_in_k,
        t_fwd=t_b[rows, inlet],
        t_bwd=t_b[rows, outlet],
        p_b=p_b,
        rho_b=rho_b,
        k_all=k_all,
    )


class PathFlow(NamedTuple):
    """Flows of a prepared batch at one cavity temperature (compact form).

    Attributes
    ----------
    flow : (B,), [kg/s]
        Signed mass flow along the two-opening path (positive = listed direction);
        0 for the all-open and closed regimes.
    rho_c : (B,), [kg/m3]
        Cavity air density.
    m_all_open : (n9, 4), [kg/s]
        Opening mass flows of the all-open rows (``setup.rows_all_open``).
    """

    flow: np.ndarray
    rho_c: np.ndarray
    m_all_open: np.ndarray


def path_flows(setup: FlowSetup, t5_k: np.ndarray, geom: AirflowGeometry, *,
               active: np.ndarray | None = None) -> PathFlow:
    """Flows of a prepared batch with the cavity air at ``t5_k`` [K].

    ``active`` (B,) bool, optional: the all-open rows outside it are not solved (their
    ``m_all_open`` rows are zero and their warm start is kept) — the coupling re-evaluates
    the whole batch's elementwise flows, which costs no more than a subset's, but solves the
    one-node problem only for the rows still iterating.

    Notes
    -----
    Two-opening paths: ΔP = p_B,in − p_B,out + ρ_c g (z_in − z_out) (docs/model.md#regimes,
    docs/model.md#plant-airflow); regimes 1–4 use the orifice closed form ṁ = sgn(ΔP)
    sqrt(2|ΔP|/(K_in/ρ_in + K_out/ρ_c)) (docs/model.md#path-flows), regimes 5–8 the power law
    Q = c·OR·sgn(ΔP)|ΔP|^n with ṁ = ρ_up Q [PARK] (the louver's loss in series,
    docs/model.md#louver-flow-loss), both regularised below Δp_t
    (docs/model.md#regularisation). Regime 9: the one-node solver with four orifices
    (docs/model.md#one-node [ENG]); regime 10: no flow.
    """
    s = setup
    rho_c = s.p_atm / (R_AIR * t5_k)
    dp = s.dp_boundary + rho_c * GRAVITY * s.dz
    fwd = dp >= 0
    rho_up = np.where(fwd, s.rho_fwd, s.rho_bwd)
    dp_t = geom.dp_reg_pa
    if s.any_orifice:
        k_up = np.where(fwd, s.k_in, s.k_out)
        k_dn = np.where(fwd, s.k_out, s.k_in)
        flow = orifice_path_mass_flow(dp, k_up, k_dn, rho_up, rho_c, dp_t)
        if s.any_power:
            flow = np.where(s.law == _LAW_ORIFICE, flow, _power_mass_flow(s, dp, rho_up, rho_c,
                                                                          dp_t))
    else:
        flow = _power_mass_flow(s, dp, rho_up, rho_c, dp_t)
    flow *= s.path_gain
    if s.any_all_open:
        r9 = s.rows_all_open
        m9 = np.zeros((r9.size, 4))
        if active is not None:
            solve = active[r9]
            r9 = r9[solve]
            if r9.size == 0:
                return PathFlow(flow, rho_c, m9)
        rho9 = rho_c[r9]
        warm = s.p_c_warm[r9]
        p_b9 = s.p_b[r9]
        # First-order prediction from the last solution: the cavity density moved (the
        # coupling's next evaluation) and the boundary pressures (the next step's weather).
        tangent = (warm[:, _W_DRHO] * (rho9 - warm[:, _W_RHO])
                   + (warm[:, _W_DPB] * (p_b9 - warm[:, _W_PB])).sum(axis=1))
        start = warm[:, _W_PC] + np.where(np.isfinite(tangent), tangent, 0.0)
        sol = one_node_flows(p_b9, s.rho_b[r9], geom.z_m, s.k_all[r9], rho9, dp_t,
                             p_c_start=start, tol_kgs=ONE_NODE_TOL_KGS)
        # In place: the next evaluation of this step (and the next step) starts here
        # (``warm`` is a copy of those rows, every column of it overwritten).
        warm[:, _W_PC], warm[:, _W_RHO], warm[:, _W_DRHO] = sol.p_c, rho9, sol.dpc_drho
        warm[:, _W_PB], warm[:, _W_DPB] = p_b9, sol.dpc_dpb
        s.p_c_warm[r9] = warm
        if active is None:
            m9 = sol.m_dot
        else:
            m9[solve] = sol.m_dot
    else:
        m9 = _EMPTY4
    return PathFlow(flow, rho_c, m9)


def _power_mass_flow(s: FlowSetup, dp: np.ndarray, rho_up: np.ndarray, rho_c: np.ndarray,
                     dp_t: float) -> np.ndarray:
    """ṁ = ρ_up Q of the power law, with the louver's loss in series where it has one."""
    q = regularised_power(dp, s.power_coef, s.n, dp_t)
    if s.any_louver:
        q = q * louver_series_factor(q, dp, s.n, rho_c, s.louver_beta)
    return rho_up * q


def opening_flows(setup: FlowSetup, pf: PathFlow) -> FlowState:
    """Expand a :class:`PathFlow` into per-opening mass flows, labels and cavity flow."""
    s = setup
    nb = s.regime.size
    m_dot = np.zeros((nb, 4))
    rows = np.arange(nb)
    m_dot[rows, s.inlet] += pf.flow
    m_dot[rows, s.outlet] -= pf.flow
    if s.any_all_open:
        m_dot[s.rows_all_open] = pf.m_all_open
    label = np.where(pf.flow >= 0, s.label_pos, s.label_neg)
    q_cav = (m_dot[:, EB] + m_dot[:, IB]) / pf.rho_c
    return FlowState(m_dot=m_dot, label=label, q_cav=q_cav)


def inflow(setup: FlowSetup, pf: PathFlow) -> tuple[np.ndarray, np.ndarray]:
    """Total mass inflow into the cavity [kg/s] and its mixed temperature [K]."""
    m_in = np.abs(pf.flow)
    t_in = np.where(pf.flow >= 0, setup.t_fwd, setup.t_bwd)
    if setup.any_all_open:
        r9 = setup.rows_all_open
        pos = np.maximum(pf.m_all_open, 0.0)
        m_out_side = pos[:, EB] + pos[:, ET]
        m_room_side = pos[:, IB] + pos[:, IT]
        tot = m_out_side + m_room_side
        m_in[r9] = tot
        t_in[r9] = np.where(tot > 0, (m_out_side * setup.t_out[r9] + m_room_side
                                      * setup.t_in[r9]) / np.where(tot > 0, tot, 1.0),
                            setup.t_in[r9])
    return m_in, t_in


def regime_flows(
    regime: np.ndarray,
    or_: np.ndarray,
    t5_k: np.ndarray,
    bnd: AirflowBoundary,
    geom: AirflowGeometry,
    *,
    f: np.ndarray,
    c: np.ndarray,
    n: np.ndarray,
    k_louver: np.ndarray | float = 0.0,
) -> FlowState:
    """Airflow of commanded regimes (1-D batch) with the cavity air at ``t5_k``.

    Parameters
    ----------
    regime : int array (B,)
        Commanded airflow regime 1..10 (selects the damper set; docs/model.md#regimes).
    or_ : array (B,), [-]
        Damper opening ratio 0..1.
    t5_k : array (B,), [K]
        Cavity air temperature used for its density.
    bnd : AirflowBoundary
        Outdoor/room temperatures [K], pressure [Pa], local wind [m/s], C_p pair.
    geom : AirflowGeometry
    f, c, n : arrays (B,) or scalars
        Form-loss factor [-], power-law coefficient at OR = 1 [m3/(s Pa^n)] and exponent.
    k_louver : array (B,) or scalar, [-]
        The louver's loss K_L(φ), in series with the power law (already in ``f``).

    Returns
    -------
    FlowState
    """
    setup = flow_setup(regime, or_, bnd, geom, f=f, c=c, n=n, k_louver=k_louver)
    t5 = np.broadcast_to(np.asarray(t5_k, float), setup.regime.shape)
    return opening_flows(setup, path_flows(setup, t5, geom))


