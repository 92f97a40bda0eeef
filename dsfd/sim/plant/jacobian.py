"""Jacobian of the truth plant's right-hand side for the Radau integrator."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import csc_matrix

if TYPE_CHECKING:
    from dsfd.sim.plant.model import PlantModel

#: State count above which the Jacobian is returned as a sparse matrix (dense LAPACK on
#: small matrices is faster; above this SuperLU is, and it is immune to BLAS threads).
SPARSE_ABOVE = 100


def jacobian(model: PlantModel, t: float, y: np.ndarray) -> np.ndarray | csc_matrix:
    """Analytic Jacobian of :meth:`PlantModel.rhs` at (t, y) [1/s].

    Notes
    -----
    Links with their conductances frozen (secant radiation, so T⁴ exchange enters with its
    secant slope), the advection with the flows frozen, plus the sensitivity of the
    advection to the flows: the flows depend on the state only through the hydrostatic
    column, so that part is (∂q/∂I) ⊗ (∂I/∂T) with ∂q/∂I by one finite difference of the
    column integral I = ∫ρ dz. Exact derivatives of the second-order advection. The
    accumulator rows are filled too, so Radau's Newton iteration updates them together
    with the temperatures. Sparse (CSC, for SuperLU) above :data:`SPARSE_ABOVE` states.
    """
    model.rhs(t, y)
    nn, lk, last = model.nn, model.links, model.last
    cap = last["cap"]
    gs, gb, ga = model.gs, model.gb, model.ga
    cr, cc = cap[lk.sym_r], cap[lk.sym_c]
    ca = cap[lk.adv_r]
    n_sym = 4 * gs.size
    w_sym = np.concatenate((-gs / cr, gs / cr, -gs / cc, gs / cc))
    sym = np.bincount(lk.jac_flat[:n_sym], w_sym, minlength=nn * nn).reshape(nn, nn)
    w = np.concatenate((-gb / cap[lk.bnd_r], -ga / ca, (ga / ca)[lk.adv_internal]))
    jac = np.zeros((model.ny, model.ny))
    jac[:nn, :nn] = sym + np.bincount(lk.jac_flat[n_sym:], w,
                                      minlength=nn * nn).reshape(nn, nn)
    # Accumulator rows (their Newton updates must follow the temperatures').
    d_bnd = np.bincount(lk.bnd_r, -gb, minlength=nn)
    d_adv = np.bincount(lk.adv_r, -ga, minlength=nn)
    d_adv += np.bincount(lk.adv_c[lk.adv_internal], ga[lk.adv_internal], minlength=nn)
    fl = last["flows"]
    if model.ctx.flow.mode != 0:
        # Flow sensitivity: the flows depend on the state through the column integral.
        integral = fl["integral"]
        d_int = 1e-7 * integral
        m2 = model.flows(*fl["args"], integral=integral + d_int)["m"]
        te = last["te"]
        ga2 = model.advective(m2)
        q2 = np.bincount(lk.adv_r, ga2 * (te[lk.adv_c] - te[lk.adv_r]), minlength=nn)
        q1 = np.bincount(lk.adv_r, last["f_adv"], minlength=nn)
        dq_di = (q2 - q1) / d_int
        di_dt = -fl["rho_col"] * model.col_w / fl["tc"]
        jac[:nn, model.col_nodes] += np.outer(dq_di / cap, di_dt)
        d_adv[model.col_nodes] += dq_di.sum() * di_dt
        model.advective(fl["m"])
    if model.adv2 is not None and last["m_cav"] != 0.0:
        corr = model.adv2.jacobian(y[:nn], last["m_cav"] * model.cp, cap)
        jac[:nn, :nn] += corr
        d_adv += (corr * cap[:, None]).sum(axis=0)
    jac[nn + 1, :nn] = d_bnd
    jac[nn + 2, :nn] = d_adv
    jac[nn + 3, :nn] = np.sign(last["bnd_total"]) * d_bnd
    n = model.lay.n
    jac[nn + 4, :nn] = np.bincount(lk.bnd_r[2 * n:], gb[2 * n:], minlength=nn)  # Q_cv,rd
    # Sparse above a few dozen states: Radau then factorises with SuperLU, which is
    # faster than dense LAPACK there and immune to BLAS thread oversubscription.
    return csc_matrix(jac) if model.ny > SPARSE_ABOVE else jac
