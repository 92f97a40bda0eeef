"""Reading a state directory's time-series database back: the cycles of one panel as arrays.

``dsfd report`` and ``dsfd export`` read the daemon's database (``docs/storage-schema.md``)
through :func:`read_history`, opened **read-only** (the daemon may be running; SQLite's WAL
lets both work). A database of an older schema is read as it is (columns it lacks are
missing values), never migrated from here.

Runs that overlap in time (simulated dry runs replaying the same weather into one state
directory) cannot form one time series: then the newest of them is read and a note says so;
``run_id`` picks another.
"""

from __future__ import annotations

import json
import math
import sqlite3
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.measured import (
    CONTROL_COLUMNS,
    KNOWN_COLUMNS,
    MeasuredData,
    iso_utc,
)
from dsfd.storage.queries import columns
from dsfd.storage.timeseries import DB_NAME, MODEL_COLUMNS

__all__ = ["History", "HistoryError", "ParameterHistory", "RunInfo", "measured_from_history",
           "read_history"]

#: Numeric columns of ``decisions`` read into :attr:`History.decisions`.
_DECISION_NUMBERS = ("slot", "heating", "cost_j", "proposed_phi_deg", "proposed_afr",
                     "proposed_or_pct", "phi_deg", "afr", "or_pct", "cycle_ms", "skipped_slots")
_DECISION_TEXT = ("method", "fallback_reason", "write_status")


class HistoryError(RuntimeError):
    """No database, not a dsfd database, or nothing in the requested window."""


@dataclass(frozen=True)
class RunInfo:
    """One start of the daemon (a row of ``runs``)."""

    run_id: int
    panel: str
    mode: str
    started_utc: str
    ended_utc: str | None
    end_reason: str | None
    version: str
    config_path: str | None
    #: The panel configuration of the run as stored (schema ≥ 2), else None.
    config: Mapping[str, Any] | None


@dataclass(frozen=True, eq=False)
class ParameterHistory:
    """Rows of ``parameters`` in time order: when θ̂ was set and to what.

    ``values`` maps each fitted name (θ and the heat-flux offsets ``q_x1``…) to an array.
    """

    time_s: np.ndarray
    run_id: np.ndarray
    source: np.ndarray
    values: dict[str, np.ndarray]

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


@dataclass(frozen=True, eq=False)
class History:
    """The cycles of one state directory in time order; arrays of shape (n,).

    Attributes
    ----------
    time_s : ndarray, [s]
        Cycle time, UTC unix seconds.
    run_id, cycle : ndarray of int
    decisions : dict
        ``decisions`` columns: numbers as float arrays (NaN for NULL), ``method``,
        ``fallback_reason``, ``write_status`` as object arrays, and ``decide_ms`` (from
        ``timings_ms``).
    values, quality : dict
        Per signal: the value as delivered (NaN if none) and its quality flag (``""`` where
        the cycle has no row for the signal).
    model : dict
        ``model`` columns (:data:`~dsfd.storage.timeseries.MODEL_COLUMNS`), NaN where NULL
        or where the database predates them.
    parameters : ParameterHistory
    events : list of (time_s, run_id, level, kind, message)
    notes : tuple of str
        What the reader had to decide (overlapping runs, an old schema).
    """

    path: Path
    schema_version: int
    runs: tuple[RunInfo, ...]
    time_s: np.ndarray
    run_id: np.ndarray
    cycle: np.ndarray
    decisions: dict[str, np.ndarray]
    values: dict[str, np.ndarray]
    quality: dict[str, np.ndarray]
    model: dict[str, np.ndarray]
    parameters: ParameterHistory
    events: list[tuple[float, int, str, str, str]] = field(default_factory=list)
    notes: tuple[str, ...] = ()

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    @property
    def panel(self) -> str:
        return self.runs[-1].panel if self.runs else ""

    @property
    def config(self) -> Mapping[str, Any] | None:
        """The configuration of the newest run that stored one."""
        return next((r.config for r in reversed(self.runs) if r.config is not None), None)

    def good(self, signal: str) -> np.ndarray:
        """Values of ``signal`` where its quality was ``good``, NaN elsewhere."""
        v = self.values.get(signal)
        if v is None:
            return np.full(len(self), np.nan)
        return np.where(self.quality[signal] == "good", v, np.nan)

    def applied(self) -> dict[str, np.ndarray]:
        """The actuator position in effect from each cycle on: the ``model`` table's record
        (schema ≥ 2), else the command where it was written (NaN for dry-run cycles of an
        old database, whose actuator positions were not stored)."""
        out = {}
        written = self.decisions["write_status"] != "dry-run"
        for name in CONTROL_COLUMNS:
            rec = self.model[f"applied_{name}"]
            out[name] = np.where(np.isfinite(rec), rec,
                                 np.where(written, self.decisions[name], np.nan))
        return out


