"""Reports of awkward logs: a night without sun, a gap between runs, overlapping replays, and
a closed-loop simulation."""

from __future__ import annotations

import json

import numpy as np

from dsfd.cli import main
from dsfd.report.figures import FIGURES
from dsfd.storage.history import read_history
from tests.report.conftest import dry_run

#: 23:00 and 01:00 local time in Suwon (UTC+9) on 1/2 January 2022: dark.
NIGHT_ISO, LATER_ISO = "2022-01-01T14:00:00Z", "2022-01-01T16:00:00Z"


def test_a_night_with_a_gap_and_an_overlapping_replay(test_panel, tmp_path, capsys):
    state = tmp_path / "state"
    dry_run(test_panel, state, 12, NIGHT_ISO)   # run 1
    dry_run(test_panel, state, 12, LATER_ISO)   # run 2, two hours later: a gap
    html, js = tmp_path / "r.html", tmp_path / "r.json"
    assert main(["report", "--state-dir", str(state), "--out", str(html), "--json", str(js),
                 "--dpi", "40"]) == 0
    doc = json.loads(js.read_text())
    text = html.read_text()
    assert text.count("<img ") == len(FIGURES)
    # Two local days (23:00 on the 1st, 01:00 on the 2nd), each with its cycles.
    assert [(d["day"], d["cycles"]) for d in doc["days"]] == [("2022-01-01", 12),
                                                             ("2022-01-02", 12)]
    # No sun: no transmitted solar, no daylight credit (< 1 Wh), in the model and in the
    # plant; the glass loses heat to the night sky instead.
    for key in ("heat_model_kwh", "heat_plant_kwh"):
        assert abs(doc["total"][key]["q_sol_trans"]) < 1e-3
        assert abs(doc["total"][key]["q_da"]) < 1e-3
        assert doc["total"][key]["q_cv_rd"] < 0
    # The gap is not a step: no one-step error across it (11 per run), none at the horizon
    # of 5 steps that would cross it (7 per run).
    assert doc["prediction_errors"]["x2"]["h1_cycles"] == 22
    assert doc["prediction_errors"]["x2"]["horizon_cycles"] == 14
    capsys.readouterr()
    # The export keeps the gap; validate does not score across it.
    csv, scores = tmp_path / "m.csv", tmp_path / "v.json"
    assert main(["export", "--state-dir", str(state), "--out", str(csv)]) == 0
    assert main(["validate", "--config", str(test_panel), "--data", str(csv), "--no-online",
                 "--horizons", "1", "--json", str(scores)]) == 0
    assert json.loads(scores.read_text())["scored_starts"] == 22

    dry_run(test_panel, state, 5, NIGHT_ISO)    # run 3 replays run 1's hour again
    history = read_history(state)
    assert sorted(set(history.run_id.tolist())) == [2, 3]
    assert any("overlap in time" in n for n in history.notes)
    assert len(read_history(state, run_id=1)) == 12
    assert main(["report", "--state-dir", str(state), "--run", "1", "--out", str(html),
                 "--dpi", "40"]) == 0
    assert "overlap" not in html.read_text()


def test_a_closed_loop_writes_the_same_report(tmp_path, capsys):
    html, js = tmp_path / "loop.html", tmp_path / "loop.json"
    assert main(["simulate", "--config", "config/panels/suwon-south.yaml", "--plant", "truth",
                 "--controller", "rule", "--calibration", "none", "--fidelity", "lumped",
                 "--start", "2022-01-02T01:00:00Z", "--hours", "0.5", "--json", str(js),
                 "--report", str(html)]) == 0
    out = capsys.readouterr().out
    assert f"wrote {html}" in out
    text = html.read_text()
    assert text.count("<img ") == len(FIGURES) and "closed-loop simulation" in text
    # a closed loop runs no detectors: its report does not pretend they found nothing
    assert "a closed-loop simulation (dsfd simulate) does not run the daemon&#x27;s " \
        "detectors" in text
    summary = json.loads(js.read_text())
    cycles = summary["cycles"]
    assert cycles == 30 and "rule " + str(cycles) in text
    assert main(["simulate", "--config", "config/panels/suwon-south.yaml", "--plant", "truth",
                 "--controller", "fixed", "--report", str(html)]) == 2
    assert "not fixed" in capsys.readouterr().err


def test_local_days_follow_the_panel_s_utc_offset():
    from dsfd.report.kpis import local_day

    t = np.array([1641049200.0 - 1, 1641049200.0])  # 2022-01-01T15:00Z = midnight at UTC+9
    assert local_day(t, 9.0).tolist() == ["2022-01-01", "2022-01-02"]
    assert local_day(t, 0.0).tolist() == ["2022-01-01", "2022-01-01"]
