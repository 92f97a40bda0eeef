"""Reconnect backoff and circuit breaker: the pure policies that bound time lost to dead devices.

Two different failure costs, two mechanisms:

* **Connect failures** (refused, port absent, host unreachable) are governed by
  :class:`Backoff` on a clock: after a failed connect the next attempt waits
  ``min_s``, doubling up to ``max_s``; a success resets it. pymodbus does not retry a failed
  *first* connect at all, and its own reconnect task only runs after an established
  connection dropped, so dsfd disables it (``reconnect_delay=0``) and owns the policy here.
* **Request timeouts** on a connected link (a silent RTU slave, a hung gateway) cost
  ``timeout·(retries+1)`` per request, every cycle. :class:`CircuitBreaker` counts cycles:
  after ``failures`` consecutive cycles with timeouts it skips the device for ``open_cycles``
  cycles (no I/O at all), then polls once (half-open): success closes the breaker, a failure
  opens it again at once.
"""

from __future__ import annotations

import math

__all__ = ["Backoff", "CircuitBreaker"]


class Backoff:
    """Exponential reconnect delay on an injected clock [s]."""

    def __init__(self, *, min_s: float, max_s: float) -> None:
        if not 0 < min_s <= max_s:
            raise ValueError("need 0 < min_s <= max_s")
        self.min_s = min_s
        self.max_s = max_s
        self._delay_s = 0.0
        self._next_s = -math.inf
        self._last_failure_s = -math.inf

    @property
    def delay_s(self) -> float:
        """Delay applied after the last failure (0 after a success)."""
        return self._delay_s

    def ready(self, now_s: float) -> bool:
        """True if a connect attempt is allowed at ``now_s``.

        A clock that went backwards (before the last failure) allows an attempt rather than
        blocking reconnects for as long as the jump.
        """
        return now_s >= self._next_s or now_s < self._last_failure_s

    def wait_s(self, now_s: float) -> float:
        """Seconds until the next attempt is allowed (0 if ready)."""
        return 0.0 if self.ready(now_s) else self._next_s - now_s

    def failed(self, now_s: float) -> float:
        """Record a failed attempt at ``now_s``; return the delay before the next one [s]."""
        self._delay_s = self.min_s if self._delay_s == 0 else min(self.max_s, 2 * self._delay_s)
        self._next_s = now_s + self._delay_s
        self._last_failure_s = now_s
        return self._delay_s

    def succeeded(self) -> None:
        """Record a successful connect: the next failure starts from ``min_s`` again."""
        self._delay_s = 0.0
        self._next_s = -math.inf
        self._last_failure_s = -math.inf


class CircuitBreaker:
    """Skip a device for ``open_cycles`` cycles after ``failures`` consecutive failed cycles."""

    def __init__(self, *, failures: int, open_cycles: int) -> None:
        if failures < 1 or open_cycles < 0:
            raise ValueError("need failures >= 1 and open_cycles >= 0")
        self.failures = failures
        self.open_cycles = open_cycles
        self.consecutive = 0
        self.skip_remaining = 0
        self.tripped = False
        #: How often the breaker opened.
        self.trips = 0

    @property
    def is_open(self) -> bool:
        """True while cycles are being skipped."""
        return self.skip_remaining > 0

    def should_skip(self) -> bool:
        """Call once per cycle before polling: True means skip the device this cycle."""
        if self.skip_remaining > 0:
            self.skip_remaining -= 1
            return True
        return False

    def record_success(self) -> None:
        """The device answered: close the breaker."""
        self.consecutive = 0
        self.tripped = False

    def record_failure(self) -> None:
        """The device timed out this cycle; may open the breaker."""
        self.consecutive += 1
        # Half-open trial failed, or the threshold was reached: open (again).
        if (self.tripped or self.consecutive >= self.failures) and self.open_cycles > 0:
            self.skip_remaining = self.open_cycles
            self.tripped = True
            self.trips += 1
