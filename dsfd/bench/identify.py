"""``dsfd bench identify``: does the on-line calibration find the parameters, and does the
model it calibrates beat persistence? (docs/benchmarks-identify.md)

The daemon's own loop runs against a simulated plant per seed (:mod:`dsfd.bench.identify_run`);
this module turns what it left into figures. Per parameter of ϑ = (θ, q):

* **relative error** (lumped-equivalent plant only, where the true θ is known):
  |θ̂/θ_true − 1|, its median over the last day's cycles and its value at the last cycle;
* **share of cycles at a bound**: θ̂ within :data:`AT_BOUND_REL_TOL` (relative) of the
  calibration's own lower or upper bound (:class:`~dsfd.estimation.params.ParameterSpace`);
* **posterior/prior sd**: the sd of the daemon's posterior over the first prior's sd, both
  in the fitting coordinates (log θ; n and q linear), median over the last day. A parameter
  is **determined** when that median is below :data:`DETERMINED_SD_RATIO`: the data, not
  the prior, fixed it. On the lumped plant also the error in posterior sds,
  |z(θ̂) − z(θ_true)|/σ_post (median over the last day): is the posterior honest?
* **day-to-day change**: the relative change of the daily median θ̂ between consecutive
  simulated days (days counted from the run's first cycle); absolute [W/m2] for the offsets;
* the offsets' size: median |q̂| over the last day [W/m2].

Per output (x1…x5 [K], cavity speed [m/s]): the mean absolute one-step and horizon
(``control.horizon_steps``, 15) errors of the model and of persistence, as ``dsfd report``
computes them from the daemon's database (:func:`dsfd.report.kpis.prediction_errors`), over
the whole run and over its last day.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from dsfd.bench.identify_run import RunSpec, SeedTrace, daemon_config, run_seed
from dsfd.bench.identify_targets import issue_targets
from dsfd.config.parameters import FIT_NAMES, N_PARAMS, OFFSET_NAMES, PARAMETER_NAMES
from dsfd.estimation.params import ParameterSpace, full_vector

__all__ = ["AT_BOUND_REL_TOL", "DAY_S", "DETERMINED_SD_RATIO", "OUTPUTS", "aggregate",
           "aggregate_table", "at_bound", "at_bound_share", "bench_identify", "daily_medians",
           "day_to_day_change", "error_over_posterior_sd", "last_day", "relative_error",
           "seed_figures", "seed_table"]

#: A parameter whose posterior sd is below this fraction of its first prior's sd (median over
#: the last day) is "determined" by the data. 0.5: the data carry at least three times the
#: information of the prior (1/0.5² = 4 = prior + 3 × prior).
DETERMINED_SD_RATIO = 0.5
#: θ̂ within this relative distance of a bound "sits at" it (the fit clips into the bounds,
#: so a parameter the fit pushes out sits exactly on it).
AT_BOUND_REL_TOL = 1e-3
DAY_S = 86400.0
#: Outputs scored: key in :class:`~dsfd.report.kpis.PredictionErrors`, key here, unit.
OUTPUTS: tuple[tuple[str, str, str], ...] = (
    *((x, x, "k") for x in ("x1", "x2", "x3", "x4", "x5")), ("v", "v_cav", "ms"))


# ---------------------------------------------------------------------------- pure helpers
def at_bound(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray, *,
             rel_tol: float = AT_BOUND_REL_TOL) -> tuple[np.ndarray, np.ndarray]:
    """(at lower, at upper), bool arrays shaped like ``theta`` (n, p): within ``rel_tol`` of
    the bound's magnitude (of the bound range for a bound at 0)."""
    theta = np.asarray(theta, float)
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    span = upper - lower

    def near(bound: np.ndarray) -> np.ndarray:
        scale = np.where(bound != 0.0, np.abs(bound), span)
        return np.isfinite(theta) & (np.abs(theta - bound) <= rel_tol * scale)

    return near(lower), near(upper)


def at_bound_share(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray, *,
                   rel_tol: float = AT_BOUND_REL_TOL) -> tuple[np.ndarray, np.ndarray]:
    """Share of the cycles (rows with a finite value) at the lower and at the upper bound,
    per parameter (p,) [0..1]."""
    lo, hi = at_bound(theta, lower, upper, rel_tol=rel_tol)
    rows = np.maximum(np.isfinite(np.asarray(theta, float)).sum(axis=0), 1)
    return lo.sum(axis=0) / rows, hi.sum(axis=0) / rows


