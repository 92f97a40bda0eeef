"""Shared fixtures of the truth-plant tests (bundled weather only)."""

from __future__ import annotations

import pytest

from dsfd.sim.replay import at_site, load_weather

RMIS = "rmis-golden-2022-01"
HOUR = 3600.0


@pytest.fixture(scope="session")
def rmis_raw():
    """The bundled RMIS record (Golden CO, 1–4 January 2022, 5 min), station clock."""
    return load_weather(RMIS)


@pytest.fixture(scope="session")
def rmis(suwon, rmis_raw):
    """The RMIS record replayed at the Suwon panel's longitude."""
    return at_site(rmis_raw, suwon)


def day_start(series, day: int) -> float:
    """First whole minute of day ``day`` (0-based) of a record [s]."""
    first = series.coverage_s[0] + day * 86400.0
    return float(-(-first // 60.0) * 60.0)
