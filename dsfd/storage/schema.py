"""The time-series database file: its schema, the steps that migrate an older one, and
opening it checked (``docs/storage-schema.md``).

:func:`connect_checked` opens ``timeseries.sqlite`` for the daemon: WAL journal,
``synchronous=NORMAL``, a ``busy_timeout``; a database written by a newer dsfd is refused
untouched (:class:`SchemaTooNewError`), an older one is migrated in place, one step per
transaction; after a run that did not end cleanly the file is checked (``PRAGMA
quick_check``). :func:`move_aside` renames an unusable file with its ``-wal``/``-shm``
companions. The writer on top of this is :class:`dsfd.storage.timeseries.Store`.
"""

from __future__ import annotations

import os
import sqlite3
from datetime import UTC, datetime
from pathlib import Path

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.storage.atomic import corrupt_name

__all__ = [
    "BUSY_TIMEOUT_MS",
    "COMFORT_COLUMNS",
    "DB_NAME",
    "FINDINGS_TABLE",
    "HEAT_TERMS",
    "MIGRATIONS",
    "MODEL_COLUMNS",
    "MQTT_CURSOR_TABLE",
    "PARAMETER_SD_COLUMNS",
    "SCHEMA",
    "SCHEMA_VERSION",
    "SchemaTooNewError",
    "connect_checked",
    "insert_meta",
    "iso_now",
    "move_aside",
]

DB_NAME = "timeseries.sqlite"
SCHEMA_VERSION = 8
#: How long a connection waits for another one's lock before a statement fails [ms].
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

#: What the daemon's diagnostics found (schema 7, issue 38; docs/storage-schema.md): one row
#: per finding, open until its evidence goes away (``ended``) or an operator acknowledges it
#: (``acknowledged``, with the ``ack`` command behind it). Written by the daemon's findings
#: thread (dsfd.daemon.findings) and, for an acknowledgement, by the loop.
FINDINGS_TABLE = """
CREATE TABLE IF NOT EXISTS findings (
    finding_id INTEGER PRIMARY KEY AUTOINCREMENT,
    run_id INTEGER,
    kind TEXT NOT NULL,
    subject TEXT NOT NULL DEFAULT '',
    confidence REAL NOT NULL,
    start_s REAL NOT NULL,
    detected_s REAL NOT NULL,
    opened_s REAL NOT NULL,
    last_seen_s REAL NOT NULL,
    evidence TEXT NOT NULL DEFAULT '[]',
    action TEXT NOT NULL,
    state TEXT NOT NULL DEFAULT 'open',
    ended_s REAL,
    end_reason TEXT NOT NULL DEFAULT '',
    ack_command_id INTEGER
);
CREATE INDEX IF NOT EXISTS findings_by_state ON findings (state, kind);
"""

#: Columns of ``parameters`` (schema 8; docs/storage-schema.md): the calibration's posterior
#: sd of each θ parameter, in the fitting coordinates (of log θ for the positive parameters,
#: so a relative sd; of n itself), from the diagonal of the state's covariance.
PARAMETER_SD_COLUMNS: tuple[str, ...] = tuple(f"sd_{name}" for name in PARAMETER_NAMES)

#: Schema changes, in order: ``MIGRATIONS[v]`` is the SQL script that takes a database of
#: version ``v - 1`` to ``v`` (``ALTER TABLE … ADD COLUMN``; new tables come from
#: :data:`SCHEMA`, whose ``CREATE … IF NOT EXISTS`` always describes the newest version).
#: To change the schema: add the columns to SCHEMA, add a step here, raise SCHEMA_VERSION,
#: and describe it in docs/storage-schema.md.
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
    # People behind the glass (issue 36): the operator's occupancy override in force; the
    # comfort quantities of every cycle are the new table ``comfort``, from SCHEMA.
    6: """
        ALTER TABLE decisions ADD COLUMN occupancy_override TEXT;
        ALTER TABLE decisions ADD COLUMN occupancy_until_s REAL;
        ALTER TABLE decisions ADD COLUMN occupancy_command_id INTEGER
    """,
    # Fault and drift diagnostics (issue 38): the findings of the daemon's detectors.
    7: FINDINGS_TABLE,
    # ... and the calibration's posterior sd with each parameter row, which the parameter
    # detector weighs the history's changes against (NULL in rows written before).
    8: ";\n".join(f"ALTER TABLE parameters ADD COLUMN {c} REAL" for c in PARAMETER_SD_COLUMNS),
}

