"""The comfort check of a command on the Suwon panel under a clear winter noon sun.

Independent reasons: beyond the cut-off angle (checked against a ray cast in test_visual) no
beam passes the slats, whatever the glass; closing the louver cuts the eye illuminance; an
exhaust regime blows no air into the room; an unoccupied room has no limit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.control.comfort import comfort_check
from dsfd.physics.comfort_visual import cutoff_angles
from dsfd.physics.forcing import FacadeOptics, facade_forcing
from dsfd.sim.replay import at_site, load_weather, weather_inputs

#: 2022-01-02 03:32 UTC, the clear noon of the bundled winter weather: ~854 W/m2 beam on the
#: south façade at a profile angle of ~30°.
NOON_S = 1641094320.0


@pytest.fixture(scope="module")
def noon(suwon):
    w = weather_inputs(at_site(load_weather("rmis-golden-2022-01"), suwon), suwon,
                       start_s=NOON_S, n_steps=2)
    f = facade_forcing(suwon, w)
    assert f.beam_wm2[0] > 800.0
    return f, FacadeOptics(suwon)


def _check(suwon, noon, **kw):
    forcing, optics = noon
    args = dict(phi_deg=0.0, afr=10, or_pct=0.0, occupied=True, t_pane_c=20.0,
                t_supply_c=22.0) | kw
    return comfort_check(suwon, optics, forcing, **args)


def test_open_slats_let_the_sun_in_and_the_cut_off_keeps_it_out(suwon, noon):
    forcing, _ = noon
    lv = suwon.louver
    cut_deg = math.degrees(cutoff_angles(math.radians(forcing.profile_deg[0]),
                                         width=lv.slat_width_m, pitch=lv.slat_pitch_m).lower)
    beyond = max(a for a in lv.angles_deg() if a <= cut_deg)  # first motor step beyond
    parallel = _check(suwon, noon, phi_deg=18.0)  # slats nearly along the ~30° rays
    shut = _check(suwon, noon, phi_deg=beyond)
    assert parallel.direct_sun_wm2 > 100.0
    assert any(v.startswith("direct sun") for v in parallel.violations)
    assert shut.direct_sun_wm2 == 0.0
    assert not any(v.startswith("direct sun") for v in shut.violations)
    assert "would violate: direct sun" in parallel.describe()


def test_closing_the_louver_lowers_the_glare(suwon, noon):
    dgps = [_check(suwon, noon, phi_deg=a).dgp for a in (0.0, -18.0, -54.0, -90.0)]
    assert dgps[0] == 1.0  # the sun through the slats on the eye: certain glare
    assert np.all(np.diff(dgps) < 0) and dgps[-1] >= 0.184


def test_supply_air_is_checked_only_when_the_regime_blows_into_the_room(suwon, noon):
    cold = _check(suwon, noon, phi_deg=-90.0, afr=7, or_pct=50.0, t_supply_c=8.0)
    assert cold.supply_air_c == 8.0
    assert any(v.startswith("supply air 8.0 <") for v in cold.violations)
    exhaust = _check(suwon, noon, phi_deg=-90.0, afr=5, or_pct=50.0, t_supply_c=8.0)
    assert exhaust.supply_air_c is None and not exhaust.violations
    closed = _check(suwon, noon, phi_deg=-90.0, afr=7, or_pct=0.0, t_supply_c=8.0)
    assert closed.supply_air_c is None


def test_a_cold_pane_breaks_the_cool_wall_limit(suwon, noon):
    # Room at 22 °C; the pane fills about half the view from 1 m.
    cold = _check(suwon, noon, phi_deg=-90.0, t_pane_c=0.0)
    assert cold.asymmetry_k < -10.0
    assert any("cool-pane asymmetry" in v and "category B" in v for v in cold.violations)
    mild = _check(suwon, noon, phi_deg=-90.0, t_pane_c=18.0)
    assert not mild.violations


def test_unoccupied_means_no_limit(suwon, noon):
    check = _check(suwon, noon, phi_deg=18.0, afr=7, or_pct=50.0, t_supply_c=5.0,
                   occupied=False, t_pane_c=0.0)
    assert check.direct_sun_wm2 > 100.0 and not check.violations
    assert "unoccupied" in check.describe()
