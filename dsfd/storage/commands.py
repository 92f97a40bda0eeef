"""The ``commands`` table: how operator requests reach the running daemon, durably and audited.

One path for every source. A front end (``dsfd override``/``resume``/``mode``/``occupancy``,
the MQTT receiver, :mod:`dsfd.integrations.mqtt.receiver`, and the BACnet device,
:mod:`dsfd.integrations.bacnet.device`) validates the request with
:func:`dsfd.daemon.commands.validate_command` and, if it is well-formed, inserts a
``pending`` row with :func:`submit` naming its ``source`` and ``requester``. Every cycle the
daemon's loop reads the pending rows (:func:`pending`), validates each again against the
configuration it runs, applies it, and marks it ``applied`` or ``rejected`` with the reason
in the same transaction as the cycle's rows
(:meth:`dsfd.storage.timeseries.Store.append`). :func:`outcome` reads that answer back. A
request the daemon does not pick up within :data:`MAX_AGE_S` is rejected as expired, so a
command never takes effect long after it was given.

No network listener of the daemon's own but the optional BACnet device (off by default,
read-only until ``bacnet.writable``): who may write the database, publish to the panel's
``<base>/cmd/`` topics on the broker (its ACL) or, with writes on, reach the BACnet port may
command the panel (docs/operating.md, "Permissions"; docs/mqtt.md, "Commands over MQTT";
docs/bacnet.md).
"""

from __future__ import annotations

import contextlib
import getpass
import json
import os
import socket
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dsfd.storage.timeseries import BUSY_TIMEOUT_MS, iso_now

__all__ = ["MAX_AGE_S", "CommandOutcome", "StoredCommand", "outcome", "pending",
           "requester", "submit"]

#: A pending command older than this when the daemon reads it is rejected as expired [s].
MAX_AGE_S = 600.0


@dataclass(frozen=True)
class StoredCommand:
    """A pending row: the request as given (``args`` holds its fields)."""

    command_id: int
    kind: str
    args: dict[str, Any]
    source: str
    requester: str
    requested_s: float

    def request(self) -> dict[str, Any]:
        """The request mapping for :func:`~dsfd.daemon.commands.validate_command`."""
        return {"command": self.kind, **self.args}


@dataclass(frozen=True)
class CommandOutcome:
    """What became of a command: ``pending``, ``applied`` or ``rejected`` (with why)."""

    command_id: int
    status: str
    reason: str
    run_id: int | None
    cycle: int | None
    handled_utc: str | None


def requester() -> str:
    """Who is asking, for the audit trail: ``user@host``, with the ``sudo`` user if any."""
    try:
        user = getpass.getuser()
    except (KeyError, OSError):
        user = str(os.getuid())
    sudo = os.environ.get("SUDO_USER")
    if sudo and sudo != user:
        user = f"{sudo} (as {user})"
    return f"{user}@{socket.gethostname()}"


def submit(db: Path, *, kind: str, args: dict[str, Any], source: str, requester: str,
           now_s: float | None = None) -> int:
    """Insert a pending command into the database at ``db``; its ``command_id``.

    The database must exist (the daemon created it): it is opened read-write, never created.
    Run as root (``sudo``) next to a daemon of another user, the files SQLite may create are
    handed to the database's owner, so the daemon can still open them.
    """
    now = time.time() if now_s is None else now_s
    conn = sqlite3.connect(f"file:{db}?mode=rw", uri=True, timeout=BUSY_TIMEOUT_MS / 1000)
    try:
        with conn:
            cur = conn.execute(
                "INSERT INTO commands (requested_s, requested_utc, source, requester, kind, "
                "args) VALUES (?, ?, ?, ?, ?, ?)",
                (now, iso_now(), source, requester, kind,
                 json.dumps(args, separators=(",", ":"))))
        command_id = int(cur.lastrowid or 0)
    finally:
        conn.close()
        _match_owner(db)
    return command_id


def outcome(conn: sqlite3.Connection, command_id: int) -> CommandOutcome | None:
    """The command's row now (None if there is no such command)."""
    row = conn.execute("SELECT status, reason, run_id, cycle, handled_utc FROM commands "
                       "WHERE command_id = ?", (command_id,)).fetchone()
    return None if row is None else CommandOutcome(command_id, *row)


def pending(conn: sqlite3.Connection) -> list[StoredCommand]:
    """Pending commands, oldest first (a row whose ``args`` is not JSON comes with the raw
    text under ``"args"``, so validation rejects it naming the field)."""
    out = []
    for cid, kind, args, source, who, requested_s in conn.execute(
            "SELECT command_id, kind, args, source, requester, requested_s FROM commands "
            "WHERE status = 'pending' ORDER BY command_id"):
        try:
            parsed = json.loads(args)
        except (TypeError, json.JSONDecodeError):
            parsed = {"args": args}
        if not isinstance(parsed, dict):
            parsed = {"args": parsed}
        out.append(StoredCommand(int(cid), str(kind), parsed, str(source), str(who),
                                 float(requested_s)))
    return out


def _match_owner(db: Path) -> None:
    """As root, give the ``-wal``/``-shm`` files the database's owner (else a daemon running
    as another user could not open them after a ``sudo dsfd override``)."""
    if os.geteuid() != 0:
        return
    try:
        st = db.stat()
    except OSError:
        return
    for suffix in ("-wal", "-shm"):
        companion = db.with_name(db.name + suffix)
        with contextlib.suppress(OSError):
            if companion.stat().st_uid != st.st_uid or companion.stat().st_gid != st.st_gid:
                os.chown(companion, st.st_uid, st.st_gid)
