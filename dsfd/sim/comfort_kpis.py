"""Comfort figures of a closed-loop run, measured on the truth plant (issue 36).

Per cycle the run records whether the room was occupied (the panel's ``occupancy:`` at the
middle of the cycle's interval) and, for occupied cycles, the plant's comfort quantities at the
end of the interval (:meth:`dsfd.sim.plant.plant.Plant.comfort`: the state the command
produced). :func:`comfort_figures` counts the occupied minutes that break each limit of the
panel's ``comfort:`` section (docs/model.md#comfort, docs/model.md#plant-comfort).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from dsfd.config.comfort import Comfort, Occupancy
from dsfd.control.occupancy import occupied
from dsfd.physics.comfort_thermal import asymmetry_limit_k, supply_air_min_c
from dsfd.sim.choices import OCCUPANCY_CHOICES
from dsfd.sim.plant.comfort import PlantComfort

if TYPE_CHECKING:
    from dsfd.sim.plant.plant import Plant

__all__ = ["COMFORT_FIGURES", "OCCUPANCY_CHOICES", "ComfortLog", "comfort_figures",
           "comfort_summary", "occupancy_for", "weekly_hours"]

_DAY = ("08:00-18:00",)
#: The named schedules of :data:`~dsfd.sim.choices.OCCUPANCY_CHOICES`: an office, weekdays
#: 08:00-18:00 local time (the schedule of issue 36's targets), and the same hours every day
#: (the bundled January record's clear and overcast days are a Sunday and a Saturday at the
#: Suwon site); ``panel`` is the panel's own ``occupancy:``, ``none`` never occupied.
_SCHEDULES = {
    "office-weekdays": Occupancy(mon=_DAY, tue=_DAY, wed=_DAY, thu=_DAY, fri=_DAY),
    "office-every-day": Occupancy(mon=_DAY, tue=_DAY, wed=_DAY, thu=_DAY, fri=_DAY, sat=_DAY,
                                  sun=_DAY),
}

#: The figures of :func:`comfort_figures`, in report order.
COMFORT_FIGURES = ("occupied_min", "direct_sun_min", "dgp_p50", "dgp_p95", "dgp_max",
                   "dgp_above_limit_share", "supply_air_in_min", "supply_air_coldest_c",
                   "supply_air_below_min", "asymmetry_beyond_min")


def occupancy_for(name: str, panel: Occupancy | None) -> Occupancy | None:
    """The schedule called ``name`` (:data:`OCCUPANCY_CHOICES`); ``panel`` is the panel's."""
    if name not in OCCUPANCY_CHOICES:
        raise ValueError(f"occupancy {name!r}: choose one of {', '.join(OCCUPANCY_CHOICES)}")
    if name == "panel":
        return panel
    return _SCHEDULES.get(name)


def weekly_hours(occupancy: Occupancy | None) -> float:
    """Occupied hours of a week (holidays aside)."""
    if occupancy is None:
        return 0.0
    return sum(end - start for wd in range(7) for start, end in occupancy.intervals(wd)) / 60.0


@dataclass
class ComfortLog:
    """Per-cycle comfort record of a closed-loop run (NaN where not measured)."""

    step_s: float
    occupied: list[bool]
    direct_sun_wm2: list[float]
    dgp: list[float]
    supply_air_c: list[float]  # NaN: no air entered the room (or unoccupied)
    asymmetry_k: list[float]

    @classmethod
    def empty(cls, step_s: float) -> ComfortLog:
        return cls(float(step_s), [], [], [], [], [])

    def record(self, plant: Plant) -> None:
        """The cycle whose interval ``plant`` just integrated: occupied at the interval's
        middle (the panel's ``occupancy:``), measured at its end (the state the command
        produced) and only while occupied (docs/model.md#plant-comfort)."""
        cfg = plant.cfg
        mid = plant.time_s - 0.5 * self.step_s
        occ = bool(occupied(mid, occupancy=cfg.occupancy, utc_offset_h=cfg.site.utc_offset_h))
        self.append(occ, plant.comfort() if occ else None)

    def append(self, is_occupied: bool, measured: PlantComfort | None) -> None:
        """One cycle: ``measured`` is None for a cycle that was not measured (unoccupied)."""
        self.occupied.append(bool(is_occupied))
        if measured is None:
            values = (math.nan,) * 4
        else:
            values = (measured.direct_sun_wm2, measured.dgp,
                      math.nan if measured.supply_air_c is None else measured.supply_air_c,
                      measured.asymmetry_k)
        for column, v in zip((self.direct_sun_wm2, self.dgp, self.supply_air_c,
                              self.asymmetry_k), values, strict=True):
            column.append(float(v))


