"""Read-only questions to a panel's database, for the daemon at start and for ``dsfd status``.

Opening for a reader (:func:`open_read_only`): SQLite reads a WAL database through its
``-shm`` index. While the daemon runs, the ``-wal`` and ``-shm`` files exist and a read-only
connection only needs read permission on the three files (SQLite ≥ 3.22). When no daemon
has the database open, those files are gone and a read-only connection cannot create them;
the database is then quiescent and is read as ``immutable``. Nothing here ever writes.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Any

from dsfd.config.panel import PARAMETER_NAMES

__all__ = ["columns", "first_row", "last_decision", "open_read_only", "parameter_history",
           "run_control_mode"]


def open_read_only(db: Path) -> sqlite3.Connection:
    """A connection that can only read ``db``; ``FileNotFoundError`` if there is none,
    ``PermissionError`` naming the file a reader cannot open."""
    if not db.exists():
        raise FileNotFoundError(f"no database at {db}")
    for path in (db, db.with_name(db.name + "-shm")):
        if path.exists():
            try:
                path.open("rb").close()
            except PermissionError:
                raise PermissionError(f"{path}: permission denied") from None
    try:
        conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5.0)
        conn.execute("SELECT 1 FROM sqlite_master LIMIT 1").fetchone()
        return conn
    except sqlite3.OperationalError:
        if db.with_name(db.name + "-wal").exists():
            raise
    # No -wal: nobody has the database open (a clean stop checkpoints and removes it), so
    # it cannot change under us; immutable reading needs no -shm.
    conn = sqlite3.connect(f"file:{db}?mode=ro&immutable=1", uri=True)
    conn.execute("SELECT 1 FROM sqlite_master LIMIT 1").fetchone()
    return conn


def columns(conn: sqlite3.Connection, table: str) -> set[str]:
    """Column names of ``table`` (an older schema may lack newer ones)."""
    return {row[1] for row in conn.execute(f"PRAGMA table_info({table})")}


def first_row(conn: sqlite3.Connection, sql: str, *params: Any) -> dict[str, Any] | None:
    """The first row of a query as a mapping by column name, None if there is none."""
    cur = conn.execute(sql, params)
    row = cur.fetchone()
    return None if row is None else dict(zip([d[0] for d in cur.description], row,
                                             strict=True))


def last_decision(conn: sqlite3.Connection) -> dict[str, Any] | None:
    """The newest stored decision (any run), as a mapping by column."""
    return first_row(conn, "SELECT * FROM decisions ORDER BY run_id DESC, cycle DESC LIMIT 1")


def run_control_mode(conn: sqlite3.Connection, run_id: int) -> str | None:
    """``control.mode`` of the panel configuration run ``run_id`` used (``runs.config_json``;
    None for a run of schema 1 or 2, or a configuration without it)."""
    row = conn.execute("SELECT config_json FROM runs WHERE run_id = ?", (run_id,)).fetchone()
    try:
        mode = json.loads(row[0])["control"]["mode"] if row and row[0] else None
    except (ValueError, KeyError, TypeError):
        return None
    return mode if isinstance(mode, str) else None


def parameter_history(conn: sqlite3.Connection, panel: str, *, limit: int = 50
                      ) -> list[tuple[int, int, float, str, dict[str, float]]]:
    """The newest rows of ``panel``'s parameter history that hold calibrated values (not
    ``prior``): (run_id, cycle, time_s, source, value by name), newest first. NULL columns
    are left out of the mapping; ``other`` (the heat-flux offsets) is merged in."""
    rows = conn.execute(
        f"SELECT p.run_id, p.cycle, p.time_s, p.source, {', '.join(PARAMETER_NAMES)}, "
        "p.other FROM parameters p JOIN runs r USING (run_id) WHERE r.panel = ? AND "
        "p.source != 'prior' ORDER BY p.time_s DESC, p.run_id DESC LIMIT ?",
        (panel, limit)).fetchall()
    out = []
    for run, cycle, time_s, source, *values, other in rows:
        named = {k: float(v) for k, v in zip(PARAMETER_NAMES, values, strict=True)
                 if v is not None}
        try:
            extra = json.loads(other or "{}")
        except json.JSONDecodeError:
            extra = {}
        if isinstance(extra, dict):
            named.update({k: float(v) for k, v in extra.items()
                          if isinstance(v, int | float) and not isinstance(v, bool)})
        out.append((int(run), int(cycle), float(time_s), str(source), named))
    return out
