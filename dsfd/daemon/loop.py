"""One control cycle: read → quality → state estimate → calibration → optimise → safety →
write → store.

The loop only moves data between the core functions (observer, calibrator, optimiser,
baseline, safety pipeline) and the two edges (drivers, store), timing every stage:

* **read** — all drivers concurrently, plus the actuator read-back, under the devices' read
  budget; a driver fault is a bad reading, never an exception out of here;
* **quality** — :class:`~dsfd.daemon.quality.QualityChecker` flags what cannot be used;
* **estimate** — measured weather → forcing (:mod:`dsfd.daemon.weather`) and the state
  estimate (:mod:`dsfd.daemon.observer`);
* **calibrate** — when due, a refit in a worker thread under ``daemon.calibrate_budget_s``;
* **decide** — the configured optimiser in a worker thread under ``control.time_budget_s``;
  if it cannot run (states missing), fails or is late, the rule-based baseline decides; if
  even that lacks its inputs (outdoor air, irradiance), nothing is proposed and the safety
  pipeline commands the safe state;
* **safety** — :class:`~dsfd.daemon.safety.SafetyPipeline`, with the decision trace;
* **write** — under the devices' write budget, verified by read-back (unless a dry run);
* **store** — one SQLite transaction per cycle under ``daemon.store_budget_s``.

Worker threads (``asyncio.to_thread``, which copies the logging context) keep the event loop
free for signals and watchdog pings. A late job is abandoned, never applied, and while it
still runs the next cycle does not start another one of its kind.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

from dsfd.config.devices import Devices
from dsfd.config.panel import PanelConfig
from dsfd.control.baseline import rule_decision
from dsfd.control.objective import is_heating
from dsfd.control.optimiser import ControlProblem, Decision, MpcOptimiser
from dsfd.control.paper_sqp import optimise_paper_sqp
from dsfd.daemon.calibration import CalibrationStage, UpdateOutcome
from dsfd.daemon.clock import Clock, Slot
from dsfd.daemon.logging_setup import get_logger
from dsfd.daemon.memory import trim_heap
from dsfd.daemon.observer import STATE_SIGNALS, StateEstimate, StateObserver
from dsfd.daemon.quality import QualityChecker, QualityReport
from dsfd.daemon.record import cycle_record
from dsfd.daemon.safety import SafetyContext, SafetyPipeline, SafetyResult
from dsfd.daemon.weather import CycleWeather, forecast_forcing, measured_weather
from dsfd.drivers.base import (
    Command,
    Driver,
    Quality,
    Reading,
    Sample,
    WriteResult,
    command_from_values,
)
from dsfd.physics.constants import T_ZERO
from dsfd.physics.forcing import FacadeOptics, Forcing, WeatherInputs, step_inputs
from dsfd.physics.model import LumpedModel
from dsfd.storage.timeseries import Store

__all__ = ["Controller", "CycleOutcome", "OffLoopJob"]

log = get_logger(__name__)
T = TypeVar("T")
#: Read and write budgets of a panel without a devices: section (the simulated plant): the
#: defaults of the devices: section.
DEFAULT_READ_BUDGET_S: float = Devices.__dataclass_fields__["read_budget_s"].default
DEFAULT_WRITE_BUDGET_S: float = Devices.__dataclass_fields__["write_budget_s"].default


class OffLoopJob:
    """Runs one blocking job at a time in a worker thread, under a time budget."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._task: asyncio.Future[Any] | None = None
        #: Jobs abandoned because they missed their budget.
        self.late = 0

    @property
    def busy(self) -> bool:
        """True while an abandoned job is still running."""
        return self._task is not None and not self._task.done()

    async def run(self, fn: Callable[[], T], *, budget_s: float) -> tuple[T | None, str]:
        """``(result, "")``, or ``(None, why)`` if busy, late or failed."""
        if self.busy:
            return None, f"previous {self.name} still running"
        task = asyncio.ensure_future(asyncio.to_thread(fn))
        self._task = task
        try:
            return await asyncio.wait_for(asyncio.shield(task), budget_s), ""
        except TimeoutError:
            self.late += 1
            task.add_done_callback(_consume)  # its result is never used
            return None, f"{self.name} exceeded its budget of {budget_s:g} s"
        except Exception as exc:
            log.exception("%s failed", self.name)
            return None, f"{self.name} failed: {type(exc).__name__}: {exc}"


def _consume(task: asyncio.Future[Any]) -> None:
    if not task.cancelled():
        task.exception()  # retrieve it, so asyncio does not warn about it


@dataclass
class CycleOutcome:
    """What one cycle did (for the log line, the summary, the bench and the tests)."""

    cycle: int
    slot: int
    skipped_slots: int
    time_s: float
    method: str
    command: Command
    proposed: Decision | None
    fallback: str
    heating: bool | None
    safety: SafetyResult
    write_status: str
    write: WriteResult | None
    quality: QualityReport
    calibration: UpdateOutcome | None
    timings_ms: dict[str, float] = field(default_factory=dict)
    manual_override: bool = False
    store_ok: bool = True

    @property
    def cycle_ms(self) -> float:
        return self.timings_ms.get("total", math.nan)


