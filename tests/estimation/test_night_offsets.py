"""The night offsets (dsfd.estimation.night_offsets, docs/model.md#diagnostics-night-offsets)
on synthetic offset histories whose change point is known.

Twelve days of 10-min estimates of the inner pane's heat-flux offset q_x3: at night a level
that wanders by ±0.5 W/m² from night to night plus correlated noise of 0.4 W/m² (the clean
bench nights held within ±0.8 W/m²); by day swings of up to ±20 W/m² that change from day to
day (the lumped model's solar form error, which the offsets take up). A thermocouple drifting
by 0.5 K a day moves q_x3 by about 8 W/m² a day: the bench's 1 K step moved it by 15–18,
the inner pane's conductance to the room and the unit's gap.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.estimation.diagnostics import residual_blocks
from dsfd.estimation.night_offsets import (
    NIGHT_OFFSET_NAMES,
    NIGHT_OFFSET_SETTINGS,
    night_offset_change,
)
from dsfd.storage.evidence import NIGHT_OFFSET_REFERENCE_S, NIGHT_OFFSET_WINDOW_S

DAY = 86400.0
STEP = 600.0
T0 = 19675 * DAY  # a UTC midnight
N_DAYS = 12
#: Night in the synthetic site's UTC hours: 11:00 to 21:00 (Suwon's winter nights, local
#: 20:00 to 06:00).
NIGHT_UTC_H = (11.0, 21.0)
#: A thermocouple drifting 0.5 K a day on the inner pane [W/m² per day].
DRIFT_WM2_PER_DAY = 8.0


def _history(seed: int, *, drift_from: float | None = None, day_step_from: float | None = None,
             night_level_wm2: float = 0.5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = T0 + STEP * np.arange(int(N_DAYS * DAY / STEP))
    hour = (t % DAY) / 3600.0
    night = (hour >= NIGHT_UTC_H[0]) & (hour < NIGHT_UTC_H[1])
    day = ((t - T0) // DAY).astype(int)
    ar = np.zeros(t.size)
    for i in range(1, t.size):
        ar[i] = 0.9 * ar[i - 1] + rng.normal(0.0, 0.4 * np.sqrt(1 - 0.81))
    level = rng.uniform(-night_level_wm2, night_level_wm2, N_DAYS + 1)[day]
    sun = np.clip(np.sin(np.pi * ((hour - 23.0) % 24.0) / 10.0), 0.0, None) * ~night
    swing = rng.uniform(-20.0, 20.0, N_DAYS + 1)[day] * sun
    q = level + ar + swing
    if drift_from is not None:
        q += np.clip(t - drift_from, 0.0, None) / DAY * DRIFT_WM2_PER_DAY
    if day_step_from is not None:
        q += np.where((t >= day_step_from) & ~night, 20.0, 0.0)
    return t, q, night


@pytest.mark.parametrize("seed", range(6))
def test_clean_nights_and_sunny_days_that_swing_give_no_finding(seed):
    t, q, night = _history(seed)
    assert night_offset_change(t, q, night, name="q_x3") is None
    # the same history judged day and night would see the sun's swings
    assert night_offset_change(t, q, np.ones(t.size, bool), name="q_x3") is not None


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("onset_h", [12.5, 21.5])  # early in a night / as a night ends
def test_a_drifting_thermocouple_is_found_after_it_began_and_within_about_a_day(seed,
                                                                              onset_h):
    """0.5 K a day: found after the onset (never before it) and named as the inner pane's
    sensor x3 reading warmer. Begun as a night ends, it waits for the next night, where 14 h
    on it reads ~0.3 K off: found within 20 h (17.5-19.5 h on 8 seeds). Begun early in a
    night, that night's ramp (at most 2.8 W/m²) stays within the allowance, and the next
    night finds it in its first hours: 25.5-28.5 h on 8 seeds, beyond the issue's day (the
    diagnostics bench's drift, begun at 00:33 local, was named after 22.0 h)."""
    onset = T0 + 8 * DAY + onset_h * 3600.0
    t, q, night = _history(seed, drift_from=onset)
    before = t < onset
    assert night_offset_change(t[before], q[before], night[before], name="q_x3") is None
    f = night_offset_change(t, q, night, name="q_x3")
    assert f is not None and f.kind == "night_offset_shift"
    assert onset < f.detected_s <= onset + (20 * 3600.0 if onset_h > 20 else DAY + 5 * 3600.0)
    assert f.start_s >= onset - 3600.0  # Page's change time: the drift's first hour or later
    (ev,) = f.evidence
    assert ev.signal == "night:q_x3" and ev.unit == "W/m2" and ev.shift > 0
    assert "inner (room-side) pane reads warmer" in f.action and "sensor x3" in f.action


@pytest.mark.parametrize("seed", range(4))
def test_a_change_of_the_daytime_offsets_alone_is_no_night_finding(seed):
    """Soiling or a new blind changes what the sun does: the day's offsets move, the
    night's do not, and the night offsets judge only the night."""
    t, q, night = _history(seed, day_step_from=T0 + 8.3 * DAY)
    assert night_offset_change(t, q, night, name="q_x3") is None


def test_the_louver_and_a_falling_offset_are_named_with_their_node():
    onset = T0 + 8 * DAY + 12 * 3600.0
    t, q, night = _history(1, drift_from=onset)
    f = night_offset_change(t, -q, night, name="q_x4")
    assert f is not None and f.evidence[0].shift < 0
    assert f.action.startswith("at night the louver reads cooler") and "sensor x4" in f.action
    assert "q_x1" not in NIGHT_OFFSET_NAMES  # the sky's cloud cover moves it at night


