"""An integration wrapped for the benchmarks: the time each stored cycle was handed to it."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["TimedIntegration"]


class TimedIntegration:
    """Passes everything to ``inner`` and keeps ``clock()`` at each ``cycle_stored`` (the
    moment the loop has committed the cycle)."""

    def __init__(self, inner: Any, *, clock: Callable[[], float] = time.perf_counter) -> None:
        self.inner = inner
        self.name = inner.name
        self.clock = clock
        self.stored: dict[int, float] = {}

    def start(self, *, database: Path) -> None:
        self.inner.start(database=database)

    def cycle_stored(self, cycle: int) -> None:
        self.stored[cycle] = self.clock()
        self.inner.cycle_stored(cycle)

    def stop(self) -> None:
        self.inner.stop()

    def health(self) -> dict[str, Any]:
        return dict(self.inner.health())
