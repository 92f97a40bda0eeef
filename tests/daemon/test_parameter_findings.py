"""The daemon's parameter detector on a database it could have written (dsfd.daemon.findings,
docs/model.md#findings): three weeks of on-line estimates with their posterior sd, written
by the daemon's Store. A path resistance doubled or a room-side convection fallen is found
after the change (never before), and the finding names the parameter, the direction and
what it means for the façade. A clean wander within the sd, or a restart from the priors,
is no finding, and so is the same wander stored with overconfident sds (the day-to-day
wander is learned from the days themselves). While the detector
lacks its five days, or is not due, it ends none of its findings."""

from __future__ import annotations

import dataclasses
import math
import sqlite3
import types
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from dsfd.config import load_panel
from dsfd.control.stake import EnergyAtStake
from dsfd.daemon.findings import (
    PARAMETER_EVERY_S,
    PARAMETER_MIN_DAYS,
    PARAMETER_RELEASE_S,
    FindingsStage,
    detect,
)
from dsfd.estimation.daylight_split import window_dark
from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.lifecycle import Changes
from dsfd.estimation.solar_response import DIRT_OR_LOUVER, DailySolarResponse
from dsfd.report.finding_figures import evidence_figure
from dsfd.storage import findings as table
from dsfd.storage.solar_series import SolarDays, by_daylight
from dsfd.storage.timeseries import CycleRecord, Store
from tests.conftest import PANELS

DAY = 86400.0
MIDNIGHT = 19675 * DAY  # 2023-11-14 00:00 UTC
DEFAULTS = {"h_out": 12.0, "h_ca1": 3.5, "h_ca2": 4.0, "h_ca3": 3.5, "h_ca4": 4.4,
            "h_in": 2.5, "f": 100.0, "c": 0.05, "n": 0.6}
#: Posterior sd of each parameter's on-line estimates, in the fitting coordinates (ln θ; n).
SIGMA = {"h_out": 0.08, "h_ca1": 0.06, "h_ca2": 0.1, "h_ca3": 0.06, "h_ca4": 0.05,
         "h_in": 0.08, "f": 0.15, "c": 0.2, "n": 0.03}
HISTORY_DAYS = 21
PANEL = load_panel(PANELS / "suwon-south.yaml")
OFFSETS = ("q_x1", "q_x2", "q_x3", "q_x4")
SHIFT_AT = MIDNIGHT + 14 * DAY + 6 * 3600.0  # 06:00 on the 15th day
#: The tests check every 6 h unless they say otherwise (every hour, the detector's own
#: cadence, costs six times the checks).
CHECK_GRID_S = 6 * 3600.0


def _decision(cycle: int, t: float) -> dict[str, object]:
    return {"slot": cycle, "time_s": t, "time_utc": "t", "method": "mpc", "phi_deg": 0.0,
            "afr": 10, "or_pct": 0.0, "write_status": "dry-run", "cycle_ms": 1.0}


