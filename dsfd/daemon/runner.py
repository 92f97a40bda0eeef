"""The daemon around the cycle: start-up, the cycle grid, signals, reloads, systemd, shutdown.

Start-up order matters: the configuration (and the run-time checks below) is validated
before anything is opened, so a bad file exits non-zero naming the key path without
touching a device; then the state directory's lock (a second daemon on the same directory
stops here, naming the holder's PID, before it opens anything); then the database and the
calibration state, and a manual hold the previous run left active (:mod:`dsfd.daemon.state`);
then the drivers; then ``READY=1``.

Signals: SIGTERM/SIGINT stop after the current cycle (``STOPPING=1``, the run is marked
ended in the database, the summary printed); SIGHUP reloads the file between cycles
(``RELOADING=1`` … ``READY=1``) — a file that fails validation is rejected with every error
and its key path logged, and the running configuration stays. Device and state-directory
changes need a restart (logged; the rest of a reload applies).
"""

from __future__ import annotations

import asyncio
import dataclasses
import logging
import signal
import sqlite3
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from dsfd.config import ConfigError, ConfigIssue, PanelConfig
from dsfd.daemon.clock import Clock, CycleGrid, RealClock, SimulatedClock, Slot
from dsfd.daemon.findings import FindingsStage, NightSite
from dsfd.daemon.hold import position_text
from dsfd.daemon.logging_setup import bind_contextvars, bound_contextvars, get_logger
from dsfd.daemon.loop import Controller, CycleOutcome
from dsfd.daemon.memory import limit_malloc_arenas
from dsfd.daemon.metrics import MetricsFile
from dsfd.daemon.notify import Notifier
from dsfd.daemon.startup import load_for_run, runtime_problems
from dsfd.daemon.state import open_state, restore_operator_state
from dsfd.daemon.summary import RunSummary
from dsfd.drivers.base import Driver
from dsfd.measured import iso_utc
from dsfd.storage.findings import open_by_kind
from dsfd.storage.lock import StateLock
from dsfd.storage.timeseries import Store

__all__ = ["Integration", "PlantUnderTest", "RunOptions", "load_for_run", "runtime_problems",
           "serve"]

log = get_logger("dsfd.daemon")


class PlantUnderTest(Protocol):
    """A simulated plant the daemon runs against instead of the devices (``--plant sim``).

    The CLI builds it (:func:`dsfd.sim.daemon_plant.simulated_plant`) and hands it to
    :func:`serve`, so the daemon does not depend on the simulation package.
    """

    @property
    def driver(self) -> Driver: ...

    @property
    def start_s(self) -> float: ...

    @property
    def notes(self) -> tuple[str, ...]: ...

    def room_heat(self) -> tuple[dict[str, float], float]:
        """Heat into the room since the start [J] by term, and the hours it covers."""
        ...

    def room_heat_now(self) -> dict[str, float] | None:
        """The same by term [J] now, None while the plant is busy integrating (per cycle)."""
        ...


class Integration(Protocol):
    """Something beside the loop that reads what the daemon stores (the MQTT publisher, the
    BACnet device).

    The CLI builds it and hands it to :func:`serve` (the daemon does not import the
    integrations). It is started once the database is open, told after every stored cycle
    (:meth:`cycle_stored` must return at once: it runs on the loop) and stopped before the
    database closes (:meth:`stop` is bounded in time).
    """

    name: str

    def start(self, *, database: Path) -> None: ...

    def cycle_stored(self, cycle: int) -> None: ...

    def stop(self) -> None: ...

    def health(self) -> Mapping[str, Any]:
        """Its state for the metrics file (called on the loop after each cycle: quick)."""
        ...


@dataclass(frozen=True, kw_only=True)
class RunOptions:
    """What ``dsfd run`` was asked to do (see ``dsfd run --help``)."""

    config_path: Path
    dry_run: bool = False
    plant: str | None = None
    plant_fidelity: str = "full"
    speed: float | None = None
    cycles: int | None = None
    state_dir: Path | None = None
    weather: str | None = None
    start_s: float | None = None
    seed: int = 1
    #: ``--fault`` arguments of a simulated plant (``dsfd.sim.plant.faults``, parsed there).
    faults: tuple[str, ...] = ()
    #: Called after every cycle (benchmarks); must be quick.
    on_cycle: Callable[[CycleOutcome], None] | None = None
    #: Builds the cycle instead of :class:`~dsfd.daemon.loop.Controller` (same arguments):
    #: benchmarks that run the daemon with a subclass, e.g. one that applies a fixed
    #: excitation schedule instead of the optimiser's decisions (``dsfd bench identify``).
    controller: Callable[..., Controller] | None = None

    @property
    def simulated_plant(self) -> bool:
        return self.plant == "sim"

    @property
    def mode(self) -> str:
        if self.simulated_plant:
            plant = ("simulated plant" if self.plant_fidelity == "full"
                     else f"simulated plant, {self.plant_fidelity}")
            return f"dry run, {plant}" if self.dry_run else plant
        return "dry run, hardware read-only" if self.dry_run else "hardware"


