"""``dsfd bench closed-loop``: how much of the achievable saving the controller gets.

For each case — a clear, a mixed and an overcast day of the winter weather, each in the
heating objective and in the synthetic cooling period (docs/benchmarks.md's closed-loop case:
outdoor air +25 K, room 25 °C, cooling objective) — the same truth plant (same seed) runs
the same window under every controller of :data:`CONTROLLERS`:

* ``rule`` (the baseline), ``mpc`` (on-line calibration, persistence forecast);
* ``oracle``: the optimiser with the true state, the true weather and the plant's
  parameters mapped to the lumped model (it still plans on the lumped model);
* ``plant-oracle``: decisions by rollouts on the truth plant itself
  (:mod:`dsfd.sim.oracle_search`) — the reference the controller is judged by;
* ``mpc-true-weather``, ``mpc-true-state``, ``mpc-true-params``: ``mpc`` given one piece of
  the oracle's information (the horizon's weather, the plant's state, or the plant's
  parameters mapped to the lumped model), to split the shortfall into forecast, state
  estimate and parameters.

Every run starts a warm-up before the scored day — a quarter of the scored duration, at most
``warmup_h`` — clipped to the start of the record, so the on-line calibration has data
behind it as it would in service; only the scored cycles are counted. The figure of merit
per case is

    mpc_share_of_plant_oracle_saving = (J_rule − J_mpc) / (J_rule − J_plant-oracle)

(1 = the controller gets everything the plant oracle gets). Days are picked from the
weather by the daytime clearness index k_t of each whole local solar day
(:func:`classify_days`).

Comfort is measured on the plant while occupied (:mod:`dsfd.sim.comfort_kpis`): every case
runs with the schedule ``occupancy`` names (default office hours 08:00-18:00 every day: the
bundled January record's clear and overcast days are a Sunday and a Saturday at the Suwon
site, so a weekdays-only office would judge only the mixed day), and reports per controller
the occupied minutes with direct sun, the DGPs distribution and its share above the limit, the
minutes with supply air below the limit and with the pane's asymmetry beyond the category.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from dsfd.bench.oracle_cache import OracleCache, config_digest
from dsfd.config.panel import PanelConfig
from dsfd.physics.solar import extraterrestrial_irradiance, solar_position
from dsfd.sim.choices import BENCH_CONTROLLERS, OccupancyName
from dsfd.sim.closed_loop import (
    J_PER_KWH,
    ClosedLoopResult,
    ClosedLoopSettings,
    run_closed_loop,
)
from dsfd.sim.comfort_kpis import COMFORT_FIGURES, occupancy_for, weekly_hours
from dsfd.sim.plant.faults import FaultSpec
from dsfd.sim.replay import at_site
from dsfd.weather import WeatherSeries

__all__ = ["CASES", "CONTROLLERS", "DayClass", "bench_closed_loop", "bench_closed_loop_seeds",
           "classify_days", "report", "share_table"]

CONTROLLERS = BENCH_CONTROLLERS
SKIES = ("clear", "mixed", "overcast")
SEASONS = ("heating", "cooling")
CASES = tuple(f"{sky}-{season}" for sky in SKIES for season in SEASONS)
#: The synthetic cooling period of docs/benchmarks.md's closed-loop section.
COOLING_T_OUT_OFFSET_K = 25.0
COOLING_ROOM_C = 25.0
WARMUP_H = 6.0
#: Clearness-index classes of the paper's Figure 11 (as ClosedLoopResult.conditions).
KT_CLEAR, KT_OVERCAST = 0.55, 0.3


@dataclass(frozen=True)
class DayClass:
    """One whole local solar day of a weather series and its sky."""

    start_s: float  # UTC of local solar midnight [s]
    clear_share: float  # daytime samples with k_t > 0.55
    mixed_share: float
    overcast_share: float  # k_t < 0.3


def classify_days(series: WeatherSeries, cfg: PanelConfig) -> dict[str, DayClass]:
    """The clearest, the most mixed and the most overcast whole day of ``series`` at the
    panel's site (daytime: sun above 5° and GHI ≥ 20 W/m2; local solar midnight from the
    site's longitude). Each day is used once: overcast first, then clear, then mixed."""
    site = at_site(series, cfg)
    t = site.time_s
    sun = solar_position(t, cfg.site.latitude_deg, cfg.site.longitude_deg)
    cos_z = np.cos(np.radians(sun.zenith_deg))
    kt = site.ghi_wm2 / np.maximum(extraterrestrial_irradiance(t) * cos_z, 1e-9)
    up = (sun.elevation_deg >= 5.0) & (site.ghi_wm2 >= 20.0)
    offset = cfg.site.longitude_deg / 15.0 * 3600.0
    day = np.floor((t + offset) / 86400.0)
    first, last = site.coverage_s
    days: list[DayClass] = []
    for d in np.unique(day):
        start = d * 86400.0 - offset
        if start < first - 600.0 or start + 86400.0 > last:
            continue  # not a whole day of data
        k = kt[(day == d) & up]
        if k.size == 0:
            continue
        days.append(DayClass(float(start), float(np.mean(k > KT_CLEAR)),
                             float(np.mean((k >= KT_OVERCAST) & (k <= KT_CLEAR))),
                             float(np.mean(k < KT_OVERCAST))))
    if len(days) < 3:
        raise ValueError(f"weather {series.source!r} has {len(days)} whole day(s) with daylight "
                         "at the site; the bench needs three (clear, mixed, overcast)")
    out: dict[str, DayClass] = {}
    for sky, key in (("overcast", "overcast_share"), ("clear", "clear_share"),
                     ("mixed", "mixed_share")):
        left = [dc for dc in days if dc not in out.values()]
        out[sky] = max(left, key=lambda dc, key=key: getattr(dc, key))
    return out