def _connect(state_dir: Path) -> sqlite3.Connection:
    path = state_dir / DB_NAME
    if not path.is_file():
        raise HistoryError(f"{path}: no database (is {state_dir} a dsfd state directory?)")
    try:
        conn = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True, timeout=5.0)
        conn.execute("SELECT COUNT(*) FROM decisions").fetchone()
    except sqlite3.Error as exc:
        raise HistoryError(f"{path}: not a readable dsfd database: {exc}") from None
    return conn


def _runs(conn: sqlite3.Connection) -> dict[int, RunInfo]:
    has_config = "config_json" in columns(conn, "runs")
    sql = ("SELECT run_id, panel, mode, started_utc, ended_utc, end_reason, version, "
           f"config_path, {'config_json' if has_config else 'NULL'} FROM runs ORDER BY run_id")
    out = {}
    for run, panel, mode, started, ended, reason, version, path, cfg in conn.execute(sql):
        config = None
        if cfg:
            try:
                config = json.loads(cfg)
            except ValueError:
                config = None
        out[int(run)] = RunInfo(int(run), panel, mode, started, ended, reason, version, path,
                                config)
    return out


def _pick_runs(conn: sqlite3.Connection, lo: float, hi: float, run_id: int | None
               ) -> tuple[list[int], list[str]]:
    """Runs with cycles in the window; the newest of those that overlap in time."""
    spans = conn.execute(
        "SELECT run_id, MIN(time_s), MAX(time_s) FROM decisions WHERE time_s BETWEEN ? AND ? "
        "GROUP BY run_id ORDER BY run_id", (lo, hi)).fetchall()
    if run_id is not None:
        return [r for r, _, _ in spans if r == run_id], []
    keep: list[tuple[int, float, float]] = []
    dropped: list[int] = []
    for run, first, last in spans:
        clash = [k for k in keep if first <= k[2] and last >= k[1]]
        for k in clash:
            keep.remove(k)
            dropped.append(k[0])
        keep.append((run, first, last))
    notes = []
    if dropped:
        notes.append(f"runs {', '.join(map(str, sorted(dropped)))} overlap in time with a "
                     f"newer run (replays of simulated weather): showing run(s) "
                     f"{', '.join(str(k[0]) for k in keep)}; --run N shows another")
    return [k[0] for k in keep], notes


def _in(runs: Sequence[int]) -> str:
    return f"run_id IN ({', '.join(str(int(r)) for r in runs)})"


def read_history(state_dir: Path, *, since_s: float | None = None,
                 until_s: float | None = None, run_id: int | None = None) -> History:
    """The cycles of ``state_dir`` between ``since_s`` and ``until_s`` [s, UTC, inclusive].

    Raises
    ------
    HistoryError
        No readable database, or no cycle in the window (the message says which).
    """
    state_dir = Path(state_dir)
    conn = _connect(state_dir)
    try:
        return _read(conn, state_dir, since_s, until_s, run_id)
    finally:
        conn.close()


