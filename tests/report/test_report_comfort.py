"""The report's comfort figure: in the page, and its quantities recomputed from a log."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from dsfd.config.comfort import Occupancy
from dsfd.measured import parse_iso_utc
from dsfd.report.comfort_figure import _panel, logged_comfort
from dsfd.report.kpis import compute_kpis
from dsfd.report.plotting import Context
from dsfd.sim.closed_loop import _controller_config

NOON, NIGHT = parse_iso_utc("2022-01-02T03:30:00Z"), parse_iso_utc("2022-01-02T14:00:00Z")


def test_the_comfort_figure_is_in_the_page(faulted_run):
    html = faulted_run.html.read_text()
    fig = re.search(r'<figure id="fig-comfort">(.*?)</figure>', html, re.S)
    assert fig is not None
    assert 'src="data:image/png;base64,' in fig.group(1)
    assert "Occupant comfort" in fig.group(1) and "occupied" in fig.group(1)


def test_glare_and_direct_sun_follow_the_louver_and_the_sun(suwon):
    cfg = dataclasses.replace(suwon, occupancy=Occupancy(sun=("08:00-18:00",)))
    t = np.array([NOON, NOON, NOON, NIGHT])  # Sunday 12:30 and 23:00 local (UTC+9)
    c = logged_comfort(cfg, t, t_out_c=np.full(4, 2.0), ghi_wm2=np.array([500.0] * 3 + [0.0]),
                       phi_deg=np.array([90.0, -90.0, 18.0, 18.0]))
    assert c.occupied.tolist() == [True, True, True, False]
    # Closed either way, no beam enters; along the noon sun it does.
    assert c.direct_sun_wm2[0] == pytest.approx(0.0, abs=1e-9)
    assert c.direct_sun_wm2[1] == pytest.approx(0.0, abs=1e-9)
    assert c.direct_sun_wm2[2] > 50.0 and c.dgp[2] > c.dgp_limit
    # At night: no light, Wienold's intercept; no sun, no cut-off.
    assert c.dgp[3] == pytest.approx(0.184) and np.isnan(c.cutoff_lower_deg[3])
    # At noon in January the sun's profile on a south façade is about 30 deg: the lower
    # cut-off of 5 cm slats at 4.5 cm pitch is well below it and the upper above it.
    assert -40.0 < c.cutoff_lower_deg[0] < 0.0 < 60.0 < c.cutoff_upper_deg[0] < 90.0


def test_a_missing_reading_is_no_value_not_a_dark_sky(suwon):
    t = np.array([NOON, NOON])
    c = logged_comfort(suwon, t, t_out_c=np.array([2.0, np.nan]),
                       ghi_wm2=np.array([500.0, 500.0]), phi_deg=np.array([18.0, 18.0]))
    assert np.isfinite(c.dgp[0]) and np.isnan(c.dgp[1]) and np.isnan(c.direct_sun_wm2[1])


def test_a_closed_loop_log_with_lifted_budgets_is_drawn(suwon, faulted_run):
    """A closed-loop simulation stores its panel with the stage budgets lifted beyond their
    bounds; the figure still rebuilds the sections it needs."""
    from dsfd.storage.history import read_history

    history = read_history(faulted_run.state_dir)
    lifted = dataclasses.asdict(_controller_config(suwon, "mpc"))
    kpis = compute_kpis(history, lifted, None)
    cfg, why = _panel(Context(history, kpis, None, lifted, 60))
    assert cfg is not None, why
    assert cfg.occupancy == suwon.occupancy and cfg.comfort == suwon.comfort
