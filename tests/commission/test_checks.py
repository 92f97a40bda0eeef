"""The commissioning plausibility checks (pure), and their orderings against the truth plant.

The orderings are physics claims; the simulated truth plant (an independent model: its own
optics, flows and sensor noise) is the reference they must never contradict on a correct
panel, over two January days and nights in several positions of louver, regime and dampers.
"""

from __future__ import annotations

import math

import pytest

from dsfd.commission.checks import (
    Conditions,
    check_duplicates,
    check_feedback,
    check_louver_range,
    check_night,
    check_order,
    check_scales,
    order_constraints,
    scale_factor,
)
from dsfd.config import load_panel
from dsfd.measured import parse_iso_utc
from dsfd.physics.solar.position import solar_position
from dsfd.sim.daemon_plant import plant_options, simulated_plant
from tests.daemon.harness import SUWON

NIGHT = Conditions(-40.0, 22.0)
#: A heating night, ordered along the heat path (room > x3 > x2 > x4, x5 > x1 >~ outdoors).
NIGHT_VALUES = {"x1_c": 2.6, "x2_c": 9.3, "x3_c": 16.8, "x4_c": 4.4, "x5_c": 5.1,
                "t_room_c": 21.4, "t_out_c": 1.0, "ghi_wm2": -2.0}
WHERE = {f"x{i}_c": f"io input {i - 1}" for i in range(1, 6)}


def test_a_power_of_ten_names_the_scale_and_the_fix() -> None:
    assert scale_factor("t_room_c", 2.14) == 10.0
    assert scale_factor("x3_c", 168.0) == 0.1
    assert scale_factor("pressure_hpa", 101.5) == 10.0  # kPa in an hPa register
    assert scale_factor("t_room_c", 21.4) is None
    found, flagged = check_scales({"t_room_c": 2.14, "x1_c": 2.6}, {"t_room_c": 0.01})
    assert flagged == {"t_room_c"}
    assert "x10 gives 21.4 degC (scale 0.01 -> 0.1)" in found[0].likely
    # Out of range but no power of ten fits: no scale is blamed.
    (odd,), _ = check_scales({"t_room_c": 55.0}, {})
    assert odd.check == "range" and "not a power of ten" in odd.likely


def test_a_correct_night_passes_and_a_swap_is_named() -> None:
    assert check_order(NIGHT_VALUES, order_constraints(NIGHT_VALUES, NIGHT), WHERE) == []
    assert check_night(NIGHT_VALUES, NIGHT) == []
    for a, b in (("x1_c", "x3_c"), ("x2_c", "x3_c"), ("x1_c", "x5_c")):
        swapped = {**NIGHT_VALUES, a: NIGHT_VALUES[b], b: NIGHT_VALUES[a]}
        (f,) = check_order(swapped, order_constraints(swapped, NIGHT), WHERE)
        assert f.check == "swap" and set(f.signals) == {a, b}, f
        assert WHERE[a] in f.likely and WHERE[b] in f.likely


def test_unrepairable_orderings_are_not_blamed_on_one_pair() -> None:
    values = {**NIGHT_VALUES, "x4_c": -10.0}  # the louver 11 K below outdoors: no swap fits
    (f,) = check_order(values, order_constraints(values, NIGHT), WHERE)
    assert f.check == "order" and "x4_c" in f.signals
    assert "no single exchange" in f.likely
    # x4 and x5 both lie between x1 and the room at night: their swap cannot be seen.
    values = {**NIGHT_VALUES, "x4_c": NIGHT_VALUES["x5_c"], "x5_c": NIGHT_VALUES["x4_c"]}
    assert check_order(values, order_constraints(values, NIGHT), WHERE) == []


