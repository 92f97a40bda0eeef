"""Schema 8 (issue 38): a real schema-7 database, written by ``dsfd run`` before this step
(two on-line calibration updates), is migrated in place: its rows are kept as they were, the
``parameters`` table gains the posterior sd columns (NULL in the old rows), a cycle written
after the migration stores its sds, and the parameter detector leaves the old rows (no sd)
alone instead of judging them."""

from __future__ import annotations

import sqlite3
from pathlib import Path

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.daemon.findings import detect
from dsfd.storage.timeseries import PARAMETER_SD_COLUMNS, SCHEMA_VERSION, CycleRecord, Store

DUMP = Path(__file__).parents[1] / "data" / "timeseries-schema7.sql"
TABLES = ("runs", "samples", "decisions", "model", "parameters", "events", "comfort",
          "findings")


def _counts(conn: sqlite3.Connection) -> tuple[int, ...]:
    return tuple(conn.execute(f"SELECT COUNT(*) FROM {t}").fetchone()[0] for t in TABLES)


def _parameters(conn: sqlite3.Connection) -> list[tuple]:
    return conn.execute(f"SELECT run_id, cycle, time_s, source, {', '.join(PARAMETER_NAMES)}, "
                        "other, cost, detail FROM parameters ORDER BY run_id, cycle").fetchall()


def test_a_schema_7_database_is_migrated_and_keeps_its_parameter_history(tmp_path):
    db = tmp_path / "timeseries.sqlite"
    with sqlite3.connect(db) as old:
        old.executescript(DUMP.read_text(encoding="utf-8"))
        assert old.execute("SELECT value FROM meta WHERE key = 'schema_version'"
                           ).fetchone() == ("7",)
        before, history = _counts(old), _parameters(old)
        columns = [r[1] for r in old.execute("PRAGMA table_info(parameters)")]
    assert [h[3] for h in history] == ["prior", "online", "online"]
    assert not set(PARAMETER_SD_COLUMNS) & set(columns)

    store = Store.open(tmp_path)
    conn = store.conn
    meta = dict(conn.execute("SELECT key, value FROM meta"))
    assert SCHEMA_VERSION == 8 and meta["schema_version"] == "8" and "migrated_to_8" in meta
    assert _counts(conn) == before and _parameters(conn) == history
    sds = conn.execute(f"SELECT {', '.join(PARAMETER_SD_COLUMNS)} FROM parameters").fetchall()
    assert sds == [(None,) * len(PARAMETER_SD_COLUMNS)] * len(history)

    # the old on-line rows have no sd: the parameter detector has nothing to judge them by
    now = history[-1][2] + 30 * 86400.0
    _, judged = detect(conn, now)
    assert "parameter_shift" not in judged

    # a cycle written on the migrated file stores its sds; the old rows stay NULL
    store.begin_run(panel="suwon-south", mode="test", version="0", config_path=None)
    t = history[-1][2] + 600.0
    theta = {name: 1.0 + i for i, name in enumerate(PARAMETER_NAMES)}
    sd = {name: 0.01 * (i + 1) for i, name in enumerate(PARAMETER_NAMES)}
    store.append(CycleRecord(cycle=1, time_s=t, samples=[], decision={
        "slot": 1, "time_s": t, "time_utc": "t", "method": "mpc", "phi_deg": 0.0, "afr": 10,
        "or_pct": 0.0, "write_status": "verified", "cycle_ms": 1.0},
        parameters=("online", theta, 1.0, "9 residuals"), parameter_sd=sd))
    new = conn.execute(f"SELECT {', '.join(PARAMETER_SD_COLUMNS)} FROM parameters "
                       "WHERE run_id = ?", (store.run_id,)).fetchone()
    assert new == tuple(sd[name] for name in PARAMETER_NAMES)
    assert _parameters(conn)[:len(history)] == history
    assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    store.close()