def _parameter_history(tmp_path: Path, *, seed: int = 0, shift: dict[str, float] | None = None,
                       sd_scale: float = 1.0, restart_at: float | None = None,
                       shift_at: float = SHIFT_AT,
                       shift_where: Callable[[np.ndarray], np.ndarray] | None = None) -> Path:
    """Three weeks of hourly on-line estimates written by the daemon's Store, from noon of
    the first day (a partial day): each parameter wanders from day to day uniformly within
    ± its posterior sd (a clean façade), has a daily cycle of one sd (what a lumped model's
    4-h windows make of the sun) and correlated hour-to-hour noise (AR(1), φ 0.8, half an
    sd); ``shift`` adds ln-factors (or to n) from :data:`SHIFT_AT` on. The stored sds are
    the posterior sds ×U(0.8, 1.25), × ``sd_scale``. ``restart_at``: the calibration
    starts again from its priors there (a ``prior`` row). ``shift_where``: the estimate
    times (of the θ parameters) the shift applies at (default all)."""
    rng = np.random.default_rng(seed)
    store = Store.open(tmp_path)
    store.begin_run(panel="p", mode="test", version="0", config_path=None)
    t = MIDNIGHT + 12 * 3600.0 + 3600.0 * np.arange(int((HISTORY_DAYS - 0.5) * 24))
    day = ((t - MIDNIGHT) // DAY).astype(int)
    z = {}
    for name, sigma in SIGMA.items():
        ar = np.zeros(t.size)
        for i in range(1, t.size):
            ar[i] = 0.8 * ar[i - 1] + rng.normal(0.0, 0.5 * sigma * np.sqrt(1 - 0.64))
        z[name] = (rng.uniform(-1.0, 1.0, HISTORY_DAYS)[day] * sigma + ar
                   + sigma * np.sin(2 * np.pi * t / DAY)
                   + np.where((t >= shift_at) & (True if shift_where is None else shift_where(t)),
                              (shift or {}).get(name, 0.0), 0.0))
    prior_sd = {name: 0.15 if name == "n" else 0.7 for name in SIGMA}
    q_wander = {q: rng.uniform(-1.0, 1.0, HISTORY_DAYS)[day] + rng.normal(0.0, 0.5, t.size)
                for q in OFFSETS}
    rows = [(t[0] - 60.0, "prior", DEFAULTS, prior_sd)]
    for i, ti in enumerate(t):
        if restart_at is not None and t[i - 1] < restart_at <= ti:
            rows.append((restart_at, "prior", DEFAULTS, prior_sd))
        theta = {n: (v + z[n][i] if n == "n" else v * np.exp(z[n][i]))
                 for n, v in DEFAULTS.items()}
        # the heat-flux offsets [W/m2]: a wander of about 1 W/m2 (the clean bench days'
        # q_x3), no sd stored; ``shift`` adds to them as it is
        theta.update({q: float(q_wander[q][i] + (shift or {}).get(q, 0.0) * (ti >= shift_at))
                      for q in OFFSETS})
        sd = {n: s * sd_scale * rng.uniform(0.8, 1.25) for n, s in SIGMA.items()}
        rows.append((float(ti), "online", theta, sd))
    for cycle, (ti, source, theta, sd) in enumerate(rows, start=1):
        store.append(CycleRecord(cycle=cycle, time_s=ti, samples=[],
                                 decision=_decision(cycle, ti),
                                 parameters=(source, theta, 1.0, "100 residuals"),
                                 parameter_sd=sd))
    store.close()
    return tmp_path / "timeseries.sqlite"


def _checks(db: Path, *, every_s: float = CHECK_GRID_S, start_s: float = MIDNIGHT + 4 * DAY,
            stop_s: float = MIDNIGHT + (HISTORY_DAYS - 0.5) * DAY) -> list[tuple[float, Changes]]:
    """The stage's checks every ``every_s`` from ``start_s`` (by default every 6 h from the
    5th day on; the detector runs at each, being due hourly)."""
    stage = FindingsStage(db, run_id=lambda: 1)
    conn = sqlite3.connect(db)
    try:
        return [(now, stage.check(conn, now)) for now in np.arange(start_s, stop_s, every_s)]
    finally:
        conn.close()


def test_an_inner_pane_thermocouple_reading_high_is_found_on_its_heat_flux_offset(tmp_path):
    """The state update takes a reading as it is, so a thermocouple 1 K high on the inner
    pane becomes a constant heat flux in the fit: q_x3 moved by 15-18 W/m2 on the
    diagnostics bench. Here +15 W/m2 from day 15: found within two days, q_x3 alone, and
    the action names the sensor x3 first."""
    db = _parameter_history(tmp_path, shift={"q_x3": 15.0})
    opened = [(now, f) for now, c in _checks(db) for f in c.opened]
    assert [f.evidence[0].signal for _, f in opened] == ["parameter:q_x3"]
    (found_at, f), = opened
    assert SHIFT_AT < found_at <= SHIFT_AT + 2 * DAY
    assert f.evidence[0].unit == "W/m2" and f.evidence[0].shift == pytest.approx(15.0, abs=3.0)
    assert f.action.startswith("q_x3 has risen by 1") and "first check its sensor x3" in f.action


@pytest.mark.parametrize("hour", [1, 12, 23])
def test_how_soon_a_change_is_found_does_not_depend_on_the_hour_it_began(tmp_path, hour):
    """The detector's days are the 24 h that end at each check, so a change is judged on a
    whole day of it one day after it began, whatever the hour (with UTC days, one at 01:00
    waited until the next midnight but one). q_x3 +15 W/m² (a thermocouple 1 K high, about
    seven sd of its wander), checked hourly as the daemon does: found within a day and an
    hour. h_in ×0.6 sits near the threshold (4.7 sd), checked every 6 h: found within two
    days, once, and not ended and opened again as the days move from check to check (the
    return delay)."""
    shift_at = MIDNIGHT + 14 * DAY + hour * 3600.0
    for name, shift, within in (("q_x3", 15.0, DAY + PARAMETER_EVERY_S),
                                ("h_in", float(np.log(0.6)), 2 * DAY)):
        db = _parameter_history(tmp_path / name, shift={name: shift}, shift_at=shift_at)
        # q_x3 around the change, hourly; h_in on the 6-hourly grid from the 5th day, where
        # without the return delay the change at 01:00 was found, ended 6 h later and
        # found again 6 h after that
        checks = (_checks(db, every_s=PARAMETER_EVERY_S, start_s=shift_at - 2 * 3600.0,
                          stop_s=shift_at + 3 * DAY) if name == "q_x3" else _checks(db))
        opened = [now for now, c in checks for f in c.opened]
        assert len(opened) == 1 and shift_at < opened[0] <= shift_at + within, name
        assert not any(c.ended for _, c in checks), name


@pytest.mark.parametrize(("name", "factor", "direction", "cause"), [
    ("f", 2.0, "risen", "clean the insect screens"),  # a clogging screen: path resistance x2
    ("h_in", 0.6, "fallen", "blind or curtain drawn"),
])
def test_a_parameter_shift_is_found_after_it_started_and_says_what_it_means(
        tmp_path, name, factor, direction, cause):
    db = _parameter_history(tmp_path, shift={name: float(np.log(factor))})
    checks = _checks(db)
    opened = [(now, f) for now, changes in checks for f in changes.opened]
    (found_at, f), = opened  # one finding, and it stays open (refreshed)
    assert f.kind == "parameter_shift" and f.evidence[0].signal == f"parameter:{name}"
    # found after the change, within three days; never before it
    assert SHIFT_AT < found_at <= SHIFT_AT + 3 * DAY
    # dated from the start of the day it began, a day being the 24 h that end a whole number
    # of days before the check that found it; detected when that day's evidence was complete
    assert f.start_s == f.evidence[0].since_s
    assert f.start_s <= SHIFT_AT < f.start_s + DAY and (found_at - f.start_s) % DAY == 0.0
    assert SHIFT_AT < f.detected_s <= found_at
    assert f.evidence[0].unit == "log"
    assert np.exp(f.evidence[0].shift) == pytest.approx(factor, rel=0.25)
    assert f"{name} has {direction}" in f.action and cause in f.action
    assert all(not c.ended for _, c in checks)
    conn = sqlite3.connect(db)
    try:
        assert conn.execute("SELECT kind, subject, state FROM findings").fetchall() == [
            ("parameter_shift", f"parameter:{name}", "open")]
        # refreshed hourly for days, it keeps the time it was first detected (each refresh's
        # alarm day ends at its own check)
        assert conn.execute("SELECT detected_s FROM findings").fetchall() == [(f.detected_s,)]
    finally:
        conn.close()


@pytest.mark.parametrize("seed", range(3))
def test_a_clean_wander_within_the_posterior_sd_is_no_finding(tmp_path, seed):
    db = _parameter_history(tmp_path, seed=seed)
    assert not any(c.opened for _, c in _checks(db))


def test_the_same_wander_stored_with_overconfident_sds_is_no_finding_but_a_shift_is(
        tmp_path):
    """The clean history of the test above with sds ten times smaller: the days' own wander
    (the between-day variance the check learns from the stored days) is the scale, so it is
    no finding, while the doubled path resistance still is, after the change."""
    db = _parameter_history(tmp_path / "clean", seed=0, sd_scale=0.1)
    assert not any(c.opened for _, c in _checks(db))
    db = _parameter_history(tmp_path / "shift", seed=0, sd_scale=0.1,
                            shift={"f": float(np.log(2.0))})
    opened = [(now, f) for now, c in _checks(db) for f in c.opened]
    assert [f.evidence[0].signal for _, f in opened] == ["parameter:f"]
    assert SHIFT_AT < opened[0][0] <= SHIFT_AT + 3 * DAY


def test_a_calibration_restarted_from_its_priors_starts_a_new_history(tmp_path):
    """The jump at a restart from the priors is no finding: the days before it are not the
    reference of the days after it."""
    db = _parameter_history(tmp_path, shift={"f": float(np.log(2.0))}, restart_at=SHIFT_AT)
    assert not any(c.opened for _, c in _checks(db))


def test_the_parameter_detector_not_run_ends_none_of_its_findings(tmp_path):
    """An open parameter finding stays open while the detector lacks its five days (a
    restart from the priors) or is not due, and ends once it has run for a day
    (PARAMETER_RELEASE_S, the return delay) without seeing it."""
    restart = MIDNIGHT + 13 * DAY + 12 * 3600.0
    db = _parameter_history(tmp_path, restart_at=restart)
    ev = Evidence(signal="parameter:f", shift=0.7, shift_sd=4.6, unit="log",
                  since_s=MIDNIGHT + 10 * DAY, statistic=6.0, threshold=5.0)
    old = Finding(kind="parameter_shift", confidence=0.6, start_s=ev.since_s,
                  detected_s=ev.since_s + DAY, evidence=(ev,), action="clean the screens")
    conn = sqlite3.connect(db)
    try:
        table.apply(conn, Changes(opened=[old]), now_s=ev.since_s + DAY, run_id=1)
        stage = FindingsStage(db, run_id=lambda: 1)
        # four complete days since the restart: too few, nothing judged, nothing ended
        early = restart + 4.6 * DAY
        assert "parameter_shift" not in detect(conn, early)[1]
        assert not stage.check(conn, early).ended
        # five: the detector runs, and the evidence is not there; the finding ends once the
        # checks of a whole day missed it (hourly, and checks between that do not run it)
        ready = restart + 5.6 * DAY
        assert PARAMETER_MIN_DAYS == 5 and "parameter_shift" in detect(conn, ready)[1]
        assert PARAMETER_RELEASE_S == DAY
        for k in range(4):
            assert not stage.check(conn, ready + k * PARAMETER_EVERY_S).ended
            assert not stage.check(conn, ready + k * PARAMETER_EVERY_S + 600.0).ended
        assert stage.check(conn, ready + DAY).ended == [1]
        # a finding opened now stays open while the detector is not due (hourly)
        later = ready + DAY
        [again] = table.apply(conn, Changes(opened=[old]), now_s=later, run_id=1)
        assert not stage.check(conn, later + 600.0).ended
        assert not stage.check(conn, later + PARAMETER_EVERY_S).ended
        assert stage.check(conn, later + PARAMETER_EVERY_S + DAY).ended == [again]
    finally:
        conn.close()


def _sunlit(t: np.ndarray) -> np.ndarray:
    return ~window_dark(t, PANEL.calibration.window_h * 3600.0,
                        latitude_deg=PANEL.site.latitude_deg,
                        longitude_deg=PANEL.site.longitude_deg)


def _solar_days(after: float) -> list[DailySolarResponse]:
    """The solar detector's daily factor: −0.03 every day, ``after`` from the shift on."""
    return [DailySolarResponse(time_s=MIDNIGHT + (d + 0.5) * DAY,
                               factor=after if MIDNIGHT + d * DAY >= SHIFT_AT - DAY else -0.03,
                               sd=0.01, node_factors=(math.nan,) * 4, sunny_steps=300)
            for d in range(HISTORY_DAYS)]


@pytest.mark.parametrize(("where", "told"), [(_sunlit, True), (None, False)])
def test_a_coefficient_moved_in_the_sunlit_windows_alone_is_told_as_a_change_of_the_sun(
        tmp_path, where, told):
    """The glass unit's h_ca4 ×2 from day 15 in the estimates whose 4-h window saw the sun
    (what dirt did to it on the diagnostics bench), the solar detector's daily factor down
    by 0.04 on the same days: the parameter finding is told as a solar_gain_shift of the
    exterior glass or the louver, with both halves as evidence. The same rise day and night
    (a failed edge seal) stays the glass unit's parameter_shift."""
    db = _parameter_history(tmp_path, shift={"h_ca4": math.log(2.0)}, shift_where=where)
    now = SHIFT_AT + 2 * DAY
    conn = sqlite3.connect(db)
    try:
        found, _ = detect(conn, now)
        assert [f.evidence[0].signal for f in found] == ["parameter:h_ca4"]
        out = by_daylight(conn, found, now, panel=PANEL, solar_days=lambda: _solar_days(-0.07))
        untold = by_daylight(conn, found, now, panel=PANEL, solar_days=list)
    finally:
        conn.close()
    (f,) = out
    assert untold == found  # no solar days: nothing says which way the sun went
    if not told:
        assert f == found[0]
        return
    assert (f.kind, f.subject) == ("solar_gain_shift", DIRT_OR_LOUVER)
    head, dark, lit, solar = f.evidence
    assert head == found[0].evidence[0] and dark.signal.endswith(":dark")
    assert solar.shift == pytest.approx(-0.04)  # the daily factor, -0.03 before
    assert abs(dark.shift) < 0.15 and lit.shift == pytest.approx(math.log(2.0), abs=0.25)
    assert "less of the sun" in f.action and "clean it" in f.action


def test_the_report_draws_a_coefficient_told_as_the_suns_by_night_and_in_the_sun(tmp_path):
    """The stored finding's figure is the coefficient's estimates apart for the dark and the
    sunlit windows (not the solar detector's daily share, which did not move enough): two
    series of daily values, the sunlit one about twice the dark one after the start."""
    db = _parameter_history(tmp_path, shift={"h_ca4": math.log(2.0)}, shift_where=_sunlit)
    now = SHIFT_AT + 2 * DAY
    conn = sqlite3.connect(db)
    try:
        found, _ = detect(conn, now)
        told = by_daylight(conn, found, now, panel=PANEL, solar_days=lambda: _solar_days(-0.07))
        table.apply(conn, Changes(opened=told), now_s=now, run_id=1)
        (row,) = table.findings_between(conn, now - DAY, now)
        fig = evidence_figure(conn, row, offset_h=9.0, config=dataclasses.asdict(PANEL))
    finally:
        conn.close()
    assert not isinstance(fig, str), fig
    assert "by night and in the sun" in fig.texts[0].get_text()
    ax = fig.axes[0]
    series = {c.get_label(): c for c in ax.containers}
    dark = next(c for label, c in series.items() if label.startswith("night windows"))
    lit = next(c for label, c in series.items() if label.startswith("sunlit windows"))
    y_dark, y_lit = (c.lines[0].get_data()[1] for c in (dark, lit))
    assert np.median(y_lit[-2:]) / np.median(y_dark[-2:]) == pytest.approx(2.0, rel=0.3)
    assert np.median(y_lit[:5]) / np.median(y_dark[:5]) == pytest.approx(1.0, rel=0.3)


class _KnownSolarDays(SolarDays):
    """The solar detector's days as :func:`_solar_days` gives them (the synthetic store
    holds no weather to compute them from), each too uncertain (sd 0.05) for a finding of
    the solar detector's own."""

    def days(self, conn: sqlite3.Connection, now_s: float) -> list[DailySolarResponse]:
        return [dataclasses.replace(d, sd=0.05) for d in _solar_days(-0.07)
                if d.time_s < now_s]


def test_a_coefficient_told_as_the_suns_stays_one_finding_when_the_detectors_run_apart(
        tmp_path):
    """The told finding comes from the parameter detector (hourly) while its kind is judged
    by the solar detector (every 6 h): a check where the solar detector runs alone keeps it,
    so it opens once and stays open (it ended and opened again every day or so on the
    diagnostics bench's soiled façade before)."""
    db = _parameter_history(tmp_path, shift={"h_ca4": math.log(2.0)}, shift_where=_sunlit)
    stage = FindingsStage(db, run_id=lambda: 1, panel=PANEL)
    stage.solar = _KnownSolarDays(PANEL, tmp_path)
    start = SHIFT_AT + DAY
    stage._ran_s["solar"] = start - 5.5 * 3600.0  # due half an hour off the parameters' hour
    conn = sqlite3.connect(db)
    try:
        changes = [stage.check(conn, now) for now in np.arange(start, start + 3 * DAY, 1800.0)]
    finally:
        conn.close()
    opened = [f for c in changes for f in c.opened if f.kind == "solar_gain_shift"]
    assert len(opened) == 1 and opened[0].subject == DIRT_OR_LOUVER
    ended = [fid for c in changes for fid in c.ended]
    conn = sqlite3.connect(db)
    try:
        solar_ids = {r["finding_id"] for r in table.findings_between(conn, 0.0, start + 3 * DAY)
                     if r["kind"] == "solar_gain_shift"}
    finally:
        conn.close()
    assert not solar_ids & set(ended)


class _BrokenSolarDays(SolarDays):
    """A store the solar days cannot be read from (a corrupt history, say)."""

    def days(self, conn: sqlite3.Connection, now_s: float) -> list[DailySolarResponse]:
        raise sqlite3.DatabaseError("database disk image is malformed")


def test_a_failing_daylight_split_is_counted_and_leaves_the_parameter_finding_as_found(
        tmp_path):
    """The split needs the solar days; when they cannot be read the check goes on, the
    failure is counted, and the coefficient's finding opens as the parameter detector told it."""
    db = _parameter_history(tmp_path, shift={"h_ca4": math.log(2.0)}, shift_where=_sunlit)
    stage = FindingsStage(db, run_id=lambda: 1, panel=PANEL)
    stage.solar = _BrokenSolarDays(PANEL, tmp_path)
    now = SHIFT_AT + 2 * DAY
    stage._ran_s["solar"] = now  # the solar detector itself is not due: only the split fails
    conn = sqlite3.connect(db)
    try:
        changes = stage.check(conn, now)
    finally:
        conn.close()
    assert stage.failures == 1
    assert [(f.kind, f.evidence[0].signal) for f in changes.opened] == [
        ("parameter_shift", "parameter:h_ca4")]


def test_a_coefficient_told_as_the_suns_is_costed_as_the_sun_it_lost(tmp_path, monkeypatch):
    """Told as the sun's, the finding's energy at stake is the sun's: the stored week costed
    with the share of the sun it lost given back (dsfd.daemon.stake; its figures are tested
    against dsfd export in test_run_summary, and replaced here by one that reports what it
    was asked: the synthetic store holds no week of cycles). It ends the action and the
    evidence, after the halves and the daily factor."""
    import dsfd.daemon.stake as stake

    asked = []

    def reported_stake(model, steps, theta, share_change):
        asked.append(share_change)
        return EnergyAtStake(j_before_kwh=0.0, j_now_kwh=1.25 / 7, days=1.0,
                             per_week_kwh=1.25)

    week = types.SimpleNamespace(step_s=60.0)  # what the replaced costing is given
    monkeypatch.setattr(stake, "stake_record", lambda panel, state_dir, now_s: week)
    monkeypatch.setattr(stake, "LumpedModel", lambda cfg: None)
    monkeypatch.setattr(stake, "model_config", lambda panel, step_s: None)
    monkeypatch.setattr(stake, "solar_energy_at_stake", reported_stake)
    db = _parameter_history(tmp_path, shift={"h_ca4": math.log(2.0)}, shift_where=_sunlit)
    stage = FindingsStage(db, run_id=lambda: 1, panel=PANEL)
    stage.solar = _KnownSolarDays(PANEL, tmp_path)
    now = SHIFT_AT + 2 * DAY
    conn = sqlite3.connect(db)
    try:
        (f,) = stage.check(conn, now).opened
    finally:
        conn.close()
    assert (f.kind, f.subject) == ("solar_gain_shift", DIRT_OR_LOUVER)
    assert [e.signal for e in f.evidence] == [
        "parameter:h_ca4", "parameter:h_ca4:dark", "parameter:h_ca4:sunlit",
        "solar_response", stake.STAKE_SIGNAL]
    assert asked == [pytest.approx(-0.04)] and f.evidence[-1].shift == 1.25
    assert "less of the sun" in f.action and f.action.endswith(
        "the change costs about 1.25 kWh a week (the model's J, Eq. 4/5)")
