"""The life of a finding (dsfd.estimation.lifecycle.reconcile), pure: refreshed while its
evidence lasts, ended when it goes, and an acknowledged one stays closed until evidence that
starts after the acknowledgement."""

from __future__ import annotations

from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.lifecycle import (
    ACKNOWLEDGED,
    ENDED,
    OPEN,
    StoredFinding,
    confirmed,
    key_of,
    reconcile,
)


def _finding(kind: str = "damper_no_flow", *, start_s: float = 1000.0, subject: str = "IT",
             signal: str = "crosscheck:v_cav_ms[EB+IT]") -> Finding:
    ev = Evidence(signal=signal, shift=-0.04, shift_sd=-2.0, unit="m/s",
                  since_s=start_s, statistic=0.0, threshold=0.02)
    return Finding(kind=kind, confidence=0.9, start_s=start_s, detected_s=start_s + 1800,
                   evidence=(ev,), action="check damper IT", subject=subject)


def _stored(fid: int, state: str, *, start_s: float = 1000.0, closed_s: float | None = None,
            kind: str = "damper_no_flow", subject: str = "IT") -> StoredFinding:
    return StoredFinding(finding_id=fid, kind=kind, subject=subject, state=state,
                         start_s=start_s, closed_s=closed_s)


def test_a_new_detection_opens_and_an_open_one_is_refreshed_while_it_lasts():
    first = reconcile([_finding()], [])
    assert first.opened == [_finding()] and not first.refreshed and not first.ended
    again = reconcile([_finding()], [_stored(1, OPEN)])
    assert again.refreshed == [(1, _finding())] and not again.opened and not again.ended


def test_an_open_finding_ends_when_its_evidence_goes_away():
    ch = reconcile([], [_stored(1, OPEN), _stored(2, ENDED, closed_s=5.0, subject="EB")])
    assert ch.ended == [1] and not ch.opened


def test_an_acknowledged_finding_stays_closed_until_evidence_that_starts_after_the_ack():
    acked = [_stored(1, ACKNOWLEDGED, start_s=1000.0, closed_s=4000.0)]
    # the same evidence, and evidence still starting before the acknowledgement: closed
    for start in (1000.0, 3999.0, 4000.0):
        ch = reconcile([_finding(start_s=start)], acked)
        assert not ch.opened and not ch.refreshed and not ch.ended
        assert [fid for fid, _ in ch.kept_closed] == [1]
    # the evidence went away meanwhile: nothing to do either
    assert not reconcile([], acked).opened
    # a change that starts after the acknowledgement is new evidence: a new finding
    ch = reconcile([_finding(start_s=4000.5)], acked)
    assert ch.opened == [_finding(start_s=4000.5)] and not ch.kept_closed


def test_only_the_latest_acknowledgement_of_a_key_counts_and_other_keys_are_independent():
    stored = [_stored(1, ACKNOWLEDGED, closed_s=9000.0), _stored(3, ACKNOWLEDGED, closed_s=2000.0)]
    # finding 3 is the newer acknowledgement: evidence from 5000 s is after it
    assert reconcile([_finding(start_s=5000.0)], stored).opened
    # a residual finding is one per signal: x2 is independent of what was said about x3
    x3 = [_stored(5, ACKNOWLEDGED, kind="residual_shift", subject="residual:x3_c",
                  closed_s=9000.0)]
    x2 = _finding("residual_shift", subject="", signal="residual:x2_c", start_s=10.0)
    assert reconcile([x2], x3).opened == [x2]
    assert not reconcile([_finding("residual_shift", subject="", signal="residual:x3_c",
                                   start_s=10.0)], x3).opened


def test_the_cross_check_is_one_finding_per_kind_whose_damper_follows_the_latest_check():
    # the check first blamed IB+IT (no path had cleared IB yet), now IT alone: the same
    # finding, refreshed (the stored subject follows), not an end and a new one
    ch = reconcile([_finding(subject="IT")], [_stored(1, OPEN, subject="IB+IT")])
    assert [fid for fid, _ in ch.refreshed] == [1] and not ch.opened and not ch.ended
    # and an acknowledgement of "IB+IT" covers the refined "IT" of the same evidence
    ch = reconcile([_finding(subject="IT")],
                   [_stored(1, ACKNOWLEDGED, subject="IB+IT", closed_s=5000.0)])
    assert not ch.opened and [fid for fid, _ in ch.kept_closed] == [1]


