"""The end-of-run summary of ``dsfd run`` agrees with what the run stored.

One short dry run of the real ``dsfd run`` process against the simulated plant (lumped
switches, the harness's fast settings: the first calibration update after half an hour of
data); the printed summary and ``--summary-json`` are checked against the SQLite database.
"""

from __future__ import annotations

import json
import math
import subprocess
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from dsfd.config.panel import PARAMETER_NAMES
from dsfd.daemon.summary import REGIME_NAMES
from dsfd.storage.schema import PARAMETER_SD_COLUMNS
from tests.daemon.harness import MORNING_ISO, ROOT, dsfd_command, query, write_panel

CYCLES = 40


def test_summary_reports_regimes_louver_heat_and_calibration(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    out_json = tmp_path / "summary.json"
    done = subprocess.run(dsfd_command(
        "run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
        "lumped", "--start", MORNING_ISO, "--cycles", str(CYCLES), "--state-dir", str(state),
        "--summary-json", str(out_json)), cwd=ROOT, capture_output=True, text=True,
        timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    summary = json.loads(out_json.read_text())
    db = state / "timeseries.sqlite"
    decisions = query(db, "SELECT afr, phi_deg, heating FROM decisions ORDER BY cycle")
    assert summary["cycles"] == len(decisions) == CYCLES

    # Regimes and louver angles: the stored commands, counted.
    regimes = Counter(afr for afr, _, _ in decisions)
    assert summary["regimes_used"] == {str(k): v for k, v in sorted(regimes.items())}
    angles = Counter(phi for _, phi, _ in decisions)
    assert summary["louver_angles"] == {f"{k:g}": v for k, v in sorted(angles.items())}
    heating = sum(h == 1 for _, _, h in decisions)
    assert summary["seasons"].get("heating", 0) == heating
    text = done.stdout
    top = regimes.most_common(1)[0][0]
    assert f"{top} {REGIME_NAMES[top]}" in text

    # Calibration: the first update is the first 'online' row of the parameter history,
    # and the end state is the last row (and the state file).
    online = query(db, "SELECT cycle, h_out, f FROM parameters WHERE source = 'online' "
                   "ORDER BY cycle")
    assert online, "the fast settings update the calibration within the run"
    assert summary["first_calibration_update_cycle"] == online[0][0]
    assert f"the first at cycle {online[0][0]}" in text
    assert "min_window_h = 0.5 h of data" in text
    (prior_h_out, prior_f), = query(db, "SELECT h_out, f FROM parameters WHERE source = "
                                    "'prior'")
    assert (summary["theta_start"]["h_out"], summary["theta_start"]["f"]) == (prior_h_out,
                                                                             prior_f)
    assert summary["theta_end"]["h_out"] == online[-1][1]
    assert summary["theta_end"]["f"] == online[-1][2]
    saved = json.loads((state / "calibration.json").read_text())
    assert summary["theta_end"]["h_out"] == saved["theta"]["h_out"]
    # Each on-line row carries the posterior sd the parameter detector needs (schema 8):
    # finite and positive, and the last row's that of the saved state's covariance (written
    # by another path, calibration.json, in the fitting coordinates).
    sds = query(db, f"SELECT {', '.join(PARAMETER_SD_COLUMNS)} FROM parameters WHERE "
                "source = 'online' ORDER BY cycle")
    assert len(sds) == len(online)
    assert all(v is not None and math.isfinite(v) and v > 0 for row in sds for v in row)
    cov = np.array(saved["cov_z"])
    assert np.sqrt(np.diag(cov))[:len(PARAMETER_NAMES)] == pytest.approx(sds[-1], rel=1e-9)
    # the flow law's f moved on this data: its sd is below the first prior's (0.7 in log)
    assert sds[-1][PARAMETER_NAMES.index("f")] < saved["prior_sd_z"]["f"]

    # Heat into the room from the simulated plant: a clear winter morning lets sun in.
    heat = summary["room_heat_kwh"]
    assert set(heat) == {"q_cv_rd", "q_sol_trans", "q_air", "q_da"}
    assert heat["q_sol_trans"] > 0
    assert "heat into the room:" in text
