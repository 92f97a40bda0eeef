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

The calibration state (``calibration.json``) is written atomically by
:mod:`dsfd.storage.calibration_file`.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import sqlite3
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.storage.buffer import WriteBuffer

__all__ = [
    "DB_NAME",
    "MIGRATIONS",
    "MODEL_COLUMNS",
    "MQTT_CURSOR_TABLE",
    "SCHEMA_VERSION",
    "CycleRecord",
    "LateEvent",
    "SchemaTooNewError",
    "Store",
]

DB_NAME = "timeseries.sqlite"
SCHEMA_VERSION = 5
#: Schema changes, in order: ``MIGRATIONS[v]`` is the SQL script that takes a database of
#: version ``v - 1`` to ``v`` (``ALTER TABLE … ADD COLUMN``; new tables come from
#: :data:`SCHEMA`, whose ``CREATE … IF NOT EXISTS`` always describes the newest version).
#: To change the schema: add the columns to SCHEMA, add a step here, raise SCHEMA_VERSION,
#: and describe it in docs/storage-schema.md.
BUSY_TIMEOUT_MS = 5000

#: Delivery state of the MQTT publisher (dsfd.integrations.mqtt), one row per destination
#: (broker and base topic): the last state message the broker acknowledged, and the broker's
#: state for ``dsfd status``. Written by the publisher's thread, never by the cycle.
MQTT_CURSOR_TABLE = """
CREATE TABLE IF NOT EXISTS mqtt_cursor (
    destination TEXT PRIMARY KEY,
    run_id INTEGER NOT NULL DEFAULT 0,
    cycle INTEGER NOT NULL DEFAULT 0,
    time_s REAL,
    connected INTEGER NOT NULL DEFAULT 0,
    last_error TEXT NOT NULL DEFAULT '',
    last_error_utc TEXT,
    backlog INTEGER NOT NULL DEFAULT 0,
    delivered INTEGER NOT NULL DEFAULT 0,
    expired INTEGER NOT NULL DEFAULT 0,
    kpi_day TEXT,
    updated_utc TEXT NOT NULL
);
"""
MIGRATIONS: dict[int, str] = {
    2: MQTT_CURSOR_TABLE,  # the MQTT delivery cursor and broker state (issue 22)
    # 3: the model's view of every cycle (table ``model``, from SCHEMA) and the panel
    # configuration of each run, for ``dsfd report`` and ``dsfd export`` (issue 21).
    3: "ALTER TABLE runs ADD COLUMN config_json TEXT",
    # Operator commands and manual holds (issue 20): who held the panel until when, and the
    # cycle's place on the monotonic grid (a wall-clock step cannot reorder cycles). The
    # commands table is new, so it comes from SCHEMA.
    4: """
        ALTER TABLE decisions ADD COLUMN hold_source TEXT;
        ALTER TABLE decisions ADD COLUMN hold_expires_s REAL;
        ALTER TABLE decisions ADD COLUMN hold_command_id INTEGER;
        ALTER TABLE decisions ADD COLUMN run_elapsed_s REAL
    """,
    # The control objective in force and the operator's ``mode`` command behind it (issue
    # 22: the MQTT ``<base>/cmd/mode`` and ``dsfd mode``).
    5: """
        ALTER TABLE decisions ADD COLUMN objective_mode TEXT;
        ALTER TABLE decisions ADD COLUMN mode_command_id INTEGER
    """,
}

_STATES = ("x1", "x2", "x3", "x4", "x5")
_HEAT_TERMS = ("q_cv_rd", "q_sol_trans", "q_air", "q_da")
#: Columns of the ``model`` table after ``run_id, cycle, time_s`` (one row per cycle; meaning
#: and units in docs/storage-schema.md): state estimate, one-step prediction of this cycle's
#: readings, the model's room-side heat over the step that ended, the horizon-end prediction,
#: the actuator position in effect from this cycle on, the simulated plant's own room heat.
MODEL_COLUMNS: tuple[tuple[str, str], ...] = (
    *((f"est_{s}_c", "REAL") for s in (*_STATES, "x6")),
    *((f"pred_{s}_c", "REAL") for s in _STATES),
    ("pred_v_cav_ms", "REAL"),
    *((f"{q}_w", "REAL") for q in _HEAT_TERMS),
    ("horizon_s", "REAL"),
    *((f"hz_{s}_c", "REAL") for s in _STATES),
    ("applied_phi_deg", "REAL"), ("applied_afr", "INTEGER"), ("applied_or_pct", "REAL"),
    *((f"plant_{q}_j", "REAL") for q in _HEAT_TERMS),
)
_MODEL_DDL = ",\n    ".join(f"{name} {kind}" for name, kind in MODEL_COLUMNS)

