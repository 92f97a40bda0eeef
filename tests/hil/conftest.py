"""Fixtures of the HIL tests: the weather station on its own pty."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from hil.station import StationEmulator


@pytest.fixture
def station() -> Iterator[StationEmulator]:
    with StationEmulator() as emu:
        yield emu
