"""Actuators: validation (never clip), louver rate limit, damper lag, OR quantisation."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from dsfd.sim.plant.actuators import (
    Actuators,
    Command,
    CommandError,
    damper_mask,
    validate_command,
)
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.plant import Plant
from tests.sim.conftest import HOUR, day_start


@pytest.mark.parametrize("bad", [
    {"phi_deg": 10.0, "afr": 1, "or_pct": 50.0},     # off the 18° grid
    {"phi_deg": 108.0, "afr": 1, "or_pct": 50.0},    # outside −90…90
    {"phi_deg": -91.0, "afr": 1, "or_pct": 50.0},
    {"phi_deg": math.nan, "afr": 1, "or_pct": 50.0},
    {"phi_deg": 0.0, "afr": 0, "or_pct": 50.0},      # regime outside 1..10
    {"phi_deg": 0.0, "afr": 11, "or_pct": 50.0},
    {"phi_deg": 0.0, "afr": 2.5, "or_pct": 50.0},
    {"phi_deg": 0.0, "afr": 1, "or_pct": 100.5},     # OR outside 0..100
    {"phi_deg": 0.0, "afr": 1, "or_pct": -1.0},
    {"phi_deg": 0.0, "afr": 1, "or_pct": math.inf},
    {"phi_deg": 0.0, "afr": 1},                      # missing field
    {"phi_deg": "up", "afr": 1, "or_pct": 5.0},      # not a number
])
def test_out_of_range_commands_raise(suwon, bad):
    with pytest.raises(CommandError):
        validate_command(suwon, bad)
    assert issubclass(CommandError, ValueError)  # the daemon catches ValueError


def test_regime_without_its_dampers_is_rejected(suwon):
    ops = dataclasses.replace(suwon.openings, exterior_top=None)
    cfg = dataclasses.replace(suwon, openings=ops)
    for afr in (3, 4, 5, 8, 9):  # need ET
        with pytest.raises(CommandError, match="dampers"):
            validate_command(cfg, Command(0.0, afr, 100.0))
    validate_command(cfg, Command(0.0, 1, 100.0))  # IB + IT still fine


def test_valid_commands_are_quantised_not_clipped(suwon):
    cmd = validate_command(suwon, {"phi_deg": -54.0, "afr": 6.0, "or_pct": 37.4})
    assert cmd == Command(-54.0, 6, 37.0)
    assert isinstance(cmd.afr, int)
    assert validate_command(suwon, Command(90.0, 10, 0.0)).or_pct == 0.0
    assert validate_command(suwon, Command(0.0, 1, 99.6)).or_pct == 100.0
    assert validate_command(suwon, Command(0.0, 1, 37.4), or_quantum_pct=None).or_pct == 37.4


def test_plant_rejects_bad_commands_and_keeps_the_last_good_one(suwon, rmis):
    plant = Plant(suwon, PlantOptions(n_segments=2), seed=0, weather_series=rmis)
    plant.reset(day_start(rmis, 1), command=Command(18.0, 1, 100.0))
    with pytest.raises(CommandError):
        plant.apply({"phi_deg": 17.0, "afr": 1, "or_pct": 100.0})
    assert plant.command == Command(18.0, 1, 100.0)


def test_louver_moves_at_its_rate():
    act = Actuators.for_options(ideal=False, rate_degs=3.0, rise_time_s=15.0)
    act.reset(0.0, np.zeros(4), t=100.0)
    act.command(100.0, 54.0, np.zeros(4))
    assert act.louver_arrival_s() == pytest.approx(118.0)  # |Δφ|/rate = 18 s
    assert act.phi_at(109.0) == pytest.approx(27.0)
    assert act.phi_at(117.9) < 54.0
    assert act.phi_at(118.0) == 54.0
    # A new command mid-way starts from where the louver is.
    act.command(106.0, -18.0, np.zeros(4))
    assert act.phi_at(106.0) == pytest.approx(18.0)
    assert act.louver_arrival_s() == pytest.approx(106.0 + 36.0 / 3.0)


def test_damper_first_order_lag_has_a_15_s_rise_time():
    act = Actuators.for_options(ideal=False, rate_degs=3.0, rise_time_s=15.0)
    act.reset(0.0, damper_mask(10) * 1.0, t=0.0)
    act.command(0.0, 0.0, damper_mask(1) * 1.0)  # open IB, IT
    tau = act.tau_s
    t10, t90 = -tau * math.log(0.9), -tau * math.log(0.1)
    assert t90 - t10 == pytest.approx(15.0)
    y = act.dampers_at(t10)
    assert y[2] == pytest.approx(0.1) and y[0] == 0.0
    assert act.dampers_at(t90)[3] == pytest.approx(0.9)
    assert not act.dampers_settled(60.0) and act.dampers_settled(120.0)


def test_ideal_actuators_follow_instantly():
    act = Actuators.for_options(ideal=True, rate_degs=3.0, rise_time_s=15.0)
    act.reset(0.0, np.zeros(4), t=0.0)
    act.command(5.0, 90.0, damper_mask(3) * 0.5)
    assert act.phi_at(5.0) == 90.0
    np.testing.assert_array_equal(act.dampers_at(5.0), [0.5, 0.5, 0.0, 0.0])


def test_plant_louver_and_dampers_take_time(suwon, rmis):
    plant = Plant(suwon, PlantOptions(n_segments=2), seed=0, weather_series=rmis)
    plant.reset(day_start(rmis, 1) + 10 * HOUR, command=Command(0.0, 10, 100.0))
    plant.apply(Command(72.0, 1, 100.0))
    plant.advance(12.0)
    st = plant.true_state()
    assert st.phi_deg == pytest.approx(36.0)  # 12 s at 3 °/s
    assert 0.5 < st.dampers[2] < 0.9  # IB opening, not yet open
    plant.advance(12.0)
    st = plant.true_state()
    assert st.phi_deg == 72.0  # arrived after 24 s
    plant.advance(96.0)
    assert plant.true_state().dampers[2] > 0.999
    assert plant.true_state().label in (1, 2)
