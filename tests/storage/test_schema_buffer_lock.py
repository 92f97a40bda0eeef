"""The store's schema 2 migration from a real version-1 database, the write buffer's
accounting, the state-directory lock and the command table."""

from __future__ import annotations

import multiprocessing
import sqlite3
from pathlib import Path

import pytest

from dsfd.storage import commands as command_table
from dsfd.storage.buffer import WriteBuffer
from dsfd.storage.lock import StateDirBusyError, StateLock, lock_holder
from dsfd.storage.timeseries import SCHEMA_VERSION, CycleRecord, Store
from tests.conftest import DATA

V1_DUMP = DATA / "timeseries-schema1.sql"  # a real schema-1 database (3 cycles), dumped


def version_1_database(path: Path) -> None:
    """The database dsfd wrote before schema 2, as a file again."""
    with sqlite3.connect(path) as conn:
        conn.executescript(V1_DUMP.read_text())


def record(cycle: int, **decision: object) -> CycleRecord:
    return CycleRecord(cycle=cycle, time_s=1.6e9 + 60 * cycle, samples=[],
                       decision={"slot": cycle, "time_s": 1.6e9 + 60 * cycle, "time_utc": "t",
                                 "method": "mpc", "phi_deg": 0.0, "afr": 10, "or_pct": 0.0,
                                 "write_status": "verified", "cycle_ms": 1.0, **decision})


def test_a_version_1_database_is_migrated_in_place_and_keeps_its_rows(tmp_path: Path) -> None:
    version_1_database(tmp_path / "timeseries.sqlite")
    store = Store.open(tmp_path)
    assert store.moved_aside is None
    meta = dict(store.conn.execute("SELECT key, value FROM meta"))
    assert meta["schema_version"] == str(SCHEMA_VERSION) == "8"
    assert {"migrated_to_2", "migrated_to_3", "migrated_to_4", "migrated_to_5",
            "migrated_to_6", "migrated_to_7", "migrated_to_8"} <= set(meta)
    old = store.conn.execute("SELECT COUNT(*), COUNT(hold_source), COUNT(hold_expires_s), "
                             "COUNT(hold_command_id), COUNT(run_elapsed_s), "
                             "COUNT(objective_mode), COUNT(mode_command_id) FROM decisions"
                             ).fetchone()
    assert old == (3, 0, 0, 0, 0, 0, 0)  # the old rows are kept, the new columns NULL
    # The new columns and the commands table work on the migrated file.
    store.begin_run(panel="p", mode="test", version="0", config_path=None)
    cid = command_table.submit(store.path, kind="override", args={"hold": "2h"},
                               source="cli", requester="a@b")
    store.append(CycleRecord(**{**record(1, hold_source="operator", hold_expires_s=1.7e9,
                                         hold_command_id=cid, run_elapsed_s=0.0,
                                         objective_mode="cooling", mode_command_id=cid
                                         ).__dict__,
                                "command_results": [(cid, "applied", "held")]}))
    new_run = store.run_id
    row = store.conn.execute("SELECT hold_source, hold_command_id, objective_mode, "
                             "mode_command_id FROM decisions WHERE run_id = ?", (new_run,)
                             ).fetchone()
    assert row == ("operator", cid, "cooling", cid)
    done = command_table.outcome(store.conn, cid)
    assert (done.status, done.reason, done.run_id, done.cycle) == ("applied", "held", new_run, 1)
    assert store.conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    store.close()


def test_the_buffer_keeps_order_counts_what_it_drops_and_accounts_once(tmp_path: Path) -> None:
    written: list[int] = []
    accounts: list[tuple[int, list[tuple[str, str, str]]]] = []
    failing = {"on": True}

    def write(rec: CycleRecord, late: object) -> None:
        if failing["on"]:
            raise sqlite3.OperationalError("database or disk is full")
        written.append(rec.cycle)
        if rec.events:
            accounts.append((rec.cycle, list(rec.events)))

    buf = WriteBuffer(write, capacity=3)
    for c in range(1, 7):
        buf.enqueue(record(c))
        assert buf.flush() is False
    assert buf.waiting == 3 and buf.failure == (1, "OperationalError: database or disk is full")
    failing["on"] = False
    buf.enqueue(record(7))  # the fourth waiting record pushes out cycle 4
    assert buf.flush() is True and buf.waiting == 0
    assert written == [5, 6, 7]  # in order; 1..4 were dropped (capacity 3)
    (cycle, events), = accounts  # the account rides on the first record written
    assert cycle == 5
    kinds = {kind: msg for _, kind, msg in events}
    assert "from cycle 1" in kinds["store_recovered"] and "3 cycle(s)" in kinds["store_recovered"]
    assert kinds["store_rows_lost"].startswith("4 cycle(s) could not be kept")
    assert "cycles 1-4 of this run" in kinds["store_rows_lost"]
    assert buf.lost_total == 4 and buf.failure is None
    buf.enqueue(record(8))
    assert buf.flush() and written[-1] == 8 and len(accounts) == 1  # accounted once


def _hold_lock(state: str, ready: multiprocessing.Event, done: multiprocessing.Event) -> None:
    lock = StateLock.acquire(Path(state))
    ready.set()
    done.wait(30)
    lock.release()


def test_the_lock_names_its_holder_and_dies_with_it(tmp_path: Path) -> None:
    ctx = multiprocessing.get_context("spawn")
    ready, done = ctx.Event(), ctx.Event()
    holder = ctx.Process(target=_hold_lock, args=(str(tmp_path), ready, done))
    holder.start()
    try:
        assert ready.wait(30)
        assert lock_holder(tmp_path) == holder.pid
        with pytest.raises(StateDirBusyError) as err:
            StateLock.acquire(tmp_path)
        assert err.value.pid == holder.pid and f"PID {holder.pid}" in str(err.value)
        assert (tmp_path / "dsfd.lock").read_text().strip() == str(holder.pid)
    finally:
        holder.kill()  # no release: the kernel drops the lock with the process
        holder.join(30)
    assert lock_holder(tmp_path) is None
    StateLock.acquire(tmp_path).release()
