"""Closed-loop runs: calibration and control against the stratified truth plant (issue 5).

``dsfd simulate --plant truth --controller C --calibration K`` runs the daemon's own cycle
(:class:`dsfd.daemon.loop.Controller`: read → quality → state estimate → calibration →
optimise → safety → write → store) on a simulated clock against the truth plant of
:mod:`dsfd.sim.plant.plant`, so the energy figures are those of the production pipeline, with
its sensor noise, actuator dynamics, 18° louver quantisation and louver move interval.

Controllers:

* ``mpc`` — the optimiser of :mod:`dsfd.control.optimiser` on a persistence forecast;
* ``paper-sqp`` — the paper's relaxed SLSQP with the louver rounded afterwards;
* ``rule`` — the rule-based baseline of :mod:`dsfd.control.baseline`;
* ``fixed`` — no control: one command held throughout (default louver 0°, dampers closed);
* ``oracle`` — the ``mpc`` optimiser with perfect information: the plant's true mid-height
  state instead of the observer, the true weather of the horizon instead of persistence, and
  the plant's own parameters mapped to the lumped model (:func:`oracle_theta`) instead of a
  calibration.
  It bounds what better information can buy the optimiser; it is not a global optimum
  (the optimiser still plans on the lumped model over 15 minutes);
* ``plant-oracle`` — an offline reference that plans on the truth plant itself: every
  decision rolls candidate commands out on copies of the plant from its true state with the
  true weather (:mod:`dsfd.sim.oracle_search`), within the same actuator grid, horizon, move
  penalty and safety pipeline;
* ``mpc-true-weather``, ``mpc-true-state`` — ``mpc`` (with its calibration) given one piece
  of the oracle's information: the true weather of the horizon, or the plant's true state;
  ``mpc-true-params`` — ``mpc`` (observer, persistence forecast) with the oracle's
  parameters frozen instead of the on-line calibration.
  They split what the oracle gains into forecast, state estimate and parameters.

Calibration: ``online`` (the daemon's on-line self-calibration), ``offline`` (θ̂ from a
``dsfd calibrate`` parameter file, frozen) or ``none`` (the panel's defaults, frozen).

Energy is the plant's own room-side heat (:meth:`~dsfd.sim.plant.plant.Plant.room_heat_j`,
integrated inside its ODE), cycle by cycle; J follows docs/model.md#control-objective with the mode
the cycle decided in (heating: J = −ΣQ; cooling: J = Σ(Q_cv,rd + Q_sol + Q_air − Q_DA)).
"""

from __future__ import annotations

import asyncio
import dataclasses
import itertools
import math
import tempfile
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dsfd.config.comfort import Comfort
from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import N_PARAMS
from dsfd.control.objective import is_heating
from dsfd.daemon.calibration import CalibrationStage
from dsfd.daemon.clock import SimulatedClock, Slot
from dsfd.daemon.loop import Controller
from dsfd.drivers.simulated import SimulatedDriver
from dsfd.physics.constants import T_ZERO
from dsfd.physics.model import LumpedModel
from dsfd.physics.solar import solar_position
from dsfd.sim.choices import (
    CALIBRATIONS,
    CONTROLLERS,
    TRUE_THETA,
    CalibrationName,
    ControllerName,
)
from dsfd.sim.comfort_kpis import ComfortLog, comfort_summary
from dsfd.sim.oracle_controllers import (
    CONTROLLER_CLASSES,
    FrozenCalibration,
    OracleController,
    PlantOracleController,
    oracle_theta,
)
from dsfd.sim.oracle_search import PlantOracle, SearchSettings, room_objective_j
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.faults import FaultSpec
from dsfd.sim.plant.model import ROOM_FLOWS
from dsfd.sim.plant.plant import Plant
from dsfd.sim.replay import at_site, step_window
from dsfd.storage.timeseries import Store
from dsfd.weather import WeatherSeries
from dsfd.weather.sky import sky_conditions

__all__ = ["CALIBRATIONS", "CONTROLLERS", "ClosedLoopResult", "ClosedLoopSettings",
           "run_closed_loop"]