def _read(conn: sqlite3.Connection, state_dir: Path, since_s: float | None,
          until_s: float | None, run_id: int | None) -> History:
    lo = -math.inf if since_s is None else since_s
    hi = math.inf if until_s is None else until_s
    version_row = conn.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
    version = int(version_row[0]) if version_row else 0
    all_runs = _runs(conn)
    picked, notes = _pick_runs(conn, lo, hi, run_id)
    if not picked:
        what = f"run {run_id}" if run_id is not None else "cycles"
        window = (f" between {iso_utc(lo) if math.isfinite(lo) else 'the start'} and "
                  f"{iso_utc(hi) if math.isfinite(hi) else 'the end'}")
        raise HistoryError(f"{state_dir / DB_NAME}: no {what}{window}")
    where = f"{_in(picked)} AND time_s BETWEEN ? AND ?"
    rows = conn.execute(
        f"SELECT run_id, cycle, time_s, {', '.join(_DECISION_NUMBERS + _DECISION_TEXT)}, "
        "json_extract(timings_ms, '$.decide') FROM decisions "
        f"WHERE {where} ORDER BY time_s, run_id, cycle", (lo, hi)).fetchall()
    n = len(rows)
    index = {(r[0], r[1]): i for i, r in enumerate(rows)}
    cols = list(zip(*rows, strict=True))
    run_ids = np.array(cols[0], int)
    decisions: dict[str, np.ndarray] = {}
    for j, name in enumerate(_DECISION_NUMBERS, start=3):
        decisions[name] = np.array([np.nan if v is None else v for v in cols[j]], float)
    for j, name in enumerate(_DECISION_TEXT, start=3 + len(_DECISION_NUMBERS)):
        decisions[name] = np.array([v or "" for v in cols[j]], object)
    decisions["decide_ms"] = np.array([np.nan if v is None else v for v in cols[-1]], float)

    values: dict[str, np.ndarray] = {}
    quality: dict[str, np.ndarray] = {}
    for run, cycle, signal, value, flag in conn.execute(
            f"SELECT run_id, cycle, signal, value, quality FROM samples WHERE {where}",
            (lo, hi)):
        i = index.get((run, cycle))
        if i is None:
            continue
        if signal not in values:
            values[signal] = np.full(n, np.nan)
            quality[signal] = np.full(n, "", object)
        values[signal][i] = np.nan if value is None else value
        quality[signal][i] = flag

    model = {name: np.full(n, np.nan) for name, _ in MODEL_COLUMNS}
    present = columns(conn, "model")
    if present:
        names = [c for c, _ in MODEL_COLUMNS if c in present]
        for run, cycle, *vals in conn.execute(
                f"SELECT run_id, cycle, {', '.join(names)} FROM model WHERE {where}", (lo, hi)):
            i = index.get((run, cycle))
            if i is not None:
                for name, v in zip(names, vals, strict=True):
                    if v is not None:
                        model[name][i] = v
    else:
        notes.append(f"database schema {version}: no model predictions stored (written by "
                     "an older dsfd); prediction errors and model heat are not available")

    # The parameter row in force at the start of the window, then the changes inside it.
    runs_sql = _in(picked)
    start_row = conn.execute(f"SELECT MAX(time_s) FROM parameters WHERE {runs_sql} AND "
                             "time_s <= ?", (lo if math.isfinite(lo) else -1e300,)).fetchone()
    p_lo = start_row[0] if start_row and start_row[0] is not None else lo
    params = _parameters(conn, runs_sql, p_lo, hi)
    events = [(float(t), int(r), level, kind, msg) for t, r, level, kind, msg in conn.execute(
        f"SELECT time_s, run_id, level, kind, message FROM events WHERE {where} "
        "ORDER BY time_s, event_id", (lo, hi))]
    return History(
        path=state_dir / DB_NAME, schema_version=version,
        runs=tuple(all_runs[r] for r in sorted(set(run_ids.tolist())) if r in all_runs),
        time_s=np.array(cols[2], float), run_id=run_ids, cycle=np.array(cols[1], int),
        decisions=decisions, values=values, quality=quality, model=model, parameters=params,
        events=events, notes=tuple(notes))


def _parameters(conn: sqlite3.Connection, runs_sql: str, lo: float, hi: float
                ) -> ParameterHistory:
    rows = conn.execute(
        f"SELECT time_s, run_id, source, {', '.join(PARAMETER_NAMES)}, other FROM parameters "
        f"WHERE {runs_sql} AND time_s BETWEEN ? AND ? ORDER BY time_s, run_id",
        (lo, hi)).fetchall()
    values: dict[str, list[float]] = {name: [] for name in PARAMETER_NAMES}
    others: list[dict[str, float]] = []
    for row in rows:
        for name, v in zip(PARAMETER_NAMES, row[3:3 + len(PARAMETER_NAMES)], strict=True):
            values[name].append(np.nan if v is None else float(v))
        try:
            other = json.loads(row[-1] or "{}")
        except ValueError:
            other = {}
        others.append(other)
    for key in sorted({k for o in others for k in o}):
        values[key] = [float(o.get(key, np.nan)) for o in others]
    return ParameterHistory(
        time_s=np.array([r[0] for r in rows], float), run_id=np.array([r[1] for r in rows], int),
        source=np.array([r[2] for r in rows], object),
        values={k: np.asarray(v, float) for k, v in values.items()})


def measured_from_history(history: History) -> MeasuredData:
    """The history as a measured-data table (``docs/measured-data-csv.md``).

    One row per cycle: every measured column from the samples whose quality was ``good``
    (a flagged sample is a missing value, never its bad value) and the actuator position
    in effect from the row on (:meth:`History.applied`).
    """
    columns: dict[str, np.ndarray] = {}
    for name in KNOWN_COLUMNS:
        if name in CONTROL_COLUMNS:
            continue
        if name in history.values:
            columns[name] = history.good(name)
    columns.update(history.applied())
    runs = ", ".join(f"{r.run_id} ({r.mode})" for r in history.runs)
    flagged = sum(int(np.sum((q != "good") & (q != ""))) for q in history.quality.values())
    notes = (f"exported by dsfd export from {history.path}, panel {history.panel}, runs {runs}",
             f"{len(history)} cycles; {flagged} flagged samples are empty cells",
             *history.notes)
    return MeasuredData(history.time_s.copy(), columns, source=str(history.path), notes=notes)
