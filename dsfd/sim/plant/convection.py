"""All convective coefficients of the truth plant in one pass (the right-hand side's hot path).

Evaluates exactly the correlations of :mod:`dsfd.sim.plant.physics` (Churchill–Chu natural
convection, developing laminar flow between the glass and the louver, laminar flow along
the slats, the cubic mixed-convection blend, DOE-2 exterior, ISO 15099 room side and closed
gap), but computes the air properties once for all film temperatures: the right-hand side
runs some 10⁵ times per simulated day, and the per-call overhead of a dozen small numpy
functions dominated it. ``tests/sim/test_plant_physics.py`` checks the two against each
other.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dsfd.physics.constants import GRAVITY, R_AIR
from dsfd.sim.plant.physics import (
    _CC_FACTOR,
    CP_AIR,
    DT_SMOOTH_K,
    LEEWARD_AB,
    PR_AIR,
    WINDWARD_AB,
)

_EPS2 = DT_SMOOTH_K * DT_SMOOTH_K
_PR_017 = 0.0358 * PR_AIR**0.17
_PR_13 = 0.664 * PR_AIR ** (1.0 / 3.0)


class Coefficients(NamedTuple):
    """Convective coefficients per segment [W/(m2 K)] (before the true multipliers)."""

    h1: np.ndarray  # L1 cavity face ↔ outer air
    h2o: np.ndarray  # louver ↔ outer air (per slat face area)
    h2i: np.ndarray  # louver ↔ inner air
    h3: np.ndarray  # L2 cavity face ↔ inner air
    h_out: np.ndarray  # L1 exterior
    h_in: np.ndarray  # L3 room face
    h_gap: np.ndarray  # ISO 15099 closed-gap conductance h_c (face ↔ gas is 2 h_c)


class ConvectionGeometry(NamedTuple):
    height: float  # H_g [m]
    gap: float  # glass–louver spacing b [m]; D_h = 2b
    slat_width: float  # [m]
    dgu_gap: float  # [m]
    dz: float  # segment height [m]
    faces_up: np.ndarray  # (4N,) face distances from the inlet, upward flow
    faces_dn: np.ndarray  # (4N,) downward flow


def coefficients(geo: ConvectionGeometry, t1: np.ndarray, t2: np.ndarray, t3: np.ndarray,
                 t4: np.ndarray, to: np.ndarray, ti: np.ndarray, *, speed: float,
                 upward: bool, p: float, t_out: float, t_in: float, wind: np.ndarray,
                 windward: bool, gap_model: bool) -> Coefficients:
    """Coefficients of every segment for panes t1..t3, louver t4, sub-cavity air to/ti [K].

    ``speed`` [m/s] is the mean cavity speed, ``upward`` its direction, ``wind`` [m/s] the
    local wind per segment; ``gap_model`` computes the ISO 15099 DGU gap (else zeros).
    """
    n = t1.size
    # Film/property temperatures: natural convection of L1/louver/louver/L2 (4N), forced
    # convection at the air temperatures (to, ti, mean) (3N), room film (N), gap mean (N).
    surf = np.concatenate((t1, t4, t4, t2))
    air = np.concatenate((to, to, ti, ti))
    t_mf = t_in + 0.25 * (t3 - t_in)
    tf = np.concatenate((0.5 * (surf + air), to, ti, 0.5 * (to + ti), t_mf, 0.5 * (t2 + t3)))
    # An implicit solver's rejected trial step can hand in absurd temperatures; keep the
    # property fits (linear in T) positive there so they give a finite, not NaN, answer.
    tf = np.maximum(tf, 150.0)
    k = 2.873e-3 + 7.76e-5 * tf
    mu = 3.723e-6 + 4.94e-8 * tf
    rho = p / (R_AIR * tf)
    # ρ²/(T μ k): the Rayleigh number per g c_p L³ |ΔT| (ν α = μ k / (ρ² c_p)).
    ra_unit = GRAVITY * CP_AIR * rho * rho / (tf * mu * k)
    d_nat = surf - air
    d_room = t3 - t_in
    d_gap = t2 - t3
    dt = np.sqrt(np.concatenate((d_nat, d_room, d_gap)) ** 2 + _EPS2)
    h_g = geo.height
    i_room, i_gap = 7 * n, 8 * n
    # Churchill & Chu (1975), vertical plate of height H_g.
    ra = ra_unit[:4 * n] * dt[:4 * n] * h_g**3
    hn = (0.825 + _CC_FACTOR * ra ** (1.0 / 6.0)) ** 2 * k[:4 * n] / h_g
    # Developing laminar flow between parallel plates (Stephan), cell average of x Nu_m.
    dh = 2.0 * geo.gap
    faces = geo.faces_up if upward else geo.faces_dn
    nu_air = mu[4 * n:6 * n] / rho[4 * n:6 * n]
    k_air = k[4 * n:6 * n]
    # Faces are ordered (lo, hi) of the outer gap, then of the inner gap.
    re_pr = np.repeat((speed * dh * PR_AIR / nu_air).reshape(2, n), 2, axis=0).ravel()
    g = dh * re_pr / np.maximum(faces, 1e-3)
    nu_m = 7.55 + 0.024 * g**1.14 / (1.0 + _PR_017 * g**0.64)
    xh = (faces * nu_m).reshape(4, n)
    k_pair = k_air.reshape(2, n)
    hg_o = (xh[1] - xh[0]) / geo.dz * k_pair[0] / dh
    hg_i = (xh[3] - xh[2]) / geo.dz * k_pair[1] / dh
    # Laminar flat plate along the slats (Pohlhausen), Re regularised.
    k_s, mu_s, rho_s = k[6 * n:7 * n], mu[6 * n:7 * n], rho[6 * n:7 * n]
    re_s = speed * geo.slat_width * rho_s / mu_s
    hsl = _PR_13 * (re_s * re_s + 1.0) ** 0.25 * k_s / geo.slat_width
    hf = np.concatenate((hg_o, hsl, hsl, hg_i))
    hc = np.cbrt(hn**3 + hf**3)
    # ISO 15099 room side: Nu = 0.56 Ra_H^¼.
    ra_room = ra_unit[i_room:i_gap] * dt[4 * n:5 * n] * h_g**3
    h_in = 0.56 * ra_room**0.25 * k[i_room:i_gap] / h_g
    # DOE-2 exterior glass: sqrt(h_n² + (a V^b)²), h_n = 1.31 |ΔT|^⅓.
    a, b = WINDWARD_AB if windward else LEEWARD_AB
    d_out = t1 - t_out
    hn_out = 1.31 * np.cbrt(np.sqrt(d_out * d_out + _EPS2))
    hf_out = a * np.maximum(wind, 0.0) ** b
    h_out = np.sqrt(hn_out * hn_out + hf_out * hf_out)
    if gap_model:
        d = geo.dgu_gap
        ra_g = ra_unit[i_gap:] * dt[5 * n:] * d**3
        nu1 = np.where(ra_g > 5e4, 0.0673838 * np.cbrt(ra_g),
                       np.where(ra_g > 1e4, 0.028154 * ra_g**0.4134,
                                1.0 + 1.7596678e-10 * ra_g**2.2984755))
        nu2 = 0.242 * (ra_g * d / h_g) ** 0.272
        h_gap = np.maximum(nu1, nu2) * k[i_gap:] / d
    else:
        h_gap = np.zeros(n)
    return Coefficients(hc[:n], hc[n:2 * n], hc[2 * n:3 * n], hc[3 * n:], h_out, h_in, h_gap)