#: Stage budgets of a closed-loop run [s]. The daemon's budgets are wall-clock limits; the
#: simulated clock does not wait for the wall clock, so on a loaded machine they would turn
#: slow calibration updates into abandoned ones and change the energy figures with the
#: machine's load. A run lifts them and counts the stages that took longer than the panel's
#: budgets instead (``late_decisions``, ``late_calibrations``).
SIM_BUDGET_S = 1e6
#: The uncontrolled reference: horizontal slats, all dampers closed (a buffer façade).
DEFAULT_FIXED = Command(0.0, 10, 100.0)
J_PER_KWH = 3.6e6


@dataclass(frozen=True, kw_only=True)
class ClosedLoopSettings:
    """One closed-loop run.

    Attributes
    ----------
    controller : str
        One of :data:`CONTROLLERS`.
    calibration : str
        One of :data:`CALIBRATIONS` (ignored by ``fixed``; ``oracle`` uses the true θ).
    seed : int
        Plant seed (true parameters, sensor noise); the same seed gives every controller
        the same plant.
    hours : float, optional, [h]
        Simulated duration (default: all of the weather).
    start_s : float, optional, [s]
        UTC start (default: the first whole minute of the weather at the site).
    offline_theta : ndarray (9,) or (13,), optional
        The frozen estimate of ``calibration="offline"``.
    fixed_command : Command
        The command of ``controller="fixed"``.
    options : PlantOptions, optional
        Plant switches (default: the full stratified plant).
    search : SearchSettings
        What ``plant-oracle`` rolls out.
    faults : tuple of FaultSpec
        Simulated faults of the plant (:mod:`dsfd.sim.plant.faults`; relative starts count
        from the run's start); every controller's plant has them, the oracles' included.
    """

    controller: ControllerName = "mpc"
    calibration: CalibrationName = "online"
    seed: int = 1
    hours: float | None = None
    start_s: float | None = None
    offline_theta: np.ndarray | None = None
    fixed_command: Command = DEFAULT_FIXED
    options: PlantOptions | None = None
    search: SearchSettings = field(default_factory=SearchSettings)
    faults: tuple[FaultSpec, ...] = ()

    def check(self) -> None:
        """Raise ValueError for an impossible combination (the message says what to do)."""
        if self.controller not in CONTROLLERS:
            raise ValueError(f"controller {self.controller!r}: choose one of {CONTROLLERS}")
        if self.calibration not in CALIBRATIONS:
            raise ValueError(f"calibration {self.calibration!r}: choose one of {CALIBRATIONS}")
        if (self.calibration == "offline" and self.offline_theta is None
                and self.controller not in ("fixed", *TRUE_THETA)):
            raise ValueError("calibration offline needs frozen parameters: pass --params "
                             "PARAMS.yaml (made by dsfd calibrate)")


