"""``dsfd simulate --plant truth`` (CSV, JSON) and ``dsfd bench plant``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from dsfd.cli import main
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.sensors import SENSOR_NAMES, SensorConfig, SensorFault
from dsfd.sim.truth_run import run_truth
from dsfd.storage.measured_csv import read_measured, write_measured
from tests.conftest import PANELS
from tests.sim.conftest import HOUR, day_start

CONFIG = str(PANELS / "suwon-south.yaml")


def test_simulate_truth_writes_a_measured_csv_that_round_trips(tmp_path, capsys):
    csv, js = tmp_path / "out.csv", tmp_path / "out.json"
    code = main(["simulate", "--config", CONFIG, "--plant", "truth", "--hours", "2",
                 "--seed", "3", "--csv", str(csv), "--json", str(js)])
    out = capsys.readouterr().out
    assert code == 0
    assert "truth plant (seed 3)" in out and "paper protocol" in out
    assert "mean cavity velocity per commanded regime [cm/s]" in out
    data = read_measured(csv)
    assert len(data) == 121 and data.step_s == 60.0
    assert set(SENSOR_NAMES) | {"phi_deg", "afr", "or_pct", "truth_label", "truth_x5_c"} <= set(
        data.columns)
    doc = json.loads(js.read_text())
    assert doc["model"] == "truth" and doc["seed"] == 3
    assert len(doc["series"]["time_utc"]) == 121
    assert doc["summary"]["energy_balance"]["residual_rel"] < 1e-3
    assert doc["summary"]["velocity_by_regime"]


def test_csv_round_trip_keeps_columns_nans_and_times(suwon, rmis, tmp_path):
    start = day_start(rmis, 1) + 12 * HOUR
    faults = (SensorFault(sensor="x3_c", kind="dropout", start_s=start + 600.0,
                          end_s=start + 1200.0),)
    run = run_truth(suwon, rmis, seed=1, hours=0.5, start_s=start,
                    command=Command(18.0, 1, 100.0), sensors=SensorConfig(faults=faults))
    path = tmp_path / "m.csv"
    write_measured(run.data, path)
    back = read_measured(path)
    np.testing.assert_array_equal(back.time_s, run.data.time_s)
    assert set(back.columns) == set(run.data.columns)
    assert back.notes == run.data.notes
    for name, col in run.data.columns.items():
        np.testing.assert_array_equal(np.isnan(back.columns[name]), np.isnan(col), name)
        np.testing.assert_allclose(back.columns[name], col, atol=6e-5, equal_nan=True)
    x3 = back.get("x3_c")
    assert np.isnan(x3[10:20]).all() and np.isfinite(x3[:10]).all()
    assert np.all(back.get("afr") == 1) and np.all(back.get("phi_deg") == 18.0)
    assert set(np.unique(back.get("truth_label"))) <= {1.0, 2.0}


def test_simulate_truth_rejects_off_grid_angle(capsys):
    code = main(["simulate", "--config", CONFIG, "--plant", "truth", "--hours", "1",
                 "--phi-deg", "10"])
    assert code == 2
    assert "18 deg louver grid" in capsys.readouterr().err


def test_simulate_lumped_is_unchanged(capsys):
    assert main(["simulate", "--config", CONFIG, "--hours", "1"]) == 0
    out = capsys.readouterr().out
    assert "lumped model, open loop" in out and "louver 0 deg, regime 1, dampers 100 %" in out
    assert main(["simulate", "--config", CONFIG, "--hours", "1", "--csv", "x.csv"]) == 2


def test_bench_plant_writes_flat_json(tmp_path, capsys):
    js = tmp_path / "bench.json"
    assert main(["bench", "plant", "--config", CONFIG, "--days", "0.02", "--json",
                 str(js)]) == 0
    doc = json.loads(js.read_text())
    assert doc["target"] == "plant"
    assert doc["sim_speedup_x"] > 0
    assert doc["simulated_s"] == pytest.approx(60.0 * doc["cycles"]) and doc["cycles"] >= 28
    figures = {k: v for k, v in doc.items() if k != "target"}
    assert all(isinstance(v, (int, float)) and math.isfinite(v) for v in figures.values())
    assert "sim_speedup_x" in capsys.readouterr().out
