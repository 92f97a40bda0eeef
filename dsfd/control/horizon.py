"""One decision's problem, its candidate controls and their batched horizon rollout.

A :class:`ControlProblem` is where the façade is and what the horizon will bring; a
:class:`Candidates` record holds constant controls (louver position, damper set, opening),
and :class:`HorizonEvaluator` rolls a batch of them out over the horizon in one call of
:meth:`LumpedModel.rollout` and prices them by Eq. 4–6 (:mod:`dsfd.control.objective`).
The optimisers (:mod:`dsfd.control.optimiser`, :mod:`dsfd.control.bruteforce`) choose
which candidates to evaluate; this module only evaluates them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from dsfd.config.panel import REGIME_OPENINGS, PanelConfig
from dsfd.control.comfort_horizon import (
    LIMIT_NAMES,
    HorizonComfort,
    acceptable,
    equally_violating,
)
from dsfd.control.objective import CostTerms, horizon_cost, louver_move_penalty
from dsfd.estimation.params import with_offsets
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, OpticalLoads, step_inputs
from dsfd.physics.model import LumpedModel

__all__ = ["CLOSED", "Best", "Candidates", "ControlProblem", "Decision", "Evaluated",
           "HorizonEvaluator", "coarsen", "coarsen_loads", "distinct_regimes"]

#: Regime 10: every damper closed (no opening ratio to search).
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
        that the horizon is predicted by the same model the state estimate comes from; None
        for none (the daemon's default, ``control.heat_offsets: false``,
        docs/model.md#heat-offsets).
    occupied : ndarray (H,) of bool or None
        Whether each horizon step is occupied; the comfort limits bind the occupied steps
        (docs/model.md#comfort-constraints). None or all False: energy only.
    """

    x0: np.ndarray
    forcing: Forcing
    theta: np.ndarray
    heating: bool
    previous_phi_deg: float | None = None
    previous_afr: int | None = None
    previous_or_pct: float | None = None
    heat_offsets_wm2: np.ndarray | None = None
    occupied: np.ndarray | None = None

    @property
    def any_occupied(self) -> bool:
        """Whether a comfort limit binds any step of the horizon."""
        return self.occupied is not None and bool(np.any(self.occupied))

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
    #: What comfort did to the choice (docs/model.md#comfort-constraints): which limits bound
    #: it, or that none could be met; empty when no step of the horizon is occupied.
    comfort: str = ""


def distinct_regimes(available: tuple[int, ...]) -> tuple[int, ...]:
    """One representative regime per damper set the panel has (1, 3, 5, 6, 9, 10)."""
    seen: dict[frozenset[str], int] = {}
    for regime in sorted(available):
        seen.setdefault(REGIME_OPENINGS[regime], regime)
    return tuple(sorted(seen.values()))


class Candidates(NamedTuple):
    """Constant controls over the horizon, one candidate per element (arrays of one length).

    Attributes
    ----------
    angle_idx : ndarray of int
        Louver position, an index into the optimiser's angles.
    regime : ndarray of int
        Airflow regime (the representative of its damper set).
    or_ : ndarray of float, [-]
        Damper opening ratio 0..1.
    """

    angle_idx: np.ndarray
    regime: np.ndarray
    or_: np.ndarray

    @classmethod
    def empty(cls) -> Candidates:
        return cls(np.zeros(0, int), np.zeros(0, int), np.zeros(0))

    @property
    def size(self) -> int:
        return int(np.asarray(self.angle_idx).size)

    def take(self, idx: np.ndarray) -> Candidates:
        return Candidates(*(np.asarray(v)[idx] for v in self))

    def join(self, *more: Candidates) -> Candidates:
        """These candidates followed by ``more``."""
        return Candidates(*(np.concatenate(v) for v in zip(self, *more, strict=True)))

    def distinct(self) -> Candidates:
        """Without repeats, in first-seen order."""
        _, first = np.unique(np.stack(list(self)), axis=1, return_index=True)
        return self.take(np.sort(first))