@dataclass
class ClosedLoopResult:
    """Per-cycle records and totals of one run (SI inside; see :meth:`summary`)."""

    settings: ClosedLoopSettings
    panel: str
    start_s: float
    step_s: float
    heat_j: dict[str, np.ndarray]  # per cycle, J over the interval that cycle commanded
    heating: np.ndarray  # per cycle, bool
    ghi_wm2: np.ndarray  # per cycle, the station's global horizontal irradiance
    commands: list[Command]
    methods: Counter[str]
    decide_ms: np.ndarray
    calibration_updates: int
    final_theta: np.ndarray
    wall_s: float
    site: tuple[float, float] = (0.0, 0.0)  # latitude, longitude [deg]
    #: Stages slower than the panel's budgets (lifted in a run, see SIM_BUDGET_S).
    late: dict[str, int] = field(default_factory=dict)
    notes: tuple[str, ...] = field(default_factory=tuple)
    #: Occupancy and the plant's comfort quantities per cycle, and the limits they are
    #: judged by (docs/model.md#plant-comfort).
    comfort: ComfortLog | None = None
    comfort_limits: Comfort = field(default_factory=Comfort)

    def comfort_summary(self, keep: np.ndarray | None = None) -> dict[str, float]:
        """:func:`~dsfd.sim.comfort_kpis.comfort_summary` of the run (``keep``: the cycles to
        count); empty without a comfort log."""
        return {} if self.comfort is None else comfort_summary(self.comfort,
                                                               self.comfort_limits, keep)

    @property
    def cycles(self) -> int:
        return len(self.commands)

    def j_per_cycle(self) -> np.ndarray:
        """Objective of each cycle's interval [J] (docs/model.md#control-objective, the cycle's
        mode)."""
        return room_objective_j(self.heat_j, self.heating)

    def louver_moves(self) -> int:
        """Commanded louver angle changes."""
        phis = [c.phi_deg for c in self.commands]
        return sum(1 for a, b in itertools.pairwise(phis) if a != b)

    def conditions(self, latitude_deg: float, longitude_deg: float) -> np.ndarray:
        """Sky condition of each cycle: ``night`` (sun below 5° or GHI < 20 W/m2), else by
        the clearness index k_t = GHI / (E_0 cos z): ``clear`` (> 0.55), ``overcast``
        (< 0.3) or ``mixed`` — the classes of the paper's Figure 11."""
        t = self.start_s + (np.arange(self.cycles) + 0.5) * self.step_s
        return sky_conditions(t, self.ghi_wm2, latitude_deg, longitude_deg)

    def by_condition(self, latitude_deg: float, longitude_deg: float) -> dict:
        """Per sky condition: cycles, regime shares, mean louver angle [deg], and for clear
        daytime the correlation of the louver angle with the solar elevation."""
        cond = self.conditions(latitude_deg, longitude_deg)
        phi = np.array([c.phi_deg for c in self.commands])
        afr = np.array([c.afr for c in self.commands])
        out: dict = {}
        for name in ("clear", "mixed", "overcast", "night"):
            sel = cond == name
            if not sel.any():
                continue
            regimes = Counter(afr[sel].tolist())
            out[name] = {"cycles": int(sel.sum()),
                         "regime_share": {str(r): n / sel.sum()
                                          for r, n in sorted(regimes.items())},
                         "phi_deg_mean": float(phi[sel].mean())}
        clear = cond == "clear"
        if clear.sum() > 2 and np.ptp(phi[clear]) > 0:
            t = self.start_s + (np.flatnonzero(clear) + 0.5) * self.step_s
            elev = solar_position(t, latitude_deg, longitude_deg).elevation_deg
            out["clear"]["phi_vs_elevation_corr"] = float(np.corrcoef(phi[clear], elev)[0, 1])
        return out

    def summary(self) -> dict:
        """Figures in engineering units (kWh, moves per day, ms), JSON-ready."""
        days = self.cycles * self.step_s / 86400.0
        regimes = Counter(c.afr for c in self.commands)
        d = self.decide_ms[np.isfinite(self.decide_ms)]
        return {
            "controller": self.settings.controller,
            "calibration": self.settings.calibration,
            "seed": self.settings.seed,
            "panel": self.panel,
            "days": days,
            "cycles": self.cycles,
            "heating_fraction": float(np.mean(self.heating)) if self.cycles else math.nan,
            "J_kwh": float(self.j_per_cycle().sum() / J_PER_KWH),
            **{f"{k}_kwh": float(v.sum() / J_PER_KWH) for k, v in self.heat_j.items()},
            "louver_moves_per_day": self.louver_moves() / days if days else math.nan,
            "regime_share": {str(r): n / self.cycles for r, n in sorted(regimes.items())},
            "methods": dict(self.methods),
            "decide_ms_median": float(np.median(d)) if d.size else math.nan,
            "decide_ms_p99": float(np.percentile(d, 99)) if d.size else math.nan,
            "calibration_updates": self.calibration_updates,
            "late_decisions": self.late.get("late_decisions", 0),
            "late_calibrations": self.late.get("late_calibrations", 0),
            "by_condition": self.by_condition(*self.site),
            "final_theta": [float(v) for v in self.final_theta[:N_PARAMS]],
            "wall_s": self.wall_s,
            "comfort": self.comfort_summary(),
            "notes": list(self.notes),
        }


