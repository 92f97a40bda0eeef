"""The slats' film against the cavity speed (dsfd.physics.slat_film, docs/model.md#slat-film)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import FacadeOptics, OpticalLoads, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.physics.slat_film import equal_speed_ms, film_factor
from dsfd.sim.plant.physics import churchill_chu_vertical, flat_plate_laminar
from tests.physics.test_model import _forcing


def test_the_factor_is_one_at_the_reference_and_grows_as_the_laminar_plate_far_above():
    v = np.array([0.0, 0.01, 0.03, 0.1, 0.3, 1.0, 4.0, 16.0])
    f = film_factor(v, equal_speed_ms=0.03, reference_speed_ms=0.1)
    assert film_factor(np.array([0.1]), equal_speed_ms=0.03, reference_speed_ms=0.1)[0] == \
        pytest.approx(1.0)
    assert np.all(np.diff(f) > 0)
    # still air: the natural part alone, (1 / (1 + (v_ref/v_e)^1.5))^(1/3)
    assert f[0] == pytest.approx((1.0 / (1.0 + (0.1 / 0.03) ** 1.5)) ** (1.0 / 3.0))
    # far above v_e the forced laminar film h ∝ Re^½ ∝ √v: 4 times the speed, twice the film
    assert f[-1] / f[-2] == pytest.approx(2.0, rel=0.01)
    # the sign of the flow does not matter
    assert film_factor(np.array([-0.2]), equal_speed_ms=0.03, reference_speed_ms=0.1)[0] == \
        pytest.approx(film_factor(np.array([0.2]), equal_speed_ms=0.03,
                                  reference_speed_ms=0.1)[0])


@pytest.mark.parametrize(("width_m", "height_m"), [(0.05, 2.5), (0.08, 1.5), (0.025, 4.0)])
def test_at_the_equal_speed_the_plants_natural_and_forced_correlations_agree(width_m,
                                                                              height_m):
    """v_e is where natural convection over the cavity height (Churchill & Chu) equals the
    laminar flat plate over the slat width: checked against the truth plant's own
    implementations of both correlations (dsfd.sim.plant.physics, with temperature-dependent
    air properties; the model takes them at 300 K)."""
    ve = equal_speed_ms(slat_width_m=width_m, height_m=height_m)
    h_n = float(churchill_chu_vertical(10.0, 300.0, height_m, 101325.0))
    h_f = float(flat_plate_laminar(ve, width_m, 300.0, 101325.0))
    assert h_f == pytest.approx(h_n, rel=0.05)


def test_a_faster_flow_cools_sunlit_slats_and_at_the_reference_speed_nothing_changes(suwon):
    """Regime 1 under the winter-noon sun (docs/model.md#parameters): with the film factor the
    steady slats are cooler the faster the flow; with the reference speed set to the flow's
    own speed the step is the constant-film model's."""
    optics = FacadeOptics(suwon)
    f = _forcing(beam=600.0, diffuse=150.0, wind=1.0, sky_drop=12.0)
    inp = step_inputs(f, optics.loads(f, np.radians(np.array([0.0]))))
    inp = inp._replace(**{k: getattr(inp, k)[:, 0] for k in OpticalLoads._fields})

    def model(**changes) -> LumpedModel:
        return LumpedModel(dataclasses.replace(
            suwon, model=dataclasses.replace(suwon.model, **changes)))

    constant = model(slat_film="constant")
    th = constant.default_theta()
    x = constant.steady_state([1], 1.0, inp, th)
    base = constant.step(x, [1], 1.0, inp, th)
    speed = float(abs(base.v_cav_ms[0]))
    assert 0.05 < speed < 0.3
    at_speed = model(slat_film="speed_dependent", slat_film_reference_speed_ms=speed)
    np.testing.assert_allclose(at_speed.step(x, [1], 1.0, inp, th).x_next, base.x_next,
                               atol=2e-3)
    slats = []
    for ref in (4.0 * speed, speed, 0.25 * speed):  # the flow is 1/4, 1, 4 × the reference
        m = model(slat_film="speed_dependent", slat_film_reference_speed_ms=ref)
        slats.append(m.steady_state([1], 1.0, inp, th)[0, 3] - T_ZERO)
    assert slats[0] > slats[1] + 1.0 > slats[2] + 2.0
    # slats in the sun stay warmer than the cavity air whatever the film
    assert min(slats) > x[0, 4] - T_ZERO
