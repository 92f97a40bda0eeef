"""The vectorised coupling fixed-point solver (docs/model.md#coupling)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.physics.rootfind import solve_fixed_point


def _phi_factory(fn):
    calls = []

    def phi(t, rows):
        calls.append((t.copy(), rows.copy()))
        return fn(t, rows)

    return phi, calls


@pytest.mark.parametrize("batch", [1, 7])
def test_contraction_and_chattering_maps_converge(batch):
    """Φ with slope −3 (plain iteration diverges, the chattering case) still converges."""
    roots = np.linspace(280, 320, batch)
    slopes = np.linspace(-3.0, 0.8, batch) if batch > 1 else np.array([-3.0])

    def fn(t, rows):
        return roots[rows] + slopes[rows] * (t - roots[rows]) + 0.01 * (t - roots[rows]) ** 2

    phi, calls = _phi_factory(fn)
    fp = solve_fixed_point(phi, roots + 7.0, tol=1e-9, max_evals=40)
    assert fp.converged.all()
    np.testing.assert_allclose(fp.t, roots, atol=1e-7)
    # The last evaluation of each element is at its returned point.
    last = {}
    for t, rows in calls:
        for ti, r in zip(t, rows, strict=True):
            last[int(r)] = ti
    np.testing.assert_allclose([last[i] for i in range(batch)], fp.t, atol=0)


def test_far_start_and_saturating_map():
    """Bounded Φ (like bounded flows): bracketing from 60 K away with a step limit."""

    def fn(t, rows):
        return 300.0 + 20.0 * np.tanh((t - 300.0) / 5.0) * -1.0

    phi, _ = _phi_factory(fn)
    fp = solve_fixed_point(phi, np.array([360.0, 240.0, 300.5]), tol=1e-8, max_evals=60)
    assert fp.converged.all()
    np.testing.assert_allclose(fp.t, 300.0, atol=1e-6)


def test_scalar_and_vector_paths_agree():
    def fn(t, rows):
        return 290.0 + 0.3 * np.sin(t / 3.0)

    one = solve_fixed_point(_phi_factory(fn)[0], np.array([280.0]), tol=1e-10, max_evals=50)
    many = solve_fixed_point(_phi_factory(fn)[0], np.array([280.0, 280.0]), tol=1e-10,
                             max_evals=50)
    np.testing.assert_allclose(one.t[0], many.t, atol=1e-9)


def test_evaluation_limit_is_respected():
    def fn(t, rows):
        return 300.0 - 50.0 * (t - 300.0)  # steep: needs many bisections at tol 1e-15

    fp = solve_fixed_point(_phi_factory(fn)[0], np.array([310.0, 290.0]), tol=1e-15,
                           max_evals=5)
    assert np.all(fp.evaluations <= 5)


@pytest.mark.parametrize("batch", [1, 5])
def test_known_slope_makes_the_first_move_a_newton_step(batch):
    """With dh/dT known (the previous step's slope), a linear map needs two evaluations;
    without it the solver needs more, and both land on the same root."""
    roots = np.linspace(285.0, 305.0, batch)
    gain = 0.3  # Φ' (h' = Φ' − 1 = −0.7)

    def fn(t, rows):
        return roots[rows] + gain * (t - roots[rows])

    cold = solve_fixed_point(_phi_factory(fn)[0], roots + 2.0, tol=1e-9, max_evals=40)
    warm = solve_fixed_point(_phi_factory(fn)[0], roots + 2.0, tol=1e-9, max_evals=40,
                             slope=np.full(batch, gain - 1.0))
    assert warm.converged.all() and cold.converged.all()
    assert np.all(warm.evaluations == 2)
    assert np.all(cold.evaluations > 2)
    np.testing.assert_allclose(warm.t, roots, atol=1e-9)
    # The slope handed on to the next solve is that of the map.
    np.testing.assert_allclose(cold.slope, gain - 1.0, rtol=1e-6)


def test_stale_positive_slope_is_ignored():
    """A slope with the wrong sign (h must fall through its root) falls back to the plain
    first iteration instead of stepping away from the root."""

    def fn(t, rows):
        return 300.0 + 0.5 * (t - 300.0)

    fp = solve_fixed_point(_phi_factory(fn)[0], np.array([310.0]), tol=1e-9, max_evals=40,
                           slope=np.array([2.0]))
    assert fp.converged.all()
    np.testing.assert_allclose(fp.t, 300.0, atol=1e-8)


def test_rollouts_started_from_a_neighbouring_solution_land_on_the_same_states(suwon):
    """The coupling's root does not depend on where its search starts. The fit's rollouts
    (15 steps from every fifth measured state of a window) of θ rows 1 % away from a base
    θ, started from the base rollouts' cavity temperatures and slopes (what the fit's finite
    differences do), end where cold-started ones do, within the coupling tolerance, with
    fewer evaluations of the coupled network (1.76 against 2.35 per row and step here: a
    cold rollout's first step has no slope to start from)."""
    from dsfd.bench.calibration import synthetic_window
    from dsfd.estimation.objective import COUPLING_TOL_K
    from dsfd.physics.coupling import StepInputs
    from dsfd.physics.model import LumpedModel

    steps, theta = synthetic_window(suwon, hours=2.0)
    model = LumpedModel(dataclasses.replace(
        suwon, model=dataclasses.replace(suwon.model, step_s=60.0)))
    horizon = 15
    starts = np.arange(0, steps.n_steps - horizon, 5)
    idx = starts[:, None] + np.arange(horizon)[None, :]
    y = np.asarray(steps.y_k, float)[starts]
    x0 = np.column_stack([y, y[:, 2]])  # x6, the room-side node, at the inner pane
    inp = StepInputs(*(np.asarray(v)[idx] for v in steps.inputs))
    reg, or_ = np.asarray(steps.regime)[idx], np.asarray(steps.or_)[idx]

    def rollout(th: np.ndarray, **guess: np.ndarray):
        def stacked(v: np.ndarray) -> np.ndarray:  # θ-major rows, as the fit's batch
            return np.concatenate([v] * th.shape[0], axis=0)

        return model.rollout(stacked(x0), stacked(reg), stacked(or_),
                             StepInputs(*(stacked(v) for v in inp)),
                             np.repeat(th, starts.size, axis=0)[:, None, :],
                             coupling_tol_k=COUPLING_TOL_K, **guess)

    base = rollout(theta[None, :])
    rows = theta[None, :].repeat(theta.size, axis=0) * (1.0 + 0.01 * np.eye(theta.size))
    cold = rollout(rows)
    n = rows.shape[0]
    warm = rollout(rows, t5_guess=np.concatenate([base.x[:, 1:, 4]] * n),
                   slope_guess=np.concatenate([base.coupling_slope] * n))
    gap = np.max(np.abs(warm.x - cold.x))
    assert 0.0 < gap < 20 * COUPLING_TOL_K  # (above 0: the warm start was used)
    assert warm.evaluations.sum() < 0.85 * cold.evaluations.sum()
