"""Measured rows → model steps: time conventions, missing columns, façade-plane irradiance."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dsfd.estimation.stepdata import step_data, weather_of_steps
from dsfd.measured import MeasuredData, MeasuredDataError
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import facade_forcing


def _table(n: int = 6, step_s: float = 60.0, **extra) -> MeasuredData:
    t = 1.6409e9 + step_s * np.arange(n + 1)
    cols = {
        "afr": np.full(n + 1, 1.0),
        "phi_deg": np.zeros(n + 1),
        "or_pct": np.full(n + 1, 100.0),
        "x1_c": np.linspace(5.0, 6.0, n + 1),
        "t_out_c": np.arange(n + 1, dtype=float),  # row j carries the interval ending at j
        "ghi_wm2": np.full(n + 1, 100.0),
    }
    cols.update(extra)
    return MeasuredData(t, cols, "table.csv")


def test_step_k_takes_the_weather_of_row_k_plus_1_at_its_midpoint(suwon):
    data = _table()
    w = weather_of_steps(data, room=suwon.room, facade=suwon.facade)
    assert np.allclose(w.t_out_k - T_ZERO, np.arange(1, 7))
    assert np.allclose(w.time_s, data.time_s[:-1] + 30.0)


def test_room_temperature_of_a_step_is_the_mean_of_its_rows(suwon):
    data = _table(t_room_c=np.array([20.0, 22.0, 22.0, 22.0, 22.0, 22.0, 24.0]))
    w = weather_of_steps(data, room=suwon.room, facade=suwon.facade)
    assert w.t_in_k[0] - T_ZERO == pytest.approx(21.0)
    assert w.t_in_k[-1] - T_ZERO == pytest.approx(23.0)


def test_missing_optional_columns_are_assumed_and_noted(suwon):
    data = _table()
    steps = step_data(suwon, data)
    assert steps.present == ("x1",)
    assert any("wind_speed_ms" in n for n in steps.notes)
    assert any("t_room_c" in n for n in steps.notes)
    assert np.all(np.isnan(steps.y_k[:, 1:]))


def test_missing_regime_column_names_the_file_and_column(suwon):
    data = _table()
    cols = {k: v for k, v in data.columns.items() if k != "afr"}
    with pytest.raises(MeasuredDataError, match=r"table\.csv.*'afr'"):
        step_data(suwon, MeasuredData(data.time_s, cols, "table.csv"))


def test_regime_the_panel_lacks_names_the_row(suwon):
    from dsfd.config import load_panel
    from tests.conftest import PANELS

    cube = load_panel(PANELS / "aalborg-cube.yaml")
    with pytest.raises(MeasuredDataError, match=r"data row 1 .*'afr'.*regime 1"):
        step_data(cube, _table())


def test_a_gap_in_the_record_invalidates_the_step(suwon):
    data = _table()
    t = data.time_s.copy()
    t[4:] += 600.0
    steps = step_data(suwon, MeasuredData(t, data.columns, "gap.csv"))
    assert steps.valid.tolist() == [True, True, True, False, True, True]


def test_facade_plane_irradiance_replaces_the_transposition(suwon):
    data = _table()
    w = weather_of_steps(data, room=suwon.room, facade=suwon.facade)
    noon = np.full(1, 1.6409e9 + 3.5 * 3600)  # ~12:30 local solar time in Suwon
    base = w._replace(time_s=noon, **{k: getattr(w, k)[:1] for k in w._fields
                                     if k not in ("time_s", "poa_global_wm2",
                                                  "poa_diffuse_wm2")})
    plain = facade_forcing(suwon, base)
    poa = facade_forcing(suwon, base._replace(poa_global_wm2=np.array([500.0]),
                                              poa_diffuse_wm2=np.array([120.0])))
    assert poa.beam_wm2[0] == pytest.approx(380.0)
    assert poa.diffuse_wm2[0] == pytest.approx(120.0)
    assert plain.beam_wm2[0] != pytest.approx(380.0)
    missing = facade_forcing(suwon, base._replace(poa_global_wm2=np.array([np.nan]),
                                                  poa_diffuse_wm2=np.array([np.nan])))
    assert missing.beam_wm2[0] == pytest.approx(plain.beam_wm2[0])


def test_facade_plane_irradiance_with_the_sun_behind_the_facade_is_diffuse(suwon):
    north = dataclasses.replace(suwon, facade=dataclasses.replace(suwon.facade,
                                                                  azimuth_deg=0.0))
    data = _table()
    w = weather_of_steps(data, room=north.room, facade=north.facade)
    noon = np.full(1, 1.6409e9 + 3.5 * 3600)
    base = w._replace(time_s=noon, **{k: getattr(w, k)[:1] for k in w._fields
                                     if k not in ("time_s", "poa_global_wm2",
                                                  "poa_diffuse_wm2")})
    f = facade_forcing(north, base._replace(poa_global_wm2=np.array([200.0]),
                                            poa_diffuse_wm2=np.array([150.0])))
    assert f.beam_wm2[0] == 0.0
    assert f.diffuse_wm2[0] == pytest.approx(200.0)


def test_poa_columns_feed_the_steps(suwon):
    data = _table(poa_wm2=np.full(7, 300.0), poa_diffuse_wm2=np.full(7, 100.0))
    cols = {k: v for k, v in data.columns.items() if k != "ghi_wm2"}
    steps = step_data(suwon, MeasuredData(data.time_s, cols, "poa.csv"))
    assert np.all(np.isfinite(steps.inputs.sources))
    assert np.all(steps.inputs.sources[:, 0] > 0.0)
