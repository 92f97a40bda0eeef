"""The report's Diagnostics section (dsfd.report.diagnostics): the findings the daemon's own
check stored, each with a figure of its evidence drawn from the stored rows.

The databases hold synthetic readings with a known change (tests/daemon/findings_data.py):
the figures must show that change where it was made, not merely exist. The end-to-end run
(a real ``dsfd run`` with a stuck damper, then ``dsfd report``) is in
tests/sim/test_stuck_damper_dry_run.py, which already makes that run."""

from __future__ import annotations

import io
import re
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from dsfd.daemon.findings import FindingsStage, NightSite
from dsfd.measured import iso_utc
from dsfd.report.diagnostics import MAX_FIGURES, build_diagnostics, render_section
from dsfd.report.finding_figures import night_figure, residual_figure
from dsfd.storage.findings import findings_between
from dsfd.storage.history import read_history
from tests.daemon.findings_data import (
    DAYS,
    NIGHT_STEP_NIGHT,
    STEP_AT,
    SUWON,
    T0,
    night_database,
    residual_database,
    write_database,
)

DUMP6 = Path(__file__).parents[1] / "data" / "timeseries-schema6.sql"


def _lines(fig: Figure, offset_h: float) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every labelled line of ``fig``: (x as UTC seconds, y); its axes are in local standard
    time, ``offset_h`` ahead of UTC."""
    out = {}
    for ax in fig.axes:
        for line in ax.get_lines():
            x = (np.asarray(line.get_xdata()).astype("datetime64[ms]").astype("int64") / 1e3
                 - offset_h * 3600.0)
            out[str(line.get_label())] = (x, np.asarray(line.get_ydata(), float))
    return out


def _minute(t: float) -> str:
    """A time as the section writes it: UTC to the minute."""
    return iso_utc(round(t))[:16].replace("T", " ")


def _png_size(section: str, fid: int) -> tuple[int, int]:
    from PIL import Image

    m = re.search(rf'<figure id="finding-{fid}">.*?src="data:image/png;base64,([^"]+)"',
                  section, re.S)
    assert m is not None, f"no figure of finding #{fid}"
    import base64

    return Image.open(io.BytesIO(base64.b64decode(m.group(1)))).size


@pytest.fixture(scope="module")
def residual_state(tmp_path_factory) -> Path:
    """Seven days with x3 reading 1 K high from day 6.5, and the daemon's check of the end."""
    state = tmp_path_factory.mktemp("residual")
    db = residual_database(state)
    with sqlite3.connect(db) as conn:
        FindingsStage(db, run_id=lambda: 1).check(conn, T0 + DAYS * 86400.0)
    return state


def test_a_stored_residual_finding_is_listed_with_a_figure_of_its_step(residual_state):
    history = read_history(residual_state)
    d = build_diagnostics(history, None, offset_h=0.0, dpi=50)
    (row,) = d.findings
    html = render_section(d)
    # listed as stored: kind, subject, state, confidence, times, action, evidence
    assert (row["kind"], row["subject"], row["state"]) == ("residual_shift", "residual:x3_c",
                                                           "open")
    for text in ("#1", "residual_shift", "residual:x3_c", f"{row['confidence']:.3g}",
                 _minute(row["start_s"]), _minute(row["detected_s"]),
                 "check the x3_c sensor", f"{row['evidence'][0]['shift']:.3g} K",
                 f"{row['evidence'][0]['statistic']:.3g} sd", "8 sd"):
        assert text in html, text
    assert _png_size(html, 1)[0] > 300
    # The figure shows the 1 K step of x3's prediction error where it was made: the block
    # means a day before the start sit near 0, those after it near +1 K; the stored start
    # and detection are marked; the CUSUM crosses its threshold at the detection.
    with sqlite3.connect(residual_state / "timeseries.sqlite") as conn:
        lines = _lines(residual_figure(conn, row, 0.0), 0.0)
    t, means = next(v for k, v in lines.items() if "block means" in k)
    before = means[(t > row["start_s"] - 86400) & (t < STEP_AT)]
    after = means[(t > STEP_AT + 1200) & (t <= T0 + DAYS * 86400)]
    assert abs(np.nanmean(before)) < 0.15 and 0.7 < np.nanmean(after) < 1.3
    assert lines["start"][0][0] == row["start_s"] and lines["detected"][0][0] == row[
        "detected_s"]
    tc, cusum = next(v for k, v in lines.items() if k.startswith("CUSUM"))
    assert cusum[-1] > 8.0 > cusum[:-1].max()
    assert row["detected_s"] - 600 <= tc[-1] <= row["detected_s"]  # the block that crossed


