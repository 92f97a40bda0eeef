"""``daemon.metrics_file``: Prometheus's own parser reads it while the daemon rewrites it."""

from __future__ import annotations

import subprocess
import sys

import pytest
from prometheus_client.parser import text_string_to_metric_families

from dsfd.estimation.lifecycle import FINDING_KINDS
from tests.daemon.harness import MORNING_ISO, ROOT, dsfd_command, query, write_panel

CYCLES = 40
METRICS = {"dsfd_cycle_duration_seconds", "dsfd_decision_duration_seconds",
           "dsfd_last_cycle_timestamp_seconds", "dsfd_cycles", "dsfd_flagged_samples",
           "dsfd_write_failures", "dsfd_calibration_updates", "dsfd_calibration_age_seconds",
           "dsfd_parameter", "dsfd_louver_angle_degrees", "dsfd_airflow_regime",
           "dsfd_damper_opening_ratio", "dsfd_hold_active", "dsfd_room_heat_watts",
           "dsfd_occupied", "dsfd_occupancy_override_active",
           "dsfd_direct_sun_watts_per_square_meter", "dsfd_daylight_glare_probability",
           "dsfd_supply_air_celsius", "dsfd_radiant_asymmetry_kelvin",
           "dsfd_occupied_seconds", "dsfd_comfort_exceeded_seconds", "dsfd_finding_open"}
ALWAYS = ["00:00-24:00"]
#: Every day occupied, and a supply-air limit warm enough to be broken in winter.
COMFORT = {"occupancy": {d: ALWAYS for d in ("mon", "tue", "wed", "thu", "fri", "sat", "sun")},
           "comfort": {"supply_air_min_c": 30.0}}


def parse(text: str) -> dict[str, list]:
    return {f.name: f.samples for f in text_string_to_metric_families(text)}


