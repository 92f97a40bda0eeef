"""The occupancy stage of the loop: an operator's override, the ``occupied`` signal and the
schedule, resolved by :func:`dsfd.control.occupancy.effective_occupancy` (issue 36).

* An ``occupancy`` command (``dsfd occupancy``, MQTT ``<base>/cmd/occupancy``) reaches the
  loop through the ``commands`` table like a hold (:class:`~dsfd.daemon.manual.ManualStage`
  hands it here). Its ``until`` is resolved against the cycle's time (the daemon's clock,
  simulated in a dry run); one that is already past is rejected with the reason. ``auto``
  ends an override. The override ends by itself at its time (an event says so), and a
  restart takes over one that has not ended (the last stored decision's
  ``occupancy_override*`` columns).
* The ``occupied`` signal counts while its reading is GOOD. When it is configured but
  flagged (stale, out of range, device down) the schedule decides; the change is logged
  once (warning) and its return once (info), and the decision trace says it every cycle.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from dsfd.config.panel import PanelConfig
from dsfd.control.occupancy import EffectiveOccupancy, OccupancyOverride, effective_occupancy
from dsfd.daemon.commands import CommandError, OperatorCommand, resolve_until
from dsfd.daemon.logging_setup import get_logger
from dsfd.drivers.base import Sample

__all__ = ["OCCUPIED_SIGNAL", "OccupancyStage"]

log = get_logger(__name__)

#: The signal a presence sensor or the BMS delivers (dsfd.signals).
OCCUPIED_SIGNAL = "occupied"


class OccupancyStage:
    """The occupancy override of one panel and the state of its occupied signal."""

    def __init__(self) -> None:
        self.override: OccupancyOverride | None = None
        self._signal_problem: str | None = None  # the last flag logged, None while GOOD

    def command(self, cmd: OperatorCommand, command_id: int, *, now_s: float,
                utc_offset_h: float, who: str) -> tuple[tuple[int, str, str],
                                                        tuple[str, str, str] | None]:
        """Apply an ``occupancy`` command at the cycle time ``now_s``: (its result, the
        event or None)."""
        if cmd.state == "auto":
            if self.override is None:
                return (command_id, "applied", "no occupancy override was in force"), None
            was = self.override.describe()
            self.override = None
            return ((command_id, "applied", f"occupancy override ended ({was}); the occupied "
                     "signal, else the schedule, decides"),
                    ("info", "occupancy_ended", f"occupancy override {was} ended by "
                     f"#{command_id} {who}"))
        try:
            until_s = resolve_until(cmd.until, now_s=now_s, utc_offset_h=utc_offset_h)
        except CommandError as exc:
            return (command_id, "rejected", str(exc)), None
        before = "none" if self.override is None else self.override.describe()
        self.override = OccupancyOverride(cmd.state == "occupied", until_s, command_id)
        now = self.override.describe()
        return ((command_id, "applied", f"occupancy {now} (override before: {before})"),
                ("info", "occupancy_set", f"occupancy {now} by #{command_id} {who}"))

    def expire(self, now_s: float) -> list[tuple[str, str, str]]:
        """End an override whose time has come; its event."""
        if self.override is None or self.override.active(now_s):
            return []
        was = self.override.describe()
        self.override = None
        log.info("occupancy override ended: %s", was)
        return [("info", "occupancy_ended", f"occupancy override {was} ended at its time")]

    def restore(self, last: Mapping[str, Any] | None, *, now_s: float) -> str | None:
        """Take over the previous run's override if it has not ended; what was restored."""
        if not last or last.get("occupancy_override") not in ("occupied", "unoccupied"):
            return None
        until = last.get("occupancy_until_s")
        if until is None or float(until) <= now_s:
            return None
        cid = last.get("occupancy_command_id")
        self.override = OccupancyOverride(last["occupancy_override"] == "occupied",
                                          float(until), None if cid is None else int(cid))
        return f"occupancy override {self.override.describe()}"

    def resolve(self, cfg: PanelConfig, sample: Sample, flags: Mapping[str, str], *,
                now_s: float) -> EffectiveOccupancy:
        """The occupancy in force at ``now_s`` from the checked ``sample`` (its quality
        ``flags``: signal → why not usable)."""
        value = sample.good(OCCUPIED_SIGNAL)
        configured = OCCUPIED_SIGNAL in sample.readings
        problem = None
        if configured and value is None:
            problem = flags.get(OCCUPIED_SIGNAL) or sample.quality(OCCUPIED_SIGNAL).value
        self._log_signal(problem)
        return effective_occupancy(now_s, occupancy=cfg.occupancy,
                                   utc_offset_h=cfg.site.utc_offset_h, override=self.override,
                                   signal=value, signal_problem=problem)

    def _log_signal(self, problem: str | None) -> None:
        if problem is not None and problem != self._signal_problem:
            log.warning(f"occupied signal not usable ({problem}): the occupancy schedule "
                        "decides until it is GOOD again", problem=problem)
        elif problem is None and self._signal_problem is not None:
            log.info("occupied signal GOOD again: it decides the occupancy (unless an "
                     "operator override is in force)")
        self._signal_problem = problem
