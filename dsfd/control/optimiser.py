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

import numpy as np

from dsfd.config.control import Control
from dsfd.config.panel import PanelConfig
from dsfd.control.comfort_horizon import (
    VISUAL_LIMITS,
    block_any,
    comfort_note,
    limits_line,
)
from dsfd.control.horizon import (
    CLOSED,
    Best,
    Candidates,
    ControlProblem,
    Decision,
    Evaluated,
    HorizonEvaluator,
    coarsen,
    coarsen_loads,
    distinct_regimes,
)
from dsfd.control.objective import J_PER_WH
from dsfd.physics.forcing import FacadeOptics
from dsfd.physics.model import LumpedModel
from dsfd.physics.regimes import ALL_OPEN

# ControlProblem, Decision and the rollout's pieces live in dsfd.control.horizon; they are
# re-exported here, where the daemon and the public API have always found them.
__all__ = ["CLOSED", "ControlProblem", "Decision", "HorizonEvaluator", "MpcOptimiser",
           "distinct_regimes", "optimise"]

#: Openings tried at full resolution for the best pair when comfort binds (:func:`_or_ladder`).
OR_LADDER = np.array([0.05, 0.1, 0.2, 0.35, 0.5, 0.7, 0.85])


class MpcOptimiser:
    """Exact over louver positions × damper sets, bounded search over OR (module docstring).

    Stages: (1) screening of every louver position × damper set × coarse OR with a coarse
    time step; (2) at full resolution, the best screened candidates, the best of every
    damper set that screened close to the best, the all-open set at the best louver
    position, OR brackets of the best pairs and the louver neighbours of the best pair;
    (3) only if needed, the louver neighbours of the full-resolution best not evaluated
    yet, and (``or_refine_rounds`` > 0) parabolic OR refinement of the best pair. The
    decision is the best full-resolution candidate. Building the optimiser once per panel
    keeps its models and optics caches.
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
        self.open_regimes = np.array([r for r in self.regimes if r != CLOSED], int)
        self.or_grid = np.asarray(ctl.or_grid_pct, float) / 100.0

    def decide(self, problem: ControlProblem) -> Decision:
        ctl: Control = self.cfg.control
        trace = [f"candidates: {len(self.angles)} louver positions x {len(self.regimes)} damper "
                 f"sets (regimes {list(self.regimes)}), OR grid {list(ctl.or_grid_pct)} %"]
        screen_problem = dataclasses.replace(
            problem, forcing=coarsen(problem.forcing, self.factor),
            occupied=None if problem.occupied is None else block_any(problem.occupied,
                                                                     self.factor))
        full = HorizonEvaluator(self.cfg, self.model, self.optics, problem, self.angles,
                                coupling_tol_k=ctl.coupling_tolerance_k)
        comfort = full.comfort
        if comfort is not None:
            assert problem.occupied is not None
            trace.append(limits_line(comfort))
        screen = HorizonEvaluator(
            self.cfg, self.screen_model, self.optics, screen_problem, self.angles,
            loads=coarsen_loads(full.loads, self.factor),
            comfort=None if comfort is None else comfort.coarsened(self.factor,
                                                                   screen_problem.forcing))
        screened = self._screen(screen)
        trace.append(f"stage 1: screened {screened.candidates.size} candidates at "
                     f"{self.screen_model.dt:g} s steps")
        finalists, n_best = self._finalists(screened)
        evaluated = full.evaluate_all(finalists)
        best = evaluated.best()
        n_pairs = min(ctl.refine_max_pairs, len(self.angles) * len(self.open_regimes))
        trace.append(f"stage 2: {finalists.size} at full resolution ({n_best} finalists, "
                     f"OR brackets of {n_pairs} pairs), best {best.describe(self.angles)}")
        best, batches, evaluated = self._refine(full, evaluated, best)
        trace.append(f"stage 3: {batches} batch(es) of louver neighbours and OR points, best "
                     f"{best.describe(self.angles)}" if batches else
                     "stage 3: not needed (the best's louver neighbours were evaluated)")
        note = ""
        if comfort is not None:
            note = comfort_note(best, evaluated.cheapest(), self.angles)
            trace.append(f"comfort: {note}")
        return best.decision(self.angles, method="mpc", comfort=note,
                             rollouts=full.rollouts + screen.rollouts, trace=tuple(trace))

    def _screen(self, screen: HorizonEvaluator) -> Evaluated:
        """Stage 1: every louver position × open damper set × coarse OR, and closed, at the
        screening's coarse time step; the grid first, in (louver, set, OR) order."""
        n_a = len(self.angles)
        open_regimes, grid = self.open_regimes, self.or_grid
        a_idx, r_idx, g_idx = (m.ravel() for m in np.meshgrid(
            np.arange(n_a), np.arange(len(open_regimes)), np.arange(len(grid)),
            indexing="ij"))
        cand = Candidates(a_idx, open_regimes[r_idx], grid[g_idx])
        if CLOSED in self.regimes:
            cand = cand.join(Candidates(np.arange(n_a), np.full(n_a, CLOSED), np.zeros(n_a)))
        return screen.evaluate_all(cand)

    def _finalists(self, screened: Evaluated) -> tuple[Candidates, int]:
        """Stage 2's one full-resolution batch: the best screened candidates, and OR brackets
        (:meth:`_or_brackets`); with the number of screened candidates among them."""
        ctl = self.cfg.control
        # Under comfort limits the ranking cost is +inf where a candidate breaks them: the
        # stages below then search among the candidates a decision may take.
        cost, cand = screened.rank_cost(), screened.candidates
        best = _best_screened(cost, cand.regime, ctl.full_candidates, ctl.finalist_margin_pct)
        if screened.excess.any():
            # The coarse step can misjudge the thermal limits (a flow it shows reversed into
            # the room with cold air while one-minute steps show exhaust: a damper set
            # screened infeasible that is the best at full resolution, seen); the visual
            # limits depend on the louver alone. So also the finalists under the visual
            # limits only, and what energy alone would choose (the trace's "what bound it").
            visual = _best_screened(screened.rank_cost(VISUAL_LIMITS), cand.regime,
                                    ctl.full_candidates, ctl.finalist_margin_pct)
            alone = np.argsort(screened.terms.cost_j, kind="stable")[: ctl.full_candidates]
            best = np.union1d(best, np.union1d(visual, alone))
        # The all-open set at every coarse OR at the screened best louver position: its
        # flows can switch pattern twice within the horizon at one-minute steps, which the
        # coarse step cannot represent (Q_air of the other sign, cost 25 % off, seen) — a
        # distortion no margin bounds, while the louver ranking the screening gets right.
        best = np.union1d(best, np.flatnonzero(
            (cand.angle_idx == cand.angle_idx[int(np.argmin(cost))])
            & (cand.regime == ALL_OPEN)))
        finalists = cand.take(best)
        if len(self.open_regimes):
            finalists = finalists.join(self._or_brackets(cost)).distinct()
        return finalists, len(best)

    def _or_brackets(self, screened_cost: np.ndarray) -> Candidates:
        """An OR bracket around the screened optimum of the ``refine_max_pairs`` best open
        louver/regime pairs, and the louver neighbours of the best pair at its screened OR:
        the winner is usually that pair at that OR, and stage 3 then finds its neighbours
        evaluated."""
        ctl = self.cfg.control
        open_regimes, grid = self.open_regimes, self.or_grid
        n_a, n_r, n_g = len(self.angles), len(open_regimes), len(grid)
        coarse = screened_cost[: n_a * n_r * n_g].reshape(n_a, n_r, n_g)
        pair_cost = coarse.min(axis=2)
        g_best = coarse.argmin(axis=2)
        top = np.argsort(pair_cost, axis=None, kind="stable")[: ctl.refine_max_pairs]
        pair_angle, pair_regime = np.unravel_index(top, pair_cost.shape)
        centre = grid[g_best[pair_angle, pair_regime]]
        spacing = float(np.max(np.diff(grid)))
        k = ctl.or_refine_points
        frac = np.linspace(-1.0, 1.0, k + 2)[1:-1]
        points = np.clip(centre[:, None] + spacing * frac[None, :], 0.0, 1.0)
        brackets = Candidates(np.repeat(pair_angle, k), np.repeat(open_regimes[pair_regime], k),
                              points.ravel())
        around = _around(int(pair_angle[0]), n_a, ctl.louver_neighbours)
        neighbours = Candidates(around, np.full(around.size, open_regimes[pair_regime[0]]),
                                np.full(around.size, centre[0]))
        return brackets.join(neighbours)

    def _refine(self, full: HorizonEvaluator, evaluated: Evaluated,
                best: Best) -> tuple[Best, int, Evaluated]:
        """Stage 3: the louver positions next to the best (the screening can misrank
        neighbouring angles by a tenth of a per cent) and parabolic refinement of the best
        pair's OR, one batch per round. Returns the best, the number of batches and every
        full-resolution candidate."""
        ctl = self.cfg.control
        new = _louver_neighbours(best, len(self.angles), ctl.louver_neighbours,
                                 evaluated.candidates)
        if (evaluated.excess.any() and best.regime != CLOSED
                and not best.same_controls(evaluated.cheapest())):
            new = new.join(_or_ladder(best, evaluated.candidates))  # comfort binds
        batches = 0
        for round_ in range(max(1, ctl.or_refine_rounds)):
            cand, cost = evaluated.candidates, evaluated.terms.cost_j
            same = (cand.angle_idx == best.angle_idx) & (cand.regime == best.regime)
            spread = float(np.ptp(cost[same])) if same.sum() > 1 else 0.0
            if (round_ < ctl.or_refine_rounds and best.regime != CLOSED
                    and spread > ctl.flat_tolerance_pct / 100.0 * max(abs(best.cost), 1.0)):
                # (a flat cost hardly depends on OR here: nothing to gain)
                points = _parabolic_points(cand.or_[same], cost[same])
                new = new.join(Candidates(np.full(points.size, best.angle_idx),
                                          np.full(points.size, best.regime), points))
            if new.size == 0:
                break
            batch = full.evaluate_all(new)
            batches += 1
            best = best.better(batch.best())
            evaluated = evaluated.join(batch)
            new = Candidates.empty()  # neighbours: once
        return best, batches, evaluated


