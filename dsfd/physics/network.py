"""The six-node thermal network of the façade and its state-space assembly (docs/model.md#network).

Nodes (0-based index → paper state): 0 → x1 exterior pane L1, 1 → x2 DGU outer pane L2,
2 → x3 DGU inner pane L3, 3 → x4 louver, 4 → x5 cavity air, 5 → x6 DGU gap gas.
All balances are per m² of glazed façade [W/m2]; the network is C ẋ = L x + q with L
symmetric (every internal link is added to both nodes, boundary links only to the
diagonal), which is what makes the exact ZOH of :mod:`dsfd.physics.zoh` cheap.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

N_STATES = 6
X1, X2, X3, X4, X5, X6 = range(6)

#: Internal links (i, j) in a fixed order; conductances are given in this order.
LINKS: tuple[tuple[int, int], ...] = (
    (X1, X5),  # h_ca1
    (X4, X5),  # a_L·h_ca2 (louver, both faces)
    (X2, X5),  # h_ca3
    (X2, X6),  # h_ca4
    (X3, X6),  # h_ca4
    (X2, X3),  # h_r,23 (DGU gap radiation)
    (X1, X4),  # g_14 (cavity long-wave)
    (X1, X2),  # g_12
    (X4, X2),  # g_42
)
# Each link conductance g_l adds −g_l to L[i,i], L[j,j] and +g_l to L[i,j], L[j,i]; as a
# (links × 36) matrix the whole Laplacian is one matmul of the conductance vector.
_LINK_TO_LAPLACIAN = np.zeros((len(LINKS), N_STATES * N_STATES))
for _l, (_i, _j) in enumerate(LINKS):
    for _a, _b, _sign in ((_i, _i, -1.0), (_j, _j, -1.0), (_i, _j, 1.0), (_j, _i, 1.0)):
        _LINK_TO_LAPLACIAN[_l, _a * N_STATES + _b] += _sign
_DIAG = np.arange(N_STATES) * (N_STATES + 1)


class Boundary(NamedTuple):
    """Boundary links of one step (arrays broadcast over the batch).

    Attributes
    ----------
    h_out, h_rad_out : [W/(m2 K)]
        L1 to outdoor air T_o and to the exterior radiant temperature T_rad,o.
    h_in, h_rad_in : [W/(m2 K)]
        L3 to room air T_i and to the room mean radiant temperature T_mrt.
    g_adv : [W/(m2 K)]
        Advective conductance c_p ṁ_in / A_f of the air entering the cavity.
    t_out, t_rad_out, t_in, t_mrt, t_inflow : [K]
        Boundary temperatures (t_inflow: mixed temperature of the cavity inflow).
    """

    h_out: np.ndarray
    h_rad_out: np.ndarray
    h_in: np.ndarray
    h_rad_in: np.ndarray
    g_adv: np.ndarray
    t_out: np.ndarray
    t_rad_out: np.ndarray
    t_in: np.ndarray
    t_mrt: np.ndarray
    t_inflow: np.ndarray


def assemble(conductance: np.ndarray, bnd: Boundary,
             sources: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Build L and q of C ẋ = L x + q (docs/model.md#network).

    Parameters
    ----------
    conductance : array (..., 9), [W/(m2 K)]
        Internal link conductances in the order of :data:`LINKS`.
    bnd : Boundary
    sources : array (..., 4), [W/m2]
        Absorbed short-wave S1 (L1), S2 (L2), S3 (L3), S4 (louver) (docs/model.md#multilayer).

    Returns
    -------
    lap : ndarray (..., 6, 6), [W/(m2 K)]
        Symmetric negative definite conductance matrix.
    q : ndarray (..., 6), [W/m2]
    """
    lap = conductance @ _LINK_TO_LAPLACIAN
    d1 = bnd.h_out + bnd.h_rad_out
    d3 = bnd.h_in + bnd.h_rad_in
    lap[..., _DIAG[X1]] -= d1
    lap[..., _DIAG[X3]] -= d3
    lap[..., _DIAG[X5]] -= bnd.g_adv
    q = np.zeros((*lap.shape[:-1], N_STATES))
    q[..., :4] = sources
    q[..., X1] += bnd.h_out * bnd.t_out + bnd.h_rad_out * bnd.t_rad_out
    q[..., X3] += bnd.h_in * bnd.t_in + bnd.h_rad_in * bnd.t_mrt
    q[..., X5] += bnd.g_adv * bnd.t_inflow
    return lap.reshape(*lap.shape[:-1], N_STATES, N_STATES), q


def boundary_heat_in(x_mean: np.ndarray, bnd: Boundary, sources: np.ndarray) -> np.ndarray:
    """Net heat entering the network over a step at the mean state [W/m2].

    Σ(boundary links into the nodes) + absorbed short-wave: the right-hand side of the
    energy balance in docs/model.md#energy-balance (ΔU = ∫ this dt for the exact ZOH).
    """
    return (
        bnd.h_out * (bnd.t_out - x_mean[..., X1])
        + bnd.h_rad_out * (bnd.t_rad_out - x_mean[..., X1])
        + bnd.h_in * (bnd.t_in - x_mean[..., X3])
        + bnd.h_rad_in * (bnd.t_mrt - x_mean[..., X3])
        + bnd.g_adv * (bnd.t_inflow - x_mean[..., X5])
        + sources.sum(axis=-1)
    )
