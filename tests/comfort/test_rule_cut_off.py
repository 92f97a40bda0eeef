"""The rule baseline's comfort rules: sun-tracking cut-off and draught limit, while occupied.

Independent references: the textbook profile angle of a vertical façade,
tan(profile) = tan(altitude) / cos(azimuth difference) (ASHRAE Handbook Fundamentals,
fenestration: shading by horizontal louvers), written here from the sun's altitude and
azimuth; the cut-off of flat slats judged by the 2-D ray cast through a stack of slats of
tests/comfort/test_visual.py (first principles, not the model's τ_bb formula); and, for level
slats, the textbook rule that the beam is excluded once tan(profile) >= s/w.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from dsfd.control.baseline import cut_off_position, rule_decision
from dsfd.physics.forcing import facade_forcing
from dsfd.physics.solar import solar_position
from dsfd.sim.replay import at_site, load_weather, weather_inputs
from tests.comfort.test_visual import _ray_cast_fraction

#: 2022-01-02, clear: 08:32, 09:32, 15:32 and 16:32 local (UTC+9), a low winter sun.
LOW_SUN_S = (1641079920.0, 1641083520.0, 1641105120.0, 1641108720.0)


def textbook_profile_deg(zenith_deg: float, azimuth_deg: float, facade_deg: float) -> float:
    """tan(profile) = tan(altitude) / cos(sun azimuth − façade azimuth)."""
    altitude = math.radians(90.0 - zenith_deg)
    return math.degrees(math.atan(math.tan(altitude)
                                  / math.cos(math.radians(azimuth_deg - facade_deg))))


def _blocks(louver, phi_deg: float, profile_deg: float) -> bool:
    return _ray_cast_fraction(math.radians(phi_deg), math.radians(profile_deg),
                              louver.slat_width_m, louver.slat_pitch_m) == 0.0


@pytest.mark.parametrize("time_s", LOW_SUN_S)
def test_cut_off_tracks_the_textbook_profile_angle_of_a_low_winter_sun(suwon, time_s):
    pos = solar_position(time_s, suwon.site.latitude_deg, suwon.site.longitude_deg)
    profile = textbook_profile_deg(float(pos.zenith_deg), float(pos.azimuth_deg),
                                   suwon.facade.azimuth_deg)
    assert 0.0 < profile < 30.0  # low sun on the south façade
    # The façade forcing the controller sees has the same profile angle.
    w = weather_inputs(at_site(load_weather("rmis-golden-2022-01"), suwon), suwon,
                       start_s=time_s - 0.5 * suwon.model.step_s, n_steps=1)
    assert facade_forcing(suwon, w).profile_deg[0] == pytest.approx(profile, abs=0.05)
    lv = suwon.louver
    cut = cut_off_position(lv, profile)
    assert _blocks(lv, cut, profile)  # no ray passes the slats
    # ... and it is the most open motor position that does so: every position nearer to
    # level lets some sun through.
    nearer = [a for a in lv.angles_deg() if abs(a) < abs(cut)]
    assert nearer and not any(_blocks(lv, a, profile) for a in nearer)


def test_level_slats_are_the_cut_off_once_the_sun_is_above_atan_s_over_w(suwon):
    lv = suwon.louver  # s/w = 0.9: level slats exclude the beam from 42° of profile up
    edge = math.degrees(math.atan(lv.slat_pitch_m / lv.slat_width_m))
    assert cut_off_position(lv, edge + 1.0) == 0.0
    assert cut_off_position(lv, edge - 3.0) != 0.0


def test_narrow_slats_take_the_least_transmitting_position(suwon):
    # w < s: no position blocks a horizontal ray; the rule takes the most closed one.
    lv = dataclasses.replace(suwon.louver, slat_width_m=0.03, slat_pitch_m=0.04)
    cut = cut_off_position(lv, 0.0)
    rays = {a: _ray_cast_fraction(math.radians(a), 0.0, 0.03, 0.04) for a in lv.angles_deg()}
    assert rays[cut] == pytest.approx(min(rays.values()), abs=1e-3)


SUNNY = dict(t_in_c=22.0, t_out_c=0.0, beam_wm2=400.0, profile_deg=12.0)


def test_occupied_rule_cuts_off_the_sun_the_energy_rule_lets_in(suwon):
    energy = rule_decision(suwon, heating=True, t5_c=35.0, **SUNNY)
    assert energy == rule_decision(suwon, heating=True, t5_c=35.0, occupied=False, **SUNNY)
    assert not _blocks(suwon.louver, energy.phi_deg, 12.0)  # along the rays: sun in
    occupied = rule_decision(suwon, heating=True, t5_c=35.0, occupied=True, **SUNNY)
    assert _blocks(suwon.louver, occupied.phi_deg, 12.0)
    assert occupied.phi_deg == cut_off_position(suwon.louver, 12.0)
    assert occupied.afr == energy.afr == 1  # warm cavity air: no draught
    assert "cut-off" in occupied.comfort and any("cut-off" in t for t in occupied.trace)


def test_occupied_rule_keeps_a_position_that_blocks_already(suwon):
    # Cooling turns the slats across the rays: nothing passes, nothing to change.
    cool = dict(t_in_c=24.0, t_out_c=28.0, beam_wm2=500.0, profile_deg=60.0)
    energy = rule_decision(suwon, heating=False, t5_c=40.0, **cool)
    occupied = rule_decision(suwon, heating=False, t5_c=40.0, occupied=True, **cool)
    assert _blocks(suwon.louver, energy.phi_deg, 60.0)
    assert (occupied.phi_deg, occupied.afr) == (energy.phi_deg, energy.afr)
    assert occupied.comfort == "no comfort rule fired"


@pytest.mark.parametrize("t5_c", [8.0, 15.0])
def test_occupied_rule_blows_no_cold_air_into_the_room(suwon, t5_c):
    # A cool night: the energy rule flushes with outdoor air through the cavity (7).
    night = dict(t_in_c=24.0, t_out_c=12.0, beam_wm2=0.0, profile_deg=0.0)
    energy = rule_decision(suwon, heating=False, t5_c=t5_c, **night)
    assert energy.afr == 7
    occupied = rule_decision(suwon, heating=False, t5_c=t5_c, occupied=True, **night)
    assert (occupied.afr, occupied.or_pct) == (10, 0.0)  # below the 18.4 °C of category B
    assert "draught" in occupied.comfort
    mild = dataclasses.replace(suwon, comfort=dataclasses.replace(
        suwon.comfort, supply_air_min_c=np.floor(t5_c) - 1.0))
    assert rule_decision(mild, heating=False, t5_c=t5_c, occupied=True, **night).afr == 7