def _around(idx: int, n_angles: int, reach: int) -> np.ndarray:
    """Louver indices within ``reach`` steps of ``idx`` (itself excluded)."""
    out = np.arange(idx - reach, idx + reach + 1)
    return out[(out >= 0) & (out < n_angles) & (out != idx)]


def _or_ladder(best: Best, evaluated: Candidates) -> Candidates:
    """The openings of :data:`OR_LADDER` not yet evaluated for the best pair, when comfort
    binds (the best is not the cheapest). The coarse OR grid and its bracket suffice for
    energy alone (its best opening was never interior in 600 cases), not for the pairs
    comfort leaves: behind a cut-off louver the all-open set had its best opening at 5 %
    (27 % of the cost missed, seen), and the screening can misjudge which set is feasible,
    so the full-resolution best may be a pair it never bracketed; a thermal limit also ends
    the opening's range at the largest flow that keeps the supply air warm enough."""
    seen = (evaluated.angle_idx == best.angle_idx) & (evaluated.regime == best.regime)
    points = OR_LADDER[~np.isin(OR_LADDER, evaluated.or_[seen])]
    return Candidates(np.full(points.size, best.angle_idx), np.full(points.size, best.regime),
                      points)


def _louver_neighbours(best: Best, n_angles: int, reach: int,
                       evaluated: Candidates) -> Candidates:
    """Louver positions within ``reach`` steps of the best, at its regime and OR, that have
    not been evaluated at full resolution yet."""
    idx = _around(best.angle_idx, n_angles, reach)
    seen = (evaluated.regime == best.regime) & np.isclose(evaluated.or_, best.or_)
    idx = idx[~np.isin(idx, evaluated.angle_idx[seen])]
    return Candidates(idx, np.full(idx.size, best.regime), np.full(idx.size, best.or_))


