"""c keeps step with f while no window shows a diagonal regime (docs/model.md#c-follows-f)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.config.parameters import Param
from dsfd.estimation.calibration import c_following_f, offline_fit
from dsfd.estimation.params import N_FIT, ParameterSpace
from dsfd.estimation.stepdata import model_config, step_data
from dsfd.physics.airflow import IT, AirflowGeometry, diagonal_path_resistance
from dsfd.physics.model import LumpedModel
from tests.estimation.synthetic import lumped_record, true_theta, with_calibration
from tests.estimation.synthetic import suwon_diagonal_k as series_k


def test_diagonal_path_resistance_is_two_dampers_and_the_cavity(suwon):
    geom = AirflowGeometry.from_sections(suwon.openings, suwon.facade)
    k = diagonal_path_resistance(np.array([20.0, 100.0]), geom)
    assert k.shape == (2, 2)
    assert k[:, 0] == pytest.approx([series_k(20.0), series_k(100.0)], rel=1e-12)
    assert np.array_equal(k[:, 0], k[:, 1])  # equal dampers: both paths alike
    no_it = dataclasses.replace(geom, area_m2=np.where(np.arange(4) == IT, 0.0, geom.area_m2))
    k = diagonal_path_resistance(50.0, no_it)
    assert k[0] == pytest.approx(series_k(50.0)) and np.isinf(k[1])


def _moved(space: ParameterSpace, geom: AirflowGeometry, f_after: float, *,
           free: tuple[str, ...] = ("f",), c: float = 0.05) -> np.ndarray:
    """ϑ after a fit that moved f from its default to ``f_after`` with ``free`` free."""
    before = space.default.copy()
    before[Param.C] = c
    after = before.copy()
    after[Param.F] = f_after
    mask = np.zeros(N_FIT, bool)
    for name in free:
        mask[Param[name.upper()]] = True
    return c_following_f(before, after, mask, space, geom)


@pytest.fixture
def geom(suwon) -> AirflowGeometry:
    return AirflowGeometry.from_sections(suwon.openings, suwon.facade)


def test_an_unfitted_c_keeps_its_ratio_to_the_orifice_conductance(suwon, geom):
    """The invariant: c·√(K_in + K_out) — c against the path's orifice conductance at 1 Pa,
    √(2/(ρK)) — is the same before and after f moved."""
    space = ParameterSpace.from_panel(suwon)
    f0 = space.default[Param.F]
    for f1 in (31.0, 100.0, 800.0):
        c1 = _moved(space, geom, f1)[Param.C]
        assert c1 * np.sqrt(series_k(f1)) == pytest.approx(0.05 * np.sqrt(series_k(f0)))
    assert _moved(space, geom, 31.0)[Param.C] > 0.05 > _moved(space, geom, 800.0)[Param.C]


def test_c_stays_where_the_fit_or_the_panel_puts_it(suwon, geom):
    space = ParameterSpace.from_panel(suwon)
    # a diagonal window fitted c; f did not move
    assert _moved(space, geom, 31.0, free=("f", "c"))[Param.C] == 0.05
    assert _moved(space, geom, 31.0, free=())[Param.C] == 0.05
    orifice = dataclasses.replace(suwon, model=dataclasses.replace(suwon.model,
                                                                   diagonal_flow="orifice"))
    held = ParameterSpace.from_panel(orifice)
    assert held.fixed[Param.C]
    assert _moved(held, geom, 31.0)[Param.C] == 0.05                     # c in no flow law
    assert _moved(space, geom, 5.0, c=0.4)[Param.C] == space.upper[Param.C]  # clipped at 0.5


@pytest.mark.parametrize("follows", [True, False])
def test_a_consistent_facade_gives_c_from_the_orifice_windows_alone(suwon, follows):
    """Synthetic record of a façade whose diagonal path shares the cavity with the orifice
    paths (f_true 30, c_true by the orifice ratio from the defaults), without any diagonal
    regime: f is recovered from the speed of regimes 1 and 3, and c with it — or, with
    ``c_follows_f: false``, c stays at its default, 42 % low."""
    f_true = 30.0
    theta = true_theta(suwon)
    theta[Param.F] = f_true
    c_default = suwon.parameters.c.default
    theta[Param.C] = c_default * np.sqrt(series_k(suwon.parameters.f.default) / series_k(f_true))
    data, _ = lumped_record(suwon, theta, step_s=300.0, hours=6.0, seed=4, regimes=(1, 3, 10))
    steps = step_data(suwon, data)
    model = LumpedModel(model_config(suwon, steps.step_s))
    cfg = with_calibration(suwon, c_follows_f=follows)
    state, fit = offline_fit(model, steps, cfg.calibration, max_nfev=20)
    assert not fit.free[Param.C]
    assert state.theta[Param.F] == pytest.approx(f_true, rel=0.25)
    if follows:
        assert state.theta[Param.C] == pytest.approx(theta[Param.C], rel=0.25)
    else:
        assert state.theta[Param.C] == c_default
        assert c_default < 0.75 * theta[Param.C]
