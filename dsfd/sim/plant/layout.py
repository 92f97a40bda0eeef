"""Node layout, capacities and link topology of the stratified truth plant
(docs/model.md#plant-layout).

Nodes are stored kind-major: ``g1`` (L1), ``g2`` (L2), ``g3`` (L3), ``lv`` (louver),
``ao`` (cavity air, outer sub-cavity or the whole cavity), ``ai`` (inner sub-cavity, only
with ``split_cavity``), ``g6`` (DGU gap gas), each a block of N segments numbered from the
bottom, then the optional plenum nodes ``pb`` (bottom row) and ``pt`` (top row).

Heat exchange is written as *row links*: a link (r, c, g) adds g (T_c − T_r) [W] to node r,
where c may index a boundary temperature (appended after the nodes: T_o, T_i, T_rad,o,
T_mrt). Symmetric links are applied to both ends; advective links (ṁ c_p from an upstream
node or boundary) only to the receiving node. The topology is fixed per plant; only the
conductances change with the state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.physics.boundary import standard_pressure_pa
from dsfd.physics.constants import R_AIR
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.flow import IS_TOP

#: Boundary temperatures appended after the nodes, in this order.
BOUNDARY = ("t_out", "t_in", "t_rad", "t_mrt")
B_OUT, B_IN, B_RAD, B_MRT = range(4)
#: Louver-to-air conductance and louver capacity of a panel without a louver (as the lumped
#: model): the node follows the cavity air [W/(m2 K)], [J/(m2 K)].
NO_LOUVER_LINK, NO_LOUVER_CAPACITY = 10.0, 1.0


@dataclass(frozen=True)
class Layout:
    """Indices of the plant's nodes."""

    n: int
    split: bool
    plenums: bool
    kinds: tuple[str, ...]

    @classmethod
    def build(cls, n: int, split: bool, plenums: bool) -> Layout:
        kinds = ("g1", "g2", "g3", "lv", "ao") + (("ai",) if split else ()) + ("g6",)
        return cls(n, split, plenums, kinds)

    def sl(self, kind: str) -> slice:
        """Slice of a per-segment kind (``ai`` is ``ao`` without a split)."""
        if kind == "ai" and not self.split:
            kind = "ao"
        i = self.kinds.index(kind)
        return slice(i * self.n, (i + 1) * self.n)

    def idx(self, kind: str) -> np.ndarray:
        s = self.sl(kind)
        return np.arange(s.start, s.stop)

    @property
    def pb(self) -> int:
        return len(self.kinds) * self.n

    @property
    def pt(self) -> int:
        return len(self.kinds) * self.n + 1

    @property
    def n_nodes(self) -> int:
        return len(self.kinds) * self.n + (2 if self.plenums else 0)

    def air_nodes(self) -> np.ndarray:
        """Indices of all cavity air nodes (sub-cavities and plenums)."""
        out = [self.idx("ao")] + ([self.idx("ai")] if self.split else [])
        if self.plenums:
            out.append(np.array([self.pb, self.pt]))
        return np.concatenate(out)


@dataclass(frozen=True)
class Geometry:
    """Vertical geometry of the plant (SI)."""

    width: float
    height: float  # glazed height H_g
    depth: float
    dz: float  # segment height δz = H_g/N (docs/model.md#plant-layout)
    stack: float  # Δz between damper centres
    z0: float  # bottom of the glazed section above the bottom damper centre
    damper_row: float  # plenum height h_d
    seg_area: float  # W δz

    @classmethod
    def from_panel(cls, cfg: PanelConfig, n: int) -> Geometry:
        fac = cfg.facade
        stack = cfg.openings.stack_height_m
        return cls(width=fac.width_m, height=fac.glazed_height_m, depth=fac.cavity_depth_m,
                   dz=fac.glazed_height_m / n, stack=stack,
                   z0=0.5 * (stack - fac.glazed_height_m),
                   damper_row=max(stack - fac.glazed_height_m, 0.05),
                   seg_area=fac.width_m * fac.glazed_height_m / n)

    def centres(self, n: int) -> np.ndarray:
        """Segment centre heights above the bottom of the glazed section [m]."""
        return (np.arange(n) + 0.5) * self.dz


