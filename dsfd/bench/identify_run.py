"""One seed of ``dsfd bench identify``: the daemon's own loop against a simulated plant, with
the calibration's estimate and posterior recorded after every cycle.

The daemon runs in this process exactly as ``dsfd run --dry-run --plant sim`` runs it
(:func:`dsfd.daemon.runner.serve`: quality checks, observer, on-line calibration in its worker
thread, decision, safety pipeline, verified writes to the simulated plant, one SQLite
transaction per cycle in a temporary state directory) on the simulated clock, as fast as the
machine allows. Three things differ, all at the edge:

* the plant is built here (:func:`dsfd.sim.daemon_plant.simulated_plant`) with the switches the
  bench asks for: the lumped-equivalent plant (the model's own structure, so the true θ is
  known: :meth:`~dsfd.sim.plant.config.TrueParameters.lumped_theta`; actuators ideal, as in the
  model; the daemon's cavity air well mixed like the plant's one node, :func:`daemon_config`)
  or the full-fidelity truth plant, each with ideal or realistic sensors;
* under ``protocol="paper"`` the cycle is a :class:`ScheduleController`, which applies the
  paper's random excitation (:func:`dsfd.sim.protocol.paper_protocol`) instead of the
  optimiser's decisions (hook: ``RunOptions.controller``); under ``"closed-loop"`` it is the
  daemon's own :class:`~dsfd.daemon.loop.Controller` (the panel's optimiser);
* the stage budgets are lifted (:data:`dsfd.sim.closed_loop.SIM_BUDGET_S`), as in the
  closed-loop simulation: on the simulated clock they would only turn the machine's load into
  abandoned calibration updates. The stages slower than the panel's budgets are counted.

After every successful update the daemon saves its calibration state
(``calibration.json``: θ̂, the heat-flux offsets and the posterior covariance in the fitting
coordinates); the bench reads it back there, so the posterior is the one the daemon keeps.
"""

from __future__ import annotations

import asyncio
import dataclasses
import logging
import math
import os
import tempfile
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.control.optimiser import Decision
from dsfd.daemon.calibration import STATE_FILE
from dsfd.daemon.logging_setup import configure_logging
from dsfd.daemon.loop import Controller, CycleOutcome
from dsfd.daemon.observer import StateEstimate
from dsfd.daemon.runner import RunOptions, serve
from dsfd.daemon.weather import CycleWeather
from dsfd.drivers.base import Command as DriverCommand
from dsfd.drivers.base import Sample
from dsfd.estimation.params import PARAMETER_NAMES, ParameterSpace
from dsfd.estimation.state import CalibrationState
from dsfd.physics.forcing import Forcing
from dsfd.report.kpis import PredictionErrors, prediction_errors, report_step_s
from dsfd.sim.closed_loop import SIM_BUDGET_S
from dsfd.sim.daemon_plant import DEFAULT_WEATHER, simulated_plant
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.protocol import Schedule, paper_protocol
from dsfd.storage.calibration_file import load_state
from dsfd.storage.history import read_history

__all__ = ["LUMPED_CAVITY_AIR_PROFILE", "PLANTS", "PROTOCOLS", "SENSORS", "RunSpec",
           "ScheduleController", "SeedTrace", "daemon_config", "plant_options_for", "run_seed"]

PLANTS = ("lumped", "truth")
SENSORS = ("ideal", "realistic")
PROTOCOLS = ("paper", "closed-loop")
#: The daemon's cavity air on the lumped-equivalent plant (:func:`daemon_config`).
LUMPED_CAVITY_AIR_PROFILE = "well_mixed"
#: Progress lines every this many cycles (6 simulated hours).
PROGRESS_EVERY = 360


