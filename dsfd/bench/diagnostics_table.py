"""The table of ``dsfd bench diagnostics`` and how a run is scored (docs/model.md
#diagnostics-bench): the issue's faults at their sizes (:func:`scenarios`), the finding kinds
that name each (:data:`NAMES`), and :func:`score`, which reads the ``findings`` table a run
left:

* **false findings** — those opened before the fault's onset (every fault run has a clean
  prefix), and every finding of a clean run;
* **detected** — the first finding opened at or after the onset; **named** — the first one
  of the kinds that name the fault: a finding of another kind detects the change without
  naming it;
* **delay** — from the onset to the named finding's opening, counted the way the issue's
  target counts it (:class:`Scenario`): minutes of operation that use the stuck damper,
  minutes of sun for a slipped louver, elapsed time for the rest.
"""

from __future__ import annotations

import sqlite3
from dataclasses import dataclass
from pathlib import Path

from dsfd.config.panel import REGIME_OPENINGS
from dsfd.estimation.solar_response import DIRT, DIRT_OR_LOUVER, LOUVER_OR_CLEANED
from dsfd.storage.evidence import DAMPER_SHORT

__all__ = ["NAMES", "PREFIX_DAYS", "SECONDS_PER_DAY", "SUN_GHI_WM2", "Scenario", "scenarios",
           "score"]

SECONDS_PER_DAY = 86400.0
#: Clean days before a fault that one of the history-hungry detectors must find.
PREFIX_DAYS = 8.0
#: A minute "of sun" for the louver target: global horizontal irradiance above the WMO's
#: sunshine threshold (120 W/m², WMO-No. 8, on the direct beam; on the horizontal it is a
#: proxy, stated as such).
SUN_GHI_WM2 = 120.0
#: The record's morning (08:30 in Suwon) where the stuck-damper runs start.
MORNING_ISO = "2022-01-01T23:30:00Z"


@dataclass(frozen=True, kw_only=True)
class Scenario:
    """One run of the bench.

    Attributes
    ----------
    name : str
        Row of the table (``stuck-damper``, ``louver-slip``, …, ``clean``).
    fault : str or None
        The ``--fault`` argument (its start an offset from the run's start); None: clean.
    onset_s : float, [s]
        The fault's start after the run's start (the clean run: its end).
    days : float, [d]
        Length of the run.
    deadline : float
        The target: within this many minutes (``delay_unit``).
    delay_unit : str
        ``operation_min`` (minutes whose command opens the stuck damper), ``sun_min``
        (minutes of sun, :data:`SUN_GHI_WM2`) or ``elapsed_min``.
    start : str or None
        ``--start`` (ISO UTC); None: the record's first minute.
    """

    name: str
    fault: str | None
    onset_s: float
    days: float
    deadline: float
    delay_unit: str
    start: str | None = None


#: Finding kinds (and subjects) that name each fault; a fault whose list is empty has no
#: detector of its own yet, and is at best detected by another kind.
NAMES: dict[str, tuple[tuple[str, str | None], ...]] = {
    "stuck-damper": (("damper_no_flow", None),),
    # the louver's heat-flux offset and the slats' convection: both actions name a slip; the
    # solar detector where it names the louver (with dirt, or with cleaned glass)
    "louver-slip": (("parameter_shift", "parameter:q_x4"), ("parameter_shift", "parameter:h_ca2"),
                    ("solar_gain_shift", DIRT_OR_LOUVER), ("solar_gain_shift", LOUVER_OR_CLEANED)),
    # the inner pane's heat-flux offset, at night or as daily means: its action names the
    # sensor x3 first
    "tc-offset": (("night_offset_shift", "night:q_x3"), ("residual_shift", "residual:x3_c"),
                  ("parameter_shift", "parameter:q_x3")),
    "tc-drift": (("night_offset_shift", "night:q_x3"), ("residual_shift", "residual:x3_c"),
                 ("parameter_shift", "parameter:q_x3")),
    # the solar detector where it names dirt (alone, or with the louver)
    "soiling": (("solar_gain_shift", DIRT), ("solar_gain_shift", DIRT_OR_LOUVER)),
    "screen": (("parameter_shift", "parameter:f"),),
}


