"""The optimiser of Eq. 6 on the real actuator sets.

The louver moves in 18° steps (11 positions) and the airflow regime is one of 10, so the
discrete part of the problem is small: every louver position is paired with every
physically distinct damper set and evaluated exactly — no relaxation, no rounding. Regime
pairs that differ only in the expected flow direction (1/2, 3/4, 5/8, 6/7) open the same
dampers, so the flow the model predicts is the same; one representative per damper set is
rolled out and the command carries the regime label the model predicts for the first
step. The damper opening OR is continuous: a coarse grid for every pair, then a bounded
refinement (successive finer grids inside the bracket of the best point) for the pairs
whose coarse cost is close to the best. All candidates of a stage go through one batched
horizon rollout (:meth:`LumpedModel.rollout`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from dsfd.config.control import Control
from dsfd.config.panel import REGIME_OPENINGS, PanelConfig
from dsfd.control.objective import CostTerms, horizon_cost, louver_move_penalty
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, step_inputs
from dsfd.physics.model import LumpedModel

CLOSED = 10


@dataclass(frozen=True)
class ControlProblem:
    """One decision: where the façade is and what the horizon will bring.

    Attributes
    ----------
    x0 : ndarray (6,), [K]
        Estimated state now (x6 from the observer).
    forcing : Forcing
        Façade boundary of the next H steps (forecast).
    theta : ndarray (9,)
        Current parameter estimate.
    heating : bool
        Heating objective (Eq. 4) or cooling (Eq. 5).
    previous_phi_deg : float or None, [deg]
        Louver angle now (for the move penalty and the SQP start).
    previous_afr : int or None
    previous_or_pct : float or None, [%]
    """

    x0: np.ndarray
    forcing: Forcing
    theta: np.ndarray
    heating: bool
    previous_phi_deg: float | None = None
    previous_afr: int | None = None
    previous_or_pct: float | None = None


@dataclass(frozen=True)
class Decision:
    """A control decision with its predicted cost and a trace of how it was reached."""

    phi_deg: float
    afr: int
    or_pct: float
    method: str
    cost_j: float
    terms_j: dict[str, float] = field(default_factory=dict)
    rollouts: int = 0
    trace: tuple[str, ...] = ()


def distinct_regimes(available: tuple[int, ...]) -> tuple[int, ...]:
    """One representative regime per damper set the panel has (1, 3, 5, 6, 9, 10)."""
    seen: dict[frozenset[str], int] = {}
    for regime in sorted(available):
        seen.setdefault(REGIME_OPENINGS[regime], regime)
    return tuple(sorted(seen.values()))


class HorizonEvaluator:
    """Batched horizon cost of constant controls for one decision."""

    def __init__(self, cfg: PanelConfig, model: LumpedModel, optics: FacadeOptics,
                 problem: ControlProblem, angles_deg: np.ndarray) -> None:
        self.cfg = cfg
        self.model = model
        self.problem = problem
        self.angles_deg = np.asarray(angles_deg, float)
        self.loads = optics.loads(problem.forcing, np.radians(self.angles_deg))
        self.rollouts = 0
        step = cfg.louver.step_deg if cfg.louver is not None else 18.0
        self._penalty = louver_move_penalty(
            self.angles_deg, problem.previous_phi_deg,
            penalty_wh=cfg.control.louver_move_penalty_wh, step_deg=step)

    def inputs(self, angle_idx: np.ndarray) -> StepInputs:
        """Model inputs of candidates with louver positions ``angle_idx`` → (C, H, ...)."""
        ld = self.loads
        picked = type(ld)(*(np.asarray(v)[angle_idx] for v in ld))
        return step_inputs(self.problem.forcing, picked)

    def evaluate(self, angle_idx: np.ndarray, regime: np.ndarray,
                 or_: np.ndarray) -> tuple[CostTerms, np.ndarray]:
        """Cost of each candidate [J] (incl. move penalty) and its first-step regime label."""
        angle_idx = np.asarray(angle_idx, int)
        n = angle_idx.size
        h = self.problem.forcing.time_s.shape[0]
        traj = self.model.rollout(
            self.problem.x0, np.broadcast_to(np.asarray(regime, int)[:, None], (n, h)),
            np.broadcast_to(np.asarray(or_, float)[:, None], (n, h)), self.inputs(angle_idx),
            self.problem.theta)
        self.rollouts += n
        terms = horizon_cost(traj, dt=self.model.dt, heating=self.problem.heating)
        terms = terms._replace(cost_j=terms.cost_j + self._penalty[angle_idx])
        return terms, traj.label[:, 0]


def coarsen(forcing: Forcing, factor: int) -> Forcing:
    """Block means of a horizon's boundary over ``factor`` consecutive steps.

    A screening pass steps the model with ``factor`` times the step length over these
    means (the exact ZOH is exact for any step; only the weather and the linearisation
    are held longer).
    """
    n = forcing.time_s.shape[0]
    starts = np.arange(0, n, factor)
    counts = np.diff(np.append(starts, n))
    return Forcing(*(np.add.reduceat(np.asarray(v, float), starts) / counts for v in forcing))


class MpcOptimiser:
    """Exact over louver positions × damper sets, bounded search over OR (module docstring).

    Stages: (1) screening of every louver position × damper set × coarse OR with a coarse
    time step; (2) the best candidates of the screening at full resolution; (3) bounded OR
    refinement of the best pairs at full resolution. The decision is the best full-resolution
    candidate. Building the optimiser once per panel keeps its models and optics caches.
    """

    def __init__(self, cfg: PanelConfig, model: LumpedModel | None = None,
                 optics: FacadeOptics | None = None) -> None:
        self.cfg = cfg
        self.model = model or LumpedModel(cfg)
        self.optics = optics or FacadeOptics(cfg)
        ctl = cfg.control
        self.factor = max(1, round(ctl.screening_step_s / cfg.model.step_s))
        coarse = dataclasses.replace(cfg.model, step_s=cfg.model.step_s * self.factor,
                                     coupling_tolerance_k=ctl.screening_tolerance_k)
        self.screen_model = LumpedModel(dataclasses.replace(cfg, model=coarse))
        self.angles = np.asarray(cfg.louver.angles_deg() if cfg.louver is not None else (0.0,))
        self.regimes = distinct_regimes(cfg.openings.available_regimes())

    def decide(self, problem: ControlProblem) -> Decision:
        ctl: Control = self.cfg.control
        angles, regimes = self.angles, self.regimes
        open_regimes = np.array([r for r in regimes if r != CLOSED], int)
        grid = np.asarray(ctl.or_grid_pct, float) / 100.0
        n_a, n_r, n_g = len(angles), len(open_regimes), len(grid)
        trace = [f"candidates: {n_a} louver positions x {len(regimes)} damper sets "
                 f"(regimes {list(regimes)}), OR grid {list(ctl.or_grid_pct)} %"]
        # Stage 1: screening of every louver position x open set x coarse OR, and closed.
        a_idx, r_idx, g_idx = (m.ravel() for m in np.meshgrid(
            np.arange(n_a), np.arange(n_r), np.arange(n_g), indexing="ij"))
        cand = [(a_idx, open_regimes[r_idx], grid[g_idx])]
        if CLOSED in regimes:
            cand.append((np.arange(n_a), np.full(n_a, CLOSED), np.zeros(n_a)))
        all_a, all_r, all_o = (np.concatenate(c) for c in zip(*cand, strict=True))
        screen_problem = dataclasses.replace(problem,
                                             forcing=coarsen(problem.forcing, self.factor))
        screen = HorizonEvaluator(self.cfg, self.screen_model, self.optics, screen_problem,
                                  angles)
        s_terms, _ = screen.evaluate(all_a, all_r, all_o)
        order = np.argsort(s_terms.cost_j, kind="stable")[: ctl.full_candidates]
        trace.append(f"stage 1: screened {all_a.size} candidates at "
                     f"{self.screen_model.dt:g} s steps")
        # Stage 2: the best screened candidates at full resolution.
        full = HorizonEvaluator(self.cfg, self.model, self.optics, problem, angles)
        fa, fr, fo = all_a[order], all_r[order], all_o[order]
        terms, labels = full.evaluate(fa, fr, fo)
        best = _Best.of(terms, labels, fa, fr, fo)
        trace.append(f"stage 2: {len(order)} at full resolution, best {best.describe(angles)}")
        # Stage 3: bounded OR refinement of the best open pairs.
        if n_r and ctl.or_refine_rounds > 0:
            best = self._refine(full, terms, fa, fr, fo, grid, best, trace)
        return best.decision(angles, method="mpc",
                             rollouts=full.rollouts + screen.rollouts, trace=tuple(trace))

    def _refine(self, ev: HorizonEvaluator, terms: CostTerms, fa: np.ndarray, fr: np.ndarray,
                fo: np.ndarray, grid: np.ndarray, best: _Best, trace: list[str]) -> _Best:
        ctl = self.cfg.control
        scale = _cost_scale(terms)
        keep = (fr != CLOSED) & (terms.cost_j <= best.cost + ctl.refine_margin_pct / 100.0
                                 * scale)
        pairs: dict[tuple[int, int], tuple[float, float]] = {}
        for i in np.flatnonzero(keep)[np.argsort(terms.cost_j[keep], kind="stable")]:
            key = (int(fa[i]), int(fr[i]))
            if key not in pairs and len(pairs) < ctl.refine_max_pairs:
                pairs[key] = (float(terms.cost_j[i]), float(fo[i]))
        if not pairs:
            return best
        pa = np.array([k[0] for k in pairs])
        pr = np.array([k[1] for k in pairs])
        pair_cost = np.array([v[0] for v in pairs.values()])
        pair_or = np.array([v[1] for v in pairs.values()])
        spacing = float(np.max(np.diff(grid)))
        lo_p = np.clip(pair_or - spacing, 0.0, 1.0)
        hi_p = np.clip(pair_or + spacing, 0.0, 1.0)
        k = ctl.or_refine_points
        rows = np.arange(len(pa))
        for _ in range(ctl.or_refine_rounds):
            pts = lo_p[:, None] + (hi_p - lo_p)[:, None] * (np.arange(1, k + 1) / (k + 1))
            ra, rr = np.repeat(pa, k), np.repeat(pr, k)
            t2, l2 = ev.evaluate(ra, rr, pts.ravel())
            best = best.better(_Best.of(t2, l2, ra, rr, pts.ravel()))
            c2 = t2.cost_j.reshape(-1, k)
            j = c2.argmin(axis=1)
            improved = c2[rows, j] < pair_cost
            pair_cost = np.where(improved, c2[rows, j], pair_cost)
            pair_or = np.where(improved, pts[rows, j], pair_or)
            width = (hi_p - lo_p) / (k + 1)
            lo_p = np.clip(pair_or - width, 0.0, 1.0)
            hi_p = np.clip(pair_or + width, 0.0, 1.0)
        trace.append(f"stage 3: refined OR of {len(pa)} pair(s) in {ctl.or_refine_rounds} "
                     f"round(s) of {k}, best {best.describe(self.angles)}")
        return best


def optimise(cfg: PanelConfig, model: LumpedModel, optics: FacadeOptics,
             problem: ControlProblem) -> Decision:
    """One MPC decision (convenience wrapper of :class:`MpcOptimiser`)."""
    return MpcOptimiser(cfg, model, optics).decide(problem)


def _cost_scale(terms: CostTerms) -> float:
    """Magnitude of the horizon's heat flows, to express margins relative to it [J]."""
    mags = np.abs(terms.q_cv_rd_j) + np.abs(terms.q_sol_j) + np.abs(terms.q_air_j) + np.abs(
        terms.q_da_j)
    return float(max(np.median(mags), 1.0))


