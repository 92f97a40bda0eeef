"""The end-of-run summary of ``dsfd run`` agrees with what the run stored.

One short dry run of the real ``dsfd run`` process against the simulated plant (lumped
switches, the harness's fast settings: the first calibration update after half an hour of
data); the printed summary and ``--summary-json`` are checked against the SQLite database.
"""

from __future__ import annotations

import json
import math
import sqlite3
import subprocess
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from dsfd.config import load_panel
from dsfd.config.panel import PARAMETER_NAMES
from dsfd.control.stake import energy_at_stake, solar_energy_at_stake
from dsfd.daemon.stake import stake_record, with_stake
from dsfd.daemon.summary import REGIME_NAMES
from dsfd.estimation.diagnostics import Evidence, Finding
from dsfd.estimation.params import FIT_NAMES
from dsfd.estimation.stepdata import StepData, model_config, step_data
from dsfd.physics.model import LumpedModel
from dsfd.storage.measured_csv import read_measured
from dsfd.storage.schema import PARAMETER_SD_COLUMNS
from tests.daemon.harness import MORNING_ISO, ROOT, dsfd_command, query, write_panel

CYCLES = 40


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, subprocess.CompletedProcess]:
    """The panel, the state directory and the finished ``dsfd run``."""
    tmp_path = tmp_path_factory.mktemp("summary")
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    done = subprocess.run(dsfd_command(
        "run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
        "lumped", "--start", MORNING_ISO, "--cycles", str(CYCLES), "--state-dir", str(state),
        "--summary-json", str(tmp_path / "summary.json")), cwd=ROOT, capture_output=True,
        text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    return panel, state, done


def test_summary_reports_regimes_louver_heat_and_calibration(run) -> None:
    _, state, done = run
    summary = json.loads((state.parent / "summary.json").read_text())
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


def test_a_parameter_finding_on_the_stored_run_gets_the_energy_at_stake(run, tmp_path) -> None:
    """The daemon's stake of a path-resistance finding over its own stored run equals the
    stake computed from what ``dsfd export`` writes of the same cycles (another reader of
    the database, through a CSV), with θ taken from the parameters table by hand: the prior
    f before the change, the last on-line f now."""
    panel_path, state, _ = run
    cfg = load_panel(panel_path)
    db = state / "timeseries.sqlite"
    (t_prior,), = query(db, "SELECT time_s FROM parameters WHERE source = 'prior'")
    t_online, = query(db, "SELECT MIN(time_s) FROM parameters WHERE source = 'online'")[0]
    (now_s,), = query(db, "SELECT MAX(time_s) FROM decisions")
    ev = Evidence(signal="parameter:f", shift=1.0, shift_sd=5.0, unit="ln", since_s=t_online,
                  statistic=6.0, threshold=5.0)
    f = Finding(kind="parameter_shift", confidence=0.6, start_s=t_online, detected_s=now_s,
                evidence=(ev,), action="the calibrated f has risen")
    with sqlite3.connect(db) as conn:
        costed = with_stake(conn, f, now_s, panel=cfg,
                            steps=stake_record(cfg, state, now_s))
    assert costed.evidence[:1] == (ev,) and len(costed.evidence) == 2
    stake = costed.evidence[1]
    assert stake.signal == "energy_at_stake" and stake.unit == "kWh/week"
    assert "kWh a week" in costed.action and costed.action.startswith(f.action)
    # the same by another path
    steps, theta_now = _exported(cfg, state, tmp_path)
    (f_prior,), = query(db, "SELECT f FROM parameters WHERE time_s = ?", t_prior)
    theta_before = theta_now.copy()
    theta_before[FIT_NAMES.index("f")] = f_prior
    assert theta_before[FIT_NAMES.index("f")] != theta_now[FIT_NAMES.index("f")]
    ref = energy_at_stake(LumpedModel(model_config(cfg, steps.step_s)), steps, theta_before,
                          theta_now)
    assert stake.shift == pytest.approx(ref.per_week_kwh, rel=1e-6, abs=1e-9)


def _exported(cfg, state: Path, tmp_path: Path) -> tuple[StepData, np.ndarray]:
    """The run's steps as ``dsfd export`` writes them, and the last stored fit vector read
    from the parameters table by hand."""
    out = tmp_path / "export.csv"
    done = subprocess.run(dsfd_command("export", "--state-dir", str(state), "--out", str(out)),
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    names = ", ".join(n for n in FIT_NAMES if not n.startswith("q_"))
    (*now_theta, other), = query(state / "timeseries.sqlite",
                                 f"SELECT {names}, other FROM parameters "
                                 "ORDER BY time_s DESC LIMIT 1")
    q = json.loads(other)
    theta = np.array([*now_theta, *(q[n] for n in FIT_NAMES if n.startswith("q_"))])
    return step_data(cfg, read_measured(out)), theta


def test_a_solar_finding_on_the_stored_run_gets_the_energy_of_the_sun_it_lost(run, tmp_path
                                                                              ) -> None:
    """Dirt that took a tenth of the sun, on the stored winter morning: the daemon's stake
    equals the solar stake of what ``dsfd export`` writes with the last θ, and it costs (in
    heating, the sun lost is heat the room no longer gains)."""
    panel_path, state, _ = run
    cfg = load_panel(panel_path)
    db = state / "timeseries.sqlite"
    (t0, now_s), = query(db, "SELECT MIN(time_s), MAX(time_s) FROM decisions")
    ev = Evidence(signal="solar_response", shift=-0.1, shift_sd=5.0, unit="1", since_s=t0,
                  statistic=6.0, threshold=5.0)
    f = Finding(kind="solar_gain_shift", confidence=0.6, start_s=t0, detected_s=now_s,
                evidence=(ev,), subject="exterior glass", action="clean the exterior glass")
    with sqlite3.connect(db) as conn:
        costed = with_stake(conn, f, now_s, panel=cfg, steps=stake_record(cfg, state, now_s))
    assert [e.signal for e in costed.evidence] == ["solar_response", "energy_at_stake"]
    assert "the change costs about" in costed.action
    steps, theta_now = _exported(cfg, state, tmp_path)
    ref = solar_energy_at_stake(LumpedModel(model_config(cfg, steps.step_s)), steps,
                                theta_now, -0.1)
    assert costed.evidence[1].shift == pytest.approx(ref.per_week_kwh, rel=1e-6)
    assert ref.per_week_kwh > 0
