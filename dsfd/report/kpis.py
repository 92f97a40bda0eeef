"""What the controller did, as numbers: the report's key figures from a state directory's
history (:class:`~dsfd.storage.history.History`). Pure numpy; the figures and the HTML are
:mod:`dsfd.report.figures` and :mod:`dsfd.report.html`.

Conventions
-----------
* Days are local standard time of the panel (``site.utc_offset_h``, no daylight saving):
  a façade's day, not a UTC day that splits it.
* The model's heat terms of a cycle are the step that *ended* at that cycle (the observer's
  one-step prediction from the previous estimate with the position actually applied);
  a simulated plant's are the differences of its cumulative integrals between cycles.
* One-step prediction error at cycle k: |prediction made at k − 1 − reading at k|;
  persistence on the same cycles: |last good reading at or before k − 1 − reading at k|
  (the definition of ``dsfd validate``). Horizon error: the horizon-end prediction made at
  k (applied position held, weather forecast) against the reading ``horizon_s`` later.
  A step counts only if it is one sampling interval long (no gap), as in ``validate``.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dsfd.report.regime_errors import errors_by_regime
from dsfd.storage.history import History
from dsfd.storage.schema import HEAT_TERMS as HEAT_TERM_KEYS

__all__ = ["HEAT_TERMS", "STATES", "Kpis", "PredictionErrors", "compute_kpis", "local_dates",
           "local_day", "prediction_errors", "report_step_s", "zone_name"]

STATES = ("x1", "x2", "x3", "x4", "x5")
_HEAT_LABELS = {"q_cv_rd": "Q_cv,rd convection + long-wave",
                "q_sol_trans": "Q_sol transmitted solar", "q_air": "Q_air ventilation air",
                "q_da": "Q_DA daylight credit"}
#: Room-side heat terms: key, label (docs/model.md#room-heat), in the model table's order.
HEAT_TERMS: tuple[tuple[str, str], ...] = tuple((k, _HEAT_LABELS[k]) for k in HEAT_TERM_KEYS)
J_PER_KWH = 3.6e6
#: A step counts as one sampling interval within this relative tolerance (as in validate).
SPACING_TOLERANCE = 0.02
#: A parameter within this fraction of its bound's range "sits at the bound".
AT_BOUND_FRACTION = 1e-3


def _get(doc: Mapping[str, Any] | None, *keys: str, default: Any = None) -> Any:
    for key in keys:
        if not isinstance(doc, Mapping) or key not in doc:
            return default
        doc = doc[key]
    return doc if doc is not None else default


def zone_name(utc_offset_h: float) -> str:
    """``UTC+09:00`` for an offset of 9 h."""
    sign = "+" if utc_offset_h >= 0 else "-"
    h, m = divmod(round(abs(utc_offset_h) * 60), 60)
    return f"UTC{sign}{h:02d}:{m:02d}"


def local_dates(time_s: np.ndarray | float, utc_offset_h: float) -> np.ndarray:
    """Local standard calendar day (``datetime64[D]``) of each UTC time [s]; a scalar time
    gives a 0-d array (``.item()`` is its :class:`datetime.date`)."""
    t = np.asarray(time_s, float) + utc_offset_h * 3600.0
    return np.floor(t / 86400.0).astype("int64").astype("datetime64[D]")


def local_day(time_s: np.ndarray, utc_offset_h: float) -> np.ndarray:
    """Local standard date (``YYYY-MM-DD``) of each UTC time [s]."""
    return local_dates(time_s, utc_offset_h).astype(str)


def report_step_s(history: History, config: Mapping[str, Any] | None) -> float:
    """The cycle period [s]: the configuration's model step, else the median spacing."""
    step = _get(config, "model", "step_s")
    if step:
        return float(step)
    d = np.diff(history.time_s)
    d = d[(d > 0) & (np.diff(history.run_id) == 0)]
    return float(np.median(d)) if d.size else 60.0


def _one_step(history: History, step_s: float) -> np.ndarray:
    """True at cycles whose previous row is the previous sampling instant (no gap)."""
    ok = np.zeros(len(history), bool)
    if len(history) > 1:
        spacing = np.diff(history.time_s)
        ok[1:] = np.abs(spacing - step_s) <= SPACING_TOLERANCE * step_s
    return ok


