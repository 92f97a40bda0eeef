"""What a start of the daemon takes over from its state directory, after the lock is held.

:func:`open_state` opens the database (a corrupt one is moved aside and a new one started)
and records the run, then the calibration state (``calibration.json``, else the database's
parameter history, else the priors: :class:`~dsfd.daemon.calibration.CalibrationStage`).
:func:`restore_operator_state` takes over what the previous run's last stored decision
says: a manual hold that has not expired, an occupancy override that has not ended, and the
control objective an operator chose (:class:`~dsfd.daemon.manual.ManualStage`), each logged
and recorded as an event.
"""

from __future__ import annotations

import dataclasses
import sqlite3
from collections.abc import Mapping
from typing import TYPE_CHECKING

from dsfd import __version__
from dsfd.config import PanelConfig
from dsfd.daemon.calibration import CalibrationStage
from dsfd.daemon.clock import Clock
from dsfd.daemon.logging_setup import get_logger
from dsfd.physics.model import LumpedModel
from dsfd.storage.queries import last_decision, parameter_history, run_control_mode
from dsfd.storage.timeseries import Store

if TYPE_CHECKING:
    from pathlib import Path

    from dsfd.daemon.manual import ManualStage
    from dsfd.daemon.runner import RunOptions

__all__ = ["open_state", "restore_operator_state"]

log = get_logger("dsfd.daemon")


def open_state(opts: RunOptions, cfg: PanelConfig, state_dir: Path, clock: Clock
               ) -> tuple[Store, CalibrationStage]:
    """The database (a corrupt one moved aside) and the calibration state (from the file,
    else the database's parameter history, else the priors)."""
    store = Store.open(state_dir, buffer_cycles=cfg.daemon.store_buffer_cycles)
    store.begin_run(panel=cfg.panel.id, mode=opts.mode, version=__version__,
                    config_path=str(opts.config_path), config=dataclasses.asdict(cfg))
    if store.moved_aside is not None:
        log.error("database was unusable and was moved aside; started a new one",
                  moved_to=str(store.moved_aside))
        store.event(cycle=0, time_s=clock.wall(), level="error", kind="database_recovered",
                    message=f"corrupt database moved to {store.moved_aside.name}")
    calibration = CalibrationStage(
        cfg, LumpedModel(cfg), state_dir=state_dir,
        history=lambda: parameter_history(store.reader(), cfg.panel.id))
    if calibration.events:
        log.warning(calibration.resume_message, theta=calibration.theta_by_name(),
                    origin=calibration.origin)
    else:
        log.info(calibration.resume_message, theta=calibration.theta_by_name())
    return store, calibration


def restore_operator_state(manual: ManualStage, store: Store, clock: Clock) -> None:
    """Take over the previous run's unexpired hold and the operator's objective."""
    last = _last_decision(store)
    restored = manual.restore(last, now_mono_s=clock.monotonic(), now_s=clock.wall())
    if restored:
        log.warning("manual hold of the previous run restored: %s", restored)
        store.event(cycle=0, time_s=clock.wall(), level="info", kind="hold_restored",
                    message=restored)
    occupancy = manual.occupancy.restore(last, now_s=clock.wall())
    if occupancy:
        log.warning("operator's occupancy override of the previous run restored: %s",
                    occupancy)
        store.event(cycle=0, time_s=clock.wall(), level="info", kind="occupancy_restored",
                    message=occupancy)
    objective = manual.restore_mode(last, file_mode_then=_control_mode_of(store, last))
    if objective:
        log.warning("operator's choice of the previous run restored: %s", objective)
        store.event(cycle=0, time_s=clock.wall(), level="info", kind="mode_restored",
                    message=objective)


def _last_decision(store: Store) -> dict[str, object] | None:
    try:
        return last_decision(store.reader())
    except sqlite3.Error:
        return None


def _control_mode_of(store: Store, last: Mapping[str, object] | None) -> str | None:
    """``control.mode`` of the panel file the run of ``last`` used (None: unknown)."""
    try:
        return None if not last else run_control_mode(store.reader(), int(last["run_id"]))
    except sqlite3.Error:
        return None
