"""Weather readers, time conventions, resampling and the solar-time shift."""

from __future__ import annotations

import calendar
import csv
from pathlib import Path

import numpy as np
import pytest

from dsfd.physics.solar import apparent_elevation, solar_position
from dsfd.weather import (
    WeatherSeries,
    bundled_weather,
    fill_short_gaps,
    read_epw,
    read_rmis,
    read_surfrad,
    read_tmy3,
    read_weather,
    resample,
    shift_to_site,
)

DATA = Path(__file__).resolve().parents[1] / "data"
EPW = DATA / "tiny_format_sample_synthetic.epw"
TMY3 = DATA / "tiny_format_sample_synthetic_tmy3.csv"
SURFRAD_SLICE = DATA / "alamosa_surfrad_20160101_1min_slice.csv"


def _utc(year: int, month: int, day: int, hour: int = 0, minute: int = 0, second: int = 0
         ) -> float:
    return float(calendar.timegm((year, month, day, hour, minute, second)))


def _solar_noon_utc(day_start_utc: float, longitude_deg: float) -> float:
    """UTC time of zero hour angle on the UTC day starting at ``day_start_utc``."""
    guess = day_start_utc + (720.0 - 4.0 * longitude_deg) * 60.0
    eot_min = solar_position(guess, 0.0, longitude_deg).equation_of_time_min
    return float(guess - eot_min * 60.0)


def _ghi_centroid(series: WeatherSeries, start_s: float, end_s: float) -> float:
    inside = (series.time_s >= start_s) & (series.time_s < end_s)
    ghi = np.nan_to_num(series.ghi_wm2[inside])
    return float(np.sum(ghi * series.time_s[inside]) / np.sum(ghi))


def _series(time_s: np.ndarray, **channels: np.ndarray) -> WeatherSeries:
    n = time_s.size
    values = {name: channels.get(name, np.zeros(n)) for name in (
        "t_out_c", "ghi_wm2", "dni_wm2", "dhi_wm2", "wind_speed_ms", "wind_dir_deg",
        "pressure_pa", "rh_pct")}
    return WeatherSeries(time_s=time_s, **values, source="test", station_latitude_deg=37.0,
                         station_longitude_deg=-105.0, station_elevation_m=0.0)


@pytest.fixture(scope="module")
def alamosa() -> WeatherSeries:
    return read_surfrad(bundled_weather("surfrad-alamosa-2016-01-01"))


@pytest.fixture(scope="module")
def golden() -> WeatherSeries:
    return read_rmis(bundled_weather("rmis-golden-2022-01"))


# --- SURFRAD -------------------------------------------------------------------------------

def test_surfrad_reproduces_reduced_csv(alamosa):
    with SURFRAD_SLICE.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    stamps = np.array([np.datetime64(r["time_utc"][:19], "s") for r in rows]).astype(float)
    index = np.searchsorted(alamosa.time_s, stamps - 30.0)  # midpoint = stamp - 30 s
    np.testing.assert_array_equal(alamosa.time_s[index], stamps - 30.0)

    def column(key: str) -> np.ndarray:
        return np.array([float(r[key]) for r in rows])

    np.testing.assert_allclose(alamosa.ghi_wm2[index], np.clip(column("ghi"), 0.0, None))
    np.testing.assert_allclose(alamosa.dni_wm2[index], np.clip(column("dni"), 0.0, None))
    np.testing.assert_allclose(alamosa.dhi_wm2[index], np.clip(column("dhi"), 0.0, None))
    np.testing.assert_allclose(alamosa.t_out_c[index], column("temp_air"))
    np.testing.assert_allclose(alamosa.rh_pct[index], column("relative_humidity"))
    np.testing.assert_allclose(alamosa.wind_speed_ms[index], column("wind_speed"))
    np.testing.assert_allclose(alamosa.wind_dir_deg[index], column("wind_direction"))
    np.testing.assert_allclose(alamosa.pressure_pa[index], 100.0 * column("pressure_hPa"))
    assert (alamosa.station_latitude_deg, alamosa.station_longitude_deg) == (37.70, -105.92)
    assert alamosa.station_elevation_m == 2317.0 and len(alamosa) == 1440
    assert "SURFRAD" in alamosa.attribution


