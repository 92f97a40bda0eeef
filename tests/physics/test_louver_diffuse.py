"""Sky and ground diffuse at the louver in the lumped model (docs/model.md#louver-diffuse)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.physics.forcing import FacadeOptics, facade_forcing
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.forcing import _knots_fine, fine_louver
from dsfd.sim.replay import at_site, load_weather, weather_inputs

GRID = np.radians(np.arange(-90.0, 91.0, 18.0))
#: Start of the mixed day of the bundled winter weather (bench closed-loop's "mixed").
MIXED_DAY_S = 1641137520.0


def _with(cfg, mode):
    return dataclasses.replace(cfg, model=dataclasses.replace(cfg.model, louver_diffuse=mode))


def test_tabulated_properties_are_the_quadrature_on_the_grid_and_close_between(suwon):
    optics = FacadeOptics(suwon)
    for phi in (GRID, np.radians([-83.3, -41.9, 7.3, 29.5, 89.6])):
        solar, visible = optics.sky_ground(phi)
        tol = 1e-12 if phi is GRID else 4e-4  # the node spacing's interpolation error
        for got, louver in ((solar, optics.louver_solar), (visible, optics.louver_visible)):
            direct = louver.sky_ground(phi)
            for name in direct._fields:
                np.testing.assert_allclose(getattr(got, name), getattr(direct, name), atol=tol)


def _diffuse_day(suwon, *, ground_share):
    """Three overcast steps: 200 W/m2 diffuse on the façade, no beam."""
    w = weather_inputs(at_site(load_weather("rmis-golden-2022-01"), suwon), suwon,
                       start_s=MIXED_DAY_S, n_steps=3)
    f = facade_forcing(suwon, w)
    diffuse = np.full(3, 200.0)
    return f._replace(beam_wm2=np.zeros(3), diffuse_wm2=diffuse, ground_wm2=ground_share * diffuse)


def test_uniform_radiance_gives_the_paper_model(suwon):
    # Half the façade's view is sky, half ground: with equal radiance the split is the
    # hemispherical average (docs/model.md#louver-diffuse).
    f = _diffuse_day(suwon, ground_share=0.5)
    split = FacadeOptics(_with(suwon, "sky_ground")).loads(f, GRID)
    uniform = FacadeOptics(_with(suwon, "uniform")).loads(f, GRID)
    open_ = np.abs(GRID) < np.radians(80.0)
    np.testing.assert_allclose(split.q_trans_wm2[open_], uniform.q_trans_wm2[open_], rtol=3e-3)
    np.testing.assert_allclose(split.sources, uniform.sources, rtol=3e-3, atol=1e-6)
    np.testing.assert_allclose(split.q_da_w, uniform.q_da_w, rtol=3e-3)


def test_slats_tilted_up_see_the_bright_sky(suwon):
    # A dark ground (a tenth of the diffuse): tilted up (φ > 0) the slats pass the sky,
    # tilted down they look at the ground. The uniform model cannot tell the two apart.
    f = _diffuse_day(suwon, ground_share=0.1)
    split = FacadeOptics(_with(suwon, "sky_ground")).loads(f, GRID).q_trans_wm2[:, 0]
    uniform = FacadeOptics(_with(suwon, "uniform")).loads(f, GRID).q_trans_wm2[:, 0]
    up, down = split[6:10], split[4:0:-1]  # +18 … +72 against −18 … −72
    assert np.all(up > 1.5 * down)
    assert np.all(np.abs(uniform[6:10] / uniform[4:0:-1] - 1.0) < 0.25)


def test_facade_ground_diffuse_is_half_the_albedo_times_ghi(suwon):
    # A vertical surface sees half the ground: I_g,v = ρ_g GHI (1 − cos 90°)/2.
    w = weather_inputs(at_site(load_weather("rmis-golden-2022-01"), suwon), suwon,
                       start_s=MIXED_DAY_S, n_steps=1440)
    f = facade_forcing(suwon, w)
    np.testing.assert_allclose(f.ground_wm2, suwon.site.albedo * f.ghi_wm2 / 2.0, rtol=1e-12)
    assert np.all(f.ground_wm2 <= f.diffuse_wm2 + 1e-9)


@pytest.mark.parametrize("mode, worst", [("sky_ground", 0.08), ("uniform", None)])
def test_lumped_transmission_follows_the_plants_fine_optics(suwon, mode, worst):
    # The truth plant's fine optics (Perez, measured or DIRINT beam, M = 10, slat thickness,
    # its own sky/ground path) are an independent reckoning of the same day: with the split
    # the lumped model's daily transmitted solar is within 8 % of it at every open angle; the
    # uniform average is nearly three times too high with the slats tilted down.
    series = at_site(load_weather("rmis-golden-2022-01"), suwon)
    w = weather_inputs(series, suwon, start_s=MIXED_DAY_S, n_steps=1440,
                       t_in_c=np.full(1440, 25.0))
    cfg = _with(suwon, mode)
    phis = GRID[1:-1]
    lumped = FacadeOptics(cfg).loads(facade_forcing(cfg, w), phis).q_trans_wm2.sum(axis=1)
    options = PlantOptions()
    fine = _knots_fine(cfg, options, w, phis, fine_louver(cfg.louver, options)).sources
    plant = fine[:, :, 4].sum(axis=0)
    ratio = lumped / plant
    if worst is None:
        assert ratio[0] > 2.5  # −72°
    else:
        assert np.all(np.abs(ratio - 1.0) < worst)


def test_measured_facade_irradiance_splits_by_ghi_or_evenly(suwon):
    w = weather_inputs(at_site(load_weather("rmis-golden-2022-01"), suwon), suwon,
                       start_s=MIXED_DAY_S + 12 * 3600, n_steps=2)  # noon
    poa = w._replace(poa_global_wm2=np.array([500.0, 500.0]),
                     poa_diffuse_wm2=np.array([150.0, 150.0]))
    with_ghi = facade_forcing(suwon, poa)
    expected = np.minimum(suwon.site.albedo * with_ghi.ghi_wm2 / 2.0, 150.0)
    np.testing.assert_allclose(with_ghi.ground_wm2, expected, rtol=1e-12)
    # Without GHI the façade's diffuse is taken as uniform radiance: half from the ground.
    no_ghi = facade_forcing(suwon, poa._replace(ghi_wm2=np.full(2, np.nan)))
    np.testing.assert_allclose(no_ghi.ground_wm2, 75.0)
