"""Fixtures of the MQTT tests: a real Mosquitto broker per test."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from dsfd.integrations.mqtt.broker import LocalBroker
from tests.integrations.mqtt_harness import mosquitto_missing


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[LocalBroker]:
    """Mosquitto on a free loopback port, password file, persistence in its directory."""
    if why := mosquitto_missing():
        pytest.skip(why)
    b = LocalBroker(tmp_path / "broker").start()
    try:
        yield b
    finally:
        b.stop()
