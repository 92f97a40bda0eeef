"""The daemon's database seen as the MQTT publisher's outbox.

State messages are not queued in memory: every stored cycle is already in ``decisions`` and
``samples`` (docs/storage-schema.md). The publisher reads the cycles after its delivery cursor
in order — ``(run_id, cycle)``, the order they were stored — and moves the cursor in the
``mqtt_cursor`` table when the broker has acknowledged them (QoS 1). A broker outage or a
daemon restart therefore loses nothing: the backlog is whatever lies after the cursor,
bounded by ``mqtt.backlog_max_age_h`` relative to the newest stored cycle.

Used only by the publisher's thread, through its own SQLite connection (WAL: reading never
blocks the daemon's writes; the cursor is written in short transactions, at most every
few seconds).
"""

from __future__ import annotations

import bisect
import sqlite3
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import date
from pathlib import Path
from typing import Any

from dsfd.integrations.mqtt.messages import day_bounds_s
from dsfd.report.kpis import J_PER_KWH
from dsfd.storage.schema import BUSY_TIMEOUT_MS, COMFORT_COLUMNS, HEAT_TERMS, iso_now

__all__ = ["COMFORT_FIELDS", "Key", "Outbox", "PendingCycle", "Status"]

#: A cycle's place in the outbox: (run_id, cycle).
Key = tuple[int, int]

_DECISION_COLUMNS = ("run_id, cycle, slot, time_s, time_utc, method, fallback_reason, heating, "
                     "phi_deg, afr, or_pct, write_status, trace, timings_ms, cycle_ms, "
                     "skipped_slots, hold_source, hold_expires_s, hold_command_id, "
                     "objective_mode, mode_command_id, occupancy_override, "
                     "occupancy_until_s, occupancy_command_id")
#: What a cycle's ``comfort`` row adds to its state (schema 6, issue 36).
COMFORT_FIELDS: tuple[str, ...] = ("occupied", "occupancy_source", "direct_sun_wm2", "dgp",
                                   "supply_air_c", "asymmetry_k", "violations")
#: What the model made of a cycle (table ``model``, issue 21): the state estimate and the
#: room-side heat of the step that ended, with the names the state message uses.
MODEL_FIELDS: tuple[str, ...] = (*(f"est_x{i}_c" for i in range(1, 7)),
                                 *(f"{q}_w" for q in HEAT_TERMS))
_STATE_QUERY = (
    "SELECT " + ", ".join(f"d.{c.strip()}" for c in _DECISION_COLUMNS.split(","))
    + ", " + ", ".join(f"m.{c}" for c in MODEL_FIELDS)
    + ", " + ", ".join(f"co.{c}" for c in COMFORT_FIELDS)
    + ", runs.mode AS mode, c.source AS hold_by_source, c.requester AS hold_by_requester "
    "FROM decisions d JOIN runs USING (run_id) "
    "LEFT JOIN model m ON m.run_id = d.run_id AND m.cycle = d.cycle "
    "LEFT JOIN comfort co ON co.run_id = d.run_id AND co.cycle = d.cycle "
    "LEFT JOIN commands c ON c.command_id = d.hold_command_id "
    "WHERE (d.run_id, d.cycle) > (?, ?) AND d.time_s >= ? ORDER BY d.run_id, d.cycle LIMIT ?")


@dataclass(frozen=True)
class PendingCycle:
    """One stored cycle to publish: its decisions row (with the run's mode) and samples."""

    key: Key
    row: Mapping[str, Any]
    samples: Mapping[str, tuple[float | None, str]]
    calibrated_s: float | None


@dataclass
class Status:
    """The publisher's view of the broker (saved with the cursor; ``dsfd status`` reads it)."""

    connected: bool = False
    last_error: str = ""
    last_error_utc: str | None = None
    backlog: int = 0
    delivered: int = 0
    expired: int = 0
    kpi_day: str | None = None


