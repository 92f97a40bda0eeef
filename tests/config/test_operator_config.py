"""The panel settings of issue 20: the override input in the devices map, the hold time and
the daily reset. Errors name the YAML key path and the bad value."""

from __future__ import annotations

import copy
from typing import Any

import pytest
import yaml

from dsfd.config import ConfigError, panel_from_mapping
from tests.conftest import PANELS


@pytest.fixture(scope="module")
def base() -> dict[str, Any]:
    return yaml.safe_load((PANELS / "suwon-south.yaml").read_text())


def errors(doc: dict[str, Any]) -> list[str]:
    try:
        panel_from_mapping(doc)
    except ConfigError as exc:
        return [str(i) for i in exc.issues]
    return []


def with_input(base: dict[str, Any], entry: int = 0, **override: Any) -> dict[str, Any]:
    doc = copy.deepcopy(base)
    doc["devices"]["entries"][entry]["override_input"] = override
    return doc


def test_an_override_input_loads_and_adds_one_block_to_the_read_budget(base) -> None:
    plain = panel_from_mapping(copy.deepcopy(base)).devices.entries[0]
    cfg = panel_from_mapping(with_input(base, table="discrete_input", address=7, invert=True))
    io = cfg.devices.entries[0]
    assert (io.override_input.table, io.override_input.address, io.override_input.invert) == (
        "discrete_input", 7, True)
    assert io.worst_case_read_s() == pytest.approx(
        plain.worst_case_read_s() + io.timeout_s * (io.retries + 1))


@pytest.mark.parametrize("entry, override, expected", [
    (0, {"table": "relay", "address": 1},
     "devices.entries[0].override_input.table: 'relay': must be one of"),
    (0, {"table": "coil", "address": -1},
     "devices.entries[0].override_input.address: -1: out of range"),
    (0, {"table": "coil"}, "devices.entries[0].override_input.address: <missing>"),
    (0, {"table": "holding", "address": 101},
     "devices.entries[0].override_input.address: 101: holding register 101 is already "
     "actuators[1]"),
    (1, {"table": "coil", "address": 0},
     "devices.entries[1].override_input: '...': a serial_station delivers"),
])
def test_override_input_errors_name_the_key_path(base, entry, override, expected) -> None:
    found = errors(with_input(base, entry, **override))
    assert any(e.startswith(expected) for e in found), found


def test_only_one_override_input_per_panel(base) -> None:
    doc = with_input(base, table="coil", address=0)
    second = copy.deepcopy(doc["devices"]["entries"][0])
    second.update(name="bms", device_id=2, sensors=[], actuators=[])
    doc["devices"]["entries"].append(second)
    found = errors(doc)
    assert any(e.startswith("devices.entries[2].override_input") and "only one" in e
               for e in found), found


@pytest.mark.parametrize("text, expected", [
    ("manual_hold_min: 0", "safety.manual_hold_min: 0.0: out of range: must be >= 1 min"),
    ("manual_reset_local: '25:00'", "safety.manual_reset_local: '25:00': expected a 24-hour"),
    ("manual_reset_local: 'noon'", "safety.manual_reset_local: 'noon': expected a 24-hour"),
    ("manual_reset_local: 22:00", "safety.manual_reset_local: 1320: expected a time in quotes"),
])
def test_hold_settings_are_checked(base, text, expected) -> None:
    doc = copy.deepcopy(base)
    doc["safety"] = yaml.safe_load(text)  # as YAML reads it (22:00 unquoted is 1320)
    found = errors(doc)
    assert any(e.startswith(expected) for e in found), found


def test_hold_settings_default_and_parse(base) -> None:
    cfg = panel_from_mapping(copy.deepcopy(base))
    assert cfg.safety.manual_hold_min == 120.0 and cfg.safety.manual_reset_minute is None
    doc = copy.deepcopy(base)
    doc["safety"] = {"manual_reset_local": "07:30"}
    assert panel_from_mapping(doc).safety.manual_reset_minute == 450