def scenarios(*, clean_days: float) -> list[Scenario]:
    """The issue's table at its sizes, then a clean run of ``clean_days``."""
    p = PREFIX_DAYS
    day = SECONDS_PER_DAY
    return [
        Scenario(name="stuck-damper", fault="damper-stuck.IT:+30min:0", onset_s=1800.0,
                 days=0.5, deadline=30.0, delay_unit="operation_min", start=MORNING_ISO),
        Scenario(name="louver-slip", fault=f"louver-slip:+{p:g}d:1", onset_s=p * day,
                 days=p + 2.0, deadline=120.0, delay_unit="sun_min"),
        Scenario(name="tc-offset", fault=f"tc-offset.x3:+{p:g}d:1", onset_s=p * day,
                 days=p + 1.5, deadline=1440.0, delay_unit="elapsed_min"),
        Scenario(name="tc-drift", fault=f"tc-drift.x3:+{p:g}d:0.5", onset_s=p * day,
                 days=p + 1.5, deadline=1440.0, delay_unit="elapsed_min"),
        # 10 % of the transmittance lost over the 7 days of the target
        Scenario(name="soiling", fault=f"soiling:+{p:g}d:{10.0 / 7.0:.4f}", onset_s=p * day,
                 days=p + 7.5, deadline=7 * 1440.0, delay_unit="elapsed_min"),
        # the path resistance doubled in the 2 days of the target
        Scenario(name="screen", fault=f"screen:+{p:g}d:0.5", onset_s=p * day,
                 days=p + 2.5, deadline=2 * 1440.0, delay_unit="elapsed_min"),
        Scenario(name="clean", fault=None, onset_s=clean_days * day, days=clean_days,
                 deadline=0.0, delay_unit="elapsed_min"),
    ]


# ------------------------------------------------------------------------------- scoring
@dataclass(frozen=True)
class _Found:
    kind: str
    subject: str
    opened_s: float

    @property
    def label(self) -> str:
        return f"{self.kind}:{self.subject}" if self.subject else self.kind


def _findings(conn: sqlite3.Connection) -> list[_Found]:
    return [_Found(str(k), str(s), float(t)) for k, s, t in conn.execute(
        "SELECT kind, subject, opened_s FROM findings ORDER BY opened_s, finding_id")]


def _names(scenario: Scenario, f: _Found) -> bool:
    for kind, subject in NAMES.get(scenario.name, ()):
        if f.kind != kind:
            continue
        if scenario.name == "stuck-damper":  # "IT", or "EB+IT" while one path was tried
            return "IT" in f.subject.split("+")
        if subject is None or f.subject == subject:
            return True
    return False


def _minutes(conn: sqlite3.Connection, scenario: Scenario, since_s: float, until_s: float
             ) -> float:
    """Minutes from ``since_s`` to ``until_s`` in the scenario's delay unit."""
    if scenario.delay_unit == "elapsed_min":
        return (until_s - since_s) / 60.0
    if scenario.delay_unit == "sun_min":
        return float(conn.execute(
            "SELECT COUNT(*) FROM samples WHERE signal = 'ghi_wm2' AND quality = 'good' AND "
            "value > ? AND time_s >= ? AND time_s <= ?",
            (SUN_GHI_WM2, since_s, until_s)).fetchone()[0])
    # operation_min: the one-minute cycles whose command in force opened the stuck damper
    used = 0
    for afr, or_pct in conn.execute(
            "SELECT applied_afr, applied_or_pct FROM model WHERE time_s >= ? AND time_s < ? "
            "AND applied_afr IS NOT NULL", (since_s, until_s)):
        opened = {DAMPER_SHORT[n] for n in REGIME_OPENINGS.get(int(afr), ())}
        used += bool(or_pct) and "IT" in opened
    return float(used)


def score(db: Path, scenario: Scenario) -> dict[str, float | str]:
    """The scenario's figures from the database a run left (see the module docstring)."""
    conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        t0, t_end = (float(v) for v in conn.execute(
            "SELECT MIN(time_s), MAX(time_s) FROM decisions").fetchone())
        onset = t0 + scenario.onset_s
        found = _findings(conn)
        before = [f for f in found if f.opened_s < onset]
        after = [f for f in found if f.opened_s >= onset]
        out: dict[str, float | str] = {
            "days": (t_end - t0) / SECONDS_PER_DAY,
            "clean_days": (min(onset, t_end) - t0) / SECONDS_PER_DAY,
            "false_findings": float(len(before)),
            "false_kinds": ",".join(sorted({f.label for f in before})),
        }
        if scenario.fault is None:
            return out
        named = next((f for f in after if _names(scenario, f)), None)
        out.update(detected=float(bool(after)), first_kind=after[0].label if after else "",
                   named=float(named is not None), deadline_min=scenario.deadline,
                   observed_min=_minutes(conn, scenario, onset, t_end))
        if after:
            out["detect_delay_min"] = _minutes(conn, scenario, onset, after[0].opened_s)
        if named is not None:
            delay = _minutes(conn, scenario, onset, named.opened_s)
            out.update(name_delay_min=delay, within_target=float(delay <= scenario.deadline))
        return out
    finally:
        conn.close()
