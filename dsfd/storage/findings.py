"""The ``findings`` table (schema 7, docs/storage-schema.md): what the daemon's diagnostics
found, and what became of it.

Written in two places: the daemon's findings thread (:mod:`dsfd.daemon.findings`) applies
:func:`dsfd.estimation.lifecycle.reconcile`'s changes with :func:`apply`, and the loop
applies an operator's ``ack`` command with :func:`acknowledge`. Each is one short
transaction, and both only change a row that is still open, so neither can undo the other.
Read by ``dsfd status``, the MQTT publisher and the metrics (:func:`open_findings`), and
``dsfd report`` (:func:`findings_between`).
"""

from __future__ import annotations

import json
import math
import sqlite3
from collections.abc import Mapping, Sequence
from typing import Any

from dsfd.estimation.diagnostics import Evidence
from dsfd.estimation.lifecycle import (
    ACKNOWLEDGED,
    ENDED,
    OPEN,
    Changes,
    StoredFinding,
    subject_of,
)

__all__ = ["COLUMNS", "acknowledge", "apply", "evidence_json", "findings_between",
           "first_signal", "load", "open_by_kind", "open_findings"]

#: Columns a reader gets from :func:`open_findings`.
COLUMNS = ("finding_id", "run_id", "kind", "subject", "confidence", "start_s", "detected_s",
           "opened_s", "last_seen_s", "evidence", "action", "state", "ended_s", "end_reason",
           "ack_command_id")


def _number(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def evidence_json(evidence: Sequence[Evidence]) -> str:
    """The evidence as a JSON list of objects (NaN, e.g. a cross-check's shift_sd: null)."""
    return json.dumps([{"signal": e.signal, "shift": _number(e.shift),
                        "shift_sd": _number(e.shift_sd), "unit": e.unit,
                        "since_s": _number(e.since_s), "statistic": _number(e.statistic),
                        "threshold": _number(e.threshold)} for e in evidence],
                      separators=(",", ":"))


def load(conn: sqlite3.Connection) -> list[StoredFinding]:
    """The open findings and the acknowledged ones (reconcile keeps the latest per key).
    Acknowledged rows pile up slowly (an operator's word each), so all are read."""
    rows = conn.execute(
        "SELECT finding_id, kind, subject, state, start_s, ended_s FROM findings "
        "WHERE state IN (?, ?)", (OPEN, ACKNOWLEDGED)).fetchall()
    return [StoredFinding(finding_id=int(i), kind=str(k), subject=str(s), state=str(st),
                          start_s=float(t0), closed_s=None if t1 is None else float(t1))
            for i, k, s, st, t0, t1 in rows]


def apply(conn: sqlite3.Connection, changes: Changes, *, now_s: float,
          run_id: int | None) -> list[int]:
    """Write ``changes`` in one transaction; the ids of the findings opened."""
    opened: list[int] = []
    with conn:
        for f in changes.opened:
            cur = conn.execute(
                "INSERT INTO findings (run_id, kind, subject, confidence, start_s, detected_s, "
                "opened_s, last_seen_s, evidence, action, state) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (run_id, f.kind, subject_of(f), f.confidence, f.start_s, f.detected_s, now_s,
                 now_s, evidence_json(f.evidence), f.action, OPEN))
            opened.append(int(cur.lastrowid or 0))
        # A parameter finding keeps the time it was first detected: the detector's days end
        # at each hourly check, so a refresh's alarm day is a later day each time.
        conn.executemany(
            "UPDATE findings SET subject = ?, confidence = ?, detected_s = CASE kind WHEN "
            "'parameter_shift' THEN detected_s ELSE ? END, last_seen_s = ?, evidence = ?, "
            "action = ? WHERE finding_id = ? AND state = ?",
            [(subject_of(f), f.confidence, f.detected_s, now_s, evidence_json(f.evidence),
              f.action, fid, OPEN) for fid, f in changes.refreshed])
        conn.executemany(
            "UPDATE findings SET state = ?, ended_s = ?, end_reason = ? "
            "WHERE finding_id = ? AND state = ?",
            [(ENDED, now_s, "the evidence went away", fid, OPEN) for fid in changes.ended])
    return opened


def acknowledge(conn: sqlite3.Connection, finding_id: int, *, command_id: int, now_s: float,
                who: str) -> tuple[str, str]:
    """An operator's ``ack``: (``applied`` or ``rejected``, why). Only an open finding can
    be acknowledged; the same command again (after a restart) is ``applied``."""
    with conn:
        row = conn.execute("SELECT kind, subject, state, ack_command_id FROM findings "
                           "WHERE finding_id = ?", (finding_id,)).fetchone()
        if row is None:
            return "rejected", f"finding: {finding_id}: no such finding"
        kind, subject, state, by = row
        name = f"#{finding_id} {kind}" + (f" ({subject})" if subject else "")
        if state == ACKNOWLEDGED and by == command_id:
            return "applied", f"finding {name} acknowledged"
        if state != OPEN:
            return "rejected", f"finding: {finding_id}: {name} is {state}, not open"
        conn.execute("UPDATE findings SET state = ?, ended_s = ?, ack_command_id = ?, "
                     "end_reason = ? WHERE finding_id = ? AND state = ?",
                     (ACKNOWLEDGED, now_s, command_id, f"acknowledged by {who}", finding_id,
                      OPEN))
    return "applied", (f"finding {name} acknowledged: closed until new evidence (a later "
                       "start) opens a new one")


def _read(conn: sqlite3.Connection, where: str, args: Sequence[Any]) -> list[dict[str, Any]]:
    """Rows of :data:`COLUMNS` by id, ``evidence`` parsed; none from a database older than
    schema 7."""
    try:
        rows = conn.execute(f"SELECT {', '.join(COLUMNS)} FROM findings WHERE {where} "
                            "ORDER BY finding_id", tuple(args)).fetchall()
    except sqlite3.OperationalError:  # a database older than schema 7: no findings yet
        return []
    out = []
    for r in rows:
        d = dict(zip(COLUMNS, r, strict=True))
        try:
            d["evidence"] = json.loads(d["evidence"])
        except (TypeError, ValueError):
            d["evidence"] = []
        out.append(d)
    return out


def open_findings(conn: sqlite3.Connection) -> list[dict[str, Any]]:
    """The open findings, oldest first, each a mapping of :data:`COLUMNS` (``evidence``
    parsed)."""
    return _read(conn, "state = ?", (OPEN,))


def findings_between(conn: sqlite3.Connection, since_s: float, until_s: float
                     ) -> list[dict[str, Any]]:
    """Every finding (open, acknowledged, ended) whose evidence overlaps ``since_s`` ..
    ``until_s`` [s]: it started by ``until_s`` and was still open at ``since_s`` (for
    ``dsfd report``); as :func:`open_findings`."""
    return _read(conn, "start_s <= ? AND (ended_s IS NULL OR ended_s >= ?)",
                 (until_s, since_s))


def open_by_kind(conn: sqlite3.Connection) -> dict[str, int]:
    """How many findings of each kind are open (an error reads as none: metrics only)."""
    try:
        return {str(k): int(n) for k, n in conn.execute(
            "SELECT kind, COUNT(*) FROM findings WHERE state = ? GROUP BY kind", (OPEN,))}
    except sqlite3.Error:
        return {}


def first_signal(row: Mapping[str, Any]) -> str:
    """The signal of a stored finding's first evidence (a row of :func:`findings_between`;
    '' without evidence)."""
    return str((row.get("evidence") or [{}])[0].get("signal") or "")
