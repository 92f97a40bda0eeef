"""Weather from daily station statistics (KMA ASOS Suwon, the paper's period)."""

from __future__ import annotations

import calendar
import csv
from pathlib import Path

import numpy as np
import pytest

from dsfd.physics.solar import solar_position
from dsfd.weather import WeatherSeries, bundled_weather, read_kma_daily, read_weather
from dsfd.weather.daily import SUWON_LATITUDE_DEG, SUWON_LONGITUDE_DEG, haurwitz_ghi, sun_times

DATA = Path(__file__).resolve().parents[1] / "data"
KST = 9 * 3600.0


@pytest.fixture(scope="module")
def rows() -> list[dict[str, str]]:
    with bundled_weather("kma-suwon-2008-12").open(newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.fixture(scope="module")
def suwon() -> WeatherSeries:
    return read_weather(bundled_weather("kma-suwon-2008-12"))


def _day_index(series: WeatherSeries) -> np.ndarray:
    return ((series.time_s - series.time_s[0]) // 86400.0).astype(int)


def test_every_day_keeps_its_mean_temperature_and_irradiation(suwon, rows):
    assert len(rows) == 62 and rows[7]["date"] == "2008-12-08"
    day = _day_index(suwon)
    assert day.max() == len(rows) - 1
    # the first sample is the middle of the first 5 minutes of 1 Dec 2008, KST
    start = calendar.timegm((2008, 12, 1, 0, 0, 0)) - KST
    assert suwon.time_s[0] == pytest.approx(start + 150.0)
    mean = np.bincount(day, weights=suwon.t_out_c) / np.bincount(day)
    assert np.allclose(mean, [float(r["avgTa"]) for r in rows], atol=1e-9)
    energy = np.bincount(day, weights=suwon.ghi_wm2 * 300.0) / 1e6
    assert np.allclose(energy, [float(r["sumGsr"]) for r in rows], rtol=1e-9)


def test_temperature_is_continuous_coldest_at_sunrise_warmest_in_the_afternoon(suwon, rows):
    assert np.max(np.abs(np.diff(suwon.t_out_c))) < 0.3  # K per 5 min
    day = _day_index(suwon)
    sunrise, noon = sun_times(suwon.time_s[0] - 150.0 + 86400.0 * np.arange(len(rows)),
                              SUWON_LATITUDE_DEG, SUWON_LONGITUDE_DEG)

    def at(t: float) -> float:
        return float(np.interp(t, suwon.time_s, suwon.t_out_c))

    for d in range(1, day.max()):
        # sunrise is a local minimum and three hours after solar noon (≈ 15:30 KST) a
        # local maximum, to within the slow mean-matching offset ...
        peak = noon[d] + 3 * 3600.0
        assert 15.0 < (peak + KST) % 86400.0 / 3600.0 < 16.0
        near = np.abs(suwon.time_s - sunrise[d]) <= 3600.0
        assert at(sunrise[d]) <= suwon.t_out_c[near].min() + 0.05
        near = np.abs(suwon.time_s - peak) <= 3600.0
        assert at(peak) >= suwon.t_out_c[near].max() - 0.05
        # ... and the rise to the afternoon is the reported diurnal range
        rise = at(peak) - at(sunrise[d])
        assert rise == pytest.approx(float(rows[d]["maxTa"]) - float(rows[d]["minTa"]),
                                     abs=1.0)


def test_irradiance_only_by_day_and_diffuse_split_left_to_the_consumer(suwon):
    elevation = 90.0 - solar_position(suwon.time_s, SUWON_LATITUDE_DEG,
                                      SUWON_LONGITUDE_DEG).zenith_deg
    assert np.all(suwon.ghi_wm2[elevation < 0] == 0.0)
    assert np.all(suwon.ghi_wm2[elevation > 5] > 0.0)
    assert np.all(np.isnan(suwon.dni_wm2)) and np.all(np.isnan(suwon.dhi_wm2))
    assert np.all(suwon.wind_dir_deg == 315.0)
    assert 1.0e5 < suwon.pressure_pa.min() and suwon.pressure_pa.max() < 1.04e5


def test_haurwitz_clear_sky():
    # 1098 cos Z exp(-0.057 / cos Z): 1037.2 W/m2 overhead, 489.9 at Z = 60°, 0 at night
    assert haurwitz_ghi(np.array([1.0, 0.5, 0.0, -0.3])) == pytest.approx(
        [1098.0 * np.exp(-0.057), 549.0 * np.exp(-0.114), 0.0, 0.0])


def test_sunrise_and_noon_match_pvlib_spa():
    """Independent reference: pvlib's SPA elevation for Suwon on 21 Dec 2016 (5-min table)."""
    with (DATA / "pvlib_ref_suwon_clearsky_5min.csv").open(newline="") as handle:
        table = list(csv.DictReader(handle))[:288]  # 21 Dec 2016, 00:00-23:55 KST
    day0 = calendar.timegm((2016, 12, 21, 0, 0, 0)) - KST
    t = day0 + 300.0 * np.arange(len(table))
    elev = np.array([float(r["spa_elevation"]) for r in table])
    up = int(np.flatnonzero(elev > 0)[0])
    spa_sunrise = t[up - 1] + 300.0 * (0 - elev[up - 1]) / (elev[up] - elev[up - 1])
    top = int(np.argmax(elev))
    a, b, _ = np.polyfit(t[top - 2: top + 3] - t[top], elev[top - 2: top + 3], 2)
    spa_noon = t[top] - b / (2 * a)
    sunrise, noon = sun_times(np.array([day0]), SUWON_LATITUDE_DEG, SUWON_LONGITUDE_DEG)
    assert noon[0] == pytest.approx(spa_noon, abs=60.0)
    # SPA's elevation includes refraction (~0.5° at the horizon, ≈ 4 min earlier)
    assert 0.0 < sunrise[0] - spa_sunrise < 6 * 60.0


def _write(tmp_path: Path, rows: list[dict[str, str]]) -> Path:
    path = tmp_path / "kma.csv"
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def test_missing_cell_missing_day_and_empty_file_are_named(tmp_path, rows):
    broken = [dict(r) for r in rows[:5]]
    broken[2]["sumGsr"] = ""
    with pytest.raises(ValueError, match=r"row 4 \(2008-12-03\): column 'sumGsr' is empty"):
        read_kma_daily(_write(tmp_path, broken))
    gap = [dict(r) for r in rows[:5]]
    del gap[3]
    with pytest.raises(ValueError, match=r"row 5 \(2008-12-05\) does not follow"):
        read_kma_daily(_write(tmp_path, gap))
    empty = tmp_path / "empty.csv"
    empty.write_text(",".join(rows[0]) + "\n")
    with pytest.raises(ValueError, match=r"empty\.csv: no data rows"):
        read_kma_daily(empty)
