"""``--fault KIND:START:RATE``: the grammar (docs/faults.md#simulated-faults), its errors by
the real ``dsfd run`` process, and a dry run that takes a fault."""

from __future__ import annotations

import subprocess

import pytest

from dsfd.measured import parse_iso_utc
from dsfd.sim.plant.faults import FaultSpecError, parse_fault
from tests.daemon.harness import MORNING_ISO, ROOT, dsfd_command, write_panel


@pytest.mark.parametrize(("text", "kind", "target", "rate", "offset_s"), [
    ("soiling:+2h:1.5", "soiling", None, 1.5, 7200.0),
    ("screen:+1.5d:1", "screen", None, 1.0, 129600.0),
    ("damper-stuck.eb:+90min:0", "damper-stuck", "EB", 0.0, 5400.0),
    ("louver-slip:+0s:-1", "louver-slip", None, -1.0, 0.0),
    ("tc-drift.x3:+30s:0.5", "tc-drift", "x3_c", 0.5, 30.0),
    ("tc-offset.t_out_c:+1h:-1", "tc-offset", "t_out_c", -1.0, 3600.0),
    ("anemometer:+1h:0.7", "anemometer", "v_cav_ms", 0.7, 3600.0),
    ("anemometer.wind_speed_ms:+1h:0.5", "anemometer", "wind_speed_ms", 0.5, 3600.0),
])
def test_relative_starts_parse(text, kind, target, rate, offset_s):
    spec = parse_fault(text)
    assert (spec.kind, spec.target, spec.rate) == (kind, target, rate)
    assert spec.start_s is None
    assert spec.start_at(1000.0) == 1000.0 + offset_s


def test_an_iso_start_with_its_colons_parses():
    spec = parse_fault("tc-offset.x1:2022-01-02T06:00:00Z:1")
    assert spec.start_at(0.0) == parse_iso_utc("2022-01-02T06:00:00Z")
    assert spec.start_at(0.0) == 1641103200.0  # date -ud 2022-01-02T06:00:00Z +%s
    assert spec.rate == 1.0


@pytest.mark.parametrize(("text", "named"), [
    ("soling:+2h:1", "kind 'soling' is unknown"),
    ("soiling:+2h", "expected KIND:START:RATE"),
    ("soiling", "expected KIND:START:RATE"),
    ("soiling:+2h:-1", "rate '-1'"),
    ("soiling:+2h:fast", "rate 'fast'"),
    ("soiling:+2h:nan", "rate 'nan'"),
    ("soiling.EB:+2h:1", "soiling takes no target"),
    ("soiling:+2hours:1", "start '+2hours'"),
    ("soiling:tomorrow:1", "start 'tomorrow'"),
    ("soiling:2022-01-02T06:00:00:1", "start '2022-01-02T06:00:00'"),  # no time zone
    ("damper-stuck:+0s:0", "damper-stuck needs a damper target"),
    ("damper-stuck.XX:+0s:0", "damper-stuck needs a damper target"),
    ("damper-stuck.EB:+0s:120", "must be within 0..100"),
    ("louver-slip:+0s:0.5", "non-zero whole number"),
    ("louver-slip:+0s:0", "non-zero whole number"),
    ("tc-drift.x9:+0s:1", "tc-drift needs a thermocouple target"),
    ("anemometer:+0s:0", "must be above 0"),
    ("anemometer.ghi_wm2:+0s:0.5", "anemometer target 'ghi_wm2'"),
])
def test_bad_specs_name_the_bad_part(text, named):
    with pytest.raises(FaultSpecError) as err:
        parse_fault(text)
    assert named in str(err.value)
    assert repr(text) in str(err.value)


@pytest.mark.parametrize(("fault", "named"), [
    ("soling:+2h:1", "kind 'soling' is unknown"),
    ("damper-stuck.EB:+2x:0", "start '+2x'"),
])
def test_dsfd_run_refuses_a_bad_fault_before_starting(tmp_path, fault, named):
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    done = subprocess.run(dsfd_command(
        "run", "--config", str(panel), "--dry-run", "--plant", "sim", "--cycles", "3",
        "--state-dir", str(state), "--fault", "soiling:+1h:1", "--fault", fault),
        cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2
    assert named in done.stderr and "--fault" in done.stderr
    assert not state.exists()  # nothing was started


def test_fault_needs_the_simulated_plant(tmp_path):
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    done = subprocess.run(dsfd_command("run", "--config", str(panel), "--dry-run", "--fault",
                                       "soiling:+1h:1"),
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2
    assert "--fault only applies to --plant sim" in done.stderr


def test_a_dry_run_takes_repeated_faults_and_says_so(tmp_path):
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    faults = ("damper-stuck.EB:+0s:0", "tc-offset.x1:+5min:2")
    args = [a for f in faults for a in ("--fault", f)]
    done = subprocess.run(dsfd_command(
        "run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
        "lumped", "--start", MORNING_ISO, "--cycles", "4", "--state-dir",
        str(tmp_path / "state"), "--log-format", "console", *args),
        cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    for f in faults:
        assert f"simulated fault {f}" in done.stdout


@pytest.mark.parametrize(("args", "named"), [
    (["closed-loop", "--fault", "soiling:+1h:x"], "rate 'x'"),
    (["model", "--fault", "soiling:+1h:1"], "--fault only applies to the closed-loop target"),
])
def test_dsfd_bench_refuses_a_bad_or_misplaced_fault(args, named):
    done = subprocess.run(dsfd_command("bench", *args), cwd=ROOT, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 2
    assert named in done.stderr
