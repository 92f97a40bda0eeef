"""The safety pipeline: an explicit priority order applied to every command before it is written.

Stages, highest priority first; each records what it set and why (the decision trace):

1. **wind** — station wind above ``wind_limit_ms`` → louver to the wind-safe angle and exterior
   dampers closed, until the wind stayed below the limit minus the hysteresis for
   ``wind_release_cycles`` cycles; unknown wind acts per ``wind_unknown``. A person's hold
   never stops the façade from protecting itself;
2. **hold** — a manual hold (:mod:`dsfd.daemon.hold`) replaces the proposal by the held
   position. Unless the wind acts or the held position differs from the read-back (an
   operator's positions, or the position to restore after a wind override), nothing is
   written; the stages below do not touch a person's position;
3. **faults** — no decision could be made (inputs missing) or a ``safety.fault_signals``
   sensor is not GOOD → the configured safe state;
4. **limits** — louver angle inside the mechanical limits, damper opening inside
   0..``or_max_pct``, no opening in the closed regime;
5. **quantisation** — louver angle onto the motor's grid (18° steps) inside the limits,
   damper opening onto its resolution ``or_step_pct``;
6. **rate** — at most one louver move per ``min_louver_move_interval_s`` and no damper moves
   smaller than ``or_deadband_pct`` (wind and faults bypass this: safety first);
7. **regimes** — a regime whose dampers the panel lacks becomes the closed regime.

The command values are built in that priority: the base (held position, else the safe state
on a fault, else the proposal), the wind's changes on top, then the mechanical stages. The
trace lists the stages in priority order.

Pure: no I/O, no clock; the loop passes the time and the measured wind.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from dsfd.config.panel import CLOSED_REGIME, REGIME_OPENINGS, PanelConfig
from dsfd.daemon.hold import Hold
from dsfd.drivers.base import Command

__all__ = ["CLOSED", "STAGES", "SafetyContext", "SafetyPipeline", "SafetyResult", "TraceEntry"]

CLOSED = CLOSED_REGIME
#: The stages in priority order (the order of the trace).
STAGES = ("wind", "hold", "faults", "limits", "quantisation", "rate", "regimes")
_EXTERIOR = frozenset({"exterior_bottom", "exterior_top"})


@dataclass(frozen=True)
class TraceEntry:
    """One stage's effect: the fields it set (empty if none) and why."""

    stage: str
    set: dict[str, float]
    why: str

    def as_dict(self) -> dict[str, object]:
        return {"stage": self.stage, "set": self.set, "why": self.why}


@dataclass(frozen=True)
class SafetyContext:
    """What the pipeline needs to know about this cycle.

    Attributes
    ----------
    now_s : float, [s]
        Monotonic time of the decision (for the louver move interval).
    wind_speed_ms : float or None, [m/s]
        GOOD station wind speed, None if unknown.
    bad_signals : frozenset of str
        Sensors that are not GOOD this cycle.
    current : Command or None
        Actuator position now (device read-back, else the last command written).
    no_decision_reason : str
        Non-empty if neither the optimiser nor the baseline could decide.
    hold : Hold or None
        The active manual hold, if any.
    """

    now_s: float
    wind_speed_ms: float | None
    bad_signals: frozenset[str] = frozenset()
    current: Command | None = None
    no_decision_reason: str = ""
    hold: Hold | None = None


@dataclass(frozen=True)
class SafetyResult:
    """The command to write and how it was reached."""

    command: Command
    trace: tuple[TraceEntry, ...]
    #: True if a fault or the wind override set the command (bypassing rate limits).
    overridden: bool
    #: True while the wind override is active.
    wind_override: bool
    #: True if the faults stage commanded the safe state.
    faulted: bool = False
    #: True while a manual hold is active.
    held: bool = False
    #: False if nothing is to be written (held in place, no wind).
    write: bool = True

    def trace_dicts(self) -> list[dict[str, object]]:
        return [t.as_dict() for t in self.trace]


@dataclass
class _Draft:
    phi_deg: float
    afr: int
    or_pct: float
    trace: list[TraceEntry] = field(default_factory=list)

    def set(self, stage: str, why: str, **values: float) -> None:
        changed = {k: v for k, v in values.items() if getattr(self, k) != v}
        for k, v in changed.items():
            setattr(self, k, int(v) if k == "afr" else float(v))
        self.trace.append(TraceEntry(stage, changed, why))

    def ordered(self) -> tuple[TraceEntry, ...]:
        """The trace in priority order (stages run in the order their values need)."""
        return tuple(sorted(self.trace, key=lambda t: STAGES.index(t.stage)))