class _Daemon:
    def __init__(self, opts: RunOptions, cfg: PanelConfig, clock: Clock, driver: Driver,
                 store: Store, controller: Controller, notifier: Notifier,
                 integrations: Sequence[Integration] = ()) -> None:
        self.opts, self.cfg, self.clock, self.driver = opts, cfg, clock, driver
        self.store, self.controller, self.notifier = store, controller, notifier
        self.integrations = tuple(integrations)
        self.stop = asyncio.Event()
        self.reload = asyncio.Event()
        self.summary = RunSummary(panel=cfg.panel.id, mode=opts.mode)
        self.cycle_failures = 0
        self.reloads_rejected = 0
        self.metrics = _metrics_file(cfg)
        self.metrics_failures = 0
        #: The diagnostics, run off the loop on what was stored (issue 38).
        self.findings = FindingsStage(store.path, run_id=lambda: store.run_id,
                                      night=NightSite.of(cfg), panel=cfg)

    async def wait_until(self, deadline_s: float) -> None:
        """Sleep until the deadline, or until a signal asks to stop or reload."""
        sleeper = asyncio.ensure_future(self.clock.sleep_until(deadline_s))
        waiters = [asyncio.ensure_future(e.wait()) for e in (self.stop, self.reload)]
        _, pending = await asyncio.wait([sleeper, *waiters],
                                        return_when=asyncio.FIRST_COMPLETED)
        for task in pending:
            task.cancel()

    async def cycles(self) -> str:
        grid = (CycleGrid(period_s=self.cfg.daemon.cycle_period_s, t0_s=self.clock.monotonic())
                if self.clock.simulated else
                CycleGrid.aligned(self.clock, period_s=self.cfg.daemon.cycle_period_s))
        slot = Slot(0, grid.deadline(0), 0)
        while True:
            await self.wait_until(slot.deadline_s)
            if self.stop.is_set():
                return "signal"
            if self.reload.is_set():
                self.reload.clear()
                self.do_reload()
                continue  # then wait for the same slot
            with bound_contextvars(cycle=self.controller.cycles + 1):
                await self.one_cycle(slot)
            # a failed cycle counts too: a cycle that always fails must not run a dry run forever
            done = self.summary.cycles + self.cycle_failures
            if self.opts.cycles is not None and done >= self.opts.cycles:
                return "cycles done"
            if self.stop.is_set():
                return "signal"
            slot = grid.after(slot.index, self.clock.monotonic())
            if slot.skipped:
                log.warning("cycle overran: %d slot(s) skipped, next cycle at slot %d",
                            slot.skipped, slot.index)

    async def one_cycle(self, slot: Slot) -> None:
        try:
            out = await self.controller.run_cycle(slot)
        except Exception:  # a bug must not end control of the panel: log, no watchdog ping
            self.cycle_failures += 1
            log.exception("cycle failed")
            return
        self.summary.add(out)
        if out.store_ok:
            for integration in self.integrations:
                integration.cycle_stored(out.cycle)
            self.findings.after_cycle(out.time_s)
        self.write_metrics(out)
        if self.opts.on_cycle is not None:
            self.opts.on_cycle(out)
        c = out.command
        t = out.timings_ms
        log.info("cycle", time_utc=iso_utc(round(out.time_s)), slot=out.slot,
                 method=out.method, phi_deg=c.phi_deg, afr=c.afr, or_pct=c.or_pct,
                 write=out.write_status, flagged=len(out.quality.flags),
                 fallback=out.fallback or None, wind_override=out.safety.wind_override,
                 calibration="not due" if out.calibration is None else (
                     "updated" if out.calibration.updated else out.calibration.skipped),
                 read_ms=t.get("read"), decide_ms=t.get("decide"), cycle_ms=t.get("total"),
                 skipped=out.skipped_slots or None,
                 hold=None if out.hold is None else out.hold.describe(),
                 stored=None if out.store_ok else f"waiting ({self.store.buffer.waiting})",
                 flagged_signals=tuple(out.quality.flags))  # console only (CONSOLE_ONLY)
        self.notifier.watchdog(f"cycle {out.cycle}: {out.method}, {position_text(c)}, "
                               f"write {out.write_status}")

    def write_metrics(self, out: CycleOutcome) -> None:
        """Rewrite the metrics file; a failure is logged (loudly once), never fatal."""
        if self.metrics is None:
            return
        try:
            self.metrics.update(out, self.controller.calibration)
            self.metrics.update_findings(open_by_kind(self.store.reader()))
            for integration in self.integrations:
                if integration.name == "mqtt":
                    self.metrics.update_mqtt(integration.health())
            self.metrics.write()
        except Exception as exc:  # metrics must never stop the control of the panel
            self.metrics_failures += 1
            log.log(logging.WARNING if self.metrics_failures == 1 else logging.DEBUG,
                    "metrics file %s not written: %s: %s", self.metrics.path,
                    type(exc).__name__, exc, failures=self.metrics_failures)
        else:
            if self.metrics_failures:
                log.info("metrics file written again after %d failure(s)",
                         self.metrics_failures)
            self.metrics_failures = 0

    def do_reload(self) -> None:
        self.notifier.reloading()
        path = self.opts.config_path
        try:
            new = load_for_run(path, simulated_plant=self.opts.simulated_plant,
                               dry_run=self.opts.dry_run)
            if new.panel.id != self.cfg.panel.id:
                raise ConfigError([ConfigIssue("panel.id", new.panel.id,
                                               f"differs from the running {self.cfg.panel.id!r}; "
                                               "restart to switch panels")], str(path))
        except ConfigError as exc:
            self.reloads_rejected += 1
            after = self.controller.cycles
            for issue in exc.issues:
                log.error("reload rejected: %s", issue, key_path=issue.path, file=str(path),
                          after_cycle=after)
            log.error("reload rejected: keeping the running configuration",
                      errors=len(exc.issues), file=str(path), after_cycle=after)
            self.store.event(cycle=self.controller.cycles, time_s=self.clock.wall(),
                             level="error", kind="reload_rejected", message=str(exc))
            self.notifier.ready("reload rejected; running configuration kept")
            return
        kept = [key for key, changed in (
            ("devices", new.devices != self.cfg.devices),
            ("daemon.state_directory",
             new.daemon.state_directory != self.cfg.daemon.state_directory),
            ("mqtt", new.mqtt != self.cfg.mqtt),
            ("bacnet", new.bacnet != self.cfg.bacnet)) if changed]
        if kept:
            log.warning("reload: %s changed; restart the service to apply", ", ".join(kept))
            new = dataclasses.replace(
                new, devices=self.cfg.devices, mqtt=self.cfg.mqtt, bacnet=self.cfg.bacnet,
                daemon=dataclasses.replace(new.daemon,
                                           state_directory=self.cfg.daemon.state_directory))
        note = self.controller.reconfigure(new)
        if new.daemon.metrics_file != self.cfg.daemon.metrics_file:
            self.metrics = _metrics_file(new)
        self.store.buffer.capacity = new.daemon.store_buffer_cycles
        self.findings.reconfigure(new)  # the next stakes are costed with the reloaded panel
        self.cfg = new
        log.info("configuration reloaded", file=str(path), calibration=note,
                 after_cycle=self.controller.cycles)
        self.store.event(cycle=self.controller.cycles, time_s=self.clock.wall(), level="info",
                         kind="reload", message=f"{path}: {note}")
        self.notifier.ready("configuration reloaded")