_PARAM_COLUMNS = ", ".join(f"{name} REAL" for name in PARAMETER_NAMES)
SCHEMA = f"""
CREATE TABLE IF NOT EXISTS meta (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS runs (
    run_id INTEGER PRIMARY KEY AUTOINCREMENT,
    panel TEXT NOT NULL,
    mode TEXT NOT NULL,
    started_utc TEXT NOT NULL,
    pid INTEGER NOT NULL,
    version TEXT NOT NULL,
    config_path TEXT,
    ended_utc TEXT,
    end_reason TEXT,
    cycles INTEGER,
    config_json TEXT
);
CREATE TABLE IF NOT EXISTS samples (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    signal TEXT NOT NULL,
    value REAL,
    quality TEXT NOT NULL,
    detail TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (run_id, cycle, signal)
) WITHOUT ROWID;
CREATE INDEX IF NOT EXISTS samples_by_time ON samples (time_s, signal);
CREATE TABLE IF NOT EXISTS decisions (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    slot INTEGER NOT NULL,
    time_s REAL NOT NULL,
    time_utc TEXT NOT NULL,
    method TEXT NOT NULL,
    fallback_reason TEXT NOT NULL DEFAULT '',
    heating INTEGER,
    cost_j REAL,
    proposed_phi_deg REAL,
    proposed_afr INTEGER,
    proposed_or_pct REAL,
    phi_deg REAL NOT NULL,
    afr INTEGER NOT NULL,
    or_pct REAL NOT NULL,
    write_status TEXT NOT NULL,
    write_errors TEXT NOT NULL DEFAULT '[]',
    trace TEXT NOT NULL DEFAULT '[]',
    timings_ms TEXT NOT NULL DEFAULT '{{}}',
    cycle_ms REAL NOT NULL,
    skipped_slots INTEGER NOT NULL DEFAULT 0,
    hold_source TEXT,
    hold_expires_s REAL,
    hold_command_id INTEGER,
    run_elapsed_s REAL,
    objective_mode TEXT,
    mode_command_id INTEGER,
    PRIMARY KEY (run_id, cycle)
);
CREATE INDEX IF NOT EXISTS decisions_by_time ON decisions (time_s);
CREATE TABLE IF NOT EXISTS parameters (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    source TEXT NOT NULL,
    {_PARAM_COLUMNS},
    other TEXT NOT NULL DEFAULT '{{}}',
    cost REAL,
    detail TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (run_id, cycle)
);
CREATE TABLE IF NOT EXISTS events (
    event_id INTEGER PRIMARY KEY AUTOINCREMENT,
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    level TEXT NOT NULL,
    kind TEXT NOT NULL,
    message TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS model (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    {_MODEL_DDL},
    PRIMARY KEY (run_id, cycle)
);
CREATE TABLE IF NOT EXISTS commands (
    command_id INTEGER PRIMARY KEY AUTOINCREMENT,
    requested_s REAL NOT NULL,
    requested_utc TEXT NOT NULL,
    source TEXT NOT NULL,
    requester TEXT NOT NULL,
    kind TEXT NOT NULL,
    args TEXT NOT NULL DEFAULT '{{}}',
    status TEXT NOT NULL DEFAULT 'pending',
    reason TEXT NOT NULL DEFAULT '',
    run_id INTEGER,
    cycle INTEGER,
    handled_utc TEXT
);
CREATE INDEX IF NOT EXISTS commands_pending ON commands (status, command_id);
""" + MQTT_CURSOR_TABLE


class SchemaTooNewError(RuntimeError):
    """The database was written by a newer dsfd; it is left as it is (never moved aside)."""


def iso_now() -> str:
    """Current UTC time, ISO 8601 with seconds and ``Z``."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


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
    handled (``applied`` or ``rejected``).
    """

    cycle: int
    time_s: float
    samples: Sequence[tuple[str, float | None, str, str]]
    decision: Mapping[str, Any]
    parameters: tuple[str, Mapping[str, float], float | None, str] | None = None
    events: Sequence[tuple[str, str, str]] = field(default_factory=tuple)
    model: Mapping[str, float | int | None] | None = None
    command_results: Sequence[tuple[int, str, str]] = field(default_factory=tuple)


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
            conn = _connect_checked(path)
        except sqlite3.DatabaseError as exc:
            moved = _move_aside(path)
            conn = _connect_checked(path)
            _insert_meta(conn, "recovered_from", f"{moved.name}: {exc}")
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
                self.conn.execute(
                    f"INSERT INTO parameters (run_id, cycle, time_s, source, "
                    f"{', '.join(PARAMETER_NAMES)}, other, cost, detail) VALUES (?, ?, ?, ?, "
                    f"{', '.join('?' for _ in PARAMETER_NAMES)}, ?, ?, ?)",
                    (run, rec.cycle, rec.time_s, source,
                     *(_num(theta.get(n)) for n in PARAMETER_NAMES), _sql(other), _num(cost),
                     detail))
            if rec.model is not None:
                cols = ["run_id", "cycle", "time_s",
                        *(c for c, _ in MODEL_COLUMNS if c in rec.model)]
                self.conn.execute(
                    f"INSERT INTO model ({', '.join(cols)}) "
                    f"VALUES ({', '.join('?' for _ in cols)})",
                    (run, rec.cycle, rec.time_s, *(_sql(rec.model[c]) for c in cols[3:])))
            self._events(run, rec.cycle, rec.time_s, rec.events)
            for cycle, time_s, level, kind, message in late_events:
                self._events(run, cycle, time_s, [(level, kind, message)])
            self.conn.executemany(
                "UPDATE commands SET status = ?, reason = ?, run_id = ?, cycle = ?, "
                "handled_utc = ? WHERE command_id = ? AND status = 'pending'",
                [(status, reason, run, rec.cycle, iso_now(), command_id)
                 for command_id, status, reason in rec.command_results])

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


