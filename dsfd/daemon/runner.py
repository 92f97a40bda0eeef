"""The daemon around the cycle: start-up, the cycle grid, signals, reloads, systemd, shutdown.

Start-up order matters: the configuration (and the run-time checks below) is validated
before anything is opened, so a bad file exits non-zero naming the key path without
touching a device; then the state directory, the database and the calibration state; then
the drivers; then ``READY=1``.

Signals: SIGTERM/SIGINT stop after the current cycle (``STOPPING=1``, the run is marked
ended in the database, the summary printed); SIGHUP reloads the file between cycles
(``RELOADING=1`` … ``READY=1``) — a file that fails validation is rejected with every error
and its key path logged, and the running configuration stays. Device and state-directory
changes need a restart (logged; the rest of a reload applies).
"""

from __future__ import annotations

import asyncio
import dataclasses
import os
import signal
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from dsfd import __version__
from dsfd.config import ConfigError, ConfigIssue, PanelConfig, load_panel
from dsfd.daemon.calibration import CalibrationStage
from dsfd.daemon.clock import Clock, CycleGrid, RealClock, SimulatedClock, Slot
from dsfd.daemon.logging_setup import bind_contextvars, bound_contextvars, get_logger
from dsfd.daemon.loop import (
    DEFAULT_READ_BUDGET_S,
    DEFAULT_WRITE_BUDGET_S,
    Controller,
    CycleOutcome,
)
from dsfd.daemon.memory import limit_malloc_arenas
from dsfd.daemon.notify import Notifier
from dsfd.daemon.summary import RunSummary
from dsfd.drivers.base import Driver
from dsfd.measured import iso_utc
from dsfd.physics.model import LumpedModel
from dsfd.signals import ACTUATOR_NAMES
from dsfd.storage.timeseries import Store

__all__ = ["PlantUnderTest", "RunOptions", "load_for_run", "runtime_problems", "serve"]

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
    #: Called after every cycle (benchmarks); must be quick.
    on_cycle: Callable[[CycleOutcome], None] | None = None

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


def runtime_problems(cfg: PanelConfig, *, simulated_plant: bool, dry_run: bool
                     ) -> list[ConfigIssue]:
    """Checks that only ``dsfd run`` needs (key paths as in the YAML file)."""
    out: list[ConfigIssue] = []
    d = cfg.daemon
    if abs(d.cycle_period_s - cfg.model.step_s) > 1e-9:
        out.append(ConfigIssue("daemon.cycle_period_s", d.cycle_period_s,
                               f"must equal model.step_s ({cfg.model.step_s:g} s): the "
                               "observer and the calibrator predict one model step per cycle"))
    dev = cfg.devices
    read_s = dev.read_budget_s if dev else DEFAULT_READ_BUDGET_S
    write_s = dev.write_budget_s if dev else DEFAULT_WRITE_BUDGET_S
    parts = {"devices.read_budget_s": read_s, "daemon.calibrate_budget_s": d.calibrate_budget_s,
             "control.time_budget_s": cfg.control.time_budget_s,
             "devices.write_budget_s": write_s, "daemon.store_budget_s": d.store_budget_s}
    if sum(parts.values()) > d.cycle_period_s:
        shown = " + ".join(f"{k} {v:g}" for k, v in parts.items())
        out.append(ConfigIssue("daemon.cycle_period_s", d.cycle_period_s,
                               f"the stage budgets do not fit into one cycle ({shown} = "
                               f"{sum(parts.values()):g} s)"))
    if simulated_plant:
        return out
    if dev is None:
        out.append(ConfigIssue("devices", None, "required to run against hardware: describe "
                               "the Modbus devices and the weather station (or use --plant "
                               "sim for a simulated plant)"))
        return out
    delivered = {s for e in dev.entries for s in e.signal_names()}
    for i, name in enumerate(cfg.safety.fault_signals):
        if name not in delivered:
            out.append(ConfigIssue(f"safety.fault_signals[{i}]", name,
                                   "no device in devices.entries delivers this sensor, so the "
                                   "daemon would only ever command the safe state"))
    owned = {a.signal for e in dev.entries for a in e.actuators}
    missing = [a for a in ACTUATOR_NAMES if a not in owned]
    if missing and not dry_run:
        out.append(ConfigIssue("devices.entries", [e.name for e in dev.entries],
                               f"no device has a register for {', '.join(missing)}: the "
                               "daemon cannot command the panel (or use --dry-run)"))
    return out


def load_for_run(path: Path, *, simulated_plant: bool, dry_run: bool) -> PanelConfig:
    """Load and validate a panel file for ``dsfd run``; :class:`ConfigError` names key paths."""
    cfg = load_panel(path)
    issues = runtime_problems(cfg, simulated_plant=simulated_plant, dry_run=dry_run)
    if issues:
        raise ConfigError(issues, str(path))
    return cfg


def resolve_state_dir(opts: RunOptions, cfg: PanelConfig) -> tuple[Path, bool]:
    """The state directory and whether it is a temporary one (simulated dry runs only)."""
    if opts.state_dir is not None:
        return opts.state_dir, False
    if cfg.daemon.state_directory:
        return Path(cfg.daemon.state_directory), False
    env = os.environ.get("STATE_DIRECTORY", "")
    if env:
        return Path(env.split(":")[0]), False  # systemd lists several, colon-separated
    if opts.simulated_plant:
        return Path(tempfile.mkdtemp(prefix=f"dsfd-{cfg.panel.id}-")), True
    raise ConfigError([ConfigIssue(
        "daemon.state_directory", None, "no state directory: set it here, pass --state-dir, "
        "or run under systemd with StateDirectory= (sets $STATE_DIRECTORY)")],
        str(opts.config_path))