def _case_config(cfg: PanelConfig, series: WeatherSeries, season: str
                 ) -> tuple[PanelConfig, WeatherSeries]:
    """The panel and weather of a season (the panel's occupancy already chosen)."""
    if season == "heating":
        return (dataclasses.replace(cfg, control=dataclasses.replace(cfg.control,
                                                                     mode="heating")), series)
    cfg = dataclasses.replace(cfg, control=dataclasses.replace(cfg.control, mode="cooling"),
                              room=dataclasses.replace(cfg.room, t_in_c=COOLING_ROOM_C))
    note = f"SYNTHETIC: measured outdoor air shifted by {COOLING_T_OUT_OFFSET_K:+g} K"
    return cfg, dataclasses.replace(series, t_out_c=series.t_out_c + COOLING_T_OUT_OFFSET_K,
                                    notes=(*series.notes, note))


def _scored(result: ClosedLoopResult, from_s: float) -> dict[str, float]:
    """J and heat terms [kWh] of the cycles that start at or after ``from_s``."""
    t = result.start_s + np.arange(result.cycles) * result.step_s
    keep = t >= from_s - 1e-6
    j = result.j_per_cycle()[keep].sum() / J_PER_KWH
    out = {"J_kwh": float(j)}
    out.update({f"{k}_kwh": float(v[keep].sum() / J_PER_KWH) for k, v in result.heat_j.items()})
    phis = np.array([c.phi_deg for c in result.commands])[keep]
    days = keep.sum() * result.step_s / 86400.0
    out["louver_moves_per_day"] = float(np.count_nonzero(np.diff(phis)) / days) if days else 0.0
    d = result.decide_ms[keep]
    d = d[np.isfinite(d)]
    out["decide_ms_median"] = float(np.median(d)) if d.size else float("nan")
    comfort = result.comfort_summary(keep)
    out.update((k, comfort[k]) for k in COMFORT_FIGURES if k in comfort)
    return out


def _share(j: dict[str, float], name: str, ref: str = "plant-oracle") -> float:
    saving = j["rule"] - j[ref]
    return (j["rule"] - j[name]) / saving if saving else float("nan")