@dataclass(frozen=True, kw_only=True)
class RunSpec:
    """What one bench run simulates (the same for every seed)."""

    config_path: Path
    cfg: PanelConfig
    plant: str = "lumped"
    sensors: str = "realistic"
    protocol: str = "paper"
    cycles: int = 1440
    weather: str = DEFAULT_WEATHER

    def check(self) -> None:
        """``ValueError`` naming the bad choice."""
        for name, value, choices in (("plant", self.plant, PLANTS),
                                     ("sensors", self.sensors, SENSORS),
                                     ("protocol", self.protocol, PROTOCOLS)):
            if value not in choices:
                raise ValueError(f"--{name} {value!r}: choose one of {', '.join(choices)}")
        if self.cycles < 1:
            raise ValueError(f"{self.cycles} cycles: need at least one")


@dataclass(frozen=True, eq=False)
class SeedTrace:
    """What one seed's run left: per cycle (n,) the estimate in force after the cycle.

    Attributes
    ----------
    time_s : ndarray (n,), [s]
        Cycle times (UTC).
    theta : ndarray (n, 13)
        ϑ̂ = (θ̂, q̂) in force after each cycle (the priors before the first update).
    sd_ratio : ndarray (n, 13)
        Posterior sd / first-prior sd of each component, in the fitting coordinates
        (log θ; n and q linear), from the covariance the daemon saved.
    truth : ndarray (9,) or None
        The plant's θ on the model's terms (lumped-equivalent plant only).
    space : ParameterSpace
        Bounds and fixed components of the calibration.
    errors : PredictionErrors
        One-step and horizon errors of the model and of persistence, per stored cycle,
        computed from the daemon's database as ``dsfd report`` does.
    errors_time_s : ndarray, [s]
        The stored cycles' times (the rows of ``errors``).
    step_s : float, [s]
    counts : dict
        ``cycles``, ``calibration_updates``, ``calibration_attempts``, ``late_calibrations``,
        ``late_decisions``, ``decisions_protocol``, ``decisions_mpc``, ``decisions_rule``,
        ``decisions_safe``, ``cpu_s``, ``wall_s``.
    """

    seed: int
    time_s: np.ndarray
    theta: np.ndarray
    sd_ratio: np.ndarray
    truth: np.ndarray | None
    space: ParameterSpace
    errors: PredictionErrors
    errors_time_s: np.ndarray
    step_s: float
    counts: dict[str, float]
    #: Parameters whose value on the plant lies on a calibration bound by construction
    #: (:func:`truth_on_bound`): a share of cycles there is the right answer, not a failure.
    truth_on_bound: tuple[str, ...] = ()


def truth_on_bound(options: PlantOptions, space: ParameterSpace) -> tuple[str, ...]:
    """Parameters the plant's own structure puts on a calibration bound.

    The full truth plant drives its diagonal paths (regimes 5–8) as orifices
    (``PlantOptions.diagonal_flow == "orifice"``, docs/model.md#plant-airflow): flow ∝ Δp^½,
    which is the power law Q = c Δp^n at n = ½, the lower bound of n (the turbulent limit).
    The model's n is then right at that bound."""
    i = PARAMETER_NAMES.index("n")
    if options.diagonal_flow == "orifice" and abs(space.lower[i] - 0.5) < 1e-9:
        return ("n",)
    return ()


