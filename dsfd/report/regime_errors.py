"""One-step prediction errors per airflow regime: where the model loses to persistence.

A lumped model's form error depends on the regime (the air's path, its speed), and an error
in one regime hides in the run's mean when another regime dominates the run. Each scored
cycle belongs to the regime applied over the step it predicts (the previous cycle's
applied regime); the steps right after a regime change form a row of their own, since the
change itself moves every node faster than any steady step does (docs/model.md#identifiability
has a run where the louver's mean error was regime 1's).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from dsfd.config.panel import REGIME_NAMES
from dsfd.storage.history import History

if TYPE_CHECKING:
    from dsfd.report.kpis import PredictionErrors

__all__ = ["AFTER_A_CHANGE", "errors_by_regime"]

#: The ``regime`` of the row of steps right after a regime change.
AFTER_A_CHANGE = "after a change"


def _interval_regimes(history: History) -> tuple[np.ndarray, np.ndarray]:
    """The regime over the step ending at each cycle, and whether it changed at its start."""
    afr = history.applied()["afr"]
    n = afr.shape[0]
    over = np.full(n, np.nan)
    before = np.full(n, np.nan)
    over[1:] = afr[:-1]
    before[2:] = afr[:-2]
    same_run = np.zeros(n, bool)
    same_run[2:] = (history.run_id[2:] == history.run_id[1:-1]) & \
        (history.run_id[1:-1] == history.run_id[:-2])
    changed = same_run & np.isfinite(over) & np.isfinite(before) & (over != before)
    return over, changed


def _row(errors: PredictionErrors, sel: np.ndarray) -> dict[str, Any]:
    row: dict[str, Any] = {}
    for key, abs_err in errors.model.items():
        m = abs_err[sel]
        q = errors.persistence[key][sel]
        e = errors.model_signed.get(key, np.full(abs_err.shape, np.nan))[sel]
        ok = np.isfinite(m) & np.isfinite(q)
        if not ok.any():
            continue
        row[key] = {"cycles": int(ok.sum()), "model_mae": float(m[ok].mean()),
                    "persistence_mae": float(q[ok].mean()),
                    "model_mean_error": float(np.nanmean(e[ok])) if np.isfinite(e[ok]).any()
                    else float("nan")}
    return row


def errors_by_regime(history: History, errors: PredictionErrors) -> list[dict[str, Any]]:
    """Per regime applied over the predicted step (steady steps only), then the steps right
    after a change: ``regime`` (int, or :data:`AFTER_A_CHANGE`), ``name`` and per output
    (``x1``…``x5`` [K], ``v`` [m/s]) its ``cycles``, ``model_mae``, ``persistence_mae`` and
    ``model_mean_error`` (prediction − reading: + the model runs warm). Outputs without a
    scored cycle in a row are left out of it; rows without any are not listed."""
    if len(history) < 2:
        return []
    over, changed = _interval_regimes(history)
    out: list[dict[str, Any]] = []
    for regime in np.unique(over[np.isfinite(over)]):
        row = _row(errors, (over == regime) & ~changed)
        if row:
            r = int(regime)
            out.append({"regime": r, "name": REGIME_NAMES.get(r, ""), "outputs": row})
    row = _row(errors, changed)
    if row:
        out.append({"regime": AFTER_A_CHANGE, "name": "the step after a regime change",
                    "outputs": row})
    return out
