"""The BACnet device's pure parts: priority arrays to operator requests, the checks of a
written value, and a cycle's state message to point values and fault flags."""

from __future__ import annotations

import pytest

from dsfd.config import load_panel
from dsfd.daemon.commands import validate_command
from dsfd.integrations.bacnet.commands import (
    BacnetWriteError,
    PriorityArrays,
    check_value,
    objective_request,
)
from dsfd.integrations.bacnet.points import point_values, points_for
from tests.conftest import PANELS

CFG = load_panel(PANELS / "suwon-south.yaml")


def test_the_highest_active_priority_is_in_force_and_relinquishing_it_resumes():
    arrays = PriorityArrays()
    assert arrays.request(until_relinquished=False) == ({"command": "resume"}, "")
    assert arrays.write("louver", 10, 54.0, "a priority 10") is True
    assert arrays.write("louver", 8, 36.0, "b priority 8") is True
    assert arrays.write("louver", 12, 72.0, "c priority 12") is False  # below 8: no change
    assert arrays.write("regime", 9, 7, "c priority 9") is True
    request, who = arrays.request(until_relinquished=False)
    assert request == {"command": "override", "louver_deg": 36.0, "regime": 7}
    assert who == "b priority 8"  # the writer of the highest priority in force
    assert arrays.write("louver", 10, None, "a priority 10") is False  # not the highest
    assert arrays.write("louver", 8, None, "b priority 8") is True  # 12 takes over
    assert arrays.request(until_relinquished=False)[0]["louver_deg"] == 72.0
    arrays.write("louver", 12, None, "")
    assert arrays.write("regime", 9, None, "") is True
    assert arrays.request(until_relinquished=False) == ({"command": "resume"}, "")
    arrays.write("damper", 5, 40.0, "")
    assert arrays.clear() is True and arrays.clear() is False


def test_a_hold_until_relinquished_lasts_the_longest_operator_hold():
    arrays = PriorityArrays()
    arrays.write("damper", 8, 40.0, "x")
    request, _ = arrays.request(until_relinquished=True)
    assert validate_command(CFG, request).hold_s == 7 * 86400.0  # a week


@pytest.mark.parametrize(("key", "value", "why"), [
    ("louver", 37.0, "grid"), ("louver", 108.0, "limits"), ("damper", 101.0, "outside"),
    ("regime", 11, "1..10"), ("louver", float("inf"), "finite")])
def test_a_value_that_does_not_fit_the_panel_is_value_out_of_range(key, value, why):
    with pytest.raises(BacnetWriteError) as exc:
        check_value(CFG, key, value)
    assert exc.value.error_code == "valueOutOfRange" and why in exc.value.reason


def test_good_values_and_objective_states():
    assert check_value(CFG, "louver", 36.0) == 36.0
    assert check_value(CFG, "regime", 7) == 7
    assert objective_request(2) == {"command": "mode", "mode": "cooling"}
    with pytest.raises(BacnetWriteError):
        objective_request(4)


def test_a_flagged_signal_sets_its_fault_flag_and_keeps_no_value():
    message = {
        "cycle": 12, "measured": {"x1_c": None, "x2_c": 20.5, "t_out_c": 1.0},
        "flagged": {"x1_c": "stuck"}, "command": {"louver_deg": 36.0, "regime": 7,
                                                  "damper_pct": 40.0},
        "write": "failed", "fault": True, "objective_mode": "auto", "set_by": "manual",
        "hold": True, "hold_source": "detected", "hold_by": None,
        "heat_w": {}, "decision_ms": None, "calibration_age_s": None}
    values = point_values(points_for(CFG), message)
    assert (values["x1"].value, values["x1"].fault) == (None, True)
    assert (values["x2"].value, values["x2"].fault) == (20.5, False)
    assert values["louver"].fault is True  # the write failed
    assert (values["fault"].value, values["objective"].value) == (True, 3)
    assert values["set_by"].value == "detected hold"
    assert (values["cycle"].value, values["cycle"].fault) == (12.0, False)
