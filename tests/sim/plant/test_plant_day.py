"""A day of the default truth plant under the paper protocol: energy balance and velocities.

One run (default options, N = 10) serves three checks:

* docs/model.md#energy-balance: |ΔU − ∫(S_abs + Q_bnd,in + H_in − H_out) dt| < 1e-3 max(∫S_abs,
  ∫|Q_bnd|);
* the measured-data table the run produces is consistent (names, NaN-free, monotone time).

A second run replays the paper's own airflow experiment, 8–11 December 2008 in Suwon
(weather reconstructed from KMA's daily statistics, :mod:`dsfd.weather.daily`): the mean
cavity velocity of each regime of the paper's Table 1 lies in its 2–15 cm/s range. The
plant is the centre of the true-parameter prior (docs/model.md#true-parameters) (all h
multipliers 1, f_true = √(20·2000) = 200), not fitted to the table. The velocities scale with f_true
and with the stack and wind pressures of the weather: colder or windier days, or a small f_true,
give more.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.bench.velocity import PAPER_DAYS, PAPER_START_DAY, PAPER_WEATHER
from dsfd.measured import EXTRA_PREFIX, KNOWN_COLUMNS
from dsfd.sim.plant.config import TrueParameters
from dsfd.sim.plant.sensors import SENSOR_NAMES
from dsfd.sim.protocol import PAPER_REGIMES
from dsfd.sim.replay import at_site, load_weather
from dsfd.sim.truth_run import run_truth, summarize_truth, velocity_table
from tests.sim.conftest import day_start

F_CENTRE = math.sqrt(20.0 * 2000.0)


def _prior_centre(cfg) -> TrueParameters:
    p = cfg.parameters
    return TrueParameters(h_multipliers=(1.0,) * 6, f=F_CENTRE, c=p.c.default, n=p.n.default)


def test_prior_centre_is_the_geometric_centre_of_the_e16_prior(suwon):
    """The benches' nominal plant (``--prior-centre``) is the one these tests build by hand:
    multipliers 1 and f_true = √(20·2000), the centre of docs/model.md#true-parameters's log-uniform
    range."""
    assert TrueParameters.prior_centre(suwon) == _prior_centre(suwon)


@pytest.fixture(scope="module")
def day_run(suwon, rmis):
    return run_truth(suwon, rmis, seed=0, hours=24.0, start_s=day_start(rmis, 2),
                     params=_prior_centre(suwon))


@pytest.fixture(scope="module")
def paper_period_run(suwon):
    kma = at_site(load_weather(PAPER_WEATHER), suwon)
    return run_truth(suwon, kma, seed=0, hours=24.0 * PAPER_DAYS,
                     start_s=day_start(kma, PAPER_START_DAY), params=_prior_centre(suwon))


def test_energy_balance_closes_over_the_day(day_run):
    eb = day_run.plant.energy_balance()
    assert eb["solar_j"] > 1e6  # a sunny day: ≈ MJ absorbed
    assert abs(eb["residual_j"]) < 1e-3 * eb["scale_j"], eb
    # The balance is not trivially zero: heat stored, lost and carried by the air.
    assert abs(eb["boundary_j"]) > 1e5 and abs(eb["enthalpy_j"]) > 1e5


@pytest.mark.slow  # its fixture runs the plant over the paper's four days: 20-35 s
def test_mean_velocity_per_regime_is_in_the_papers_range(paper_period_run):
    assert paper_period_run.steps == 4 * 1440
    table = velocity_table(paper_period_run.data)
    assert set(table) == set(PAPER_REGIMES)
    for regime, row in table.items():
        assert row["samples"] > 60, (regime, row)
        for key in ("true_ms", "anemometer_ms"):
            assert 0.02 <= row[key] <= 0.15, (regime, key, row)
    # Exhaust (5) is the fastest, as in the paper (14.1 cm/s).
    assert table[5]["true_ms"] == max(r["true_ms"] for r in table.values())


def test_run_table_and_summary(day_run):
    d = day_run.data
    assert len(d) == day_run.steps + 1 == 1441
    assert np.all(np.diff(d.time_s) == 60.0)
    names = set(d.columns)
    assert set(SENSOR_NAMES) <= names
    assert {"phi_deg", "afr", "or_pct"} <= names
    assert all(n in KNOWN_COLUMNS or n.startswith(EXTRA_PREFIX) for n in names)
    assert all(np.isfinite(d.get(n)).all() for n in SENSOR_NAMES)
    s = summarize_truth(day_run)
    assert s["commands"] == len(day_run.schedule) >= 16
    assert s["energy_balance"]["residual_rel"] < 1e-3
    assert set(s["realised_regimes"]) <= {str(r) for r in range(1, 11)}
    # The louver follows the protocol's angles (on the 18° grid after each move).
    assert set(np.unique(d.get("phi_deg"))) <= set(day_run.cfg.louver.angles_deg())
