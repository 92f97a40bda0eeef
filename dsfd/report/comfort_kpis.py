"""The comfort figures of a span of cycles (a local day), from the ``comfort`` table's rows
(schema 6, docs/storage-schema.md): what the MQTT ``kpi`` topic and the report's day table
show (issue 36). Pure numpy.

Each cycle stands for one cycle period (``step_s``) of its occupancy. A figure counts only
occupied cycles, because no comfort limit applies to an empty room, and compares each
quantity with the limit stored *with it* (the limits in force at that cycle):

* ``occupied_min`` — occupied time;
* ``occupied_direct_sun_min`` — occupied time with the unscattered beam into the room above
  ``direct_sun_max_wm2``;
* ``dgp_p95`` — the 95th percentile of the simplified daylight glare probability over the
  occupied cycles (EN 17037's glare criterion is met when DGP ≤ the class limit for 95 % of
  the occupied time), and ``dgp_above_limit_pct`` the share of those cycles above
  ``dgp_max`` [%];
* ``supply_air_below_limit_min`` — occupied time with air blown into the room colder than
  ``supply_air_min_c``;
* ``asymmetry_beyond_limit_min`` — occupied time with the pane's radiant asymmetry beyond
  ``asymmetry_max_k``.

Cycles whose quantities could not be computed (no forecast, no state estimate) count as
occupied time but in no other figure; ``comfort_unknown_min`` says how much that was.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["COMFORT_KPI_KEYS", "comfort_kpis"]

#: Keys of :func:`comfort_kpis`, in the order they are published.
COMFORT_KPI_KEYS = ("occupied_min", "occupied_direct_sun_min", "dgp_p95",
                    "dgp_above_limit_pct", "supply_air_below_limit_min",
                    "asymmetry_beyond_limit_min", "comfort_unknown_min")


def _column(rows: Sequence[Mapping[str, Any]], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else float(r[key]) for r in rows], float)


def comfort_kpis(rows: Sequence[Mapping[str, Any]], *, step_s: float) -> dict[str, Any]:
    """The figures of the module docstring over ``rows`` (one per cycle) [min, 1, %]."""
    minutes = step_s / 60.0
    occ = np.array([bool(r.get("occupied")) for r in rows], bool)
    sun, dgp = _column(rows, "direct_sun_wm2"), _column(rows, "dgp")
    air, asym = _column(rows, "supply_air_c"), _column(rows, "asymmetry_k")
    with np.errstate(invalid="ignore"):  # NaN compares False: an unknown is no exceedance
        sun_over = occ & (sun > _column(rows, "direct_sun_max_wm2"))
        dgp_over = occ & (dgp > _column(rows, "dgp_max"))
        air_under = occ & (air < _column(rows, "supply_air_min_c"))
        asym_over = occ & (np.abs(asym) > _column(rows, "asymmetry_max_k"))
    dgp_occ = dgp[occ & np.isfinite(dgp)]
    return {
        "occupied_min": float(occ.sum() * minutes),
        "occupied_direct_sun_min": float(sun_over.sum() * minutes),
        "dgp_p95": float(np.percentile(dgp_occ, 95)) if dgp_occ.size else None,
        "dgp_above_limit_pct": float(100.0 * dgp_over.sum() / dgp_occ.size)
        if dgp_occ.size else None,
        "supply_air_below_limit_min": float(air_under.sum() * minutes),
        "asymmetry_beyond_limit_min": float(asym_over.sum() * minutes),
        "comfort_unknown_min": float((occ & ~np.isfinite(dgp)).sum() * minutes),
    }
