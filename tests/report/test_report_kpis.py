"""The report's key figures against the database, computed independently in SQL."""

from __future__ import annotations

import math

from dsfd.cli import main
from tests.daemon.harness import query, write_panel
from tests.report.conftest import CYCLES

J_PER_KWH = 3.6e6
TERMS = ("q_cv_rd", "q_sol_trans", "q_air", "q_da")


def test_counts_match_the_database(faulted_run):
    db = faulted_run.state_dir / "timeseries.sqlite"
    total = faulted_run.doc["total"]
    assert total["cycles"] == CYCLES == sum(total["methods"].values())
    assert total["methods"] == dict(query(db, "SELECT method, COUNT(*) FROM decisions "
                                              "GROUP BY method"))
    # The injected faults: x3 dropped out, x1 spiked; each flagged reading counted once.
    flagged = {(r["signal"], r["quality"]): r["samples"] for r in faulted_run.doc["flagged"]}
    assert flagged == {(s, q): n for s, q, n in query(
        db, "SELECT signal, quality, COUNT(*) FROM samples WHERE quality != 'good' "
        "GROUP BY 1, 2")}
    assert flagged[("x3_c", "not_finite")] == 3 and ("x1_c", "out_of_range") in flagged
    assert total["flagged"] == sum(flagged.values())
    assert total["calibration_updates"] == query(
        db, "SELECT COUNT(*) FROM parameters WHERE source = 'online'")[0][0] > 0
    (moves,), = query(db, "SELECT COUNT(*) FROM (SELECT applied_phi_deg AS p, LAG("
                          "applied_phi_deg) OVER (ORDER BY cycle) AS q FROM model) "
                          "WHERE p != q")
    assert total["louver_moves"] == moves
    assert total["write_failures"] == 0


def test_heat_is_the_stored_power_integrated_and_the_plant_s_own_difference(faulted_run):
    db = faulted_run.state_dir / "timeseries.sqlite"
    total = faulted_run.doc["total"]
    for term in TERMS:
        (watts,), = query(db, f"SELECT SUM({term}_w) FROM model")
        assert math.isclose(total["heat_model_kwh"][term], watts * 60 / J_PER_KWH,
                            rel_tol=1e-12, abs_tol=1e-12)
        (first,), = query(db, f"SELECT plant_{term}_j FROM model ORDER BY cycle LIMIT 1")
        (last,), = query(db, f"SELECT plant_{term}_j FROM model ORDER BY cycle DESC LIMIT 1")
        assert math.isclose(total["heat_plant_kwh"][term], (last - first) / J_PER_KWH,
                            rel_tol=1e-9, abs_tol=1e-12)
    # The model's estimate covers every step after the first cycle.
    assert math.isclose(total["heat_model_hours"], (CYCLES - 1) / 60)
    # The lumped-equivalent plant is the lumped model: both see the same sun through the
    # same glazing, so the transmitted solar agrees to within the calibration's error.
    model, plant = (total[k]["q_sol_trans"] for k in ("heat_model_kwh", "heat_plant_kwh"))
    assert plant > 0.05 and abs(model - plant) < 0.25 * plant


def test_estimates_and_one_step_errors_are_stored_as_the_observer_made_them(faulted_run):
    db = faulted_run.state_dir / "timeseries.sqlite"
    # x1 is taken as measured (measurement gain 1): the stored estimate is the reading.
    rows = query(db, "SELECT m.est_x1_c, s.value FROM model m JOIN samples s USING (run_id, "
                     "cycle) WHERE s.signal = 'x1_c' AND s.quality = 'good'")
    assert len(rows) > CYCLES - 10
    assert max(abs(a - b) for a, b in rows) < 1e-9
    # x2 has no fault: one-step model and persistence errors from plain SQL.
    (model, persist, n), = query(
        db, "SELECT AVG(ABS(m.pred_x2_c - s.value)), AVG(ABS(p.value - s.value)), COUNT(*) "
        "FROM model m JOIN samples s ON s.run_id = m.run_id AND s.cycle = m.cycle "
        "JOIN samples p ON p.run_id = m.run_id AND p.cycle = m.cycle - 1 "
        "WHERE s.signal = 'x2_c' AND p.signal = 'x2_c' AND m.pred_x2_c IS NOT NULL")
    err = faulted_run.doc["prediction_errors"]["x2"]
    assert err["h1_cycles"] == n == CYCLES - 1
    assert math.isclose(err["h1_model_mae"], model, rel_tol=1e-12)
    assert math.isclose(err["h1_persistence_mae"], persist, rel_tol=1e-12)
    assert err["horizon_cycles"] > 0 and faulted_run.doc["horizon_steps"] == 5


