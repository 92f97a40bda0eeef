"""Thermal comfort near the panel: draught rate, supply-air limit, radiant asymmetry.

pythermalcomfort 4.8 has neither the ISO 7730 draught rate nor the radiant asymmetry (only
ASHRAE 55's ankle draught), so it cannot be the reference here. The references are: the
properties ISO 7730:2005 §6.2 states of its draught model (no draught below 0.05 m/s or at
34 °C, rising with speed and turbulence) and the original, unrounded model of Fanger et al.
(1988) that it rounds; ISO 7730:2005 §6.4's percentage-dissatisfied
curves for a warm and a cool wall against the Table A.4 limits and the Table A.1 PD limits
(5 % for A and B, 10 % for C), i.e. two different parts of the standard that must agree;
and the view-factor kernel integral (test_visual) with the plane radiant temperature's
small-difference linearisation (ISO 7726:1998 Annex B).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.config.comfort import Comfort
from dsfd.physics.comfort_geometry import window_view_factor
from dsfd.physics.comfort_thermal import (
    asymmetry_limit_k,
    draught_rate_pct,
    draught_temperature_min_c,
    plane_radiant_temperature_c,
    radiant_asymmetry_k,
    supply_air_min_c,
)


def test_draught_rate_properties_the_standard_states():
    assert draught_rate_pct(18.0, [0.0, 0.03, 0.05], 40.0).tolist() == [0.0, 0.0, 0.0]
    assert draught_rate_pct([34.0, 36.0], 0.3, 40.0).tolist() == [0.0, 0.0]
    v = np.linspace(0.06, 0.5, 30)
    assert np.all(np.diff(draught_rate_pct(20.0, v, 40.0)) > 0)  # faster: more draught
    t = np.linspace(16.0, 30.0, 30)
    assert np.all(np.diff(draught_rate_pct(t, 0.2, 40.0)) < 0)  # warmer: less
    assert draught_rate_pct(20.0, 0.2, 60.0) > draught_rate_pct(20.0, 0.2, 10.0)
    assert draught_rate_pct(-40.0, 5.0, 100.0) == 100.0  # a percentage


def test_draught_rate_is_the_rounded_fanger_1988_model():
    # Fanger, Melikov, Hanzawa & Ring, "Air turbulence and sensation of draught", Energy and
    # Buildings 12 (1988), with its unrounded coefficients as ASHRAE RP-781 (Fountain &
    # Huizenga 1995) gives them: PD = (34 - t)(v - 0.05)^0.6223 (3.143 + 0.3696 v Tu).
    # ISO 7730 rounds them; over the model's range (20-26 °C, 0.06-0.5 m/s, Tu 10-60 %) the
    # two agree within 2 %.
    t, v, tu = np.meshgrid(np.linspace(20, 26, 7), np.linspace(0.06, 0.5, 12),
                           np.linspace(10, 60, 6))
    fanger = (34.0 - t) * (v - 0.05) ** 0.6223 * (3.143 + 0.3696 * v * tu)
    below = fanger < 95.0  # a percentage: both stop at 100
    np.testing.assert_allclose(draught_rate_pct(t, v, tu)[below], fanger[below], rtol=0.02)
    assert below.mean() > 0.8


@pytest.mark.parametrize(("category", "dr"), [("A", 10.0), ("B", 20.0), ("C", 30.0)])
def test_supply_air_limit_reaches_the_category_draught_rate(category, dr):
    comfort = Comfort(category=category, supply_air_speed_ms=0.15, turbulence_pct=40.0)
    limit = supply_air_min_c(comfort)
    assert draught_rate_pct(limit, 0.15, 40.0) == pytest.approx(dr)
    assert draught_rate_pct(limit + 0.5, 0.15, 40.0) < dr < draught_rate_pct(limit - 0.5,
                                                                               0.15, 40.0)
    assert supply_air_min_c(Comfort(category=category, supply_air_min_c=16.0)) == 16.0


def test_stricter_categories_need_warmer_supply_air():
    limits = [supply_air_min_c(Comfort(category=c)) for c in "ABC"]
    assert limits[0] > limits[1] > limits[2]
    assert draught_temperature_min_c(20.0, 0.05, 40.0) == -math.inf  # still air never draughts


def _pd_warm_wall(dt: float) -> float:  # ISO 7730:2005 §6.4, warm wall
    return 100.0 / (1.0 + math.exp(3.72 - 0.052 * dt)) - 3.5


def _pd_cool_wall(dt: float) -> float:  # ISO 7730:2005 §6.4, cool wall
    return 100.0 / (1.0 + math.exp(6.61 - 0.345 * dt))


@pytest.mark.parametrize(("category", "pd_max"), [("A", 5.0), ("B", 5.0), ("C", 10.0)])
def test_asymmetry_limits_agree_with_the_dissatisfied_curves(category, pd_max):
    warm = asymmetry_limit_k(category, warm=True)
    cool = asymmetry_limit_k(category, warm=False)
    # The table's limits keep PD within the category's limit (the table rounds: 13 K of a
    # cool wall gives 10.7 %), and the curves reach it within 3 K above the table.
    assert _pd_warm_wall(warm) <= pd_max and _pd_warm_wall(warm + 3.0) > pd_max
    assert _pd_cool_wall(cool) <= pd_max + 1.0 and _pd_cool_wall(cool + 3.0) > pd_max
    assert _pd_cool_wall(cool - 1.0) <= pd_max


def test_plane_radiant_temperature_limits_and_linearisation():
    assert plane_radiant_temperature_c(1.0, 5.0, 22.0) == pytest.approx(5.0)
    assert plane_radiant_temperature_c(0.0, 5.0, 22.0) == pytest.approx(22.0)
    # For small differences t_pr ~ sum F_i t_i (ISO 7726 Annex B); fourth powers weigh the
    # warmer surface a little more, so the exact value lies above the linear one.
    exact = plane_radiant_temperature_c(0.4, 16.0, 22.0)
    linear = 0.4 * 16.0 + 0.6 * 22.0
    assert linear < exact < linear + 0.1


def test_asymmetry_of_the_suwon_pane_for_a_seated_occupant(suwon):
    comfort = Comfort()
    width, height = suwon.facade.width_m, suwon.facade.glazed_height_m
    f = window_view_factor(distance_m=comfort.occupant_distance_m, width_m=width,
                           height_m=height, lateral_m=width / 2,
                           elevation_m=comfort.asymmetry_height_m - comfort.sill_height_m)
    assert 0.0 < f < 1.0  # a finite window fills part of the half space the plane faces
    cold = radiant_asymmetry_k(view_factor=f, t_pane_c=12.0, t_room_c=22.0)
    warm = radiant_asymmetry_k(view_factor=f, t_pane_c=40.0, t_room_c=22.0)
    assert cold == pytest.approx(f * (12.0 - 22.0), abs=0.3)
    assert warm == pytest.approx(f * (40.0 - 22.0), abs=0.6) and warm > 0 > cold
    # Closer to the pane, the same pane is felt more.
    near = window_view_factor(distance_m=0.3, width_m=width, height_m=height,
                              lateral_m=width / 2, elevation_m=0.6)
    assert abs(radiant_asymmetry_k(view_factor=near, t_pane_c=12.0, t_room_c=22.0)) > abs(cold)
