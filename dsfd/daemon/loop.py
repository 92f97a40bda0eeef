"""One control cycle: read → quality → state estimate → calibration → optimise → safety →
write → store.

The loop only moves data between the core functions (observer, calibrator, optimiser,
baseline, safety pipeline) and the two edges (drivers, store), timing every stage:

* **read** — all drivers concurrently, plus the actuator read-back, under the devices' read
  budget; a driver fault is a bad reading, never an exception out of here
  (:mod:`dsfd.daemon.device_io`);
* **quality** — :class:`~dsfd.daemon.quality.QualityChecker` flags what cannot be used;
* **estimate** — measured weather → forcing (:mod:`dsfd.daemon.weather`) and the state
  estimate (:mod:`dsfd.daemon.observer`);
* **calibrate** — when due, a refit in a worker thread under ``daemon.calibrate_budget_s``;
* **decide** — the configured optimiser in a worker thread under ``control.time_budget_s``;
  if it cannot run (states missing), fails or is late, the rule-based baseline decides; if
  even that lacks its inputs (outdoor air, irradiance), nothing is proposed and the safety
  pipeline commands the safe state;
* **safety** — :class:`~dsfd.daemon.safety.SafetyPipeline`, with the decision trace;
* **write** — under the devices' write budget, verified by read-back (unless a dry run;
  :mod:`dsfd.daemon.device_io`);
* **predict** — the states at the end of the horizon with the applied position held (for
  the report's multi-step prediction error; the one-step prediction and the room-side heat
  of the step that ended come free with the observer's update);
* **store** — one SQLite transaction per cycle under ``daemon.store_budget_s``.

Worker threads (``asyncio.to_thread``, which copies the logging context) keep the event loop
free for signals and watchdog pings. A late job is abandoned, never applied, and while it
still runs the next cycle does not start another one of its kind.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable, Mapping
from typing import TypeVar

import numpy as np

from dsfd.config.control import Control
from dsfd.config.panel import PanelConfig
from dsfd.control.baseline import rule_decision
from dsfd.control.comfort import ComfortCheck, comfort_check
from dsfd.control.comfort_horizon import LEAST_VIOLATION
from dsfd.control.objective import is_heating
from dsfd.control.occupancy import EffectiveOccupancy, effective_profile
from dsfd.control.optimiser import ControlProblem, Decision, MpcOptimiser
from dsfd.daemon.calibration import CalibrationStage, UpdateOutcome
from dsfd.daemon.clock import Clock, Slot, WallClockWatch
from dsfd.daemon.device_io import DeviceIO, DeviceReading
from dsfd.daemon.hold import HoldUpdate
from dsfd.daemon.jobs import OffLoopJob
from dsfd.daemon.logging_setup import get_logger
from dsfd.daemon.manual import ManualStage
from dsfd.daemon.memory import trim_heap
from dsfd.daemon.observer import STATE_SIGNALS, StateEstimate, StateObserver, horizon_end
from dsfd.daemon.occupancy import OCCUPIED_SIGNAL
from dsfd.daemon.outcome import CycleOutcome
from dsfd.daemon.quality import QualityChecker
from dsfd.daemon.record import cycle_record
from dsfd.daemon.safety import SafetyContext, SafetyPipeline
from dsfd.daemon.weather import CycleWeather, forecast_forcing, measured_weather
from dsfd.drivers.base import Command, Driver, Sample
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import FacadeOptics, Forcing, WeatherInputs, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.storage.timeseries import Store

__all__ = ["Controller", "CycleOutcome", "OffLoopJob"]

log = get_logger(__name__)
T = TypeVar("T")


class Controller:
    """The cycle of one panel (drivers, clock and store given by the runner)."""

    def __init__(self, cfg: PanelConfig, *, driver: Driver, clock: Clock, store: Store,
                 calibration: CalibrationStage, write_enabled: bool,
                 plant_heat_j: Callable[[], Mapping[str, float] | None] | None = None) -> None:
        self.driver = driver
        self.io = DeviceIO(driver, write_enabled=write_enabled)
        #: A simulated plant's cumulative room heat by term [J] (None: real hardware).
        self.plant_heat_j = plant_heat_j
        self.clock = clock
        self.store = store
        self.calibration = calibration
        self.quality = QualityChecker(cfg.daemon.quality)
        self.safety = SafetyPipeline(cfg)
        self.manual = ManualStage(cfg, store)
        self.cycles = 0
        self.optimise_job = OffLoopJob("optimisation")
        self.calibrate_job = OffLoopJob("calibration update")
        self.store_job = OffLoopJob("store")
        self._grid0_s: float | None = None  # the first cycle's slot on the monotonic grid
        self._clock_watch = WallClockWatch()
        self._configure(cfg)

    def _configure(self, cfg: PanelConfig) -> None:
        self.cfg = cfg
        model = LumpedModel(cfg)
        # The optimiser keeps its own model and optics caches: it may still be running in
        # its thread (late, abandoned) while the loop thread steps the observer.
        self.optics = FacadeOptics(cfg)
        self.observer = StateObserver(model, max_predicted_cycles=cfg.daemon.max_predicted_cycles)
        self.mpc = MpcOptimiser(cfg)
        self.io.configure(cfg.devices)

    def reconfigure(self, cfg: PanelConfig) -> str:
        """Switch to a reloaded, validated configuration between cycles."""
        self.quality.settings = cfg.daemon.quality
        self.safety.reconfigure(cfg)
        self.manual.reconfigure(cfg)
        self._configure(cfg)
        return self.calibration.reconfigure(cfg, LumpedModel(cfg))

    # ------------------------------------------------------------------ the cycle
    async def run_cycle(self, slot: Slot) -> CycleOutcome:
        """Run one cycle at ``slot``; never raises for device or numerical faults."""
        t: dict[str, float] = {}
        t0 = time.perf_counter()
        now_s, events = self._begin(slot)
        got = await self.io.read(now_s)
        plant_heat = self.plant_heat_j() if self.plant_heat_j is not None else None
        t["read"] = _ms(t0)
        mark = time.perf_counter()
        report = self.quality.check(got.sample, age_s=t["read"] / 1e3)
        checked = report.sample
        t["quality"] = _ms(mark)

        held = self._hold_update(slot, now_s, got)
        occupancy = self.manual.occupancy.resolve(self.cfg, checked, report.flags, now_s=now_s)
        # While held, the positions read back are what the panel got.
        current = got.read_back or self.io.expected or self.io.last_written
        mark = time.perf_counter()
        weather = measured_weather(self.cfg, checked)
        estimate = self._estimate(checked, weather, current)
        t["estimate"] = _ms(mark)

        mark = time.perf_counter()
        calibration = await self._calibrate(checked, now_s)
        t["calibrate"] = _ms(mark)

        mark = time.perf_counter()
        objective, objective_by = self.manual.objective_mode
        heating, forecast = self._outlook(weather, objective, now_s)
        if held.hold is None:
            decision, method, fallback, no_decision = await self._decide(
                weather, estimate, current, checked, forecast, heating=bool(heating),
                occupancy=self._occupancy_profile(now_s, self.cfg.control.horizon_steps,
                                                  checked))
        else:  # a person has the panel: nothing to optimise
            decision, method, fallback, no_decision = None, "manual", "", ""
        t["decide"] = _ms(mark)

        mark = time.perf_counter()
        ctx = SafetyContext(now_s=self.clock.monotonic(),
                            wind_speed_ms=checked.good("wind_speed_ms"),
                            bad_signals=frozenset(report.flags), current=current,
                            no_decision_reason=no_decision, hold=held.hold)
        safe = self.safety.apply(None if decision is None else _command_or_none(decision), ctx)
        if safe.faulted:  # the faults stage replaced the decision
            method = "safe"
        t["safety"] = _ms(mark)

        mark = time.perf_counter()
        write, status = await self.io.write(safe.command) if safe.write else (None, "held")
        t["write"] = _ms(mark)
        # Held or a dry run: the positions read back are what the panel got.
        applied = safe.command if status not in ("dry-run", "held") else current
        self.calibration.set_controls(applied)

        mark = time.perf_counter()
        horizon_x = self._horizon_end(estimate, forecast, applied)
        t["predict"] = _ms(mark)
        mark = time.perf_counter()
        comfort = self._comfort(estimate, forecast, safe.command, occupancy, decision)
        t["comfort"] = _ms(mark)

        outcome = CycleOutcome(
            cycle=self.cycles, slot=slot.index, skipped_slots=slot.skipped, time_s=now_s,
            method=method, command=safe.command, proposed=decision, fallback=fallback,
            heating=heating, safety=safe, write_status=status, write=write, quality=report,
            calibration=calibration, timings_ms=t, manual_override=bool(held.moved),
            estimate=estimate, applied=applied, horizon_x_k=horizon_x,
            horizon_s=self.cfg.control.horizon_steps * self.cfg.model.step_s,
            plant_heat_j=plant_heat, hold=held.hold, objective_mode=objective,
            mode_command_id=objective_by,
            run_elapsed_s=round(slot.deadline_s - self._grid0_s, 6),
            events=[*events, *held.events, *_drain(self.calibration.events)],
            command_results=held.results, comfort=comfort, occupancy=occupancy,
            occupancy_override=self.manual.occupancy.override)
        mark = time.perf_counter()
        outcome.store_ok = await self._store(outcome, weather)
        t["store"] = _ms(mark)
        t["total"] = _ms(t0)
        return outcome

    def _begin(self, slot: Slot) -> tuple[float, list[tuple[str, str, str]]]:
        """Count the cycle; its wall-clock time and the events of a wall-clock step."""
        self.cycles += 1
        now_s = self.clock.wall()
        events = self._clock_events(now_s)
        if self._grid0_s is None:
            self._grid0_s = slot.deadline_s
        if slot.skipped:
            self.observer.reset()  # the prediction spans one step; a gap restarts it
        return now_s, events

    def _outlook(self, weather: CycleWeather, objective: str, now_s: float
                 ) -> tuple[bool | None, Forcing | None]:
        """Heating (else cooling) now under ``objective``, and the forecast over the
        horizon; both None without the weather."""
        if weather.inputs is None:
            return None, None
        heating = is_heating(self._control(objective), float(weather.inputs.t_out_k[0]))
        return heating, self._forecast(weather.inputs, now_s)

    def _control(self, objective: str) -> Control:
        """The control settings with the objective in force (an operator's ``mode``)."""
        if objective == self.cfg.control.mode:
            return self.cfg.control
        return dataclasses.replace(self.cfg.control, mode=objective)

    def _clock_events(self, now_s: float) -> list[tuple[str, str, str]]:
        """A wall-clock step since the last cycle: logged, an event, and the calibration
        record restarted (rows on two time lines cannot be cut into model steps)."""
        step = self._clock_watch.step(self.clock.monotonic(), now_s)
        if step is None:
            return []
        self.calibration.restart_record()
        why = (f"wall clock stepped by {step:+.1f} s since the last cycle (NTP or RTC); the "
               "cycle grid runs on the monotonic clock and is unchanged; the calibration "
               "record restarts")
        log.warning(why, step_s=round(step, 3))
        return [("warning", "clock_step", why)]

    def _hold_update(self, slot: Slot, now_s: float, got: DeviceReading) -> HoldUpdate:
        up = self.manual.update(now_mono_s=slot.deadline_s, now_s=now_s,
                                read_back=got.read_back, expected=self.io.expected,
                                input_active=got.input_active,
                                input_where=self.driver.override_input or "")
        if up.adopted:
            self.io.expected = got.read_back  # the panel is where the person put it
        self.manual.handled(up.results)
        for level, kind, message in up.events:
            log.log(logging.WARNING if level == "warning" else logging.INFO, message,
                    event_kind=kind)
        return up

    def _estimate(self, checked: Sample, weather: CycleWeather, current: Command | None
                  ) -> StateEstimate:
        y = {n: v for n in STATE_SIGNALS if (v := checked.good(n)) is not None}
        step = None
        if weather.forcing is not None and current is not None:
            loads = self.optics.loads(weather.forcing, math.radians(current.phi_deg))
            step = step_inputs(weather.forcing, loads)
        return self.observer.update(y, step=step, applied=current,
                                    theta=self.calibration.theta,
                                    offsets=self.calibration.offsets)

    async def _calibrate(self, checked: Sample, now_s: float) -> UpdateOutcome | None:
        self.calibration.add_row(checked)
        if not self.calibration.due(now_s):
            return None
        result, why = await self.calibrate_job.run(self.calibration.prepare_update(),
                                                   budget_s=self.cfg.daemon.calibrate_budget_s)
        if result is None:
            log.warning("calibration update abandoned: %s; parameters kept", why)
            return UpdateOutcome(False, why, self.calibration.theta, math.nan, 0)
        outcome = self.calibration.accept(result, now_s=now_s)
        trim_heap()  # the refit's temporaries are free now; give their pages back
        if outcome.updated:
            log.info("calibration updated", **self.calibration.theta_by_name(),
                     residuals=outcome.n_residuals)
        else:
            log.info("calibration update skipped: %s", outcome.skipped)
        return outcome

    def _occupancy_profile(self, now_s: float, steps: int, checked: Sample) -> np.ndarray:
        """Whether the room is occupied at the start of each of the next ``steps`` model
        steps from ``now_s``: the one place the decision learns about occupancy
        (docs/model.md#comfort-constraints): an operator's override until its end, else the
        occupied signal's GOOD reading carried over, else the weekly schedule."""
        times_s = now_s + self.cfg.model.step_s * np.arange(max(steps, 1))
        profile, _ = effective_profile(
            times_s, occupancy=self.cfg.occupancy, utc_offset_h=self.cfg.site.utc_offset_h,
            override=self.manual.occupancy.override, signal=checked.good(OCCUPIED_SIGNAL))
        return profile

    async def _decide(self, weather: CycleWeather, estimate: StateEstimate,
                      current: Command | None, checked: Sample, forecast: Forcing | None, *,
                      heating: bool, occupancy: np.ndarray
                      ) -> tuple[Decision | None, str, str, str]:
        """(decision, method, fallback reason, why no decision at all); ``occupancy`` per
        horizon step (:meth:`_occupancy_profile`)."""
        if weather.inputs is None or weather.forcing is None or forecast is None:
            why = "required weather not GOOD: " + ", ".join(
                f"{n} ({checked.quality(n).value})" for n in weather.missing)
            return None, "safe", why, why
        wanted = self.cfg.control.optimiser
        fallback = ""
        if wanted != "rule":
            if not estimate.usable:
                fallback = f"state estimate not usable: {estimate.why}"
            else:
                problem = ControlProblem(
                    x0=estimate.x_k, forcing=forecast,
                    theta=self.calibration.theta, heating=heating,
                    heat_offsets_wm2=(self.calibration.offsets if self.cfg.control.heat_offsets
                                      else None),
                    previous_phi_deg=None if current is None else current.phi_deg,
                    previous_afr=None if current is None else current.afr,
                    previous_or_pct=None if current is None else current.or_pct,
                    occupied=occupancy)
                decision, why = await self.optimise_job.run(
                    self._optimiser(problem), budget_s=self.cfg.control.time_budget_s)
                if decision is not None and _command_or_none(decision) is not None:
                    if decision.comfort.startswith(LEAST_VIOLATION):
                        log.info("comfort: %s", decision.comfort)
                    return decision, decision.method, "", ""
                fallback = why or f"optimiser returned an invalid command {decision}"
        t5 = estimate.celsius(4) if estimate.age_cycles[4] <= \
            self.cfg.daemon.max_predicted_cycles else None
        forcing = weather.forcing
        decision = rule_decision(
            self.cfg, heating=heating, t5_c=t5, t_in_c=weather.t_room_c,
            t_out_c=float(weather.inputs.t_out_k[0]) - T_ZERO,
            beam_wm2=float(forcing.beam_wm2[0]), profile_deg=float(forcing.profile_deg[0]),
            previous_afr=None if current is None else current.afr, occupied=bool(occupancy[0]))
        if fallback:
            log.info("fallback to the baseline: %s", fallback)
        return decision, "rule", fallback, ""

    def _forecast(self, measured: WeatherInputs, now_s: float) -> Forcing:
        """The façade boundary over the horizon from ``now_s``: persistence of the measured
        interval (a simulation's oracle overrides this with the true weather)."""
        return forecast_forcing(self.cfg, measured, start_s=now_s)

    def _horizon_end(self, estimate: StateEstimate, forecast: Forcing | None,
                     applied: Command | None) -> np.ndarray | None:
        if forecast is None or applied is None or not estimate.usable:
            return None
        try:
            x_end = horizon_end(self.observer.model, self.optics, forecast, estimate.x_k,
                                applied, self.calibration.theta, self.calibration.offsets,
                                coupling_tol_k=self.cfg.control.screening_tolerance_k)
            if x_end is not None:  # what the sensors will read (docs/model.md#reading-offsets)
                x_end[:5] += self.observer.reading_offset_k(applied.afr)
            return x_end
        except (ValueError, ArithmeticError, np.linalg.LinAlgError):
            log.exception("horizon prediction failed")
            return None

    def _comfort(self, estimate: StateEstimate, forecast: Forcing | None, command: Command,
                 occupancy: EffectiveOccupancy, decision: Decision | None
                 ) -> ComfortCheck | None:
        """The comfort of the command sent and what bound its choice, for the trace
        (docs/model.md#comfort-trace): pane and supply air are the estimated x3 and x5 now,
        the occupancy as resolved this cycle (override > signal > schedule)."""
        if forecast is None or not estimate.usable:
            return None
        is_occupied = occupancy.occupied
        bound = ""
        if decision is not None and decision.comfort:
            sent = _command_or_none(decision) == command
            bound = decision.comfort if sent else (
                f"{decision.comfort} (then the safety pipeline changed the command)")
        try:
            return comfort_check(self.cfg, self.optics, forecast, phi_deg=command.phi_deg,
                                 afr=command.afr, or_pct=command.or_pct,
                                 occupied=is_occupied,
                                 t_pane_c=float(estimate.x_k[2]) - T_ZERO,
                                 t_supply_c=float(estimate.x_k[4]) - T_ZERO)._replace(
                                     bound=bound)
        except (ValueError, ArithmeticError):
            log.exception("comfort check failed")
            return None

    def _optimiser(self, problem: ControlProblem) -> Callable[[], Decision]:
        if self.cfg.control.optimiser == "paper-sqp":
            # imported here: SciPy's optimiser costs every other daemon ~38 MB resident
            from dsfd.control.paper_sqp import optimise_paper_sqp

            mpc = self.mpc
            return lambda: optimise_paper_sqp(self.cfg, mpc.model, mpc.optics, problem)
        return lambda: self.mpc.decide(problem)

    async def _store(self, out: CycleOutcome, weather: CycleWeather) -> bool:
        """Queue the cycle's rows and write what waits; a failed write keeps them queued."""
        buffer = self.store.buffer
        buffer.enqueue(cycle_record(out, weather, self.calibration))
        written, why = await self.store_job.run(buffer.flush,
                                                budget_s=self.cfg.daemon.store_budget_s)
        if written:
            return True
        waiting = buffer.waiting
        failure = buffer.failure[1] if buffer.failure else why
        log.log(logging.ERROR if waiting <= 1 else logging.DEBUG,
                "cycle %d not stored yet: %s; %d cycle(s) wait in memory (at most %d)",
                out.cycle, failure or "store busy", waiting, buffer.capacity)
        return False


def _drain(items: list[T]) -> list[T]:
    out = list(items)
    items.clear()
    return out


def _ms(start: float) -> float:
    return round((time.perf_counter() - start) * 1e3, 3)


def _command_or_none(d: Decision) -> Command | None:
    try:
        return Command(phi_deg=d.phi_deg, afr=d.afr, or_pct=d.or_pct)
    except (ValueError, TypeError):
        return None
