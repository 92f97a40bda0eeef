"""Change detectors (docs/model.md#diagnostics) on synthetic series with a known change point:
found after it and never before; nothing on stationary noise (fixed seeds); a parameter
wandering within its posterior sd is not a finding."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.estimation.diagnostics import (
    ResidualSettings,
    block_labels,
    block_means,
    page_cusum,
    residual_change,
    residual_settings,
)
from dsfd.estimation.parameter_shift import (
    ParameterSettings,
    between_day_variance,
    parameter_change,
)

DAY = 86400.0
T0 = 1_640_995_200.0  # 2022-01-01T00:00Z, a whole number of blocks


def _residual_noise(seed: int, days: float, *, sigma: float = 0.3, rho: float = 0.9,
                    daily_k: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    """One-minute residuals of a model that is fine but not perfect: AR(1) noise (ρ per
    minute, stationary sd ``sigma``) plus a daily error cycle of amplitude ``daily_k`` whose
    size changes from day to day (sunny and overcast days)."""
    rng = np.random.default_rng(seed)
    n = int(days * 1440)
    t = T0 + 60.0 * np.arange(n)
    e = rng.standard_normal(n) * sigma * np.sqrt(1 - rho**2)
    r = np.empty(n)
    r[0] = rng.standard_normal() * sigma
    for i in range(1, n):
        r[i] = rho * r[i - 1] + e[i]
    day_size = rng.uniform(0.2, 1.0, size=int(np.ceil(days)) + 1)
    hour = (t - T0) / 3600.0 % 24.0
    sun = np.clip(np.sin(np.pi * (hour - 7.0) / 10.0), 0.0, None)
    r += daily_k * day_size[((t - T0) // DAY).astype(int)] * sun
    return t, r


def test_page_cusum_on_a_hand_made_series():
    # by hand: S+ = 0, 0, 0.5, 1.5, 3.0 > h = 2.5 at index 4; last zero at index 1
    cs = page_cusum(np.array([0.0, -1.0, 1.5, 2.0, 2.5]), k=1.0, h=2.5)
    assert (cs.alarm, cs.side, cs.start) == (4, 1, 2)
    np.testing.assert_allclose(cs.statistic, [0.0, 0.0, 0.5, 1.5, 3.0])
    down = page_cusum(np.array([np.nan, -3.0, np.nan, -3.0]), k=1.0, h=3.5)
    assert (down.alarm, down.side, down.start) == (3, -1, 1)
    assert page_cusum(np.full(1000, 0.99), k=1.0, h=0.1).alarm is None


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("size_k", [1.0, -1.0])
def test_a_residual_step_is_found_after_it_and_never_before(seed, size_k):
    """A thermocouple step of ±1 K on day 4 of residuals with σ = 0.3 K."""
    t, r = _residual_noise(seed, 6.0)
    change_s = T0 + 4.2 * DAY
    r = r + np.where(t >= change_s, size_k, 0.0)
    f = residual_change(t, r, signal="x3_c", unit="K")
    assert f is not None and f.kind == "residual_shift"
    assert change_s <= f.detected_s <= change_s + 0.25 * DAY
    assert abs(f.start_s - change_s) <= 3600.0  # within six 10-min blocks
    ev, = f.evidence
    assert ev.signal == "residual:x3_c" and ev.unit == "K"
    assert np.sign(ev.shift) == np.sign(size_k)
    assert abs(ev.shift - size_k) < 0.5 * abs(size_k)
    assert 0.5 <= f.confidence <= 1.0
    # the series up to the change alone holds nothing
    assert residual_change(t[t < change_s], r[t < change_s], signal="x3_c", unit="K") is None


def _daily_controls(t: np.ndarray) -> np.ndarray:
    """The regime in force: 1 at night, 7 from 07:00 to 17:00, the same every day."""
    hour = (t - T0) / 3600.0 % 24.0
    return np.where((hour >= 7.0) & (hour < 17.0), 7.0, 1.0)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_control_first_used_at_an_hour_is_judged_against_its_own_kind_only(seed):
    """Day 5, 08:00-11:00: a regime never used at that hour, under which the lumped model is
    1.5 K off (its form error, not a change of the façade). Against the same hour's blocks
    of the usual regime it is a finding; against blocks of its own regime (none) it is not."""
    t, r = _residual_noise(seed, 6.0)
    control = _daily_controls(t)
    hour = (t - T0) / 3600.0 % 24.0
    new = (t >= T0 + 5 * DAY) & (t < T0 + 6 * DAY) & (hour >= 8.0) & (hour < 11.0)
    control[new] = 2.0
    r = r + np.where(new, 1.5, 0.0)
    assert residual_change(t, r, signal="x4_c", unit="K") is not None
    assert residual_change(t, r, signal="x4_c", unit="K", control=control) is None


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_residual_step_under_the_usual_controls_is_found_with_control_labels(seed):
    t, r = _residual_noise(seed, 6.0)
    change_s = T0 + 4.2 * DAY
    r = r + np.where(t >= change_s, 1.0, 0.0)
    f = residual_change(t, r, signal="x3_c", unit="K", control=_daily_controls(t))
    assert f is not None and change_s <= f.detected_s <= change_s + 0.25 * DAY
    assert residual_change(t[t < change_s], r[t < change_s], signal="x3_c", unit="K",
                           control=_daily_controls(t[t < change_s])) is None


def test_block_labels_take_the_control_held_by_most_of_a_block():
    t = T0 + 60.0 * np.arange(40)  # four 10-min blocks
    r = np.zeros(40)
    labels = np.array([1.0] * 10 + [2.0] * 4 + [7.0] * 6 + [np.nan] * 10 + [np.nan] * 3
                      + [2.0] * 7)
    blocks, _ = block_means(t, r, block_s=600.0, min_samples=3)
    got = block_labels(t, r, labels, blocks, block_s=600.0)
    np.testing.assert_array_equal(got[[0, 1, 3]], [1.0, 7.0, 2.0])
    assert np.isnan(got[2])  # no known control: compared with any block


def test_residuals_without_a_known_control_are_judged_as_without_labels():
    t, r = _residual_noise(1, 6.0)
    r = r + np.where(t >= T0 + 4.2 * DAY, 1.0, 0.0)
    plain = residual_change(t, r, signal="x3_c", unit="K")
    unknown = residual_change(t, r, signal="x3_c", unit="K", control=np.full(t.size, np.nan))
    assert plain is not None and unknown == plain


def test_a_residual_drift_is_found_after_it_starts():
    """A drift of 0.5 K/day from day 3 (on residuals of 0.3 K sd, found within two days)."""
    t, r = _residual_noise(7, 6.0)
    start = T0 + 3.0 * DAY
    r = r + np.clip((t - start) / DAY, 0.0, None) * 0.5
    f = residual_change(t, r, signal="x1_c", unit="K")
    assert f is not None
    assert start < f.detected_s <= start + 2.0 * DAY
    assert f.evidence[0].shift > 0


@pytest.mark.parametrize("seed", range(5))
def test_no_finding_on_thirty_days_of_stationary_residuals(seed):
    t, r = _residual_noise(100 + seed, 30.0)
    r[np.random.default_rng(seed).uniform(size=r.size) < 0.02] = np.nan  # missing samples
    assert residual_change(t, r, signal="x2_c", unit="K") is None


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_day_whose_errors_sit_a_few_tenths_off_is_no_finding_for_a_temperature(seed):
    """A calibrated model's errors on a different kind of day sit 0.1-0.34 K off the days
    before (the bench's clean winter days) while their spread is 0.05-0.08 K: in spreads
    alone that is a change. With the temperature settings (allowance at least 0.4 K) it is
    not, while a 1 K thermocouple step still is within hours, and a 0.5 K/day drift within
    about a day."""
    t, r = _residual_noise(seed, 8.0, sigma=0.08, daily_k=0.1)
    day6 = (t >= T0 + 6 * DAY) & (t < T0 + 7 * DAY)
    off = r + np.where(day6, 0.34, 0.0)
    assert residual_change(t, off, signal="x2_c", unit="K") is not None  # spreads alone
    st = residual_settings("K")
    assert st.min_shift == pytest.approx(0.8)
    assert residual_change(t, off, signal="x2_c", unit="K", settings=st) is None
    step_s = T0 + 6.3 * DAY
    step = residual_change(t, r + np.where(t >= step_s, 1.0, 0.0), signal="x3_c", unit="K",
                           settings=st)
    assert step is not None and step_s <= step.detected_s <= step_s + 3 * 3600.0
    drift = residual_change(t, r + np.clip((t - step_s) / DAY, 0.0, None) * 0.5,
                            signal="x3_c", unit="K", settings=st)
    # the target for a 0.5 K/day drift is one day; this allowance takes a little
    # longer (1.0-1.1 days on these residuals): the price of no finding on a different day
    assert drift is not None and step_s + 0.5 * DAY < drift.detected_s <= step_s + 1.25 * DAY
    assert residual_settings("m/s").min_shift == 0.0  # the cavity speed: spreads only


def test_no_statistic_without_a_reference_and_a_gap_is_not_a_change():
    st = ResidualSettings()
    assert st.min_reference_blocks > 2 * (2 * st.half_width_blocks + 1)  # needs 3 days
    t, r = _residual_noise(11, 10.0)
    short = t < T0 + 2.9 * DAY
    jump = 5.0 * (t[short] > T0 + 2.5 * DAY)
    assert residual_change(t[short], r[short] + jump, signal="x1_c", unit="K",
                           settings=st) is None
    # a half-day hole in the data changes nothing
    hole = (t > T0 + 5.5 * DAY) & (t < T0 + 6.0 * DAY)
    assert residual_change(t[~hole], r[~hole], signal="x1_c", unit="K") is None


# ----------------------------------------------------------------------------- parameters
def _daily(days: int, seed: int, *, sd: float, wander_sd: float) -> tuple[np.ndarray, ...]:
    """Daily estimates of a parameter at 3.0 with posterior sd ``sd``, wandering uniformly
    within ± ``wander_sd`` × sd of the truth (a clean façade's day-to-day spread)."""
    rng = np.random.default_rng(seed)
    t = T0 + DAY * np.arange(days)
    sds = sd * rng.uniform(0.8, 1.25, size=days)
    values = 3.0 + rng.uniform(-wander_sd, wander_sd, size=days) * sds
    return t, values, sds


@pytest.mark.parametrize("seed", range(10))
def test_a_parameter_wandering_within_its_posterior_sd_is_no_finding(seed):
    t, v, sd = _daily(120, seed, sd=0.2, wander_sd=1.0)
    assert parameter_change(t, v, sd, name="h_out", unit="W/(m2 K)") is None


def test_a_daily_wander_beyond_an_overconfident_sd_is_rarely_a_finding():
    """Posterior sds ten times smaller than the clean days' wander (a lumped parameter's
    form error changing with the weather): the days' own spread is the scale. Without the
    between-day variance every one of these histories is a finding; with it, at most one
    finding in 3,000 clean days (the variance is estimated from a few weeks of days, so
    now and then it comes out small)."""
    found = 0
    for seed in range(50):
        t, v, sd = _daily(60, seed, sd=0.2, wander_sd=1.0)
        found += parameter_change(t, v, sd / 10.0, name="h_out") is not None
        assert parameter_change(t, v, sd / 10.0, name="h_out",
                                settings=ParameterSettings(wander_days=0.0, min_wander=0)
                                ) is not None
    assert found <= 1


@pytest.mark.parametrize("seed", range(3))
def test_a_step_beyond_the_wander_is_found_with_an_overconfident_sd(seed):
    t, v, sd = _daily(40, seed, sd=0.2, wander_sd=1.0)
    v = v.copy()
    v[20:] += 4.0 * 0.2  # four times the wander's half-width, forty times the sd
    f = parameter_change(t, v, sd / 10.0, name="h_out")
    assert f is not None and t[20] <= f.detected_s <= t[24]


def test_the_detector_uses_the_sd():
    """Steady days (no wander): a step of 5 sd is found; with sds five times larger the same
    step is 1 sd, within the 1.5-sd allowance, and nothing is found."""
    t, v, sd = _daily(40, 1, sd=0.2, wander_sd=0.0)
    v = v.copy()
    v[20:] += 1.0
    assert parameter_change(t, v, sd, name="f") is not None
    assert parameter_change(t, v, 5.0 * sd, name="f") is None


def test_between_day_variance_recovers_a_known_tau():
    """θ_j = μ + u_j + e_j with u ~ N(0, τ²), e ~ N(0, σ_j²): the estimate converges to τ²."""
    rng = np.random.default_rng(7)
    n, tau = 40000, 0.3
    sd = rng.uniform(0.1, 0.4, n)
    v = 2.0 + tau * rng.standard_normal(n) + sd * rng.standard_normal(n)
    assert between_day_variance(v, sd) == pytest.approx(tau**2, rel=0.05)
    # the errors alone (τ = 0) give ≈ 0, clipped at 0 from below
    assert between_day_variance(2.0 + sd * rng.standard_normal(n), sd) < 0.002
    assert between_day_variance(v[:1], sd[:1]) == 0.0


def test_a_drift_in_the_reference_does_not_inflate_the_between_day_variance():
    """Soiling under way: a trend of one sd a day adds half a day's step squared, not the
    trend's whole spread (which a variance about the mean would take in)."""
    days = np.arange(7.0)
    sd = np.full(7, 0.2)
    drifting = 3.0 - 0.2 * days
    assert between_day_variance(drifting, sd) == pytest.approx(0.0)
    assert np.var(drifting, ddof=1) - 0.2**2 > 0.05


@pytest.mark.parametrize("seed", range(5))
def test_a_parameter_step_is_found_after_it_and_never_before(seed):
    t, v, sd = _daily(40, seed, sd=0.2, wander_sd=1.0)
    change = 20
    v = v.copy()
    v[change:] += 4.0 * 0.2  # four posterior sd
    f = parameter_change(t, v, sd, name="f", unit="")
    assert f is not None and f.kind == "parameter_shift"
    assert t[change] <= f.detected_s <= t[change + 4]
    assert f.start_s == t[change]
    ev, = f.evidence
    assert ev.signal == "parameter:f" and 2.5 < ev.shift_sd < 5.5
    # the action says what a risen path resistance means for the façade
    assert f.action.startswith("f has risen by 0.") and "insect screens" in f.action
    assert parameter_change(t[:change], v[:change], sd[:change], name="f") is None


def test_a_slow_parameter_trend_is_found_within_days():
    """Soiling-like: the parameter falls by one posterior sd a day from day 15."""
    t, v, sd = _daily(40, 3, sd=0.2, wander_sd=1.0)
    v = v - np.clip(np.arange(40) - 15, 0, None) * 0.2
    f = parameter_change(t, v, sd, name="h_ca1", settings=ParameterSettings())
    assert f is not None and f.evidence[0].shift < 0
    assert t[15] < f.detected_s <= t[15] + 5 * DAY