def column_weights(lay: Layout, geo: Geometry) -> tuple[np.ndarray, np.ndarray]:
    """Air nodes and lengths [m] of the hydrostatic column from z = 0 to the stack height.

    Each segment contributes its overlap with [0, Δz]; the end pieces below and above the
    glazed section take the plenum temperature, or with plenums off the adjacent
    segment's (docs/model.md#plant-layout). With a split cavity each sub-cavity carries half the
    weight.
    """
    n = lay.n
    lo = geo.z0 + np.arange(n) * geo.dz
    hi = lo + geo.dz
    seg = np.clip(np.minimum(hi, geo.stack) - np.maximum(lo, 0.0), 0.0, None)
    bottom_end = max(geo.z0, 0.0)
    top_end = max(geo.stack - (geo.z0 + geo.height), 0.0)
    share = 0.5 if lay.split else 1.0
    nodes, weights = [], []
    for kind in ("ao", "ai") if lay.split else ("ao",):
        w = seg * share
        if not lay.plenums:
            w[0] += bottom_end * share
            w[-1] += top_end * share
        nodes.append(lay.idx(kind))
        weights.append(w)
    if lay.plenums:
        nodes.append(np.array([lay.pb, lay.pt]))
        weights.append(np.array([bottom_end, top_end]))
    return np.concatenate(nodes), np.concatenate(weights)


def capacities(cfg: PanelConfig, lay: Layout,
               geo: Geometry) -> tuple[np.ndarray, np.ndarray, float]:
    """Node heat capacities [J/K], the air-node mask and the variable-air factor.

    Returns
    -------
    cap : (n_nodes,), [J/K]
        With constant air properties (docs/model.md#plant-switches) ρ_a c_p V from the model
        options.
    air_volume : (n_nodes,), [m3]
        Air volume of each air node (0 for solid nodes).
    p_ref : float, [Pa]
        Standard pressure at the site elevation; with ``air_properties='variable'`` an air
        node holds p_ref c_p V/(R T) [J/K].
    """
    gl, mo = cfg.glazing, cfg.model
    a = geo.seg_area
    cap = np.zeros(lay.n_nodes)
    vol = np.zeros(lay.n_nodes)

    def pane(layer) -> float:
        return layer.density_kgm3 * layer.heat_capacity_jkgk * layer.thickness_m * a

    cap[lay.sl("g1")] = pane(gl.exterior)
    cap[lay.sl("g2")] = pane(gl.interior_outer)
    cap[lay.sl("g3")] = pane(gl.interior_inner)
    lv = cfg.louver
    if lv is not None:
        cap[lay.sl("lv")] = (lv.density_kgm3 * lv.heat_capacity_jkgk * lv.slat_thickness_m
                             * lv.slat_width_m / lv.slat_pitch_m * a)
    else:
        cap[lay.sl("lv")] = NO_LOUVER_CAPACITY * a
    cavity = geo.depth * a / (2 if lay.split else 1)
    vol[lay.sl("ao")] = cavity
    vol[lay.sl("ai")] = cavity
    vol[lay.sl("g6")] = gl.interior_gap_m * a
    if lay.plenums:
        vol[[lay.pb, lay.pt]] = geo.width * geo.depth * geo.damper_row
    rho_cp = mo.air_density_kgm3 * mo.air_heat_capacity_jkgk
    air = vol > 0
    cap[air] = rho_cp * vol[air]
    p_ref = standard_pressure_pa(cfg.site.elevation_m)
    return cap, vol, p_ref


