"""The one weather path: measured or forecast weather → the model's weather inputs."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.physics.boundary import (
    DEW_POINT_DEPRESSION_K,
    STANDARD_PRESSURE_PA,
    dew_point_k,
    model_weather,
    sky_dew_point_k,
)
from dsfd.physics.constants import T_ZERO


def test_unmeasured_channels_get_the_stated_defaults(suwon):
    w = model_weather(time_s=[0.0, 60.0], t_out_c=[-2.0, -1.0], ghi_wm2=[100.0, 200.0],
                      room=suwon.room, facade_azimuth_deg=suwon.facade.azimuth_deg)
    np.testing.assert_array_equal(w.t_out_k, [-2.0 + T_ZERO, -1.0 + T_ZERO])
    np.testing.assert_array_equal(w.wind_speed_ms, [0.0, 0.0])  # calm
    np.testing.assert_array_equal(w.wind_dir_deg, [suwon.facade.azimuth_deg] * 2)  # normal
    np.testing.assert_array_equal(w.pressure_pa, [101325.0, 101325.0])  # standard atmosphere
    assert STANDARD_PRESSURE_PA == 101325.0  # ISO 2533
    assert np.isnan(w.dni_wm2).all() and np.isnan(w.dhi_wm2).all()  # decomposed downstream
    assert np.isnan(w.t_dew_k).all()
    np.testing.assert_array_equal(w.t_in_k, [suwon.room.t_in_c + T_ZERO] * 2)
    assert suwon.room.t_mrt_c is None
    np.testing.assert_array_equal(w.t_mrt_k, w.t_in_k)  # radiant = air when not configured
    assert w.poa_global_wm2 is None and w.poa_diffuse_wm2 is None


def test_single_missing_values_are_filled_and_measured_ones_kept(suwon):
    room = dataclasses.replace(suwon.room, t_mrt_c=19.0)
    w = model_weather(time_s=[0.0, 60.0, 120.0], t_out_c=5.0, ghi_wm2=[-3.0, np.nan, 50.0],
                      wind_speed_ms=[np.nan, -0.2, 3.0], wind_dir_deg=[90.0, np.nan, 270.0],
                      pressure_pa=[np.nan, 99000.0, np.inf], t_in_c=[20.0, 21.0, 22.0],
                      room=room, facade_azimuth_deg=180.0)
    np.testing.assert_array_equal(w.t_out_k, [5.0 + T_ZERO] * 3)  # a scalar is repeated
    np.testing.assert_array_equal(w.wind_speed_ms, [0.0, 0.0, 3.0])
    np.testing.assert_array_equal(w.wind_dir_deg, [90.0, 180.0, 270.0])
    np.testing.assert_array_equal(w.pressure_pa, [101325.0, 99000.0, 101325.0])
    np.testing.assert_array_equal(w.ghi_wm2[[0, 2]], [0.0, 50.0])  # instrument offset clipped
    assert np.isnan(w.ghi_wm2[1])
    np.testing.assert_array_equal(w.t_in_k, np.array([20.0, 21.0, 22.0]) + T_ZERO)
    np.testing.assert_array_equal(w.t_mrt_k, [19.0 + T_ZERO] * 3)


def test_weather_files_keep_their_wind_as_recorded(suwon):
    w = model_weather(time_s=[0.0], t_out_c=[0.0], ghi_wm2=[0.0], wind_speed_ms=[-0.07],
                      room=suwon.room, facade_azimuth_deg=180.0, clip_negative=False)
    assert w.wind_speed_ms[0] == -0.07


@pytest.mark.parametrize(("t_c", "rh_pct", "expected_c"), [
    # Psychrometric tables (e.g. ASHRAE Handbook—Fundamentals, ch. 1): 20 °C at 50 % has a
    # dew point of 9.3 °C; 30 °C at 70 % of 23.9 °C; 0 °C at 80 % of −3.0 °C (over water).
    (20.0, 50.0, 9.3), (30.0, 70.0, 23.9), (0.0, 80.0, -3.0),
])
def test_dew_point_matches_psychrometric_tables(t_c, rh_pct, expected_c):
    assert dew_point_k(t_c, rh_pct) - T_ZERO == pytest.approx(expected_c, abs=0.1)


def test_saturated_air_is_at_its_dew_point_and_unknown_humidity_falls_back():
    t = np.array([-10.0, 0.0, 25.0])
    np.testing.assert_allclose(dew_point_k(t, 100.0), t + T_ZERO, atol=1e-9)
    assert np.isnan(dew_point_k(10.0, np.nan))
    w = model_weather(time_s=[0.0, 1.0], t_out_c=[10.0, 10.0], ghi_wm2=None,
                      rh_pct=[np.nan, 100.0], room=_Room(), facade_azimuth_deg=0.0)
    np.testing.assert_allclose(sky_dew_point_k(w),
                               [10.0 + T_ZERO - DEW_POINT_DEPRESSION_K, 10.0 + T_ZERO])


@dataclasses.dataclass(frozen=True)
class _Room:
    t_in_c: float = 21.0
    t_mrt_c: float | None = None