class _Daemon:
    def __init__(self, opts: RunOptions, cfg: PanelConfig, clock: Clock, driver: Driver,
                 store: Store, controller: Controller, notifier: Notifier) -> None:
        self.opts, self.cfg, self.clock, self.driver = opts, cfg, clock, driver
        self.store, self.controller, self.notifier = store, controller, notifier
        self.stop = asyncio.Event()
        self.reload = asyncio.Event()
        self.summary = RunSummary(panel=cfg.panel.id, mode=opts.mode)
        self.cycle_failures = 0
        self.reloads_rejected = 0

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
            if self.opts.cycles is not None and self.summary.cycles >= self.opts.cycles:
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
                 skipped=out.skipped_slots or None)
        self.notifier.watchdog(f"cycle {out.cycle}: {out.method}, louver {c.phi_deg:+.0f} deg, "
                               f"regime {c.afr}, dampers {c.or_pct:g} %, "
                               f"write {out.write_status}")

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
             new.daemon.state_directory != self.cfg.daemon.state_directory)) if changed]
        if kept:
            log.warning("reload: %s changed; restart the service to apply", ", ".join(kept))
            new = dataclasses.replace(new, devices=self.cfg.devices, daemon=dataclasses.replace(
                new.daemon, state_directory=self.cfg.daemon.state_directory))
        note = self.controller.reconfigure(new)
        self.cfg = new
        log.info("configuration reloaded", file=str(path), calibration=note,
                 after_cycle=self.controller.cycles)
        self.store.event(cycle=self.controller.cycles, time_s=self.clock.wall(), level="info",
                         kind="reload", message=f"{path}: {note}")
        self.notifier.ready("configuration reloaded")


async def serve(opts: RunOptions, cfg: PanelConfig, *, state_dir: Path,
                plant: PlantUnderTest | None = None,
                print_line: Callable[[str], None] = print) -> RunSummary:
    """Run the daemon until the cycles are done or a signal stops it; return the summary.

    ``plant`` is the simulated plant of ``--plant sim`` (its driver replaces the devices and
    the clock starts at its start); without it the panel's ``devices:`` are opened.
    """
    limit_malloc_arenas()
    bind_contextvars(panel=cfg.panel.id)
    notifier = Notifier()
    clock: Clock
    if plant is not None:
        clock = SimulatedClock(start_utc_s=plant.start_s, speed=opts.speed)
        driver: Driver = plant.driver
        for note in plant.notes:
            print_line(f"  {note}")
    else:
        from dsfd.drivers.factory import build_drivers

        clock = RealClock() if opts.speed is None else SimulatedClock(
            start_utc_s=opts.start_s if opts.start_s is not None else RealClock().wall(),
            speed=opts.speed)
        assert cfg.devices is not None  # runtime_problems guarantees it
        driver = build_drivers(cfg.devices, clock=clock.monotonic)
    store = Store.open(state_dir)
    store.begin_run(panel=cfg.panel.id, mode=opts.mode, version=__version__,
                    config_path=str(opts.config_path))
    if store.moved_aside is not None:
        log.error("database was unusable and was moved aside; started a new one",
                  moved_to=str(store.moved_aside))
        store.event(cycle=0, time_s=clock.wall(), level="error", kind="database_recovered",
                    message=f"corrupt database moved to {store.moved_aside.name}")
    calibration = CalibrationStage(cfg, LumpedModel(cfg), state_dir=state_dir)
    log.info(calibration.resume_message, theta=calibration.theta_by_name())
    # A dry run never writes to hardware; an in-process simulated plant may follow.
    write_enabled = not opts.dry_run or not getattr(driver, "hardware", True)
    controller = Controller(cfg, driver=driver, clock=clock, store=store,
                            calibration=calibration, write_enabled=write_enabled)
    daemon = _Daemon(opts, cfg, clock, driver, store, controller, notifier)
    daemon.summary.start_calibration(calibration)
    loop = asyncio.get_running_loop()
    loop.add_signal_handler(signal.SIGTERM, daemon.stop.set)
    loop.add_signal_handler(signal.SIGINT, daemon.stop.set)
    loop.add_signal_handler(signal.SIGHUP, daemon.reload.set)
    reason = "error"
    try:
        await driver.start()
        notifier.ready(f"controlling panel {cfg.panel.id} ({opts.mode})")
        log.info("daemon ready", mode=opts.mode, state_dir=str(state_dir),
                 database=str(store.path), writes=write_enabled)
        reason = await daemon.cycles()
    finally:
        notifier.stopping(f"stopping: {reason}")
        for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
            loop.remove_signal_handler(sig)
        store.end_run(reason=reason, cycles=daemon.summary.cycles)
        try:
            await driver.close()
        finally:
            store.close()
            notifier.close()
    heat, hours = (None, 0.0) if plant is None else plant.room_heat()
    daemon.summary.finish(calibration, room_heat_j=heat, room_heat_h=hours)
    log.info("daemon stopped", reason=reason, cycles=daemon.summary.cycles,
             cycle_failures=daemon.cycle_failures)
    return daemon.summary
