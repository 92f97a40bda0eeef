"""The one parameter catalogue: the panel file, the calibration and the plant agree with it."""

from __future__ import annotations

import dataclasses

from dsfd.config.calibration import Calibration
from dsfd.config.panel import Parameters
from dsfd.config.parameters import (
    CONVECTIVE_NAMES,
    FIT_NAMES,
    N_PARAMS,
    OFFSET_NAMES,
    PARAMETER_NAMES,
    Param,
)
from dsfd.physics.model import LumpedModel


def test_the_panel_section_has_one_entry_per_parameter_in_catalogue_order():
    assert tuple(f.name for f in dataclasses.fields(Parameters)) == PARAMETER_NAMES
    assert FIT_NAMES == (*PARAMETER_NAMES, *OFFSET_NAMES)
    assert [p.value for p in Param] == list(range(len(FIT_NAMES)))
    assert CONVECTIVE_NAMES == tuple(n for n in PARAMETER_NAMES if n.startswith("h_"))
    assert OFFSET_NAMES == ("q_x1", "q_x2", "q_x3", "q_x4") and N_PARAMS == 9


def test_theta_by_name_is_the_panel_value_of_that_name(suwon):
    theta = LumpedModel(suwon).default_theta()
    for p in Param:
        if p < N_PARAMS:
            assert theta[p] == getattr(suwon.parameters, p.key).default


def test_calibration_fixed_accepts_every_catalogue_name_and_nothing_else():
    assert Calibration(fixed=FIT_NAMES).check() == []
    problems = Calibration(fixed=("h_out", "h_gap")).check()
    assert [(p.key, p.value) for p in problems] == [("fixed", "h_gap")]


def test_identifiability_always_fit_accepts_every_catalogue_name_and_nothing_else():
    assert Calibration(identifiability_always_fit=FIT_NAMES).check() == []
    problems = Calibration(identifiability_always_fit=("f", "hout")).check()
    assert [(p.key, p.value) for p in problems] == [("identifiability_always_fit", "hout")]