def variable_air_capacity(vol: np.ndarray, t_k: np.ndarray, p_ref: float,
                          cp: float) -> np.ndarray:
    """ρ(T) c_p V with ρ = p_ref/(R T) [J/K] (air_properties='variable')."""
    return p_ref * cp * vol / (R_AIR * t_k)


@dataclass(frozen=True)
class Links:
    """Fixed topology: symmetric, boundary and advective row links (see module doc)."""

    sym_r: np.ndarray
    sym_c: np.ndarray
    bnd_r: np.ndarray
    bnd_c: np.ndarray  # into the extended temperature vector
    adv_r: np.ndarray
    adv_c: np.ndarray
    rows: np.ndarray  # rows of the single bincount: sym_r, sym_c, bnd_r, adv_r
    jac_flat: np.ndarray  # flat (n×n) Jacobian positions of the weights of jac_weights
    adv_internal: np.ndarray  # advective links whose source is a node


def build_links(lay: Layout, sym: list[tuple[np.ndarray, np.ndarray]],
                bnd: list[tuple[np.ndarray, int]],
                adv: list[tuple[np.ndarray, np.ndarray]]) -> Links:
    """Concatenate link groups (in the order the conductances will be given)."""
    nn = lay.n_nodes
    sym_r = np.concatenate([r for r, _ in sym]).astype(int)
    sym_c = np.concatenate([c for _, c in sym]).astype(int)
    bnd_r = np.concatenate([r for r, _ in bnd]).astype(int)
    bnd_c = np.concatenate([np.full(r.size, nn + b) for r, b in bnd]).astype(int)
    adv_r = np.concatenate([r for r, _ in adv]).astype(int)
    adv_c = np.concatenate([c for _, c in adv]).astype(int)
    rows = np.concatenate([sym_r, sym_c, bnd_r, adv_r])
    internal = adv_c < nn
    jac_flat = np.concatenate([
        sym_r * nn + sym_r, sym_r * nn + sym_c, sym_c * nn + sym_c, sym_c * nn + sym_r,
        bnd_r * nn + bnd_r, adv_r * nn + adv_r,
        adv_r[internal] * nn + adv_c[internal],
    ])
    return Links(sym_r, sym_c, bnd_r, bnd_c, adv_r, adv_c, rows, jac_flat, internal)


@dataclass(frozen=True)
class Topology:
    """Links of a plant and how the right-hand side fills their conductances.

    Attributes
    ----------
    links : Links
    n_sym_m2 : int
        Symmetric links given per m² façade (× segment area); the rest (vertical glass
        conduction, ``conduction`` [W/K]) are absolute.
    group_slices : list of slice
        Conductance groups: 0 L1–air, 1 louver–outer air, 2 louver–inner air, 3 L2–air,
        4/5 DGU faces–gas, 6 radiation (L2–L3, L1–louver, L1–L2, louver–L2), 7 sub-cavity
        exchange.
    n_up, n_dn : int
        Advective chain links for upward / downward flow (then the four openings').
    frac_adv : ndarray
        Share of the flow each advective link carries.
    open_slices : list of slice
        Advective links of the openings EB, ET, IB, IT.
    bottom_nodes, top_nodes : list of int
        Air nodes at the bottom and top damper rows.
    """

    links: Links
    n_sym_m2: int
    group_slices: list[slice]
    conduction: np.ndarray
    n_up: int
    n_dn: int
    frac_adv: np.ndarray
    open_slices: list[slice]
    bottom_nodes: list[int]
    top_nodes: list[int]