def _connect_checked(path: Path) -> sqlite3.Connection:
    """Connect, configure, create the schema; raise DatabaseError if the file is unusable."""
    existed = path.exists() and path.stat().st_size > 0
    if not path.exists():
        # Created here, the file gets 0666 less the umask (SQLite alone would cap it at
        # 0644), and its -wal/-shm files take its mode: a group-shared state directory
        # (UMask=0007) gives operators the write access commands need.
        os.close(os.open(path, os.O_CREAT | os.O_WRONLY | os.O_CLOEXEC, 0o666))
    conn = sqlite3.connect(path, timeout=BUSY_TIMEOUT_MS / 1000, check_same_thread=False,
                           isolation_level="DEFERRED")
    try:
        conn.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        # Before anything writes (even the journal mode): a newer database stays untouched.
        version = _schema_version(conn)
        if version is not None and version > SCHEMA_VERSION:
            raise SchemaTooNewError(
                f"{path}: schema version {version} was written by a newer dsfd; this one "
                f"writes version {SCHEMA_VERSION} (upgrade dsfd, or move the file away)")
        mode = conn.execute("PRAGMA journal_mode = WAL").fetchone()[0]
        if str(mode).lower() != "wal":
            raise sqlite3.DatabaseError(f"cannot switch to WAL journal (got {mode!r})")
        conn.execute("PRAGMA synchronous = NORMAL")
        conn.execute("PRAGMA foreign_keys = ON")
        if existed and not _last_run_ended_cleanly(conn):
            verdict = conn.execute("PRAGMA quick_check").fetchone()[0]
            if verdict != "ok":
                raise sqlite3.DatabaseError(f"quick_check: {verdict}")
        if version is not None:
            _migrate(conn, version)
        with conn:
            conn.executescript(SCHEMA)
        if version is None:
            _insert_meta(conn, "schema_version", str(SCHEMA_VERSION))
            _insert_meta(conn, "created_utc", iso_now())
    except (sqlite3.DatabaseError, SchemaTooNewError):
        conn.close()
        raise
    return conn


def _schema_version(conn: sqlite3.Connection) -> int | None:
    """The stored schema version, or None for a new (empty) database."""
    try:
        row = conn.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
    except sqlite3.OperationalError:  # no meta table: a new database
        return None
    return None if row is None else int(row[0])


def _migrate(conn: sqlite3.Connection, version: int) -> None:
    """Apply the steps from ``version`` to :data:`SCHEMA_VERSION`, each in one transaction,
    recording each in ``meta`` (``migrated_to_<v>``)."""
    for target in range(version + 1, SCHEMA_VERSION + 1):
        with conn:
            for statement in filter(str.strip, MIGRATIONS[target].split(";")):
                conn.execute(statement)
            conn.execute("INSERT OR REPLACE INTO meta (key, value) VALUES "
                         "('schema_version', ?)", (str(target),))
            conn.execute("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)",
                         (f"migrated_to_{target}", iso_now()))


def _last_run_ended_cleanly(conn: sqlite3.Connection) -> bool:
    try:
        row = conn.execute("SELECT ended_utc FROM runs ORDER BY run_id DESC LIMIT 1").fetchone()
    except sqlite3.OperationalError:  # no runs table yet: nothing to trust, check
        return False
    return row is not None and row[0] is not None


def _insert_meta(conn: sqlite3.Connection, key: str, value: str) -> None:
    with conn:
        conn.execute("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)", (key, value))


def _move_aside(path: Path) -> Path:
    """Rename ``path`` and its ``-wal``/``-shm`` companions to ``*.corrupt.<iso>``."""
    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%S.%fZ")
    target = path.with_name(f"{path.name}.corrupt.{stamp}")
    for suffix in ("", "-wal", "-shm"):
        src = path.with_name(path.name + suffix)
        if src.exists():
            os.replace(src, target.with_name(target.name + suffix))
    _fsync_dir(path.parent)
    return target


def _fsync_dir(directory: Path) -> None:
    fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
