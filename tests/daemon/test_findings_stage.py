"""The daemon's findings check on a database it could have written (dsfd.daemon.findings):
the residual detector runs on the stored readings minus the stored one-step predictions once
six days are stored, finds a 1 K step on one output after it started (never before), and
names that output only; the check stores it and the next hourly run refreshes it. The night
check finds a thermocouple step on the exterior pane. The parameter detector, on three weeks
of on-line estimates with their posterior sd written by the daemon's Store, finds a path
resistance doubled or a room-side convection fallen after the change (never before) and says
what it means; a clean wander within the sd, or a restart from the priors, is no finding;
while it lacks its five days or is not due it ends none of its findings."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from dsfd.daemon.findings import (
    PARAMETER_EVERY_S,
    PARAMETER_MIN_DAYS,
    RESIDUAL_EVERY_S,
    RESIDUAL_MIN_S,
    FindingsStage,
    NightSite,
    detect,
)
from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.lifecycle import Changes
from dsfd.storage import findings as table
from dsfd.storage.timeseries import CycleRecord, Store

STEP_S = 120.0  # two-minute cycles: five readings in every 10-min block
DAYS = 7
T0 = 1.7e9
STEP_AT = T0 + 6.5 * 86400.0
OUTPUTS = (*(f"x{i}_c" for i in range(1, 6)), "v_cav_ms")


def _write(tmp_path: Path, t: np.ndarray, readings: dict[str, np.ndarray],
           predictions: dict[str, np.ndarray]) -> Path:
    """A database the daemon could have written: one cycle per ``t``, GOOD readings and
    the ``model`` table's columns given."""
    store = Store.open(tmp_path)
    run = store.begin_run(panel="p", mode="test", version="0", config_path=None)
    store.close()
    n = t.size
    db = tmp_path / "timeseries.sqlite"
    with sqlite3.connect(db) as conn:
        conn.executemany("INSERT INTO samples (run_id, cycle, time_s, signal, value, quality) "
                         "VALUES (?, ?, ?, ?, ?, 'good')",
                         [(run, c, t[c], name, float(v[c])) for name, v in readings.items()
                          for c in range(n)])
        conn.executemany("INSERT INTO decisions (run_id, cycle, slot, time_s, time_utc, "
                         "method, phi_deg, afr, or_pct, write_status, cycle_ms) VALUES "
                         "(?, ?, ?, ?, 't', 'mpc', 0.0, 10, 0.0, 'dry-run', 1.0)",
                         [(run, c, c, t[c]) for c in range(n)])
        cols = ", ".join(["run_id", "cycle", "time_s", *predictions])
        conn.executemany(f"INSERT INTO model ({cols}) VALUES "
                         f"({', '.join('?' for _ in range(3 + len(predictions)))})",
                         [(run, c, t[c], *(float(m[c]) for m in predictions.values()))
                          for c in range(n)])
    return db


def _database(tmp_path: Path) -> Path:
    """Seven days of cycles: predictions follow a daily cycle, readings are the prediction
    plus AR(1) noise (0.3 K or 0.02 m/s sd), and x3 reads 1 K high from day 6.5 on."""
    rng = np.random.default_rng(7)
    n = int(DAYS * 86400 / STEP_S)
    t = T0 + np.arange(n) * STEP_S
    readings, predictions = {}, {}
    for name in OUTPUTS:
        sd = 0.02 if name == "v_cav_ms" else 0.3
        pred = (0.1 if name == "v_cav_ms" else 20.0) + sd * np.sin(2 * np.pi * t / 86400.0)
        noise = np.zeros(n)
        for i in range(1, n):  # AR(1), phi 0.5: correlated like one-step errors are
            noise[i] = 0.5 * noise[i - 1] + rng.normal(0, sd * np.sqrt(1 - 0.25))
        readings[name] = pred + noise + (np.where(t >= STEP_AT, 1.0, 0.0)
                                         if name == "x3_c" else 0.0)
        predictions[f"pred_{name}"] = pred
    return _write(tmp_path, t, readings, predictions)


