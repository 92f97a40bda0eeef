"""Blocking work off the event loop, one job of a kind at a time, under a time budget."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any, TypeVar

from dsfd.daemon.logging_setup import get_logger

__all__ = ["OffLoopJob"]

log = get_logger("dsfd.daemon.loop")
T = TypeVar("T")


class OffLoopJob:
    """Runs one blocking job at a time in a worker thread, under a time budget."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._task: asyncio.Future[Any] | None = None
        #: Jobs abandoned because they missed their budget.
        self.late = 0

    @property
    def busy(self) -> bool:
        """True while an abandoned job is still running."""
        return self._task is not None and not self._task.done()

    async def run(self, fn: Callable[[], T], *, budget_s: float) -> tuple[T | None, str]:
        """``(result, "")``, or ``(None, why)`` if busy, late or failed."""
        if self.busy:
            return None, f"previous {self.name} still running"
        task = asyncio.ensure_future(asyncio.to_thread(fn))
        self._task = task
        try:
            return await asyncio.wait_for(asyncio.shield(task), budget_s), ""
        except TimeoutError:
            self.late += 1
            task.add_done_callback(_consume)  # its result is never used
            return None, f"{self.name} exceeded its budget of {budget_s:g} s"
        except Exception as exc:
            log.exception("%s failed", self.name)
            return None, f"{self.name} failed: {type(exc).__name__}: {exc}"


def _consume(task: asyncio.Future[Any]) -> None:
    if not task.cancelled():
        task.exception()  # retrieve it, so asyncio does not warn about it
