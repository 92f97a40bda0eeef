"""Schema 6 (issue 36): a real schema-5 database, written by dsfd before this step, is
migrated in place: its rows are kept, the occupancy override columns are added (NULL for the
old cycles) and the ``comfort`` table is created and written by the next run."""

from __future__ import annotations

import sqlite3
from pathlib import Path

from dsfd.storage import commands as command_table
from dsfd.storage.timeseries import COMFORT_COLUMNS, SCHEMA_VERSION, CycleRecord, Store

DUMP = Path(__file__).parents[1] / "data" / "timeseries-schema5.sql"


def _schema5_database(path: Path) -> None:
    with sqlite3.connect(path) as conn:
        conn.executescript(DUMP.read_text(encoding="utf-8"))


def _counts(conn: sqlite3.Connection) -> tuple[int, ...]:
    return tuple(conn.execute(f"SELECT COUNT(*) FROM {t}").fetchone()[0]
                 for t in ("runs", "samples", "decisions", "model", "parameters", "events"))


def test_a_schema_5_database_is_migrated_and_keeps_its_rows(tmp_path: Path) -> None:
    db = tmp_path / "timeseries.sqlite"
    _schema5_database(db)
    with sqlite3.connect(db) as conn:
        assert conn.execute("SELECT value FROM meta WHERE key = 'schema_version'"
                            ).fetchone() == ("5",)
        before = _counts(conn)
        decisions_before = conn.execute("SELECT * FROM decisions ORDER BY cycle").fetchall()
        assert not conn.execute("SELECT name FROM sqlite_master WHERE name = 'comfort'"
                                ).fetchall()
    assert before[1:3] == (39, 3)  # 13 signals x 3 cycles, 3 decisions

    store = Store.open(tmp_path)
    assert store.moved_aside is None
    conn = store.conn
    meta = dict(conn.execute("SELECT key, value FROM meta"))
    assert meta["schema_version"] == str(SCHEMA_VERSION) and "migrated_to_6" in meta
    assert _counts(conn) == before
    # the old decisions are unchanged in their old columns, NULL in the new ones
    rows = conn.execute("SELECT * FROM decisions ORDER BY cycle").fetchall()
    old_width = len(decisions_before[0])
    assert [r[:old_width] for r in rows] == decisions_before
    assert {r[old_width:] for r in rows} == {(None, None, None)}
    names = [r[1] for r in conn.execute("PRAGMA table_info(decisions)")][old_width:]
    assert names == ["occupancy_override", "occupancy_until_s", "occupancy_command_id"]
    comfort_cols = [r[1] for r in conn.execute("PRAGMA table_info(comfort)")]
    assert comfort_cols == ["run_id", "cycle", "time_s", *(c for c, _ in COMFORT_COLUMNS)]

    # the next run writes both on the migrated file
    store.begin_run(panel="suwon-south", mode="test", version="0", config_path=None)
    cid = command_table.submit(store.path, kind="occupancy",
                               args={"state": "occupied", "until": "18:00"}, source="cli",
                               requester="a@b")
    t = 1.7e9
    store.append(CycleRecord(
        cycle=1, time_s=t, samples=[("occupied", 1.0, "good", "")],
        decision={"slot": 1, "time_s": t, "time_utc": "t", "method": "mpc", "phi_deg": 0.0,
                  "afr": 10, "or_pct": 0.0, "write_status": "dry-run", "cycle_ms": 1.0,
                  "occupancy_override": "occupied", "occupancy_until_s": t + 3600,
                  "occupancy_command_id": cid},
        comfort={"occupied": True, "occupancy_source": "override", "direct_sun_wm2": 0.0,
                 "dgp": 0.21, "supply_air_c": None, "asymmetry_k": -1.5,
                 "direct_sun_max_wm2": 5.0, "dgp_max": 0.35, "supply_air_min_c": 17.4,
                 "asymmetry_max_k": 10.0, "violations": []},
        command_results=[(cid, "applied", "occupancy occupied until …")]))
    run = store.run_id
    assert conn.execute("SELECT occupancy_override, occupancy_until_s, occupancy_command_id "
                        "FROM decisions WHERE run_id = ?", (run,)).fetchone() == (
        "occupied", t + 3600, cid)
    assert conn.execute("SELECT occupied, occupancy_source, dgp, supply_air_c, violations "
                        "FROM comfort WHERE run_id = ?", (run,)).fetchone() == (
        1, "override", 0.21, None, "[]")
    assert command_table.outcome(conn, cid).status == "applied"
    assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    store.close()
