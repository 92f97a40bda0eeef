"""Comfort measured on the truth plant in closed-loop runs, counted while occupied (issue 36)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from dsfd.config.comfort import Comfort
from dsfd.measured import parse_iso_utc
from dsfd.sim.closed_loop import ClosedLoopSettings, run_closed_loop
from dsfd.sim.comfort_kpis import ComfortLog, comfort_figures, occupancy_for, weekly_hours
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.comfort import PlantComfort
from dsfd.sim.plant.config import PlantOptions

FAST = PlantOptions.lumped_equivalent(sensors="realistic", actuators="realistic")
#: 07:50 local time (UTC+9) on Monday 3 January 2022, and the same on Sunday 2 January.
MONDAY_0750, SUNDAY_0750 = "2022-01-02T22:50:00Z", "2022-01-01T22:50:00Z"


def _measured(sun: float, dgp: float, air: float | None, asym: float) -> PlantComfort:
    return PlantComfort(time_s=0.0, phi_deg=0.0, profile_deg=0.0, direct_sun_wm2=sun,
                        e_v_lx=0.0, dgp=dgp, supply_air_c=air, t_pane_c=20.0,
                        t_room_mrt_c=20.0, asymmetry_k=asym)


def test_the_figures_count_occupied_minutes_beyond_each_limit():
    log = ComfortLog.empty(60.0)
    log.append(False, None)  # unoccupied: never counted, whatever it is
    for row in ((0.0, 0.20, None, 24.0),  # warm pane beyond 23 K (ISO 7730 B)
                (10.0, 0.50, 10.0, -11.0),  # sun, glare, cold air, cool pane beyond 10 K
                (5.0, 0.30, 25.0, 5.0),  # direct sun at the limit is not beyond it
                (0.0, 0.40, 15.0, -10.0)):  # cold air; the cool pane exactly at the limit
        log.append(True, _measured(*row))
    limits = Comfort(category="B", direct_sun_max_wm2=5.0, dgp_max=0.35, supply_air_min_c=18.0)
    fig = comfort_figures(log, limits)
    assert fig["occupied_min"] == 4.0
    assert fig["direct_sun_min"] == 1.0
    # DGPs 0.2, 0.3, 0.4, 0.5: median 0.35, p95 by linear interpolation 0.4 + 0.85 * 0.1
    assert fig["dgp_p50"] == pytest.approx(0.35)
    assert fig["dgp_p95"] == pytest.approx(0.485)
    assert fig["dgp_max"] == 0.5 and fig["dgp_above_limit_share"] == 0.5
    assert fig["supply_air_below_min"] == 2.0  # 10 and 15 degC; no inflow is not cold
    assert fig["supply_air_in_min"] == 3.0 and fig["supply_air_coldest_c"] == 10.0
    assert fig["asymmetry_beyond_min"] == 2.0
    # Two-minute cycles count double; ``keep`` limits the count to some cycles.
    twice = dataclasses.replace(log, step_s=120.0)
    assert comfort_figures(twice, limits)["occupied_min"] == 8.0
    part = comfort_figures(log, limits, keep=np.array([True, True, True, False, False]))
    assert part["occupied_min"] == 2.0 and part["dgp_max"] == 0.5


def test_nobody_there_leaves_the_glare_figures_undefined_and_counts_nothing():
    log = ComfortLog.empty(60.0)
    for _ in range(3):
        log.append(False, None)
    fig = comfort_figures(log, Comfort())
    assert fig["occupied_min"] == 0.0 and fig["direct_sun_min"] == 0.0
    assert math.isnan(fig["dgp_p95"]) and math.isnan(fig["dgp_above_limit_share"])


def test_named_schedules():
    assert weekly_hours(occupancy_for("office-weekdays", None)) == 50.0
    assert weekly_hours(occupancy_for("office-every-day", None)) == 70.0
    assert occupancy_for("none", occupancy_for("office-weekdays", None)) is None
    panel = occupancy_for("office-weekdays", None)
    assert occupancy_for("panel", panel) is panel
    with pytest.raises(ValueError, match="office-weekdays"):
        occupancy_for("shifts", None)


def _run(suwon, rmis_raw, start_iso: str, command: Command):
    cfg = dataclasses.replace(suwon, occupancy=occupancy_for("office-weekdays", None))
    settings = ClosedLoopSettings(controller="fixed", fixed_command=command, seed=3,
                                  start_s=parse_iso_utc(start_iso), hours=20 / 60, options=FAST)
    return run_closed_loop(cfg, rmis_raw, settings)


@pytest.fixture(scope="module")
def monday(suwon, rmis_raw):
    """20 minutes from 07:50 local on a clear Monday: slats closed, and slats horizontal."""
    return {name: _run(suwon, rmis_raw, MONDAY_0750, cmd) for name, cmd in (
        ("closed", Command(90.0, 10, 100.0)), ("open", Command(0.0, 10, 100.0)))}


def test_an_office_morning_is_counted_from_eight_o_clock(monday):
    for result in monday.values():
        assert result.cycles == 20
        s = result.summary()["comfort"]
        assert s["occupied_min"] == 10.0  # 08:00-08:10 of the 07:50-08:10 window
        assert result.comfort.occupied == [False] * 10 + [True] * 10
        # measured only while occupied
        assert np.isnan(result.comfort.dgp[:10]).all()
        assert np.isfinite(result.comfort.dgp[10:]).all()
        # the dampers are shut: no air enters the room, so none is too cold
        assert np.isnan(result.comfort.supply_air_c).all() and s["supply_air_below_min"] == 0
        assert s["supply_air_in_min"] == 0 and math.isnan(s["supply_air_coldest_c"])


def test_closed_slats_keep_the_sun_out_and_open_ones_let_it_dazzle(monday):
    closed, open_ = (monday[k].summary()["comfort"] for k in ("closed", "open"))
    assert closed["direct_sun_min"] == 0.0 and closed["dgp_above_limit_share"] == 0.0
    # The low morning sun passes horizontal slats (profile angle below the cut-off).
    assert open_["direct_sun_min"] == 10.0 and open_["dgp_above_limit_share"] == 1.0
    assert open_["dgp_p50"] > closed["dgp_max"]


def test_a_weekday_office_is_empty_on_sunday(suwon, rmis_raw):
    s = _run(suwon, rmis_raw, SUNDAY_0750, Command(0.0, 10, 100.0)).summary()["comfort"]
    assert s["occupied_min"] == 0.0 and s["direct_sun_min"] == 0.0
    assert math.isnan(s["dgp_max"])
