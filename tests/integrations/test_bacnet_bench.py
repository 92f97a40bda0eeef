"""``dsfd bench bacnet`` runs the daemon with its device and a client process and prints its
figures as JSON."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.daemon.harness import ROOT, dsfd_command

pytest.importorskip("bacpypes3", reason="needs the bacnet extra: pip install 'dsfd[bacnet]'")


def test_bench_bacnet_reports_cov_latency_and_read_rate(tmp_path: Path) -> None:
    out = tmp_path / "bacnet.json"
    done = subprocess.run(dsfd_command("bench", "bacnet", "--cycles", "5", "--reads", "20",
                                       "--json", str(out)), cwd=ROOT, capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    figures = json.loads(out.read_text())
    assert figures["target"] == "bacnet" and figures["cycles"] == 5
    assert figures["cov_missed"] == 0  # a notification for every measured cycle
    assert 0 < figures["cov_latency_ms_p50"] <= figures["cov_latency_ms_p99"] <= figures[
        "cov_latency_ms_max"]
    assert figures["reads"] == 20 and figures["rpm_per_s"] > 0
    assert figures["property_values_per_s"] > figures["rpm_per_s"]
    assert "cov_latency_ms_p99" in done.stdout
