"""The schema step that adds the MQTT delivery cursor migrates an older database in place.

(Written when that step was 1 → 2, the newest; if later steps follow it, undo those too.)
"""

from __future__ import annotations

import sqlite3
from pathlib import Path

from dsfd.storage.timeseries import MIGRATIONS, PARAMETER_SD_COLUMNS, SCHEMA_VERSION, Store


def test_a_schema_1_database_is_migrated_and_keeps_its_rows(tmp_path: Path) -> None:
    store = Store.open(tmp_path)
    store.begin_run(panel="p", mode="test", version="0", config_path=None)
    store.end_run(reason="test", cycles=0)
    store.close()
    db = tmp_path / "timeseries.sqlite"
    step = next(v for v, sql in MIGRATIONS.items() if "mqtt_cursor" in sql)
    assert SCHEMA_VERSION == step + 6  # six later steps, undone below (see the docstring)
    with sqlite3.connect(db) as conn:  # what the dsfd before this step left behind
        conn.execute("DROP TABLE mqtt_cursor")
        conn.execute("DROP TABLE model")  # step 3 (issue 21): the model table ...
        conn.execute("ALTER TABLE runs DROP COLUMN config_json")  # ... and the run's config
        conn.execute("DROP TABLE commands")  # step 4 (issue 20): the command table ...
        conn.execute("DROP TABLE comfort")  # step 6 (issue 36): comfort, occupancy override
        conn.execute("DROP TABLE findings")  # step 7 (issue 38): the diagnostics' findings
        for column in PARAMETER_SD_COLUMNS:  # step 8 (issue 38): the posterior sd of θ
            conn.execute(f"ALTER TABLE parameters DROP COLUMN {column}")
        for column in ("hold_source", "hold_expires_s", "hold_command_id", "run_elapsed_s",
                       "objective_mode", "mode_command_id", "occupancy_override",
                       "occupancy_until_s", "occupancy_command_id"):  # ... holds; step 5
            conn.execute(f"ALTER TABLE decisions DROP COLUMN {column}")  # (issue 22): mode
        conn.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'", (step - 1,))
    Store.open(tmp_path).close()
    with sqlite3.connect(db) as conn:
        meta = dict(conn.execute("SELECT key, value FROM meta"))
        columns = [r[1] for r in conn.execute("PRAGMA table_info(mqtt_cursor)")]
        runs = conn.execute("SELECT panel FROM runs").fetchall()
    assert meta["schema_version"] == str(SCHEMA_VERSION) and f"migrated_to_{step}" in meta
    assert columns[:3] == ["destination", "run_id", "cycle"]
    assert runs == [("p",)]
