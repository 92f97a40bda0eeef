"""``dsfd calibrate`` and ``dsfd validate`` on a small CSV: tables, JSON keys, errors."""

from __future__ import annotations

import json

import pytest
import yaml

from dsfd.cli import main
from dsfd.measured import MeasuredData
from dsfd.storage.measured_csv import write_measured
from tests.conftest import PANELS
from tests.estimation.synthetic import lumped_record, true_theta


@pytest.fixture(scope="module")
def files(tmp_path_factory, suwon):
    """A quick panel (updates every 30 min) and 4 h of 5-minute lumped-model data."""
    root = tmp_path_factory.mktemp("cli")
    doc = yaml.safe_load((PANELS / "suwon-south.yaml").read_text())
    doc["calibration"] = {"update_interval_s": 1800.0, "max_nfev": 4, "offline_max_nfev": 8}
    panel = root / "panel.yaml"
    panel.write_text(yaml.safe_dump(doc))
    data, _ = lumped_record(suwon, true_theta(suwon), step_s=300.0, hours=4.0, seed=5)
    csv = root / "data.csv"
    write_measured(data, csv)
    return root, panel, csv, data


def test_calibrate_then_validate_prints_the_tables_and_writes_the_json(files, capsys):
    root, panel, csv, _ = files
    params = root / "params.yaml"
    assert main(["calibrate", "--config", str(panel), "--data", str(csv), "--out", str(params),
                 "--end", "2022-01-02T02:00:00Z"]) == 0
    cap = capsys.readouterr()
    assert "fitting: 100%" in cap.err and "\r" not in cap.err  # stderr is no terminal here
    assert params.exists() and "wrote" in cap.out
    out = root / "scores.json"
    assert main(["validate", "--config", str(panel), "--data", str(csv), "--params",
                 str(params), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Table 2" in text and "Table 1" in text and "self-calibr" in text
    doc = json.loads(out.read_text())
    for key in ("online.h1.x1_mae_c", "online.h15.mean_mae_c", "offline.h1.mean_mae_c",
                "uncalibrated.h1.mean_mae_c", "persistence.h15.mean_mae_c",
                "online.velocity_mae_cms.regime_1", "offline.velocity_mae_cms.regime_5",
                "measured.velocity_mean_cms.regime_6", "online.theta.h_out"):
        assert key in doc, key
    assert doc["online_updates"] >= 2
    # the data come from the model: calibrated models predict better than persistence
    assert doc["online.h15.mean_mae_c"] < doc["persistence.h15.mean_mae_c"]


def test_missing_columns_are_skipped(files, capsys, tmp_path):
    _, panel, _, data = files
    keep = {k: v for k, v in data.columns.items() if k not in ("x4_c", "x5_c", "v_cav_ms")}
    csv = tmp_path / "partial.csv"
    write_measured(MeasuredData(data.time_s, keep, "partial"), csv)
    out = tmp_path / "scores.json"
    assert main(["validate", "--config", str(panel), "--data", str(csv), "--no-online",
                 "--horizons", "1,6", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "not measured (skipped): x4, x5, v" in text
    assert "no cavity speed" in text
    doc = json.loads(out.read_text())
    assert "uncalibrated.h6.x3_mae_c" in doc and "uncalibrated.h6.x4_mae_c" not in doc
    assert not any("velocity" in k for k in doc)


def test_user_errors_name_the_file_and_key(files, capsys, tmp_path):
    _, panel, csv, _ = files
    bad = tmp_path / "params.yaml"
    bad.write_text("schema: dsfd.parameters\nschema_version: 1\npanel_id: suwon-south\n"
                   "parameters: {h_out: 12}\n")
    assert main(["validate", "--config", str(panel), "--data", str(csv), "--params",
                 str(bad), "--no-online"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "'parameters.h_ca1'" in err
    broken = tmp_path / "broken.csv"
    broken.write_text(csv.read_text().replace("x2_c", "x2_degc", 1))
    assert main(["calibrate", "--config", str(panel), "--data", str(broken), "--out",
                 str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err
    assert str(broken) in err and "'x2_degc'" in err