def bench_closed_loop(cfg: PanelConfig, series: WeatherSeries, *, days: float = 1.0,
                      seed: int = 1, cases: Sequence[str] = CASES,
                      controllers: Sequence[str] = CONTROLLERS, warmup_h: float = WARMUP_H,
                      progress: Callable[[str], None] | None = None,
                      on_figures: Callable[[dict[str, float]], None] | None = None,
                      oracle_cache: OracleCache | None = None,
                      faults: tuple[FaultSpec, ...] = (),
                      occupancy: OccupancyName = "office-every-day") -> dict[str, float]:
    """Run every controller on every case; flat figures ``<case>.<controller>.<figure>``
    and ``<case>.mpc_share_of_plant_oracle_saving`` (and the other shares) when ``rule`` and
    ``plant-oracle`` are among ``controllers`` (a run of some controllers alone, e.g. to add
    the split to an earlier run on the same seed, has no shares). ``on_figures`` receives a
    copy of the figures so far after every controller's run (a plant-oracle day takes about
    an hour: the CLI saves them, so a stopped bench keeps what it finished). With
    ``oracle_cache`` the plant oracle's figures of a case are taken from it where it has them
    (``<case>.plant-oracle.cached`` = 1) and stored in it where it does not. ``faults``
    (:mod:`dsfd.sim.plant.faults`, relative starts from each case's run start, warm-up
    included) are in every controller's plant; the cache, which knows clean plants only, is
    then not used. ``occupancy`` names the schedule every case runs with
    (:data:`~dsfd.sim.comfort_kpis.OCCUPANCY_CHOICES`; ``panel``: the panel's own); the
    comfort limits are the panel's ``comfort:``."""
    unknown = sorted(set(cases) - set(CASES))
    if unknown:
        raise ValueError(f"unknown case(s) {unknown}; choose from {', '.join(CASES)}")
    unknown = sorted(set(controllers) - set(CONTROLLERS))
    if unknown:
        raise ValueError(f"unknown controller(s) {unknown}; choose from {', '.join(CONTROLLERS)}")
    cfg = dataclasses.replace(cfg, occupancy=occupancy_for(occupancy, cfg.occupancy))
    skies = classify_days(series, cfg)
    first = at_site(series, cfg).coverage_s[0]
    fig: dict[str, float] = {"seed": float(seed), "days": float(days),
                             "faults": float(len(faults)),
                             "occupied_h_per_week": weekly_hours(cfg.occupancy)}
    if faults:
        oracle_cache = None
    for case in cases:
        sky, season = case.split("-")
        day = skies[sky]
        start = max(first, day.start_s - min(warmup_h, 6.0 * days) * 3600.0)
        start = float(np.ceil(start / 60.0) * 60.0)
        hours = (day.start_s - start) / 3600.0 + 24.0 * days
        ccfg, cseries = _case_config(cfg, series, season)
        fig[f"{case}.day_start_s"] = day.start_s
        fig[f"{case}.warmup_h"] = (day.start_s - start) / 3600.0
        j: dict[str, float] = {}
        oracle_key = OracleCache.key(case=case, seed=seed, days=days, warmup_h=warmup_h,
                              weather=series.source, digest=config_digest(ccfg))
        for name in controllers:
            wall = time.perf_counter()
            cached = (oracle_cache.get(oracle_key) if oracle_cache is not None
                      and name == "plant-oracle" else None)
            if cached is None:
                res = run_closed_loop(ccfg, cseries, ClosedLoopSettings(
                    controller=name, calibration="online", seed=seed, hours=hours,
                    start_s=start, faults=faults))
                scored = _scored(res, day.start_s)
                if oracle_cache is not None and name == "plant-oracle":
                    oracle_cache.put(oracle_key, scored)
            else:
                scored = cached
                fig[f"{case}.{name}.cached"] = 1.0
            for key, value in scored.items():
                fig[f"{case}.{name}.{key}"] = value
            fig[f"{case}.{name}.wall_s"] = time.perf_counter() - wall
            j[name] = scored["J_kwh"]
            if progress is not None:
                progress(f"{case}: {name} J {scored['J_kwh']:+.3f} kWh "
                         f"({time.perf_counter() - wall:.0f} s)")
            if on_figures is not None:
                on_figures(dict(fig))
        if not {"rule", "plant-oracle"} <= j.keys():
            continue  # a partial run (e.g. only the split controllers): no shares
        for name in controllers:
            if name not in ("rule", "plant-oracle"):
                fig[f"{case}.{name.replace('-', '_')}_share_of_plant_oracle_saving"] = \
                    _share(j, name)
    return fig


def report(fig: dict[str, float]) -> str:
    """One table per case: J and heat terms per controller, and the shares (text)."""
    cases = [c for c in CASES if f"{c}.day_start_s" in fig]
    lines = [f"Closed loop on the truth plant (seed {fig['seed']:g}), {fig['days']:g} scored "
             "day(s) per case; share = (J_rule - J) / (J_rule - J_plant-oracle)"]
    for case in cases:
        start = fig[f"{case}.day_start_s"]
        day = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(start))
        lines += ["", f"{case}: local day from {day} (warm-up {fig[f'{case}.warmup_h']:.1f} h)",
                  f"{'controller':<18}{'J':>9}{'Q_cv,rd':>9}{'Q_sol':>9}{'Q_air':>9}"
                  f"{'Q_DA':>9}{'moves/d':>9}{'share':>8}  [kWh]"]
        names = [k.split(".")[1] for k in fig if k.startswith(f"{case}.")
                 and k.endswith(".J_kwh")]
        for name in names:
            p = f"{case}.{name}."
            share = fig.get(f"{case}.{name.replace('-', '_')}_share_of_plant_oracle_saving")
            lines.append(f"{name:<18}{fig[p + 'J_kwh']:9.3f}{fig[p + 'q_cv_rd_kwh']:9.3f}"
                         f"{fig[p + 'q_sol_trans_kwh']:9.3f}{fig[p + 'q_air_kwh']:9.3f}"
                         f"{fig[p + 'q_da_kwh']:9.3f}{fig[p + 'louver_moves_per_day']:9.1f}"
                         + (f"{share:8.1%}" if share is not None else f"{'':>8}"))
        lines += _comfort_rows(fig, case, names)
    return "\n".join(lines)


