"""The daemon's findings check on a database it could have written (dsfd.daemon.findings):
the residual detector runs on the stored readings minus the stored one-step predictions once
six days are stored, finds a 1 K step on one output after it started (never before), and
names that output only; the check stores it and the next hourly run refreshes it."""

from __future__ import annotations

import sqlite3

import pytest

from dsfd.daemon.findings import RESIDUAL_EVERY_S, RESIDUAL_MIN_S, FindingsStage, NightSite
from tests.daemon.findings_data import (
    DAYS,
    STEP_AT,
    SUWON,
    T0,
    night_database,
    residual_database,
)


def test_the_check_finds_a_residual_step_after_it_started_and_names_that_output(tmp_path):
    db = residual_database(tmp_path)
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


@pytest.mark.parametrize("recorded", [False, True])
def test_a_control_never_used_at_that_hour_is_no_residual_finding(tmp_path, recorded):
    """Three hours of a regime the controller had not used before, under which the model's
    x2 is 1.5 K off: judged against the same hours' blocks of the usual regime it looks
    like a change of the façade; the stored applied regime (``model.applied_afr``) keeps it
    to blocks of its own kind, of which there are none."""
    db = residual_database(tmp_path, new_control=True, record_control=recorded)
    stage = FindingsStage(db, run_id=lambda: 1)
    conn = sqlite3.connect(db)
    try:
        opened = stage.check(conn, T0 + DAYS * 86400.0).opened
    finally:
        conn.close()
    signals = [f.evidence[0].signal for f in opened]
    assert signals == ([] if recorded else ["residual:x2_c"])


@pytest.mark.parametrize("step_k", [0.0, 1.5])
def test_the_night_check_finds_a_thermocouple_step_on_the_exterior_pane(tmp_path, step_k):
    """Three weeks of 10-min cycles in Suwon: the exterior pane sits 0.5 ± 0.3 K (night to
    night) above the outdoor air, and ``step_k`` more from the 15th night on (a thermocouple
    step). The check runs with the site's night mask once 8 days are stored."""
    db, t = night_database(tmp_path, step_k)
    site = NightSite(**SUWON)
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