def _held(y: np.ndarray) -> np.ndarray:
    """The last finite value at or before each row (NaN before the first)."""
    idx = np.where(np.isfinite(y), np.arange(y.shape[0]), -1)
    idx = np.maximum.accumulate(idx) if idx.size else idx
    return np.where(idx >= 0, y[np.maximum(idx, 0)], np.nan)


@dataclass(frozen=True, eq=False)
class PredictionErrors:
    """Absolute prediction errors per cycle (NaN where not scored).

    ``model``/``persistence``: per output (``x1``…``x5`` [K], ``v`` [m/s]) an array of the
    one-step errors at each cycle; ``horizon_model``/``horizon_persistence``: the horizon
    errors, placed at the cycle the prediction was made.
    """

    model: dict[str, np.ndarray]
    persistence: dict[str, np.ndarray]
    horizon_model: dict[str, np.ndarray]
    horizon_persistence: dict[str, np.ndarray]
    horizon_steps: int
    #: The one-step errors with their sign, prediction − reading (the model's bias).
    model_signed: dict[str, np.ndarray] = field(default_factory=dict)


def prediction_errors(history: History, step_s: float) -> PredictionErrors:
    """One-step and horizon errors of the daemon's model and of persistence (module doc)."""
    n = len(history)
    one = _one_step(history, step_s)
    model: dict[str, np.ndarray] = {}
    signed: dict[str, np.ndarray] = {}
    persist: dict[str, np.ndarray] = {}
    outputs = [(s, f"{s}_c", f"pred_{s}_c") for s in STATES] + [("v", "v_cav_ms",
                                                                 "pred_v_cav_ms")]
    for key, signal, pred_col in outputs:
        y = history.good(signal)
        if key == "v":
            y = np.abs(y)
        pred = history.model[pred_col]
        prev_held = np.full(n, np.nan)
        prev_held[1:] = _held(y)[:-1]
        scored = one & np.isfinite(y) & np.isfinite(pred) & np.isfinite(prev_held)
        signed[key] = np.where(scored, pred - y, np.nan)
        model[key] = np.abs(signed[key])
        persist[key] = np.where(scored, np.abs(prev_held - y), np.nan)
    horizon = history.model["horizon_s"]
    h_s = float(np.nanmedian(horizon)) if np.isfinite(horizon).any() else math.nan
    h_steps = round(h_s / step_s) if math.isfinite(h_s) else 0
    hz_model: dict[str, np.ndarray] = {}
    hz_persist: dict[str, np.ndarray] = {}
    target = np.full(n, -1)
    if h_steps > 0 and n:
        # The row h_steps later, if every step in between is one interval (no gap).
        later = np.arange(n) + h_steps
        inside = later < n
        gaps = np.concatenate([[0], np.cumsum(~one[1:])])  # gaps up to each row
        ok = inside.copy()
        ok[inside] = (gaps[later[inside]] == gaps[np.arange(n)[inside]]) & \
            (history.run_id[later[inside]] == history.run_id[inside])
        target = np.where(ok, later, -1)
    for key, signal, _ in outputs[:5]:
        y = history.good(signal)
        held = _held(y)
        hz = history.model[f"hz_{key}_c"]
        y_t = np.where(target >= 0, y[np.maximum(target, 0)], np.nan)
        scored = np.isfinite(y_t) & np.isfinite(hz) & np.isfinite(held)
        hz_model[key] = np.where(scored, np.abs(hz - y_t), np.nan)
        hz_persist[key] = np.where(scored, np.abs(held - y_t), np.nan)
    return PredictionErrors(model, persist, hz_model, hz_persist, h_steps, signed)


@dataclass
class DayKpis:
    """Key figures of one local day (or of the whole report: ``day = "total"``)."""

    day: str
    cycles: int = 0
    hours: float = 0.0
    methods: Counter[str] = field(default_factory=Counter)
    louver_moves: int = 0
    damper_moves: int = 0
    flagged: int = 0
    write_failures: int = 0
    decide_ms_p50: float = math.nan
    decide_ms_p99: float = math.nan
    calibration_updates: int = 0
    heat_model_kwh: dict[str, float] = field(default_factory=dict)
    heat_model_hours: float = 0.0
    heat_plant_kwh: dict[str, float] | None = None


