"""Cavity airflow of the truth plant, solved inside the right-hand side (docs/model.md#airflow,
docs/model.md#plant-airflow).

Openings EB, ET, IB, IT (0..3) with mass flows positive INTO the cavity. The cavity is one
pressure node whose hydrostatic column is the integrated, stratified air column
(docs/model.md#plant-airflow): p_c(z) = P_c − g ∫_0^z ρ(T5(z')) dz', so each opening sees

    Δp_k = p_B,k − p_c(z_k) = head_k − P_c,    head_k = p_B,k + g ∫_0^{z_k} ρ dz.

Two open dampers (regimes 1–8): closed form with the inflow density at the inlet and the
cavity density at the outlet (docs/model.md#path-flows), or the power law of the lumped model for
the diagonal regimes (``diagonal_flow='power_law'``). Three or four open dampers (regime 9, or
while dampers move between regimes): Σ ṁ_k(P_c) = 0 by safeguarded Newton (docs/model.md#one-node).
All laws are regularised below Δp_t with the IBPSA polynomial (docs/model.md#regularisation).

These functions run thousands of times per simulated hour, so they work on Python floats
(four openings) rather than numpy arrays.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dsfd.physics.airflow import louver_series_factor
from dsfd.sim.plant.physics import damper_loss_scalar

EB, ET, IB, IT = 0, 1, 2, 3
IS_TOP = (False, True, False, True)
#: IBPSA regularisation slope parameter γ (docs/model.md#regularisation).
_GAMMA = 1.5

NONE, PAIR, NETWORK = 0, 1, 2


def reg_coefficients(m: float) -> tuple[float, float, float, float]:
    """IBPSA polynomial coefficients a, b, c, d for exponent ``m``
    (docs/model.md#regularisation)."""
    return (_GAMMA, m * m / 8 - 3 * _GAMMA - 1.5 * m + 35 / 8,
            -m * m / 4 + 3 * _GAMMA + 2.5 * m - 21 / 4, m * m / 8 - _GAMMA - m + 15 / 8)


SQRT_COEF = reg_coefficients(0.5)


def reg_power(dp: float, coef: float, m: float, dp_t: float,
              abcd: tuple[float, float, float, float]) -> float:
    """coef·sgn(Δp)|Δp|^m, C²-smooth below Δp_t (IBPSA ``powerLawFixedM``) [flow units]."""
    if dp >= dp_t:
        return coef * dp**m
    if dp <= -dp_t:
        return -coef * (-dp) ** m
    a, b, c, d = abcd
    p = dp / dp_t
    p2 = p * p
    return coef * dp_t**m * p * (a + p2 * (b + p2 * (c + p2 * d)))


def reg_power_slope(dp: float, coef: float, m: float, dp_t: float,
                    abcd: tuple[float, float, float, float]) -> float:
    """d/dΔp of :func:`reg_power` (≥ 0)."""
    mag = abs(dp)
    if mag >= dp_t:
        return coef * m * mag ** (m - 1.0)
    a, b, c, d = abcd
    p2 = (dp / dp_t) ** 2
    return coef * dp_t ** (m - 1.0) * (a + p2 * (3 * b + p2 * (5 * c + p2 * 7 * d)))


@dataclass(frozen=True)
class OpeningData:
    """Fixed opening data of a panel (arrays (4,))."""

    area_m2: np.ndarray
    discharge: np.ndarray
    cavity_area_m2: float
    floor: float  # minimum OR of an open damper (docs/model.md#openings)
    damper_model: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "area_list", tuple(float(a) for a in self.area_m2))
        object.__setattr__(self, "cd_list", tuple(float(c) for c in self.discharge))


def opening_resistance(od: OpeningData, y: Sequence[float], target_open: Sequence[bool],
                       f: float, k_louver: float) -> list[float]:
    """Per-opening loss coefficients K_k [1/m4] (inf = shut).

    Notes
    -----
    ``orifice`` (lumped, docs/model.md#plant-airflow): 1/(C_d y_eff A_d)², y_eff = max(y, floor) for
    a damper of the commanded set, y otherwise; ``exponential`` (truth, docs/model.md#plant-airflow,
    docs/model.md#true-parameters): ζ(y)/A_d². Both add half the cavity loss (f + K_L)/(2A_c²) to
    each opening, so a two-opening path has Σζ(A_c/A_d)² + K_L + f referenced to the cavity velocity
    (docs/model.md#one-node, docs/model.md#true-parameters).
    """
    cavity = (f + k_louver) / (2.0 * od.cavity_area_m2**2)
    out = []
    for area, cd, yk, want in zip(od.area_list, od.cd_list, y, target_open, strict=True):
        if area <= 0.0:
            out.append(math.inf)
        elif od.damper_model == "orifice":
            eff = cd * (max(yk, od.floor) if want else yk) * area
            out.append(1.0 / (eff * eff) + cavity if eff > 0 else math.inf)
        elif want or yk > 0:
            out.append(damper_loss_scalar(yk) / (area * area) + cavity)
        else:
            out.append(math.inf)
    return out


