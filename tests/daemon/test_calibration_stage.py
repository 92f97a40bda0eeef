"""The daemon's calibration stage when its state file or the database fails it: control goes
on with a usable θ̂, and the event says what happened and where."""

from __future__ import annotations

import dataclasses
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from dsfd.daemon.calibration import CalibrationStage
from dsfd.estimation.calibration import UpdateReport
from dsfd.estimation.params import ParameterSpace
from dsfd.physics.model import LumpedModel


def test_an_unusable_state_file_that_cannot_be_moved_nor_replaced_by_the_history(
        suwon, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    state_file = tmp_path / "calibration.json"
    state_file.write_text("[]")  # JSON, but not a calibration state

    def refuse(path: Path) -> Path:
        raise PermissionError(13, "Permission denied", str(path))

    def broken_history() -> list:
        raise sqlite3.OperationalError("disk I/O error")

    monkeypatch.setattr("dsfd.daemon.calibration.move_aside", refuse)
    stage = CalibrationStage(suwon, LumpedModel(suwon), state_dir=tmp_path,
                             history=broken_history)
    message = stage.resume_message
    assert stage.origin == "prior"
    assert np.array_equal(stage.state.theta, ParameterSpace.from_panel(suwon).default)
    assert str(state_file) in message and "could not be moved aside (Permission denied)" in message
    assert "the parameter history could not be read (disk I/O error)" in message
    assert message.endswith("starting from the priors")
    assert stage.events == [("warning", "calibration_recovered", message)]
    assert state_file.read_text() == "[]"  # left where it was


def test_an_update_that_cannot_be_saved_is_used_and_reported(suwon, tmp_path: Path) -> None:
    stage = CalibrationStage(suwon, LumpedModel(suwon), state_dir=tmp_path)
    assert stage.origin == "prior" and not stage.events
    (tmp_path / "calibration.json").mkdir()  # from now on the file cannot be replaced
    updated = dataclasses.replace(stage.state, updates=stage.state.updates + 1)
    outcome = stage.accept(UpdateReport(updated, None), now_s=0.0)
    assert outcome.updated and stage.state.updates == updated.updates  # in use all the same
    ((level, kind, message),) = stage.events
    assert (level, kind) == ("error", "calibration_not_saved")
    assert str(tmp_path / "calibration.json") in message
    assert "a restart would start from the previous file" in message