def test_surfrad_zenith_column_confirms_end_of_interval_stamps(alamosa):
    table = np.loadtxt(bundled_weather("surfrad-alamosa-2016-01-01"), skiprows=2)
    file_zenith = table[:, 7]
    up = file_zenith < 80.0

    def apparent_zenith(t: np.ndarray) -> np.ndarray:
        sun = solar_position(t, alamosa.station_latitude_deg, alamosa.station_longitude_deg)
        return 90.0 - apparent_elevation(sun.elevation_deg, pressure_pa=alamosa.pressure_pa,
                                         temp_c=alamosa.t_out_c)

    at_midpoint = np.abs(apparent_zenith(alamosa.time_s) - file_zenith)[up]
    at_stamp = np.abs(apparent_zenith(alamosa.time_s + 30.0) - file_zenith)[up]
    # file zenith rounded to 0.01 deg; measured mean/max 0.016/0.025 deg at the midpoint,
    # 0.07/0.10 deg at the stamp
    assert at_midpoint.max() < 0.04
    assert at_midpoint.mean() < 0.5 * at_stamp.mean()


# --- RMIS ----------------------------------------------------------------------------------

def test_rmis_times_are_utc_midpoints(golden):
    # first stamp 1/1/2022 0:05 MST, end of a 5-minute interval -> 07:02:30 UTC
    assert golden.time_s[0] == _utc(2022, 1, 1, 7, 2, 30)
    assert np.all(np.diff(golden.time_s) == 300.0)
    assert not np.isnan(golden.ghi_wm2).any()  # the empty 23:55 rows are filled or trimmed
    assert golden.nominal_step_s == 300.0
    assert np.nanmin(golden.ghi_wm2) == 0.0


@pytest.mark.parametrize("day", [2, 4])  # the clear days
def test_rmis_clear_day_centroid_at_solar_noon(golden, day):
    local_midnight = _utc(2022, 1, day, 7)  # MST = UTC - 7
    centroid = _ghi_centroid(golden, local_midnight, local_midnight + 86400.0)
    noon = _solar_noon_utc(_utc(2022, 1, day), golden.station_longitude_deg)
    assert abs(centroid - noon) < 15 * 60.0  # measured: -7.6 and -6.2 min


# --- EPW and TMY3 (synthetic format samples) ------------------------------------------------

def test_epw_reader_location_times_and_missing_codes():
    series = read_epw(EPW)
    assert series.station_latitude_deg == 37.27 and series.station_longitude_deg == 126.99
    assert series.station_elevation_m == 34.0
    # hour 1 of 1 Jan (hour ending, KST = UTC+9) -> midpoint 00:30 KST = 15:30 UTC 31 Dec
    assert series.time_s[0] == _utc(2016, 12, 31, 15, 30)
    assert np.all(np.diff(series.time_s) == 3600.0) and len(series) == 30
    assert not np.isnan(series.ghi_wm2).any() and not np.isnan(series.t_out_c).any()
    assert 0.0 < series.ghi_wm2[12] < 1000.0  # the 9999 code was interpolated over
    assert series.wind_dir_deg[1] == pytest.approx(355.0)  # mean of 350 and 0 on the circle
    assert series.pressure_pa[0] == 102100.0
    noon = _solar_noon_utc(_utc(2017, 1, 1), 126.99)
    centroid = _ghi_centroid(series, noon - 43200.0, noon + 43200.0)
    assert abs(centroid - noon) < 15 * 60.0
    assert any("filled short gaps" in note for note in series.notes)


def test_tmy3_reader_metadata_typical_year_and_missing_codes():
    series = read_tmy3(TMY3)
    assert series.station_longitude_deg == -105.18 and series.station_elevation_m == 1829.0
    assert any("placed in 1991" in note for note in series.notes)
    assert series.time_s[0] == _utc(1991, 1, 31, 7, 30)  # 00:30 MST
    assert np.all(np.diff(series.time_s) == 3600.0)
    assert series.pressure_pa[21] == pytest.approx(81500.0)  # -9900 filled, mbar -> Pa
    noon = _solar_noon_utc(_utc(1991, 1, 31), -105.18)
    centroid = _ghi_centroid(series, noon - 43200.0, noon + 43200.0)
    assert abs(centroid - noon) < 15 * 60.0