def _comfort_rows(fig: dict[str, float], case: str, names: Sequence[str]) -> list[str]:
    """The case's comfort table: occupied minutes beyond each limit, DGPs distribution."""
    rows = [f"{name:<18}" + "".join(_cell(fig.get(f"{case}.{name}.{k}"), fmt) for k, fmt in (
        ("occupied_min", "9.0f"), ("direct_sun_min", "9.0f"), ("dgp_p50", "7.2f"),
        ("dgp_p95", "7.2f"), ("dgp_max", "7.2f"), ("dgp_above_limit_share", "8.0%"),
        ("supply_air_in_min", "8.0f"), ("supply_air_below_min", "9.0f"),
        ("asymmetry_beyond_min", "9.0f")))
        for name in names if f"{case}.{name}.occupied_min" in fig]
    if not rows:
        return []
    return [f"{'comfort (plant)':<18}{'occupied':>9}{'sun':>9}{'DGP50':>7}{'DGP95':>7}"
            f"{'DGPmax':>7}{'>DGPlim':>8}{'air in':>8}{'cold air':>9}{'asymm.':>9}  [min]",
            *rows]


def _cell(value: float | None, fmt: str) -> str:
    width = int(fmt.split(".")[0])
    return f"{'-':>{width}}" if value is None or not np.isfinite(value) else f"{value:{fmt}}"



def bench_closed_loop_seeds(cfg: PanelConfig, series: WeatherSeries, *, seeds: Sequence[int],
                            on_figures: Callable[[dict[str, float]], None] | None = None,
                            **options) -> dict[str, float]:
    """:func:`bench_closed_loop` for each seed, figures prefixed ``seed<S>.``; ``options`` as
    there. ``on_figures`` receives all seeds' figures so far after every controller's run."""
    fig: dict[str, float] = {"seeds": float(len(seeds))}
    for seed in seeds:
        done = dict(fig)

        def hand_over(part: dict[str, float], done=done, seed=seed) -> None:
            if on_figures is not None:
                on_figures({**done, **{f"seed{seed}.{k}": v for k, v in part.items()}})

        progress = options.get("progress")
        seed_options = options if progress is None else {
            **options, "progress": lambda msg, seed=seed, say=progress: say(f"seed {seed}: {msg}")}
        part = bench_closed_loop(cfg, series, seed=seed, on_figures=hand_over, **seed_options)
        fig.update({f"seed{seed}.{k}": v for k, v in part.items()})
    return fig


def share_table(fig: dict[str, float]) -> str:
    """mpc's share of the plant oracle's saving per case (rows) and seed (columns), text."""
    seeds = sorted({int(k.split(".")[0][4:]) for k in fig if k.startswith("seed")
                    and k.split(".")[0][4:].isdigit()})
    cases = [c for c in CASES if any(f"seed{s}.{c}.day_start_s" in fig for s in seeds)]
    lines = ["mpc share of the plant oracle's saving over the rule (J_rule - J_mpc) / "
             "(J_rule - J_plant-oracle)",
             f"{'case':<18}" + "".join(f"{f'seed {s}':>10}" for s in seeds) + f"{'mean':>10}"]
    for case in cases:
        shares = [fig.get(f"seed{s}.{case}.mpc_share_of_plant_oracle_saving") for s in seeds]
        known = [v for v in shares if v is not None and np.isfinite(v)]
        cells = "".join(f"{v:10.1%}" if v is not None else f"{'-':>10}" for v in shares)
        mean = f"{np.mean(known):10.1%}" if known else f"{'-':>10}"
        lines.append(f"{case:<18}{cells}{mean}")
    return "\n".join(lines)