def test_a_night_offset_shift_is_drawn_from_the_nights_the_check_judged(tmp_path):
    db, t = night_database(tmp_path, 1.5)
    with sqlite3.connect(db) as conn:
        FindingsStage(db, run_id=lambda: 1, night=NightSite(**SUWON)).check(conn, t[-1])
    config = {"site": {"latitude_deg": SUWON["latitude_deg"],
                       "longitude_deg": SUWON["longitude_deg"], "utc_offset_h": 9.0},
              "room": {"t_in_c": SUWON["room_c"]}}
    d = build_diagnostics(read_history(tmp_path), config, offset_h=9.0, dpi=40)
    (row,) = d.findings
    assert row["kind"] == "pane_offset_shift" and 1 in d.figures
    assert "check the x1_c thermocouple or the outdoor-air sensor" in render_section(d)
    with sqlite3.connect(db) as conn:
        lines = _lines(night_figure(conn, row, 9.0, config), 9.0)
    tm, medians = lines["nightly median (the check's input)"]
    ref_t, ref = lines["reference: median of the nights before the start"]
    # the nights after the start sit 1.5 K (the step made) above the reference level
    step_night_s = T0 + (NIGHT_STEP_NIGHT - 0.5) * 86400.0
    assert ref_t[-1] == row["start_s"] and ref_t[0] < step_night_s
    assert np.mean(medians[tm > step_night_s]) - ref[0] == pytest.approx(1.5, abs=0.4)
    assert abs(np.mean(medians[tm < step_night_s]) - ref[0]) < 0.3
    # without the site, night cannot be told: no figure, and the section says why
    bare = build_diagnostics(read_history(tmp_path), None, offset_h=9.0, dpi=40)
    assert not bare.figures and "the site is not recorded" in bare.no_figure[1]
    assert "#1: no figure: the site is not recorded" in render_section(bare)


def test_without_findings_the_section_says_so_in_one_line(tmp_path):
    t = T0 + 60.0 * np.arange(90)
    write_database(tmp_path, t, {"x1_c": np.full(t.size, 5.0)}, {})
    html = render_section(build_diagnostics(read_history(tmp_path), None, offset_h=0.0,
                                            dpi=40))
    assert html.count("<p>") == 1 and "<figure" not in html and "<table" not in html
    assert "No findings in this period" in html
    # ... and how much history each detector needs before it judges, against this log's
    assert "6 days" in html and "8 days" in html and "this log spans 1.5 h" in html


def test_a_database_older_than_the_findings_says_so(tmp_path):
    with sqlite3.connect(tmp_path / "timeseries.sqlite") as conn:
        conn.executescript(DUMP6.read_text())
    html = render_section(build_diagnostics(read_history(tmp_path), None, offset_h=0.0,
                                            dpi=40))
    assert "No findings: this database (schema 6) predates" in html


def test_at_most_a_few_figures_open_findings_first_the_rest_listed(residual_state, tmp_path):
    """Nine findings overlap the period (the residual one open, eight earlier ones of the
    same output that ended, and a cavity finding with no readings to draw), one ended before
    it: all ten listed, six drawn with the open one among them, the rest say why not."""
    db = tmp_path / "timeseries.sqlite"
    with sqlite3.connect(residual_state / "timeseries.sqlite") as src, sqlite3.connect(db) as dst:
        src.backup(dst)
        (evidence,) = dst.execute("SELECT evidence FROM findings").fetchone()
        end = T0 + DAYS * 86400.0
        rows = [("residual_shift", "residual:x3_c", end - 3600.0 * (k + 2),
                 end - 3600.0 * (k + 1)) for k in range(8)]
        rows += [("cavity_no_flow", "", end - 7200.0, end - 3600.0),
                 ("residual_shift", "residual:x3_c", T0 - 7200.0, T0 - 3600.0)]
        dst.executemany(
            "INSERT INTO findings (run_id, kind, subject, confidence, start_s, detected_s, "
            "opened_s, last_seen_s, evidence, action, state, ended_s, end_reason) "
            "VALUES (1, ?, ?, 0.9, ?, ?, ?, ?, ?, 'check', 'ended', ?, "
            "'the evidence went away')", [(k, s, a, a, a, a, evidence, b) for k, s, a, b in rows])
    history = read_history(tmp_path)
    with sqlite3.connect(db) as conn:
        assert len(findings_between(conn, history.time_s[0], history.time_s[-1])) == 10
    d = build_diagnostics(history, None, offset_h=0.0, dpi=30)
    html = render_section(d)
    assert len(d.findings) == 10 and len(d.figures) == MAX_FIGURES == 6
    assert 1 in d.figures  # the open one
    assert html.count("<figure ") == 6 and html.count("not drawn: the report draws at most 6") \
        == 3
    assert "#10: no figure: no stored cavity speed readings" in html
    assert "#11" not in html  # ended before the period


