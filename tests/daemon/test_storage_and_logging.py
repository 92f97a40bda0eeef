"""The time-series store (schema, pragmas, documentation) and the logging set-up."""

from __future__ import annotations

import asyncio
import io
import json
import logging
import re
import shutil
import sqlite3
import subprocess
from pathlib import Path

import pytest

from dsfd.daemon.logging_setup import (
    bind_contextvars,
    bound_contextvars,
    clear_contextvars,
    configure_logging,
    get_logger,
)
from dsfd.storage.timeseries import CycleRecord, Store
from tests.daemon.harness import ROOT

SCHEMA_DOC = ROOT / "docs" / "storage-schema.md"


def record(cycle: int) -> CycleRecord:
    return CycleRecord(
        cycle=cycle, time_s=1.6e9 + 60 * cycle,
        samples=[("x1_c", 20.5, "good", ""), ("t_out_c", None, "timeout", "io: no response")],
        decision={"slot": cycle, "time_s": 1.6e9 + 60 * cycle, "time_utc": "x",
                  "method": "rule", "phi_deg": 18.0, "afr": 10, "or_pct": 0.0,
                  "write_status": "verified", "trace": [{"stage": "faults", "set": {},
                                                         "why": "no fault"}],
                  "timings_ms": {"read": 1.0}, "cycle_ms": 3.0},
        parameters=("prior", {"h_out": 12.0, "q_x1": 0.0}, None, "first"),
        events=[("warning", "sensor_fault", "t_out_c: timeout")])


def test_store_is_wal_with_normal_sync_and_one_transaction_per_cycle(tmp_path: Path) -> None:
    store = Store.open(tmp_path)
    assert store.conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert store.conn.execute("PRAGMA synchronous").fetchone()[0] == 1  # NORMAL
    assert store.conn.execute("PRAGMA busy_timeout").fetchone()[0] >= 1000
    run = store.begin_run(panel="p", mode="test", version="0", config_path=None)
    store.append(record(1))
    with pytest.raises(sqlite3.IntegrityError):
        store.append(record(1))  # a duplicate cycle: the whole transaction is rolled back
    assert store.conn.execute("SELECT COUNT(*) FROM events").fetchone()[0] == 1
    store.end_run(reason="test", cycles=1)
    store.close()
    conn = sqlite3.connect(tmp_path / "timeseries.sqlite")
    (trace, other), = conn.execute("SELECT d.trace, p.other FROM decisions d JOIN parameters "
                                   "p USING (run_id, cycle) WHERE run_id = ?", (run,))
    assert json.loads(trace)[0]["why"] == "no fault" and json.loads(other) == {"q_x1": 0.0}
    assert conn.execute("SELECT value FROM samples WHERE signal = 't_out_c'").fetchone() == (
        None,)


@pytest.mark.skipif(shutil.which("sqlite3") is None, reason="sqlite3 shell not installed")
def test_store_is_readable_with_the_sqlite3_shell(tmp_path: Path) -> None:
    store = Store.open(tmp_path)
    store.begin_run(panel="p", mode="test", version="0", config_path=None)
    store.append(record(1))
    out = subprocess.run(["sqlite3", str(tmp_path / "timeseries.sqlite"),
                          "SELECT method, phi_deg FROM decisions"], capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "rule|18.0"
    store.close()


def test_every_table_and_column_is_documented(tmp_path: Path) -> None:
    store = Store.open(tmp_path)
    doc = SCHEMA_DOC.read_text()
    tables = [t for (t,) in store.conn.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'")]
    for table in tables:
        assert re.search(rf"^### `{table}`", doc, re.MULTILINE), table
        for _, column, *_ in store.conn.execute(f"PRAGMA table_info({table})"):
            assert f"`{column}`" in doc, f"{table}.{column} not in {SCHEMA_DOC.name}"
    store.close()


def test_log_lines_carry_panel_and_cycle_also_from_stdlib_and_worker_threads() -> None:
    stream = io.StringIO()
    configure_logging(stream=stream, json=True, pymodbus_level=logging.WARNING)
    clear_contextvars()
    bind_contextvars(panel="suwon-south")
    log = get_logger("dsfd.test")

    async def cycle() -> None:
        with bound_contextvars(cycle=7):
            log.info("cycle", method="mpc")
            logging.getLogger("pymodbus.logging").warning("Failed to connect %s", "io")
            await asyncio.to_thread(lambda: get_logger("dsfd.worker").info("in a thread"))

    try:
        asyncio.run(cycle())
    finally:
        clear_contextvars()
        configure_logging(stream=io.StringIO(), json=True)
    lines = [json.loads(line) for line in stream.getvalue().splitlines()]
    assert [(r["event"], r["panel"], r["cycle"]) for r in lines] == [
        ("cycle", "suwon-south", 7), ("Failed to connect io", "suwon-south", 7),
        ("in a thread", "suwon-south", 7)]
    assert lines[1]["logger"] == "pymodbus.logging" and lines[1]["level"] == "warning"
    assert all("timestamp" in r for r in lines)


def test_console_output_on_a_terminal_is_not_json() -> None:
    stream = io.StringIO()
    configure_logging(stream=stream, json=False)
    get_logger("dsfd.test").info("hello", cycle=3)
    configure_logging(stream=io.StringIO(), json=True)
    text = stream.getvalue()
    assert "hello" in text and not text.lstrip().startswith("{")
