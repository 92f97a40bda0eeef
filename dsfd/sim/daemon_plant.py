"""``dsfd run --plant sim``: the in-process simulated plant on bundled real weather.

Builds the truth plant (:class:`dsfd.sim.plant.plant.Plant`) on a weather file replayed at the
panel's site, picks the start (``--start`` or the first whole minute of the data) and wraps
it in a :class:`~dsfd.drivers.simulated.SimulatedDriver`. A run longer than the weather
record replays the record again, back to back (said in the notes), so benchmarks can run
any number of cycles.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from dsfd.config.model import ModelOptions
from dsfd.config.panel import PanelConfig
from dsfd.daemon.runner import RunOptions
from dsfd.drivers.simulated import SimulatedDriver
from dsfd.measured import iso_utc
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.faults import FaultSpec, parse_fault
from dsfd.sim.plant.plant import Plant
from dsfd.sim.replay import at_site, load_weather
from dsfd.weather import WeatherSeries

__all__ = ["DEFAULT_WEATHER", "SimulatedPlant", "cycles_covered", "plant_for_run",
           "plant_options", "repeat_weather", "simulated_plant", "weather_window"]

#: RMIS Golden CO, 1-4 January 2022: overcast, clear and mixed winter days.
DEFAULT_WEATHER = "rmis-golden-2022-01"


def plant_options(fidelity: str, model: ModelOptions | None = None) -> PlantOptions:
    """``full``: the stratified truth plant (docs/model.md#truth-plant); ``lumped``: the same plant
    with the lumped model's switches (one segment, lumped optics and flows, those of ``model``
    when given) but realistic sensors and actuators — much faster, for quick dry runs and
    tests of the daemon itself."""
    if fidelity == "full":
        return PlantOptions()
    if fidelity == "lumped":
        return PlantOptions.lumped_equivalent(model, sensors="realistic", actuators="realistic")
    raise ValueError(f"plant fidelity {fidelity!r}: choose full or lumped")


@dataclass(frozen=True)
class SimulatedPlant:
    """The driver, where it starts, how many cycles the weather covers, and notes."""

    driver: SimulatedDriver
    plant: Plant
    start_s: float
    weather: WeatherSeries
    notes: tuple[str, ...]

    def room_heat(self) -> tuple[dict[str, float], float]:
        """Heat into the room since the start [J] by term, and the hours it covers [h]."""
        return self.plant.room_heat_j(), (self.plant.time_s - self.start_s) / 3600.0

    def room_heat_now(self) -> dict[str, float] | None:
        """Heat into the room since the start [J] by term; None while an integration that
        the read budget abandoned is still running (the plant is not thread-safe)."""
        return None if self.driver.busy else self.plant.room_heat_j()


def weather_window(cfg: PanelConfig, *, weather: str = DEFAULT_WEATHER,
                   start_s: float | None = None) -> tuple[WeatherSeries, float]:
    """The weather replayed at the panel's site and the start [s, UTC] of the run.

    The default start is the first whole minute one model step into the data.

    Raises
    ------
    FileNotFoundError, ValueError
        Unknown weather, or a start outside the data (the message names both).
    """
    series = at_site(load_weather(weather), cfg)
    first, last = series.coverage_s
    if start_s is None:
        start_s = math.ceil((first + cfg.model.step_s) / 60.0) * 60.0
    if not first <= start_s < last:
        raise ValueError(f"--start {iso_utc(start_s)} is outside the weather {weather!r} "
                         f"at the site ({iso_utc(first)} to {iso_utc(last)})")
    return series, float(start_s)


def cycles_covered(series: WeatherSeries, *, start_s: float, period_s: float) -> int:
    """Whole cycles of ``period_s`` [s] the weather covers from ``start_s``."""
    return max(0, int((series.coverage_s[1] - start_s) // period_s) - 1)


def repeat_weather(series: WeatherSeries, *, until_s: float) -> WeatherSeries:
    """``series`` replayed back to back until it covers ``until_s`` [s, UTC]."""
    first, last = series.coverage_s
    if last >= until_s:
        return series
    period = last - first
    copies = math.ceil((until_s - first) / period)
    channels = {name: np.concatenate([getattr(series, name)] * copies)
                for name in ("t_out_c", "ghi_wm2", "dni_wm2", "dhi_wm2", "wind_speed_ms",
                             "wind_dir_deg", "pressure_pa", "rh_pct")}
    time = np.concatenate([series.time_s + k * period for k in range(copies)])
    note = f"record replayed {copies} times back to back (period {period / 86400:.2f} days)"
    return dataclasses.replace(series, time_s=time, notes=(*series.notes, note), **channels)


def simulated_plant(cfg: PanelConfig, *, weather: str = DEFAULT_WEATHER,
                    start_s: float | None = None, cycles: int | None = None, seed: int = 1,
                    period_s: float | None = None, options: PlantOptions | None = None,
                    faults: tuple[FaultSpec, ...] = ()) -> SimulatedPlant:
    """Build the plant for a dry run.

    Parameters
    ----------
    weather : str
        Bundled weather name or a weather file.
    start_s : float, optional, [s]
        UTC start (default: see :func:`weather_window`).
    cycles : int, optional
        Cycles to cover; the weather is repeated if it is shorter.
    seed : int
        Seeds the plant's true parameters and sensor noise.
    period_s : float, optional, [s]
        Cycle period (default ``cfg.daemon.cycle_period_s``).
    options : PlantOptions, optional
        Plant switches (default: the full-fidelity truth plant).
    faults : tuple of FaultSpec
        Simulated faults (:mod:`dsfd.sim.plant.faults`); relative starts count from the
        run's start.

    Raises
    ------
    FileNotFoundError, ValueError
        As :func:`weather_window`.
    """
    period = period_s or cfg.daemon.cycle_period_s
    series, start_s = weather_window(cfg, weather=weather, start_s=start_s)
    if cycles is not None:
        series = repeat_weather(series, until_s=start_s + (cycles + 2) * period)
    plant = Plant(cfg, options or PlantOptions(), seed=seed, weather_series=series,
                  faults=faults)
    plant.reset(start_s)
    notes = (f"weather: {series.source}", *series.notes,
             *(f"simulated fault {f.text or f.kind}" for f in faults))
    return SimulatedPlant(SimulatedDriver(plant), plant, float(start_s), series, notes)


def plant_for_run(cfg: PanelConfig, opts: RunOptions) -> SimulatedPlant:
    """The simulated plant ``dsfd run --plant sim`` asks for (weather, start, seed, fidelity,
    faults); :class:`~dsfd.sim.plant.faults.FaultSpecError` for a bad ``--fault``."""
    return simulated_plant(cfg, weather=opts.weather or DEFAULT_WEATHER, start_s=opts.start_s,
                           cycles=opts.cycles, seed=opts.seed,
                           options=plant_options(opts.plant_fidelity, cfg.model),
                           faults=tuple(parse_fault(f) for f in opts.faults))
