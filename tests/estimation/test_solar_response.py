"""The solar detector (dsfd.estimation.solar_response) on synthetic days whose truth is
known: offsets that remove a known share of the computed sun give that share back; a
façade that loses a share of its sun from a known day is found after that day and never
before, and named by which nodes lost it; a clean façade's wander is no finding."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.estimation.solar_response import (
    DIRT,
    DIRT_OR_LOUVER,
    DailySolarResponse,
    SolarSettings,
    solar_response,
    solar_response_change,
)

DAY = 86400.0
START = 19000 * DAY
MINUTES = 60.0 * np.arange(1440)


def _day(k: int, *, pane_loss: float, slat_loss: float, rng: np.random.Generator,
         noise_wm2: float = 5.0) -> tuple[np.ndarray, ...]:
    """Day ``k`` of one-minute steps: a clear winter day's absorbed sun (half a sine from
    07:30 to 16:30, 200 W/m² on the pane x1 and 420 on the slats x4 at noon, a few W/m² on
    the inner panes) and offsets that remove ``pane_loss`` / ``slat_loss`` of it, plus a
    constant per update (10 min) of ``noise_wm2`` (the offsets' own wander)."""
    t = START + k * DAY + MINUTES
    hour = MINUTES / 3600.0
    shape = np.clip(np.sin(np.pi * (hour - 7.5) / 9.0), 0.0, None)
    s = np.outer(shape, [200.0, 4.0, 3.0, 420.0])
    loss = np.array([pane_loss, slat_loss, slat_loss, slat_loss])
    update = np.arange(t.size) // 10
    q = -loss * s + rng.normal(0.0, noise_wm2, (update.max() + 1, 4))[update]
    return t, q, s, update + 1000 * k


def test_offsets_that_remove_a_share_of_the_sun_give_it_back():
    rng = np.random.default_rng(0)
    day = solar_response(*_day(0, pane_loss=0.1, slat_loss=0.1, rng=rng, noise_wm2=0.0))
    assert day is not None
    assert day.factor == pytest.approx(-0.1, abs=1e-12)
    assert day.node_factors[0] == pytest.approx(-0.1, abs=1e-12)
    assert day.node_factors[3] == pytest.approx(-0.1, abs=1e-12)
    # the steps are sunny from about 08:00 to 16:00 (the slats above 50 W/m²)
    assert 420 <= day.sunny_steps <= 520
    t, q, s, c = _day(0, pane_loss=0.1, slat_loss=0.1, rng=rng)
    noisy = solar_response(t, q, s, c)
    assert noisy is not None
    # the standard error counts updates, not steps: a constant noise σ per update of m = 10
    # steps is worth one observation per update, sd ≈ σ √m / sqrt(Σ (S − S̄)²) over the
    # sunny steps of every node (steps counted as independent would give 1/√m of it)
    sunny = s[:, 3] >= 50.0
    dev = s[sunny] - s[sunny].mean(axis=0)
    expected_sd = 5.0 * np.sqrt(10.0) / np.sqrt(np.sum(dev * dev))
    assert noisy.sd == pytest.approx(expected_sd, rel=0.5)
    assert noisy.factor == pytest.approx(-0.1, abs=4 * noisy.sd)


def test_a_held_offset_does_not_dilute_the_factor():
    """The exterior pane's offset held all day (the identifiability test) is left out: the
    factor is the slats', not pulled towards 0 by a node that could not follow the sun."""
    rng = np.random.default_rng(0)
    t, q, s, c = _day(0, pane_loss=0.1, slat_loss=0.1, rng=rng, noise_wm2=0.0)
    q[:, 0] = 17.0
    day = solar_response(t, q, s, c)
    assert day is not None and day.factor == pytest.approx(-0.1, abs=1e-12)
    assert np.isnan(day.node_factors[0])


def test_an_overcast_day_has_no_value():
    rng = np.random.default_rng(0)
    t, q, s, c = _day(0, pane_loss=0.0, slat_loss=0.0, rng=rng)
    assert solar_response(t, q, s * 0.1, c) is None  # slats never reach 50 W/m²


def _history(days: int, onset: int | None, *, per_day: float, pane: bool, seed: int = 1,
             wander: float = 0.02) -> list[DailySolarResponse]:
    """Daily factors with a clean wander of ``wander`` from day to day (the lumped model's
    solar form error changes with the sky) and, from day ``onset``, a loss growing by
    ``per_day`` a day on the slats (and the pane if ``pane``)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(days):
        lost = 0.0 if onset is None or k < onset else per_day * (k - onset + 1)
        form = rng.normal(-0.02, wander)
        day = solar_response(*_day(k, pane_loss=(lost if pane else 0.0) - form,
                                   slat_loss=lost - form, rng=rng))
        assert day is not None
        out.append(day)
    return out


def test_soiling_is_found_after_its_start_and_named():
    """10 % of the sun lost over a week from day 10 (the issue's size) on a façade whose
    clean days wander by 0.02: found after the onset, named as dirt (both nodes fell)."""
    history = _history(20, 10, per_day=0.1 / 7, pane=True)
    onset_s = START + 10 * DAY
    for upto in range(1, 10):
        assert solar_response_change(history[:upto]) is None, f"found before the onset ({upto})"
    found = solar_response_change(history)
    assert found is not None and found.kind == "solar_gain_shift"
    assert onset_s <= found.detected_s <= onset_s + 7 * DAY
    assert found.evidence[0].shift < -0.03
    assert "dirt on the exterior glass; clean it" in found.action
    assert found.subject == DIRT
    pane = {e.signal: e.shift for e in found.evidence}
    assert pane["solar_response:x1"] < -0.03 and pane["solar_response:x4"] < -0.03


def test_a_loss_on_the_slats_alone_names_both_causes():
    history = _history(20, 10, per_day=0.1 / 3, pane=False)
    found = solar_response_change(history)
    assert found is not None
    assert "slipped motor step" in found.action and "cannot tell these apart" in found.action
    assert found.subject == DIRT_OR_LOUVER


@pytest.mark.parametrize("seed", range(8))
def test_a_clean_facade_raises_nothing(seed):
    """Twenty clean days whose factor wanders by 0.03 from day to day."""
    assert solar_response_change(_history(20, None, per_day=0.0, pane=True, seed=seed,
                                          wander=0.03)) is None


def test_settings_need_the_wander_first():
    """Under ``days.min_wander`` days before the guard, no statistic: a short history is
    never a finding, whatever it holds."""
    history = _history(8, 0, per_day=0.05, pane=True)
    assert solar_response_change(history, settings=SolarSettings()) is None
