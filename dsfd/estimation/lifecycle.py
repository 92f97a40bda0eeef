"""The life of a finding: what the detectors see now against what is stored (pure).

The daemon runs the detectors (:mod:`dsfd.estimation.diagnostics`,
:mod:`dsfd.estimation.crosschecks`) every few minutes on its recent rows; each run gives the
findings the evidence supports *now*. :func:`reconcile` turns that into changes of the
stored findings (docs/model.md#findings):

* a detection whose key (:func:`key_of`: the kind, and the signal of a one-signal kind) has
  an **open** stored finding refreshes it (confidence, evidence, subject, the last time it
  was seen);
* a detection whose key was **acknowledged** by an operator stays closed while its
  evidence started no later than the acknowledgement (the operator has seen it); evidence
  that starts after it (a later change point, or a window of readings entirely after it)
  is new, and opens a new finding;
* any other detection opens a new finding;
* an open finding the detectors no longer report **ends**: its evidence went away (only
  when its detector ran: one that runs less often, or lacks the history, ends nothing).

Two alarm delays go around it: :func:`confirmed` holds a new finding back until its evidence
has lasted, :func:`held_open` an end until the evidence has stayed away.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

from dsfd.estimation.diagnostics import Finding

__all__ = ["ACKNOWLEDGED", "ENDED", "FINDING_KINDS", "OPEN", "Changes", "StoredFinding",
           "confirmed", "held_open", "key_of", "reconcile", "subject_of"]

OPEN, ACKNOWLEDGED, ENDED = "open", "acknowledged", "ended"
#: Every kind the detectors report (one Home Assistant problem sensor and one metric each).
FINDING_KINDS = ("damper_no_flow", "cavity_no_flow", "cavity_flow_when_closed",
                 "pane_out_of_bounds", "pane_offset_shift", "residual_shift", "parameter_shift",
                 "night_offset_shift", "solar_gain_shift")
#: Kinds about one signal: the subject is the evidence's signal.
_SIGNAL_KINDS = frozenset({"residual_shift", "parameter_shift", "pane_out_of_bounds",
                           "pane_offset_shift", "night_offset_shift"})


def subject_of(f: Finding) -> str:
    """What the finding is about: its own subject (the damper(s) of ``damper_no_flow``),
    else the signal of a one-signal kind, else ''."""
    if f.subject:
        return f.subject
    if f.kind in _SIGNAL_KINDS and f.evidence:
        return f.evidence[0].signal
    return ""


def _key(kind: str, subject: str) -> tuple[str, str]:
    # A one-signal kind is one finding per signal. The cavity cross-check reports one
    # finding per check; the damper it names is refined as readings come in (a path seen
    # flowing before the fault can first clear the stuck damper), so its kind alone is the
    # key and the subject follows the latest check.
    return (kind, subject) if kind in _SIGNAL_KINDS else (kind, "")


def key_of(f: Finding) -> tuple[str, str]:
    """What tells one finding from another: (kind, signal) for a one-signal kind, else
    (kind, '')."""
    return _key(f.kind, subject_of(f))


@dataclass(frozen=True, kw_only=True)
class StoredFinding:
    """What :func:`reconcile` needs of a stored finding.

    ``closed_s``: when it was acknowledged or ended [s] (None while open).
    """

    finding_id: int
    kind: str
    subject: str
    state: str
    start_s: float
    closed_s: float | None = None

    @property
    def key(self) -> tuple[str, str]:
        return _key(self.kind, self.subject)


@dataclass
class Changes:
    """``opened``: new findings; ``refreshed``: (id, the detection now) of open ones;
    ``ended``: ids of open ones whose evidence went away; ``kept_closed``: (id of the
    acknowledged finding, the detection it covers)."""

    opened: list[Finding] = field(default_factory=list)
    refreshed: list[tuple[int, Finding]] = field(default_factory=list)
    ended: list[int] = field(default_factory=list)
    kept_closed: list[tuple[int, Finding]] = field(default_factory=list)


def reconcile(detected: Iterable[Finding], stored: Sequence[StoredFinding], *,
              judged: Collection[str] | None = None) -> Changes:
    """The changes that take the ``stored`` findings to what ``detected`` says now.

    ``stored`` holds at least every open finding and, per key, the latest acknowledged one
    (older rows change nothing). Two detections with one key: the first counts. ``judged``:
    the kinds whose detectors ran (None: all); an open finding of a kind not judged this
    time keeps its state (a detector that did not run has not seen the evidence go).
    """
    out = Changes()
    open_by_key = {s.key: s for s in stored if s.state == OPEN}
    acked: dict[tuple[str, str], StoredFinding] = {}
    for s in stored:
        if s.state == ACKNOWLEDGED and (s.key not in acked
                                        or s.finding_id > acked[s.key].finding_id):
            acked[s.key] = s
    seen: set[tuple[str, str]] = set()
    for f in detected:
        key = key_of(f)
        if key in seen:
            continue
        seen.add(key)
        if key in open_by_key:
            out.refreshed.append((open_by_key[key].finding_id, f))
            continue
        ack = acked.get(key)
        if ack is not None and ack.closed_s is not None and f.start_s <= ack.closed_s:
            out.kept_closed.append((ack.finding_id, f))
            continue
        out.opened.append(f)
    out.ended = [s.finding_id for k, s in open_by_key.items()
                 if k not in seen and (judged is None or s.kind in judged)]
    return out


def confirmed(detected: Iterable[Finding], stored: Sequence[StoredFinding],
              pending: Mapping[tuple[str, str], float], *, now_s: float, confirm_s: float,
              kinds: Collection[str]) -> tuple[list[Finding], dict[tuple[str, str], float]]:
    """Hold back new findings of ``kinds`` until their evidence has lasted ``confirm_s``.

    The time delay of an alarm (BACnet's ``Time_Delay`` of intrinsic reporting, ASHRAE 135
    clause 13.3: a condition must persist that long before the object reports it): a
    detection of one of ``kinds`` whose key has no open stored finding passes once the
    same key has been detected, check after check, since at least ``confirm_s`` ago.
    ``pending`` maps each such key to when it was first seen; the new map is returned with
    the detections that pass (the others unchanged). A key not detected in this check
    starts again. Open findings are refreshed (or ended) as usual: only the opening waits.
    """
    is_open = {s.key for s in stored if s.state == OPEN}
    out: list[Finding] = []
    waiting: dict[tuple[str, str], float] = {}
    for f in detected:
        key = key_of(f)
        if f.kind not in kinds or key in is_open:
            out.append(f)
            continue
        first = pending.get(key, now_s)
        if now_s - first >= confirm_s:
            out.append(f)
        else:
            waiting[key] = first
    return out, waiting


def held_open(changes: Changes, stored: Sequence[StoredFinding],
              absent: Mapping[tuple[str, str], float], *, now_s: float, release_s: float,
              kinds: Collection[str], judged: Collection[str]
              ) -> tuple[Changes, dict[tuple[str, str], float]]:
    """Hold back the end of open findings of ``kinds`` until their evidence has stayed away
    ``release_s``.

    The time delay of an alarm's return to normal (BACnet's ``Time_Delay_Normal`` of
    intrinsic reporting, ASHRAE 135 clause 13.3: the condition must have been normal that long
    before the object reports it): a detector whose statistic hovers at its threshold would
    otherwise end a finding and open a new one for the same change. ``absent`` maps the key of
    each open finding held so far to when its detector first missed it; the new map is
    returned with ``changes`` whose ``ended`` keeps only the ends that are due. A key seen
    again starts afresh; one whose detector did not run (not in ``judged``) keeps its time.
    """
    by_id = {s.finding_id: s for s in stored}
    still_open = {s.key: s.kind for s in stored if s.state == OPEN}
    waiting = {k: t for k, t in absent.items()
               if k in still_open and still_open[k] not in judged}
    ended: list[int] = []
    for fid in changes.ended:
        s = by_id[fid]
        first = absent.get(s.key, now_s)
        if s.kind not in kinds or now_s - first >= release_s:
            ended.append(fid)
        else:
            waiting[s.key] = first
    return replace(changes, ended=ended), waiting
