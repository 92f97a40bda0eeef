"""Cycles waiting for the database: what keeps control going when writes fail (full disk).

The daemon never writes a cycle straight into SQLite. It puts the cycle's record into a
:class:`WriteBuffer` (:meth:`~WriteBuffer.enqueue`, in the loop's thread, instant) and then
lets a worker thread :meth:`~WriteBuffer.flush` the buffer: every waiting record in order,
each in its own transaction, stopping at the first that fails. So a failed write (``ENOSPC``
→ ``SQLITE_FULL``, ``EFBIG`` under ``RLIMIT_FSIZE`` → ``SQLITE_IOERR_WRITE``, a broken disk)
costs the cycle nothing: the record waits, and the next cycle's flush tries again.

The buffer is bounded (``daemon.store_buffer_cycles``). When it is full the oldest waiting
record is dropped and counted. The first record written after a failure carries the account
as events: ``store_recovered`` (from which cycle it failed, why, how many cycles were written
late) and ``store_rows_lost`` (how many cycles could not be kept, and which). Nothing is
dropped silently. A record the database refuses for good (a constraint violation: a bug) is
dropped, logged and counted the same way, so it cannot block the records behind it.

Thread safety: ``enqueue`` (loop thread) and ``flush`` (a worker thread, or the stop) share
the list under a lock that is never held during a database write; flushes run one at a
time.
"""

from __future__ import annotations

import logging
import sqlite3
import threading
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from dsfd.storage.timeseries import CycleRecord, LateEvent

__all__ = ["WriteBuffer"]

log = logging.getLogger(__name__)

#: Events recorded outside cycles that wait for the database at most [count].
MAX_LATE_EVENTS = 100


class WriteBuffer:
    """Records waiting to be written by ``write(record, late_events)``, oldest first."""

    def __init__(self, write: Callable[[CycleRecord, Sequence[LateEvent]], None], *,
                 capacity: int) -> None:
        if capacity < 1:
            raise ValueError("capacity must be at least 1")
        self._write = write
        self.capacity = capacity
        self._pending: list[CycleRecord] = []
        self._late: list[LateEvent] = []
        self._lock = threading.Lock()
        self._flushing = threading.Lock()  # one flush at a time (the loop's, or the stop's)
        self._writing: CycleRecord | None = None
        #: Cycles dropped since the last report, and their first and last cycle number.
        self._lost: list[int] = []
        self._lost_why: set[str] = set()
        self._late_dropped = 0
        #: The failure being ridden out: (first cycle not written, error), else None.
        self.failure: tuple[int, str] | None = None
        #: Cycles written, dropped and events dropped over the buffer's life.
        self.written = 0
        self.lost_total = 0

    @property
    def waiting(self) -> int:
        """Records not yet written."""
        with self._lock:
            return len(self._pending)

    def enqueue(self, rec: CycleRecord) -> None:
        """Add one cycle; if the buffer is full, drop the oldest record not being written."""
        with self._lock:
            self._pending.append(rec)
            while len(self._pending) > self.capacity:
                index = 1 if self._pending[0] is self._writing else 0
                self._drop(self._pending.pop(index), f"memory buffer of {self.capacity} "
                           "cycles full")

    def add_late_event(self, event: LateEvent) -> None:
        """An event that could not be written outside a cycle: it goes in with the next
        record written."""
        with self._lock:
            if len(self._late) < MAX_LATE_EVENTS:
                self._late.append(event)
            else:
                self._late_dropped += 1

    def flush(self, *, wait_s: float = -1.0) -> bool:
        """Write every waiting record, oldest first; False if one failed (it stays), or if
        another flush still runs after ``wait_s`` [s] (default: wait for it)."""
        if not self._flushing.acquire(timeout=wait_s):
            return False
        try:
            return self._flush()
        finally:
            self._flushing.release()

    def _flush(self) -> bool:
        while True:
            with self._lock:
                if not self._pending:
                    return True
                rec = self._writing = self._pending[0]
                notes, late = self._notes(rec), list(self._late)
            try:
                self._write(replace(rec, events=[*rec.events, *notes]) if notes else rec,
                            late)
            except sqlite3.IntegrityError as exc:  # never writable: do not block the rest
                log.error("cycle %d cannot be stored and is dropped: %s", rec.cycle, exc)
                with self._lock:
                    self._writing = None
                    self._remove(rec)
                    self._drop(rec, f"refused by the database: {exc}")
                continue
            except sqlite3.Error as exc:
                with self._lock:
                    self._writing = None
                    if self.failure is None:
                        self.failure = (rec.cycle, f"{type(exc).__name__}: {exc}")
                return False
            with self._lock:
                self._writing = None
                self._remove(rec)
                self.written += 1
                if notes:  # the account went in with this record: start a new one
                    self.failure = None
                    self._lost.clear()
                    self._lost_why.clear()
                    self._late_dropped = 0
                del self._late[:len(late)]

    # ------------------------------------------------------------------ internals
    def _remove(self, rec: CycleRecord) -> None:
        for i, r in enumerate(self._pending):
            if r is rec:
                del self._pending[i]
                return

    def _drop(self, rec: CycleRecord, why: str) -> None:
        self._lost.append(rec.cycle)
        self._lost_why.add(why)
        self.lost_total += 1

    def _notes(self, rec: CycleRecord) -> list[tuple[str, str, str]]:
        """Events that account for a failure, if this record ends one (lock held)."""
        out: list[tuple[str, str, str]] = []
        if self.failure is not None:
            first, error = self.failure
            out.append(("warning", "store_recovered",
                        f"database writes failed from cycle {first} ({error}); "
                        f"{len(self._pending)} cycle(s) kept in memory are written now"))
        if self._lost:
            cycles = sorted(self._lost)
            out.append(("error", "store_rows_lost",
                        f"{len(cycles)} cycle(s) could not be kept "
                        f"({'; '.join(sorted(self._lost_why))}): cycles {_spans(cycles)} of "
                        "this run are missing"))
        if self._late_dropped:
            out.append(("error", "store_rows_lost", f"{self._late_dropped} event(s) recorded "
                        "outside cycles could not be kept"))
        return out


def _spans(cycles: Sequence[int]) -> str:
    """``1-3, 7`` for [1, 2, 3, 7]."""
    parts: list[str] = []
    start = prev = cycles[0]
    for c in [*cycles[1:], None]:
        if c is not None and c == prev + 1:
            prev = c
            continue
        parts.append(f"{start}" if start == prev else f"{start}-{prev}")
        if c is not None:
            start = prev = c
    return ", ".join(parts)
