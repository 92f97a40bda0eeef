"""The night offsets in the daemon's findings check (dsfd.daemon.findings,
docs/model.md#diagnostics-night-offsets), on three weeks of on-line estimates written by the
daemon's Store in Suwon (tests.daemon.test_parameter_findings): the heat-flux offsets wander
by about 1 W/m² a day. A thermocouple 1 K high on the inner pane (q_x3 +15 W/m² from 15:00
local on the 15th day) is found in the first night after it (never before), as the inner
pane's sensor; the check that ran the night offsets judges their kind, and the stage stores
the finding."""

from __future__ import annotations

import sqlite3

import numpy as np

from dsfd.daemon.findings import (
    NIGHT_OFFSET_EVERY_S,
    NIGHT_OFFSET_MIN_S,
    FindingsStage,
    NightSite,
    detect,
)
from tests.daemon.findings_data import SUWON
from tests.daemon.test_parameter_findings import DAY, MIDNIGHT, SHIFT_AT, _parameter_history

SITE = NightSite(**SUWON)


def _night_findings(conn: sqlite3.Connection, now_s: float):
    found, judged = detect(conn, now_s, residuals=False, parameters=False, night_offsets=SITE)
    return [f for f in found if f.kind == "night_offset_shift"], judged


def test_a_thermocouple_reading_high_is_found_in_the_first_night_after_it(tmp_path):
    db = _parameter_history(tmp_path, shift={"q_x3": 15.0})
    conn = sqlite3.connect(db)
    try:
        # the first rows are at noon of day 0: 4 days of history from noon of day 4
        early, judged = _night_findings(conn, MIDNIGHT + 4.4 * DAY)
        assert NIGHT_OFFSET_MIN_S == 4 * DAY and not early
        assert "night_offset_shift" not in judged
        hourly = np.arange(MIDNIGHT + 4.6 * DAY, SHIFT_AT + DAY, NIGHT_OFFSET_EVERY_S)
        first = None
        for now in hourly:
            found, judged = _night_findings(conn, now)
            assert "night_offset_shift" in judged
            if now < SHIFT_AT:
                assert not found, now  # clean nights: nothing, and nothing before the change
            elif found and first is None:
                first = (now, found)
        assert first is not None
        now, (f,) = first
        # 15:00 local: the next night starts about 20:00 local; found in its first hours
        assert SHIFT_AT < f.detected_s <= now <= SHIFT_AT + 12 * 3600.0
        assert f.evidence[0].signal == "night:q_x3"
        assert f.evidence[0].shift > 5.0 and "sensor x3" in f.action
        stored = FindingsStage(db, run_id=lambda: 1, night=SITE).check(conn, now)
        assert [(g.kind, g.evidence[0].signal) for g in stored.opened
                if g.kind == "night_offset_shift"] == [("night_offset_shift", "night:q_x3")]
    finally:
        conn.close()


def test_without_the_site_the_night_offsets_are_not_judged(tmp_path):
    db = _parameter_history(tmp_path, shift={"q_x3": 15.0})
    conn = sqlite3.connect(db)
    try:
        found, judged = detect(conn, SHIFT_AT + DAY, residuals=False, parameters=False)
    finally:
        conn.close()
    assert "night_offset_shift" not in judged
    assert not [f for f in found if f.kind == "night_offset_shift"]
