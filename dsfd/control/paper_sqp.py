"""The paper's optimiser, for comparison: relaxed AFR, SQP, louver rounded afterwards.

Yoon et al. solve Eq. 6 with LabVIEW's constrained nonlinear optimisation (sequential
quadratic programming), with the discrete airflow regime translated into a continuous
AFR* and the louver angle treated as continuous, then rounded to the nearest multiple of
18° for the motor. Here: scipy's SLSQP on (φ, AFR*, OR) scaled to [0, 1]³, finite-difference
gradients, AFR = round(AFR*) inside the objective (docs/model.md#paper-sqp: the objective is
piecewise constant in AFR*, which is exactly the weakness this baseline exhibits), and
after convergence φ rounded to the 18° grid and the rounded control re-evaluated — that
re-evaluated cost is what the applied control achieves.

While horizon steps are occupied, the comfort limits enter as an exact penalty,
:data:`COMFORT_PENALTY_WH` per unit of normalised violation (docs/model.md#comfort-constraints),
the way a penalty formulation hands constraints to SQP; the decision's ``cost_j`` stays
the energy cost J (``relaxed_cost_j`` is the relaxed objective, penalty included).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from dsfd.config.panel import PanelConfig
from dsfd.control.baseline import quantise_louver
from dsfd.control.comfort_horizon import HorizonComfort
from dsfd.control.objective import J_PER_WH, horizon_cost, louver_move_penalty
from dsfd.control.optimiser import ControlProblem, Decision
from dsfd.physics.forcing import FacadeOptics
from dsfd.physics.model import LumpedModel

#: Finite-difference step of SLSQP in the scaled variables (1 % of each range).
FD_STEP = 0.01
#: Penalty on the normalised comfort violation [Wh per unit]: far above any horizon's energy
#: (a 15-minute horizon moves a few hundred Wh), so that any feasible control beats any
#: infeasible one.
COMFORT_PENALTY_WH = 1e5


def _nearest_available(afr_star: float, available: tuple[int, ...]) -> int:
    afr = int(np.clip(np.round(afr_star), 1, 10))
    return min(available, key=lambda r: (abs(r - afr), r))


def optimise_paper_sqp(cfg: PanelConfig, model: LumpedModel, optics: FacadeOptics,
                       problem: ControlProblem, *, max_iterations: int = 50) -> Decision:
    """SLSQP on the relaxed problem, then louver rounding (see module docstring)."""
    available = cfg.openings.available_regimes()
    h = problem.forcing.time_s.shape[0]
    step = cfg.louver.step_deg if cfg.louver is not None else 18.0
    calls = {"n": 0}
    occupied = problem.occupied if problem.any_occupied else None

    def cost(phi_deg: float, afr: int, or_: float) -> tuple[float, int, float]:
        """Energy cost J [J], first-step label and comfort violation of a control."""
        loads = optics.loads(problem.forcing, np.radians(phi_deg))
        traj = model.rollout(problem.x0, np.full((1, h), afr), np.full((1, h), or_),
                             problem.step_inputs(loads), problem.theta,
                             coupling_tol_k=cfg.control.coupling_tolerance_k)
        calls["n"] += 1
        j = horizon_cost(traj, dt=model.dt, heating=problem.heating).cost_j[0]
        j += louver_move_penalty(np.array([phi_deg]), problem.previous_phi_deg,
                                 penalty_wh=cfg.control.louver_move_penalty_wh,
                                 step_deg=step)[0]
        violation = 0.0
        if occupied is not None:
            comfort = HorizonComfort(cfg, optics, problem.forcing, np.array([phi_deg]),
                                     occupied)
            violation = float(comfort.excess(np.array([0]), traj).sum())
        return float(j), int(traj.label[0, 0]), violation

    def unscale(u: np.ndarray) -> tuple[float, float, float]:
        return -90.0 + 180.0 * u[0], 0.5 + (10.0 - 1e-9) * u[1], float(np.clip(u[2], 0, 1))

    def objective(u: np.ndarray) -> float:
        phi, afr_star, or_ = unscale(u)
        if cfg.louver is None:
            phi = 0.0
        j, _, violation = cost(phi, _nearest_available(afr_star, available), or_)
        return j / J_PER_WH + COMFORT_PENALTY_WH * violation

    phi0 = problem.previous_phi_deg if problem.previous_phi_deg is not None else 0.0
    afr0 = problem.previous_afr if problem.previous_afr is not None else 5
    or0 = (problem.previous_or_pct if problem.previous_or_pct is not None else 50.0) / 100.0
    u0 = np.array([(phi0 + 90.0) / 180.0, (afr0 - 0.5) / 10.0, or0])
    res = minimize(objective, np.clip(u0, 0, 1), method="SLSQP", bounds=[(0.0, 1.0)] * 3,
                   options={"maxiter": max_iterations, "ftol": 1e-6, "eps": FD_STEP})
    phi_c, afr_star, or_c = unscale(res.x)
    afr = _nearest_available(afr_star, available)
    relaxed_j = float(res.fun) * J_PER_WH
    phi_q = quantise_louver(phi_c, cfg.louver)
    j_q, label, violation = cost(phi_q, afr, or_c)
    closed = afr == 10
    trace = (f"SLSQP: {res.nit} iterations, status {res.status} ({res.message})",
             f"relaxed optimum: louver {phi_c:+.1f} deg, AFR* {afr_star:.2f} -> {afr}, "
             f"OR {or_c * 100:.1f} %, J {relaxed_j / J_PER_WH:+.2f} Wh",
             f"louver rounded to {phi_q:+.0f} deg: J {j_q / J_PER_WH:+.2f} Wh")
    note = ""
    if occupied is not None:
        note = (f"comfort as a penalty of {COMFORT_PENALTY_WH:g} Wh per unit violation: "
                + ("every limit met" if violation == 0.0 else
                   f"the rounded control still violates {violation:.3g}"))
        trace = (*trace, f"comfort: {note}")
    return Decision(phi_deg=phi_q, afr=10 if closed else label,
                    or_pct=0.0 if closed else round(or_c * 100.0, 1), method="paper-sqp",
                    cost_j=j_q, terms_j={"relaxed_cost_j": relaxed_j}, rollouts=calls["n"],
                    trace=trace, comfort=note)