_STATES = ("x1", "x2", "x3", "x4", "x5")
#: The model's room-side heat terms (docs/model.md#room-heat), in the order of the
#: ``model`` table's columns: every reader of the table names them from here.
HEAT_TERMS: tuple[str, ...] = ("q_cv_rd", "q_sol_trans", "q_air", "q_da")
#: Columns of the ``model`` table after ``run_id, cycle, time_s`` (one row per cycle; meaning
#: and units in docs/storage-schema.md): state estimate, one-step prediction of this cycle's
#: readings, the model's room-side heat over the step that ended, the horizon-end prediction,
#: the actuator position in effect from this cycle on, the simulated plant's own room heat.
MODEL_COLUMNS: tuple[tuple[str, str], ...] = (
    *((f"est_{s}_c", "REAL") for s in (*_STATES, "x6")),
    *((f"pred_{s}_c", "REAL") for s in _STATES),
    ("pred_v_cav_ms", "REAL"),
    *((f"{q}_w", "REAL") for q in HEAT_TERMS),
    ("horizon_s", "REAL"),
    *((f"hz_{s}_c", "REAL") for s in _STATES),
    ("applied_phi_deg", "REAL"), ("applied_afr", "INTEGER"), ("applied_or_pct", "REAL"),
    *((f"plant_{q}_j", "REAL") for q in HEAT_TERMS),
)
_MODEL_DDL = ",\n    ".join(f"{name} {kind}" for name, kind in MODEL_COLUMNS)
#: Columns of the ``comfort`` table after ``run_id, cycle, time_s`` (schema 6, one row per
#: cycle; docs/storage-schema.md): the occupancy in force and where it came from, the comfort
#: quantities of the command (NULL when they could not be computed) and the limits in force
#: with them, and the limits broken while occupied.
COMFORT_COLUMNS: tuple[tuple[str, str], ...] = (
    ("occupied", "INTEGER NOT NULL"), ("occupancy_source", "TEXT NOT NULL"),
    ("direct_sun_wm2", "REAL"), ("dgp", "REAL"), ("supply_air_c", "REAL"),
    ("asymmetry_k", "REAL"),
    ("direct_sun_max_wm2", "REAL"), ("dgp_max", "REAL"), ("supply_air_min_c", "REAL"),
    ("asymmetry_max_k", "REAL"),
    ("violations", "TEXT NOT NULL DEFAULT '[]'"),
)
_COMFORT_DDL = ",\n    ".join(f"{name} {kind}" for name, kind in COMFORT_COLUMNS)

_PARAM_COLUMNS = ", ".join(f"{name} REAL" for name in PARAMETER_NAMES)
_PARAM_SD_DDL = ",\n    ".join(f"{name} REAL" for name in PARAMETER_SD_COLUMNS)
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
    occupancy_override TEXT,
    occupancy_until_s REAL,
    occupancy_command_id INTEGER,
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
    {_PARAM_SD_DDL},
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
CREATE TABLE IF NOT EXISTS comfort (
    run_id INTEGER NOT NULL REFERENCES runs(run_id),
    cycle INTEGER NOT NULL,
    time_s REAL NOT NULL,
    {_COMFORT_DDL},
    PRIMARY KEY (run_id, cycle)
);
CREATE INDEX IF NOT EXISTS comfort_by_time ON comfort (time_s);
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
""" + MQTT_CURSOR_TABLE + FINDINGS_TABLE


class SchemaTooNewError(RuntimeError):
    """The database was written by a newer dsfd; it is left as it is (never moved aside)."""


def iso_now() -> str:
    """Current UTC time, ISO 8601 with seconds and ``Z``."""
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def connect_checked(path: Path) -> sqlite3.Connection:
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
            insert_meta(conn, "schema_version", str(SCHEMA_VERSION))
            insert_meta(conn, "created_utc", iso_now())
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


def insert_meta(conn: sqlite3.Connection, key: str, value: str) -> None:
    with conn:
        conn.execute("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)", (key, value))


def move_aside(path: Path) -> Path:
    """Rename ``path`` and its ``-wal``/``-shm`` companions to ``*.corrupt.<iso>``."""
    target = corrupt_name(path)
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