def test_metrics_file_is_complete_at_every_read_and_matches_the_database(tmp_path):
    prom = tmp_path / "textfile" / "dsfd-test.prom"
    prom.parent.mkdir()
    panel = write_panel(tmp_path / "panel.yaml", devices=False,
                        extra={"daemon": {"metrics_file": str(prom)}, **COMFORT})
    state = tmp_path / "state"
    proc = subprocess.Popen(
        dsfd_command("run", "--config", str(panel), "--dry-run", "--plant", "sim",
                     "--plant-fidelity", "lumped", "--start", MORNING_ISO, "--cycles",
                     str(CYCLES), "--state-dir", str(state)),
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    reads, seen = 0, set()
    try:
        while proc.poll() is None:  # read as fast as we can while the daemon rewrites
            try:
                text = prom.read_text()
            except FileNotFoundError:
                continue
            families = parse(text)  # raises on a torn line
            assert set(families) == METRICS, sorted(METRICS ^ set(families))
            reads += 1
            seen.add(families["dsfd_last_cycle_timestamp_seconds"][0].value)
    finally:
        proc.wait(timeout=300)
    assert proc.returncode == 0, proc.stderr.read().decode() if proc.stderr else ""
    print(f"{reads} reads, {len(seen)} distinct cycles")
    assert reads > 0 and len(seen) >= 1
    # Only the .prom file is left (the temporary files were renamed over it).
    assert [p.name for p in prom.parent.iterdir()] == [prom.name]
    families = parse(prom.read_text())
    db = state / "timeseries.sqlite"
    labels = {s.labels.get("panel") for f in families.values() for s in f}
    assert labels == {"suwon-south"}
    cycles = {s.labels["method"]: s.value for s in families["dsfd_cycles"]
              if s.name == "dsfd_cycles_total"}
    assert cycles == {m: float(n) for m, n in query(
        db, "SELECT method, COUNT(*) FROM decisions GROUP BY method")}
    (t, phi, afr, or_pct), = query(db, "SELECT time_s, applied_phi_deg, applied_afr, "
                                       "applied_or_pct FROM model ORDER BY cycle DESC LIMIT 1")
    value = {name: fam[0].value for name, fam in families.items() if fam}
    assert families["dsfd_flagged_samples"] == []  # no fault injected in this run
    assert value["dsfd_last_cycle_timestamp_seconds"] == t
    assert (value["dsfd_louver_angle_degrees"], value["dsfd_airflow_regime"],
            value["dsfd_damper_opening_ratio"]) == (phi, afr, or_pct / 100)
    assert value["dsfd_hold_active"] == 0.0
    params = {s.labels["parameter"]: s.value for s in families["dsfd_parameter"]}
    (h_out, n), = query(db, "SELECT h_out, n FROM parameters ORDER BY cycle DESC LIMIT 1")
    assert (params["h_out"], params["n"]) == (h_out, n)
    heat = {s.labels["term"]: s.value for s in families["dsfd_room_heat_watts"]}
    (q_sol,), = query(db, "SELECT q_sol_trans_w FROM model ORDER BY cycle DESC LIMIT 1")
    assert set(heat) == {"q_cv_rd", "q_sol_trans", "q_air", "q_da"}
    assert heat["q_sol_trans"] == q_sol
    check_comfort(families, db)
    # the open findings by kind (issue 38): every kind has its series, as in the database
    found = {s.labels["kind"]: s.value for s in families["dsfd_finding_open"]}
    stored = dict(query(db, "SELECT kind, COUNT(*) FROM findings WHERE state = 'open' "
                            "GROUP BY kind"))
    assert set(found) == set(FINDING_KINDS) | set(stored)
    assert found == {k: float(stored.get(k, 0)) for k in found}


def check_comfort(families: dict[str, list], db) -> None:
    """The comfort series against the ``comfort`` table, counted here in SQL (issue 36)."""
    occupied = [(s.labels["source"], s.value) for s in families["dsfd_occupied"]]
    assert occupied == [("schedule", 1.0)]
    assert families["dsfd_occupancy_override_active"][0].value == 0.0
    (n_occupied,), = query(db, "SELECT SUM(occupied) FROM comfort")
    total = {s.name: s.value for s in families["dsfd_occupied_seconds"]}
    assert total["dsfd_occupied_seconds_total"] == n_occupied * 60.0 == CYCLES * 60.0
    exceeded = {s.labels["limit"]: s.value for s in families["dsfd_comfort_exceeded_seconds"]
                if s.name.endswith("_total")}
    expected = query(db, "SELECT SUM(direct_sun_wm2 > direct_sun_max_wm2), SUM(dgp > dgp_max), "
                         "SUM(supply_air_c < supply_air_min_c), "
                         "SUM(ABS(asymmetry_k) > asymmetry_max_k) FROM comfort WHERE occupied")
    assert exceeded == {k: 60.0 * (n or 0) for k, n in zip(
        ("direct_sun", "glare", "draught", "asymmetry"), expected[0], strict=True)}
    assert exceeded["draught"] > 0  # 30 °C supply air is not reached on a winter morning
    last = query(db, "SELECT direct_sun_wm2, dgp, supply_air_c, asymmetry_k FROM comfort "
                     "ORDER BY cycle DESC LIMIT 1")[0]
    gauges = [families[name][0].value for name in (
        "dsfd_direct_sun_watts_per_square_meter", "dsfd_daylight_glare_probability",
        "dsfd_supply_air_celsius", "dsfd_radiant_asymmetry_kelvin")]
    for got, want in zip(gauges, last, strict=True):
        assert got == want or (want is None and got != got)  # NULL: NaN


def run_without(module: str, args: list[str]) -> subprocess.CompletedProcess:
    """``dsfd ARGS`` in a Python where ``module`` cannot be imported (extra not installed)."""
    code = (f"import sys; sys.modules[{module!r}] = None\n"
            "from dsfd.cli import main\nsys.exit(main(sys.argv[1:]))")
    return subprocess.run([sys.executable, "-c", code, *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)


def test_a_metrics_file_without_prometheus_client_is_a_configuration_error(tmp_path):
    prom = tmp_path / "dsfd.prom"
    panel = write_panel(tmp_path / "panel.yaml", devices=False,
                        extra={"daemon": {"metrics_file": str(prom)}})
    out = run_without("prometheus_client", [
        "run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
        "lumped", "--cycles", "2", "--state-dir", str(tmp_path / "state")])
    assert out.returncode == 2
    assert "daemon.metrics_file" in out.stderr and "pip install 'dsfd[metrics]'" in out.stderr
    assert not (tmp_path / "state").exists() and not prom.exists()


def test_a_report_without_matplotlib_exits_2_naming_the_extra(tmp_path):
    out = run_without("matplotlib", ["report", "--state-dir", str(tmp_path), "--out",
                                     str(tmp_path / "r.html")])
    assert out.returncode == 2 and "pip install 'dsfd[report]'" in out.stderr


def test_a_metrics_file_must_be_a_prom_file_in_a_directory_that_exists(tmp_path):
    from dsfd.config import ConfigError
    from dsfd.daemon.startup import load_for_run

    nowhere = tmp_path / "no-such-directory"
    for path, why in ((tmp_path / "dsfd.txt", "must end in .prom"),
                      (nowhere / "dsfd.prom", f"directory {nowhere} does not exist")):
        panel = write_panel(tmp_path / "panel.yaml", devices=False,
                            extra={"daemon": {"metrics_file": str(path)}})
        with pytest.raises(ConfigError) as exc:
            load_for_run(panel, simulated_plant=True, dry_run=True)
        (issue,) = exc.value.issues
        assert issue.path == "daemon.metrics_file" and why in issue.message
        assert not path.exists()


def test_flagged_samples_are_counted_by_signal_and_quality_as_stored(tmp_path):
    """A faulted dry run (tests/report/dryrun.py: x3 drops out, x1 spikes): the counters of
    ``dsfd_flagged_samples_total`` carry the labels ``signal`` and ``quality`` and equal the
    database's count of non-good samples per signal and quality."""
    from tests.report.conftest import dry_run

    prom = tmp_path / "dsfd-test.prom"
    panel = write_panel(tmp_path / "panel.yaml", devices=False,
                        extra={"daemon": {"metrics_file": str(prom)}})
    state = tmp_path / "state"
    dry_run(panel, state, 45, MORNING_ISO, faults=True)
    flagged = {(s.labels["signal"], s.labels["quality"]): s.value
               for s in parse(prom.read_text())["dsfd_flagged_samples"]
               if s.name == "dsfd_flagged_samples_total"}
    stored = {(sig, q): float(n) for sig, q, n in query(
        state / "timeseries.sqlite",
        "SELECT signal, quality, COUNT(*) FROM samples WHERE quality != 'good' GROUP BY 1, 2")}
    assert ("x3_c", "not_finite") in stored and ("x1_c", "out_of_range") in stored
    assert flagged == stored
