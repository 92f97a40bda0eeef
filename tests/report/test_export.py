"""``dsfd export``: the daemon's log back into dsfd validate and dsfd calibrate."""

from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest

from dsfd.cli import main
from dsfd.storage.measured_csv import read_measured
from tests.daemon.harness import ROOT, dsfd_command, query
from tests.report.conftest import CYCLES


def test_export_then_validate_agrees_with_the_report(faulted_run, tmp_path, capsys):
    db = faulted_run.state_dir / "timeseries.sqlite"
    csv = tmp_path / "measured.csv"
    assert main(["export", "--state-dir", str(faulted_run.state_dir), "--out", str(csv)]) == 0
    data = read_measured(csv)
    assert len(data) == CYCLES and data.step_s == 60.0
    # A flagged sample is an empty cell, never its bad value — which the database keeps.
    flagged = query(db, "SELECT time_s, signal, value FROM samples WHERE quality != 'good'")
    spikes = [v for _, s, v in flagged if s == "x1_c"]
    assert spikes and all(v is not None for v in spikes)
    for t, signal, _ in flagged:
        row = int(np.flatnonzero(data.time_s == t)[0])
        assert math.isnan(data.columns[signal][row]), (t, signal)
    # Good samples survive to the exported precision.
    good = query(db, "SELECT time_s, value FROM samples WHERE signal = 'x2_c' AND "
                     "quality = 'good' ORDER BY time_s")
    assert np.max(np.abs(data.columns["x2_c"] - [v for _, v in good])) <= 5e-7
    # The position in effect, from the model table.
    applied = [r[0] for r in query(db, "SELECT applied_afr FROM model ORDER BY cycle")]
    assert data.columns["afr"].tolist() == applied
    capsys.readouterr()

    out = tmp_path / "validate.json"
    assert main(["validate", "--config", str(faulted_run.panel), "--data", str(csv),
                 "--no-online", "--horizons", "1", "--json", str(out)]) == 0
    scores = json.loads(out.read_text())
    for s in ("x1", "x2", "x3", "x4", "x5"):
        ours = faulted_run.doc["prediction_errors"][s]["h1_persistence_mae"]
        assert abs(scores[f"persistence.h1.{s}_mae_c"] - ours) < 1e-6, s
    assert scores["scored_starts"] == CYCLES - 1


def test_calibrate_runs_on_the_exported_history(faulted_run, tmp_path, capsys):
    csv, params = tmp_path / "measured.csv", tmp_path / "params.yaml"
    with pytest.raises(SystemExit) as exit_:  # the state directory is named one way
        main(["export", "--config", str(faulted_run.panel), "--state-dir",
              str(faulted_run.state_dir), "--out", str(csv)])
    assert exit_.value.code == 2 and "not allowed with argument" in capsys.readouterr().err
    assert main(["export", "--state-dir", str(faulted_run.state_dir), "--out", str(csv)]) == 0
    capsys.readouterr()
    assert main(["calibrate", "--config", str(faulted_run.panel), "--data", str(csv),
                 "--out", str(params), "--max-nfev", "3"]) == 0
    assert "h_out" in params.read_text()
    err = capsys.readouterr().err  # not a terminal: plain progress lines
    assert "\r" not in err and "fitting: 100%" in err


def test_validate_logs_plain_progress_lines_when_stderr_is_a_file(faulted_run, tmp_path):
    csv, log = tmp_path / "measured.csv", tmp_path / "stderr.log"
    assert main(["export", "--state-dir", str(faulted_run.state_dir), "--out", str(csv)]) == 0
    with log.open("w") as err:
        out = subprocess.run(dsfd_command("validate", "--config", str(faulted_run.panel),
                                          "--data", str(csv)),
                             cwd=ROOT, stdout=subprocess.PIPE, stderr=err, text=True,
                             check=True, timeout=300)
    text = log.read_text()
    assert "\r" not in text
    lines = [line for line in text.splitlines() if line.startswith("replay:")]
    assert 6 <= len(lines) <= 12 and lines[-1].startswith("replay: 100% (74/74)")
    # Column headers are the models' whole names, apart.
    header = next(line for line in out.stdout.splitlines() if line.startswith("state "))
    assert header.split() == ["state", "self-calibrating", "uncalibrated", "persistence",
                              "measured"]


def test_export_that_cannot_write_its_file_exits_1_naming_it(faulted_run, tmp_path, capsys):
    blocked = tmp_path / "a-directory.csv"
    blocked.mkdir()  # the CSV cannot replace a directory
    assert main(["export", "--state-dir", str(faulted_run.state_dir), "--out",
                 str(blocked)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("dsfd export: ") and str(blocked) in err
    assert blocked.is_dir() and not any(blocked.iterdir())
