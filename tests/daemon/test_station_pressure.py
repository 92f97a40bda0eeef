"""The station's barometer reaches the model: the air density of every step follows it.

Without a barometer the daemon models the standard atmosphere at the site's elevation
(docs/model.md#inputs). A sea-level default on a record from Golden CO (1.8 km, 823 hPa)
makes the air 23 % too dense, which the self-calibration absorbs into wrong parameters.
"""

from __future__ import annotations

import dataclasses

import pytest

from dsfd.config import load_panel
from dsfd.daemon.weather import measured_weather
from dsfd.drivers.base import Reading, Sample
from dsfd.physics.boundary import standard_pressure_pa
from dsfd.physics.constants import STANDARD_PRESSURE_PA
from tests.daemon.harness import ROOT

PANEL = ROOT / "config" / "panels" / "suwon-south.yaml"


def _sample(**values: float) -> Sample:
    return Sample(1_641_081_600.0, {k: Reading.good(v, "station") for k, v in values.items()})


def test_a_good_pressure_reading_sets_the_air_of_the_step():
    cfg = load_panel(PANEL)
    base = dict(t_out_c=5.0, ghi_wm2=400.0, wind_speed_ms=2.0, wind_dir_deg=180.0,
                t_room_c=21.0)
    high = measured_weather(cfg, _sample(**base, pressure_hpa=823.4))
    assert high.inputs.pressure_pa[0] == 82340.0
    assert high.forcing.p_atm_pa[0] == 82340.0
    # no barometer (or a flagged one): the standard atmosphere at the site's elevation
    at_sea = dataclasses.replace(cfg, site=dataclasses.replace(cfg.site, elevation_m=0.0))
    assert measured_weather(at_sea, _sample(**base)).forcing.p_atm_pa[0] == STANDARD_PRESSURE_PA
    golden = dataclasses.replace(cfg, site=dataclasses.replace(cfg.site, elevation_m=1829.0))
    assert measured_weather(golden, _sample(**base)).forcing.p_atm_pa[0] == pytest.approx(
        81_200.0, rel=2e-3)


@pytest.mark.parametrize(("elevation_m", "table_pa"), [(0.0, 101_325.0), (500.0, 95_461.0),
                                                      (1000.0, 89_876.0), (2000.0, 79_501.0)])
def test_standard_pressure_follows_the_standard_atmosphere_table(elevation_m, table_pa):
    # U.S. Standard Atmosphere 1976, Table I (geopotential altitude): the formula is the same
    # troposphere, so it must reproduce the table to its rounding.
    assert standard_pressure_pa(elevation_m) == pytest.approx(table_pa, rel=5e-4)
