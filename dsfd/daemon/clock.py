"""Time for the daemon: one :class:`Clock` interface, a real and a simulated implementation,
and the fixed cycle grid.

* :class:`RealClock` — deadlines on ``time.monotonic()`` (immune to NTP steps), UTC stamps from
  ``time.time()``.
* :class:`SimulatedClock` — a virtual clock starting at a given UTC instant, either
  accelerated (``speed`` × real time, ``dsfd run --speed X``) or as fast as possible
  (``speed=None``: sleeping jumps straight to the deadline and work takes no virtual time —
  benchmarks and tests run days of cycles in seconds).

:class:`CycleGrid` puts cycle k at ``t0 + k·period`` on the clock's monotonic axis. After an
overrun the next cycle is the first slot still in the future; the skipped slots are counted,
never run back to back (ecosystem notes §6.1).

Stage budgets (``asyncio.timeout``) always count real seconds: a simulated clock makes days
pass quickly, not computers faster.
"""

from __future__ import annotations

import asyncio
import math
import time
from dataclasses import dataclass
from typing import Protocol

__all__ = ["CLOCK_STEP_TOLERANCE_S", "Clock", "CycleGrid", "RealClock", "SimulatedClock", "Slot",
           "WallClockWatch"]

#: A difference between the wall clock's and the monotonic clock's advance between two
#: cycles beyond this is a wall-clock step (NTP, RTC) [s]; NTP slewing stays far below it.
CLOCK_STEP_TOLERANCE_S = 2.0


class Clock(Protocol):
    """Monotonic deadlines, UTC stamps and sleeping until a deadline."""

    #: True for a virtual clock (dry runs, HIL, benchmarks).
    simulated: bool

    def monotonic(self) -> float:
        """Seconds on a clock that never jumps [s]; deadlines live here."""
        ...

    def wall(self) -> float:
        """UTC unix time [s] for stamping samples and decisions."""
        ...

    async def sleep_until(self, deadline_s: float) -> None:
        """Return once :meth:`monotonic` has reached ``deadline_s`` [s]."""
        ...


class RealClock:
    """The host's clocks: ``time.monotonic`` for deadlines, ``time.time`` for stamps."""

    simulated = False

    def monotonic(self) -> float:
        return time.monotonic()

    def wall(self) -> float:
        return time.time()

    async def sleep_until(self, deadline_s: float) -> None:
        # asyncio's own clock is time.monotonic(), so this wakes at the deadline, not later
        # by the accumulated work time (no drift).
        delay = deadline_s - time.monotonic()
        if delay > 0:
            await asyncio.sleep(delay)


class SimulatedClock:
    """Virtual time from ``start_utc_s``, accelerated by ``speed`` or as fast as possible.

    Parameters
    ----------
    start_utc_s : float, [s]
        UTC unix time the virtual clock starts at (``dsfd run --start``).
    speed : float or None
        Virtual seconds per real second; ``None`` runs as fast as possible.
    """

    simulated = True

    def __init__(self, *, start_utc_s: float, speed: float | None = None) -> None:
        if speed is not None and not (math.isfinite(speed) and speed > 0):
            raise ValueError(f"speed must be a positive number, got {speed!r}")
        self.start_utc_s = float(start_utc_s)
        self.speed = speed
        self._virtual_s = 0.0
        self._real0_s = time.monotonic()
        self._wall_step_s = 0.0

    def monotonic(self) -> float:
        if self.speed is None:
            return self._virtual_s
        return (time.monotonic() - self._real0_s) * self.speed

    def wall(self) -> float:
        return self.start_utc_s + self.monotonic() + self._wall_step_s

    def step_wall(self, seconds: float) -> None:
        """Step the wall clock by ``seconds`` [s] as NTP or an RTC would, leaving the
        monotonic clock alone (tests of the daemon's behaviour across a step)."""
        self._wall_step_s += float(seconds)

    async def sleep_until(self, deadline_s: float) -> None:
        if self.speed is None:
            self._virtual_s = max(self._virtual_s, deadline_s)
            await asyncio.sleep(0)  # still yield, so signal handlers and I/O get their turn
            return
        delay = (deadline_s - self.monotonic()) / self.speed
        if delay > 0:
            await asyncio.sleep(delay)


@dataclass(frozen=True)
class Slot:
    """Where the next cycle runs: slot ``index`` at ``deadline_s``, after ``skipped`` slots."""

    index: int
    deadline_s: float
    skipped: int


class CycleGrid:
    """Cycle slots ``t0 + k·period`` on a monotonic axis [s]."""

    def __init__(self, *, period_s: float, t0_s: float) -> None:
        if not period_s > 0:
            raise ValueError("period_s must be positive")
        self.period_s = float(period_s)
        self.t0_s = float(t0_s)

    @classmethod
    def aligned(cls, clock: Clock, *, period_s: float) -> CycleGrid:
        """Grid whose slots fall on whole multiples of the period in UTC (hh:mm:00 for 60 s).

        The phase is taken once from the wall clock; afterwards only the monotonic clock
        counts, so a wall-clock step never bunches or drops cycles.
        """
        now_mono, now_wall = clock.monotonic(), clock.wall()
        wait = (-now_wall) % period_s
        return cls(period_s=period_s, t0_s=now_mono + wait)

    def deadline(self, index: int) -> float:
        """Start of slot ``index`` [s, monotonic]."""
        return self.t0_s + index * self.period_s

    def after(self, index: int, now_s: float) -> Slot:
        """The slot following ``index`` given the time ``now_s``; skip slots already past."""
        nxt = index + 1
        if now_s <= self.deadline(nxt):
            return Slot(nxt, self.deadline(nxt), 0)
        first_future = math.floor((now_s - self.t0_s) / self.period_s) + 1
        return Slot(first_future, self.deadline(first_future), first_future - nxt)


class WallClockWatch:
    """Notices wall-clock steps: compares how far the wall and the monotonic clock moved
    since the previous look (ecosystem notes §6.1)."""

    def __init__(self, tolerance_s: float = CLOCK_STEP_TOLERANCE_S) -> None:
        self.tolerance_s = tolerance_s
        self._last: tuple[float, float] | None = None

    def step(self, monotonic_s: float, wall_s: float) -> float | None:
        """The step of the wall clock since the previous call [s], None if within the
        tolerance (or the first call)."""
        last, self._last = self._last, (monotonic_s, wall_s)
        if last is None:
            return None
        step = (wall_s - last[1]) - (monotonic_s - last[0])
        return step if abs(step) > self.tolerance_s else None
