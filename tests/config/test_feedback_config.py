"""An actuator's optional position feedback register (read by ``dsfd commission``): it loads,
and its errors name the YAML key path and the bad value."""

from __future__ import annotations

import copy
from typing import Any

import pytest
import yaml

from dsfd.config import panel_from_mapping
from tests.config.test_operator_config import errors
from tests.conftest import PANELS


@pytest.fixture(scope="module")
def base() -> dict[str, Any]:
    return yaml.safe_load((PANELS / "suwon-south.yaml").read_text())


def with_feedback(base: dict[str, Any], **feedback: Any) -> dict[str, Any]:
    doc = copy.deepcopy(base)
    doc["devices"]["entries"][0]["actuators"][0]["feedback"] = feedback
    return doc


def test_a_feedback_register_loads_as_a_point_named_after_its_actuator(base) -> None:
    cfg = panel_from_mapping(with_feedback(base, address=10, scale=0.1))
    io = cfg.devices.entries[0]
    (point,) = io.feedback_points()
    assert (point.name, point.table, point.address, point.data_type, point.scale) == (
        "phi_deg", "input", 10, "int16", 0.1)
    assert panel_from_mapping(copy.deepcopy(base)).devices.entries[0].feedback_points() == ()


@pytest.mark.parametrize("feedback, expected", [
    ({"address": 3}, "devices.entries[0].actuators[0].feedback.address: 3: input registers "
                     "3..3 overlap sensors[3]"),
    ({"address": 10, "table": "coil"},
     "devices.entries[0].actuators[0].feedback.table: 'coil': must be one of"),
    ({"address": 10, "scale": 0}, "devices.entries[0].actuators[0].feedback.scale: 0"),
    ({"table": "input"}, "devices.entries[0].actuators[0].feedback.address: <missing>"),
    ({"address": 10, "sign": -1}, "devices.entries[0].actuators[0].feedback.sign"),
])
def test_feedback_errors_name_the_key_path(base, feedback, expected) -> None:
    found = errors(with_feedback(base, **feedback))
    assert any(e.startswith(expected) for e in found), found