@dataclass
class FlowPiece:
    """The flow problem of one integration piece (fixed damper set)."""

    mode: int
    a: int = 0
    b: int = 0
    power: bool = False
    power_coef: float = 0.0
    n: float = 0.5
    abcd_n: tuple[float, float, float, float] = SQRT_COEF
    active: tuple[int, ...] = ()
    dp_t: float = 0.01


def pair_flow(fp: FlowPiece, head: list[float], rho_b: list[float], rho_node: list[float],
              k: list[float], louver_beta: float = 0.0) -> float:
    """Mass flow a → b [kg/s] of a two-opening path.

    ``louver_beta`` = K_L/(2 A_c²) [1/m4]: the slats' loss, in series with the power law of
    ``diagonal_flow='power_law'`` as in the lumped model (docs/model.md#louver-flow-loss); the
    orifice paths have it in ``k`` already.
    """
    a, b = fp.a, fp.b
    dp = head[a] - head[b]
    if dp >= 0.0:
        r_in, r_out, k_in, k_out = rho_b[a], rho_node[b], k[a], k[b]
    else:
        r_in, r_out, k_in, k_out = rho_b[b], rho_node[a], k[b], k[a]
    if fp.power:
        q = reg_power(dp, fp.power_coef, fp.n, fp.dp_t, fp.abcd_n)
        if louver_beta > 0.0:
            q *= float(louver_series_factor(q, dp, fp.n, r_out, louver_beta))
        return r_in * q
    coef = math.sqrt(2.0 / (k_in / r_in + k_out / r_out))
    return reg_power(dp, coef, 0.5, fp.dp_t, SQRT_COEF)


def network_flows(fp: FlowPiece, head: list[float], rho_b: list[float],
                  rho_node: list[float], k: list[float], pc0: float,
                  tol: float = 1e-13) -> tuple[list[float], float]:
    """Opening flows [kg/s] and cavity pressure P_c [Pa] with three or four open openings.

    Σ_k ṁ_k(P_c) = 0 with ṁ_k = reg(head_k − P_c; C_k = sqrt(2ρ_up,k/K_k)), ρ_up the
    boundary density for inflow and the cavity node's for outflow (docs/model.md#one-node). Σṁ falls
    strictly with P_c: Newton from the previous root, kept inside a shrinking bracket.
    """
    act = fp.active
    heads = [head[i] for i in act]
    lo, hi = min(heads) - 1.0, max(heads) + 1.0
    pc = pc0 if lo < pc0 < hi else 0.5 * (lo + hi)
    inv_k = [1.0 / k[i] for i in act]
    for _ in range(60):
        total = 0.0
        slope = 0.0
        for j, i in enumerate(act):
            dp = heads[j] - pc
            coef = math.sqrt(2.0 * (rho_b[i] if dp > 0 else rho_node[i]) * inv_k[j])
            total += reg_power(dp, coef, 0.5, fp.dp_t, SQRT_COEF)
            slope += reg_power_slope(dp, coef, 0.5, fp.dp_t, SQRT_COEF)
        if total > 0:
            lo = pc
        else:
            hi = pc
        if abs(total) <= tol or hi - lo <= 1e-12 * (1.0 + abs(pc)):
            break
        step = pc + total / slope if slope > 0 else 0.5 * (lo + hi)
        pc = step if lo < step < hi else 0.5 * (lo + hi)
    m = [0.0, 0.0, 0.0, 0.0]
    for j, i in enumerate(act):
        dp = heads[j] - pc
        coef = math.sqrt(2.0 * (rho_b[i] if dp > 0 else rho_node[i]) * inv_k[j])
        m[i] = reg_power(dp, coef, 0.5, fp.dp_t, SQRT_COEF)
    return m, pc
