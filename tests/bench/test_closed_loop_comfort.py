"""``dsfd bench closed-loop --occupancy …``: comfort figures per case and controller."""

from __future__ import annotations

import json
import math
import subprocess
import sys

from tests.conftest import PANELS


def test_the_bench_reports_comfort_on_the_schedule_it_was_given(tmp_path):
    out = tmp_path / "cl.json"
    # Mixed day (Monday 3 January at the site): from local solar midnight, with no warm-up, the
    # first 0.05 days (72 min) are all before 08:00, so nobody is there yet.
    cmd = [sys.executable, "-m", "dsfd", "bench", "closed-loop", "--config",
           str(PANELS / "suwon-south.yaml"), "--days", "0.05", "--case", "mixed-heating",
           "--controllers", "rule", "--occupancy", "office-weekdays", "--json", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    fig = json.loads(out.read_text())
    assert fig["occupied_h_per_week"] == 50.0
    assert fig["mixed-heating.rule.occupied_min"] == 0.0
    assert fig["mixed-heating.rule.direct_sun_min"] == 0.0
    assert math.isnan(fig["mixed-heating.rule.dgp_p95"])  # no occupied minute to take it over
    assert "comfort (plant)" in proc.stdout and "occupied" in proc.stdout


def test_an_unknown_schedule_is_refused_by_name(tmp_path):
    cmd = [sys.executable, "-m", "dsfd", "bench", "closed-loop", "--occupancy", "shifts"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "office-every-day" in proc.stderr
