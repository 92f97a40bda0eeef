"""The energy at stake of open parameter findings is costed when first reported and every
STAKE_EVERY_S after (dsfd.daemon.stake.StakeCache): the detector reports an open finding at
every hourly run, and costing a week twice per finding is the findings thread's largest
expense. Between costings a finding carries the last figure. The costing itself is replaced
by a counter here (its figures are tested against ``dsfd export`` in test_run_summary)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

import dsfd.daemon.stake as stake
from dsfd.config import load_panel
from dsfd.estimation.diagnostics import Evidence, Finding
from tests.conftest import PANELS


def _finding(name: str) -> Finding:
    ev = Evidence(signal=f"parameter:{name}", shift=0.5, shift_sd=5.0, unit="log",
                  since_s=0.0, statistic=6.0, threshold=5.0)
    return Finding(kind="parameter_shift", confidence=0.6, start_s=0.0, detected_s=1.0,
                   evidence=(ev,), action=f"{name} has risen")


@pytest.fixture
def counted(monkeypatch):
    calls = {"week": 0, "stake": []}

    def fake_record(panel, state_dir, now_s):
        calls["week"] += 1
        return "week"

    def fake_stake(conn, f, now_s, *, panel, steps):
        calls["stake"].append((f.evidence[0].signal, now_s))
        ev = Evidence(signal=stake.STAKE_SIGNAL, shift=now_s / 3600.0, shift_sd=math.nan,
                      unit="kWh/week", since_s=now_s, statistic=math.nan, threshold=math.nan)
        return dataclasses.replace(f, evidence=(*f.evidence, ev),
                                   action=f.action + f"; costs {now_s / 3600.0:g} kWh")

    monkeypatch.setattr(stake, "stake_record", fake_record)
    monkeypatch.setattr(stake, "with_stake", fake_stake)
    return calls


def test_a_finding_is_costed_when_new_and_every_six_hours_and_keeps_its_figure(counted):
    cache = stake.StakeCache(load_panel(PANELS / "suwon-south.yaml"), Path("."))
    f, q = _finding("f"), _finding("q_x3")  # an offset's finding is never costed
    hourly = [cache.apply(None, [f, q], h * 3600.0) for h in range(13)]
    assert counted["stake"] == [("parameter:f", 0.0), ("parameter:f", 6 * 3600.0),
                                ("parameter:f", 12 * 3600.0)]
    assert counted["week"] == 3 and cache.costings == 3
    for h, (costed_f, offset) in enumerate(hourly):
        at = 6 * (h // 6)  # the figure of the last costing
        assert costed_f.evidence[-1].shift == at and costed_f.action.endswith(f"costs {at} kWh")
        assert costed_f.evidence[0] == f.evidence[0] and offset == q
    # a second finding is costed when it appears; the first keeps its cadence
    h = _finding("h_in")
    cache.apply(None, [f, h], 14 * 3600.0)
    assert counted["stake"][-1] == ("parameter:h_in", 14 * 3600.0) and cache.costings == 4
    # nothing costed, no week read
    cache.apply(None, [q], 15 * 3600.0)
    assert counted["week"] == 4


@pytest.mark.parametrize(("per_week", "words"), [
    (1.234, "the change costs about 1.23 kWh a week"),
    (-0.2, "the change saves about 0.20 kWh a week"),
    (0.0013, "the change moves the cost by less than 0.01 kWh a week")])
def test_the_stake_sentence_says_cost_or_saving_and_no_false_zero(monkeypatch, per_week,
                                                                   words):
    """A stake too small for two decimals is said to be small, not "about 0.00"."""
    monkeypatch.setattr(stake, "_stake", lambda *a: stake.EnergyAtStake(
        j_before_kwh=0.0, j_now_kwh=per_week, days=7.0, per_week_kwh=per_week))
    f = stake.with_stake(None, _finding("f"), 0.0, panel=None, steps="week")
    assert f.evidence[-1].shift == per_week and words in f.action