def test_read_weather_dispatches_by_content():
    assert read_weather(EPW).source.startswith("EnergyPlus")
    assert read_weather(TMY3).source.startswith("NSRDB TMY3")
    assert read_weather(bundled_weather("rmis-golden-2022-01")).source.startswith("NREL RMIS")
    assert "SURFRAD" in read_weather(bundled_weather("surfrad-alamosa-2016-01-01")).source
    with pytest.raises(ValueError, match="unknown bundled weather 'nope'"):
        bundled_weather("nope")


def test_read_weather_rejects_unknown_format(tmp_path):
    path = tmp_path / "x.txt"
    path.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="unknown weather file format"):
        read_weather(path)


# --- gap filling, resampling, shifting --------------------------------------------------------

def test_fill_short_gaps_rule():
    t = np.arange(12.0)
    v = np.array([np.nan, 1, np.nan, np.nan, np.nan, 5, np.nan, np.nan, np.nan, np.nan, 10,
                  np.nan])
    filled, n = fill_short_gaps(t, v)
    np.testing.assert_allclose(filled[1:6], [1, 2, 3, 4, 5])  # run of 3: filled
    assert np.isnan(filled[[0, 6, 7, 8, 9, 11]]).all() and n == 3  # run of 4 and ends: not


def test_resample_to_step_midpoints_with_linear_interpolation():
    t = np.arange(5) * 600.0
    series = _series(t, t_out_c=np.array([0.0, 6.0, 12.0, 18.0, 24.0]))
    out = resample(series, start_s=0.0, step_s=900.0, n_steps=3)
    np.testing.assert_array_equal(out.time_s, [450.0, 1350.0, 2250.0])
    np.testing.assert_allclose(out.t_out_c, [4.5, 13.5, 22.5])
    assert any("resampled" in note for note in out.notes)
    edge = resample(series, start_s=-300.0, step_s=600.0, n_steps=1)  # first sample's interval
    assert edge.t_out_c[0] == 0.0


def test_resample_wind_direction_on_the_circle():
    t = np.array([0.0, 600.0])
    series = _series(t, wind_speed_ms=np.array([2.0, 2.0]), wind_dir_deg=np.array([350.0, 30.0]))
    out = resample(series, start_s=0.0, step_s=300.0, n_steps=2)
    wrapped = np.mod(out.wind_dir_deg - [0.0, 20.0] + 180.0, 360.0) - 180.0
    assert np.all(np.abs(wrapped) < 1.0)  # through north, not through south
    assert out.wind_speed_ms[0] == 2.0
    calm = _series(t, wind_speed_ms=np.zeros(2), wind_dir_deg=np.array([350.0, 30.0]))
    assert resample(calm, start_s=0.0, step_s=600.0, n_steps=1).wind_dir_deg[0] == (
        pytest.approx(10.0))


def test_resample_window_outside_data_raises_named_window(alamosa):
    with pytest.raises(ValueError, match=r"2016-01-01 23:00:00 UTC to 2016-01-02 01:00:00 UTC"):
        resample(alamosa, start_s=_utc(2016, 1, 1, 23), step_s=900.0, n_steps=8)
    # the file's 1-min means (stamped at their end) cover 31 Dec 23:59 to 1 Jan 23:59 UTC
    day = resample(alamosa, start_s=_utc(2015, 12, 31, 23, 59), step_s=60.0, n_steps=1440)
    np.testing.assert_allclose(day.ghi_wm2, alamosa.ghi_wm2)


def test_shift_to_site_puts_alamosa_noon_at_suwon_noon(alamosa):
    shifted = shift_to_site(alamosa, longitude_deg=127.0)
    assert shifted.shift_s == pytest.approx((-105.92 - 127.0) / 15.0 * 3600.0)
    assert shifted.notes[-1] == (
        "shifted by −15.53 h: replayed at the same local solar time at 127.0°E")
    noon = _solar_noon_utc(_utc(2016, 1, 1), 127.0)
    centroid = _ghi_centroid(shifted, noon - 43200.0, noon + 43200.0)
    assert abs(centroid - noon) < 15 * 60.0
    again = shift_to_site(shifted, longitude_deg=127.0)
    np.testing.assert_array_equal(again.time_s, shifted.time_s)
    assert sum(note.startswith("shifted by") for note in again.notes) == 1


def test_weather_series_validates_shape_and_time():
    with pytest.raises(ValueError, match="strictly increasing"):
        _series(np.array([0.0, 0.0]))
    with pytest.raises(ValueError, match="t_out_c has 3 values for 2 times"):
        _series(np.array([0.0, 1.0]), t_out_c=np.zeros(3))
