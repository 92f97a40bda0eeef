"""``dsfd bench diagnostics`` scoring (dsfd.bench.diagnostics.score) on databases of the
daemon's schema whose answers are known by construction, and its refusals on the CLI.

The expected figures are counted from the rows written here: which findings opened before
the onset (false), which after (detected; named only by the kinds that name the fault), and
the delay in the target's unit (minutes that used the stuck damper, minutes of sun).
"""

from __future__ import annotations

import dataclasses
import signal
import sqlite3
import subprocess
import time
from pathlib import Path

import pytest

from dsfd.bench.diagnostics import Scenario, report, scenarios, score
from dsfd.cli.bench import diagnostics_seeds
from dsfd.storage.timeseries import Store
from tests.daemon.harness import ROOT, dsfd_command

T0 = 1.7e9
MIN = 60.0


def _database(tmp_path: Path, *, n: int, afr: list[int], or_pct: list[float],
              ghi: list[float], findings: list[tuple[str, str, float]]) -> Path:
    """``n`` one-minute cycles from T0 with the command in force ``afr``/``or_pct`` and
    the GHI reading per cycle, and ``findings`` (kind, subject, opened at [s after T0])."""
    store = Store.open(tmp_path)
    run = store.begin_run(panel="p", mode="test", version="0", config_path=None)
    store.close()
    db = tmp_path / "timeseries.sqlite"
    with sqlite3.connect(db) as conn:
        conn.executemany("INSERT INTO decisions (run_id, cycle, slot, time_s, time_utc, "
                         "method, phi_deg, afr, or_pct, write_status, cycle_ms) VALUES "
                         "(?, ?, ?, ?, 't', 'mpc', 0.0, ?, ?, 'dry-run', 1.0)",
                         [(run, c, c, T0 + c * MIN, afr[c], or_pct[c]) for c in range(n)])
        conn.executemany("INSERT INTO model (run_id, cycle, time_s, applied_afr, "
                         "applied_or_pct) VALUES (?, ?, ?, ?, ?)",
                         [(run, c, T0 + c * MIN, afr[c], or_pct[c]) for c in range(n)])
        conn.executemany("INSERT INTO samples (run_id, cycle, time_s, signal, value, quality) "
                         "VALUES (?, ?, ?, 'ghi_wm2', ?, 'good')",
                         [(run, c, T0 + c * MIN, ghi[c]) for c in range(n)])
        conn.executemany("INSERT INTO findings (run_id, kind, subject, confidence, start_s, "
                         "detected_s, opened_s, last_seen_s, action) VALUES "
                         "(?, ?, ?, 0.6, ?, ?, ?, ?, 'x')",
                         [(run, k, s, T0 + t, T0 + t, T0 + t, T0 + t) for k, s, t in findings])
    return db


def _scenario(name: str, **kw: object) -> Scenario:
    base = next(s for s in scenarios(clean_days=1.0) if s.name == name)
    return dataclasses.replace(base, **kw)  # type: ignore[arg-type]


def test_a_stuck_damper_is_timed_in_minutes_that_used_it_and_earlier_findings_are_false(
        tmp_path: Path) -> None:
    # 120 cycles; onset at 30 min; regime 1 (IB + IT, open) on the even cycles from 40 on,
    # regime 10 (closed) otherwise; the named finding opens at 80 min
    n = 120
    afr = [1 if c >= 40 and c % 2 == 0 else 10 for c in range(n)]
    db = _database(tmp_path, n=n, afr=afr, or_pct=[100.0] * n, ghi=[0.0] * n,
                   findings=[("cavity_flow_when_closed", "", 10 * MIN),
                             ("cavity_no_flow", "", 60 * MIN),
                             ("damper_no_flow", "IB+IT", 80 * MIN)])
    fig = score(db, _scenario("stuck-damper", onset_s=30 * MIN))
    assert fig["false_findings"] == 1.0 and fig["false_kinds"] == "cavity_flow_when_closed"
    assert fig["detected"] == 1.0 and fig["first_kind"] == "cavity_no_flow"
    assert fig["named"] == 1.0
    # the cycles in [30 min, 80 min) with IT commanded open: even cycles 40..78 → 20
    assert fig["name_delay_min"] == 20.0 and fig["within_target"] == 1.0
    assert fig["detect_delay_min"] == 10.0  # even cycles 40..58
    assert fig["clean_days"] == pytest.approx(30 * MIN / 86400.0)


