"""The plant oracle: each decision chosen by rolling candidate commands out on the truth plant.

An offline reference, not a controller. At a decision the truth plant (its full state:
every segment temperature, the actuators in motion, the integrator) is copied once per
candidate command; each copy is commanded and integrated over the control horizon with
the true weather, and the candidate whose *plant* objective is lowest wins:

    J = −(Q_cv,rd + Q_sol + Q_air + Q_DA)        (heating, paper Eq. 4)
    J =  Q_cv,rd + Q_sol + Q_air − Q_DA           (cooling, Eq. 5; docs/model.md#control-objective)

over the horizon, from the plant's own room-side heat integrals, plus the same louver move
penalty as the optimiser (``control.louver_move_penalty_wh`` per 18° step). So it plans on
the truth itself, within the same actuator grid, horizon and penalty as ``mpc``; what it
does not do is search every command (one 15-minute plant rollout costs ~0.1 s).

It keeps to the comfort limits ``mpc`` keeps to (docs/model.md#comfort-constraints): while a
horizon step is occupied, only the candidates the lumped evaluation with perfect
information finds acceptable (every limit met, or the least violation) may win
(:meth:`PlantOracle.comfort_allowed`). Without them it was no yardstick for ``mpc``: on the
clear cooling day it bought its saving with glare above the limit in 28 % of the occupied
minutes, where ``mpc`` and the rule had none (seeds 1 and 2, 29 Nov).

What it searches (:meth:`PlantOracle.candidates`):

* *full search* (every ``full_every``-th decision; default every one): the lumped model with perfect
  information (the plant's true mid-height state, the true weather, the plant's parameters
  mapped to the lumped θ) ranks every louver position × damper set × OR in
  ``or_grid_pct``; the best ``per_damper_set`` of each damper set are candidates, and so
  are the lumped optimiser's own decision (continuous OR), its louver neighbours within
  ``louver_reach`` steps, the same damper set at the OR grid points, the command now
  applied (no move) and the last plant-oracle choice;
* *short list* (the decisions in between): the command now applied, the last choice, the
  lumped optimiser's decision and its louver neighbours.

Callers may add candidates (``extra``), e.g. the command ``mpc`` would send, so that the
oracle's choice can be shown to cost no more on the plant than that command (when the comfort
limits allow it among the candidates).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from dsfd.config.panel import REGIME_OPENINGS, PanelConfig
from dsfd.control.comfort_horizon import acceptable
from dsfd.control.horizon import Candidates
from dsfd.control.objective import J_PER_WH, louver_move_penalty
from dsfd.control.optimiser import (
    CLOSED,
    ControlProblem,
    Decision,
    HorizonEvaluator,
    MpcOptimiser,
    distinct_regimes,
)
from dsfd.sim.plant.model import ROOM_FLOWS

if TYPE_CHECKING:
    from dsfd.sim.plant.plant import Plant

__all__ = ["Candidate", "PlantCost", "PlantOracle", "SearchSettings", "plant_rollout_cost",
           "room_objective_j"]



class Candidate(NamedTuple):
    """A command on the actuator grid (louver angle [deg], regime, OR [%])."""

    phi_deg: float
    afr: int
    or_pct: float

    def as_dict(self) -> dict[str, float]:
        return {"phi_deg": self.phi_deg, "afr": self.afr, "or_pct": self.or_pct}

    @classmethod
    def of(cls, phi_deg: float, afr: int, or_pct: float) -> Candidate:
        """Normalised: OR on whole per cent, 0 in the closed regime."""
        return cls(float(phi_deg), int(afr), 0.0 if int(afr) == CLOSED
                   else float(min(100.0, max(0.0, round(or_pct)))))


def room_objective_j(heat_j: Mapping[str, np.ndarray | float], heating: np.ndarray | bool
                     ) -> np.ndarray:
    """J of room-side heat ``heat_j`` [J] (keys :data:`ROOM_FLOWS`), heating or cooling."""
    gains = heat_j["q_cv_rd"] + heat_j["q_sol_trans"] + heat_j["q_air"]
    return np.where(heating, -(gains + heat_j["q_da"]), gains - heat_j["q_da"])


@dataclass(frozen=True)
class PlantCost:
    """A candidate rolled out on the plant: J [J] (with the move penalty) and heat [J]."""

    candidate: Candidate
    j: float
    heat_j: dict[str, float]
    #: Why the plant could not integrate this command (J is then inf), else "".
    failure: str = ""


def plant_rollout_cost(plant: Plant, candidate: Candidate, *, seconds: float, heating: bool,
                       previous_phi_deg: float | None, penalty_wh: float,
                       step_deg: float) -> PlantCost:
    """Roll ``candidate`` out on a copy of ``plant`` for ``seconds`` (the plant is untouched).

    The copy shares the plant's weather series (read only); everything that evolves —
    temperatures, actuators, integrator, forcing cache — is its own. A command whose
    integration fails (the plant's Radau can step into non-physical trial states after an
    abrupt change from an extreme state) costs inf and says why.
    """
    twin = copy.deepcopy(plant, memo={id(plant.series): plant.series, id(plant.cfg): plant.cfg})
    before = twin.room_heat_j()
    try:
        # (a failing integration may pass through non-physical trial states on the way)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            twin.apply(candidate.as_dict())
            twin.advance(seconds)
    except (ArithmeticError, ValueError, RuntimeError) as exc:
        return PlantCost(candidate, math.inf, {}, f"{type(exc).__name__}: {exc}")
    after = twin.room_heat_j()
    heat = {k: after[k] - before[k] for k in ROOM_FLOWS}
    penalty = louver_move_penalty(np.array([candidate.phi_deg]), previous_phi_deg,
                                  penalty_wh=penalty_wh, step_deg=step_deg)[0]
    return PlantCost(candidate, float(room_objective_j(heat, heating)) + float(penalty), heat)


@dataclass(frozen=True, kw_only=True)
class SearchSettings:
    """How much of the actuator grid the plant oracle rolls out (module docstring)."""

    per_damper_set: int = 2
    louver_reach: int = 1
    or_grid_pct: tuple[float, ...] = (0.0, 50.0, 100.0)
    full_every: int = 1


@dataclass
class PlantOracle:
    """Chooses commands by plant rollouts (module docstring). One per closed-loop run."""

    cfg: PanelConfig
    settings: SearchSettings = field(default_factory=SearchSettings)
    decisions: int = 0
    last_choice: Candidate | None = None
    rollouts: int = 0
    #: Every candidate of the last decision with its plant cost (for inspection).
    last_costs: list[PlantCost] = field(default_factory=list)
    #: Whether the comfort limits let the last decision take each integrated candidate.
    last_allowed: dict[Candidate, bool] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.optimiser = MpcOptimiser(self.cfg)
        lv = self.cfg.louver
        self.angles = np.asarray(lv.angles_deg() if lv is not None else (0.0,))
        self.step_deg = lv.step_deg if lv is not None else 18.0
        self.regimes = distinct_regimes(self.cfg.openings.available_regimes())

    # ------------------------------------------------------------------ candidates
    def _representative(self, afr: int) -> int:
        """The regime of :attr:`regimes` that opens the same dampers as ``afr``."""
        return next(r for r in self.regimes if REGIME_OPENINGS[r] == REGIME_OPENINGS[int(afr)])

    def _lumped_ranking(self, problem: ControlProblem) -> list[tuple[float, Candidate]]:
        """Every louver position × damper set × grid OR, ranked by the lumped model."""
        ctl = self.cfg.control
        grid = [g for g in self.settings.or_grid_pct]
        a, r, o = [], [], []
        for i in range(self.angles.size):
            for reg in self.regimes:
                for g in ([0.0] if reg == CLOSED else grid):
                    a.append(i)
                    r.append(reg)
                    o.append(g / 100.0)
        ev = HorizonEvaluator(self.cfg, self.optimiser.model, self.optimiser.optics, problem,
                              self.angles, coupling_tol_k=ctl.coupling_tolerance_k)
        terms, _ = ev.evaluate(np.array(a), np.array(r), np.array(o))
        return sorted((float(c), Candidate.of(self.angles[i], reg, 100.0 * g))
                      for c, i, reg, g in zip(terms.cost_j, a, r, o, strict=True))

    def _around(self, best: Candidate) -> list[Candidate]:
        """The louver neighbours of ``best`` at its damper set and OR."""
        idx = int(np.argmin(np.abs(self.angles - best.phi_deg)))
        reach = self.settings.louver_reach
        return [Candidate.of(self.angles[j], best.afr, best.or_pct)
                for j in range(max(0, idx - reach), min(self.angles.size, idx + reach + 1))]

    def candidates(self, problem: ControlProblem, *, current: Candidate | None,
                   extra: Iterable[Candidate] = (), full: bool = True
                   ) -> tuple[list[Candidate], Decision]:
        """The commands to roll out, and the lumped optimiser's decision among them."""
        lumped = self.optimiser.decide(problem)
        best = Candidate.of(lumped.phi_deg, self._representative(lumped.afr), lumped.or_pct)
        out = [best, *self._around(best)]
        if full:
            per_set: dict[int, int] = {}
            for _, cand in self._lumped_ranking(problem):
                if per_set.get(cand.afr, 0) < self.settings.per_damper_set:
                    per_set[cand.afr] = per_set.get(cand.afr, 0) + 1
                    out.append(cand)
            if best.afr != CLOSED:
                out += [Candidate.of(best.phi_deg, best.afr, g) for g in self.settings.or_grid_pct]
        out += [c for c in (current, self.last_choice) if c is not None]
        out += list(extra)
        return list(dict.fromkeys(out)), lumped

    def comfort_allowed(self, problem: ControlProblem, cands: Sequence[Candidate]
                        ) -> np.ndarray:
        """Which of ``cands`` the comfort limits let a decision take, judged as ``mpc``
        judges its own candidates (:func:`dsfd.control.comfort_horizon.acceptable` of the
        lumped rollout's violation, docs/model.md#comfort-constraints): every limit met, or
        the least violation among them. All, when no step of the horizon is occupied."""
        if not problem.any_occupied or not cands:
            return np.ones(len(cands), bool)
        ctl = self.cfg.control
        ev = HorizonEvaluator(self.cfg, self.optimiser.model, self.optimiser.optics, problem,
                              self.angles, coupling_tol_k=ctl.coupling_tolerance_k)
        idx = np.array([int(np.argmin(np.abs(self.angles - c.phi_deg))) for c in cands])
        evaluated = ev.evaluate_all(Candidates(
            idx, np.array([self._representative(c.afr) for c in cands]),
            np.array([c.or_pct / 100.0 for c in cands])))
        return acceptable(evaluated.violation)

    # ------------------------------------------------------------------ decision
    def decide(self, plant: Plant, problem: ControlProblem, *, current: Candidate | None,
               extra: Sequence[Candidate] = (),
               feasible: Callable[[Candidate], Candidate] | None = None) -> Decision:
        """The candidate with the lowest plant objective over the horizon.

        ``feasible`` maps a candidate to the command that would actually be applied (e.g.
        the safety pipeline's louver move interval); candidates are rolled out as applied.
        """
        full = self.decisions % max(1, self.settings.full_every) == 0
        self.decisions += 1
        cands, lumped = self.candidates(problem, current=current, extra=extra, full=full)
        if feasible is not None:
            cands = list(dict.fromkeys(feasible(c) for c in cands))
        seconds = problem.forcing.time_s.shape[0] * float(self.cfg.model.step_s)
        costs = [plant_rollout_cost(plant, c, seconds=seconds, heating=problem.heating,
                                    previous_phi_deg=problem.previous_phi_deg,
                                    penalty_wh=self.cfg.control.louver_move_penalty_wh,
                                    step_deg=self.step_deg) for c in cands]
        self.rollouts += len(costs)
        self.last_costs = costs
        failed = [pc for pc in costs if pc.failure]
        if len(failed) == len(costs):
            raise RuntimeError("no candidate could be integrated on the plant: "
                               f"{failed[0].failure}")
        integrated = [pc for pc in costs if not pc.failure]
        allowed = self.comfort_allowed(problem, [pc.candidate for pc in integrated])
        self.last_allowed = {pc.candidate: bool(ok) for pc, ok in zip(integrated, allowed,
                                                                     strict=True)}
        win = min((pc for pc, ok in zip(integrated, allowed, strict=True) if ok),
                  key=lambda pc: pc.j)
        self.last_choice = win.candidate
        ranked = sorted(costs, key=lambda pc: pc.j)
        barred = len(allowed) - int(np.count_nonzero(allowed))
        trace = (f"plant oracle ({'full search' if full else 'short list'}): "
                 f"{len(costs)} candidates rolled out on the truth plant over {seconds:g} s"
                 + (f" ({len(failed)} failed to integrate: {failed[0].failure})" if failed else "")
                 + (f"; {barred} barred by the comfort limits" if barred else ""),
                 "best: " + ", ".join(f"{_describe(pc)}" for pc in ranked[:3]),
                 f"lumped optimiser's choice: louver {lumped.phi_deg:+.0f} deg, regime "
                 f"{lumped.afr}, OR {lumped.or_pct:.0f} %")
        c = win.candidate
        return Decision(phi_deg=c.phi_deg, afr=c.afr, or_pct=c.or_pct, method="plant-oracle",
                        cost_j=win.j, terms_j={f"{k}_j": v for k, v in win.heat_j.items()},
                        rollouts=len(costs), trace=trace)


def _describe(pc: PlantCost) -> str:
    c = pc.candidate
    return (f"{c.phi_deg:+.0f} deg/regime {c.afr}/OR {c.or_pct:.0f} % "
            f"J {pc.j / J_PER_WH:+.2f} Wh")

