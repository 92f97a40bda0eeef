"""The model table and runs.config_json (schema 3, issue 21): a real schema-1 database is
migrated in place through every step by the daemon's store, and read as it is (never
migrated) by dsfd report and dsfd export."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from dsfd.storage.history import measured_from_history, read_history
from dsfd.storage.timeseries import MODEL_COLUMNS, SCHEMA_VERSION, CycleRecord, Store
from tests.conftest import DATA

DUMP = DATA / "timeseries-schema1.sql"


def schema1_db(state_dir: Path) -> Path:
    """The dump of a database written by dsfd of schema 1, as a file again."""
    state_dir.mkdir(parents=True, exist_ok=True)
    path = state_dir / "timeseries.sqlite"
    conn = sqlite3.connect(path)
    conn.executescript(DUMP.read_text())
    conn.close()
    return path


def test_a_schema1_database_is_migrated_in_place_keeping_every_row(tmp_path):
    path = schema1_db(tmp_path)
    conn = sqlite3.connect(path)
    before = {t: conn.execute(f"SELECT COUNT(*) FROM {t}").fetchone()[0]
              for t in ("runs", "samples", "decisions", "parameters", "events")}
    assert conn.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone() == (
        "1",)
    conn.close()
    assert SCHEMA_VERSION >= 3
    store = Store.open(tmp_path)
    c = store.conn
    assert c.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone() == (
        str(SCHEMA_VERSION),)
    for step in range(2, SCHEMA_VERSION + 1):
        assert c.execute("SELECT COUNT(*) FROM meta WHERE key = ?",
                         (f"migrated_to_{step}",)).fetchone() == (1,)
    for table, n in before.items():
        assert c.execute(f"SELECT COUNT(*) FROM {table}").fetchone()[0] == n, table
    cols = {r[1] for r in c.execute("PRAGMA table_info(model)")}
    assert {name for name, _ in MODEL_COLUMNS} <= cols
    assert c.execute("SELECT config_json FROM runs").fetchall() == [(None,)]
    # The migrated database takes a new run with the new rows.
    run = store.begin_run(panel="suwon-south", mode="test", version="0", config_path=None,
                          config={"site": {"latitude_deg": 37.3}})
    store.append(CycleRecord(
        cycle=1, time_s=1.7e9, samples=[("x1_c", 20.0, "good", "")],
        decision={"slot": 0, "time_s": 1.7e9, "time_utc": "t", "method": "rule",
                  "phi_deg": 0.0, "afr": 10, "or_pct": 0.0, "write_status": "dry-run",
                  "cycle_ms": 1.0},
        model={"est_x1_c": 20.0, "applied_afr": 10, "plant_q_da_j": 5.0}))
    assert c.execute("SELECT est_x1_c, applied_afr, plant_q_da_j, hz_x1_c FROM model WHERE "
                     "run_id = ?", (run,)).fetchall() == [(20.0, 10, 5.0, None)]
    store.close()


def test_reading_a_schema1_database_leaves_it_untouched(tmp_path):
    path = schema1_db(tmp_path)
    history = read_history(tmp_path)
    assert len(history) == 3 and history.schema_version == 1
    assert any("no model predictions" in n for n in history.notes)
    assert np.isnan(history.model["pred_x1_c"]).all()
    # Nothing was migrated by the reader.
    conn = sqlite3.connect(path)
    assert conn.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone() == (
        "1",)
    assert "model" not in {r[0] for r in conn.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table'")}
    conn.close()
    # Schema 1 stored no actuator positions: the export takes the commands that were
    # written and verified (the simulated plant followed them), never a dry run's.
    data = measured_from_history(history)
    assert history.decisions["write_status"].tolist() == ["verified"] * 3
    assert data.columns["afr"].tolist() == history.decisions["afr"].tolist()
    assert np.isfinite(data.columns["x1_c"]).all()
    history.decisions["write_status"][:] = "dry-run"
    assert np.isnan(history.applied()["afr"]).all()


def test_an_empty_state_directory_is_a_clear_error(tmp_path):
    from dsfd.storage.history import HistoryError

    with pytest.raises(HistoryError, match="no database"):
        read_history(tmp_path)