@dataclass
class Kpis:
    """Everything the report's tables show (see :func:`compute_kpis`)."""

    days: list[DayKpis]
    total: DayKpis
    flagged: dict[tuple[str, str], int]
    at_bound: list[dict[str, Any]]
    errors: dict[str, dict[str, float]]
    horizon_steps: int
    step_s: float
    utc_offset_h: float
    #: One-step errors per airflow regime (:func:`dsfd.report.regime_errors.errors_by_regime`).
    errors_by_regime: list[dict[str, Any]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready figures (``dsfd report --json``)."""
        def day(d: DayKpis) -> dict[str, Any]:
            out = {k: v for k, v in vars(d).items() if k != "methods"}
            out["methods"] = dict(d.methods)
            return out

        return {"days": [day(d) for d in self.days], "total": day(self.total),
                "flagged": [{"signal": s, "quality": q, "samples": n}
                            for (s, q), n in sorted(self.flagged.items())],
                "parameters_at_bound": self.at_bound, "prediction_errors": self.errors,
                "prediction_errors_by_regime": self.errors_by_regime,
                "horizon_steps": self.horizon_steps, "step_s": self.step_s,
                "utc_offset_h": self.utc_offset_h}


def _moves(values: list[np.ndarray], run_id: np.ndarray) -> np.ndarray:
    """True at cycles where any of ``values`` changed since the previous cycle of the run."""
    moved = np.zeros(run_id.shape[0], bool)
    if run_id.size < 2:
        return moved
    same_run = run_id[1:] == run_id[:-1]
    for v in values:
        a, b = v[:-1], v[1:]
        moved[1:] |= same_run & np.isfinite(a) & np.isfinite(b) & (a != b)
    return moved


def _plant_heat(history: History, day: np.ndarray, mid_day: np.ndarray
                ) -> dict[str, dict[str, float]] | None:
    """Per day and term, the simulated plant's heat [kWh] from its cumulative integrals."""
    cols = {k: history.model[f"plant_{k}_j"] for k, _ in HEAT_TERMS}
    if not any(np.isfinite(c).any() for c in cols.values()):
        return None
    same = np.zeros(len(history), bool)
    same[1:] = history.run_id[1:] == history.run_id[:-1]
    out: dict[str, dict[str, float]] = {}
    for k, c in cols.items():
        d = np.full(len(history), np.nan)
        d[1:] = c[1:] - c[:-1]
        d = np.where(same, d, np.nan)
        for name in np.unique(day):
            out.setdefault(name, {})[k] = float(np.nansum(d[mid_day == name])) / J_PER_KWH
    return out


def _at_bound(history: History, config: Mapping[str, Any] | None, end_s: float
              ) -> list[dict[str, Any]]:
    """Parameters that sat at a bound: name, bound, hours, first time."""
    p = history.parameters
    out: list[dict[str, Any]] = []
    if not len(p) or config is None:
        return out
    offset_bound = _get(config, "calibration", "offset_bound_wm2")
    # A row is in force until the next one, but not past the last cycle of its run (the
    # time the daemon was down is no time at a bound).
    run_end = {int(r): float(history.time_s[history.run_id == r].max())
               for r in np.unique(history.run_id)}
    ends = np.array([run_end.get(int(r), end_s) for r in p.run_id])
    until = np.minimum(np.append(p.time_s[1:], np.inf), ends)
    start = float(history.time_s[0])
    durations = np.clip(until - np.clip(p.time_s, start, None), 0.0, None)
    for name, values in p.values.items():
        bounds = _get(config, "parameters", name)
        if isinstance(bounds, Mapping):
            lo, hi = float(bounds["lower"]), float(bounds["upper"])
        elif name.startswith("q_") and offset_bound:
            lo, hi = -float(offset_bound), float(offset_bound)
        else:
            continue
        tol = AT_BOUND_FRACTION * (hi - lo)
        for label, bound in (("lower", lo), ("upper", hi)):
            sits = np.isfinite(values) & (np.abs(values - bound) <= tol)
            if sits.any():
                out.append({"parameter": name, "bound": label, "value": bound,
                            "hours": float(durations[sits].sum() / 3600.0),
                            "first_utc_s": float(p.time_s[sits][0])})
    return out


def _summary_errors(err: PredictionErrors) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    for key in (*STATES, "v"):
        row: dict[str, float] = {}
        m, q = err.model[key], err.persistence[key]
        row["h1_cycles"] = float(np.isfinite(m).sum())
        row["h1_model_mae"] = float(np.nanmean(m)) if np.isfinite(m).any() else math.nan
        row["h1_persistence_mae"] = float(np.nanmean(q)) if np.isfinite(q).any() else math.nan
        if key in err.horizon_model:
            hm, hq = err.horizon_model[key], err.horizon_persistence[key]
            row["horizon_cycles"] = float(np.isfinite(hm).sum())
            row["horizon_model_mae"] = (float(np.nanmean(hm)) if np.isfinite(hm).any()
                                        else math.nan)
            row["horizon_persistence_mae"] = (float(np.nanmean(hq)) if np.isfinite(hq).any()
                                              else math.nan)
        out[key] = row
    return out


def compute_kpis(history: History, config: Mapping[str, Any] | None,
                 errors: PredictionErrors | None = None) -> Kpis:
    """Per local day and in total (see the module docstring for the conventions)."""
    step_s = report_step_s(history, config)
    lon = _get(config, "site", "longitude_deg")
    offset = _get(config, "site", "utc_offset_h",
                  default=round(lon / 15.0) if lon is not None else 0.0)
    t = history.time_s
    day = local_day(t, offset)
    mid_day = local_day(t - 0.5 * step_s, offset)  # the step that ended at the cycle
    dec = history.decisions
    applied = history.applied()
    louver = _moves([applied["phi_deg"]], history.run_id)
    damper = _moves([applied["afr"], applied["or_pct"]], history.run_id)
    flagged_any = np.zeros(len(history), int)
    flagged: Counter[tuple[str, str]] = Counter()
    for signal, q in history.quality.items():
        bad = (q != "good") & (q != "")
        flagged_any += bad
        for flag in np.unique(q[bad]):
            flagged[(signal, str(flag))] += int(np.sum(q == flag))
    p = history.parameters
    updates_day = local_day(p.time_s, offset) if len(p) else np.array([], str)
    online = p.source == "online" if len(p) else np.array([], bool)
    inside = (p.time_s >= t[0]) & (p.time_s <= t[-1]) if len(p) else np.array([], bool)
    plant = _plant_heat(history, day, mid_day)

    def figures(name: str, sel: np.ndarray, sel_mid: np.ndarray) -> DayKpis:
        d = DayKpis(day=name, cycles=int(sel.sum()))
        d.hours = d.cycles * step_s / 3600.0
        d.methods = Counter(str(m) for m in dec["method"][sel])
        d.louver_moves = int(louver[sel].sum())
        d.damper_moves = int(damper[sel].sum())
        d.flagged = int(flagged_any[sel].sum())
        d.write_failures = int(np.sum(dec["write_status"][sel] == "failed"))
        ms = dec["decide_ms"][sel]
        ms = ms[np.isfinite(ms)]
        if ms.size:
            d.decide_ms_p50 = float(np.percentile(ms, 50))
            d.decide_ms_p99 = float(np.percentile(ms, 99))
        pick = inside & online & (np.isin(updates_day, [name]) if name != "total"
                                  else np.ones_like(online))
        d.calibration_updates = int(pick.sum())
        covered = np.zeros(len(history), bool)
        for k, _ in HEAT_TERMS:
            w = history.model[f"{k}_w"][sel_mid]
            covered[sel_mid] |= np.isfinite(history.model[f"{k}_w"][sel_mid])
            d.heat_model_kwh[k] = float(np.nansum(w) * step_s / J_PER_KWH)
        d.heat_model_hours = float(covered.sum() * step_s / 3600.0)
        if plant is not None:
            names = [name] if name != "total" else list(plant)
            d.heat_plant_kwh = {k: sum(plant[n].get(k, 0.0) for n in names if n in plant)
                                for k, _ in HEAT_TERMS}
        return d

    days = [figures(name, day == name, mid_day == name) for name in np.unique(day)]
    everything = np.ones(len(history), bool)
    total = figures("total", everything, everything)
    err = errors if errors is not None else prediction_errors(history, step_s)
    return Kpis(days=days, total=total, flagged=dict(flagged),
                at_bound=_at_bound(history, config, float(t[-1])),
                errors=_summary_errors(err), horizon_steps=err.horizon_steps, step_s=step_s,
                utc_offset_h=float(offset), errors_by_regime=errors_by_regime(history, err))
