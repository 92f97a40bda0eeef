"""Fixtures for the driver tests: event-loop runner, free TCP ports, a fake monotonic clock."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine
from typing import Any, TypeVar

import pytest

from dsfd.integrations.mqtt.broker import free_port

T = TypeVar("T")

#: Hang guard for one async scenario [s]; tests assert behaviour, never elapsed time.
SCENARIO_LIMIT_S = 30.0


class FakeClock:
    """Monotonic clock the test advances by hand [s]."""

    def __init__(self, start_s: float = 1000.0) -> None:
        self.now_s = start_s

    def __call__(self) -> float:
        return self.now_s

    def advance(self, dt_s: float) -> None:
        self.now_s += dt_s


@pytest.fixture
def clock() -> FakeClock:
    return FakeClock()


@pytest.fixture
def run() -> Callable[[Coroutine[Any, Any, T]], T]:
    """Run one async scenario to completion in a fresh event loop, with a hang guard."""

    def _run(coro: Coroutine[Any, Any, T]) -> T:
        async def guarded() -> T:
            async with asyncio.timeout(SCENARIO_LIMIT_S):
                return await coro

        return asyncio.run(guarded())

    return _run


@pytest.fixture
def tcp_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago."""
    return free_port()


def _build_devices(entries: list[dict[str, Any]]) -> Any:
    from dsfd.config.devices import Devices
    from dsfd.config.loader import build

    # Budgets are not under test here; the config tests check them.
    return build(Devices, {"read_budget_s": 3600, "write_budget_s": 3600, "entries": entries},
                 prefix="devices")


@pytest.fixture
def make_devices() -> Callable[[list[dict[str, Any]]], Any]:
    """Build a validated ``Devices`` from a list of device mappings (as in YAML)."""
    return _build_devices


#: Fast-failing settings for emulated devices: 0.2 s per attempt, 2 attempts.
FAST = {"timeout_s": 0.2, "retries": 1, "reconnect_backoff_min_s": 1.0,
        "reconnect_backoff_max_s": 30.0, "breaker_failures": 2, "breaker_cycles": 3}


@pytest.fixture
def fast() -> dict[str, Any]:
    return dict(FAST)