@dataclass(frozen=True, eq=False)
class Evaluated:
    """Candidates rolled out over the horizon: their cost terms, first-step regime labels
    and the relative excess of each comfort limit (C, 4), zero when nothing is occupied."""

    candidates: Candidates
    terms: CostTerms
    labels: np.ndarray
    excess: np.ndarray

    @property
    def violation(self) -> np.ndarray:
        """Normalised comfort violation per candidate (docs/model.md#comfort-constraints)."""
        return self.excess.sum(axis=1)

    def rank_cost(self, limits: slice = slice(None)) -> np.ndarray:
        """The cost of the candidates a decision may take (:func:`acceptable`), +inf for the
        others: ranking by it is ranking by cost under the comfort constraints (``limits``:
        only those columns of :data:`LIMIT_NAMES`)."""
        excess = self.excess[:, limits]
        if not excess.any():
            return self.terms.cost_j
        return np.where(acceptable(excess.sum(axis=1)), self.terms.cost_j, np.inf)

    def best(self) -> Best:
        """The cheapest acceptable (the first of equal costs)."""
        i = int(np.argmin(self.rank_cost()))
        return Best.at(i, self)

    def cheapest(self) -> Best:
        """The cheapest, comfort ignored (what energy alone would choose)."""
        return Best.at(int(np.argmin(self.terms.cost_j)), self)

    def join(self, other: Evaluated) -> Evaluated:
        return Evaluated(self.candidates.join(other.candidates),
                         CostTerms(*(np.concatenate(v) for v in zip(self.terms, other.terms,
                                                                   strict=True))),
                         np.concatenate([self.labels, other.labels]),
                         np.concatenate([self.excess, other.excess]))


class HorizonEvaluator:
    """Batched horizon cost of constant controls for one decision."""

    def __init__(self, cfg: PanelConfig, model: LumpedModel, optics: FacadeOptics,
                 problem: ControlProblem, angles_deg: np.ndarray, *,
                 coupling_tol_k: float | None = None,
                 loads: OpticalLoads | None = None,
                 comfort: HorizonComfort | None = None) -> None:
        self.cfg = cfg
        self.model = model
        self.coupling_tol_k = coupling_tol_k
        self.problem = problem
        self.angles_deg = np.asarray(angles_deg, float)
        self.loads = (optics.loads(problem.forcing, np.radians(self.angles_deg))
                      if loads is None else loads)
        #: The comfort limits of the occupied steps; None (nothing occupied): energy only.
        self.comfort = comfort
        if comfort is None and problem.any_occupied:
            assert problem.occupied is not None
            self.comfort = HorizonComfort(cfg, optics, problem.forcing, self.angles_deg,
                                          problem.occupied)
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
        ev = self.evaluate_all(Candidates(np.asarray(angle_idx, int), np.asarray(regime, int),
                                          np.asarray(or_, float)))
        return ev.terms, ev.labels

    def evaluate_all(self, candidates: Candidates) -> Evaluated:
        """Cost, first-step label and comfort excess of each candidate, kept with it."""
        angle_idx, regime, or_ = candidates
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
        excess = (self.comfort.excess(angle_idx, traj) if self.comfort is not None
                  else np.zeros((n, len(LIMIT_NAMES))))
        return Evaluated(candidates, terms, traj.label[:, 0], excess)


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


@dataclass(frozen=True)
class Best:
    """The cheapest candidate of a batch: its cost [J], controls, first-step label and
    cost terms [J] (what a :class:`Decision` is made of)."""

    cost: float
    angle_idx: int
    regime: int
    or_: float
    label: int
    terms: dict[str, float]
    #: Relative excess of each comfort limit (:data:`LIMIT_NAMES` order), zeros if none.
    excess: tuple[float, ...] = (0.0,) * len(LIMIT_NAMES)

    @classmethod
    def at(cls, i: int, ev: Evaluated) -> Best:
        """Candidate ``i`` of an evaluated batch."""
        a, r, o = ev.candidates
        terms = ev.terms
        return cls(float(terms.cost_j[i]), int(a[i]), int(r[i]), float(o[i]),
                   int(ev.labels[i]),
                   {name: float(getattr(terms, name)[i]) for name in terms._fields},
                   tuple(float(v) for v in ev.excess[i]))

    @property
    def violation(self) -> float:
        return float(sum(self.excess))

    def better(self, other: Best) -> Best:
        """The better of two: the cheaper where both are acceptable next to each other
        (:func:`acceptable`), else the less violating."""
        if equally_violating(self.violation, other.violation):
            return other if other.cost < self.cost else self
        return other if other.violation < self.violation else self

    def same_controls(self, other: Best) -> bool:
        return (self.angle_idx, self.regime, self.or_) == (other.angle_idx, other.regime,
                                                           other.or_)

    def describe(self, angles: np.ndarray) -> str:
        return (f"louver {angles[self.angle_idx]:+.0f} deg, regime {self.label}, OR "
                f"{self.or_ * 100:.1f} %, J {self.cost / 3600.0:+.2f} Wh")

    def decision(self, angles: np.ndarray, *, method: str, rollouts: int,
                 trace: tuple[str, ...], comfort: str = "") -> Decision:
        or_pct = 0.0 if self.regime == CLOSED else round(self.or_ * 100.0, 1)
        return Decision(phi_deg=float(angles[self.angle_idx]), afr=self.label, or_pct=or_pct,
                        method=method, cost_j=self.cost, terms_j=self.terms, rollouts=rollouts,
                        trace=trace, comfort=comfort)
