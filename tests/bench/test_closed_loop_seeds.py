"""``dsfd bench closed-loop --seeds … --oracle-cache FILE``: the share per case and seed, with
the plant oracle's results kept between runs (issue 35: an oracle day costs ~40 CPU minutes)."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import pytest

from dsfd.bench.closed_loop import bench_closed_loop
from dsfd.bench.oracle_cache import ORACLE_VERSION, OracleCache, config_digest
from dsfd.sim.replay import load_weather
from tests.conftest import PANELS

PANEL = PANELS / "suwon-south.yaml"
TINY = dict(days=0.003, cases=("clear-heating",), warmup_h=0.0)


@pytest.mark.slow
def test_the_plant_oracle_is_computed_once_and_taken_from_the_cache(suwon, tmp_path):
    rmis_raw = load_weather("rmis-golden-2022-01")
    cache_file = tmp_path / "oracle.json"
    first = bench_closed_loop(suwon, rmis_raw, seed=1, controllers=("rule", "plant-oracle"),
                              oracle_cache=OracleCache(cache_file), **TINY)
    assert "clear-heating.plant-oracle.cached" not in first
    stored = json.loads(cache_file.read_text())
    assert stored["oracle_version"] == ORACLE_VERSION
    ((key, entry),) = stored["entries"].items()
    assert key.startswith("clear-heating|seed 1|")
    assert entry["figures"]["J_kwh"] == first["clear-heating.plant-oracle.J_kwh"]
    assert entry["commit"]  # the commit that produced it (or "unknown" outside a checkout)

    again = bench_closed_loop(suwon, rmis_raw, seed=1, controllers=("rule", "plant-oracle"),
                              oracle_cache=OracleCache(cache_file), **TINY)
    assert again["clear-heating.plant-oracle.cached"] == 1.0
    assert again["clear-heating.plant-oracle.J_kwh"] == first["clear-heating.plant-oracle.J_kwh"]
    # the rule ran again and the share is computed from both
    assert again["clear-heating.rule.J_kwh"] == first["clear-heating.rule.J_kwh"]
    # another panel (or seed) is another plant: the entry does not apply
    other = dataclasses.replace(suwon, room=dataclasses.replace(suwon.room, t_in_c=21.0))
    third = bench_closed_loop(other, rmis_raw, seed=1, controllers=("plant-oracle",),
                              oracle_cache=OracleCache(cache_file), **TINY)
    assert "clear-heating.plant-oracle.cached" not in third
    assert len(json.loads(cache_file.read_text())["entries"]) == 2


@pytest.mark.slow
def test_the_cli_prints_the_share_per_case_and_seed(tmp_path):
    out, cache = tmp_path / "cl.json", tmp_path / "oracle.json"
    cmd = [sys.executable, "-m", "dsfd", "bench", "closed-loop", "--config", str(PANEL),
           "--days", "0.003", "--case", "clear-heating", "--controllers",
           "rule,mpc,plant-oracle", "--seeds", "1,2", "--oracle-cache", str(cache),
           "--json", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    fig = json.loads(out.read_text())
    for seed in (1, 2):
        j = {n: fig[f"seed{seed}.clear-heating.{n}.J_kwh"]
             for n in ("rule", "mpc", "plant-oracle")}
        share = fig[f"seed{seed}.clear-heating.mpc_share_of_plant_oracle_saving"]
        assert share == pytest.approx((j["rule"] - j["mpc"]) / (j["rule"] - j["plant-oracle"]))
    table = proc.stdout.splitlines()
    header = next(line for line in table if line.startswith("case"))
    assert "seed 1" in header and "seed 2" in header and "mean" in header
    assert any(line.startswith("clear-heating") for line in table)
    assert len(json.loads(cache.read_text())["entries"]) == 2
    assert "closed loop: seed(s) 1, 2\n" in proc.stderr
    assert "seed 2: clear-heating: mpc J" in proc.stderr


def test_a_seed_count_says_which_seeds_it_runs_and_how_to_name_one(tmp_path):
    """``--seeds 1`` is one seed counted from ``--seed`` (0), not seed 1: the bench says so
    before it starts (a plant-oracle day ran on seed 0 that way, when seed 1 was meant)."""
    proc = subprocess.run([sys.executable, "-m", "dsfd", "bench", "closed-loop", "--config",
                           str(PANEL), "--days", "0.003", "--case", "clear-heating",
                           "--controllers", "rule", "--seeds", "1"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    first = proc.stderr.splitlines()[0]
    assert first == ("closed loop: seed(s) 0 (--seeds 1 is a count from --seed 0; name seeds "
                     "as a list, e.g. 1,2,3, or one as --seed N)")
    assert "seed 0: clear-heating: rule J" in proc.stderr


def test_a_seed_list_is_for_the_closed_loop_only():
    proc = subprocess.run([sys.executable, "-m", "dsfd", "bench", "paper-tables", "--seeds",
                           "1,2"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert "a list of seeds is for closed-loop" in proc.stderr
    bad = subprocess.run([sys.executable, "-m", "dsfd", "bench", "closed-loop", "--seeds",
                          "one"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "a count (e.g. 5) or a list" in bad.stderr


def test_a_file_that_is_no_oracle_cache_is_refused_naming_it(tmp_path):
    bad = tmp_path / "results.json"
    bad.write_text('{"target": "closed-loop"}')
    proc = subprocess.run([sys.executable, "-m", "dsfd", "bench", "closed-loop", "--case",
                           "clear-heating", "--oracle-cache", str(bad)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert f"{bad}: not a plant-oracle cache" in proc.stderr
    assert bad.read_text() == '{"target": "closed-loop"}'  # nothing written over it


@pytest.mark.slow
def test_a_calibration_setting_keeps_the_cached_oracle_because_the_oracle_never_reads_it(
        suwon, tmp_path):
    """The digest leaves out ``calibration`` and ``control.heat_offsets``
    (NOT_READ_BY_ORACLE, NOT_READ_BY_ORACLE_SETTINGS); checked by running the plant oracle
    under two such settings: the same J."""
    rmis_raw = load_weather("rmis-golden-2022-01")
    tuned = dataclasses.replace(
        suwon, calibration=dataclasses.replace(
            suwon.calibration, identifiability_sd_ratio=0.5, measurement_gain=(0.5,) * 5),
        control=dataclasses.replace(suwon.control, heat_offsets=not suwon.control.heat_offsets))
    assert config_digest(tuned) == config_digest(suwon)
    runs = [bench_closed_loop(cfg, rmis_raw, seed=2, controllers=("plant-oracle",), **TINY)
            for cfg in (suwon, tuned)]
    key = "clear-heating.plant-oracle.J_kwh"
    assert runs[0][key] == runs[1][key]
    # what the oracle does read changes the digest
    penalised = dataclasses.replace(suwon, control=dataclasses.replace(
        suwon.control, louver_move_penalty_wh=0.5))
    assert config_digest(penalised) != config_digest(suwon)
