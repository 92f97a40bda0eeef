"""The calibration's bounded least-squares solver against independent references, and the
daemon's memory reason for it: a calibration update loads no SciPy."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from scipy.optimize import least_squares, lsq_linear

from dsfd.estimation.lsq import bounded_least_squares
from tests.conftest import ROOT


class Counted:
    """r(x) and J(x) of a problem, counting the residual evaluations."""

    def __init__(self, fun, jac):
        self.fun, self.jac_of, self.calls, self.costs = fun, jac, 0, []

    def __call__(self, x):
        self.calls += 1
        r = self.fun(x)
        self.costs.append(0.5 * float(r @ r))
        return r

    def jac(self, x):
        return self.jac_of(x)


def rosenbrock():
    return Counted(lambda x: np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]]),
                   lambda x: np.array([[-20.0 * x[0], 10.0], [-1.0, 0.0]]))


def test_linear_problem_inside_the_box_reaches_the_normal_equations_solution():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(40, 5)), rng.normal(size=40)
    exact = np.linalg.lstsq(a, b, rcond=None)[0]
    p = Counted(lambda x: a @ x - b, lambda x: a)
    res = bounded_least_squares(p, p.jac, np.zeros(5), np.full(5, -10.0), np.full(5, 10.0),
                                x_scale=np.ones(5), max_nfev=30, ftol=1e-12, xtol=1e-12)
    assert res.x == pytest.approx(exact, abs=1e-8)
    assert res.cost == pytest.approx(0.5 * np.sum((a @ exact - b) ** 2), rel=1e-10)


def test_linear_problem_with_binding_bounds_matches_scipys_bounded_solution():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(30, 6)), 3.0 * rng.normal(size=30)
    lo, hi = np.full(6, -0.2), np.full(6, 0.3)
    ref = lsq_linear(a, b, bounds=(lo, hi), tol=1e-12)
    assert np.any(np.isclose(ref.x, lo) | np.isclose(ref.x, hi))  # a bound binds
    p = Counted(lambda x: a @ x - b, lambda x: a)
    res = bounded_least_squares(p, p.jac, np.zeros(6), lo, hi, x_scale=np.ones(6),
                                max_nfev=200, ftol=1e-14, xtol=1e-14, gtol=1e-12)
    assert res.x == pytest.approx(ref.x, abs=1e-6)
    assert np.all((res.x >= lo) & (res.x <= hi))


@pytest.mark.parametrize(("lo", "hi", "x0"), [
    ([-2.0, -2.0], [2.0, 2.0], [-1.2, 1.0]),   # minimum (1, 1) inside
    ([-2.0, -2.0], [0.8, 2.0], [-1.2, 1.0]),   # x0 ≤ 0.8 binds: minimum on the edge
    ([1.5, 0.0], [3.0, 10.0], [2.5, 1.0]),     # x0 ≥ 1.5 binds
])
def test_rosenbrock_with_bounds_matches_scipys_trust_region_reflective(lo, hi, x0):
    lo, hi = np.array(lo), np.array(hi)
    ref = least_squares(rosenbrock().fun, x0, jac=rosenbrock().jac_of, bounds=(lo, hi),
                        method="trf", ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=1000)
    p = rosenbrock()
    res = bounded_least_squares(p, p.jac, np.array(x0), lo, hi, x_scale=np.ones(2),
                                max_nfev=1000, ftol=1e-12, xtol=1e-12, gtol=1e-12)
    assert res.x == pytest.approx(ref.x, abs=1e-5)
    assert res.cost == pytest.approx(ref.cost, abs=1e-9)


def test_cost_never_rises_and_the_evaluation_budget_holds():
    p = rosenbrock()
    res = bounded_least_squares(p, p.jac, np.array([-1.2, 1.0]), np.full(2, -2.0),
                                np.full(2, 2.0), x_scale=np.ones(2), max_nfev=7)
    assert p.calls == res.nfev <= 7
    assert res.status == "max_nfev"
    assert res.cost == min(p.costs) < p.costs[0]
    assert res.fun == pytest.approx(p.fun(res.x)) and res.jac == pytest.approx(p.jac(res.x))


def test_non_finite_residuals_raise_at_the_start_and_are_rejected_later():
    with pytest.raises(ValueError, match="not finite"):
        bounded_least_squares(lambda x: np.array([np.nan]), lambda x: np.ones((1, 1)),
                              np.zeros(1), -np.ones(1), np.ones(1), x_scale=np.ones(1),
                              max_nfev=5)
    # r = x − 2, but NaN beyond x = 1 (a model that fails there): the first step lands
    # in the NaN region, is rejected, and the shorter steps approach 1 from below
    p = Counted(lambda x: np.array([x[0] - 2.0 if x[0] <= 1.0 else np.nan]),
                lambda x: np.ones((1, 1)))
    res = bounded_least_squares(p, p.jac, np.array([-3.0]), np.array([-5.0]),
                                np.array([5.0]), x_scale=np.array([1.0]), max_nfev=40)
    assert np.isnan(p.costs).any()  # the rejection was exercised
    assert np.isfinite(res.cost) and res.x[0] <= 1.0
    assert res.cost < p.costs[0] and res.x[0] > 0.0


def test_scaling_makes_badly_scaled_variables_converge_alike():
    """x₂ lives at 1e4 times x₁'s scale: with x_scale the solver still finds (1, 1e4)."""
    p = Counted(lambda x: np.array([x[0] - 1.0, (x[1] - 1e4) / 1e4, x[0] * x[1] / 1e4 - 1.0]),
                lambda x: np.array([[1.0, 0.0], [0.0, 1e-4], [x[1] / 1e4, x[0] / 1e4]]))
    res = bounded_least_squares(p, p.jac, np.array([3.0, 3e4]), np.array([0.0, 0.0]),
                                np.array([10.0, 1e5]), x_scale=np.array([1.0, 1e4]),
                                max_nfev=50, ftol=1e-12, xtol=1e-12)
    assert res.x == pytest.approx([1.0, 1e4], rel=1e-6)


def test_an_online_calibration_update_loads_no_scipy():
    """The daemon's calibration runs without importing SciPy (its ~38 MB resident cost
    measured by ``dsfd bench daemon``'s ``import_rss_mb``): a real update on a synthetic
    lumped record in a fresh interpreter."""
    code = textwrap.dedent("""
        import sys
        from dsfd.config import load_panel
        from dsfd.estimation.calibration import OnlineCalibrator
        from dsfd.estimation.observer import observe
        from dsfd.estimation.stepdata import model_config, step_data
        from dsfd.physics.model import LumpedModel
        from tests.estimation.synthetic import lumped_record, true_theta
        import dsfd.daemon.runner, dsfd.drivers.modbus
        cfg = load_panel('config/panels/suwon-south.yaml')
        data, _ = lumped_record(cfg, true_theta(cfg), step_s=300.0, hours=4.0)
        steps = step_data(cfg, data)
        model = LumpedModel(model_config(cfg, steps.step_s))
        track = observe(model, steps, model.default_theta()[None])
        cal = OnlineCalibrator(model)
        rep = cal.update(steps, track.x_hat[0], track.x_pred[0])
        assert rep.fit is not None and rep.fit.nfev > 1, rep
        print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy'))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
