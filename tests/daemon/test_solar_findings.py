"""The solar detector in the daemon's findings check (dsfd.storage.solar_series,
docs/model.md#diagnostics-solar), on a database the daemon could have written: 22 days of
10-minute cycles of the bundled KMA Suwon record of December 2008 (the panel's own site: real
irradiance, so real clear and overcast days), the louver stepping through its angles, and
on-line heat-flux offsets that remove a known share of the sun the model computes from the
stored weather and commands (plus each day's own form error). The days' factors give the
share back; dirt on the glass from day 10 (10 % over a week, the issue's size) is found
after it, never before, named as dirt, stored, and the report draws its evidence."""

from __future__ import annotations

import dataclasses
import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from dsfd.config import load_panel
from dsfd.daemon.findings import FindingsStage
from dsfd.estimation.params import OFFSET_NAMES
from dsfd.estimation.stepdata import step_data
from dsfd.report.diagnostics import build_diagnostics
from dsfd.sim.replay import at_site, load_weather
from dsfd.storage import findings as table
from dsfd.storage.history import measured_from_history, read_history
from dsfd.storage.solar_series import SOLAR_EVERY_S, SolarDays, solar_day_start_s
from dsfd.storage.timeseries import CycleRecord, Store
from tests.conftest import PANELS

DAY = 86400.0
STEP_S = 600.0
DAYS = 22
ONSET_DAY = 10
LOSS_PER_DAY = 0.1 / 7.0
PANEL = load_panel(PANELS / "suwon-south.yaml")


def _weather_samples(t: np.ndarray) -> dict[str, np.ndarray]:
    series = at_site(load_weather("kma-suwon-2008-12"), PANEL)
    at = lambda v: np.interp(t, series.time_s, v)  # noqa: E731
    return {"ghi_wm2": at(series.ghi_wm2), "t_out_c": at(series.t_out_c),
            "wind_speed_ms": at(series.wind_speed_ms), "wind_dir_deg": at(series.wind_dir_deg),
            "pressure_hpa": at(series.pressure_pa) / 100.0, "rh_pct": at(series.rh_pct),
            "t_room_c": np.full(t.size, 22.0), "v_cav_ms": np.full(t.size, 0.05),
            **{f"x{i}_c": np.full(t.size, 15.0) for i in range(1, 6)}}