def _best_screened(cost: np.ndarray, regime: np.ndarray, n_best: int,
                   margin_pct: float) -> np.ndarray:
    """Screened candidates for the full-resolution stage: the ``n_best`` best overall and
    the best of every damper set whose screened cost is within ``margin_pct`` of the best.

    The damper sets can differ by less than the screening's coarse time step distorts
    their costs (it holds the end-of-step flows over 300 s, which misrepresents the fast
    cavity-air transient after a regime change: 2.2 % seen); the best of each such set
    then decides at full resolution which one wins.
    """
    order = np.argsort(cost, kind="stable")
    _, first = np.unique(regime[order], return_index=True)
    best = cost[order[0]]
    close = first[cost[order[first]] - best <= margin_pct / 100.0 * max(abs(best), J_PER_WH)]
    return np.unique(np.concatenate([order[:n_best], order[close]]))


def _parabolic_points(ors: np.ndarray, costs: np.ndarray) -> np.ndarray:
    """New openings to try around the best of ``ors``: the vertex of the parabola through
    the best point and its neighbours, and the midpoints towards both neighbours."""
    order = np.argsort(ors)
    x, y = ors[order], costs[order]
    x, idx = np.unique(x, return_index=True)
    y = y[idx]
    if x.size < 2:
        return np.zeros(0)
    i = int(np.argmin(y))
    lo, hi = max(i - 1, 0), min(i + 1, x.size - 1)
    cands = [0.5 * (x[lo] + x[i]), 0.5 * (x[i] + x[hi])]
    if 0 < i < x.size - 1:
        x0, x1, x2 = x[i - 1], x[i], x[i + 1]
        y0, y1, y2 = y[i - 1], y[i], y[i + 1]
        den = (x1 - x0) * (y1 - y2) - (x1 - x2) * (y1 - y0)
        if den != 0:
            vertex = x1 - 0.5 * ((x1 - x0) ** 2 * (y1 - y2) - (x1 - x2) ** 2 * (y1 - y0)) / den
            if x0 < vertex < x2:
                cands.append(vertex)
    out = np.unique(np.clip(cands, 0.0, 1.0))
    return out[~np.isin(out, x)]


def optimise(cfg: PanelConfig, model: LumpedModel, optics: FacadeOptics,
             problem: ControlProblem) -> Decision:
    """One MPC decision (convenience wrapper of :class:`MpcOptimiser`)."""
    return MpcOptimiser(cfg, model, optics).decide(problem)