def test_in_winter_sun_a_louver_swapped_with_the_exterior_pane_is_named() -> None:
    # Clear winter noon: the black louver absorbs most of the sun and heats the cavity air.
    sun = Conditions(30.0, 22.0)
    noon = {"x1_c": 9.0, "x2_c": 24.0, "x3_c": 23.0, "x4_c": 38.0, "x5_c": 27.0,
            "t_room_c": 21.5, "t_out_c": 0.5, "ghi_wm2": 520.0}
    assert check_order(noon, order_constraints(noon, sun), WHERE) == []
    swapped = {**noon, "x1_c": noon["x4_c"], "x4_c": noon["x1_c"]}
    (f,) = check_order(swapped, order_constraints(swapped, sun), WHERE)
    assert f.check == "swap" and set(f.signals) == {"x1_c", "x4_c"}, f
    # Overcast (little irradiance): no sun ordering is claimed.
    dull = {**swapped, "ghi_wm2": 80.0}
    assert order_constraints(dull, sun) == []


def test_irradiance_at_night_and_daytime_are_told_apart() -> None:
    (f,) = check_night({"ghi_wm2": 450.0}, NIGHT)
    assert f.signals == ("ghi_wm2",)
    assert check_night({"ghi_wm2": 450.0}, Conditions(30.0)) == []


def test_copied_registers_and_feedback_sign() -> None:
    series = {"x2_c": [9.3, 9.4, 9.3], "x3_c": [9.3, 9.4, 9.3], "x1_c": [2.6, 2.7, 2.6]}
    (dup,) = check_duplicates(series, WHERE)
    assert set(dup.signals) == {"x2_c", "x3_c"}
    assert check_feedback("phi_deg", 36.0, 35.0, "fb") is None  # within 2 deg
    assert check_feedback("phi_deg", 36.0, -36.0, "fb").check == "sign"
    assert check_feedback("or_pct", 40.0, 4.0, "fb").check == "scale"
    assert check_feedback("afr", 3.0, 4.0, "fb").check == "feedback"
    assert check_feedback("phi_deg", 0.0, 0.0, "fb") is None


@pytest.mark.slow
@pytest.mark.parametrize("command", [
    {"phi_deg": 0.0, "afr": 10, "or_pct": 0.0},     # closed cavity
    {"phi_deg": 0.0, "afr": 9, "or_pct": 50.0},     # room air through the cavity
    {"phi_deg": -54.0, "afr": 3, "or_pct": 40.0},   # outdoor air through the cavity
])
def test_the_orderings_hold_on_the_truth_plant(command: dict[str, float]) -> None:
    cfg = load_panel(SUWON)
    hours = 40
    plant = simulated_plant(cfg, start_s=parse_iso_utc("2022-01-01T15:00:00Z"),
                            cycles=hours * 60 + 10, options=plant_options("lumped")).plant
    plant.apply(command)
    checked = {"night": 0, "sun": 0}
    for quarter in range(4 * hours):
        plant.advance(900.0)
        if quarter < 8:  # two hours to forget the initial state
            continue
        values = {k: v for k, v in plant.read_sensors().items()
                  if isinstance(v, float) and math.isfinite(v)}
        elevation = float(solar_position(plant.time_s, cfg.site.latitude_deg,
                                         cfg.site.longitude_deg).elevation_deg)
        cond = Conditions(elevation, cfg.room.t_in_c)
        constraints = order_constraints(values, cond)
        assert check_order(values, constraints, WHERE) == [], (elevation, values)
        assert check_night(values, cond) == []
        names = {c.hi for c in constraints}
        checked["night"] += "x3_c" in names
        checked["sun"] += "x4_c" in names and not cond.night
    assert checked["night"] >= 20 and checked["sun"] >= 10, checked  # both were exercised


def test_a_louver_outside_its_mechanical_range_at_the_mirror_angle_is_an_inverted_sign(
) -> None:
    # A louver that only tilts one way (0..90 deg) read at -36 deg: its mirror fits.
    assert check_louver_range(-36.0, 0.0, 90.0, "io holding 100").check == "sign"
    assert check_louver_range(36.0, 0.0, 90.0, "io holding 100") is None
    assert check_louver_range(-36.0, -90.0, 90.0, "io holding 100") is None
    assert check_louver_range(-72.0, -30.0, 60.0, "io holding 100").check == "range"
