"""The daemon's findings check on a database it could have written (dsfd.daemon.findings):
the residual detector runs on the stored readings minus the stored one-step predictions once
six days are stored, finds a 1 K step on one output after it started (never before), and
names that output only; the check stores it and the next hourly run refreshes it."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from dsfd.daemon.findings import RESIDUAL_EVERY_S, RESIDUAL_MIN_S, FindingsStage, NightSite
from dsfd.storage.timeseries import Store

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
