"""The paper's random excitation protocol (Fig. 7a)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.sim.protocol import PAPER_REGIMES, paper_protocol


def test_protocol_holds_30_to_90_minutes_on_the_grid(suwon):
    s = paper_protocol(suwon, seed=3, start_s=0.0, duration_s=5 * 86400.0)
    holds = np.diff(s.times_s)
    assert holds.min() >= 1800.0 and holds.max() <= 5400.0
    assert np.all(holds % 60.0 == 0.0)
    assert {c.afr for c in s.commands} == set(PAPER_REGIMES)
    assert {c.phi_deg for c in s.commands} <= set(suwon.louver.angles_deg())
    assert len({c.phi_deg for c in s.commands}) >= 8
    assert all(c.or_pct == 100.0 for c in s.commands)
    assert s.at(-5.0) == s.commands[0] and s.at(s.times_s[3] + 1.0) == s.commands[3]


def test_protocol_is_seeded(suwon):
    a = paper_protocol(suwon, seed=7, start_s=0.0, duration_s=86400.0, or_pct=60.0)
    b = paper_protocol(suwon, seed=7, start_s=0.0, duration_s=86400.0, or_pct=60.0)
    c = paper_protocol(suwon, seed=8, start_s=0.0, duration_s=86400.0, or_pct=60.0)
    assert a == b and a != c
    assert all(cmd.or_pct == 60.0 for cmd in a.commands)


def test_protocol_uses_only_available_regimes(suwon):
    ops = dataclasses.replace(suwon.openings, exterior_top=None, exterior_bottom=None)
    cfg = dataclasses.replace(suwon, openings=ops)
    s = paper_protocol(cfg, seed=1, start_s=0.0, duration_s=86400.0)
    assert {c.afr for c in s.commands} == {1}
    with pytest.raises(ValueError):
        paper_protocol(cfg, seed=1, start_s=0.0, duration_s=86400.0, regimes=[3, 5])