class Outbox:
    """Cursor and backlog of one destination (``host:port base_topic``) in the database."""

    def __init__(self, conn: sqlite3.Connection, destination: str) -> None:
        self.conn = conn
        self.destination = destination

    @classmethod
    def open(cls, database: Path, destination: str) -> Outbox:
        conn = sqlite3.connect(database, timeout=BUSY_TIMEOUT_MS / 1000,
                               isolation_level=None)  # autocommit: each write its own txn
        conn.execute(f"PRAGMA busy_timeout = {BUSY_TIMEOUT_MS}")
        conn.row_factory = sqlite3.Row
        return cls(conn, destination)

    def close(self) -> None:
        self.conn.close()

    # ------------------------------------------------------------------ cursor
    def cursor(self) -> tuple[Key, Status]:
        """The acknowledged position and the saved counters (zero for a new destination)."""
        row = self.conn.execute(
            "SELECT run_id, cycle, delivered, expired, kpi_day FROM mqtt_cursor "
            "WHERE destination = ?", (self.destination,)).fetchone()
        if row is None:
            return (0, 0), Status()
        return (int(row["run_id"]), int(row["cycle"])), Status(
            delivered=int(row["delivered"]), expired=int(row["expired"]),
            kpi_day=row["kpi_day"])

    def save(self, acked: Key, status: Status, *, time_s: float | None) -> None:
        """Write the cursor and the broker state (one short transaction)."""
        self.conn.execute(
            "INSERT INTO mqtt_cursor (destination, run_id, cycle, time_s, connected, "
            "last_error, last_error_utc, backlog, delivered, expired, kpi_day, updated_utc) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (destination) DO UPDATE "
            "SET run_id = excluded.run_id, cycle = excluded.cycle, "
            "time_s = COALESCE(excluded.time_s, time_s), connected = excluded.connected, "
            "last_error = excluded.last_error, last_error_utc = excluded.last_error_utc, "
            "backlog = excluded.backlog, delivered = excluded.delivered, "
            "expired = excluded.expired, kpi_day = excluded.kpi_day, "
            "updated_utc = excluded.updated_utc",
            (self.destination, *acked, time_s, int(status.connected), status.last_error,
             status.last_error_utc, status.backlog, status.delivered, status.expired,
             status.kpi_day, iso_now()))

    # ------------------------------------------------------------------ backlog
    def newest_time_s(self) -> float | None:
        row = self.conn.execute("SELECT MAX(time_s) FROM decisions").fetchone()
        return None if row[0] is None else float(row[0])

    def oldest_allowed_s(self, max_age_s: float, *, newest_s: float | None = None
                         ) -> float | None:
        """The oldest cycle time still sent: ``max_age_s`` before the newest stored cycle
        (``newest_s`` if the caller just read it, else read now); None if none is stored."""
        newest = self.newest_time_s() if newest_s is None else newest_s
        return None if newest is None else newest - max_age_s

    def backlog(self, after: Key, *, max_age_s: float) -> int:
        """Stored cycles after ``after`` that are young enough to be sent."""
        oldest = self.oldest_allowed_s(max_age_s)
        if oldest is None:
            return 0
        return int(self.conn.execute(
            "SELECT COUNT(*) FROM decisions WHERE (run_id, cycle) > (?, ?) AND time_s >= ?",
            (*after, oldest)).fetchone()[0])

    def pending(self, after: Key, *, limit: int, max_age_s: float,
                newest_s: float | None = None) -> tuple[list[PendingCycle], int, Key | None]:
        """Up to ``limit`` cycles after ``after`` in stored order, young enough to send
        (``newest_s``: :meth:`newest_time_s` if the caller just read it).

        Returns the cycles, how many older ones were passed over, and the position just
        before the first returned cycle when some were passed over (else None).
        """
        oldest = self.oldest_allowed_s(max_age_s, newest_s=newest_s)
        if oldest is None or limit <= 0:
            return [], 0, None
        rows = self.conn.execute(_STATE_QUERY, (*after, oldest, limit)).fetchall()
        if not rows:
            return [], 0, None
        first: Key = (int(rows[0]["run_id"]), int(rows[0]["cycle"]))
        skipped = int(self.conn.execute(
            "SELECT COUNT(*) FROM decisions WHERE (run_id, cycle) > (?, ?) "
            "AND (run_id, cycle) < (?, ?)", (*after, *first)).fetchone()[0])
        samples = self._samples(rows)
        calibrated = self._calibration_times([float(r["time_s"]) for r in rows])
        out = []
        for r, cal in zip(rows, calibrated, strict=True):
            key = (int(r["run_id"]), int(r["cycle"]))
            out.append(PendingCycle(key, dict(r), samples.get(key, {}), cal))
        return out, skipped, ((first[0], first[1] - 1) if skipped else None)

    def _samples(self, rows: list[sqlite3.Row]
                 ) -> dict[Key, dict[str, tuple[float | None, str]]]:
        out: dict[Key, dict[str, tuple[float | None, str]]] = {}
        by_run: dict[int, list[int]] = {}
        for r in rows:
            by_run.setdefault(int(r["run_id"]), []).append(int(r["cycle"]))
        for run, cycles in by_run.items():
            for cycle, signal, value, quality in self.conn.execute(
                    "SELECT cycle, signal, value, quality FROM samples WHERE run_id = ? "
                    "AND cycle BETWEEN ? AND ?", (run, min(cycles), max(cycles))):
                out.setdefault((run, int(cycle)), {})[signal] = (value, quality)
        return out

    def _calibration_times(self, times_s: list[float]) -> list[float | None]:
        """For each cycle time, the newest on-line calibration update at or before it [s]
        (two queries per batch: the parameters table has no time index)."""
        lo, hi = min(times_s), max(times_s)
        before = self.conn.execute("SELECT MAX(time_s) FROM parameters WHERE source = "
                                   "'online' AND time_s <= ?", (lo,)).fetchone()[0]
        updates = [float(t) for (t,) in self.conn.execute(
            "SELECT time_s FROM parameters WHERE source = 'online' AND time_s > ? "
            "AND time_s <= ? ORDER BY time_s", (lo, hi))]
        out: list[float | None] = []
        for t in times_s:
            i = bisect.bisect_right(updates, t)
            out.append(updates[i - 1] if i else (None if before is None else float(before)))
        return out

    # ------------------------------------------------------------------ KPIs
    def day_rows(self, day: date, utc_offset_h: float) -> tuple[list[dict[str, Any]], int, int]:
        """A local day's decisions rows in stored order, its flagged samples and updates."""
        start, end = day_bounds_s(day, utc_offset_h)
        rows = [dict(r) for r in self.conn.execute(
            f"SELECT {_DECISION_COLUMNS} FROM decisions WHERE time_s >= ? AND time_s < ? "
            "ORDER BY run_id, cycle", (start, end))]
        flagged = self.conn.execute(
            "SELECT COUNT(*) FROM samples WHERE time_s >= ? AND time_s < ? "
            "AND quality != 'good'", (start, end)).fetchone()[0]
        updates = self.conn.execute(
            "SELECT COUNT(*) FROM parameters WHERE source = 'online' AND time_s >= ? "
            "AND time_s < ?", (start, end)).fetchone()[0]
        return rows, int(flagged), int(updates)

    def day_comfort(self, day: date, utc_offset_h: float) -> list[dict[str, Any]]:
        """A local day's ``comfort`` rows (schema 6) in stored order."""
        start, end = day_bounds_s(day, utc_offset_h)
        cols = ", ".join(c for c, _ in COMFORT_COLUMNS)
        return [dict(r) for r in self.conn.execute(
            f"SELECT {cols} FROM comfort WHERE time_s >= ? AND time_s < ? "
            "ORDER BY run_id, cycle", (start, end))]

    def day_heat(self, day: date, utc_offset_h: float, *, step_s: float
                 ) -> tuple[dict[str, float | None], float]:
        """The model's heat into the room over a local day [kWh] by term, and the hours its
        steps cover. A cycle's ``model`` row holds the step-mean heat [W] of the step that
        ended at it; the step belongs to the day of its midpoint (as in ``dsfd report``)."""
        start, end = day_bounds_s(day, utc_offset_h)
        row = self.conn.execute(
            f"SELECT {', '.join(f'SUM({q}_w)' for q in HEAT_TERMS)}, COUNT(q_cv_rd_w) FROM model "
            "WHERE time_s - ? >= ? AND time_s - ? < ?",
            (step_s / 2, start, step_s / 2, end)).fetchone()
        kwh = {q: None if v is None else float(v) * step_s / J_PER_KWH
               for q, v in zip(HEAT_TERMS, row[:-1], strict=True)}
        return kwh, int(row[-1]) * step_s / 3600.0
