"""Calibration state and parameters files: round trip, atomic write, validation, fallback."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from dsfd.config.parameters import N_FIT, N_PARAMS
from dsfd.estimation.params import FIT_NAMES, ParameterSpace
from dsfd.estimation.state import CalibrationState
from dsfd.storage.calibration_file import (
    CalibrationFileError,
    load_state,
    load_state_or_prior,
    read_params,
    save_state,
    write_params,
)
from tests.conftest import DATA


@pytest.fixture
def space(suwon):
    return ParameterSpace.from_panel(suwon)


@pytest.fixture
def state(space):
    rng = np.random.default_rng(0)
    theta = space.default * np.exp(0.1 * rng.standard_normal(space.default.size))
    theta[N_PARAMS:] = [3.0, -1.5, 0.5, 0.0]  # q_x1..q_x4
    a = 0.01 * rng.standard_normal((N_FIT, N_FIT))
    return CalibrationState(panel_id="suwon-south", theta=space.clip(theta),
                            cov_z=a @ a.T + 1e-4 * np.eye(N_FIT), prior_theta=space.default,
                            prior_sd_z=space.prior_sd, last_update_s=1.6409e9, updates=42,
                            failed_updates=1, residuals_last=5208, cost_last=123.4,
                            free_last=("h_out", "f"))


def test_state_round_trips_through_the_file(tmp_path, space, state):
    path = tmp_path / "calibration.json"
    save_state(path, state, space)
    back = load_state(path, space=space, panel_id="suwon-south")
    assert np.allclose(back.theta, state.theta, rtol=0, atol=0)
    assert np.allclose(back.cov_z, state.cov_z)
    assert (back.last_update_s, back.updates, back.failed_updates, back.free_last) == (
        state.last_update_s, 42, 1, ("h_out", "f"))
    assert [p.name for p in tmp_path.iterdir()] == ["calibration.json"]  # no temp left
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 2 and list(doc["theta"]) == list(FIT_NAMES)
    assert "cov_z" in doc and "prior_sd_z" in doc and "cov_phi" not in doc
    assert set(doc["std_error"]) == set(FIT_NAMES)


def test_a_version_1_file_from_before_the_rename_still_loads(space):
    """tests/data/calibration_state_v1.json was written by dsfd before the fit coordinates were
    renamed φ → z (keys ``cov_phi``, ``prior_sd_phi``)."""
    path = DATA / "calibration_state_v1.json"
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 1 and "cov_phi" in doc and "cov_z" not in doc
    st = load_state(path, space=space, panel_id="suwon-south")
    assert np.array_equal(st.theta, [doc["theta"][k] for k in FIT_NAMES])
    assert np.array_equal(st.cov_z, np.array(doc["cov_phi"]))  # symmetric already
    assert np.array_equal(st.prior_sd_z, [doc["prior_sd_phi"][k] for k in FIT_NAMES])
    assert (st.updates, st.free_last) == (7, ("h_out", "h_in"))


def test_a_bad_key_of_a_version_1_file_is_named_as_the_file_names_it(tmp_path, space):
    doc = json.loads((DATA / "calibration_state_v1.json").read_text())
    doc["cov_phi"] = [[1.0, 2.0]]
    path = tmp_path / "calibration.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(CalibrationFileError, match="key 'cov_phi'"):
        load_state(path, space=space, panel_id="suwon-south")


def test_a_file_of_a_newer_dsfd_is_refused_naming_the_versions(tmp_path, space, state):
    doc = state.to_dict(space)
    doc["schema_version"] = 3
    path = tmp_path / "calibration.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(CalibrationFileError, match=r"3 is not supported \(this dsfd reads 1, 2\)"):
        load_state(path, space=space, panel_id="suwon-south")


def test_save_replaces_atomically(tmp_path, space, state):
    path = tmp_path / "calibration.json"
    save_state(path, state, space)
    save_state(path, CalibrationState.initial("suwon-south", space), space)
    assert load_state(path, space=space, panel_id="suwon-south").updates == 0


def test_a_write_interrupted_before_the_rename_leaves_the_old_file(tmp_path, space, state,
                                                                   monkeypatch):
    """A crash while saving keeps the previous state readable and leaves no temp file."""
    path = tmp_path / "calibration.json"
    save_state(path, state, space)
    before = path.read_bytes()

    def crash(src, dst):
        assert Path(src).read_text().startswith("{")  # the new content was fully written
        raise OSError("power cut")

    monkeypatch.setattr("os.replace", crash)
    with pytest.raises(OSError, match="power cut"):
        save_state(path, CalibrationState.initial("suwon-south", space), space)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert load_state(path, space=space, panel_id="suwon-south").updates == 42
    assert [p.name for p in tmp_path.iterdir()] == ["calibration.json"]


def test_missing_file_starts_from_the_priors(tmp_path, space):
    st, msg = load_state_or_prior(tmp_path / "none.json", space=space, panel_id="suwon-south")
    assert np.array_equal(st.theta, space.default)
    assert "no calibration state" in msg


@pytest.mark.parametrize("corrupt, key", [
    ("{ not json", "line 1"),
    ('{"schema": "other"}', "'schema'"),
    (None, "'theta.h_out'"),
    (None, "'cov_z'"),
    (None, "'panel_id'"),
])
def test_corrupt_file_falls_back_to_the_priors_with_a_clear_message(tmp_path, space, state,
                                                                    corrupt, key):
    path = tmp_path / "calibration.json"
    if corrupt is None:
        doc = state.to_dict(space)
        if key == "'theta.h_out'":
            doc["theta"]["h_out"] = 1e6  # outside the bounds
        elif key == "'cov_z'":
            doc["cov_z"] = [[1.0, 2.0]]
        else:
            doc["panel_id"] = "another-panel"
        corrupt = json.dumps(doc)
    path.write_text(corrupt)
    st, msg = load_state_or_prior(path, space=space, panel_id="suwon-south")
    assert np.array_equal(st.theta, space.default) and st.updates == 0
    assert "starting from the panel priors" in msg
    assert str(path) in msg and key in msg


def test_parameters_file_round_trip_and_errors(tmp_path, space, state):
    path = tmp_path / "params.yaml"
    write_params(path, state, space, provenance={"data": "x.csv"})
    theta = read_params(path, space=space, panel_id="suwon-south")
    assert np.allclose(theta, state.theta, rtol=1e-5)
    text = path.read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("h_in:", "h_inn:", 1))
    with pytest.raises(CalibrationFileError, match=r"bad\.yaml.*'parameters\.h_inn'"):
        read_params(bad, space=space)
    bad.write_text(text.replace("  f: ", "  f: -", 1))
    with pytest.raises(CalibrationFileError, match=r"bad\.yaml.*'parameters\.f'.*bounds"):
        read_params(bad, space=space)
    with pytest.raises(CalibrationFileError, match="'panel_id'"):
        read_params(path, space=space, panel_id="aalborg-cube")