def test_a_parameter_finding_is_drawn_with_its_daily_values_and_the_level_before(tmp_path):
    """The path resistance doubled from the 15th day (tests/daemon/test_parameter_findings):
    the figure's daily values after the start sit about twice the drawn level before it,
    the level within the days' wander of the synthetic truth (f = 100), and its marks are
    the stored start and detection."""
    from tests.daemon.test_parameter_findings import DEFAULTS, SHIFT_AT

    fig = _drawn_parameter_finding(tmp_path, "f", float(np.log(2.0)))
    ax = fig.axes[0]
    assert ax.get_yscale() == "log" and "f" in ax.get_ylabel()
    lines = _lines(fig, 0.0)
    _, (level, _) = lines["level of the days before the start"]
    assert 0.8 * DEFAULTS["f"] < level < 1.25 * DEFAULTS["f"]
    daily = next(c for c in ax.containers).lines[0]  # the error bars' points
    t = np.asarray(daily.get_xdata()).astype("datetime64[ms]").astype("int64") / 1e3
    after = np.asarray(daily.get_ydata(), float)[t > SHIFT_AT + 86400.0]
    assert after.size >= 3 and np.all((after > 1.5 * level) & (after < 2.6 * level))
    marks = {ln.get_label(): ln.get_xdata()[0] for ln in ax.get_lines()
             if ln.get_label() in ("start", "detected")}
    assert set(marks) == {"start", "detected"}


def test_a_heat_flux_offset_finding_is_drawn_in_w_per_m2_from_the_stored_offsets(tmp_path):
    """q_x3 +15 W/m2 from the 15th day (an inner-pane thermocouple reading high): the figure
    reads the on-line offsets from the rows' JSON, draws them on a linear W/m2 axis, the
    level before near 0 (the synthetic history's wander of about 1 W/m2) and the daily
    values after about 15 W/m2 above it."""
    from tests.daemon.test_parameter_findings import SHIFT_AT

    fig = _drawn_parameter_finding(tmp_path, "q_x3", 15.0)
    ax = fig.axes[0]
    assert ax.get_yscale() == "linear" and "W/m²" in ax.get_ylabel()
    _, (level, _) = _lines(fig, 0.0)["level of the days before the start"]
    assert abs(level) < 1.5
    estimates = next(ln for ln in ax.get_lines() if ln.get_label() == "each on-line estimate")
    t = np.asarray(estimates.get_xdata()).astype("datetime64[ms]").astype("int64") / 1e3
    late = np.asarray(estimates.get_ydata(), float)[t > SHIFT_AT + 86400.0]
    assert late.size > 24 and abs(np.median(late) - level - 15.0) < 2.0


def _drawn_parameter_finding(tmp_path, name: str, shift: float):
    """The figure of the one parameter finding the daemon's checks open on a synthetic
    history with ``shift`` added to ``name`` from the 15th day
    (tests/daemon/test_parameter_findings)."""
    from dsfd.report.finding_figures import parameter_figure
    from tests.daemon.test_parameter_findings import _checks, _parameter_history

    db = _parameter_history(tmp_path, shift={name: shift})
    _checks(db)
    with sqlite3.connect(db) as conn:
        rows = [r for r in findings_between(conn, 0.0, 1e12) if r["kind"] == "parameter_shift"]
        assert [r["subject"] for r in rows] == [f"parameter:{name}"]
        return parameter_figure(conn, rows[0], 0.0)
