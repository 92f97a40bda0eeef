"""The optimiser of Eq. 6 against brute force, the paper's SQP and physical expectations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.bench.control_cases import day_forcing, random_problems
from dsfd.config import load_panel
from dsfd.control.bruteforce import brute_force
from dsfd.control.optimiser import (
    ControlProblem,
    MpcOptimiser,
    _parabolic_points,
    distinct_regimes,
)
from dsfd.control.paper_sqp import optimise_paper_sqp
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import step_inputs
from dsfd.sim.openloop import first_step
from tests.conftest import PANELS


@pytest.fixture(scope="module")
def mpc(suwon):
    return MpcOptimiser(suwon)


def test_one_representative_per_damper_set(suwon):
    assert distinct_regimes(suwon.openings.available_regimes()) == (1, 3, 5, 6, 9, 10)
    assert distinct_regimes((3, 4, 10)) == (3, 10)


def _gap_pct(cost, ref):
    return 100.0 * (cost - ref.cost_j) / max(abs(ref.cost_j), 3600.0)


def test_matches_brute_force_and_never_loses_to_paper_sqp(suwon, mpc):
    """Random states and weathers: within 0.1 % of brute force (OR in 1 % steps)."""
    for problem in random_problems(suwon, 4, seed=11):
        d = mpc.decide(problem)
        ref = brute_force(suwon, mpc.model, mpc.optics, problem, or_step_pct=1.0)
        assert _gap_pct(d.cost_j, ref) <= 0.1, (d, ref)
        sqp = optimise_paper_sqp(suwon, mpc.model, mpc.optics, problem)
        assert d.cost_j <= sqp.cost_j + 1e-6 * abs(sqp.cost_j) + 1e-3


@pytest.mark.parametrize(("seed", "index"), [(0, 170), (1, 73), (2, 156), (2, 4), (8, 110)])
def test_damper_sets_misranked_by_the_screening_are_decided_at_full_resolution(
        suwon, mpc, seed, index):
    """Two cooling cases from the benchmark's random problems. (0, 170): every damper set
    within 0.2 % of the others, exhaust (5) at full opening ranked outside the eight
    finalists, 0.23 % above brute force. (1, 73): the 300 s screening step put the
    all-open set 2.2 % ahead of supply through the cavity, which wins by 4.6 % at full
    resolution; both failed before the best of every damper set near the screened best
    was also evaluated at full resolution. (2, 156): the screening preferred the louver at
    0° to −18° (0.14 % worse), fixed by re-evaluating the best's louver neighbours. (2, 4):
    a night with a flat cost, where the screening ranks the angles the wrong way round;
    evaluating only the neighbours of the screened best left 0.10 %: stage 3 must still
    walk from the full-resolution best. (8, 110): cooling; with all dampers open the flows
    switch pattern twice within the horizon at one-minute steps, which the 300 s screening
    cannot show (its Q_air of the other sign, the set screened 24 % above the best): 4.6 %
    above brute force until the all-open set at the screened best louver position was always
    evaluated at full resolution."""
    problem = random_problems(suwon, index + 1, seed=seed)[index]
    ref = brute_force(suwon, mpc.model, mpc.optics, problem, or_step_pct=1.0)
    d = mpc.decide(problem)
    assert _gap_pct(d.cost_j, ref) <= 0.1, (d, ref)


def test_parabolic_or_rounds_only_ever_improve_the_decision(suwon):
    """``or_refine_rounds`` (off by default) adds full-resolution openings around the best:
    the decision can only get cheaper, and stays on the OR limits."""
    refined = dataclasses.replace(suwon, control=dataclasses.replace(
        suwon.control, or_refine_rounds=2))
    plain_mpc, refined_mpc = MpcOptimiser(suwon), MpcOptimiser(refined)
    for problem in random_problems(suwon, 6, seed=21):
        plain, better = plain_mpc.decide(problem), refined_mpc.decide(problem)
        assert better.cost_j <= plain.cost_j
        assert 0.0 <= better.or_pct <= 100.0


def test_parabolic_points_land_on_the_vertex_of_a_parabola():
    """The refinement's vertex step is exact for a quadratic cost (independent check: the
    vertex of 3 (x − 0.37)² + 1 is 0.37), and it never proposes a point already tried."""
    xs = np.array([0.0, 0.2, 0.5, 0.8, 1.0])
    pts = _parabolic_points(xs, 3.0 * (xs - 0.37) ** 2 + 1.0)
    assert np.any(np.isclose(pts, 0.37))
    assert not np.any(np.isin(pts, xs))
    assert np.all((pts >= 0.0) & (pts <= 1.0))


def test_commands_lie_on_the_actuator_grid(suwon, mpc):
    angles = set(suwon.louver.angles_deg())
    for problem in random_problems(suwon, 6, seed=5):
        for d in (mpc.decide(problem), optimise_paper_sqp(suwon, mpc.model, mpc.optics,
                                                          problem)):
            assert d.phi_deg in angles
            assert d.afr in suwon.openings.available_regimes()
            assert 0.0 <= d.or_pct <= 100.0
            if d.afr == 10:
                assert d.or_pct == 0.0
            assert d.trace


def test_sunny_winter_day_brings_cavity_air_into_the_room(suwon, mpc):
    """Clear winter noon, cavity hotter than the room: the regime delivers cavity air."""
    forcing = day_forcing(suwon)
    k = int(np.argmax(forcing.beam_wm2))
    window = forcing.window(k, k + suwon.control.horizon_steps)
    theta = mpc.model.default_theta()
    inp = step_inputs(window, mpc.optics.loads(window, 0.0))
    x0 = mpc.model.steady_state([10], 0.0, first_step(inp), theta)[0]
    assert x0[4] - T_ZERO > window.t_in_k[0] - T_ZERO + 10  # hot closed cavity
    d = mpc.decide(ControlProblem(x0=x0, forcing=window, theta=theta, heating=True))
    assert d.afr in (1, 2, 7, 8, 9)
    assert d.terms_j["q_air_j"] > 0
    assert d.or_pct > 0


def test_no_louver_panel_decides_without_louver_positions():
    cfg = load_panel(PANELS / "suwon-south-no-louver.yaml")
    opt = MpcOptimiser(cfg)
    problem = random_problems(cfg, 1, seed=2)[0]
    d = opt.decide(problem)
    assert d.phi_deg == 0.0


def test_calibrated_heat_offsets_enter_the_horizon_prediction(suwon, mpc):
    """The offsets the self-calibration fits are heat the model lacks: a positive offset
    on the louver node must warm the predicted louver and raise the heat gained in
    heating mode, exactly as the same extra absorbed short-wave would."""
    import dataclasses

    from dsfd.control.optimiser import HorizonEvaluator

    problem = random_problems(suwon, 1, seed=3)[0]
    problem = dataclasses.replace(problem, heating=True)
    warm = dataclasses.replace(problem, heat_offsets_wm2=np.array([0.0, 0.0, 0.0, 50.0]))
    cand = (np.array([5]), np.array([1]), np.array([1.0]))
    base_ev = HorizonEvaluator(suwon, mpc.model, mpc.optics, problem, mpc.angles)
    warm_ev = HorizonEvaluator(suwon, mpc.model, mpc.optics, warm, mpc.angles)
    base_in, warm_in = base_ev.inputs(cand[0]), warm_ev.inputs(cand[0])
    np.testing.assert_allclose(np.asarray(warm_in.sources) - np.asarray(base_in.sources),
                               np.broadcast_to([0.0, 0.0, 0.0, 50.0], base_in.sources.shape))
    base, _ = base_ev.evaluate(*cand)
    hot, _ = warm_ev.evaluate(*cand)
    assert hot.cost_j[0] < base.cost_j[0]  # more heat into the room: lower heating cost