@pytest.fixture(scope="module")
def soiled(tmp_path_factory) -> tuple[Path, float, np.ndarray]:
    """The database, the first day's start and each day's form error."""
    tmp = tmp_path_factory.mktemp("solar")
    series = at_site(load_weather("kma-suwon-2008-12"), PANEL)
    first = solar_day_start_s(float(series.time_s[0]), PANEL.site.longitude_deg) + DAY
    t = first + STEP_S * np.arange(int(DAYS * DAY / STEP_S))
    samples = _weather_samples(t)
    phi = np.resize(np.arange(-54.0, 55.0, 18.0), t.size)  # a step every 10 min
    store = Store.open(tmp)
    store.begin_run(panel=PANEL.panel.id, mode="test", version="0", config_path=None)
    for c, ti in enumerate(t):
        store.append(CycleRecord(
            cycle=c + 1, time_s=float(ti),
            samples=[(k, float(v[c]), "good", "") for k, v in samples.items()],
            decision={"slot": c, "time_s": float(ti), "time_utc": "t", "method": "mpc",
                      "phi_deg": float(phi[c]), "afr": 10, "or_pct": 0.0,
                      "write_status": "dry-run", "cycle_ms": 1.0},
            model={"applied_phi_deg": float(phi[c]), "applied_afr": 10,
                   "applied_or_pct": 0.0}))
    store.close()
    # the sun the model computes from what was stored, as the detector recomputes it
    steps = step_data(PANEL, measured_from_history(read_history(tmp)))
    sources = np.asarray(steps.inputs.sources)[:, :4]
    day = ((steps.time_s[:-1] - first) // DAY).astype(int)
    rng = np.random.default_rng(3)
    form = rng.normal(-0.02, 0.02, DAYS)  # each day's own solar form error
    q = -(_lost(steps.time_s[:-1], first) + form[day])[:, None] * sources \
        + rng.normal(0.0, 2.0, sources.shape)
    with sqlite3.connect(tmp / "timeseries.sqlite") as conn:
        conn.executemany(
            "INSERT INTO parameters (run_id, cycle, time_s, source, other) "
            "VALUES (1, ?, ?, 'online', ?)",
            [(c + 1, float(ti), json.dumps(dict(zip(OFFSET_NAMES, map(float, q[c]), strict=True))))
             for c, ti in enumerate(steps.time_s[:-1])])
    return tmp / "timeseries.sqlite", first, form


def _lost(time_s: np.ndarray, first: float) -> np.ndarray:
    """The share of the sun lost to dirt [-]: 10 % a week from the onset."""
    return np.clip((time_s - (first + ONSET_DAY * DAY)) / DAY * LOSS_PER_DAY, 0.0, 1.0)


def test_the_days_give_the_lost_share_back(soiled):
    db, first, form = soiled
    conn = sqlite3.connect(db)
    try:
        days = SolarDays(PANEL, db.parent).days(conn, first + DAYS * DAY)
    finally:
        conn.close()
    # overcast days have no value; the record has both kinds
    assert 8 <= len(days) < DAYS
    for d in days:
        k = int((d.time_s - first) // DAY)
        # the day's share is its S²-weighted mean: the loss within an hour of solar noon
        mid = first + k * DAY + np.array([11.0, 13.0]) * 3600.0
        expected = -(form[k] + _lost(mid, first))
        # within 4 of its standard errors (the offsets' noise of 2 W/m² a step)
        slack = 4.0 * d.sd
        assert expected.min() - slack <= d.factor <= expected.max() + slack, k
        assert d.sd < 0.05
        if d.sd < 0.005:  # a clear day: each node alone gives the same share
            for node in (0, 3):
                assert d.node_factors[node] == pytest.approx(d.factor, abs=0.02)


def _copy(db: Path, tmp_path: Path) -> Path:
    """A state directory with a copy of the module's database (a check stores findings)."""
    state = tmp_path / "state"
    state.mkdir()
    src, dst = sqlite3.connect(db), sqlite3.connect(state / "timeseries.sqlite")
    try:
        src.backup(dst)
    finally:
        src.close()
        dst.close()
    return state


def test_dirt_is_found_after_it_began_and_named(soiled, tmp_path):
    db, first, _ = soiled
    db = _copy(db, tmp_path) / "timeseries.sqlite"
    onset = first + ONSET_DAY * DAY
    stage = FindingsStage(db, run_id=lambda: 1, panel=PANEL)
    conn = sqlite3.connect(db)
    opened = []
    try:
        for now in np.arange(first + DAY, first + DAYS * DAY, SOLAR_EVERY_S):
            changes = stage.check(conn, float(now))
            opened += [(now, f) for f in changes.opened if f.kind == "solar_gain_shift"]
    finally:
        conn.close()
    assert opened, "the dirt was not found"
    now, f = opened[0]
    # after the onset (never before), within the 12 days of dirt the record holds; how
    # soon on the truth plant is the diagnostics bench's to say
    assert onset < f.detected_s <= now
    assert f.start_s >= onset - DAY
    assert "dirt on the exterior glass; clean it" in f.action
    assert f.evidence[0].signal == "solar_response" and f.evidence[0].shift < -0.03


def test_the_report_draws_the_days_the_detector_judged(soiled, tmp_path):
    """The report's diagnostics section draws a stored solar finding from the stored rows
    (with the panel's configuration: the days are recomputed from the weather and the
    commands); without a configuration it says why there is no figure."""
    db, first, _ = soiled
    state = _copy(db, tmp_path)
    stage = FindingsStage(state / "timeseries.sqlite", run_id=lambda: 1, panel=PANEL)
    conn = sqlite3.connect(state / "timeseries.sqlite")
    try:
        for now in np.arange(first + DAY, first + DAYS * DAY, SOLAR_EVERY_S):
            stage.check(conn, float(now))
    finally:
        conn.close()
    history = read_history(state)
    drawn = build_diagnostics(history, dataclasses.asdict(PANEL), offset_h=9.0, dpi=40)
    solar = [r for r in drawn.findings if r["kind"] == "solar_gain_shift"]
    assert len(solar) == 1
    fid = int(solar[0]["finding_id"])
    assert fid in drawn.figures and "share of the sun" in drawn.figures[fid].caption
    bare = build_diagnostics(history, None, offset_h=9.0, dpi=40)
    assert "configuration" in bare.no_figure[fid]


def test_a_solar_detector_that_fails_leaves_the_other_detectors_and_its_findings(
        soiled, tmp_path):
    """A store the solar detector cannot read (here: any error from it) is logged and
    counted; the check itself goes on, and an open solar finding is not ended by a check
    in which the detector did not run."""
    db, first, _ = soiled
    db = _copy(db, tmp_path) / "timeseries.sqlite"
    stage = FindingsStage(db, run_id=lambda: 1, panel=PANEL)
    conn = sqlite3.connect(db)
    try:
        for now in np.arange(first + DAY, first + DAYS * DAY, SOLAR_EVERY_S):
            stage.check(conn, float(now))
        assert [f for f in table.load(conn) if f.kind == "solar_gain_shift"
                and f.state == "open"]

        def broken(*_args: object) -> None:
            raise KeyError("x4_c")

        stage.solar.finding = broken  # type: ignore[union-attr, method-assign]
        for k in range(1, 9):  # two days of checks, longer than the release delay
            changes = stage.check(conn, first + DAYS * DAY + k * SOLAR_EVERY_S)
            assert not [f for f in changes.ended]
        assert stage.failures == 8
        assert [f for f in table.load(conn) if f.kind == "solar_gain_shift"
                and f.state == "open"]
    finally:
        conn.close()
