"""The day's comfort figures (issue 36) from comfort rows written out by hand: each figure
counted here cycle by cycle, against the limit stored in the row."""

from __future__ import annotations

from typing import Any

import pytest

from dsfd.report.comfort_kpis import COMFORT_KPI_KEYS, comfort_kpis

LIMITS = {"direct_sun_max_wm2": 5.0, "dgp_max": 0.35, "supply_air_min_c": 18.0,
          "asymmetry_max_k": 10.0}


def row(occupied: bool, dgp: float | None, *, sun: float = 0.0, air: float | None = None,
        asym: float = 0.0, **limits: float) -> dict[str, Any]:
    return {"occupied": occupied, "dgp": dgp, "direct_sun_wm2": None if dgp is None else sun,
            "supply_air_c": air, "asymmetry_k": None if dgp is None else asym,
            **LIMITS, **limits}


def test_figures_count_occupied_cycles_against_their_own_limits() -> None:
    # 21 occupied cycles with DGPs 0.20, 0.21 … 0.40: the 95th percentile (linear between
    # order statistics, rank 0.95 · 20 = 19) is the 20th value, 0.39; five lie above 0.35.
    rows = [row(True, round(0.20 + 0.01 * k, 2)) for k in range(21)]
    rows[0].update(direct_sun_wm2=5.0)        # at the limit: not beyond it
    rows[1].update(direct_sun_wm2=40.0)       # direct sun on the desk
    rows[2].update(supply_air_c=12.0)         # draught
    rows[3].update(supply_air_c=18.0)         # at the limit: fine
    rows[4].update(asymmetry_k=-11.0)         # a cold pane, beyond the limit
    rows[5].update(asymmetry_k=12.0, asymmetry_max_k=23.0)  # warm wall: its own limit
    rows += [row(False, 0.9, sun=300.0, air=5.0, asym=30.0)] * 4  # nobody there: no count
    rows += [row(True, None)] * 2             # quantities unknown
    k = comfort_kpis(rows, step_s=120.0)      # two-minute cycles
    assert tuple(k) == COMFORT_KPI_KEYS
    assert k["occupied_min"] == 23 * 2.0
    assert k["occupied_direct_sun_min"] == 2.0
    assert k["dgp_p95"] == pytest.approx(0.39)
    assert k["dgp_above_limit_pct"] == pytest.approx(100.0 * 5 / 21)  # 0.36 … 0.40
    assert k["supply_air_below_limit_min"] == 2.0
    assert k["asymmetry_beyond_limit_min"] == 2.0
    assert k["comfort_unknown_min"] == 4.0


def test_an_empty_or_unoccupied_day_has_no_glare_figures() -> None:
    for rows in ([], [row(False, 0.5)] * 3):
        k = comfort_kpis(rows, step_s=60.0)
        assert k["occupied_min"] == 0.0 and k["dgp_p95"] is None
        assert k["dgp_above_limit_pct"] is None