@pytest.mark.parametrize("seed", range(3))
def test_checks_on_a_moving_window_find_a_change_when_it_is_new(seed):
    """The daemon judges the last 7 days every hour and reads the 6 before as references
    only: each judged block keeps its reference from check to check, so the first check
    that finds the change finds it in the newest hour (not back in days that earlier checks
    judged without it), and no check finds anything before the onset."""
    onset = T0 + 8 * DAY + 21.5 * 3600.0
    t, q, night = _history(seed, drift_from=onset)
    week, refs = 7 * DAY, 6 * DAY
    first = None
    for now in np.arange(T0 + 4 * DAY, t[-1], 3600.0):
        w = (t >= now - week - refs) & (t <= now)
        f = night_offset_change(t[w], q[w], night[w], name="q_x3", judge_from_s=now - week)
        if f is not None:
            first = (now, f)
            break
    assert first is not None
    now, f = first
    assert onset < now - 3600.0 < f.detected_s <= now


def test_each_judged_block_keeps_its_reference_from_one_check_to_the_next():
    """What makes the property above hold on any history (on the diagnostics bench's drift
    the window alone opened a finding on q_x2 dated two days before the onset): with the
    daemon's reading of 6 days of references before its 7-day window, the standardised
    value of every block judged at one check is the same at the next check an hour later.
    Without them, the blocks near the window's start lose reference days as it moves."""
    t, q, night = _history(3)
    v = np.where(night, q, np.nan)

    def z_by_block(now: float, refs: float) -> dict[int, float]:
        w = (t >= now - NIGHT_OFFSET_WINDOW_S - refs) & (t <= now)
        b = residual_blocks(t[w], v[w], settings=NIGHT_OFFSET_SETTINGS)
        judged = b.blocks * NIGHT_OFFSET_SETTINGS.block_s >= now - NIGHT_OFFSET_WINDOW_S
        return dict(zip(b.blocks[judged].tolist(), b.z[judged].tolist(), strict=True))

    now = T0 + 11.5 * DAY
    for refs, same in ((NIGHT_OFFSET_REFERENCE_S, True), (0.0, False)):
        before, after = z_by_block(now, refs), z_by_block(now + 3600.0, refs)
        # the block the earlier check was in has grown since: not the same block
        common = [k for k in before if k in after and np.isfinite(before[k])
                  and (k + 1) * NIGHT_OFFSET_SETTINGS.block_s <= now]
        assert len(common) > 15
        assert all(before[k] == after[k] for k in common) is same


@pytest.mark.parametrize("seed", range(6))
def test_nights_whose_level_wanders_widely_raise_the_allowance_not_a_finding(seed):
    """On the real Aalborg week the offsets at night moved by up to 20 W/m² from one night
    to the next. Nights whose level wanders uniformly within ±12 W/m²: no finding, because
    the allowance follows the recent nights' departures; on the same history with quiet
    nights (±0.5 W/m²) the allowance is the 2 W/m² floor and a 15 W/m² step (a sensor 1 K
    off) is found in its first night."""
    t, q, night = _history(seed, night_level_wm2=12.0)
    assert night_offset_change(t, q, night, name="q_x2") is None
    onset = T0 + 8 * DAY + 12.5 * 3600.0
    t, q, night = _history(seed)
    q = q + np.where(t >= onset, 15.0, 0.0)
    f = night_offset_change(t, q, night, name="q_x3")
    assert f is not None and onset < f.detected_s <= onset + 8 * 3600.0


@pytest.mark.parametrize(("seed", "step_wm2"), [(0, 2.5), (1, 3.0), (3, 3.0)])
def test_a_held_departure_below_the_smallest_change_is_no_finding(seed, step_wm2):
    """A night level that moves by 2.5-3 W/m² and stays there (about 0.2 K on the inner
    pane) exceeds the 2 W/m² allowance: on these histories the CUSUM alone crosses its
    threshold within 30 h, on a mean departure of 3.3-3.6 W/m². That is below the smallest
    change worth a finding (4 W/m²), so with ``alarm_min_shift`` it is never one (the real
    Aalborg week's q_x3 under the identifiability test, docs/model.md#diagnostics-night-offsets)."""
    onset = T0 + 7 * DAY + 12.5 * 3600.0
    t, q, night = _history(seed)
    q = q + np.where(t >= onset, step_wm2, 0.0)
    statistic_alone = dataclasses.replace(NIGHT_OFFSET_SETTINGS, alarm_min_shift=False)
    f = night_offset_change(t, q, night, name="q_x3", settings=statistic_alone)
    assert f is not None and f.evidence[0].shift < NIGHT_OFFSET_SETTINGS.min_shift == 4.0
    assert night_offset_change(t, q, night, name="q_x3") is None


@pytest.mark.parametrize("seed", range(4))
def test_a_held_departure_above_the_smallest_change_is_found_in_its_first_night(seed):
    onset = T0 + 7 * DAY + 12.5 * 3600.0
    t, q, night = _history(seed)
    f = night_offset_change(t, q + np.where(t >= onset, 6.0, 0.0), night, name="q_x3")
    assert f is not None and onset < f.detected_s <= onset + 6 * 3600.0
    assert f.evidence[0].shift >= NIGHT_OFFSET_SETTINGS.min_shift
