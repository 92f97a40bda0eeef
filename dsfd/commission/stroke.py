"""``dsfd commission --stroke``: move every actuator through its range and back.

The plan (:func:`plan_moves`): every louver step of ``louver.step_deg`` between the
mechanical limits ``safety.phi_min_deg``..``phi_max_deg``; every regime whose dampers the
panel has (``openings``); the damper opening from 0 to ``safety.or_max_pct`` in steps; then
back to the position read before the first move. Each move is written through the daemon's
driver (write, then read-back of the set-point registers) and, where an actuator has a
position feedback register, timed until the feedback is within tolerance of the target or
has stopped changing for ``settle_s``.

Before every move the wind is checked against ``safety.wind_limit_ms``: above it (or, with
``safety.wind_unknown: safe``, without a wind reading younger than ``wind_max_age_s``) the
stroke stops and commands the wind-safe louver angle with every damper closed (regime 10),
and does not return to the start position.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from dsfd.commission.checks import FEEDBACK_TOLERANCE, Finding, check_feedback
from dsfd.drivers.base import Command
from dsfd.signals import ACTUATOR_NAMES

if TYPE_CHECKING:
    from dsfd.commission.rig import Rig
    from dsfd.config.panel import PanelConfig

__all__ = ["Move", "StrokeOptions", "StrokeResult", "plan_moves", "run_stroke"]

_CLOSED = 10


@dataclass(frozen=True, kw_only=True)
class StrokeOptions:
    damper_step_pct: float = 25.0
    move_timeout_s: float = 120.0
    settle_s: float = 3.0
    poll_s: float = 0.1
    wind_max_age_s: float = 30.0


@dataclass(frozen=True)
class Move:
    """One commanded position and what came of it. ``time_s`` [s] runs from the write to
    the feedback within tolerance (without feedback: to the verified read-back)."""

    stage: str
    actuator: str
    target: Command
    verified: bool
    feedback: dict[str, float]
    reached: bool
    time_s: float
    detail: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"stage": self.stage, "actuator": self.actuator,
                "target": self.target.as_dict(), "verified": self.verified,
                "feedback": self.feedback, "reached": self.reached,
                "time_s": round(self.time_s, 4), "detail": self.detail}


@dataclass
class StrokeResult:
    start: Command | None
    end: Command | None = None
    moves: list[Move] = field(default_factory=list)
    stopped: str = ""
    findings: list[Finding] = field(default_factory=list)

    @property
    def returned(self) -> bool:
        return self.start is not None and self.end == self.start


def louver_steps(panel: PanelConfig) -> list[float]:
    """Multiples of the louver step within the mechanical limits [deg]."""
    step = panel.louver.step_deg if panel.louver is not None else 18.0
    lo, hi = panel.safety.phi_min_deg, panel.safety.phi_max_deg
    return [k * step for k in range(math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9) + 1)]


def plan_moves(panel: PanelConfig, start: Command, *, damper_step_pct: float
               ) -> list[tuple[str, str, Command]]:
    """(stage, actuator exercised, command) of the whole stroke (module docstring)."""
    safety = panel.safety
    regimes = panel.openings.available_regimes()
    open_regimes = [r for r in regimes if r != _CLOSED]
    opening = start.or_pct if start.afr != _CLOSED and start.or_pct > 0 else min(
        50.0, safety.or_max_pct)
    moves = [("louver", "phi_deg", Command(phi_deg=phi, afr=start.afr, or_pct=start.or_pct))
             for phi in louver_steps(panel)]
    moves += [("regime", "afr", Command(phi_deg=start.phi_deg, afr=r,
                                        or_pct=0.0 if r == _CLOSED else opening))
              for r in regimes]
    if open_regimes:
        regime = start.afr if start.afr in open_regimes else open_regimes[0]
        n = max(1, math.ceil(safety.or_max_pct / damper_step_pct - 1e-9))
        moves += [("damper", "or_pct", Command(phi_deg=start.phi_deg, afr=regime,
                                               or_pct=min(safety.or_max_pct, k * damper_step_pct)))
                  for k in range(n + 1)]
    moves.append(("return", "all", start))
    return moves


class _Wind:
    """The newest good wind reading of the station and its age."""

    def __init__(self, rig: Rig, clock: Callable[[], float]) -> None:
        self.rig = rig
        self.clock = clock
        self.speed_ms: float | None = None
        self.at_s = -math.inf

    async def first(self, limit_s: float, poll_s: float) -> None:
        """Wait up to ``limit_s`` for a first reading (the station pushes every few s)."""
        t0 = self.clock()
        while (await self.now())[0] is None and self.clock() - t0 < limit_s:
            await asyncio.sleep(poll_s)

    async def now(self) -> tuple[float | None, float]:
        """(speed [m/s] or None, age [s])."""
        driver = self.rig.composite.driver_for("wind_speed_ms")
        if driver is not None:
            value = (await driver.read(time.time())).good("wind_speed_ms")
            if value is not None:
                self.speed_ms, self.at_s = value, self.clock()
        return self.speed_ms, self.clock() - self.at_s


async def _move(rig: Rig, stage: str, actuator: str, cmd: Command, opts: StrokeOptions,
                clock: Callable[[], float]) -> Move:
    t0 = clock()
    result = await rig.composite.write(cmd)
    elapsed = clock() - t0
    targets = cmd.as_dict()
    watched = [n for n in ACTUATOR_NAMES if n in rig.feedback]
    feedback: dict[str, float] = {}
    if not watched or not result.written:
        return Move(stage, actuator, cmd, result.ok, feedback, result.ok, elapsed,
                    "; ".join(result.errors))
    exercised = watched if actuator == "all" else [n for n in watched if n == actuator]

    def there(names: list[str]) -> bool:
        return all(n in feedback and abs(feedback[n] - targets[n]) <= FEEDBACK_TOLERANCE[n]
                   for n in names)

    last_change, previous = clock(), None
    while True:
        feedback = await rig.read_feedback()
        now = clock()
        if there(watched):
            return Move(stage, actuator, cmd, result.ok, feedback, result.ok, now - t0,
                        "; ".join(result.errors))
        if feedback != previous:
            last_change, previous = now, feedback
        if now - last_change >= opts.settle_s or now - t0 >= opts.move_timeout_s:
            off = [n for n in watched if not there([n])]
            why = (f"{', '.join(off)} stopped short of the target"
                   if now - t0 < opts.move_timeout_s
                   else f"not there after {opts.move_timeout_s:g} s")
            # Time to position of the exercised actuator is unknown here: the full wait.
            return Move(stage, actuator, cmd, result.ok, feedback,
                        result.ok and there(exercised), now - t0,
                        "; ".join((*result.errors, why)))
        await asyncio.sleep(opts.poll_s)


async def run_stroke(panel: PanelConfig, rig: Rig, opts: StrokeOptions, *,
                     clock: Callable[[], float] = time.monotonic,
                     log: Callable[[Move], None] = lambda m: None) -> StrokeResult:
    """Run the stroke (module docstring); ``log`` sees each move as it ends."""
    start = await rig.composite.read_back()
    out = StrokeResult(start=start)
    if start is None:
        out.findings.append(Finding("stroke", ACTUATOR_NAMES, "the actuators' set-point "
                                    "registers could not all be read (or hold an invalid "
                                    "command): nothing was moved",
                                    "wiring, addresses, device id or scales"))
        return out
    wind = _Wind(rig, clock)
    await wind.first(opts.wind_max_age_s, opts.poll_s)
    safety = panel.safety
    for stage, actuator, cmd in plan_moves(panel, start, damper_step_pct=opts.damper_step_pct):
        speed, age = await wind.now()
        stale = speed is None or age > opts.wind_max_age_s
        if (speed is not None and speed > safety.wind_limit_ms) or (
                stale and safety.wind_unknown == "safe"):
            out.stopped = (f"wind {speed:.1f} m/s above safety.wind_limit_ms "
                           f"{safety.wind_limit_ms:g}" if not stale else
                           "no wind reading (safety.wind_unknown: safe)")
            safe = Command(phi_deg=safety.wind_safe_angle_deg, afr=_CLOSED, or_pct=0.0)
            move = await _move(rig, "wind-safe", "all", safe, opts, clock)
            out.moves.append(move)
            log(move)
            break
        move = await _move(rig, stage, actuator, cmd, opts, clock)
        out.moves.append(move)
        log(move)
    out.end = await rig.composite.read_back()
    out.findings += stroke_findings(out, rig)
    return out


def stroke_findings(result: StrokeResult, rig: Rig) -> list[Finding]:
    """One finding per actuator and kind of failure, and the end position."""
    out: list[Finding] = []
    failed: dict[tuple[str, str], list[Move]] = defaultdict(list)
    examples: dict[tuple[str, str], Finding] = {}
    for m in result.moves:
        if not m.verified:
            failed[(m.actuator, "verify")].append(m)
            continue
        for name, value in m.feedback.items():
            f = check_feedback(name, m.target.as_dict()[name], value, rig.feedback_where(name))
            if f is not None:
                failed[(name, f.check)].append(m)
                examples.setdefault((name, f.check), f)
    n = len(result.moves)
    for (name, kind), moves in failed.items():
        if kind == "verify":
            out.append(Finding("stroke", (name,), f"{name}: {len(moves)} of {n} moves not "
                               f"verified: {moves[0].detail}", "wiring, address or device id"))
            continue
        ex = examples[(name, kind)]
        out.append(Finding(kind, ex.signals, f"{ex.message}, and so at the end of {len(moves)} "
                           f"of {n} moves", ex.likely))
    if result.stopped:
        out.append(Finding("wind", ("wind_speed_ms",), f"stroke stopped: {result.stopped}; "
                           "the louver was sent to its wind-safe angle, dampers closed",
                           "wait for calmer weather and run --stroke again"))
    elif not result.returned:
        out.append(Finding("stroke", ACTUATOR_NAMES, f"the end position {result.end} differs "
                           f"from the start {result.start}", "see the last moves"))
    return out