class SafetyPipeline:
    """Applies the stages in order; keeps the wind-override and louver-move state."""

    def __init__(self, cfg: PanelConfig) -> None:
        self.cfg = cfg
        self.wind_override = False
        self._calm_cycles = 0
        #: Monotonic time of the last louver move the pipeline let through [s].
        self.last_louver_move_s: float | None = None

    def reconfigure(self, cfg: PanelConfig) -> None:
        """Use a reloaded configuration; the override and move state carry over."""
        self.cfg = cfg

    def apply(self, proposal: Command | None, ctx: SafetyContext) -> SafetyResult:
        """Run every stage on ``proposal`` (None: nothing could be decided)."""
        wind_why = self._wind_state(ctx)
        if ctx.hold is not None:
            return self._held(ctx, wind_why)
        safe = self.cfg.safety.safe_state
        if proposal is None:
            d = _Draft(safe.phi_deg, safe.afr, safe.or_pct)
        else:
            d = _Draft(proposal.phi_deg, proposal.afr, proposal.or_pct)
        d.set("hold", "no manual hold")
        faulted = self._faults(d, proposal, ctx)
        overridden = self._wind(d, wind_why) or faulted
        self._limits(d)
        self._quantise(d)
        self._rate(d, ctx, overridden)
        self._regimes(d)
        cmd = Command(phi_deg=d.phi_deg, afr=d.afr, or_pct=d.or_pct)
        self._note_move(cmd, ctx)
        return SafetyResult(cmd, d.ordered(), overridden, self.wind_override, faulted)

    def _held(self, ctx: SafetyContext, wind_why: str) -> SafetyResult:
        """A manual hold: the held position, changed only by the wind."""
        hold = ctx.hold
        assert hold is not None
        safe = self.cfg.safety.safe_state
        base = hold.position or ctx.current or Command(phi_deg=safe.phi_deg, afr=safe.afr,
                                                       or_pct=safe.or_pct)
        d = _Draft(base.phi_deg, base.afr, base.or_pct)
        d.trace.append(TraceEntry("hold", base.as_dict(), f"{hold.describe()}: held "
                                  "position, the optimiser does not decide"))
        wind = self._wind(d, wind_why)
        cmd = Command(phi_deg=d.phi_deg, afr=d.afr, or_pct=d.or_pct)
        write = wind or (ctx.current is not None and cmd != ctx.current)
        skipped = "manual hold: a person's position is not changed"
        for stage in ("faults", "limits", "quantisation", "rate", "regimes"):
            d.set(stage, skipped)
        if write:
            self._note_move(cmd, ctx)
        elif ctx.current is not None:
            cmd = ctx.current  # held in place: record where it actually is
        return SafetyResult(cmd, d.ordered(), wind, self.wind_override, False, held=True,
                            write=write)

    def _note_move(self, cmd: Command, ctx: SafetyContext) -> None:
        if ctx.current is not None and cmd.phi_deg != ctx.current.phi_deg:
            self.last_louver_move_s = ctx.now_s
        elif ctx.current is None:
            self.last_louver_move_s = ctx.now_s  # position unknown: this write moves it

    # ------------------------------------------------------------------ stages
    def _faults(self, d: _Draft, proposal: Command | None, ctx: SafetyContext) -> bool:
        safe = self.cfg.safety.safe_state
        bad = sorted(set(self.cfg.safety.fault_signals) & ctx.bad_signals)
        if proposal is None or ctx.no_decision_reason:
            why = ctx.no_decision_reason or "no decision"
        elif bad:
            why = f"fault signal(s) not GOOD: {', '.join(bad)}"
        else:
            d.set("faults", "no fault")
            return False
        d.set("faults", f"{why} -> safe state", phi_deg=safe.phi_deg, afr=safe.afr,
              or_pct=safe.or_pct)
        return True

    def _wind_state(self, ctx: SafetyContext) -> str:
        """Update the wind override from this cycle's wind; why it is (not) active."""
        s = self.cfg.safety
        wind = ctx.wind_speed_ms
        release = s.wind_limit_ms - s.wind_hysteresis_ms
        if wind is None or not math.isfinite(wind):
            if s.wind_unknown == "safe":
                self.wind_override, self._calm_cycles = True, 0
                return "wind speed unknown -> treated as above the limit"
            return f"wind speed unknown -> override {'kept' if self.wind_override else 'off'}"
        if wind > s.wind_limit_ms:
            self.wind_override, self._calm_cycles = True, 0
            return f"wind {wind:.1f} m/s above {s.wind_limit_ms:g} m/s"
        if self.wind_override and wind < release:
            self._calm_cycles += 1
            if self._calm_cycles >= s.wind_release_cycles:
                self.wind_override = False
                return (f"wind {wind:.1f} m/s below {release:g} m/s for "
                        f"{self._calm_cycles} cycles -> override released")
            return (f"wind {wind:.1f} m/s below {release:g} m/s for {self._calm_cycles}/"
                    f"{s.wind_release_cycles} cycles -> override held")
        if self.wind_override:
            self._calm_cycles = 0
            return f"wind {wind:.1f} m/s inside the hysteresis band -> override held"
        return f"wind {wind:.1f} m/s below {s.wind_limit_ms:g} m/s"

    def _wind(self, d: _Draft, why: str) -> bool:
        """Apply an active wind override to the draft."""
        s = self.cfg.safety
        if not self.wind_override:
            d.set("wind", why)
            return False
        values: dict[str, float] = {"phi_deg": s.wind_safe_angle_deg}
        if s.wind_close_exterior and REGIME_OPENINGS[d.afr] & _EXTERIOR:
            values.update(afr=CLOSED, or_pct=0.0)
            why += "; exterior dampers closed"
        d.set("wind", why, **values)
        return True

    def _limits(self, d: _Draft) -> None:
        s = self.cfg.safety
        phi = min(max(d.phi_deg, s.phi_min_deg), s.phi_max_deg)
        top = 0.0 if d.afr == CLOSED else s.or_max_pct
        or_pct = min(max(d.or_pct, 0.0), top)
        d.set("limits", f"louver {s.phi_min_deg:g}..{s.phi_max_deg:g} deg, dampers "
              f"0..{top:g} %", phi_deg=phi, or_pct=or_pct)

    def _quantise(self, d: _Draft) -> None:
        lv, s = self.cfg.louver, self.cfg.safety
        or_pct = round(min(round(d.or_pct / s.or_step_pct) * s.or_step_pct, s.or_max_pct), 6)
        if lv is None:
            d.set("quantisation", f"no louver -> 0 deg; dampers onto {s.or_step_pct:g} % steps",
                  phi_deg=0.0, or_pct=or_pct)
            return
        angles = np.array([a for a in lv.angles_deg()
                           if s.phi_min_deg - 1e-9 <= a <= s.phi_max_deg + 1e-9])
        if angles.size == 0:  # limits narrower than one step: nearest reachable angle
            angles = np.asarray(lv.angles_deg())
        phi = float(angles[np.argmin(np.abs(angles - d.phi_deg))])
        d.set("quantisation", f"louver onto the {lv.step_deg:g} deg motor grid, dampers onto "
              f"{s.or_step_pct:g} % steps", phi_deg=phi, or_pct=or_pct)

    def _rate(self, d: _Draft, ctx: SafetyContext, overridden: bool) -> None:
        s = self.cfg.safety
        cur = ctx.current
        if cur is None:
            d.set("rate", "actuator position unknown -> no rate limit")
            return
        notes: list[str] = []
        values: dict[str, float] = {}
        last = self.last_louver_move_s
        if d.phi_deg != cur.phi_deg and last is not None and not overridden:
            since = ctx.now_s - last
            if since < s.min_louver_move_interval_s:
                values["phi_deg"] = cur.phi_deg
                notes.append(f"louver held at {cur.phi_deg:+.0f} deg: last move {since:.0f} s "
                             f"ago (< {s.min_louver_move_interval_s:g} s)")
        if (d.afr == cur.afr and d.or_pct != cur.or_pct
                and abs(d.or_pct - cur.or_pct) < s.or_deadband_pct and not overridden):
            values["or_pct"] = cur.or_pct
            notes.append(f"damper change {d.or_pct - cur.or_pct:+.1f} % inside the "
                         f"{s.or_deadband_pct:g} % dead-band")
        if overridden and d.phi_deg != cur.phi_deg:
            notes.append("override: louver moves regardless of the interval")
        d.set("rate", "; ".join(notes) or "within rate limits", **values)

    def _regimes(self, d: _Draft) -> None:
        available = self.cfg.openings.available_regimes()
        if d.afr not in available:
            d.set("regimes", f"regime {d.afr} needs dampers this panel lacks -> closed",
                  afr=CLOSED, or_pct=0.0)
        elif d.afr == CLOSED and d.or_pct != 0.0:
            d.set("regimes", "closed regime -> no opening", or_pct=0.0)
        else:
            d.set("regimes", f"regime {d.afr} available")