def _metrics_file(cfg: PanelConfig) -> MetricsFile | None:
    path = cfg.daemon.metrics_file
    return None if path is None else MetricsFile(path, cfg.panel.id)


async def serve(opts: RunOptions, cfg: PanelConfig, *, state_dir: Path,
                plant: PlantUnderTest | None = None,
                integrations: Sequence[Integration] = (),
                print_line: Callable[[str], None] = print,
                clock: Clock | None = None) -> RunSummary:
    """Run the daemon until the cycles are done or a signal stops it; return the summary.

    ``plant`` is the simulated plant of ``--plant sim`` (its driver replaces the devices and
    the clock starts at its start); without it the panel's ``devices:`` are opened.
    ``integrations`` (the MQTT publisher, the BACnet device) run beside the loop, fed from
    the database.
    ``clock`` replaces the daemon's clock (tests that step the wall clock).

    Raises :class:`~dsfd.storage.lock.StateDirBusyError` before anything is opened if
    another process controls ``state_dir``.
    """
    lock = StateLock.acquire(state_dir)  # one controller per state directory, first of all
    try:
        return await _serve_locked(opts, cfg, state_dir=state_dir, plant=plant,
                                   integrations=integrations, print_line=print_line,
                                   clock=clock)
    finally:
        lock.release()


