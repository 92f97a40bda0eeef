"""The safety pipeline: priority order, what each stage sets and why, and its state."""

from __future__ import annotations

import dataclasses

import pytest

from dsfd.config import load_panel
from dsfd.daemon.safety import SafetyContext, SafetyPipeline
from dsfd.drivers.base import Command
from tests.conftest import PANELS


@pytest.fixture
def cfg():
    return load_panel(PANELS / "suwon-south.yaml")


def ctx(now_s: float = 1000.0, *, wind: float | None = 2.0, bad: frozenset[str] = frozenset(),
        current: Command | None = None, no_decision: str = "") -> SafetyContext:
    return SafetyContext(now_s=now_s, wind_speed_ms=wind, bad_signals=bad, current=current,
                         no_decision_reason=no_decision)


def stages(result) -> dict[str, dict[str, float]]:
    return {t.stage: t.set for t in result.trace}


def why(result, stage: str) -> str:
    return next(t.why for t in result.trace if t.stage == stage)


def test_every_stage_records_itself_in_priority_order(cfg) -> None:
    out = SafetyPipeline(cfg).apply(Command(phi_deg=10.0, afr=1, or_pct=42.4), ctx())
    assert [t.stage for t in out.trace] == ["wind", "hold", "faults", "limits", "quantisation",
                                            "rate", "regimes"]
    assert out.command == Command(phi_deg=18.0, afr=1, or_pct=42.0)  # 18° grid, 1 % steps
    assert stages(out)["quantisation"] == {"phi_deg": 18.0, "or_pct": 42.0}
    assert not out.overridden


def test_missing_inputs_and_fault_signals_give_the_safe_state(cfg) -> None:
    safe = cfg.safety.safe_state
    p = SafetyPipeline(cfg)
    out = p.apply(None, ctx(no_decision="required weather not GOOD: t_out_c (timeout)"))
    assert out.command == Command(phi_deg=safe.phi_deg, afr=safe.afr, or_pct=safe.or_pct)
    assert "t_out_c (timeout)" in why(out, "faults") and out.overridden and out.faulted
    out = p.apply(Command(phi_deg=0.0, afr=3, or_pct=100.0), ctx(bad=frozenset({"ghi_wm2"})))
    assert out.command.afr == safe.afr and "ghi_wm2" in why(out, "faults")


def test_wind_override_with_hysteresis_and_release_delay(cfg) -> None:
    cfg = dataclasses.replace(cfg, safety=dataclasses.replace(
        cfg.safety, wind_limit_ms=15.0, wind_hysteresis_ms=3.0, wind_release_cycles=2))
    p = SafetyPipeline(cfg)
    open_outside = Command(phi_deg=0.0, afr=3, or_pct=100.0)
    winds = [14.0, 16.0, 13.0, 11.0, 11.5, 11.0, 14.0]
    seen = [p.apply(open_outside, ctx(wind=w)) for w in winds]
    active = [r.wind_override for r in seen]
    # on above 15; held inside the band (13) and for 2 cycles below 12; off; 14 stays off.
    assert active == [False, True, True, True, False, False, False]
    hit = seen[1]
    assert hit.command == Command(phi_deg=cfg.safety.wind_safe_angle_deg, afr=10, or_pct=0.0)
    assert "16.0 m/s above 15" in why(hit, "wind")
    assert "exterior dampers closed" in why(hit, "wind")
    assert stages(hit)["wind"] == {"phi_deg": 90.0, "afr": 10, "or_pct": 0.0}
    # Unknown wind counts as high wind by default.
    assert SafetyPipeline(cfg).apply(open_outside, ctx(wind=None)).wind_override


def test_louver_moves_at_most_once_per_interval_but_overrides_move_it(cfg) -> None:
    p = SafetyPipeline(cfg)  # 300 s between moves by default
    here = Command(phi_deg=0.0, afr=10, or_pct=0.0)
    first = p.apply(Command(phi_deg=36.0, afr=10, or_pct=0.0), ctx(100.0, current=here))
    assert first.command.phi_deg == 36.0
    moved = first.command
    held = p.apply(Command(phi_deg=72.0, afr=10, or_pct=0.0), ctx(200.0, current=moved))
    assert held.command.phi_deg == 36.0 and "held at +36 deg" in why(held, "rate")
    later = p.apply(Command(phi_deg=72.0, afr=10, or_pct=0.0), ctx(401.0, current=moved))
    assert later.command.phi_deg == 72.0
    storm = p.apply(Command(phi_deg=0.0, afr=10, or_pct=0.0),
                    ctx(402.0, wind=30.0, current=later.command))
    assert storm.command.phi_deg == cfg.safety.wind_safe_angle_deg  # safety first


def test_damper_deadband_and_regimes_the_panel_lacks(cfg) -> None:
    p = SafetyPipeline(cfg)
    now = Command(phi_deg=0.0, afr=1, or_pct=50.0)
    out = p.apply(Command(phi_deg=0.0, afr=1, or_pct=53.0), ctx(current=now))
    assert out.command.or_pct == 50.0 and "dead-band" in why(out, "rate")
    out = p.apply(Command(phi_deg=0.0, afr=3, or_pct=53.0), ctx(current=now))
    assert out.command.or_pct == 53.0  # a regime change always goes through
    no_exterior = dataclasses.replace(cfg, openings=dataclasses.replace(
        cfg.openings, exterior_bottom=None, exterior_top=None))
    out = SafetyPipeline(no_exterior).apply(Command(phi_deg=0.0, afr=3, or_pct=80.0), ctx())
    assert (out.command.afr, out.command.or_pct) == (10, 0.0)
    assert "needs dampers this panel lacks" in out.trace[-1].why


def test_limits_clamp_to_the_mechanism(cfg) -> None:
    cfg = dataclasses.replace(cfg, safety=dataclasses.replace(
        cfg.safety, phi_min_deg=-40.0, phi_max_deg=60.0, or_max_pct=80.0))
    out = SafetyPipeline(cfg).apply(Command(phi_deg=90.0, afr=1, or_pct=100.0), ctx())
    assert out.command == Command(phi_deg=54.0, afr=1, or_pct=80.0)
