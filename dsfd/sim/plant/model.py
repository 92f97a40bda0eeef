"""Right-hand side and Jacobian of the stratified truth plant (docs/model.md#truth-plant).

State y = [T (n_nodes) [K], ∫S dt, ∫Q_bnd dt, ∫(H_in − H_out) dt, ∫|Q_bnd| dt,
∫Q_cv,rd dt, ∫Q_sol,trans dt, ∫Q_air dt, ∫Q_DA dt [J]]; the first four accumulators
instrument the energy balance in docs/model.md#energy-balance, the last four are the room-side heat
flows of docs/model.md#room-heat (Q_air by the panel's ``model.q_air_basis``, docs/model.md#q-air,
with the temperature of the air actually entering the room). Per node (absolute units)

    C_i dT_i/dt = Σ_links g (T_j − T_i) + Σ_inflows ṁ c_p (T_up − T_i) + S_i A_seg

with convective, conductive and radiative (secant σ(T_a²+T_b²)(T_a+T_b), i.e. exact T⁴)
links, upwind advection (docs/model.md#plant-layout: c5 δz W dT5_k/dt = ṁ c_p (T5_{k−1} − T5_k),
plus the optional second-order correction of :mod:`dsfd.sim.plant.advection`) and the absorbed
short-wave. The airflow is solved inside every evaluation from the current stratified
column (fully implicit coupling, :mod:`dsfd.sim.plant.flow`); the convective coefficients
come from :mod:`dsfd.sim.plant.convection`, the Jacobian from
:mod:`dsfd.sim.plant.jacobian`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from scipy.sparse import csc_matrix

from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import CONVECTIVE_NAMES, Param
from dsfd.physics.airflow import louver_flow_loss
from dsfd.physics.constants import GRAVITY, R_AIR, SIGMA
from dsfd.physics.forcing import TERRAIN_PROFILE
from dsfd.physics.slat_film import film_factor, panel_equal_speed_ms
from dsfd.sim.plant.actuators import Actuators
from dsfd.sim.plant.advection import Advection2
from dsfd.sim.plant.config import PlantOptions, TrueParameters
from dsfd.sim.plant.convection import ConvectionGeometry, coefficients
from dsfd.sim.plant.flow import (
    EB,
    IB,
    IS_TOP,
    IT,
    NETWORK,
    PAIR,
    FlowPiece,
    OpeningData,
    network_flows,
    opening_resistance,
    pair_flow,
)
from dsfd.sim.plant.forcing import lw_exchange_table
from dsfd.sim.plant.jacobian import jacobian
from dsfd.sim.plant.layout import (
    NO_LOUVER_LINK,
    Geometry,
    Layout,
    build_topology,
    capacities,
    column_weights,
    variable_air_capacity,
)
from dsfd.sim.plant.physics import iso15099_gap, lateral_open_fraction

N_ACC = 8
#: Room-side accumulators (after the four of the energy balance), in order.
ROOM_FLOWS = ("q_cv_rd", "q_sol_trans", "q_air", "q_da")


@dataclass
class Piece:
    """Everything constant over one integration piece (part of one model step)."""

    ts: float  # start of the forcing step [s]
    inv_len: float  # 1/step length [1/s]
    fa: np.ndarray  # (8,) forcing at the step start
    fd: np.ndarray  # (8,) end − start
    src_a: np.ndarray  # (m, 4) [W/m2]
    src_d: np.ndarray
    windward: bool
    act: Actuators
    phi_moving: bool
    dampers_moving: bool
    target_open: np.ndarray  # (4,) bool
    flow: FlowPiece
    h_scale: np.ndarray  # (6,) multipliers (with drift); × defaults in constant mode
    k_static: list[float] | None = None
    static: dict = field(default_factory=dict)
    pc: float = 0.0
    target_open_list: list[bool] = field(default_factory=list)
    k_factor: float = 1.0  # every opening's resistance × this (a clogged screen)


class _Films(NamedTuple):
    """Convective coefficients of one evaluation [W/(m2 K)], per segment or scalar."""

    h1: np.ndarray | float  # L1 cavity face
    h2o: np.ndarray | float  # louver, outer sub-cavity side
    h2i: np.ndarray | float  # louver, inner side
    h3: np.ndarray | float  # L2 cavity face
    h4: np.ndarray | float  # each DGU face ↔ the gap gas
    h_out: np.ndarray | float
    h_in: np.ndarray | float


class PlantModel:
    """Network of one plant: topology, constants, right-hand side and Jacobian."""

    def __init__(self, cfg: PanelConfig, options: PlantOptions, params: TrueParameters) -> None:
        self.cfg, self.opt, self.params = cfg, options, params
        has_louver = cfg.louver is not None
        n = options.n_segments
        lay = self.lay = Layout.build(n, options.split_cavity and has_louver, options.plenums)
        geo = self.geo = Geometry.from_panel(cfg, n)
        self.nn = lay.n_nodes
        self.ny = self.nn + N_ACC
        self.cap0, self.vol, self.p_ref = capacities(cfg, lay, geo)
        self.cp = cfg.model.air_heat_capacity_jkgk
        self.credit = cfg.model.q_air_basis == "ventilation_credit"
        self.air = np.flatnonzero(self.vol > 0)
        self.variable_air = options.air_properties == "variable"
        self.col_nodes, self.col_w = column_weights(lay, geo)
        self.has_louver = has_louver
        lv = cfg.louver
        self.phis = np.asarray(lv.angles_deg() if lv else (0.0,), float)
        self.lw = lw_exchange_table(cfg, options, self.phis)  # (m, 3)
        gl = cfg.glazing
        self.eps1f, self.eps3b = gl.exterior.emissivity_front, gl.interior_inner.emissivity_back
        self.f23 = 1.0 / (1.0 / gl.interior_outer.emissivity_back
                          + 1.0 / gl.interior_inner.emissivity_front - 1.0)
        self.a_l = 2.0 * lv.slat_width_m / lv.slat_pitch_m if lv else 0.0
        self.gap = geo.depth / 2 if has_louver else geo.depth
        self.h_default = np.array(cfg.parameters.values("default", CONVECTIVE_NAMES))
        #: v_e of the slat film's factor (0: h_ca2 constant; docs/model.md#slat-film).
        self.slat_equal_ms = (panel_equal_speed_ms(cfg)
                              if options.slat_film_reference_speed_ms > 0 else 0.0)
        # Local wind of each segment relative to the façade centre (power law,
        # docs/model.md#plant-heat-transfer).
        a_site, _ = TERRAIN_PROFILE[cfg.site.terrain]
        z_seg = cfg.site.facade_height_m - 0.5 * geo.height + geo.centres(n)
        self.wind_profile = (np.maximum(z_seg, 0.5) / cfg.site.facade_height_m) ** a_site
        ops = cfg.openings
        area = np.array([getattr(ops, k).area_m2 if getattr(ops, k) else 0.0
                         for k in ("exterior_bottom", "exterior_top", "interior_bottom",
                                   "interior_top")])
        cd = np.array([getattr(ops, k).discharge_coefficient if getattr(ops, k) else 0.6
                       for k in ("exterior_bottom", "exterior_top", "interior_bottom",
                                 "interior_top")])
        self.openings = OpeningData(area, cd, geo.depth * geo.width, ops.min_opening_ratio,
                                    options.damper_model)
        self.p_room = ops.room_pressure_pa
        self.dp_t = ops.regularisation_pa
        top = self.topology = build_topology(cfg, options, lay, geo)
        self.links, self.n_sym_m2, self.gsl = top.links, top.n_sym_m2, top.group_slices
        self.n_up, self.n_dn, self.frac_adv = top.n_up, top.n_dn, top.frac_adv
        self.open_slices = top.open_slices
        self.bottom_list, self.top_list = top.bottom_nodes, top.top_nodes
        self.gs = np.zeros(self.links.sym_r.size)
        self.gs[self.n_sym_m2:] = top.conduction
        self.gb = np.zeros(self.links.bnd_r.size)
        self.ga = np.zeros(self.links.adv_r.size)
        self.slices = {k: lay.sl(k) for k in ("g1", "g2", "g3", "lv", "ao", "ai", "g6")}
        self.adv2 = Advection2(lay) if options.advection == "upwind2" else None
        self.slat_width = lv.slat_width_m if lv else geo.depth
        self.dgu_gap = gl.interior_gap_m
        # Distances of the segment faces from the inlet (upward / downward flow), for the
        # cell average of the developing-flow Nusselt number, twice (outer, inner gap).
        dz = geo.dz
        lo_up, hi_up = np.arange(n) * dz, (np.arange(n) + 1) * dz
        self.faces_up = np.tile(np.concatenate([lo_up, hi_up]), 2)
        self.faces_dn = np.tile(np.concatenate([geo.height - hi_up, geo.height - lo_up]), 2)
        self.conv_geo = ConvectionGeometry(geo.height, self.gap, self.slat_width, self.dgu_gap,
                                           dz, self.faces_up, self.faces_dn)
        i = lay.idx
        self.rad_a = np.concatenate([i("g2"), i("g1"), i("g1"), i("lv")])
        self.rad_b = np.concatenate([i("g3"), i("lv"), i("g2"), i("g2")])
        self.rad_factor = np.concatenate([np.full(n, self.f23), np.zeros(3 * n)])
        self.n_rad_fixed = n
        self.rad_bnd_eps = np.concatenate([np.full(n, self.eps1f), np.full(n, self.eps3b)])
        self.rad_bnd_t = np.zeros(2 * n)
        self.ctx: Piece | None = None
        self.evaluations = 0
        self.last: dict = {}

    # ------------------------------------------------------------------ helpers
    def capacity(self, T: np.ndarray) -> np.ndarray:
        """Node heat capacities at temperatures ``T`` [J/K]."""
        if not self.variable_air:
            return self.cap0
        cap = self.cap0.copy()
        cap[self.air] = variable_air_capacity(self.vol[self.air], T[self.air], self.p_ref,
                                              self.cp)
        return cap

    def stored_energy(self, T: np.ndarray) -> float:
        """U = Σ ∫C dT of all nodes relative to 0 K (ln form for variable air) [J]."""
        if not self.variable_air:
            return float(self.cap0 @ T)
        solid = np.ones(self.nn, bool)
        solid[self.air] = False
        k_air = self.p_ref * self.cp * self.vol[self.air] / R_AIR
        return float(self.cap0[solid] @ T[solid] + k_air @ np.log(T[self.air]))

    def angle_weights(self, phi_deg: float) -> tuple[int, float]:
        """Lower grid index and weight of ``phi_deg`` in the louver grid."""
        m = self.phis.size
        if m == 1:
            return 0, 0.0
        pos = (phi_deg - self.phis[0]) / (self.phis[1] - self.phis[0])
        i = min(max(int(np.floor(pos)), 0), m - 2)
        return i, float(min(max(pos - i, 0.0), 1.0))

    def louver_terms(self, phi_deg: float) -> tuple[np.ndarray, float, float]:
        """LW factors (3,), louver flow loss K_L [-] and lateral h_x·open [W/(m2 K)]."""
        i, w = self.angle_weights(phi_deg)
        lw = self.lw[i] if w == 0.0 else (1 - w) * self.lw[i] + w * self.lw[i + 1]
        lv = self.cfg.louver
        if lv is None:
            return lw, 0.0, 0.0
        phi = np.radians(phi_deg)
        k_l = float(louver_flow_loss(phi, depth_m=self.geo.depth, slat_width_m=lv.slat_width_m,
                                     slat_pitch_m=lv.slat_pitch_m, height_m=self.geo.height)
                    ) if self.opt.louver_flow_resistance else 0.0
        hx = self.opt.lateral_h_wm2k * float(lateral_open_fraction(
            phi, slat_width_m=lv.slat_width_m, slat_pitch_m=lv.slat_pitch_m))
        return lw, k_l, hx

    def resistances(self, ctx: Piece, t: float, k_l: float) -> list[float]:
        y = ctx.act.dampers_at(t).tolist()
        k = opening_resistance(self.openings, y, ctx.target_open_list, self.params.f, k_l)
        return k if ctx.k_factor == 1.0 else [v * ctx.k_factor for v in k]

    def set_piece(self, ctx: Piece, t0: float) -> None:
        """Install a piece and precompute what does not change inside it."""
        ctx.target_open_list = [bool(v) for v in ctx.target_open]
        phi = ctx.act.phi_at(t0)
        i, w = self.angle_weights(phi)
        st = ctx.static
        st["src_a"] = (1 - w) * ctx.src_a[i] + w * ctx.src_a[min(i + 1, self.phis.size - 1)]
        st["src_d"] = (1 - w) * ctx.src_d[i] + w * ctx.src_d[min(i + 1, self.phis.size - 1)]
        st["lw"], st["k_l"], st["hx"] = self.louver_terms(phi)
        if not (ctx.phi_moving or ctx.dampers_moving):
            ctx.k_static = self.resistances(ctx, t0, st["k_l"])
        self.ctx = ctx

    # ------------------------------------------------------------------ flows
    def flows(self, t: float, T: np.ndarray, p: float, t_out: float, t_in: float,
              wind: float, cp_b: float, cp_t: float, k_l: float,
              integral: float | None = None, column: np.ndarray | None = None) -> dict:
        """Opening flows and the column data at state ``T`` (see :mod:`plant_flow`).

        ``integral`` overrides ∫_0^Δz ρ dz [kg/m2] (used for the Jacobian); ``column``
        gives the air temperatures of the column (default ``T``).
        """
        ctx = self.ctx
        tc = (T if column is None else column)[self.col_nodes]
        rho_col = p / (R_AIR * tc)
        if integral is None:
            integral = float(rho_col @ self.col_w)
        bn, tn = self.bottom_list, self.top_list
        t_bot = T[bn[0]] if len(bn) == 1 else 0.5 * (T[bn[0]] + T[bn[1]])
        t_top = T[tn[0]] if len(tn) == 1 else 0.5 * (T[tn[0]] + T[tn[1]])
        rho_bot, rho_top = p / (R_AIR * t_bot), p / (R_AIR * t_top)
        rho_o, rho_i = p / (R_AIR * t_out), p / (R_AIR * t_in)
        dyn = 0.5 * rho_o * wind * wind
        g_int = GRAVITY * integral
        stack = self.geo.stack
        head = [dyn * cp_b, -rho_o * GRAVITY * stack + dyn * cp_t + g_int, self.p_room,
                self.p_room - rho_i * GRAVITY * stack + g_int]
        out = {"m": [0.0, 0.0, 0.0, 0.0], "integral": integral, "rho_col": rho_col,
               "tc": tc, "rho_mean": integral / stack, "t_bot": t_bot, "t_top": t_top,
               "args": (t, T, p, t_out, t_in, wind, cp_b, cp_t, k_l)}
        fp = ctx.flow
        if fp.mode == 0:
            return out
        if not (t_bot > 0.0 and t_top > 0.0):
            # Radau's Newton iteration can try a state far from the solution (-300 K seen):
            # such air has no density and no flows; NaN makes the solver reject the iterate
            # and shorten the step (scipy's collocation solve stops at non-finite values).
            out["m"] = [math.nan] * 4
            return out
        k = ctx.k_static if ctx.k_static is not None else self.resistances(ctx, t, k_l)
        rho_b = [rho_o, rho_o, rho_i, rho_i]
        rho_node = [rho_bot, rho_top, rho_bot, rho_top]
        if fp.mode == PAIR:
            m_ab = pair_flow(fp, head, rho_b, rho_node, k,
                             k_l / (2.0 * self.openings.cavity_area_m2**2))
            out["m"][fp.a], out["m"][fp.b] = m_ab, -m_ab
        elif fp.mode == NETWORK:
            m, ctx.pc = network_flows(fp, head, rho_b, rho_node, k, ctx.pc)
            out["m"] = m
        return out

    def advective(self, m: list[float]) -> np.ndarray:
        """Advective conductances ṁ c_p · fraction of every advective link [W/K]."""
        ga = self.ga
        cp = self.cp
        m_cav = m[EB] + m[IB]
        ga[:self.n_up] = max(m_cav, 0.0) * cp
        ga[self.n_up:self.n_up + self.n_dn] = max(-m_cav, 0.0) * cp
        for k, sl in enumerate(self.open_slices):
            ga[sl] = max(m[k], 0.0) * cp
        ga *= self.frac_adv
        return ga

    # ------------------------------------------------------------------ RHS
    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt of the plant at time ``t`` [K/s and W]."""
        self.evaluations += 1
        ctx = self.ctx
        T = y[:self.nn]
        s = (t - ctx.ts) * ctx.inv_len
        t_out, t_in, t_mrt, t_rad, p, wind, cp_b, cp_t = (ctx.fa + s * ctx.fd).tolist()
        src, lw, k_l, hx = self._sources_and_louver(t, s)
        fl = self.flows(t, T, p, t_out, t_in, wind, cp_b, cp_t, k_l)
        m = fl["m"]
        m_cav = m[EB] + m[IB]
        films = self._films(T, fl, m_cav, p, t_out, t_in, wind)
        gs = self._surface_conductances(T, films, lw, hx)
        gb = self._boundary_conductances(T, films, t_rad, t_mrt)
        return self._balance(t, T, gs, gb, fl, m_cav, src, (t_out, t_in, t_rad, t_mrt), p)

    def _sources_and_louver(self, t: float, s: float
                            ) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Absorbed short-wave per m² (interpolated in time, and in φ while the louver
        moves), the cavity long-wave factors, the slats' flow loss and the lateral h_x."""
        ctx = self.ctx
        if ctx.phi_moving:
            phi = ctx.act.phi_at(t)
            i, w = self.angle_weights(phi)
            j = min(i + 1, self.phis.size - 1)
            src = ((1 - w) * (ctx.src_a[i] + s * ctx.src_d[i])
                   + w * (ctx.src_a[j] + s * ctx.src_d[j]))
            lw, k_l, hx = self.louver_terms(phi)
            return src, lw, k_l, hx
        st = ctx.static
        return st["src_a"] + s * st["src_d"], st["lw"], st["k_l"], st["hx"]

    def _films(self, T: np.ndarray, fl: dict, m_cav: float, p: float, t_out: float,
               t_in: float, wind: float) -> _Films:
        """Convective coefficients of the surfaces [W/(m2 K)], per segment or constant,
        times the plant's multipliers."""
        ctx, opt, sl = self.ctx, self.opt, self.slices
        t1, t2, t3, t4 = T[sl["g1"]], T[sl["g2"]], T[sl["g3"]], T[sl["lv"]]
        to, ti = T[sl["ao"]], T[sl["ai"]]
        hs = ctx.h_scale
        speed = abs(m_cav) / (fl["rho_mean"] * self.openings.cavity_area_m2)
        if opt.convection == "constant":
            h = hs * self.h_default
            h1, h2o, h2i, h3 = h[Param.H_CA1], h[Param.H_CA2], h[Param.H_CA2], h[Param.H_CA3]
            if self.slat_equal_ms > 0.0:
                h2o = h2i = h2o * float(film_factor(
                    speed, equal_speed_ms=self.slat_equal_ms,
                    reference_speed_ms=opt.slat_film_reference_speed_ms))
            h_out, h_in = h[Param.H_OUT], h[Param.H_IN]
        else:
            c = coefficients(self.conv_geo, t1, t2, t3, t4, to, ti, speed=speed,
                             upward=m_cav >= 0, p=p, t_out=t_out, t_in=t_in,
                             wind=wind * self.wind_profile, windward=ctx.windward,
                             gap_model=opt.dgu_gap == "iso15099")
            h1, h3 = hs[Param.H_CA1] * c.h1, hs[Param.H_CA3] * c.h3
            h2o, h2i = hs[Param.H_CA2] * c.h2o, hs[Param.H_CA2] * c.h2i
            h_out, h_in = hs[Param.H_OUT] * c.h_out, hs[Param.H_IN] * c.h_in
        if opt.dgu_gap == "constant_h":
            h4 = hs[Param.H_CA4] * self.h_default[Param.H_CA4]
        elif opt.convection == "constant":
            h4 = hs[Param.H_CA4] * 2.0 * iso15099_gap(t2, t3, self.dgu_gap, self.geo.height, p)
        else:
            h4 = hs[Param.H_CA4] * 2.0 * c.h_gap
        return _Films(h1, h2o, h2i, h3, h4, h_out, h_in)

    def _surface_conductances(self, T: np.ndarray, films: _Films, lw: np.ndarray,
                              hx: float) -> np.ndarray:
        """Conductances of the links between nodes [W/K]: convection, the DGU gap, the
        cavity long-wave (secant σ(T_a² + T_b²)(T_a + T_b)) and the lateral exchange."""
        lay = self.lay
        gs = self.gs
        g = self.gsl
        gs[g[0]] = films.h1
        if not self.has_louver:
            gs[g[1]] = NO_LOUVER_LINK
        elif lay.split:
            gs[g[1]] = 0.5 * self.a_l * films.h2o
            gs[g[2]] = 0.5 * self.a_l * films.h2i
        else:
            gs[g[1]] = self.a_l * films.h2o
        gs[g[3]] = films.h3
        gs[g[4]] = films.h4
        gs[g[5]] = films.h4
        ta, tb = T[self.rad_a], T[self.rad_b]
        lwf = self.rad_factor
        lwf[self.n_rad_fixed:] = np.repeat(lw, lay.n)
        gs[g[6]] = lwf * SIGMA * (ta * ta + tb * tb) * (ta + tb)
        if lay.split:
            gs[g[7]] = hx
        gs[:self.n_sym_m2] *= self.geo.seg_area
        return gs

    def _boundary_conductances(self, T: np.ndarray, films: _Films, t_rad: float,
                               t_mrt: float) -> np.ndarray:
        """Conductances to the outdoor and room air and radiant temperatures [W/K]."""
        sl = self.slices
        gb = self.gb
        n = self.lay.n
        gb[0:n] = films.h_out
        gb[2 * n:3 * n] = films.h_in
        tr = np.concatenate((T[sl["g1"]], T[sl["g3"]]))
        te_r = self.rad_bnd_t
        te_r[:n] = t_rad
        te_r[n:] = t_mrt
        hr = self.rad_bnd_eps * SIGMA * (tr * tr + te_r * te_r) * (tr + te_r)
        gb[n:2 * n] = hr[:n]
        gb[3 * n:] = hr[n:]
        gb *= self.geo.seg_area
        return gb

    def _balance(self, t: float, T: np.ndarray, gs: np.ndarray, gb: np.ndarray, fl: dict,
                 m_cav: float, src: np.ndarray, bounds: tuple[float, float, float, float],
                 p: float) -> np.ndarray:
        """dT/dt of the nodes from the link flows and sources, then the accumulators."""
        nn, n = self.nn, self.lay.n
        t_out, t_in = bounds[0], bounds[1]
        m = fl["m"]
        te = np.concatenate((T, bounds))
        lk = self.links
        ga = self.advective(m)
        f_sym = gs * (te[lk.sym_c] - te[lk.sym_r])
        f_bnd = gb * (te[lk.bnd_c] - te[lk.bnd_r])
        f_adv = ga * (te[lk.adv_c] - te[lk.adv_r])
        q = np.bincount(lk.rows, np.concatenate((f_sym, -f_sym, f_bnd, f_adv)), minlength=nn)
        adv_total = float(f_adv.sum())
        face_out = None
        if self.adv2 is not None and m_cav != 0.0:
            q_corr, face_out = self.adv2.corrections(T, m_cav * self.cp,
                                                     self._inflow_mix(m, m_cav, t_out, t_in, T))
            q += q_corr
            adv_total += float(q_corr.sum())
        src_w = src * self.geo.seg_area
        q[:4 * n] += np.repeat(src_w[:4], n)
        cap = self.capacity(T)
        out = np.empty(self.ny)
        out[:nn] = q / cap
        bnd_total = float(f_bnd.sum())
        out[nn:] = (float(src_w[:4].sum()) * n, bnd_total, adv_total, abs(bnd_total),
                    -float(f_bnd[2 * n:].sum()), float(src_w[4]) * n,
                    self._q_air(m, fl, face_out, m_cav, t_out, t_in), float(src_w[5]) * n)
        self.last = {"cap": cap, "f_adv": f_adv, "flows": fl, "m_cav": m_cav, "t": t, "te": te,
                     "bnd_total": bnd_total, "face_out": face_out,
                     "p": p, "phi_deg": self.ctx.act.phi_at(t), "src": src}
        return out

    def opening_temperatures(self, fl: dict, face_out: float | None, m_cav: float
                             ) -> np.ndarray:
        """Temperature of the air at each opening EB, ET, IB, IT [K]: the bottom or top air
        node; with second-order advection and no plenums, the outflow end at its
        reconstructed face value."""
        t = np.array([fl["t_top"] if top else fl["t_bot"] for top in IS_TOP])
        if face_out is not None and not self.lay.plenums:
            downstream = np.array(IS_TOP) if m_cav > 0 else ~np.array(IS_TOP)
            t = np.where(downstream, t + face_out, t)
        return t

    def _q_air(self, m: list[float], fl: dict, face_out: float | None, m_cav: float,
               t_out: float, t_in: float) -> float:
        """Q_air into the room [W] (docs/model.md#q-air) with a = ṁ cavity → room at the temperature
        of the air leaving through IB/IT, b = ṁ room → cavity."""
        t_open = self.opening_temperatures(fl, face_out, m_cav)
        a = b = a_t = 0.0
        for k in (IB, IT):
            if m[k] < 0.0:
                a -= m[k]
                a_t -= m[k] * t_open[k]
            else:
                b += m[k]
        if a <= 0.0:
            return 0.0 if self.credit else self.cp * b * (t_out - t_in)
        t_sup = a_t / a
        if self.credit:
            return self.cp * (min(a, b) * (t_sup - t_in) + max(0.0, a - b) * (t_sup - t_out))
        return self.cp * (a * (t_sup - t_in) + max(0.0, b - a) * (t_out - t_in))

    def _inflow_mix(self, m: list[float], m_cav: float, t_out: float, t_in: float,
                    T: np.ndarray) -> float:
        """Mixed temperature of the openings feeding the inlet row [K] (no plenum)."""
        a, b = (m[0], m[2]) if m_cav > 0 else (m[1], m[3])
        a, b = max(a, 0.0), max(b, 0.0)
        if a + b <= 0.0:
            nodes = self.bottom_list if m_cav > 0 else self.top_list
            return float(np.mean(T[nodes]))
        return (a * t_out + b * t_in) / (a + b)

    def jac(self, t: float, y: np.ndarray) -> np.ndarray | csc_matrix:
        """Analytic Jacobian (see :func:`dsfd.sim.plant_jacobian.jacobian`)."""
        return jacobian(self, t, y)


def _sec(a: np.ndarray, b: np.ndarray | float) -> np.ndarray:
    """σ(T_a² + T_b²)(T_a + T_b): secant of σT⁴, so g (T_b − T_a) = σ(T_b⁴ − T_a⁴)."""
    return SIGMA * (a * a + b * b) * (a + b)