@dataclass(frozen=True)
class _Best:
    cost: float
    angle_idx: int
    regime: int
    or_: float
    label: int
    terms: dict[str, float]

    @classmethod
    def of(cls, terms: CostTerms, labels: np.ndarray, a: np.ndarray, r: np.ndarray,
           o: np.ndarray) -> _Best:
        i = int(np.argmin(terms.cost_j))
        return cls(float(terms.cost_j[i]), int(a[i]), int(r[i]), float(o[i]), int(labels[i]),
                   {name: float(getattr(terms, name)[i]) for name in terms._fields})

    def better(self, other: _Best) -> _Best:
        return other if other.cost < self.cost else self

    def describe(self, angles: np.ndarray) -> str:
        return (f"louver {angles[self.angle_idx]:+.0f} deg, regime {self.label}, OR "
                f"{self.or_ * 100:.1f} %, J {self.cost / 3600.0:+.2f} Wh")

    def decision(self, angles: np.ndarray, *, method: str, rollouts: int,
                 trace: tuple[str, ...]) -> Decision:
        or_pct = 0.0 if self.regime == CLOSED else round(self.or_ * 100.0, 1)
        return Decision(phi_deg=float(angles[self.angle_idx]), afr=self.label, or_pct=or_pct,
                        method=method, cost_j=self.cost, terms_j=self.terms, rollouts=rollouts,
                        trace=trace)