def test_the_check_finds_a_residual_step_after_it_started_and_names_that_output(tmp_path):
    db = _database(tmp_path)
    stage = FindingsStage(db, run_id=lambda: 1)
    conn = sqlite3.connect(db)
    try:
        # before six days are stored the residual detector does not run
        assert RESIDUAL_MIN_S > 5.9 * 86400.0
        early = stage.check(conn, T0 + 5.9 * 86400.0)
        assert not early.opened
        # before the step: nothing; after it: x3 alone
        assert not stage.check(conn, STEP_AT - 600.0).opened
        now = T0 + DAYS * 86400.0
        changes = stage.check(conn, now)
        assert [f.kind for f in changes.opened] == ["residual_shift"]
        (f,) = changes.opened
        assert f.evidence[0].signal == "residual:x3_c"
        # detected after the step; Page's change time within three blocks of it
        assert STEP_AT < f.detected_s <= now and abs(f.start_s - STEP_AT) <= 1800.0
        assert 0.5 <= f.evidence[0].shift <= 1.5  # the 1 K step, within the noise
        # 10 min later the CUSUM is not due (hourly): the finding stays open untouched
        soon = stage.check(conn, now + 600.0)
        assert not soon.opened and not soon.refreshed and not soon.ended
        again = stage.check(conn, now + RESIDUAL_EVERY_S)
        assert not again.opened and [fid for fid, _ in again.refreshed] == [1]
        assert conn.execute("SELECT kind, subject, state FROM findings").fetchall() == [
            ("residual_shift", "residual:x3_c", "open")]
    finally:
        conn.close()


@pytest.mark.parametrize("step_k", [0.0, 1.5])
def test_the_night_check_finds_a_thermocouple_step_on_the_exterior_pane(tmp_path, step_k):
    """Three weeks of 10-min cycles in Suwon: the exterior pane sits 0.5 ± 0.3 K (night to
    night) above the outdoor air, and ``step_k`` more from the 15th night on (a thermocouple
    step). The check runs with the site's night mask once 8 days are stored."""
    rng = np.random.default_rng(3)
    days = 21
    t = T0 + 600.0 * np.arange(days * 144)
    night_id = ((t - T0 + 12 * 3600) // 86400).astype(int)  # T0 is 07:13 in Suwon: 19:13-19:13
    t_out = 2.0 + 4.0 * np.sin(2 * np.pi * (t - T0) / 86400.0)
    x1 = (t_out + rng.normal(0.5, 0.3, days + 2)[night_id] + rng.normal(0, 0.2, t.size)
          + np.where(night_id >= 15, step_k, 0.0))
    db = _write(tmp_path, t, {"x1_c": x1, "t_out_c": t_out, "t_room_c": np.full(t.size, 21.0)},
                {})
    site = NightSite(latitude_deg=37.3, longitude_deg=127.0, room_c=21.0)
    conn = sqlite3.connect(db)
    try:
        step_s = T0 + 14.5 * 86400.0  # noon before the 15th night
        assert not FindingsStage(db, run_id=lambda: 1, night=site).check(conn, step_s).opened
        # without the night check nothing is judged about the panes
        assert not FindingsStage(db, run_id=lambda: 1).check(conn, t[-1]).opened
        changes = FindingsStage(db, run_id=lambda: 1, night=site).check(conn, t[-1])
        if step_k == 0.0:
            assert not changes.opened  # quiet nights: nothing
            return
        (f,) = changes.opened
        assert f.kind == "pane_offset_shift"
        assert f.evidence[0].signal == "crosscheck:x1_c-t_out_c"
        assert step_s <= f.start_s < f.detected_s <= t[-1]  # the first stepped night
        assert f.evidence[0].shift == pytest.approx(1.5, abs=0.6)
    finally:
        conn.close()


# ---------------------------------------------------------------------------- parameters
DAY = 86400.0
MIDNIGHT = 19675 * DAY  # 2023-11-14 00:00 UTC
DEFAULTS = {"h_out": 12.0, "h_ca1": 3.5, "h_ca2": 4.0, "h_ca3": 3.5, "h_ca4": 4.4,
            "h_in": 2.5, "f": 100.0, "c": 0.05, "n": 0.6}
#: Posterior sd of each parameter's on-line estimates, in the fitting coordinates (ln θ; n).
SIGMA = {"h_out": 0.08, "h_ca1": 0.06, "h_ca2": 0.1, "h_ca3": 0.06, "h_ca4": 0.05,
         "h_in": 0.08, "f": 0.15, "c": 0.2, "n": 0.03}
HISTORY_DAYS = 21
SHIFT_AT = MIDNIGHT + 14 * DAY + 6 * 3600.0  # 06:00 on the 15th day


def _decision(cycle: int, t: float) -> dict[str, object]:
    return {"slot": cycle, "time_s": t, "time_utc": "t", "method": "mpc", "phi_deg": 0.0,
            "afr": 10, "or_pct": 0.0, "write_status": "dry-run", "cycle_ms": 1.0}


def _parameter_history(tmp_path: Path, *, seed: int = 0, shift: dict[str, float] | None = None,
                       sd_scale: float = 1.0, restart_at: float | None = None) -> Path:
    """Three weeks of hourly on-line estimates written by the daemon's Store, from noon of
    the first day (a partial day): each parameter wanders from day to day uniformly within
    ± its posterior sd (a clean façade), has a daily cycle of one sd (what a lumped model's
    4-h windows make of the sun) and correlated hour-to-hour noise (AR(1), φ 0.8, half an
    sd); ``shift`` adds ln-factors (or to n) from :data:`SHIFT_AT` on. The stored sds are
    the posterior sds ×U(0.8, 1.25), × ``sd_scale``. ``restart_at``: the calibration
    starts again from its priors there (a ``prior`` row)."""
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
                   + np.where(t >= SHIFT_AT, (shift or {}).get(name, 0.0), 0.0))
    prior_sd = {name: 0.15 if name == "n" else 0.7 for name in SIGMA}
    rows = [(t[0] - 60.0, "prior", DEFAULTS, prior_sd)]
    for i, ti in enumerate(t):
        if restart_at is not None and t[i - 1] < restart_at <= ti:
            rows.append((restart_at, "prior", DEFAULTS, prior_sd))
        theta = {n: (v + z[n][i] if n == "n" else v * np.exp(z[n][i]))
                 for n, v in DEFAULTS.items()}
        sd = {n: s * sd_scale * rng.uniform(0.8, 1.25) for n, s in SIGMA.items()}
        rows.append((float(ti), "online", theta, sd))
    for cycle, (ti, source, theta, sd) in enumerate(rows, start=1):
        store.append(CycleRecord(cycle=cycle, time_s=ti, samples=[],
                                 decision=_decision(cycle, ti),
                                 parameters=(source, theta, 1.0, "100 residuals"),
                                 parameter_sd=sd))
    store.close()
    return tmp_path / "timeseries.sqlite"


