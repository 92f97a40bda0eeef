"""Persistence in the state directory: the SQLite time-series store and atomic JSON files.

``timeseries.sqlite`` (schema: ``docs/storage-schema.md``) holds every sample with its quality
flag, every decision with its safety trace and stage timings, the parameter history and
notable events. One writer (the daemon), WAL journal, ``synchronous=NORMAL`` (a crash of the
process never loses a committed cycle; a power cut may roll back the last few), and a
``busy_timeout`` so a reader (``sqlite3``, pandas) never makes a write fail. Each cycle is
one transaction. The daemon writes through :attr:`Store.buffer`
(:class:`~dsfd.storage.buffer.WriteBuffer`): a write that fails (full disk) keeps the cycle
waiting in memory instead of stopping control.

A database that cannot be opened or fails its check (after a run that did not end cleanly)
is moved aside with its ``-wal``/``-shm`` files as ``timeseries.sqlite.corrupt.<iso>`` and a
new one is started: the controller must keep running, and the old file stays for inspection.

The schema, its migrations and the checked opening of the file are
:mod:`dsfd.storage.schema` (its names are re-exported here). The calibration state
(``calibration.json``) is written atomically by :mod:`dsfd.storage.calibration_file`.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import sqlite3
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.storage.buffer import WriteBuffer
from dsfd.storage.schema import (
    BUSY_TIMEOUT_MS,
    COMFORT_COLUMNS,
    DB_NAME,
    HEAT_TERMS,
    MIGRATIONS,
    MODEL_COLUMNS,
    MQTT_CURSOR_TABLE,
    PARAMETER_SD_COLUMNS,
    SCHEMA_VERSION,
    SchemaTooNewError,
    connect_checked,
    insert_meta,
    iso_now,
    move_aside,
)

__all__ = [
    "BUSY_TIMEOUT_MS",
    "COMFORT_COLUMNS",
    "DB_NAME",
    "HEAT_TERMS",
    "MIGRATIONS",
    "MODEL_COLUMNS",
    "MQTT_CURSOR_TABLE",
    "PARAMETER_SD_COLUMNS",
    "SCHEMA_VERSION",
    "CycleRecord",
    "LateEvent",
    "SchemaTooNewError",
    "Store",
    "iso_now",
]


def _num(value: float | None) -> float | None:
    """SQL value of a number: NULL for None/NaN/inf."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


@dataclass(frozen=True)
class CycleRecord:
    """Everything one cycle stores, committed in one transaction.

    ``samples``: (signal, value or None, quality, detail); ``decision``: column → value of the
    ``decisions`` table; ``parameters``: (source, estimate by name, cost, detail) when the
    parameters changed this cycle (names beyond θ, e.g. the calibrator's heat-flux offsets,
    go into the JSON column ``other``); ``events``: (level, kind, message); ``model``: column
    → value of the ``model`` table (:data:`MODEL_COLUMNS`; absent ones are NULL);
    ``command_results``: (command_id, status, reason) of the operator commands this cycle
    handled (``applied`` or ``rejected``); ``comfort``: column → value of the ``comfort``
    table (:data:`COMFORT_COLUMNS`, schema 6); ``parameter_sd``: the posterior sd of the
    ``parameters`` row's θ by parameter name, in the fitting coordinates (the columns
    :data:`PARAMETER_SD_COLUMNS`, schema 8; absent ones are NULL).
    """

    cycle: int
    time_s: float
    samples: Sequence[tuple[str, float | None, str, str]]
    decision: Mapping[str, Any]
    parameters: tuple[str, Mapping[str, float], float | None, str] | None = None
    events: Sequence[tuple[str, str, str]] = field(default_factory=tuple)
    model: Mapping[str, float | int | None] | None = None
    command_results: Sequence[tuple[int, str, str]] = field(default_factory=tuple)
    comfort: Mapping[str, Any] | None = None
    parameter_sd: Mapping[str, float] | None = None


#: An event recorded outside its own cycle: (cycle, time_s, level, kind, message).
LateEvent = tuple[int, float, str, str, str]