class Controller:
    """The cycle of one panel (drivers, clock and store given by the runner)."""

    def __init__(self, cfg: PanelConfig, *, driver: Driver, clock: Clock, store: Store,
                 calibration: CalibrationStage, write_enabled: bool) -> None:
        self.driver = driver
        self.clock = clock
        self.store = store
        self.calibration = calibration
        self.write_enabled = write_enabled
        self.quality = QualityChecker(cfg.daemon.quality)
        self.safety = SafetyPipeline(cfg)
        self.cycles = 0
        self.optimise_job = OffLoopJob("optimisation")
        self.calibrate_job = OffLoopJob("calibration update")
        self.store_job = OffLoopJob("store")
        self._last_written: Command | None = None
        self._last_verified: Command | None = None
        self._writes_failing = 0  # consecutive failed writes: the first is logged loudly
        self._configure(cfg)

    def _configure(self, cfg: PanelConfig) -> None:
        self.cfg = cfg
        model = LumpedModel(cfg)
        # The optimiser keeps its own model and optics caches: it may still be running in
        # its thread (late, abandoned) while the loop thread steps the observer.
        self.optics = FacadeOptics(cfg)
        self.observer = StateObserver(model, max_predicted_cycles=cfg.daemon.max_predicted_cycles)
        self.mpc = MpcOptimiser(cfg)
        devices = cfg.devices
        self.read_budget_s = devices.read_budget_s if devices else DEFAULT_READ_BUDGET_S
        self.write_budget_s = devices.write_budget_s if devices else DEFAULT_WRITE_BUDGET_S

    def reconfigure(self, cfg: PanelConfig) -> str:
        """Switch to a reloaded, validated configuration between cycles."""
        self.quality.settings = cfg.daemon.quality
        self.safety.reconfigure(cfg)
        self._configure(cfg)
        return self.calibration.reconfigure(cfg, LumpedModel(cfg))

    # ------------------------------------------------------------------ the cycle
    async def run_cycle(self, slot: Slot) -> CycleOutcome:
        """Run one cycle at ``slot``; never raises for device or numerical faults."""
        self.cycles += 1
        t: dict[str, float] = {}
        t0 = time.perf_counter()
        now_s = self.clock.wall()
        if slot.skipped:
            self.observer.reset()  # the prediction spans one step; a gap restarts it

        sample, current, override = await self._read(now_s)
        t["read"] = _ms(t0)
        mark = time.perf_counter()
        report = self.quality.check(sample, age_s=t["read"] / 1e3)
        checked = report.sample
        t["quality"] = _ms(mark)

        mark = time.perf_counter()
        weather = measured_weather(self.cfg, checked)
        estimate = self._estimate(checked, weather, current)
        t["estimate"] = _ms(mark)

        mark = time.perf_counter()
        calibration = await self._calibrate(checked, now_s)
        t["calibrate"] = _ms(mark)

        mark = time.perf_counter()
        heating = (None if weather.inputs is None
                   else is_heating(self.cfg.control, float(weather.inputs.t_out_k[0])))
        decision, method, fallback, no_decision = await self._decide(
            weather, estimate, current, checked, now_s, heating=bool(heating))
        t["decide"] = _ms(mark)

        mark = time.perf_counter()
        wind = checked.good("wind_speed_ms")
        ctx = SafetyContext(now_s=self.clock.monotonic(), wind_speed_ms=wind,
                            bad_signals=frozenset(report.flags), current=current,
                            no_decision_reason=no_decision)
        proposal = None if decision is None else _command_or_none(decision)
        safe = self.safety.apply(proposal, ctx)
        if safe.faulted:  # the faults stage replaced the decision
            method = "safe"
        t["safety"] = _ms(mark)

        mark = time.perf_counter()
        write, status = await self._write(safe.command)
        t["write"] = _ms(mark)
        self.calibration.set_controls(safe.command if status != "dry-run" else current)

        outcome = CycleOutcome(
            cycle=self.cycles, slot=slot.index, skipped_slots=slot.skipped, time_s=now_s,
            method=method, command=safe.command, proposed=decision, fallback=fallback,
            heating=heating,
            safety=safe, write_status=status, write=write, quality=report,
            calibration=calibration, timings_ms=t, manual_override=override)
        mark = time.perf_counter()
        outcome.store_ok = await self._store(outcome, weather)
        t["store"] = _ms(mark)
        t["total"] = _ms(t0)
        return outcome

    async def _read(self, now_s: float) -> tuple[Sample, Command | None, bool]:
        """Sample, actuator position now, and whether it moved without us (manual)."""
        try:
            async with asyncio.timeout(self.read_budget_s):
                sample, actuators = await asyncio.gather(self.driver.read(now_s),
                                                         self.driver.read_actuators())
        except Exception as exc:  # the drivers should not raise; the loop must not die
            if isinstance(exc, TimeoutError):
                why, quality = f"read exceeded its budget of {self.read_budget_s:g} s", \
                    Quality.TIMEOUT
            else:
                log.exception("read failed")
                why, quality = f"read failed: {type(exc).__name__}: {exc}", Quality.DEVICE_ERROR
            sample = Sample(now_s, {n: Reading.bad(quality, "daemon", why)
                                    for n in self.driver.sensor_names})
            actuators = {}
        read_back = command_from_values(actuators)
        override = False
        verified = self._last_verified
        if read_back is not None and verified is not None and read_back != verified:
            override = True
            log.warning("actuators at %s, not the verified %s: moved by someone else "
                        "(manual override?)", read_back.as_dict(), verified.as_dict())
        current = read_back or self._last_verified or self._last_written
        return sample, current, override

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

    async def _decide(self, weather: CycleWeather, estimate: StateEstimate,
                      current: Command | None, checked: Sample, now_s: float, *,
                      heating: bool) -> tuple[Decision | None, str, str, str]:
        """(decision, method, fallback reason, why no decision at all)."""
        if weather.inputs is None or weather.forcing is None:
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
                    x0=estimate.x_k, forcing=self._forecast(weather.inputs, now_s),
                    theta=self.calibration.theta, heating=heating,
                    heat_offsets_wm2=self.calibration.offsets,
                    previous_phi_deg=None if current is None else current.phi_deg,
                    previous_afr=None if current is None else current.afr,
                    previous_or_pct=None if current is None else current.or_pct)
                decision, why = await self.optimise_job.run(
                    self._optimiser(problem), budget_s=self.cfg.control.time_budget_s)
                if decision is not None and _command_or_none(decision) is not None:
                    return decision, decision.method, "", ""
                fallback = why or f"optimiser returned an invalid command {decision}"
        t5 = estimate.celsius(4) if estimate.age_cycles[4] <= \
            self.cfg.daemon.max_predicted_cycles else None
        forcing = weather.forcing
        decision = rule_decision(
            self.cfg, heating=heating, t5_c=t5, t_in_c=weather.t_room_c,
            t_out_c=float(weather.inputs.t_out_k[0]) - T_ZERO,
            beam_wm2=float(forcing.beam_wm2[0]), profile_deg=float(forcing.profile_deg[0]),
            previous_afr=None if current is None else current.afr)
        if fallback:
            log.info("fallback to the baseline: %s", fallback)
        return decision, "rule", fallback, ""

    def _forecast(self, measured: WeatherInputs, now_s: float) -> Forcing:
        """The façade boundary over the horizon from ``now_s``: persistence of the measured
        interval (a simulation's oracle overrides this with the true weather)."""
        return forecast_forcing(self.cfg, measured, start_s=now_s)

    def _optimiser(self, problem: ControlProblem) -> Callable[[], Decision]:
        if self.cfg.control.optimiser == "paper-sqp":
            mpc = self.mpc
            return lambda: optimise_paper_sqp(self.cfg, mpc.model, mpc.optics, problem)
        return lambda: self.mpc.decide(problem)

    async def _write(self, cmd: Command) -> tuple[WriteResult | None, str]:
        if not self.write_enabled:
            return None, "dry-run"
        try:
            async with asyncio.timeout(self.write_budget_s):
                result = await self.driver.write(cmd)
        except Exception as exc:
            if not isinstance(exc, TimeoutError):
                log.exception("write failed")
            why = (f"write exceeded its budget of {self.write_budget_s:g} s"
                   if isinstance(exc, TimeoutError) else f"write failed: {exc}")
            result = WriteResult(requested=cmd, owned=self.driver.actuator_names, errors=(why,))
        self._last_written = cmd
        if result.ok:
            if self._writes_failing:
                log.info("commands verified again after %d failed write(s)",
                         self._writes_failing)
            self._writes_failing = 0
            self._last_verified = cmd
            return result, "verified"
        # A failed verification is not a manual override: forget the verified position, so
        # the next read-back is not compared with a command that may never have arrived.
        self._last_verified = None
        self._writes_failing += 1
        log.log(logging.WARNING if self._writes_failing == 1 else logging.DEBUG,
                "command %s not verified: %s", cmd.as_dict(),
                "; ".join(result.errors) or "read-back incomplete",
                failed_writes=self._writes_failing)
        return result, "failed"

    async def _store(self, out: CycleOutcome, weather: CycleWeather) -> bool:
        record = cycle_record(out, weather, self.calibration)
        _, why = await self.store_job.run(lambda: self.store.append(record),
                                          budget_s=self.cfg.daemon.store_budget_s)
        if why:
            log.error("cycle %d not stored: %s", out.cycle, why)
        return not why


def _ms(start: float) -> float:
    return round((time.perf_counter() - start) * 1e3, 3)


def _command_or_none(d: Decision) -> Command | None:
    try:
        return Command(phi_deg=d.phi_deg, afr=d.afr, or_pct=d.or_pct)
    except (ValueError, TypeError):
        return None