def comfort_figures(log: ComfortLog, comfort: Comfort,
                    keep: np.ndarray | None = None) -> dict[str, float]:
    """Occupied minutes breaking each comfort limit and the DGPs distribution.

    Parameters
    ----------
    log : ComfortLog
    comfort : Comfort
        The limits (the panel's ``comfort:``).
    keep : bool array, optional
        The cycles to count (e.g. the scored day of a bench case); default all.

    Returns
    -------
    dict
        ``occupied_min``; ``direct_sun_min`` (beam into the room above
        ``direct_sun_max_wm2``); ``dgp_p50``, ``dgp_p95``, ``dgp_max`` (over the occupied
        cycles, NaN without any) and ``dgp_above_limit_share`` (of the occupied cycles above
        ``dgp_max``); ``supply_air_in_min`` (cavity air entering the room at all) and
        ``supply_air_coldest_c`` (NaN if none), ``supply_air_below_min`` (air entering the
        room colder than the supply limit); ``asymmetry_beyond_min`` (warm or cool pane
        beyond ISO 7730's category limit).
        All counts are in minutes of occupied cycles.
    """
    occ = np.asarray(log.occupied, bool)
    if keep is not None:
        occ = occ & np.asarray(keep, bool)
    minutes = log.step_s / 60.0
    sun, dgp, air, asym = (np.asarray(v, float)[occ] for v in (
        log.direct_sun_wm2, log.dgp, log.supply_air_c, log.asymmetry_k))
    warm = asymmetry_limit_k(comfort.category, warm=True)
    cool = asymmetry_limit_k(comfort.category, warm=False)
    with np.errstate(invalid="ignore"):
        beyond = (asym > warm) | (asym < -cool)
        cold_air = air < supply_air_min_c(comfort)  # NaN (no inflow) is never below
    out = {"occupied_min": float(occ.sum() * minutes),
           "direct_sun_min": float(np.sum(sun > comfort.direct_sun_max_wm2) * minutes)}
    for name, q in (("dgp_p50", 50), ("dgp_p95", 95), ("dgp_max", 100)):
        out[name] = float(np.percentile(dgp, q)) if dgp.size else math.nan
    out["dgp_above_limit_share"] = float(np.mean(dgp > comfort.dgp_max)) if dgp.size \
        else math.nan
    inflow = np.isfinite(air)
    out["supply_air_in_min"] = float(np.sum(inflow) * minutes)
    out["supply_air_coldest_c"] = float(air[inflow].min()) if inflow.any() else math.nan
    out["supply_air_below_min"] = float(np.sum(cold_air) * minutes)
    out["asymmetry_beyond_min"] = float(np.sum(beyond) * minutes)
    return out


def comfort_summary(log: ComfortLog, comfort: Comfort,
                    keep: np.ndarray | None = None) -> dict[str, float]:
    """:func:`comfort_figures` with the limits they were judged by, JSON-ready."""
    return {**comfort_figures(log, comfort, keep),
            "direct_sun_limit_wm2": comfort.direct_sun_max_wm2, "dgp_limit": comfort.dgp_max,
            "supply_air_limit_c": supply_air_min_c(comfort),
            "asymmetry_limit_warm_k": asymmetry_limit_k(comfort.category, warm=True),
            "asymmetry_limit_cool_k": asymmetry_limit_k(comfort.category, warm=False)}