def _clock_and_driver(opts: RunOptions, cfg: PanelConfig, plant: PlantUnderTest | None,
                      clock: Clock | None, print_line: Callable[[str], None]
                      ) -> tuple[Clock, Driver]:
    """The simulated plant's clock and driver, or the devices' drivers (not yet started)
    on the real clock (or a simulated one with ``--speed``); ``clock`` replaces the clock."""
    if plant is not None:
        for note in plant.notes:
            print_line(f"  {note}")
        return clock or SimulatedClock(start_utc_s=plant.start_s, speed=opts.speed), plant.driver
    from dsfd.drivers.factory import build_drivers

    clock = clock or (RealClock() if opts.speed is None else SimulatedClock(
        start_utc_s=opts.start_s if opts.start_s is not None else RealClock().wall(),
        speed=opts.speed))
    assert cfg.devices is not None  # runtime_problems guarantees it
    return clock, build_drivers(cfg.devices, clock=clock.monotonic)


async def _serve_locked(opts: RunOptions, cfg: PanelConfig, *, state_dir: Path,
                        plant: PlantUnderTest | None, integrations: Sequence[Integration],
                        print_line: Callable[[str], None], clock: Clock | None
                        ) -> RunSummary:
    limit_malloc_arenas()
    # A file-size limit (RLIMIT_FSIZE) must fail a write with EFBIG, not kill the daemon.
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    bind_contextvars(panel=cfg.panel.id)
    notifier = Notifier()
    clock, driver = _clock_and_driver(opts, cfg, plant, clock, print_line)
    store, calibration = open_state(opts, cfg, state_dir, clock)
    # A dry run never writes to hardware; an in-process simulated plant may follow.
    write_enabled = not opts.dry_run or not getattr(driver, "hardware", True)
    controller = (opts.controller or Controller)(
        cfg, driver=driver, clock=clock, store=store, calibration=calibration,
        write_enabled=write_enabled,
        plant_heat_j=None if plant is None else plant.room_heat_now)
    restore_operator_state(controller.manual, store, clock)
    daemon = _Daemon(opts, cfg, clock, driver, store, controller, notifier, integrations)
    daemon.summary.start_calibration(calibration)
    loop = asyncio.get_running_loop()
    loop.add_signal_handler(signal.SIGTERM, daemon.stop.set)
    loop.add_signal_handler(signal.SIGINT, daemon.stop.set)
    loop.add_signal_handler(signal.SIGHUP, daemon.reload.set)
    reason = "error"
    started: list[Integration] = []
    try:
        for integration in integrations:
            integration.start(database=store.path)
            started.append(integration)
        await driver.start()
        notifier.ready(f"controlling panel {cfg.panel.id} ({opts.mode})")
        log.info("daemon ready", mode=opts.mode, state_dir=str(state_dir),
                 database=str(store.path), writes=write_enabled)
        reason = await daemon.cycles()
    finally:
        notifier.stopping(f"stopping: {reason}")
        for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
            loop.remove_signal_handler(sig)
        await asyncio.to_thread(daemon.findings.stop)
        try:
            store.end_run(reason=reason, cycles=daemon.summary.cycles)
        except sqlite3.Error as exc:
            log.error("run end not recorded: %s", exc)
        if store.buffer.waiting:
            log.error("%d cycle(s) could not be written before the stop",
                      store.buffer.waiting)
        try:
            await driver.close()
        finally:
            for integration in started:
                try:
                    await asyncio.to_thread(integration.stop)
                except Exception:
                    log.exception("stopping %s failed", integration.name)
            store.close()
            notifier.close()
    heat, hours = (None, 0.0) if plant is None else plant.room_heat()
    daemon.summary.finish(calibration, room_heat_j=heat, room_heat_h=hours)
    log.info("daemon stopped", reason=reason, cycles=daemon.summary.cycles,
             cycle_failures=daemon.cycle_failures)
    return daemon.summary
