"""Schema 7 (issue 38): a real schema-6 database, written by ``dsfd run`` before this step,
is migrated in place (its rows kept, the ``findings`` table added); on the migrated file the
findings go through their life in SQL: opened, refreshed, acknowledged by an operator's
command, kept closed for the same evidence, opened again by evidence that starts later, and
ended when the evidence goes."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.lifecycle import reconcile
from dsfd.storage import findings as table
from dsfd.storage.timeseries import SCHEMA_VERSION, Store

DUMP = Path(__file__).parents[1] / "data" / "timeseries-schema6.sql"
TABLES = ("runs", "samples", "decisions", "model", "parameters", "events", "comfort")


def _counts(conn: sqlite3.Connection) -> tuple[int, ...]:
    return tuple(conn.execute(f"SELECT COUNT(*) FROM {t}").fetchone()[0] for t in TABLES)


def _stuck(start_s: float) -> Finding:
    ev = Evidence(signal="crosscheck:v_cav_ms[IB+IT]", shift=-0.03, shift_sd=float("nan"),
                  unit="m/s", since_s=start_s, statistic=0.001, threshold=0.02)
    return Finding(kind="damper_no_flow", confidence=0.8, start_s=start_s,
                   detected_s=start_s + 1800, evidence=(ev,), action="check damper IT",
                   subject="IT")


def _check(conn: sqlite3.Connection, detected: list[Finding], now_s: float) -> list[int]:
    return table.apply(conn, reconcile(detected, table.load(conn)), now_s=now_s, run_id=2)


def _states(conn: sqlite3.Connection) -> list[tuple[int, str]]:
    return conn.execute("SELECT finding_id, state FROM findings ORDER BY finding_id").fetchall()


def test_a_schema_6_database_is_migrated_and_the_findings_live_in_it(tmp_path: Path) -> None:
    db = tmp_path / "timeseries.sqlite"
    with sqlite3.connect(db) as old:
        old.executescript(DUMP.read_text(encoding="utf-8"))
        assert old.execute("SELECT value FROM meta WHERE key = 'schema_version'"
                           ).fetchone() == ("6",)
        before = _counts(old)
        assert not old.execute("SELECT name FROM sqlite_master WHERE name = 'findings'"
                               ).fetchall()
    assert before[1:3] == (39, 3)  # 13 signals x 3 cycles, 3 decisions

    store = Store.open(tmp_path)
    conn = store.conn
    meta = dict(conn.execute("SELECT key, value FROM meta"))
    assert meta["schema_version"] == str(SCHEMA_VERSION) and "migrated_to_7" in meta
    assert _counts(conn) == before
    assert table.open_findings(conn) == []

    t0 = 1.7e9
    [first] = _check(conn, [_stuck(t0)], now_s=t0 + 1800)
    assert _check(conn, [_stuck(t0)], now_s=t0 + 2400) == []  # refreshed, not reopened
    [row] = table.open_findings(conn)
    assert (row["finding_id"], row["subject"], row["last_seen_s"]) == (first, "IT", t0 + 2400)
    assert row["evidence"][0]["signal"] == "crosscheck:v_cav_ms[IB+IT]"
    assert row["evidence"][0]["shift_sd"] is None  # NaN is no JSON number

    # an operator acknowledges it: closed, and the same evidence keeps it closed
    assert table.acknowledge(conn, first, command_id=7, now_s=t0 + 3000, who="a@b")[0] == \
        "applied"
    assert table.acknowledge(conn, first, command_id=8, now_s=t0 + 3001, who="a@b")[0] == \
        "rejected"  # no longer open
    assert table.acknowledge(conn, 999, command_id=9, now_s=t0 + 3002, who="a@b") == (
        "rejected", "finding: 999: no such finding")
    for now in (t0 + 3600, t0 + 4200):
        assert _check(conn, [_stuck(t0 + 600)], now_s=now) == []
    assert _states(conn) == [(first, "acknowledged")]
    assert table.open_findings(conn) == []

    # evidence that starts after the acknowledgement opens a new finding; it ends when the
    # evidence goes away
    [second] = _check(conn, [_stuck(t0 + 3500)], now_s=t0 + 5400)
    assert _check(conn, [], now_s=t0 + 6000) == []
    assert _states(conn) == [(first, "acknowledged"), (second, "ended")]
    ended = conn.execute("SELECT ended_s, end_reason, evidence FROM findings WHERE "
                         "finding_id = ?", (second,)).fetchone()
    assert ended[:2] == (t0 + 6000, "the evidence went away") and json.loads(ended[2])
    assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    store.close()
