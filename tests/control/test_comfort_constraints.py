"""The optimiser under the comfort limits of the occupied horizon steps.

Independent references: the 2-D ray cast through flat slats (tests/comfort/test_visual.py)
and the textbook profile angle for the direct sun; the standalone comfort check of one step
(:func:`dsfd.control.comfort.comfort_check`, the trace's check) for the chosen command;
brute force over the whole actuator grid under the same constraints; and the invariants of
a constrained minimum (it never costs less than the unconstrained one, and it is the
unconstrained one when nothing binds).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.bench.control_cases import day_forcing, random_problems
from dsfd.control.bruteforce import brute_force
from dsfd.control.comfort import comfort_check
from dsfd.control.comfort_horizon import LIMIT_NAMES, VIOLATION_BAND
from dsfd.control.horizon import Candidates, HorizonEvaluator
from dsfd.control.optimiser import ControlProblem, MpcOptimiser
from dsfd.control.paper_sqp import optimise_paper_sqp
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import step_inputs
from dsfd.sim.openloop import first_step
from tests.comfort.test_visual import _ray_cast_fraction

H = 15


@pytest.fixture(scope="module")
def mpc(suwon):
    return MpcOptimiser(suwon)


def _problem(mpc, start_utc_s: float, *, pane_c: float | None = None) -> ControlProblem:
    """A heating decision on the bundled clear winter day from the closed steady state."""
    forcing = day_forcing(mpc.cfg)
    k = int(np.searchsorted(forcing.time_s, start_utc_s))
    window = forcing.window(k, k + H)
    theta = mpc.model.default_theta()
    inp = step_inputs(window, mpc.optics.loads(window, 0.0))
    x0 = mpc.model.steady_state([10], 0.0, first_step(inp), theta)[0]
    if pane_c is not None:
        x0[2] = pane_c + T_ZERO
    return ControlProblem(x0=x0, forcing=window, theta=theta, heating=True,
                          previous_phi_deg=18.0, previous_afr=10, previous_or_pct=0.0)


#: 2022-01-02 08:32 and 12:32 local: a low morning sun and the clear noon.
MORNING_S, NOON_S = 1641079920.0, 1641094320.0


def _occupied(problem: ControlProblem, first: int = 0, last: int = H) -> ControlProblem:
    mask = np.zeros(H, bool)
    mask[first:last] = True
    return dataclasses.replace(problem, occupied=mask)


def _sun_passes(cfg, phi_deg: float, profile_deg: float) -> float:
    lv = cfg.louver
    return _ray_cast_fraction(np.radians(phi_deg), np.radians(profile_deg), lv.slat_width_m,
                              lv.slat_pitch_m)


@pytest.mark.parametrize("start_s", [MORNING_S, NOON_S])
def test_the_limits_shut_out_the_sun_that_energy_alone_lets_in(suwon, mpc, start_s):
    problem = _problem(mpc, start_s)
    profile = float(problem.forcing.profile_deg[0])
    free = mpc.decide(problem)
    bound = mpc.decide(_occupied(problem))
    assert _sun_passes(suwon, free.phi_deg, profile) > 0.1  # energy alone: sun on the desks
    assert bound.cost_j >= free.cost_j  # a constraint never makes the optimum cheaper
    assert "direct sun cut-off" in bound.comfort and "bound the choice" in bound.comfort
    assert bound.trace[-1] == f"comfort: {bound.comfort}"
    # The chosen command, checked step by step by the trace's comfort check.
    for k in range(H):
        check = comfort_check(suwon, mpc.optics, problem.forcing.window(k, H),
                              phi_deg=bound.phi_deg, afr=bound.afr, or_pct=bound.or_pct,
                              occupied=True, t_pane_c=20.0, t_supply_c=25.0)
        assert check.direct_sun_wm2 <= suwon.comfort.direct_sun_max_wm2
        assert check.dgp <= suwon.comfort.dgp_max


def test_a_zero_direct_sun_limit_is_the_geometric_cut_off(suwon, mpc):
    strict = dataclasses.replace(suwon, comfort=dataclasses.replace(suwon.comfort,
                                                                    direct_sun_max_wm2=0.0))
    opt = MpcOptimiser(strict)
    problem = _problem(opt, MORNING_S)
    d = opt.decide(_occupied(problem))
    for profile in problem.forcing.profile_deg:
        assert _sun_passes(suwon, d.phi_deg, float(profile)) == 0.0


def test_under_the_limits_the_search_matches_brute_force(suwon, mpc):
    problem = _occupied(_problem(mpc, MORNING_S))
    d = mpc.decide(problem)
    ref = brute_force(suwon, mpc.model, mpc.optics, problem, or_step_pct=5.0)
    assert "no candidate" not in d.comfort
    assert d.cost_j <= ref.cost_j + 1e-3 * max(abs(ref.cost_j), 3600.0)


def test_occupancy_starting_inside_the_horizon_binds_the_held_command(suwon, mpc):
    """The candidates are held over the horizon, so a room occupied from step 11 on already
    constrains this decision; one that became empty before it does not."""
    problem = _problem(mpc, NOON_S)
    free = mpc.decide(problem)
    later = mpc.decide(_occupied(problem, first=10))
    assert any(t.startswith("comfort: 5 of 15 steps occupied (steps 11-15)")
               for t in later.trace)
    assert _sun_passes(suwon, later.phi_deg, float(problem.forcing.profile_deg[12])) < \
        _sun_passes(suwon, free.phi_deg, float(problem.forcing.profile_deg[12]))
    assert mpc.decide(_occupied(problem, first=0, last=0)) == free


def test_unoccupied_decisions_are_the_energy_only_decisions(suwon, mpc):
    for problem in random_problems(suwon, 4, seed=7):
        free = mpc.decide(problem)
        empty = mpc.decide(dataclasses.replace(problem, occupied=np.zeros(H, bool)))
        assert empty == free  # every field: command, cost, terms, trace
        assert free.comfort == "" and not any(t.startswith("comfort") for t in free.trace)


def test_least_violation_when_no_candidate_meets_the_limits(suwon, mpc):
    """A pane at -5 °C beside a 20 °C room breaks the cool-wall asymmetry limit of category B
    (10 K) whatever the panel does in 15 minutes: the decision takes the least violation,
    says so, and no candidate of the full grid violates less."""
    problem = _occupied(_problem(mpc, MORNING_S, pane_c=-5.0))
    d = mpc.decide(problem)
    assert d.comfort.startswith("no candidate meets every limit: least violation")
    assert "radiant asymmetry" in d.comfort
    # Every candidate on the grid, evaluated under the same limits.
    n_a = len(mpc.angles)
    a, r, o = (m.ravel() for m in np.meshgrid(np.arange(n_a), mpc.open_regimes,
                                              np.linspace(0.0, 1.0, 6), indexing="ij"))
    grid = Candidates(np.append(a, np.arange(n_a)), np.append(r, np.full(n_a, 10)),
                      np.append(o, np.zeros(n_a)))
    ev = HorizonEvaluator(suwon, mpc.model, mpc.optics, problem, mpc.angles).evaluate_all(grid)
    assert np.all(ev.violation > 0.0)
    chosen = float(d.comfort.split("least violation ")[1].split(" ")[0])
    assert chosen <= (ev.violation.min() + VIOLATION_BAND) * (1.0 + 5e-3)  # (3 digits)
    # The asymmetry excess is the relative excess of the limit averaged over the horizon:
    # here |Δt_pr| − 10 K over 10 K, the same order at every step.
    asym = ev.excess[:, LIMIT_NAMES.index("radiant asymmetry")]
    assert np.all((asym > 0.0) & (asym < 1.0))


def test_the_papers_sqp_takes_the_limits_as_a_penalty(suwon, mpc):
    problem = _problem(mpc, NOON_S)
    free = optimise_paper_sqp(suwon, mpc.model, mpc.optics, problem)
    bound = optimise_paper_sqp(suwon, mpc.model, mpc.optics, _occupied(problem))
    assert free.comfort == "" and _sun_passes(suwon, free.phi_deg, 30.0) > 0.1
    # SLSQP on the penalised relaxed objective may stop on either side: before the direct
    # sun was judged under the beam bound (docs/model.md#direct-sun-bound) it reached the
    # feasible side at noon from the paper's start, with the bound's 6 % more penalty it
    # stops at the start (seen); either way its note says which, and says it truly.
    passes = [_sun_passes(suwon, bound.phi_deg, float(p)) for p in problem.forcing.profile_deg]
    if bound.comfort.endswith("every limit met"):
        assert max(passes) == 0.0
    else:
        assert "the rounded control still violates" in bound.comfort
        assert max(passes) > 0.0


def _random_sunny(cfg, index: int, *, offset: int) -> ControlProblem:
    """Problem ``index`` of the random set (seed 9) from ``offset`` on, every other one moved
    onto a random sunny window of the bundled winter days (seed 5), every step occupied."""
    rng = np.random.default_rng(5)
    forcing = day_forcing(cfg)
    sunny = np.flatnonzero(forcing.beam_wm2 > 30.0)
    sunny = sunny[sunny < forcing.time_s.size - H]
    problem = None
    for i, problem in enumerate(random_problems(cfg, offset + index + 1, seed=9)[offset:]):
        if i % 2 == 0:
            k = int(rng.choice(sunny))
            problem = dataclasses.replace(problem, forcing=forcing.window(k, k + H))
    assert problem is not None
    return _occupied(problem)


@pytest.mark.parametrize(("supply_min_c", "offset", "index"), [(None, 0, 14), (21.0, 40, 10),
                                                               (21.0, 40, 50)])
def test_search_cases_once_missed_under_the_limits(suwon, supply_min_c, offset, index):
    """(None, 0, 14): the 300 s screening showed the exhaust set's flow reversed into the room
    with cold air (infeasible) where one-minute steps show exhaust, and the decision cost 111 %
    more than brute force until the finalists under the visual limits alone were evaluated
    too. (21.0, 40, 10) and (50): the screening judged the other way round, and the all-open
    set behind the cut-off louver has its best opening at 5 %, which the coarse grid and its
    bracket never reach (27 % and 14 %) until the best pair's OR ladder when comfort binds."""
    cfg = suwon if supply_min_c is None else dataclasses.replace(
        suwon, comfort=dataclasses.replace(suwon.comfort, supply_air_min_c=supply_min_c))
    opt = MpcOptimiser(cfg)
    problem = _random_sunny(cfg, index, offset=offset)
    d = opt.decide(problem)
    ref = brute_force(cfg, opt.model, opt.optics, problem, or_step_pct=5.0)
    assert "no candidate" not in d.comfort
    assert d.cost_j <= ref.cost_j + 1e-3 * max(abs(ref.cost_j), 3600.0), (d, ref)