def build_topology(cfg: PanelConfig, opt: PlantOptions, lay: Layout,
                   geo: Geometry) -> Topology:
    """Every link of the plant (docs/model.md#network per segment, docs/model.md#plant-layout)."""
    n = lay.n
    i = lay.idx
    sym = [(i("g1"), i("ao")), (i("lv"), i("ao"))]
    if lay.split:
        sym.append((i("lv"), i("ai")))
    sym += [(i("g2"), i("ai")), (i("g2"), i("g6")), (i("g3"), i("g6")), (i("g2"), i("g3")),
            (i("g1"), i("lv")), (i("g1"), i("g2")), (i("lv"), i("g2"))]
    if lay.split:
        sym.append((i("ao"), i("ai")))
    n_sym_m2 = sum(r.size for r, _ in sym)
    # Slices of the conductance groups: 0 L1–air, 1 louver–outer air, 2 louver–inner
    # air, 3 L2–air, 4/5 DGU faces–gas, 6 radiation (L2–L3, L1–louver, L1–L2,
    # louver–L2), 7 sub-cavity exchange.
    sizes = [n, n, n if lay.split else 0, n, n, n, 4 * n, n if lay.split else 0]
    ends = np.cumsum(sizes)
    gsl = [slice(int(e - z), int(e)) for e, z in zip(ends, sizes, strict=True)]
    cond = np.zeros(0)
    if opt.glass_vertical_conduction and n > 1:
        gl = cfg.glazing
        for kind, layer in (("g1", gl.exterior), ("g2", gl.interior_outer),
                            ("g3", gl.interior_inner)):
            sym.append((i(kind)[:-1], i(kind)[1:]))
            g = opt.glass_conductivity_wmk * layer.thickness_m * geo.width / geo.dz
            cond = np.append(cond, np.full(n - 1, g))
    bnd = [(i("g1"), B_OUT), (i("g1"), B_RAD), (i("g3"), B_IN), (i("g3"), B_MRT)]
    adv, frac_up, frac_dn = [], [], []
    subs = ("ao", "ai") if lay.split else ("ao",)
    share = 1.0 / len(subs)
    for direction, fracs in ((1, frac_up), (-1, frac_dn)):
        for kind in subs:
            seg = i(kind)
            recv, src = (seg[1:], seg[:-1]) if direction > 0 else (seg[:-1], seg[1:])
            if lay.plenums:
                if direction > 0:
                    recv = np.concatenate([[seg[0]], recv, [lay.pt]])
                    src = np.concatenate([[lay.pb], src, [seg[-1]]])
                else:
                    recv = np.concatenate([[seg[-1]], recv, [lay.pb]])
                    src = np.concatenate([[lay.pt], src, [seg[0]]])
            adv.append((recv, src))
            fracs.append(np.full(recv.size, share))
    n_up = sum(f.size for f in frac_up)
    n_dn = sum(f.size for f in frac_dn)
    frac_open = []
    nn = lay.n_nodes
    for k in range(4):
        top = IS_TOP[k]
        boundary = nn + (B_OUT if k in (0, 1) else B_IN)
        if lay.plenums:
            recv = np.array([lay.pt if top else lay.pb])
        else:
            recv = np.array([i(kind)[-1 if top else 0] for kind in subs])
        adv.append((recv, np.full(recv.size, boundary)))
        frac_open.append(np.full(recv.size, 1.0 / recv.size))
    frac_adv = np.concatenate(frac_up + frac_dn + frac_open)
    open_slices = []
    pos = n_up + n_dn
    for f in frac_open:
        open_slices.append(slice(pos, pos + f.size))
        pos += f.size
    links = build_links(lay, sym, bnd, adv)
    # The nodes at the bottom and top openings (their air leaves there).
    if lay.plenums:
        bottom, top = np.array([lay.pb]), np.array([lay.pt])
    else:
        bottom = np.array([i(k)[0] for k in subs])
        top = np.array([i(k)[-1] for k in subs])
    return Topology(links=links, n_sym_m2=n_sym_m2, group_slices=gsl, conduction=cond,
                    n_up=n_up, n_dn=n_dn, frac_adv=frac_adv, open_slices=open_slices,
                    bottom_nodes=[int(v) for v in bottom], top_nodes=[int(v) for v in top])