def test_the_key_tells_findings_apart_by_kind_and_signal():
    assert key_of(_finding()) == ("damper_no_flow", "")
    residual = _finding("residual_shift", subject="", signal="residual:x3_c")
    assert key_of(residual) == ("residual_shift", "residual:x3_c")
    assert key_of(_finding("cavity_no_flow", subject="")) == ("cavity_no_flow", "")
    # two detections with one key in one check: one finding
    assert len(reconcile([_finding(), _finding(start_s=50.0)], []).opened) == 1


def test_a_detector_that_did_not_run_ends_none_of_its_findings():
    residual = _stored(4, OPEN, kind="residual_shift", subject="residual:x3_c")
    flow = _stored(5, OPEN)
    ch = reconcile([], [residual, flow], judged={"damper_no_flow"})
    assert ch.ended == [5]  # the cross-check ran and no longer sees it; the CUSUM did not run
    assert reconcile([], [residual, flow], judged=set()).ended == []


def test_a_new_cross_check_finding_waits_for_its_time_delay_an_open_one_does_not():
    """Alarm time delay (BACnet Time_Delay): the evidence must be reported check after
    check for ``confirm_s`` before a finding opens; a check without it starts again."""
    flow = ("damper_no_flow",)
    f = _finding()
    kept, pending = confirmed([f], [], {}, now_s=0.0, confirm_s=300.0, kinds=flow)
    assert kept == [] and pending == {key_of(f): 0.0}
    kept, pending = confirmed([f], [], pending, now_s=299.0, confirm_s=300.0, kinds=flow)
    assert kept == [] and pending == {key_of(f): 0.0}
    kept, pending = confirmed([f], [], pending, now_s=300.0, confirm_s=300.0, kinds=flow)
    assert kept == [f] and pending == {}
    # a blip: seen once, gone at the next check, seen again later: the delay starts again
    _, pending = confirmed([f], [], {}, now_s=0.0, confirm_s=300.0, kinds=flow)
    _, pending = confirmed([], [], pending, now_s=300.0, confirm_s=300.0, kinds=flow)
    kept, pending = confirmed([f], [], pending, now_s=600.0, confirm_s=300.0, kinds=flow)
    assert kept == [] and pending == {key_of(f): 600.0}
    # an open finding of that key is refreshed at once; other kinds never wait
    kept, _ = confirmed([f], [_stored(1, OPEN)], {}, now_s=0.0, confirm_s=300.0, kinds=flow)
    assert kept == [f]
    r = _finding("residual_shift", subject="residual:x3_c")
    kept, pending = confirmed([r], [], {}, now_s=0.0, confirm_s=300.0, kinds=flow)
    assert kept == [r] and pending == {}


def test_an_open_finding_of_a_held_kind_ends_only_after_its_evidence_stayed_away():
    """held_open: the return delay of an alarm. A parameter finding the detector misses is
    kept open until it has missed it for release_s; seen again, the delay starts afresh;
    checks in which its detector did not run keep the time it was first missed. Other kinds
    end at once."""
    from dsfd.estimation.lifecycle import held_open

    par = _stored(1, OPEN, kind="parameter_shift", subject="parameter:f")
    flow = _stored(2, OPEN)
    kw = {"release_s": 100.0, "kinds": ("parameter_shift",)}
    judged_all = ("parameter_shift", "damper_no_flow")
    ch, absent = held_open(reconcile([], [par, flow]), [par, flow], {}, now_s=0.0,
                           judged=judged_all, **kw)
    assert ch.ended == [2] and absent == {par.key: 0.0}
    # a check in which the parameter detector did not run: nothing ends, the time is kept
    ch, absent = held_open(reconcile([], [par], judged=()), [par], absent, now_s=50.0,
                           judged=(), **kw)
    assert not ch.ended and absent == {par.key: 0.0}
    ch, absent = held_open(reconcile([], [par]), [par], absent, now_s=99.0,
                           judged=judged_all, **kw)
    assert not ch.ended and absent == {par.key: 0.0}
    # seen again: refreshed, and the delay starts afresh when it is missed next
    seen = _finding("parameter_shift", subject="", signal="parameter:f")
    ch, absent = held_open(reconcile([seen], [par]), [par], absent, now_s=120.0,
                           judged=judged_all, **kw)
    assert [fid for fid, _ in ch.refreshed] == [1] and absent == {}
    ch, absent = held_open(reconcile([], [par]), [par], absent, now_s=130.0,
                           judged=judged_all, **kw)
    assert not ch.ended and absent == {par.key: 130.0}
    ch, absent = held_open(reconcile([], [par]), [par], absent, now_s=230.0,
                           judged=judged_all, **kw)
    assert ch.ended == [1] and absent == {}
