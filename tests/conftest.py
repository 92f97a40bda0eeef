"""Shared fixtures."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
PANELS = ROOT / "config" / "panels"


@pytest.fixture(scope="session")
def suwon():
    from dsfd.config import load_panel

    return load_panel(PANELS / "suwon-south.yaml")
