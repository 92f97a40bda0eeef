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
from dsfd.control.objective import J_PER_WH, CostTerms, horizon_cost, louver_move_penalty
from dsfd.estimation.params import with_offsets
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, OpticalLoads, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.physics.regimes import ALL_OPEN

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
    heat_offsets_wm2 : ndarray (4,) or None, [W/m2]
        Calibrated heat-flux offsets on nodes x1..x4 (the self-calibration's input
        disturbance, :mod:`dsfd.estimation.params`), added to the absorbed short-wave so
        that the horizon is predicted by the same model the state estimate comes from.
    """

    x0: np.ndarray
    forcing: Forcing
    theta: np.ndarray
    heating: bool
    previous_phi_deg: float | None = None
    previous_afr: int | None = None
    previous_or_pct: float | None = None
    heat_offsets_wm2: np.ndarray | None = None

    def step_inputs(self, loads: OpticalLoads) -> StepInputs:
        """Model inputs of the horizon for louver loads ``loads``, offsets included."""
        inp = step_inputs(self.forcing, loads)
        if self.heat_offsets_wm2 is None:
            return inp
        return with_offsets(inp, self.heat_offsets_wm2)


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
                 problem: ControlProblem, angles_deg: np.ndarray, *,
                 coupling_tol_k: float | None = None,
                 loads: OpticalLoads | None = None) -> None:
        self.cfg = cfg
        self.model = model
        self.coupling_tol_k = coupling_tol_k
        self.problem = problem
        self.angles_deg = np.asarray(angles_deg, float)
        self.loads = (optics.loads(problem.forcing, np.radians(self.angles_deg))
                      if loads is None else loads)
        self.rollouts = 0
        step = cfg.louver.step_deg if cfg.louver is not None else 18.0
        self._penalty = louver_move_penalty(
            self.angles_deg, problem.previous_phi_deg,
            penalty_wh=cfg.control.louver_move_penalty_wh, step_deg=step)

    def inputs(self, angle_idx: np.ndarray) -> StepInputs:
        """Model inputs of candidates with louver positions ``angle_idx`` → (C, H, ...)."""
        ld = self.loads
        picked = type(ld)(*(np.asarray(v)[angle_idx] for v in ld))
        return self.problem.step_inputs(picked)

    def evaluate(self, angle_idx: np.ndarray, regime: np.ndarray,
                 or_: np.ndarray) -> tuple[CostTerms, np.ndarray]:
        """Cost of each candidate [J] (incl. move penalty) and its first-step regime label."""
        angle_idx = np.asarray(angle_idx, int)
        n = angle_idx.size
        h = self.problem.forcing.time_s.shape[0]
        traj = self.model.rollout(
            self.problem.x0, np.broadcast_to(np.asarray(regime, int)[:, None], (n, h)),
            np.broadcast_to(np.asarray(or_, float)[:, None], (n, h)), self.inputs(angle_idx),
            self.problem.theta, coupling_tol_k=self.coupling_tol_k)
        self.rollouts += n
        terms = horizon_cost(traj, dt=self.model.dt, heating=self.problem.heating)
        terms = terms._replace(cost_j=terms.cost_j + self._penalty[angle_idx])
        return terms, traj.label[:, 0]


def _block_means(v: np.ndarray, factor: int, axis: int) -> np.ndarray:
    n = v.shape[axis]
    starts = np.arange(0, n, factor)
    counts = np.diff(np.append(starts, n)).reshape((-1,) + (1,) * (v.ndim - axis - 1))
    return np.add.reduceat(np.asarray(v, float), starts, axis=axis) / counts


def coarsen(forcing: Forcing, factor: int) -> Forcing:
    """Block means of a horizon's boundary over ``factor`` consecutive steps.

    A screening pass steps the model with ``factor`` times the step length over these
    means (the exact ZOH is exact for any step; only the weather and the linearisation
    are held longer).
    """
    return Forcing(*(_block_means(v, factor, 0) for v in forcing))


def coarsen_loads(loads: OpticalLoads, factor: int) -> OpticalLoads:
    """Block means of the optical loads (m angles, n steps, ...) over ``factor`` steps: the
    screening's loads are the step averages of the full-resolution ones (no second pass
    through the optics)."""
    return OpticalLoads(*(_block_means(v, factor, 1) for v in loads))


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
        full = HorizonEvaluator(self.cfg, self.model, self.optics, problem, angles,
                                coupling_tol_k=ctl.coupling_tolerance_k)
        screen = HorizonEvaluator(self.cfg, self.screen_model, self.optics, screen_problem,
                                  angles, loads=coarsen_loads(full.loads, self.factor))
        s_terms, _ = screen.evaluate(all_a, all_r, all_o)
        trace.append(f"stage 1: screened {all_a.size} candidates at "
                     f"{self.screen_model.dt:g} s steps")
        # Stage 2, one full-resolution batch: the best screened candidates, and an OR
        # bracket around the screened optimum of the best open louver/regime pairs.
        finalists = _finalists(s_terms.cost_j, all_r, ctl.full_candidates,
                               ctl.finalist_margin_pct)
        # The all-open set at every coarse OR at the screened best louver position: its
        # flows can switch pattern twice within the horizon at one-minute steps, which the
        # coarse step cannot represent (Q_air of the other sign, cost 25 % off, seen) — a
        # distortion no margin bounds, while the louver ranking the screening gets right.
        finalists = np.union1d(finalists, np.flatnonzero(
            (all_a == all_a[int(np.argmin(s_terms.cost_j))]) & (all_r == ALL_OPEN)))
        fa, fr, fo = all_a[finalists], all_r[finalists], all_o[finalists]
        if n_r:
            coarse = s_terms.cost_j[: n_a * n_r * n_g].reshape(n_a, n_r, n_g)
            pair_cost = coarse.min(axis=2)
            g_best = coarse.argmin(axis=2)
            top = np.argsort(pair_cost, axis=None, kind="stable")[: ctl.refine_max_pairs]
            pa, pr = np.unravel_index(top, pair_cost.shape)
            centre = grid[g_best[pa, pr]]
            spacing = float(np.max(np.diff(grid)))
            k = ctl.or_refine_points
            frac = np.linspace(-1.0, 1.0, k + 2)[1:-1]
            pts = np.clip(centre[:, None] + spacing * frac[None, :], 0.0, 1.0)
            # The louver neighbours of the best pair at its screened OR: the winner is
            # usually that pair at that OR, and stage 3 then finds its neighbours evaluated.
            na_ = _around(int(pa[0]), n_a, ctl.louver_neighbours)
            fa = np.concatenate([fa, np.repeat(pa, k), na_])
            fr = np.concatenate([fr, np.repeat(open_regimes[pr], k),
                                 np.full(na_.size, open_regimes[pr[0]])])
            fo = np.concatenate([fo, pts.ravel(), np.full(na_.size, centre[0])])
            fa, fr, fo = _distinct(fa, fr, fo)
        terms, labels = full.evaluate(fa, fr, fo)
        best = _Best.of(terms, labels, fa, fr, fo)
        trace.append(f"stage 2: {fa.size} at full resolution ({len(finalists)} finalists, "
                     f"OR brackets of {min(ctl.refine_max_pairs, n_a * n_r)} pairs), best "
                     f"{best.describe(angles)}")
        # Stage 3: the louver positions next to the best (the screening can misrank
        # neighbouring angles by a tenth of a per cent) and parabolic refinement of the
        # best pair's OR, one batch per round.
        na, nr, new = _louver_neighbours(best, n_a, ctl.louver_neighbours, fa, fr, fo)
        batches = 0
        for round_ in range(max(1, ctl.or_refine_rounds)):
            same = (fa == best.angle_idx) & (fr == best.regime)
            spread = float(np.ptp(terms.cost_j[same])) if same.sum() > 1 else 0.0
            if (round_ < ctl.or_refine_rounds and best.regime != CLOSED
                    and spread > ctl.flat_tolerance_pct / 100.0 * max(abs(best.cost), 1.0)):
                # (a flat cost hardly depends on OR here: nothing to gain)
                pts = _parabolic_points(fo[same], terms.cost_j[same])
                na = np.concatenate([na, np.full(pts.size, best.angle_idx)])
                nr = np.concatenate([nr, np.full(pts.size, best.regime)])
                new = np.concatenate([new, pts])
            if new.size == 0:
                break
            t3, l3 = full.evaluate(na, nr, new)
            batches += 1
            best = best.better(_Best.of(t3, l3, na, nr, new))
            fa, fr, fo = (np.concatenate(v) for v in ((fa, na), (fr, nr), (fo, new)))
            terms = CostTerms(*(np.concatenate(v) for v in zip(terms, t3, strict=True)))
            na, nr, new = np.zeros(0, int), np.zeros(0, int), np.zeros(0)  # neighbours: once
        trace.append(f"stage 3: {batches} batch(es) of louver neighbours and OR points, best "
                     f"{best.describe(angles)}" if batches else
                     "stage 3: not needed (the best's louver neighbours were evaluated)")
        return best.decision(angles, method="mpc",
                             rollouts=full.rollouts + screen.rollouts, trace=tuple(trace))


def _distinct(a: np.ndarray, r: np.ndarray, o: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidates (louver index, regime, OR) without repeats, in first-seen order."""
    _, first = np.unique(np.stack([a, r, o]), axis=1, return_index=True)
    keep = np.sort(first)
    return a[keep], r[keep], o[keep]


def _around(idx: int, n_angles: int, reach: int) -> np.ndarray:
    """Louver indices within ``reach`` steps of ``idx`` (itself excluded)."""
    out = np.arange(idx - reach, idx + reach + 1)
    return out[(out >= 0) & (out < n_angles) & (out != idx)]


def _louver_neighbours(best: _Best, n_angles: int, reach: int, fa: np.ndarray,
                       fr: np.ndarray, fo: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Louver positions within ``reach`` steps of the best, at its regime and OR, that have
    not been evaluated at full resolution yet (angle indices, regimes, openings)."""
    idx = _around(best.angle_idx, n_angles, reach)
    seen = (fr == best.regime) & np.isclose(fo, best.or_)
    idx = idx[~np.isin(idx, fa[seen])]
    return idx, np.full(idx.size, best.regime), np.full(idx.size, best.or_)


def _finalists(cost: np.ndarray, regime: np.ndarray, n_best: int,
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
