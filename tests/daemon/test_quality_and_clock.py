"""Sensor quality checks and the cycle grid (pure parts of the daemon, no I/O)."""

from __future__ import annotations

import asyncio
import logging

import pytest

from dsfd.config.daemon import QualitySettings
from dsfd.daemon.clock import CycleGrid, SimulatedClock
from dsfd.daemon.quality import QualityChecker
from dsfd.drivers.base import Quality, Reading, Sample


def sample(t: float, **values: float) -> Sample:
    return Sample(t, {k: Reading.good(v, "io") for k, v in values.items()})


def test_range_rate_and_stuck_flags_carry_no_value_and_say_why() -> None:
    q = QualityChecker(QualitySettings(stuck_window=4, max_rate_k_per_min=10.0))
    r = q.check(sample(0.0, x1_c=20.0, x5_c=95.0, ghi_wm2=-50.0))
    assert r.flags == {"x5_c": "range", "ghi_wm2": "range"}
    assert r.sample.quality("x5_c") is Quality.OUT_OF_RANGE
    assert r.sample.good("x5_c") is None and r.original.good("x5_c") == 95.0
    assert "outside the plausible range -40..90" in r.sample.readings["x5_c"].detail
    # A 15 K jump of a pane within a minute is a spike; the cavity air may do that.
    r = q.check(sample(60.0, x1_c=35.0, x5_c=40.0))
    assert r.flags == {"x1_c": "rate"} and "rate of change 15.0 K/min" in (
        r.sample.readings["x1_c"].detail)
    r = q.check(sample(120.0, x1_c=35.1, x5_c=55.0))  # the new level is then accepted
    assert not r.flags
    for k in range(4):
        r = q.check(sample(180.0 + 60 * k, x1_c=36.0 + k, x5_c=30.0))
    assert r.flags == {"x5_c": "stuck"}  # four identical x5 readings
    assert r.sample.quality("x5_c") is Quality.STUCK


def test_stale_samples_and_driver_flags_are_reported_and_counted(
        caplog: pytest.LogCaptureFixture) -> None:
    r = QualityChecker(QualitySettings(max_sample_age_s=30.0)).check(
        sample(0.0, x1_c=20.0), age_s=45.0)
    assert r.flags == {"x1_c": "stale"} and "45 s old" in r.sample.readings["x1_c"].detail
    q = QualityChecker(QualitySettings())
    lost = Sample(60.0, {"x1_c": Reading.bad(Quality.TIMEOUT, "io", "io: no response")})
    caplog.clear()
    with caplog.at_level(logging.DEBUG, logger="dsfd.daemon.quality"):
        for k in range(3):
            r = q.check(Sample(60.0 + 60 * k, lost.readings))
        back = q.check(sample(300.0, x1_c=20.5))
    assert r.flags == {"x1_c": "timeout"}
    assert q.counts[("x1_c", "timeout")] == 3 and q.total_flags() == 3
    levels = [rec.levelname for rec in caplog.records if "x1_c" in rec.getMessage()]
    # First occurrence loudly, repeats quietly, recovery noted.
    assert levels == ["WARNING", "DEBUG", "DEBUG", "INFO"]
    assert back.recovered == ["x1_c"]


def test_grid_skips_overrun_slots_instead_of_running_back_to_back() -> None:
    grid = CycleGrid(period_s=60.0, t0_s=100.0)
    assert grid.after(0, 130.0).index == 1 and grid.after(0, 130.0).skipped == 0
    late = grid.after(0, 100.0 + 60.0 * 3.5)  # cycle 0 ran until slot 3.5
    assert (late.index, late.skipped, late.deadline_s) == (4, 3, 340.0)  # slots 1-3 missed


def test_simulated_clock_runs_as_fast_as_possible_on_the_grid() -> None:
    clock = SimulatedClock(start_utc_s=1_640_995_200.0)
    grid = CycleGrid(period_s=60.0, t0_s=clock.monotonic())

    async def days() -> float:
        slot = grid.after(-1, clock.monotonic())
        for _ in range(3 * 1440):
            await clock.sleep_until(slot.deadline_s)
            slot = grid.after(slot.index, clock.monotonic())
        return clock.wall()

    assert asyncio.run(days()) == 1_640_995_200.0 + (3 * 1440 - 1) * 60.0


def test_accelerated_clock_is_scaled_real_time() -> None:
    clock = SimulatedClock(start_utc_s=0.0, speed=600.0)

    async def one_cycle() -> float:
        await clock.sleep_until(60.0)  # one simulated minute = 0.1 s
        return clock.monotonic()

    assert asyncio.run(one_cycle()) >= 60.0
    with pytest.raises(ValueError, match="speed"):
        SimulatedClock(start_utc_s=0.0, speed=0.0)
