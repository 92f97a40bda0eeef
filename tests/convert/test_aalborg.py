"""The Aalborg "Cube" data: converter conventions, panel file, scores of the simple models."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dsfd.cli import main
from dsfd.config import load_panel
from dsfd.convert.aalborg import AalborgFormatError, convert_aalborg
from dsfd.estimation.night_offsets import NIGHT_OFFSET_NAMES, night_offset_change
from dsfd.estimation.stepdata import step_data
from dsfd.estimation.validation import replay_scores
from dsfd.measured import iso_utc
from dsfd.storage.evidence import night_mask
from dsfd.storage.measured_csv import read_measured
from tests.conftest import DATA, PANELS

SRC = DATA / "dsf_aalborg_cube"


@pytest.fixture(scope="module")
def cube():
    return load_panel(PANELS / "aalborg-cube.yaml")


def test_conversion_follows_the_measured_data_conventions():
    data = convert_aalborg(SRC)
    assert len(data) == 1009 and data.step_s == 600.0
    assert iso_utc(data.time_s[0]) == "2006-09-30T23:00:00Z"  # 1 Oct 00:00 CET
    # states are readings at t: row 0 holds the first reading (Tei 11.46 degC)
    assert data.get("x1_c")[0] == pytest.approx(11.46)
    assert np.isnan(data.get("x1_c")[-1])
    # weather is the mean of [t, t+600 s), so it sits on the row that ends the interval
    assert np.isnan(data.get("t_out_c")[0]) and data.get("t_out_c")[1] == pytest.approx(11.1)
    assert data.get("wind_speed_ms")[1] == pytest.approx(0.5)
    assert set(data.get("afr")) == {3.0}
    assert data.has("ghi_wm2") and data.has("dhi_wm2") and not data.has("poa_wm2")
    facade = convert_aalborg(SRC, irradiance="facade", hourly="hold")
    assert facade.has("poa_wm2") and facade.has("poa_diffuse_wm2")
    # hourly values are held over their six rows
    assert len(set(facade.get("poa_wm2")[1 + 6 * 12: 1 + 6 * 13])) == 1


def test_cli_writes_a_csv_the_tools_read(tmp_path, capsys):
    out = tmp_path / "cube.csv"
    assert main(["convert-aalborg", str(SRC), "--out", str(out)]) == 0
    assert "BSD-3-Clause" in capsys.readouterr().out
    data = read_measured(out)
    assert len(data) == 1009 and any("DSFModelica" in n for n in data.notes)


def test_broken_source_names_file_and_line(tmp_path):
    for name in ("BoundaryConditions10min.txt", "DSFValidation10min.txt"):
        (tmp_path / name).write_text((SRC / name).read_text())
    path = tmp_path / "DSFValidation10min.txt"
    lines = path.read_text().splitlines()
    lines[10] = "600 21.79 0 0 0 11.38 x 20.24"
    path.write_text("\n".join(lines))
    with pytest.raises(AalborgFormatError, match=r"DSFValidation10min\.txt: line 11"):
        convert_aalborg(tmp_path)


def test_panel_and_the_scores_of_persistence_and_the_uncalibrated_model(cube):
    assert cube.openings.available_regimes() == (3, 4, 10)
    steps = step_data(cube, convert_aalborg(SRC))
    assert steps.present == ("x1", "x2", "x3")
    out = replay_scores(cube, steps, horizons=(1, 6), online=False)
    # persistence: 0.32 degC at 10 min, 1.22 degC at 1 h (mean of the three glass panes)
    assert out.mae_c("persistence", 1, "mean") == pytest.approx(0.32, abs=0.01)
    assert out.mae_c("persistence", 6, "mean") == pytest.approx(1.22, abs=0.01)
    assert 0.3 < out.mae_c("uncalibrated", 1, "mean") < 1.0
    assert out.mae_c("uncalibrated", 1, "x4") is None
    assert "uncalibrated.h1.x4_mae_c" not in out.flat()


def test_the_data_folder_carries_its_licence():
    text = Path(SRC / "LICENSE").read_text()
    assert "BSD 3-Clause" in text and "DamaAlessandro" in text


@pytest.mark.slow
def test_self_calibration_halves_the_uncalibrated_error_and_beats_persistence(cube):
    """Issue 4 on real data (1-7 Oct, the three glass temperatures, 10 min and 1 h ahead).

    Bars from the issue, independent of this code: the self-calibrating model's mean error
    at most half the uncalibrated model's, and below persistence (0.32 / 1.22 degC).
    """
    steps = step_data(cube, convert_aalborg(SRC))
    out = replay_scores(cube, steps, horizons=(1, 6))
    assert out.online_updates > 300  # an update every 30 min over the week
    for h in (1, 6):
        mean = out.horizons[h].mean_mae_c
        assert mean["online"] <= 0.5 * mean["uncalibrated"], h
        assert mean["online"] < mean["persistence"], h
    # issue 38: the night offsets on the replay's heat-flux offsets find nothing (the façade
    # did not change during the measurements; the offsets moved by up to 20 W/m² from one
    # night to the next, far more than on the simulated bench)
    t = steps.time_s[:-1]
    night = night_mask(t, latitude_deg=cube.site.latitude_deg,
                       longitude_deg=cube.site.longitude_deg)
    assert np.count_nonzero(night) * steps.step_s > 6 * 6 * 3600.0  # six nights of 6 h or more
    for name in NIGHT_OFFSET_NAMES:
        assert night_offset_change(t, out.online_offsets_wm2[name], night, name=name) is None