def relative_error(theta: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """|θ̂/θ_true − 1| elementwise (broadcast over rows)."""
    return np.abs(np.asarray(theta, float) / np.asarray(truth, float) - 1.0)


def last_day(time_s: np.ndarray, *, day_s: float = DAY_S) -> np.ndarray:
    """True at the cycles of the run's last ``day_s`` (all of a shorter run)."""
    t = np.asarray(time_s, float)
    if not np.isfinite(t).any():
        return np.zeros(t.shape, bool)
    return np.isfinite(t) & (t > np.nanmax(t) - day_s)


def daily_medians(time_s: np.ndarray, values: np.ndarray, *, day_s: float = DAY_S
                  ) -> np.ndarray:
    """Median of ``values`` (n, p) per simulated day counted from the first cycle: (d, p)."""
    t = np.asarray(time_s, float)
    v = np.asarray(values, float)
    ok = np.isfinite(t)
    if not ok.any():
        return np.zeros((0, v.shape[1]))
    day = np.floor((t - np.nanmin(t)) / day_s).astype(int)
    out = np.full((int(day[ok].max()) + 1, v.shape[1]), np.nan)
    for d in range(out.shape[0]):
        rows = v[ok & (day == d)]
        if rows.size:
            out[d] = np.nanmedian(rows, axis=0)
    return out


def day_to_day_change(medians: np.ndarray, *, relative: np.ndarray) -> np.ndarray:
    """Change of the daily medians (d, p) between consecutive days (d − 1, p): relative
    |m_k/m_{k−1} − 1| where ``relative`` (p,) is True, absolute |m_k − m_{k−1}| elsewhere."""
    m = np.asarray(medians, float)
    if m.shape[0] < 2:
        return np.zeros((0, m.shape[1]))
    a, b = m[:-1], m[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(relative, np.abs(b / a - 1.0), np.abs(b - a))


def error_over_posterior_sd(theta: np.ndarray, sd_ratio: np.ndarray, truth: np.ndarray,
                            space: ParameterSpace) -> np.ndarray:
    """|z(θ̂) − z(θ_true)| / σ_post per cycle and component (n, 13), in the fitting
    coordinates (σ_post = ratio × the first prior's sd); the offsets' truth is 0. An honest
    posterior gives about 0.67 (the median of |N(0, 1)|); far more: it is overconfident."""
    z_true = space.to_z(full_vector(np.asarray(truth, float)))
    return np.abs(space.to_z(theta) - z_true) / (np.asarray(sd_ratio, float) * space.prior_sd)


def _median(x: np.ndarray) -> float:
    x = np.asarray(x, float)
    return float(np.nanmedian(x)) if np.isfinite(x).any() else math.nan


def _mean(x: np.ndarray) -> float:
    x = np.asarray(x, float)
    return float(np.nanmean(x)) if np.isfinite(x).any() else math.nan


# ---------------------------------------------------------------------------- one seed
def seed_figures(trace: SeedTrace) -> dict[str, float]:
    """The flat figures of one seed (keys without the seed prefix; module doc)."""
    sp = trace.space
    last = last_day(trace.time_s)
    lo_share, hi_share = at_bound_share(trace.theta, sp.lower, sp.upper)
    ratio = np.array([_median(trace.sd_ratio[last, i]) for i in range(len(FIT_NAMES))])
    changes = day_to_day_change(daily_medians(trace.time_s, trace.theta),
                                relative=np.arange(len(FIT_NAMES)) < N_PARAMS)
    final = trace.theta[np.flatnonzero(np.isfinite(trace.time_s))[-1]]
    z_err = (None if trace.truth is None else
             error_over_posterior_sd(trace.theta[last], trace.sd_ratio[last], trace.truth, sp))
    out: dict[str, float] = {}
    for i, name in enumerate(FIT_NAMES):
        offset = name in OFFSET_NAMES
        unit = "_wm2" if offset else ""
        if offset:
            out[f"{name}.abs_last_day_median_wm2"] = _median(np.abs(trace.theta[last, i]))
        out[f"{name}.last{unit}"] = float(final[i])
        if trace.truth is not None and not offset:
            truth = float(trace.truth[i])
            out[f"{name}.true"] = truth
            out[f"{name}.true_outside_bounds"] = float(not sp.lower[i] <= truth <= sp.upper[i])
            out[f"{name}.rel_err_last_day_median"] = _median(
                relative_error(trace.theta[last, i], truth))
            out[f"{name}.rel_err_last"] = float(relative_error(final[i], truth))
        out[f"{name}.at_bound_pct"] = 100.0 * float(lo_share[i] + hi_share[i])
        out[f"{name}.at_lower_pct"] = 100.0 * float(lo_share[i])
        out[f"{name}.at_upper_pct"] = 100.0 * float(hi_share[i])
        out[f"{name}.sd_ratio_last_day_median"] = float(ratio[i])
        if z_err is not None:
            out[f"{name}.err_over_post_sd_last_day_median"] = _median(z_err[:, i])
        out[f"{name}.fixed"] = float(bool(sp.fixed[i]))
        out[f"{name}.truth_on_bound"] = float(name in trace.truth_on_bound)
        out[f"{name}.determined"] = float(not sp.fixed[i] and ratio[i] < DETERMINED_SD_RATIO)
        kind = "wm2" if offset else "rel"
        for k in range(changes.shape[0]):
            out[f"{name}.day{k + 2}_change_{kind}"] = float(changes[k, i])
        out[f"{name}.day_change_max_{kind}"] = (float(np.nanmax(changes[:, i]))
                                                if np.isfinite(changes[:, i]).any() else math.nan)
    out.update(_error_figures(trace))
    out.update({k: float(v) for k, v in trace.counts.items()})
    return out


def _error_figures(trace: SeedTrace) -> dict[str, float]:
    """``mae.<output>.h1_model_<unit>`` … over the run and ``mae_last_day.…`` over its last
    day (the errors of ``dsfd report``; the horizon errors sit at the cycle they were made)."""
    err = trace.errors
    hz = f"h{err.horizon_steps}"
    every = np.ones(trace.errors_time_s.shape, bool)
    out: dict[str, float] = {}
    for prefix, rows in (("mae", every), ("mae_last_day", last_day(trace.errors_time_s))):
        for key, name, unit in OUTPUTS:
            out[f"{prefix}.{name}.h1_model_{unit}"] = _mean(err.model[key][rows])
            out[f"{prefix}.{name}.h1_persistence_{unit}"] = _mean(err.persistence[key][rows])
            if key in err.horizon_model:
                out[f"{prefix}.{name}.{hz}_model_{unit}"] = _mean(err.horizon_model[key][rows])
                out[f"{prefix}.{name}.{hz}_persistence_{unit}"] = _mean(
                    err.horizon_persistence[key][rows])
    return out


# ---------------------------------------------------------------------------- all seeds
def aggregate(per_seed: Mapping[int, Mapping[str, float]]) -> dict[str, float]:
    """``all.<key>.median`` and ``all.<key>.max`` over the seeds for every per-seed figure;
    ``all.<parameter>.determined_seeds``: in how many seeds it was determined."""
    out: dict[str, float] = {}
    if not per_seed:
        return out
    keys = [k for k in next(iter(per_seed.values()))
            if all(k in figs for figs in per_seed.values())]
    for key in keys:
        values = np.array([figs[key] for figs in per_seed.values()], float)
        if key.endswith(".determined"):
            out[f"all.{key}_seeds"] = float(np.nansum(values))
            continue
        out[f"all.{key}.median"] = _median(values)
        out[f"all.{key}.max"] = float(np.nanmax(values)) if np.isfinite(values).any() \
            else math.nan
    return out


# ---------------------------------------------------------------------------- tables
def _pct(x: float) -> str:
    return "–" if not math.isfinite(x) else f"{100.0 * x:.1f} %"


def _num(x: float, fmt: str = ".3g") -> str:
    return "–" if not math.isfinite(x) else format(x, fmt)


def _wm2(x: float) -> str:
    return "–" if not math.isfinite(x) else f"{x:.1f} W/m2"


def seed_table(seed: int, figs: Mapping[str, float]) -> str:
    """The human table of one seed."""
    lines = [f"seed {seed}: {figs.get('cycles', 0):.0f} cycles, "
             f"{figs.get('calibration_updates', 0):.0f} calibration updates, "
             f"{figs.get('cpu_s', math.nan):.0f} s CPU",
             f"  {'parameter':<9} {'true':>8} {'last':>8} {'rel.err':>8} {'at bound':>9} "
             f"{'sd/prior':>8} {'determined':>10} {'day change':>10} {'err/sd':>7}"]
    for name in PARAMETER_NAMES:
        lines.append(
            f"  {name:<9} {_num(figs.get(f'{name}.true', math.nan)):>8} "
            f"{_num(figs[f'{name}.last']):>8} "
            f"{_pct(figs.get(f'{name}.rel_err_last_day_median', math.nan)):>8} "
            f"{figs[f'{name}.at_bound_pct']:>7.1f} % "
            f"{_num(figs[f'{name}.sd_ratio_last_day_median'], '.2f'):>8} "
            f"{_determined(figs, name):>10} "
            f"{_pct(figs[f'{name}.day_change_max_rel']):>10} "
            f"{_num(figs.get(f'{name}.err_over_post_sd_last_day_median', math.nan), '.2g'):>7}")
    lines.append(f"  {'offset':<9} {'':>8} {'last':>8} {'|q|':>8} {'at bound':>9} "
                 f"{'sd/prior':>8} {'determined':>10} {'day change':>10} {'err/sd':>7}"
                 "   [W/m2]")
    for name in OFFSET_NAMES:
        lines.append(
            f"  {name:<9} {'':>8} {_num(figs[f'{name}.last_wm2'], '.1f'):>8} "
            f"{_num(figs[f'{name}.abs_last_day_median_wm2'], '.1f'):>8} "
            f"{figs[f'{name}.at_bound_pct']:>7.1f} % "
            f"{_num(figs[f'{name}.sd_ratio_last_day_median'], '.2f'):>8} "
            f"{_determined(figs, name):>10} "
            f"{_num(figs[f'{name}.day_change_max_wm2'], '.1f'):>10} "
            f"{_num(figs.get(f'{name}.err_over_post_sd_last_day_median', math.nan), '.2g'):>7}")
    lines.append("  (rel.err: median |θ̂/θ_true − 1| over the last day; |q|: median |q̂| over "
                 "the last day [W/m2]; sd/prior: median over the last day; day change: largest "
                 "between consecutive days; err/sd: median |z(θ̂) − z(θ_true)|/σ_post over the "
                 "last day, about 0.67 for an honest posterior)")
    lines += _error_table(figs)
    return "\n".join(lines)


def _determined(figs: Mapping[str, float], name: str) -> str:
    if figs.get(f"{name}.fixed"):
        return "fixed"
    return "yes" if figs[f"{name}.determined"] else "no"


def _error_table(figs: Mapping[str, float], prefix: str = "mae") -> list[str]:
    hz = next((k.split(".")[2].split("_")[0] for k in figs
               if k.startswith(f"{prefix}.x1.h") and not k.split(".")[2].startswith("h1_")),
              "h15")
    lines = [f"  {'output':<9} {'model 1':>9} {'persist 1':>9} {'model ' + hz[1:]:>9} "
             f"{'persist ' + hz[1:]:>10}   (MAE over the run, steps ahead)"]
    for _key, name, unit in OUTPUTS:
        scale, label = (100.0, "cm/s") if unit == "ms" else (1.0, "K")
        cells = [figs.get(f"{prefix}.{name}.{h}_{who}_{unit}", math.nan) * scale
                 for h, who in (("h1", "model"), ("h1", "persistence"), (hz, "model"),
                                (hz, "persistence"))]
        lines.append(f"  {name + ' ' + label:<9} " + " ".join(
            f"{_num(c, '.3f'):>9}" for c in cells))
    return lines


def aggregate_table(figs: Mapping[str, float], seeds: Sequence[int]) -> str:
    """The human table over the seeds."""
    n = len(seeds)
    lines = [f"all seeds ({', '.join(map(str, seeds))}): median / worst over the seeds",
             f"  {'parameter':<9} {'rel.err med':>11} {'rel.err max':>11} {'at bound max':>12} "
             f"{'sd/prior med':>12} {'determined':>10} {'day change max':>14}"]
    for name in (*PARAMETER_NAMES, *OFFSET_NAMES):
        offset = name in OFFSET_NAMES
        change = figs.get(f"all.{name}.day_change_max_{'wm2' if offset else 'rel'}.max",
                          math.nan)
        err = "abs_last_day_median_wm2" if offset else "rel_err_last_day_median"
        med, worst = (figs.get(f"all.{name}.{err}.{s}", math.nan) for s in ("median", "max"))
        lines.append(
            f"  {name:<9} "
            f"{_wm2(med) if offset else _pct(med):>11} "
            f"{_wm2(worst) if offset else _pct(worst):>11} "
            f"{figs.get(f'all.{name}.at_bound_pct.max', math.nan):>10.1f} % "
            f"{_num(figs.get(f'all.{name}.sd_ratio_last_day_median.median', math.nan), '.2f'):>12} "
            f"{figs.get(f'all.{name}.determined_seeds', 0):>6.0f} of {n} "
            f"{_wm2(change) if offset else _pct(change):>14}")
    lines.append("  (offsets: median |q̂| over the last day instead of a relative error)")
    lines += [line.replace("(MAE over the run", "(MAE over the run, median over the seeds")
              for line in _error_table({k[4:-7]: v for k, v in figs.items()
                                        if k.startswith("all.mae.") and k.endswith(".median")})]
    return "\n".join(lines)


# ---------------------------------------------------------------------------- the bench
def bench_identify(spec: RunSpec, *, seeds: Sequence[int],
                   on_figures: Callable[[dict[str, Any]], None] | None = None,
                   show: Callable[[str], None] = print,
                   progress: Callable[[str], None] | None = None,
                   keep_state: Path | None = None) -> dict[str, Any]:
    """Run every seed, print its table as it finishes and hand the figures so far to
    ``on_figures`` (``partial`` 1 until the last seed); return all figures. ``keep_state``:
    keep each seed's state directory there (:func:`~dsfd.bench.identify_run.run_seed`).

    A run stopped by SIGINT/SIGTERM ends after the current cycle: the seeds finished so far
    are kept (``partial`` 1, ``stopped`` 1); the interrupted seed is left out.
    """
    spec.check()
    figs: dict[str, Any] = {
        "plant": spec.plant, "sensors": spec.sensors, "protocol": spec.protocol,
        "model_cavity_air_profile": daemon_config(
            spec.cfg, plant=spec.plant).model.cavity_air_profile,
        "weather": spec.weather, "days": spec.cycles * spec.cfg.model.step_s / DAY_S,
        "cycles_per_seed": float(spec.cycles), "first_seed": float(seeds[0]),
        "seeds": float(len(seeds)), "determined_sd_ratio": DETERMINED_SD_RATIO,
        "at_bound_rel_tol": AT_BOUND_REL_TOL, "horizon_steps": float(
            spec.cfg.control.horizon_steps)}
    per_seed: dict[int, dict[str, float]] = {}
    stopped = False
    show(f"dsfd bench identify: {spec.plant} plant, {spec.sensors} sensors, {spec.protocol} "
         f"protocol, {figs['days']:g} days ({spec.cycles} cycles) per seed, seeds "
         f"{seeds[0]}..{seeds[-1]}, weather {spec.weather}; the daemon's cavity air "
         f"{figs['model_cavity_air_profile']}")
    days = spec.cycles * spec.cfg.model.step_s / DAY_S
    for seed in seeds:
        try:
            trace = run_seed(spec, seed, progress=progress, keep_state=keep_state)
            done = seed_figures(trace)
        except KeyboardInterrupt as exc:  # the daemon stopped on SIGINT/SIGTERM, or Ctrl-C
            show(f"stopped: {exc or 'interrupted'}; seed {seed} left out")
            stopped = True
            break
        per_seed[seed] = done
        figs.update({f"seed{seed}.{k}": v for k, v in done.items()})
        figs["cpu_s_per_seed_day"] = _mean(np.array(
            [f["cpu_s"] for f in per_seed.values()])) / days
        show(seed_table(seed, done))
        show("")
        if on_figures is not None and seed != seeds[-1]:
            on_figures({**figs, **aggregate(per_seed), "seeds_done": float(len(per_seed)),
                        "partial": 1.0})
    figs.update(aggregate(per_seed))
    figs["seeds_done"] = float(len(per_seed))
    figs["stopped"] = float(stopped)
    figs["partial"] = float(stopped)
    if per_seed:
        targets, lines = issue_targets(figs, list(per_seed), plant=spec.plant)
        figs.update(targets)
        show(aggregate_table(figs, list(per_seed)))
        show("issue 35's targets (docs/benchmarks-identify.md):")
        show("\n".join(lines))
        show("")
    return figs
