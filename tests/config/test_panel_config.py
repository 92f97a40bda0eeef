"""Panel configuration: shipped files load; bad files name the key path and value."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from dsfd.config import ConfigError, load_panel, panel_from_mapping
from tests.conftest import PANELS

SHIPPED = sorted(PANELS.glob("*.yaml"))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_shipped_panels_are_valid(path):
    cfg = load_panel(path)
    assert cfg.panel.id == path.stem


def test_suwon_panel_holds_the_paper_unit(suwon):
    assert suwon.facade.azimuth_deg == 180.0
    assert suwon.facade.cavity_depth_m == 0.25
    assert suwon.louver.slat_width_m == 0.05
    assert suwon.louver.angles_deg() == tuple(float(a) for a in range(-90, 91, 18))
    assert suwon.openings.available_regimes() == tuple(range(1, 11))
    assert suwon.parameters.f.upper == 1e4  # docs/model.md#parameters


def test_panel_without_louver_is_expressible():
    cfg = load_panel(PANELS / "suwon-south-no-louver.yaml")
    assert cfg.louver is None


def _suwon_dict() -> dict:
    return yaml.safe_load((PANELS / "suwon-south.yaml").read_text())


def _issues(data: dict) -> dict[str, str]:
    with pytest.raises(ConfigError) as exc:
        panel_from_mapping(data, source="test.yaml")
    return {issue.path: str(issue) for issue in exc.value.issues}


def test_errors_name_every_key_path_and_value():
    d = _suwon_dict()
    d["facade"]["cavity_dept_m"] = d["facade"].pop("cavity_depth_m")  # misspelt
    d["louver"]["slat_width_m"] = "five cm"  # string where a number belongs
    d["glazing"]["interior_gap_m"] = -0.012  # negative
    d["site"]["terrain"] = "forest"
    issues = _issues(d)
    assert "facade.cavity_dept_m" in issues and "did you mean 'cavity_depth_m'" in issues[
        "facade.cavity_dept_m"]
    assert "facade.cavity_depth_m" in issues and "missing" in issues["facade.cavity_depth_m"]
    assert "'five cm'" in issues["louver.slat_width_m"]
    assert "-0.012" in issues["glazing.interior_gap_m"]
    assert "'forest'" in issues["site.terrain"]


def test_negative_cavity_depth_and_inconsistent_geometry():
    d = _suwon_dict()
    d["facade"]["cavity_depth_m"] = -0.25
    assert "facade.cavity_depth_m" in _issues(d)
    d["facade"]["cavity_depth_m"] = 0.04  # slat (5 cm) wider than the cavity
    issues = _issues(d)
    assert "louver.slat_width_m" in issues and "wider than the cavity" in issues[
        "louver.slat_width_m"]


def test_cross_field_checks():
    d = _suwon_dict()
    d["parameters"]["h_in"] = {"default": 9.0, "lower": 1.0, "upper": 8.0}
    d["glazing"]["exterior"]["solar_reflectance_front"] = 0.5  # τ 0.6 + ρ 0.5 > 1
    d["louver"]["step_deg"] = 17.0
    issues = _issues(d)
    assert "parameters.h_in.default" in issues
    assert "glazing.exterior.solar_reflectance_front" in issues
    assert "louver.step_deg" in issues


def test_observer_gains_need_one_per_measured_state_within_0_1():
    d = _suwon_dict()
    d["calibration"] = {"measurement_gain": [1, 0.3]}
    issues = _issues(d)
    assert "calibration.measurement_gain" in issues
    assert "[1.0, 0.3]" in issues["calibration.measurement_gain"]
    assert "one gain per measured state" in issues["calibration.measurement_gain"]
    d["calibration"] = {"measurement_gain": [1, 0.3, 0.3, 1, 1.5]}
    assert "1.5" in _issues(d)["calibration.measurement_gain[4]"]
    d["calibration"] = {"measurement_gain": [1, 0.3, 0.3, 1, 1]}
    cfg = panel_from_mapping(d, source="test.yaml")
    assert cfg.calibration.measurement_gain == (1.0, 0.3, 0.3, 1.0, 1.0)



def test_innovation_smoothing_needs_one_time_constant_per_offset_node():
    d = _suwon_dict()
    d["calibration"] = {"innovation_smoothing_s": [300, 1800]}
    issues = _issues(d)
    assert "one time constant per offset node" in issues["calibration.innovation_smoothing_s"]
    d["calibration"] = {"innovation_smoothing_s": [300, 1800, -5, 300]}
    assert "-5" in _issues(d)["calibration.innovation_smoothing_s[2]"]
    d["calibration"] = {"innovation_smoothing_s": [0, 3600, 3600, 0]}
    cfg = panel_from_mapping(d, source="test.yaml")
    assert cfg.calibration.innovation_smoothing_s == (0.0, 3600.0, 3600.0, 0.0)


def test_reading_offsets_need_one_time_constant_per_measured_state():
    d = _suwon_dict()
    d["calibration"] = {"reading_offset_tracking_s": [0, 0, 120, 120]}
    issues = _issues(d)
    assert "[0.0, 0.0, 120.0, 120.0]" in issues["calibration.reading_offset_tracking_s"]
    assert "one time constant per measured state" in \
        issues["calibration.reading_offset_tracking_s"]
    d["calibration"] = {"reading_offset_tracking_s": [0, 0, 0, -1, 120]}
    assert "-1" in _issues(d)["calibration.reading_offset_tracking_s[3]"]
    d["calibration"] = {"reading_offset_memory_s": 0}
    assert "calibration.reading_offset_memory_s" in _issues(d)

def test_booleans_are_not_numbers_and_ints_are_not_strings():
    d = _suwon_dict()
    d["model"]["step_s"] = True
    d["panel"]["id"] = 7
    issues = _issues(d)
    assert "model.step_s" in issues and "panel.id" in issues


def test_duplicate_keys_and_bad_yaml_are_errors(tmp_path: Path):
    text = (PANELS / "suwon-south.yaml").read_text()
    dup = tmp_path / "dup.yaml"
    dup.write_text(text.replace("facade:\n", "facade:\n  width_m: 3.0\n", 1))
    with pytest.raises(ConfigError, match="duplicate key 'width_m'"):
        load_panel(dup)
    broken = tmp_path / "broken.yaml"
    broken.write_text("panel: {id: x\n")
    with pytest.raises(ConfigError, match="invalid YAML"):
        load_panel(broken)


def test_check_config_run_makes_the_checks_of_dsfd_run_in_that_mode(tmp_path: Path):
    """A file that passes ``check-config --run MODE`` starts in that mode, and one that fails
    fails ``dsfd run`` the same way: here the stage budgets do not fit into the cycle, and a
    panel without devices cannot run against hardware."""
    tight = tmp_path / "tight.yaml"
    d = _suwon_dict()
    d.setdefault("daemon", {})["calibrate_budget_s"] = 59.0
    tight.write_text(yaml.safe_dump(d))
    no_devices = PANELS / "suwon-south-no-louver.yaml"

    def dsfd(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "dsfd", *args], capture_output=True,
                              text=True, timeout=120)

    plain = dsfd("check-config", str(tight))
    assert plain.returncode == 0  # the file alone is valid
    checked = dsfd("check-config", "--run", "sim", str(tight))
    assert checked.returncode == 2
    assert "daemon.cycle_period_s" in checked.stderr and "stage budgets" in checked.stderr
    run = dsfd("run", "--config", str(tight), "--plant", "sim", "--dry-run", "--cycles", "1")
    assert run.returncode == 2 and "stage budgets" in run.stderr
    assert dsfd("check-config", "--run", "sim", str(no_devices)).returncode == 0
    hw = dsfd("check-config", "--run", "hardware", str(no_devices))
    assert hw.returncode == 2 and "required to run against hardware" in hw.stderr
    assert dsfd("check-config", "--run", "hardware",
                str(PANELS / "suwon-south.yaml")).returncode == 0


def test_check_config_cli(tmp_path: Path):
    bad = tmp_path / "bad.yaml"
    d = _suwon_dict()
    d["facade"]["cavity_dept_m"] = d["facade"].pop("cavity_depth_m")
    d["louver"]["slat_width_m"] = "wide"
    d["glazing"]["interior_gap_m"] = -1
    bad.write_text(yaml.safe_dump(d))
    ok = subprocess.run([sys.executable, "-m", "dsfd", "check-config", *map(str, SHIPPED)],
                        capture_output=True, text=True)
    assert ok.returncode == 0
    assert all(f"OK {p}" in ok.stdout for p in SHIPPED)
    res = subprocess.run([sys.executable, "-m", "dsfd", "check-config", str(SHIPPED[0]),
                          str(bad)], capture_output=True, text=True)
    assert res.returncode == 2
    for key in ("facade.cavity_dept_m", "louver.slat_width_m", "glazing.interior_gap_m"):
        assert key in res.stderr
    assert f"OK {SHIPPED[0]}" in res.stdout