class ScheduleController(Controller):
    """The daemon's cycle with the decision taken from a fixed schedule.

    Everything else is the daemon's own: the safety pipeline still checks the command, the
    write is verified, and the calibration record gets the position actually applied.
    Without the required weather the daemon's own rule applies (safe state).
    """

    def __init__(self, *args: object, schedule: Schedule, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.schedule = schedule

    async def _decide(self, weather: CycleWeather, estimate: StateEstimate,
                      current: DriverCommand | None, checked: Sample, forecast: Forcing | None,
                      *, heating: bool, occupancy: np.ndarray
                      ) -> tuple[Decision | None, str, str, str]:
        if weather.inputs is None or weather.forcing is None or forecast is None:
            return await super()._decide(weather, estimate, current, checked, forecast,
                                         heating=heating, occupancy=occupancy)
        cmd = self.schedule.at(self.clock.wall())
        return (Decision(phi_deg=cmd.phi_deg, afr=cmd.afr, or_pct=cmd.or_pct,
                         method="protocol", cost_j=math.nan,
                         trace=("paper protocol: random louver angle and regime every "
                                "30-90 min",)), "protocol", "", "")


def plant_options_for(cfg: PanelConfig, *, plant: str, sensors: str) -> PlantOptions:
    """``lumped``: every switch at the lumped model's setting (ideal actuators, as the model
    has them) with ``sensors``; ``truth``: the full-fidelity plant with ``sensors``."""
    if plant == "lumped":
        return PlantOptions.lumped_equivalent(cfg.model, sensors=sensors, actuators="ideal")
    if plant == "truth":
        return PlantOptions(sensors=sensors)
    raise ValueError(f"--plant {plant!r}: choose one of {', '.join(PLANTS)}")


def daemon_config(cfg: PanelConfig, *, plant: str) -> PanelConfig:
    """The panel as the bench's daemon runs it: the decision, calibration and store budgets
    lifted (module doc), and on the lumped-equivalent plant the model's cavity air well mixed,
    as the plant's one air node is (``model.cavity_air_profile``; the N = 1 equivalence of
    docs/model.md#plant-switches): only then is the plant the model's own structure and its θ
    the true one."""
    model = cfg.model
    if plant == "lumped":
        model = dataclasses.replace(model, cavity_air_profile=LUMPED_CAVITY_AIR_PROFILE)
    return dataclasses.replace(
        cfg, model=model,
        control=dataclasses.replace(cfg.control, time_budget_s=SIM_BUDGET_S),
        daemon=dataclasses.replace(cfg.daemon, calibrate_budget_s=SIM_BUDGET_S,
                                   store_budget_s=SIM_BUDGET_S))


class _Recorder:
    """``RunOptions.on_cycle``: the estimate in force and the stage timings of every cycle."""

    def __init__(self, spec: RunSpec, space: ParameterSpace, state_dir: Path,
                 progress: Callable[[str], None] | None, seed: int) -> None:
        self.spec, self.space, self.path = spec, space, state_dir / STATE_FILE
        self.progress, self.seed = progress, seed
        n = spec.cycles
        self.time_s = np.full(n, np.nan)
        self.theta = np.full((n, space.default.size), np.nan)
        self.sd_ratio = np.full_like(self.theta, np.nan)
        self.counts: Counter[str] = Counter()
        self._set(CalibrationState.initial(spec.cfg.panel.id, space))
        self._t0 = time.perf_counter()

    def _set(self, state: CalibrationState) -> None:
        self._theta = state.theta.copy()
        self._ratio = np.sqrt(np.clip(np.diag(state.cov_z), 0.0, None)) / state.prior_sd_z

    def __call__(self, out: CycleOutcome) -> None:
        i = out.cycle - 1
        if i >= self.time_s.size:
            return
        cal, t = out.calibration, out.timings_ms
        if cal is not None:
            self.counts["calibration_attempts"] += 1
            self.counts["late_calibrations"] += (
                t.get("calibrate", 0.0) > 1e3 * self.spec.cfg.daemon.calibrate_budget_s)
            if cal.updated:
                self.counts["calibration_updates"] += 1
                self._set(load_state(self.path, space=self.space,
                                     panel_id=self.spec.cfg.panel.id))
        self.counts["late_decisions"] += (t.get("decide", 0.0)
                                          > 1e3 * self.spec.cfg.control.time_budget_s)
        self.counts[f"decisions_{out.method}"] += 1
        self.time_s[i], self.theta[i], self.sd_ratio[i] = out.time_s, self._theta, self._ratio
        if self.progress is not None and out.cycle % PROGRESS_EVERY == 0:
            self.progress(f"  seed {self.seed}: cycle {out.cycle}/{self.spec.cycles}, "
                          f"{self.counts['calibration_updates']} updates, "
                          f"{time.perf_counter() - self._t0:.0f} s")


def run_seed(spec: RunSpec, seed: int, *, progress: Callable[[str], None] | None = None,
             keep_state: Path | None = None) -> SeedTrace:
    """Run the daemon for ``spec.cycles`` cycles against the plant of ``seed``.

    The daemon's state directory is temporary, or ``keep_state/seed<seed>`` (created; it must
    not exist yet) to read it afterwards with ``dsfd report``.

    Raises
    ------
    FileNotFoundError, ValueError
        Unknown weather, bad choices, an existing ``keep_state/seed<seed>``.
    KeyboardInterrupt
        The run was stopped (SIGINT/SIGTERM) before its last cycle.
    """
    spec.check()
    kept = None if keep_state is None else Path(keep_state) / f"seed{seed}"
    if kept is not None and kept.exists():
        raise ValueError(f"{kept} exists: a kept state directory is never reused (its runs "
                         "would overlap the new one)")
    cfg = daemon_config(spec.cfg, plant=spec.plant)
    options = plant_options_for(cfg, plant=spec.plant, sensors=spec.sensors)
    sim = simulated_plant(cfg, weather=spec.weather, cycles=spec.cycles, seed=seed,
                          options=options)
    truth = sim.plant.params.lumped_theta(cfg) if spec.plant == "lumped" else None
    space = ParameterSpace.from_panel(cfg)
    factory: Callable[..., Controller] = _controller_factory(cfg, spec, sim.start_s, seed)
    sink = open(os.devnull, "w")  # noqa: SIM115 - open for the whole run, closed below
    configure_logging(stream=sink, json=True, level=logging.WARNING)
    cpu0, wall0 = os.times(), time.perf_counter()
    try:
        with tempfile.TemporaryDirectory(prefix="dsfd-bench-identify-") as tmp:
            state_dir = Path(tmp) if kept is None else kept
            state_dir.mkdir(parents=True, exist_ok=True)
            recorder = _Recorder(spec, space, state_dir, progress, seed)
            opts = RunOptions(config_path=spec.config_path, dry_run=True, plant="sim",
                              plant_fidelity="full" if spec.plant == "truth" else "lumped",
                              cycles=spec.cycles, seed=seed, weather=spec.weather,
                              on_cycle=recorder, controller=factory)
            summary = asyncio.run(serve(opts, cfg, state_dir=state_dir, plant=sim,
                                        print_line=lambda _line: None))
            if summary.cycles < spec.cycles:
                raise KeyboardInterrupt(f"seed {seed} stopped after {summary.cycles} of "
                                        f"{spec.cycles} cycles")
            history = read_history(state_dir)
            step_s = report_step_s(history, history.config)
            errors = prediction_errors(history, step_s)
    finally:
        sink.close()
    cpu1 = os.times()
    counts = {k: float(v) for k, v in recorder.counts.items()}
    counts.update(cycles=float(summary.cycles),
                  cpu_s=(cpu1.user - cpu0.user) + (cpu1.system - cpu0.system),
                  wall_s=time.perf_counter() - wall0)
    return SeedTrace(seed=seed, time_s=recorder.time_s, theta=recorder.theta,
                     sd_ratio=recorder.sd_ratio, truth=truth, space=space, errors=errors,
                     errors_time_s=history.time_s, step_s=step_s, counts=counts,
                     truth_on_bound=truth_on_bound(options, space) if truth is None else ())


def _controller_factory(cfg: PanelConfig, spec: RunSpec, start_s: float, seed: int
                        ) -> Callable[..., Controller]:
    """The cycle of the run: the schedule's (paper protocol, seeded like the plant) or the
    daemon's own, with the device budgets lifted (module doc)."""
    schedule = None
    if spec.protocol == "paper":
        schedule = paper_protocol(cfg, seed=seed, start_s=start_s,
                                  duration_s=(spec.cycles + 1) * cfg.daemon.cycle_period_s)

    def build(*args: object, **kwargs: object) -> Controller:
        controller = (Controller(*args, **kwargs) if schedule is None  # type: ignore[arg-type]
                      else ScheduleController(*args, schedule=schedule, **kwargs))
        controller.io.read_budget_s = controller.io.write_budget_s = SIM_BUDGET_S
        return controller

    return build
