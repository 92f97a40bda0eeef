"""The parameter detector's daily series and what its findings say (dsfd.estimation.
parameter_watch): a day's daily cycle averages out, a day of correlated estimates counts as
one estimate's worth of evidence (copies do not shrink its sd), days with too little of them
are left out; every θ parameter has a meaning in each direction, and the two parameters of
the air path agree on what more resistance is."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.estimation.parameter_watch import (
    DAY_MIN_SPAN_S,
    LOG_UNIT,
    OFFSET_UNIT,
    PARAMETER_MEANING,
    daily_estimates,
    day_start_s,
    parameter_action,
)
from dsfd.estimation.params import OFFSET_NAMES

DAY = 86400.0
MIDNIGHT = 19675 * DAY
HOURS = MIDNIGHT + 3600.0 * np.arange(24)


def test_a_days_cycle_averages_out_and_its_time_is_its_last_estimate():
    """Hourly estimates 1.0 + 0.3 sin(2πt/day) with equal sds: a whole period of a sinusoid
    has mean zero, so the day's value is its level."""
    t = np.concatenate([HOURS, HOURS + DAY])
    v = np.concatenate([np.full(24, 1.0), np.full(24, 1.5)]) + 0.3 * np.sin(2 * np.pi * t / DAY)
    days, mean, sd = daily_estimates(t, v, np.full(t.size, 0.1))
    assert days.tolist() == [HOURS[-1], HOURS[-1] + DAY]
    assert mean == pytest.approx([1.0, 1.5], abs=1e-12)
    assert sd == pytest.approx([0.1, 0.1])


def test_copies_of_an_estimate_are_one_estimates_worth():
    """Consecutive on-line estimates are nearly one piece of evidence: each estimate of a
    day repeated ten times leaves the day's value and its sd as they were (a σ/√n sd would
    shrink by √10)."""
    rng = np.random.default_rng(1)
    v, sd = rng.normal(0.0, 0.1, 24), rng.uniform(0.05, 0.2, 24)
    once = daily_estimates(HOURS, v, sd)
    tenfold = daily_estimates(np.repeat(HOURS, 10), np.repeat(v, 10), np.repeat(sd, 10))
    for a, b in zip(once, tenfold, strict=True):
        assert a == pytest.approx(b, rel=1e-12)
    # an estimate 100 times less certain hardly moves the day's value
    lone = daily_estimates(HOURS, np.where(np.arange(24) == 5, 10.0, 0.0),
                           np.where(np.arange(24) == 5, 10.0, 0.1))[1]
    assert abs(lone[0]) < 1e-3  # the unweighted mean would be 10/24


def test_short_days_and_estimates_without_an_sd_are_left_out():
    # the first day from noon (the daemon started then), a day cut at 17:00, a whole day
    t = np.concatenate([HOURS[12:], HOURS[:18] + DAY, HOURS + 2 * DAY])
    v = np.zeros(t.size)
    days = daily_estimates(t, v, np.full(t.size, 0.1))[0]
    assert DAY_MIN_SPAN_S == 18 * 3600.0 and days.tolist() == [HOURS[-1] + 2 * DAY]
    # rows without an sd (written before schema 8: NULL, read as NaN) make no day
    sd = np.where(t < MIDNIGHT + 2 * DAY, 0.1, np.nan)
    assert daily_estimates(t, v, sd)[0].size == 0


def test_every_parameter_has_a_meaning_in_each_direction():
    assert set(PARAMETER_MEANING) == set(PARAMETER_NAMES) | set(OFFSET_NAMES)
    for name in OFFSET_NAMES:  # a heat-flux offset: told in W/m2, its sensor first
        up = parameter_action(name, side=1, shift=17.0, shift_sd=8.0, unit=OFFSET_UNIT)
        assert up.startswith(f"{name} has risen by 17 W/m2 (8.0 sd of its daily spread): ")
        assert f"first check its sensor x{name[-1]}" in up
    for name in PARAMETER_NAMES:
        up = parameter_action(name, side=1, shift=0.7, shift_sd=4.0, unit=LOG_UNIT)
        down = parameter_action(name, side=-1, shift=-0.7, shift_sd=-4.0, unit=LOG_UNIT)
        assert up.startswith(f"{name} has risen ×2.01 (4.0 sd of its daily spread): ")
        assert down.startswith(f"{name} has fallen ×0.50 (4.0 sd of its daily spread): ")
        assert up != down
    assert parameter_action("n", side=1, shift=0.08, shift_sd=3.0).startswith(
        "n has risen by 0.08 (3.0 sd of its daily spread)")


def test_the_air_path_parameters_agree_on_what_more_resistance_is():
    """f is a loss (more resistance: f up), c a conductance (more resistance: c down): a
    clogged screen is f risen and c fallen, a damper stuck open f fallen and c risen."""
    def cause(name: str, side: int) -> str:
        return PARAMETER_MEANING[name][side].split(": ", 1)[1]

    assert cause("f", +1) == cause("c", -1) and "clean the insect screens" in cause("f", +1)
    assert cause("f", -1) == cause("c", +1) and "stuck open" in cause("f", -1)


def test_causes_the_evidence_cannot_separate_are_named_together():
    assert "weather, not a fault" in PARAMETER_MEANING["h_out"][1]
    assert "anemometer" in PARAMETER_MEANING["f"][1]  # a reading low looks like a clog
    assert "cannot tell" in PARAMETER_MEANING["h_ca1"][-1]
    # less sun absorbed in a dirty exterior pane reads as more cooling, never as less
    for name in ("h_out", "h_ca1"):
        assert "dirt" in PARAMETER_MEANING[name][1] and "dirt" not in PARAMETER_MEANING[name][-1]
    assert "dirt" not in PARAMETER_MEANING["h_ca3"][1]
    assert "x4" in PARAMETER_MEANING["h_ca2"][1]
    # an unknown parameter still gets an action, naming it
    assert parameter_action("h_x9", side=1, shift=5.0, shift_sd=3.0, unit="W/m2").startswith(
        "the calibrated h_x9 has risen by 5 W/m2")


def test_days_can_be_the_24_h_that_end_at_a_given_time():
    """end_s: the days are [end − k d, end − (k−1) d); a level that steps at 15:00 on the
    second day is one whole day of each level in the days ending at 15:00 of the third,
    where the UTC days mix them."""
    t = MIDNIGHT + 3600.0 * np.arange(3 * 24)
    step = MIDNIGHT + DAY + 15 * 3600.0
    v = np.where(t >= step, 1.0, 0.0)
    sd = np.full(t.size, 0.1)
    days, mean, _ = daily_estimates(t, v, sd, end_s=step + DAY)
    assert mean.tolist() == [0.0, 1.0] and days.tolist() == [step - 3600.0, step + DAY - 3600.0]
    assert daily_estimates(t, v, sd)[1] == pytest.approx([0.0, 9 / 24, 1.0])
    assert day_start_s(step + 10.0, end_s=step + DAY) == step
    assert day_start_s(step - 10.0, end_s=step + DAY) == step - DAY
    assert day_start_s(step - 10.0) == MIDNIGHT + DAY