def test_a_closed_damper_opening_does_not_count_and_a_finding_on_another_damper_names_nothing(
        tmp_path: Path) -> None:
    n = 60
    db = _database(tmp_path, n=n, afr=[1] * n, or_pct=[0.0] * n, ghi=[0.0] * n,
                   findings=[("damper_no_flow", "EB", 40 * MIN)])
    fig = score(db, _scenario("stuck-damper", onset_s=10 * MIN))
    assert fig["detected"] == 1.0 and fig["named"] == 0.0
    assert "name_delay_min" not in fig and "within_target" not in fig
    # regime 1 at 0 % opening is the closed cavity: no minute used IT
    assert fig["detect_delay_min"] == 0.0 and fig["observed_min"] == 0.0


def test_a_louver_slip_is_timed_in_minutes_of_sun_and_named_by_the_louver_parameters(
        tmp_path: Path) -> None:
    n = 200
    ghi = [500.0 if 50 <= c < 100 else 50.0 for c in range(n)]  # 50 min of sun
    db = _database(tmp_path, n=n, afr=[10] * n, or_pct=[0.0] * n, ghi=ghi,
                   findings=[("residual_shift", "residual:x2_c", 150 * MIN)])
    fig = score(db, _scenario("louver-slip", onset_s=20 * MIN))
    assert fig["detected"] == 1.0 and fig["named"] == 0.0  # a pane's residual names no slip
    assert fig["detect_delay_min"] == 50.0 and fig["observed_min"] == 50.0
    assert fig["false_findings"] == 0.0


@pytest.mark.parametrize(("kind", "subject", "named"), [
    ("parameter_shift", "parameter:q_x3", True),   # the inner pane's heat-flux offset
    ("parameter_shift", "parameter:q_x2", False),  # another pane's
    ("parameter_shift", "parameter:h_in", False),
])
def test_a_thermocouple_offset_is_named_by_its_panes_heat_flux_offset(
        tmp_path: Path, kind: str, subject: str, named: bool) -> None:
    n = 300
    db = _database(tmp_path, n=n, afr=[10] * n, or_pct=[0.0] * n, ghi=[0.0] * n,
                   findings=[(kind, subject, 250 * MIN)])
    fig = score(db, _scenario("tc-offset", onset_s=100 * MIN))
    assert fig["named"] == float(named)


def test_a_thermocouple_step_is_named_by_its_own_residual_only(tmp_path: Path) -> None:
    n = 300
    db = _database(tmp_path, n=n, afr=[10] * n, or_pct=[0.0] * n, ghi=[0.0] * n,
                   findings=[("residual_shift", "residual:x2_c", 120 * MIN),
                             ("residual_shift", "residual:x3_c", 200 * MIN)])
    fig = score(db, _scenario("tc-offset", onset_s=100 * MIN))
    assert fig["first_kind"] == "residual_shift:residual:x2_c"
    assert fig["detect_delay_min"] == 20.0 and fig["name_delay_min"] == 100.0
    assert fig["within_target"] == 1.0


def test_a_clean_run_counts_every_finding_as_false_and_the_table_totals_them(
        tmp_path: Path) -> None:
    n = 1440
    db = _database(tmp_path, n=n, afr=[10] * n, or_pct=[0.0] * n, ghi=[0.0] * n,
                   findings=[("residual_shift", "residual:x5_c", 700 * MIN)])
    clean = _scenario("clean", onset_s=86400.0, days=1.0)
    fig = score(db, clean)
    assert fig["false_findings"] == 1.0 and fig["clean_days"] == pytest.approx(1439 / 1440)
    assert "detected" not in fig
    table = report({f"winter.clean.seed1.{k}": v for k, v in fig.items()})
    assert table.splitlines()[-1] == "false findings: 1 over 1.00 clean simulated days"


