"""``dsfd bench mqtt`` runs against a real Mosquitto and prints its figures as JSON."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.daemon.harness import ROOT, dsfd_command
from tests.integrations.mqtt_harness import mosquitto_missing


def test_bench_mqtt_reports_latency_and_drain_rate(tmp_path: Path) -> None:
    if why := mosquitto_missing():
        pytest.skip(why)
    out = tmp_path / "mqtt.json"
    done = subprocess.run(dsfd_command("bench", "mqtt", "--cycles", "5", "--backlog", "300",
                                       "--json", str(out)), cwd=ROOT, capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    figures = json.loads(out.read_text())
    assert figures["target"] == "mqtt" and figures["cycles"] == 5
    # A new destination gets everything stored: the 5 measured cycles and the 300 copies,
    # and the bench itself checked that the copies arrived complete and in order.
    assert figures["drain_messages"] == 305
    assert 0 < figures["latency_ms_p50"] <= figures["latency_ms_p99"] <= figures[
        "latency_ms_max"]
    assert figures["drain_msgs_per_s"] > 0 and figures["state_bytes_mean"] > 500
    assert "latency_ms_p99" in done.stdout
