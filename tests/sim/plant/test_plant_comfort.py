"""The truth plant's own comfort quantities (docs/model.md#plant-comfort): physical invariants."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.measured import parse_iso_utc
from dsfd.physics.comfort_geometry import window_view_factor
from dsfd.physics.constants import T_ZERO
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.comfort import _strip_view_factors
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.plant import Plant

#: The clear Sunday of the bundled record at the Suwon site (UTC+9): 10:00, 12:00, 15:00
#: local time, and 23:00 (night).
SUNNY = ("2022-01-02T01:00:00Z", "2022-01-02T03:00:00Z", "2022-01-02T06:00:00Z")
NIGHT = "2022-01-02T14:00:00Z"


@pytest.fixture(scope="module")
def plant(suwon, rmis):
    """The full-fidelity plant with actuators that follow a command at once, so one instant
    can be looked at under every louver angle."""
    p = Plant(suwon, PlantOptions(actuators="ideal"), seed=4, weather_series=rmis)
    p.reset(parse_iso_utc(SUNNY[0]) - 600.0)
    return p


def _at(plant: Plant, iso: str) -> None:
    t = parse_iso_utc(iso)
    if t > plant.time_s:
        plant.advance(t - plant.time_s)


def _blocks_beam(phi_deg: float, profile_deg: float, width: float, pitch: float) -> bool:
    """Thin flat slats stop the beam when one slat's shadow along the ray covers the pitch:
    |sin(phi_s - phi)| w >= s cos(phi_s) (ASHRAE Handbook Fundamentals, fenestration: the
    profile-angle construction; for horizontal slats tan(phi_s) >= s/w)."""
    ps, ph = math.radians(profile_deg), math.radians(phi_deg)
    return abs(math.sin(ps - ph)) * width >= pitch * math.cos(ps) - 1e-12


@pytest.mark.parametrize("iso", SUNNY)
def test_no_beam_passes_the_louver_at_or_beyond_cut_off(plant, iso):
    _at(plant, iso)
    lv = plant.cfg.louver
    seen = {}
    for phi in lv.angles_deg():
        plant.apply(Command(float(phi), 10, 100.0))
        seen[float(phi)] = plant.comfort()
    profile = seen[0.0].profile_deg
    assert 5.0 < profile < 60.0  # the sun is in front of the façade
    blocked = [phi for phi in seen if _blocks_beam(phi, profile, lv.slat_width_m,
                                                   lv.slat_pitch_m)]
    assert -90.0 in blocked and 90.0 in blocked
    for phi in blocked:
        assert seen[phi].direct_sun_wm2 == pytest.approx(0.0, abs=1e-9), phi
    # ... while with the slats along the ray the beam comes in.
    along = min(seen, key=lambda phi: abs(phi - profile))
    assert seen[along].direct_sun_wm2 > 50.0
    assert all(seen[phi].direct_sun_wm2 > 0.0 for phi in seen if phi not in blocked
               and abs(phi - profile) < 20.0)


def test_glare_rises_with_the_light_the_plant_lets_in(plant):
    _at(plant, SUNNY[1])
    rows = []
    for phi in plant.cfg.louver.angles_deg():
        plant.apply(Command(float(phi), 10, 100.0))
        c = plant.comfort()
        rows.append((c.e_v_lx, c.dgp))
    e_v, dgp = np.array(rows).T
    order = np.argsort(e_v)
    assert np.all(np.diff(dgp[order]) >= 0.0)  # more light at the eye, more glare
    assert np.ptp(e_v) > 1000.0
    open_, closed = rows[len(rows) // 2], rows[-1]  # 0 deg and 90 deg
    assert open_[1] > closed[1]
    # Noon with the slats open against the same slats at night: no light at all gives
    # Wienold's intercept, DGPs = 0.184.
    plant.apply(Command(0.0, 10, 100.0))
    _at(plant, NIGHT)
    night = plant.comfort()
    assert night.e_v_lx == pytest.approx(0.0, abs=1e-6)
    assert night.dgp == pytest.approx(0.184, abs=1e-9)
    assert night.direct_sun_wm2 == 0.0 and open_[1] > night.dgp


@pytest.mark.parametrize("afr", [1, 2, 3, 4, 5, 6, 7, 8, 9, 10])
def test_supply_air_is_the_cavity_outlet_air_when_it_enters_the_room(plant, afr):
    plant.apply(Command(0.0, afr, 100.0))
    plant.advance(120.0)
    c = plant.comfort()
    st = plant.true_state()
    into_room = -st.m_dot_kgs[2:] > 0.0  # IB, IT: flows positive into the cavity
    out_anywhere = st.m_dot_kgs < 0.0
    if afr in (3, 4, 10):  # exterior circulation, closed: no damper to the room open
        assert c.supply_air_c is None
    elif into_room.any():
        if out_anywhere.sum() == into_room.sum():  # every outflow goes to the room
            assert c.supply_air_c == pytest.approx(st.t_outlet_k - T_ZERO, abs=1e-9)
        assert st.label in (1, 2, 7, 8, 9)
        # The air comes from the cavity: within its range of temperatures.
        air = np.concatenate([st.segments_k["ao"], st.segments_k["ai"]]) - T_ZERO
        assert air.min() - 0.5 <= c.supply_air_c <= air.max() + 0.5
    else:  # an exhaust regime: room air goes out, none comes in
        assert c.supply_air_c is None


def test_the_pane_is_seen_strip_by_strip(plant, suwon):
    strips = _strip_view_factors(suwon, plant.model.lay.n)
    com, fac = suwon.comfort, suwon.facade
    whole = float(window_view_factor(distance_m=com.occupant_distance_m, width_m=fac.width_m,
                                     height_m=fac.glazed_height_m, lateral_m=fac.width_m / 2,
                                     elevation_m=com.asymmetry_height_m - com.sill_height_m))
    assert strips.sum() == pytest.approx(whole, rel=1e-9)  # view factors add up
    assert np.argmax(strips) == int((com.asymmetry_height_m - com.sill_height_m)
                                    / (fac.glazed_height_m / strips.size))  # the facing strip
    c = plant.comfort()
    g3 = plant.true_state().segments_k["g3"] - T_ZERO
    assert g3.min() - 1e-9 <= c.t_pane_c <= g3.max() + 1e-9
    assert np.sign(c.asymmetry_k) == np.sign(c.t_pane_c - c.t_room_mrt_c)
