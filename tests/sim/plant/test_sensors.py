"""Simulated sensors: error model, faults, and what the plant reports."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.physics.constants import T_ZERO
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.plant import Plant
from dsfd.sim.plant.sensors import SENSOR_NAMES, SensorBank, SensorConfig, SensorFault
from tests.sim.conftest import HOUR, day_start

TRUE = {"x1_c": 5.0, "x2_c": 15.0, "x3_c": 20.0, "x4_c": 25.0, "x5_c": 18.0, "t_room_c": 22.0,
        "v_cav_ms": 0.05, "t_out_c": 2.0, "ghi_wm2": 400.0, "wind_speed_ms": 2.0,
        "wind_dir_deg": 180.0, "pressure_hpa": 1012.5, "rh_pct": 60.0}


def _readings(bank: SensorBank, n: int, true=TRUE, t0: float = 0.0) -> dict[str, np.ndarray]:
    rows = [bank.read(dict(true), t0 + 60.0 * k) for k in range(n)]
    return {name: np.array([r[name] for r in rows]) for name in SENSOR_NAMES}


def test_thermocouple_bias_and_noise():
    bank = SensorBank(SensorConfig(), np.random.default_rng(1), ideal=False)
    r = _readings(bank, 4000)
    for name in ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c", "t_room_c", "t_out_c"):
        err = r[name] - TRUE[name]
        assert abs(err.mean() - bank.bias[name]) < 0.02
        assert abs(bank.bias[name]) <= 0.3
        assert err.std() == pytest.approx(0.2, rel=0.08)
    biases = [bank.bias[n] for n in ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c")]
    assert len(set(biases)) == 5  # one fixed bias per sensor


def test_anemometer_and_station_noise():
    bank = SensorBank(SensorConfig(), np.random.default_rng(2), ideal=False)
    slow = _readings(bank, 4000, {**TRUE, "v_cav_ms": 0.08})
    assert slow["v_cav_ms"].std() == pytest.approx(0.02, rel=0.1)
    fast = _readings(bank, 4000, {**TRUE, "v_cav_ms": -0.3})  # reads the speed
    assert fast["v_cav_ms"].mean() == pytest.approx(0.3, abs=0.005)
    assert fast["v_cav_ms"].std() == pytest.approx(0.02 + 0.05 * 0.3, rel=0.1)
    assert np.all(slow["v_cav_ms"] >= 0)
    gain = slow["ghi_wm2"].mean() / 400.0
    assert abs(gain - 1.0) <= 0.021 and gain == pytest.approx(bank.gain, abs=0.002)
    assert np.all((slow["wind_dir_deg"] >= 0) & (slow["wind_dir_deg"] < 360))
    # the barometer and the hygrometer: unbiased, σ 0.1 hPa and 1 % RH
    assert slow["pressure_hpa"].mean() == pytest.approx(1012.5, abs=0.01)
    assert slow["pressure_hpa"].std() == pytest.approx(0.1, rel=0.1)
    assert slow["rh_pct"].std() == pytest.approx(1.0, rel=0.1)
    near_saturation = _readings(bank, 2000, {**TRUE, "rh_pct": 99.5})["rh_pct"]
    assert near_saturation.max() <= 100.0


def test_ideal_sensors_return_the_true_values():
    bank = SensorBank(SensorConfig(), np.random.default_rng(3), ideal=True)
    assert bank.read(dict(TRUE), 0.0) == TRUE


def test_faults_dropout_stuck_spikes():
    faults = (SensorFault(sensor="x1_c", kind="dropout", start_s=600.0, end_s=1200.0),
              SensorFault(sensor="x2_c", kind="stuck", start_s=300.0),
              SensorFault(sensor="x3_c", kind="stuck", start_s=0.0, value=-5.0),
              SensorFault(sensor="v_cav_ms", kind="spikes", start_s=0.0, magnitude=1.0,
                          probability=0.2))
    bank = SensorBank(SensorConfig(faults=faults), np.random.default_rng(4), ideal=True)
    rows = []
    for k in range(40):
        true = {**TRUE, "x2_c": 15.0 + k}
        rows.append(bank.read(true, 60.0 * k))
    x1 = np.array([r["x1_c"] for r in rows])
    assert np.isnan(x1[10:20]).all() and np.isfinite(x1[:10]).all() and np.isfinite(x1[20:]).all()
    x2 = np.array([r["x2_c"] for r in rows])
    assert np.all(x2[5:] == 20.0) and x2[4] == 19.0  # stuck at the reading at 300 s
    assert all(r["x3_c"] == -5.0 for r in rows)
    v = np.array([r["v_cav_ms"] for r in rows])
    spikes = np.abs(v - 0.05) > 0.5
    assert 2 <= spikes.sum() <= 20
    with pytest.raises(ValueError):
        SensorFault(sensor="x9_c", kind="dropout", start_s=0.0)


def test_plant_sensors_read_mid_height_and_weather(suwon, rmis):
    start = day_start(rmis, 1) + 11 * HOUR
    faults = (SensorFault(sensor="x4_c", kind="dropout", start_s=start + 120.0),)
    plant = Plant(suwon, PlantOptions(n_segments=4), seed=5, weather_series=rmis,
                  sensors=SensorConfig(faults=faults))
    plant.reset(start, command=Command(0.0, 1, 100.0))
    plant.advance(60.0)
    r = plant.read_sensors()
    assert tuple(r) == SENSOR_NAMES
    st = plant.true_state()
    for i in range(5):
        assert abs(r[f"x{i + 1}_c"] - (st.x_mid_k[i] - T_ZERO)) < 1.5  # bias + noise
    assert r["t_room_c"] == pytest.approx(suwon.room.t_in_c, abs=1.5)
    assert r["ghi_wm2"] > 100.0 and r["v_cav_ms"] >= 0.0
    assert math.isfinite(r["x4_c"])
    plant.advance(120.0)
    assert math.isnan(plant.read_sensors()["x4_c"])
    # x1..x5 sit at mid-height, not at the segment average.
    prof = st.segments_k["g2"]
    assert st.x_mid_k[1] == pytest.approx(np.interp(0.5 * suwon.facade.glazed_height_m,
                                                    st.z_m, prof))


def test_room_schedule_drives_the_room_sensor(suwon, rmis):
    start = day_start(rmis, 1)
    plant = Plant(suwon, PlantOptions(n_segments=2, sensors="ideal"), seed=1,
                  weather_series=rmis, room_schedule=[(start, 20.0), (start + HOUR, 24.0)])
    plant.reset(start)
    plant.advance(1800.0)
    assert plant.read_sensors()["t_room_c"] == pytest.approx(22.0)
