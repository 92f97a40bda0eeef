"""The daylight split of a heat-transfer coefficient's change (dsfd.estimation.daylight_split,
docs/model.md#daylight-split), on synthetic on-line estimates whose truth is known: a change
made in the sunlit windows alone is told as the sun's, one made day and night is not, and
a clean history is neither. Which windows are dark follows the sun at the site."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.estimation.daylight_split import (
    DaylightSplit,
    as_solar_finding,
    daylight_only,
    daylight_split,
    window_dark,
)
from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.solar_response import (
    DIRT_OR_LOUVER,
    LOUVER_OR_CLEANED,
    DailySolarResponse,
    factor_shift,
)

DAY = 86400.0
MIDNIGHT = 19723 * DAY  # 2024-01-01 00:00 UTC
SUWON = {"latitude_deg": 37.27, "longitude_deg": 127.0}  # local solar noon ≈ 03:32 UTC
WINDOW_S = 4 * 3600.0
SHIFT_DAY = 14


def test_a_window_is_dark_only_when_the_sun_was_down_at_both_of_its_ends():
    """Local solar midnight at Suwon is about 15:32 UTC: a 4-h window ending then is all
    night; one ending at noon, or one hour after sunset (its start in daylight), is not."""
    t = MIDNIGHT + np.array([15.5, 3.5, 9.6 + 1.0]) * 3600.0
    assert window_dark(t, WINDOW_S, **SUWON).tolist() == [True, False, False]
    # and in the middle of the night only once the window has left the evening behind
    hours = MIDNIGHT + 3600.0 * np.arange(0.0, 24.0, 0.25)
    dark = window_dark(hours, WINDOW_S, **SUWON)
    assert 0.30 < dark.mean() < 0.45  # a January night of ~14 h less the 4-h window


def _history(shift: float, *, where: str, seed: int = 0):
    """21 days of 10-min ln h estimates (sd 0.1) wandering by 0.5 sd a day, with ``shift``
    added from day 14 in the windows ``where`` ("lit", "all")."""
    rng = np.random.default_rng(seed)
    t = MIDNIGHT + 600.0 * np.arange(21 * 144)
    dark = window_dark(t, WINDOW_S, **SUWON)
    day = ((t - MIDNIGHT) // DAY).astype(int)
    v = math.log(4.0) + 0.05 * rng.standard_normal(21)[day] + 0.03 * rng.standard_normal(t.size)
    moved = (day >= SHIFT_DAY) & ((~dark) if where == "lit" else True)
    v = v + np.where(moved, shift, 0.0)
    return t, v, np.full(t.size, 0.1), dark


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_change_in_the_sunlit_windows_alone_is_the_suns(seed):
    """h ×2 in the windows that saw the sun (what the soiled bench façade's h_ca4 did), the
    dark windows unchanged: the sunlit half moved by ln 2, the dark half stays within the
    allowance, and the split says daylight only."""
    t, v, sd, dark = _history(math.log(2.0), where="lit", seed=seed)
    since = MIDNIGHT + SHIFT_DAY * DAY
    split = daylight_split(t, v, sd, dark, since_s=since, end_s=MIDNIGHT + 17 * DAY)
    assert split.lit_shift == pytest.approx(math.log(2.0), abs=0.15)
    assert abs(split.dark_shift) < 0.1
    assert daylight_only(split, side=+1, k_sd=1.5)
    assert not daylight_only(split, side=-1, k_sd=1.5)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_change_by_day_and_by_night_is_not_the_suns(seed):
    """A failed seal lets the gas out for good: h ×2 in every window moves both halves."""
    t, v, sd, dark = _history(math.log(2.0), where="all", seed=seed)
    split = daylight_split(t, v, sd, dark, since_s=MIDNIGHT + SHIFT_DAY * DAY,
                           end_s=MIDNIGHT + 17 * DAY)
    assert split.dark_shift == pytest.approx(math.log(2.0), abs=0.15)
    assert split.dark_z > 1.5
    assert not daylight_only(split, side=+1, k_sd=1.5)


def test_a_clean_history_is_neither_and_a_half_without_days_is_not_judged():
    t, v, sd, dark = _history(0.0, where="all")
    split = daylight_split(t, v, sd, dark, since_s=MIDNIGHT + SHIFT_DAY * DAY,
                           end_s=MIDNIGHT + 17 * DAY)
    assert not daylight_only(split, side=+1, k_sd=1.5)
    assert not daylight_only(split, side=-1, k_sd=1.5)
    # no dark estimate at all (a store without nights): nothing to tell by
    none = daylight_split(t, v, sd, np.zeros(t.size, bool), since_s=MIDNIGHT + SHIFT_DAY * DAY,
                          end_s=MIDNIGHT + 17 * DAY)
    assert math.isnan(none.dark_z) and not daylight_only(none, side=+1, k_sd=1.5)


def _finding() -> Finding:
    head = Evidence(signal="parameter:h_ca4", shift=0.5, shift_sd=4.0, unit="log",
                    since_s=MIDNIGHT, statistic=6.0, threshold=5.0)
    return Finding(kind="parameter_shift", confidence=0.6, start_s=MIDNIGHT,
                   detected_s=MIDNIGHT + DAY, evidence=(head,), action="a failed seal")


@pytest.mark.parametrize(("b_shift", "subject", "words"),
                         [(-0.04, DIRT_OR_LOUVER, "less of the sun"),
                          (+0.04, LOUVER_OR_CLEANED, "more of the sun")])
def test_the_told_finding_keeps_its_evidence_and_takes_its_direction_from_the_daily_factor(
        b_shift, subject, words):
    split = DaylightSplit(dark_z=0.2, lit_z=4.0, dark_shift=0.02, lit_shift=math.log(2.0))
    f = as_solar_finding(_finding(), split, factor_shift=b_shift)
    assert (f.kind, f.subject) == ("solar_gain_shift", subject)
    assert [e.signal for e in f.evidence] == ["parameter:h_ca4", "parameter:h_ca4:dark",
                                             "parameter:h_ca4:sunlit", "solar_response"]
    assert f.evidence[-1].shift == b_shift  # what its energy at stake is costed from
    assert f.start_s == MIDNIGHT and f.confidence == 0.6
    assert "×2.00 in the hours with sun and ×1.02 at night" in f.action and words in f.action


def test_the_daily_factors_shift_is_after_the_start_against_the_reference_before_the_guard():
    days = [DailySolarResponse(time_s=MIDNIGHT + (d + 0.5) * DAY, factor=b, sd=0.01,
                               node_factors=(b,) * 4, sunny_steps=400)
            for d, b in enumerate([-0.03, -0.03, -0.03, -0.03, -0.03, 0.5, 0.5, -0.07, -0.09])]
    # days 7 and 8 from the start; the reference is days 0-4 (the two before are the guard)
    assert factor_shift(days, since_s=MIDNIGHT + 7 * DAY) == pytest.approx(-0.05)
    assert factor_shift(days, since_s=MIDNIGHT + 10 * DAY) is None
    assert factor_shift(days[7:], since_s=MIDNIGHT + 7 * DAY) is None