@pytest.mark.parametrize(("args", "message"), [
    (["--seasons", "summer"], "unknown season(s) summer"),
    (["--scenarios", "stuck-damper,dirt"], "unknown scenario(s) dirt"),
    (["--seasons", "winter", "--target-free"], "unrecognized arguments"),
])
def test_the_cli_refuses_an_unknown_season_or_scenario_naming_it(args: list[str],
                                                                  message: str) -> None:
    done = subprocess.run(dsfd_command("bench", "diagnostics", "--seeds", "1", *args),
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2 and message in done.stderr, done.stderr


def test_a_recheck_of_a_folder_without_kept_runs_is_an_error_naming_it(tmp_path: Path) -> None:
    """Not an empty table and exit 0: the operator mistyped the folder or the seeds."""
    (tmp_path / "winter.screen.seed2").mkdir()  # another seed's run, and no database
    done = subprocess.run(dsfd_command("bench", "diagnostics", "--seeds", "1", "--seasons",
                                       "winter", "--scenarios", "screen", "--recheck",
                                       str(tmp_path)),
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2, done.stdout
    assert f"--recheck {tmp_path}: no kept run" in done.stderr, done.stderr
    assert "looked for winter.screen.seed1;" in done.stderr, done.stderr


@pytest.mark.parametrize(("seeds", "seed", "expected"), [
    (None, None, (1, 2, 3)),        # the seeds
    (2, None, (1, 2)),              # a count from 1
    (None, 2, (2,)),                # --seed alone: that seed
    (2, 3, (3, 4)),                 # a count from --seed, as closed-loop and identify take it
    ((2, 5), 7, (2, 5)),            # a list as given
])
def test_the_seeds_a_diagnostics_bench_runs(seeds, seed, expected) -> None:
    assert diagnostics_seeds(seeds, seed) == expected


def test_seed_alone_runs_that_seed_and_says_so(tmp_path: Path) -> None:
    """``--seed 2`` means seed 2 (a count ``--seeds 2`` would also run seed 1): the recheck
    of an empty folder names what it looked for."""
    done = subprocess.run(dsfd_command("bench", "diagnostics", "--seed", "2", "--seasons",
                                       "winter", "--scenarios", "screen,tc-offset", "--recheck",
                                       str(tmp_path)),
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2, done.stdout
    assert "looked for winter.tc-offset.seed2, winter.screen.seed2;" in done.stderr, done.stderr


def test_a_stopped_bench_leaves_no_daemon_behind(tmp_path: Path) -> None:
    """SIGTERM to the bench while its ``dsfd run`` runs: the run is stopped too (it was left
    running on its own, writing to a folder the operator then deleted), and the bench says
    it was interrupted."""
    keep = tmp_path / "k"
    bench = subprocess.Popen(dsfd_command("bench", "diagnostics", "--seeds", "1,", "--seasons",
                                          "winter", "--scenarios", "clean", "--days", "1",
                                          "--keep-state", str(keep)),
                             cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)
    db = keep / "winter.clean.seed1" / "timeseries.sqlite"
    try:
        deadline = time.monotonic() + 120.0
        while not _has_cycles(db):  # the daemon is running and storing cycles
            assert bench.poll() is None and time.monotonic() < deadline, bench.stderr
            time.sleep(0.2)
        bench.send_signal(signal.SIGTERM)
        _, err = bench.communicate(timeout=60)
    finally:
        if bench.poll() is None:
            bench.kill()
    assert bench.returncode == 130 and "interrupted" in err, err
    left = subprocess.run(["pgrep", "-f", str(db.parent)], capture_output=True, text=True,
                          check=False)
    assert left.stdout.strip() == "", left.stdout


def _has_cycles(db: Path) -> bool:
    if not db.exists():
        return False
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as conn:
            return conn.execute("SELECT COUNT(*) FROM decisions").fetchone()[0] > 0
    except sqlite3.Error:
        return False


def test_the_diagnostics_options_are_refused_by_other_targets() -> None:
    done = subprocess.run(dsfd_command("bench", "model", "--scenarios", "clean"), cwd=ROOT,
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2
    assert "--scenarios only applies to the diagnostics target" in done.stderr


@pytest.mark.parametrize(("subject", "named"), [("parameter:q_x4", True),
                                                 ("parameter:h_ca2", True),
                                                 ("parameter:q_x1", False)])
def test_a_louver_slip_is_named_by_a_louver_parameter(tmp_path: Path, subject: str,
                                                        named: bool) -> None:
    n = 200
    db = _database(tmp_path, n=n, afr=[10] * n, or_pct=[0.0] * n, ghi=[500.0] * n,
                   findings=[("parameter_shift", subject, 150 * MIN)])
    fig = score(db, _scenario("louver-slip", onset_s=20 * MIN))
    assert fig["named"] == float(named)