def _checks(db: Path) -> list[tuple[float, Changes]]:
    """The stage's checks every 6 h (the parameter detector's cadence) from the 5th day on."""
    stage = FindingsStage(db, run_id=lambda: 1)
    conn = sqlite3.connect(db)
    try:
        return [(now, stage.check(conn, now)) for now in
                MIDNIGHT + 4 * DAY + PARAMETER_EVERY_S * np.arange(HISTORY_DAYS * 4 - 15)]
    finally:
        conn.close()


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
    assert SHIFT_AT <= f.start_s < SHIFT_AT + DAY and f.detected_s <= found_at
    assert f.evidence[0].unit == "log"
    assert np.exp(f.evidence[0].shift) == pytest.approx(factor, rel=0.25)
    assert f"{name} has {direction}" in f.action and cause in f.action
    assert all(not c.ended for _, c in checks)
    conn = sqlite3.connect(db)
    try:
        assert conn.execute("SELECT kind, subject, state FROM findings").fetchall() == [
            ("parameter_shift", f"parameter:{name}", "open")]
    finally:
        conn.close()


@pytest.mark.parametrize("seed", range(3))
def test_a_clean_wander_within_the_posterior_sd_is_no_finding(tmp_path, seed):
    db = _parameter_history(tmp_path, seed=seed)
    assert not any(c.opened for _, c in _checks(db))


def test_the_same_wander_stored_with_overconfident_sds_is_a_finding(tmp_path):
    """The check weighs the history against the stored sds: the clean history of the test
    above with sds ten times smaller is a finding."""
    db = _parameter_history(tmp_path, seed=0, sd_scale=0.1)
    assert any(f.kind == "parameter_shift" for _, c in _checks(db) for f in c.opened)


def test_a_calibration_restarted_from_its_priors_starts_a_new_history(tmp_path):
    """The jump at a restart from the priors is no finding: the days before it are not the
    reference of the days after it."""
    db = _parameter_history(tmp_path, shift={"f": float(np.log(2.0))}, restart_at=SHIFT_AT)
    assert not any(c.opened for _, c in _checks(db))


def test_the_parameter_detector_not_run_ends_none_of_its_findings(tmp_path):
    """An open parameter finding stays open while the detector lacks its five days (a
    restart from the priors) or is not due, and ends once it runs and no longer sees it."""
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
        # five: the detector runs, and the evidence is not there
        ready = restart + 5.6 * DAY
        assert PARAMETER_MIN_DAYS == 5 and "parameter_shift" in detect(conn, ready)[1]
        assert stage.check(conn, ready).ended == [1]
        # a finding opened now stays open while the detector is not due (6-hourly)
        [again] = table.apply(conn, Changes(opened=[old]), now_s=ready, run_id=1)
        assert not stage.check(conn, ready + 600.0).ended
        assert stage.check(conn, ready + PARAMETER_EVERY_S).ended == [again]
    finally:
        conn.close()