def test_report_options_and_errors(faulted_run, tmp_path, capsys):
    out = tmp_path / "r.html"
    assert main(["report", "--state-dir", str(tmp_path), "--out", str(out)]) == 1
    assert "no database" in capsys.readouterr().err
    assert main(["report", "--state-dir", str(faulted_run.state_dir), "--out", str(out),
                 "--since", "2030-01-01T00:00:00Z"]) == 1
    assert "no cycles between 2030-01-01T00:00:00Z" in capsys.readouterr().err
    assert main(["report", "--state-dir", str(faulted_run.state_dir), "--out", str(out),
                 "--since", "yesterday"]) == 2
    assert not out.exists()
    # --config finds the state directory as dsfd run does (daemon.state_directory here).
    panel = write_panel(tmp_path / "p.yaml", devices=False,
                        extra={"daemon": {"state_directory": str(faulted_run.state_dir)}})
    assert main(["report", "--config", str(panel), "--out", str(out), "--dpi", "30"]) == 0
    assert out.read_text().count("<img ") == 7
    other = write_panel(tmp_path / "q.yaml", devices=False, extra={
        "panel": {"id": "north"}, "daemon": {"state_directory": str(faulted_run.state_dir)}})
    assert main(["export", "--config", str(other), "--out", str(tmp_path / "m.csv")]) == 2
    assert "holds panel 'suwon-south', not 'north'" in capsys.readouterr().err


def synthetic_history(times_s, run_ids, param_times, param_runs, h_out):
    """A History of bare cycles with a parameter history of h_out (pure-logic tests)."""
    from pathlib import Path

    import numpy as np

    from dsfd.storage.history import History, ParameterHistory
    from dsfd.storage.timeseries import MODEL_COLUMNS

    n = len(times_s)
    dec = {k: np.full(n, np.nan) for k in ("phi_deg", "afr", "or_pct", "decide_ms")}
    dec.update(method=np.full(n, "mpc", object), write_status=np.full(n, "verified", object))
    params = ParameterHistory(np.asarray(param_times, float), np.asarray(param_runs),
                              np.array(["online"] * len(param_times), object),
                              {"h_out": np.asarray(h_out, float)})
    return History(Path("x"), 2, (), np.asarray(times_s, float), np.asarray(run_ids),
                   np.arange(n), dec, {}, {}, {c: np.full(n, np.nan) for c, _ in MODEL_COLUMNS},
                   params)


def test_time_at_a_bound_ends_with_the_run_not_at_the_next_start():
    from dsfd.report.kpis import compute_kpis

    # Run 1: cycles 0..30 min; h_out at its lower bound 3 from minute 10 to the run's end.
    # Run 2 starts two hours later with h_out at the bound again until its end (+15 min).
    t = [*range(0, 1801, 60), *range(9000, 9901, 60)]
    runs = [1] * 31 + [2] * 16
    h = synthetic_history(t, runs, [0, 600, 9000], [1, 1, 2], [12.0, 3.0, 3.0])
    config = {"parameters": {"h_out": {"lower": 3.0, "upper": 40.0, "default": 12.0}},
              "model": {"step_s": 60.0}, "site": {"utc_offset_h": 0.0}}
    at = compute_kpis(h, config).at_bound
    assert [(a["parameter"], a["bound"]) for a in at] == [("h_out", "lower")]
    assert math.isclose(at[0]["hours"], (1200 + 900) / 3600)  # not the 2 h between runs


def test_one_step_errors_by_regime_partition_the_scored_cycles(faulted_run):
    """Each scored cycle counted once: under the regime applied over its step when the step
    before had the same, else in the "after a change" row; figures recomputed here from the
    rows of the database with plain loops."""
    db = faulted_run.state_dir / "timeseries.sqlite"
    afr = dict(query(db, "SELECT cycle, applied_afr FROM model"))
    pred = dict(query(db, "SELECT cycle, pred_x2_c FROM model WHERE pred_x2_c IS NOT NULL"))
    y = dict(query(db, "SELECT cycle, value FROM samples WHERE signal = 'x2_c' "
                       "AND quality = 'good'"))
    rows: dict[object, list[tuple[float, float, float]]] = {}
    for c in sorted(pred):
        if c not in y or c - 1 not in y:
            continue
        over = afr[c - 1]
        key = over if afr.get(c - 2, over) == over else "after a change"
        rows.setdefault(key, []).append((abs(pred[c] - y[c]), abs(y[c - 1] - y[c]),
                                         pred[c] - y[c]))
    by_regime = faulted_run.doc["prediction_errors_by_regime"]
    got = {r["regime"]: r["outputs"]["x2"] for r in by_regime if "x2" in r["outputs"]}
    assert set(got) == set(rows)
    for key, errs in rows.items():
        n = len(errs)
        assert got[key]["cycles"] == n
        assert math.isclose(got[key]["model_mae"], sum(e[0] for e in errs) / n, rel_tol=1e-9)
        assert math.isclose(got[key]["persistence_mae"], sum(e[1] for e in errs) / n,
                            rel_tol=1e-9)
        assert math.isclose(got[key]["model_mean_error"], sum(e[2] for e in errs) / n,
                            rel_tol=1e-9, abs_tol=1e-12)
    # the rows partition the cycles of the whole-run table
    total = faulted_run.doc["prediction_errors"]["x2"]["h1_cycles"]
    assert sum(len(e) for e in rows.values()) == total
    assert "One step ahead by airflow regime" in faulted_run.html.read_text()