class Store:
    """The time-series database of one panel (one writer: the daemon)."""

    def __init__(self, path: Path, conn: sqlite3.Connection, *, moved_aside: Path | None,
                 buffer_cycles: int = 720) -> None:
        self.path = path
        self.conn = conn
        #: Where a corrupt database was moved at open, if it was.
        self.moved_aside = moved_aside
        self.run_id: int | None = None
        #: The daemon's path into the database: cycles wait here while writes fail.
        self.buffer = WriteBuffer(self.append, capacity=buffer_cycles)
        self._reader: sqlite3.Connection | None = None

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(cls, state_dir: Path, *, buffer_cycles: int = 720) -> Store:
        """Open (or create) ``state_dir/timeseries.sqlite``; move a corrupt one aside.

        ``buffer_cycles``: cycles kept in memory while the database cannot be written
        (:class:`~dsfd.storage.buffer.WriteBuffer`).
        """
        state_dir.mkdir(parents=True, exist_ok=True)
        path = state_dir / DB_NAME
        moved: Path | None = None
        try:
            conn = connect_checked(path)
        except sqlite3.DatabaseError as exc:
            moved = move_aside(path)
            conn = connect_checked(path)
            insert_meta(conn, "recovered_from", f"{moved.name}: {exc}")
        return cls(path, conn, moved_aside=moved, buffer_cycles=buffer_cycles)

    def begin_run(self, *, panel: str, mode: str, version: str, config_path: str | None,
                  config: Mapping[str, Any] | None = None) -> int:
        """Record the start of a daemon run; returns its ``run_id``.

        ``config`` is the panel configuration as a mapping (``dataclasses.asdict``), kept as
        JSON so that a report knows the site, the bounds and the horizon of the run.
        """
        with self.conn:
            cur = self.conn.execute(
                "INSERT INTO runs (panel, mode, started_utc, pid, version, config_path, "
                "config_json) VALUES (?, ?, ?, ?, ?, ?, ?)",
                (panel, mode, iso_now(), os.getpid(), version, config_path,
                 None if config is None else _sql(dict(config))))
        self.run_id = int(cur.lastrowid or 0)
        return self.run_id

    def end_run(self, *, reason: str, cycles: int) -> None:
        """Mark the run as cleanly ended (the next start then skips the integrity check).

        Cycles still waiting in the buffer are written first; a run whose rows could not all
        be written is left unmarked, so the next start checks the database."""
        if self.run_id is None or not self.buffer.flush(wait_s=10.0) or self.buffer.waiting:
            return
        with self.conn:
            self.conn.execute("UPDATE runs SET ended_utc = ?, end_reason = ?, cycles = ? "
                              "WHERE run_id = ?", (iso_now(), reason, cycles, self.run_id))

    # ------------------------------------------------------------------ writing
    def append(self, rec: CycleRecord, late_events: Sequence[LateEvent] = ()) -> None:
        """Write one cycle atomically (all rows or none), with ``late_events`` recorded
        earlier outside a cycle while the database could not be written."""
        run = self.run_id
        if run is None:
            raise RuntimeError("begin_run() first")
        with self.conn:
            self.conn.executemany(
                "INSERT INTO samples (run_id, cycle, time_s, signal, value, quality, detail) "
                "VALUES (?, ?, ?, ?, ?, ?, ?)",
                [(run, rec.cycle, rec.time_s, name, _num(value), quality, detail)
                 for name, value, quality, detail in rec.samples])
            cols = list(rec.decision)
            self.conn.execute(
                f"INSERT INTO decisions (run_id, cycle, {', '.join(cols)}) "
                f"VALUES (?, ?, {', '.join('?' for _ in cols)})",
                (run, rec.cycle, *(_sql(rec.decision[c]) for c in cols)))
            if rec.parameters is not None:
                source, theta, cost, detail = rec.parameters
                other = {k: v for k, v in theta.items() if k not in PARAMETER_NAMES}
                sd = rec.parameter_sd or {}
                cols = [*PARAMETER_NAMES, "other", "cost", "detail", *PARAMETER_SD_COLUMNS]
                self.conn.execute(
                    f"INSERT INTO parameters (run_id, cycle, time_s, source, {', '.join(cols)}) "
                    f"VALUES (?, ?, ?, ?, {', '.join('?' for _ in cols)})",
                    (run, rec.cycle, rec.time_s, source,
                     *(_num(theta.get(n)) for n in PARAMETER_NAMES), _sql(other), _num(cost),
                     detail, *(_num(sd.get(n)) for n in PARAMETER_NAMES)))
            if rec.model is not None:
                self._row("model", run, rec, rec.model, MODEL_COLUMNS)
            if rec.comfort is not None:
                self._row("comfort", run, rec, rec.comfort, COMFORT_COLUMNS)
            self._events(run, rec.cycle, rec.time_s, rec.events)
            for cycle, time_s, level, kind, message in late_events:
                self._events(run, cycle, time_s, [(level, kind, message)])
            self.conn.executemany(
                "UPDATE commands SET status = ?, reason = ?, run_id = ?, cycle = ?, "
                "handled_utc = ? WHERE command_id = ? AND status = 'pending'",
                [(status, reason, run, rec.cycle, iso_now(), command_id)
                 for command_id, status, reason in rec.command_results])

    def _row(self, table: str, run: int, rec: CycleRecord, values: Mapping[str, Any],
             known: Sequence[tuple[str, str]]) -> None:
        """One row of a per-cycle table: the given columns of ``known``, the rest NULL."""
        cols = ["run_id", "cycle", "time_s", *(c for c, _ in known if c in values)]
        self.conn.execute(f"INSERT INTO {table} ({', '.join(cols)}) "
                          f"VALUES ({', '.join('?' for _ in cols)})",
                          (run, rec.cycle, rec.time_s, *(_sql(values[c]) for c in cols[3:])))

    def event(self, *, cycle: int, time_s: float, level: str, kind: str, message: str) -> None:
        """Record one event outside a cycle (start-up, reload, stop); if the database cannot
        be written now, it goes in with the next cycle that can be."""
        if self.run_id is None:
            return
        try:
            with self.conn:
                self._events(self.run_id, cycle, time_s, [(level, kind, message)])
        except sqlite3.Error:
            self.buffer.add_late_event((cycle, time_s, level, kind, message))

    def _events(self, run: int, cycle: int, time_s: float,
                events: Iterable[tuple[str, str, str]]) -> None:
        self.conn.executemany(
            "INSERT INTO events (run_id, cycle, time_s, level, kind, message) "
            "VALUES (?, ?, ?, ?, ?, ?)",
            [(run, cycle, time_s, level, kind, msg) for level, kind, msg in events])

    # ------------------------------------------------------------------ reading
    def reader(self) -> sqlite3.Connection:
        """A second connection for reads in the loop thread (WAL: never waits for the
        writer, which may be busy in the store's worker thread)."""
        if self._reader is None:
            self._reader = sqlite3.connect(self.path, timeout=1.0, check_same_thread=False)
        return self._reader

    def close(self) -> None:
        for conn in (self._reader, self.conn):
            if conn is not None:
                with contextlib.suppress(sqlite3.Error):
                    conn.close()


def _sql(value: Any) -> Any:
    if isinstance(value, float):
        return _num(value)
    if isinstance(value, list | tuple | dict):
        return json.dumps(value, separators=(",", ":"), default=str)
    if isinstance(value, bool):
        return int(value)
    return value
