"""The Plant API the daemon and the calibration use."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.config.parameters import N_PARAMS, Param
from dsfd.physics.constants import T_ZERO
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.config import PlantOptions, TrueParameters, drift_factors
from dsfd.sim.plant.plant import Plant
from dsfd.sim.replay import weather_inputs
from tests.sim.conftest import HOUR, day_start


@pytest.fixture(scope="module")
def small(suwon, rmis):
    plant = Plant(suwon, PlantOptions(n_segments=4), seed=11, weather_series=rmis)
    plant.reset(day_start(rmis, 1) + 10 * HOUR, command=Command(18.0, 3, 100.0))
    return plant


def test_true_parameters_are_seeded_draws_in_the_e16_ranges(suwon, rmis_raw):
    draws = [Plant(suwon, seed=s, weather_series=rmis_raw).params for s in range(30)]
    m = np.array([p.h_multipliers for p in draws])
    f = np.array([p.f for p in draws])
    assert m.min() >= 0.5 and m.max() <= 2.0 and f.min() >= 20.0 and f.max() <= 2000.0
    assert np.log(f).std() > 0.8  # spread over the log range, not a constant
    assert Plant(suwon, seed=3, weather_series=rmis_raw).params == draws[3]
    p = draws[0]
    theta = p.lumped_theta(suwon)
    assert theta.shape == (N_PARAMS,) and theta[Param.F] == p.f
    assert theta[Param.H_OUT] == pytest.approx(p.h_multipliers[Param.H_OUT]
                                               * suwon.parameters.h_out.default)


def test_state_flows_and_label(small):
    small.advance(600.0)
    st = small.true_state()
    for kind in ("g1", "g2", "g3", "lv", "ao", "ai", "g6"):
        assert st.segments_k[kind].shape == (4,)
        assert np.all((st.segments_k[kind] > T_ZERO - 40) & (st.segments_k[kind] < T_ZERO + 90))
    assert np.isfinite(st.plenums_k).all()
    m = st.m_dot_kgs
    assert abs(m.sum()) < 1e-9 and m[2] == m[3] == 0.0  # regime 3: EB + ET only
    assert st.label in (3, 4)
    assert (st.label == 3) == (m[0] > 0)
    area = small.cfg.facade.cavity_depth_m * small.cfg.facade.width_m
    assert np.sign(st.v_cav_ms) == np.sign(m[0])
    assert abs(m[0]) / (1.4 * area) < abs(st.v_cav_ms) < abs(m[0]) / (0.7 * area)
    assert np.isfinite(st.t_outlet_k)
    cols = st.truth_columns()
    assert cols["truth_label"] == st.label and "truth_x6_c" in cols


def test_advance_in_parts_equals_one_advance(suwon, rmis):
    def run(parts):
        plant = Plant(suwon, PlantOptions(n_segments=3), seed=2, weather_series=rmis)
        plant.reset(day_start(rmis, 2) + 12 * HOUR, command=Command(0.0, 1, 100.0))
        for p in parts:
            plant.advance(p)
        return plant.true_state().x_mid_k, plant.time_s

    x_a, t_a = run([150.0])
    x_b, t_b = run([20.0, 70.0, 60.0])
    assert t_a == t_b
    np.testing.assert_allclose(x_a, x_b, atol=0.01)  # within the solver tolerance


def test_perfect_forecast_is_the_lumped_weather(small, suwon):
    fc = small.perfect_forecast(15)
    ref = weather_inputs(small.series, suwon, start_s=small.time_s, n_steps=15)
    assert fc.time_s.shape == (15,)
    np.testing.assert_allclose(fc.t_out_k, ref.t_out_k)
    np.testing.assert_allclose(fc.ghi_wm2, ref.ghi_wm2)
    assert fc.time_s[0] == pytest.approx(small.time_s + 30.0)


def test_weather_beyond_the_record_is_an_error(suwon, rmis):
    plant = Plant(suwon, PlantOptions(n_segments=2), seed=1, weather_series=rmis)
    plant.reset(rmis.coverage_s[1] - 90.0)
    with pytest.raises(ValueError, match="outside the weather"):
        plant.advance(600.0)


def test_lumped_optics_zoh_matches_fine_forcing_in_magnitude(suwon, rmis):
    """Fine optics (Perez, M = 10, thickness, sky/ground) differ from the lumped ones."""
    start = day_start(rmis, 1) + 11 * HOUR
    out = {}
    for optics in ("lumped", "fine"):
        plant = Plant(suwon, PlantOptions(n_segments=1, optics=optics), seed=1,
                      weather_series=rmis)
        plant.reset(start, command=Command(0.0, 10, 100.0))
        table, row = plant.tables.step(0)
        out[optics] = table.src_a[row][:, :4]  # absorbed; then transmitted and Q_DA
        assert table.src_a.shape[-1] == 6
    lumped, fine = out["lumped"], out["fine"]
    assert lumped.shape == fine.shape == (11, 4)
    rel = np.abs(fine.sum(axis=1) - lumped.sum(axis=1)) / lumped.sum(axis=1)
    assert 1e-3 < rel.max() < 0.3


def test_drift_and_options(suwon, rmis):
    opt = PlantOptions(n_segments=2, drift_reflectance_per_day=0.02, drift_h_name="h_ca1",
                       drift_h_per_day=-0.1)
    d_rho, factors = drift_factors(opt, 2 * 86400.0)
    assert d_rho == pytest.approx(0.04)
    assert factors[Param.H_CA1] == pytest.approx(0.8) and factors.sum() == 5.8
    plant = Plant(suwon, opt, seed=1, weather_series=rmis,
                  params=TrueParameters.nominal(suwon))
    plant.reset(day_start(rmis, 1) + 11 * HOUR)
    plant.advance(300.0)
    assert np.isfinite(plant.true_state().x_mid_k).all()
    with pytest.raises(ValueError):
        PlantOptions(damper_model="butterfly")
    with pytest.raises(ValueError):
        PlantOptions(drift_h_name="h_x")


def test_an_unphysical_trial_state_is_rejected_not_raised(suwon, rmis):
    """Radau's Newton iteration tried cavity air at −300 K in a dry run (all dampers open):
    the one-node flow solver then took the square root of a negative density and the plant
    failed. The right-hand side answers such a state with NaN, which makes the solver reject
    the iterate and shorten the step."""
    plant = Plant(suwon, PlantOptions(n_segments=3), seed=1, weather_series=rmis)
    plant.reset(day_start(rmis, 1) + 11 * HOUR, command=Command(0.0, 9, 100.0))
    plant.advance(60.0)
    model = plant.model
    y = plant._y.copy()
    y[:model.nn] = -300.0
    assert np.isnan(model.rhs(plant.time_s, y)).any()
    plant.advance(60.0)  # and the plant goes on from its real state
    assert np.isfinite(plant.true_state().x_mid_k).all()


def test_panel_without_louver_runs(suwon, rmis):
    import dataclasses

    cfg = dataclasses.replace(suwon, louver=None)
    plant = Plant(cfg, PlantOptions(n_segments=3), seed=1, weather_series=rmis)
    plant.reset(day_start(rmis, 1) + 11 * HOUR, command=Command(0.0, 9, 100.0))
    plant.advance(600.0)
    st = plant.true_state()
    assert st.label == 9 and np.isfinite(st.x_mid_k).all()
    assert abs(plant.energy_balance()["residual_j"]) < 1e-3 * plant.energy_balance()["scale_j"]


@pytest.mark.parametrize("name", ["tiny_format_sample_synthetic.epw",
                                  "tiny_format_sample_synthetic_tmy3.csv"])
def test_replays_typical_year_files(suwon, name):
    """EPW and TMY3 through dsfd.weather: hourly data, DIRINT where DNI/DHI are missing."""
    from dsfd.sim.replay import load_weather
    from tests.conftest import DATA

    series = load_weather(DATA / name)
    plant = Plant(suwon, PlantOptions(n_segments=3), seed=1, weather_series=series)
    first = plant.series.coverage_s[0]
    plant.reset(first + 12 * HOUR - (first % 60.0), command=Command(0.0, 1, 100.0))
    for _ in range(30):
        plant.advance(60.0)
    r = plant.read_sensors()
    assert all(np.isfinite(v) for v in r.values())
    assert r["ghi_wm2"] > 0.0


def test_the_station_pyranometer_reads_the_sky_that_heats_the_plant(suwon, rmis):
    """The station's GHI is the closure DNI cos Z + DHI of the measured beam and diffuse the
    plant's optics use — not the record's own GHI channel, which on the clear afternoon of
    2 January falls more than 10 % short of that closure (a controller fed it would see a
    weaker sun than the one heating the façade)."""
    from dsfd.physics.solar import solar_position

    plant = Plant(suwon, PlantOptions(n_segments=3), seed=2, weather_series=rmis)
    plant.reset(day_start(rmis, 1) + 14.5 * HOUR, command=Command(0.0, 1, 100.0))
    plant.advance(60.0)
    got = plant.station_weather()["ghi_wm2"]
    t = plant.time_s - 30.0  # the logger's interval mean sits mid-interval
    s = plant.series
    dni, dhi, channel = (float(np.interp(t, s.time_s, getattr(s, c)))
                         for c in ("dni_wm2", "dhi_wm2", "ghi_wm2"))
    zenith = float(solar_position(np.array([t]), suwon.site.latitude_deg,
                                  suwon.site.longitude_deg).zenith_deg[0])
    assert 60.0 < zenith < 80.0 and dni > 500.0  # a clear winter afternoon
    assert got == pytest.approx(dni * np.cos(np.radians(zenith)) + dhi, rel=1e-9)
    assert got > 1.1 * channel
    plant.reset(day_start(rmis, 1) + 2 * HOUR, command=Command(0.0, 1, 100.0))
    plant.advance(60.0)
    night = plant.station_weather()["ghi_wm2"]
    assert 0.0 <= night < 2.0  # the diffuse channel's night offset, never negative or NaN