def _controller_config(cfg: PanelConfig, controller: str) -> PanelConfig:
    """The panel as the run's controller sees it: its optimiser, and the stage budgets lifted
    (:data:`SIM_BUDGET_S`)."""
    # Every controller but these three plans with the mpc optimiser (the oracles and the
    # split controllers differ only in the information they give it).
    optimiser = {"paper-sqp": "paper-sqp", "rule": "rule", "fixed": "rule"}
    control = dataclasses.replace(cfg.control, optimiser=optimiser.get(controller, "mpc"),
                                  time_budget_s=SIM_BUDGET_S)
    daemon = dataclasses.replace(cfg.daemon, calibrate_budget_s=SIM_BUDGET_S,
                                 store_budget_s=SIM_BUDGET_S)
    return dataclasses.replace(cfg, control=control, daemon=daemon)


def run_closed_loop(cfg: PanelConfig, series: WeatherSeries, settings: ClosedLoopSettings, *,
                    progress: Callable[[int, int], None] | None = None,
                    state_dir: Path | None = None) -> ClosedLoopResult:
    """Run one controller against the truth plant on ``series`` (any site: replayed here).

    The daemon's cycle stores everything in ``state_dir`` as ``dsfd run`` does (for ``dsfd
    report``); by default a temporary directory, removed at the end.

    Raises
    ------
    ValueError
        Impossible settings (:meth:`ClosedLoopSettings.check`) or a window outside the data.
    """
    settings.check()
    site = at_site(series, cfg)
    dt = float(cfg.model.step_s)
    start, n = step_window(site, dt, start_s=settings.start_s, hours=settings.hours)
    # Every controller stops where the oracle's perfect forecast still has data, so runs of
    # different controllers over "all the weather" cover the same window.
    fits = int((site.coverage_s[1] - start) // dt) - cfg.control.horizon_steps - 1
    if fits < 1:
        raise ValueError("the weather ends within one control horizon of the start")
    n = min(n, fits)
    plant = Plant(cfg, settings.options, seed=settings.seed, weather_series=site,
                  faults=settings.faults)
    plant.reset(start, command=settings.fixed_command if settings.controller == "fixed"
                else None)
    if state_dir is not None:
        return asyncio.run(_run(cfg, plant, settings, start, n, state_dir, progress))
    with tempfile.TemporaryDirectory(prefix="dsfd-closed-loop-") as tmp:
        return asyncio.run(_run(cfg, plant, settings, start, n, Path(tmp), progress))


def _calibration_for(ctrl_cfg: PanelConfig, cfg: PanelConfig, plant: Plant,
                     settings: ClosedLoopSettings, state_dir: Path
                     ) -> CalibrationStage | FrozenCalibration:
    """The run's calibration: on-line, or frozen at the oracle's, the off-line or the
    panel's parameters."""
    model = LumpedModel(ctrl_cfg)
    if settings.controller not in TRUE_THETA and settings.calibration == "online":
        return CalibrationStage(ctrl_cfg, model, state_dir=state_dir)
    if settings.controller in TRUE_THETA:
        theta = oracle_theta(cfg, plant)
    elif settings.calibration == "offline":
        theta = settings.offline_theta
    else:
        theta = None
    return FrozenCalibration(ctrl_cfg, model, state_dir=state_dir, theta=theta)


def _controller_for(ctrl_cfg: PanelConfig, plant: Plant, settings: ClosedLoopSettings, *,
                    driver: SimulatedDriver, clock: SimulatedClock, store: Store,
                    calibration: CalibrationStage | FrozenCalibration) -> Controller:
    """The daemon's cycle for ``settings.controller``, given the information it may use."""
    cls, true_state, true_weather = CONTROLLER_CLASSES.get(settings.controller,
                                                            (Controller, False, False))
    controller = cls(ctrl_cfg, driver=driver, clock=clock, store=store,
                     calibration=calibration, write_enabled=True,
                     plant_heat_j=plant.room_heat_j)
    controller.io.read_budget_s = controller.io.write_budget_s = SIM_BUDGET_S
    if isinstance(controller, OracleController):
        controller.plant = plant
        controller.true_state, controller.true_weather = true_state, true_weather
    if isinstance(controller, PlantOracleController):
        controller.search = PlantOracle(ctrl_cfg, settings=settings.search)
    return controller


async def _run(cfg: PanelConfig, plant: Plant, settings: ClosedLoopSettings, start: float,
               n: int, state_dir: Path, progress: Callable[[int, int], None] | None
               ) -> ClosedLoopResult:
    ctrl_cfg = _controller_config(cfg, settings.controller)
    calibration = _calibration_for(ctrl_cfg, cfg, plant, settings, state_dir)
    clock = SimulatedClock(start_utc_s=start)
    driver = SimulatedDriver(plant)
    store = Store.open(state_dir)
    store.begin_run(panel=cfg.panel.id, mode=f"closed-loop simulation, controller "
                    f"{settings.controller}, calibration {settings.calibration}",
                    version="sim", config_path=None, config=dataclasses.asdict(ctrl_cfg))
    controller = _controller_for(ctrl_cfg, plant, settings, driver=driver, clock=clock,
                                 store=store, calibration=calibration)
    heat: dict[str, list[float]] = {k: [] for k in ROOM_FLOWS}
    heating: list[bool] = []
    ghi: list[float] = []
    commands: list[Command] = []
    methods: Counter[str] = Counter()
    decide_ms: list[float] = []
    updates = 0
    late: Counter[str] = Counter()
    comfort = ComfortLog.empty(cfg.model.step_s)
    wall = time.perf_counter()
    try:
        for i in range(n):
            await clock.sleep_until(i * plant.cfg.model.step_s)
            if settings.controller == "fixed":
                await driver.read(clock.wall())  # advances the plant to the cycle time
                cmd, method, mode, ms = settings.fixed_command, "fixed", None, math.nan
            else:
                out = await controller.run_cycle(Slot(i, clock.monotonic(), 0))
                cmd = Command(out.command.phi_deg, out.command.afr, out.command.or_pct)
                method, mode = out.method, out.heating
                ms = out.timings_ms.get("decide", math.nan)
                updates += int(out.calibration is not None and out.calibration.updated)
                late["late_decisions"] += ms > 1e3 * cfg.control.time_budget_s
                late["late_calibrations"] += (out.timings_ms.get("calibrate", 0.0)
                                              > 1e3 * cfg.daemon.calibrate_budget_s)
            before = plant.room_heat_j()
            plant.advance(float(cfg.model.step_s))  # the interval the command holds
            after = plant.room_heat_j()
            # The next read finds the plant already there (the driver only advances when
            # behind), so the room heat of each interval is attributed to its command.
            for k in ROOM_FLOWS:
                heat[k].append(after[k] - before[k])
            comfort.record(plant)
            station = plant.station_weather()
            if mode is None:  # no controller decided a mode: the panel's rule, as the loop
                mode = is_heating(cfg.control, station["t_out_c"] + T_ZERO)
            heating.append(bool(mode))
            ghi.append(station["ghi_wm2"])
            commands.append(cmd)
            methods[method] += 1
            decide_ms.append(ms)
            if progress is not None:
                progress(i + 1, n)
    finally:
        store.end_run(reason="done", cycles=len(commands))
        store.close()
    return ClosedLoopResult(
        settings=settings, panel=cfg.panel.id, start_s=start, step_s=float(cfg.model.step_s),
        heat_j={k: np.asarray(v) for k, v in heat.items()}, heating=np.asarray(heating),
        ghi_wm2=np.asarray(ghi, float),
        commands=commands, methods=methods, decide_ms=np.asarray(decide_ms, float),
        calibration_updates=updates, final_theta=calibration.theta, late=dict(late),
        wall_s=time.perf_counter() - wall, comfort=comfort, comfort_limits=cfg.comfort,
        site=(cfg.site.latitude_deg, cfg.site.longitude_deg),
        notes=(f"truth plant seed {settings.seed}; true h multipliers "
               + ", ".join(f"{m:.2f}" for m in plant.params.h_multipliers)
               + f"; f_true {plant.params.f:.0f}",))

