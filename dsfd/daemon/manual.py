"""The manual-hold stage of the loop: operator commands from the database, the override
input and the read-back, fed to the pure :class:`~dsfd.daemon.hold.HoldTracker`.

Each cycle :meth:`ManualStage.update` picks up the pending ``commands`` rows
(:mod:`dsfd.storage.commands`), validates each against the running configuration (a request
that no longer fits, or one older than :data:`~dsfd.storage.commands.MAX_AGE_S` on the
host's clock, is rejected with the reason), and updates the hold. The results travel with
the cycle's record and are written in its transaction; until then the stage remembers them,
so a command is never applied twice even while the database cannot be written.

At start, :meth:`ManualStage.restore` takes over a detected or operator hold that the
previous run left active (the last stored decision says so, and it has not expired), at the
position the actuators have then: a restart of the service neither undoes a person's hold
nor moves the panel.

``ack`` commands close an open finding of the diagnostics (:mod:`dsfd.storage.findings`;
docs/model.md#findings); they move nothing either.

``occupancy`` commands go to :class:`~dsfd.daemon.occupancy.OccupancyStage` (an override of
the occupancy the comfort limits follow, until a time); they are no hold either.

The stage also keeps the **control objective** an operator chose with a ``mode`` command
(heating, cooling, auto) in place of the panel file's ``control.mode``. It is no hold: the
controller goes on deciding, for that objective. It lasts until the next ``mode`` command or
until the panel file's ``control.mode`` changes (at a reload, or between two runs: the
newer word wins, as with holds), and it survives a restart (:meth:`ManualStage.restore_mode`).
"""

from __future__ import annotations

import logging
import sqlite3
import time
from collections.abc import Mapping
from typing import Any

from dsfd.config.panel import PanelConfig
from dsfd.daemon.commands import OBJECTIVE_MODES, CommandError, OperatorCommand, validate_command
from dsfd.daemon.hold import Hold, HoldTracker, HoldUpdate, PendingCommand
from dsfd.daemon.occupancy import OccupancyStage
from dsfd.drivers.base import Command
from dsfd.storage import commands as command_table
from dsfd.storage import findings as finding_table
from dsfd.storage.timeseries import Store

__all__ = ["ManualStage"]

log = logging.getLogger(__name__)


class ManualStage:
    """Hold tracking and operator commands of one panel."""

    def __init__(self, cfg: PanelConfig, store: Store) -> None:
        self.cfg = cfg
        self.store = store
        self.tracker = HoldTracker(cfg)
        #: Results not yet known to be stored, by command id.
        self._handled: dict[int, tuple[str, str]] = {}
        self._read_failing = False
        #: The objective an operator chose and the ``mode`` command that chose it; None: the
        #: panel file's ``control.mode``.
        self.operator_mode: tuple[str, int] | None = None
        #: Events that happened between cycles (a reload), handed over with the next update.
        self._events: list[tuple[str, str, str]] = []
        #: An operator's occupancy override and the occupied signal's state (issue 36).
        self.occupancy = OccupancyStage()

    @property
    def hold(self) -> Hold | None:
        return self.tracker.hold

    @property
    def objective_mode(self) -> tuple[str, int | None]:
        """The control objective in force and the operator command behind it (None: the
        panel file's ``control.mode``)."""
        if self.operator_mode is not None:
            return self.operator_mode
        return self.cfg.control.mode, None

    def reconfigure(self, cfg: PanelConfig) -> None:
        if self.operator_mode is not None and cfg.control.mode != self.cfg.control.mode:
            mode, cid = self.operator_mode
            self._events.append(("info", "mode_ended", f"control objective {mode} (operator "
                                 f"command #{cid}) ended: the panel file's control.mode is "
                                 f"now {cfg.control.mode}"))
            self.operator_mode = None
        self.cfg = cfg
        self.tracker.cfg = cfg

    def restore(self, last: Mapping[str, Any] | None, *, now_mono_s: float, now_s: float
                ) -> str | None:
        """Resume the hold of the last stored decision if it is timed and still running;
        what was restored (for the log and an event), None if nothing."""
        if not last or last.get("hold_source") not in ("detected", "operator"):
            return None
        expires = last.get("hold_expires_s")
        if expires is None or expires <= now_s:
            return None
        since = float(last.get("time_s") or now_s)
        # Held wherever the panel is now: it may have been moved while the daemon was down,
        # and a restart must not move it back.
        hold = Hold(str(last["hold_source"]), None, since, float(expires),
                    now_mono_s + (float(expires) - now_s), "time",
                    command_id=last.get("hold_command_id"), by="restored after a restart")
        self.tracker.restore(hold)
        return hold.describe()

    def restore_mode(self, last: Mapping[str, Any] | None, *, file_mode_then: str | None
                     ) -> str | None:
        """Keep the objective an operator chose in the previous run (the last stored
        decision), unless the panel file's ``control.mode`` has changed since
        (``file_mode_then``: the previous run's, None if unknown); what was restored."""
        if not last or last.get("mode_command_id") is None:
            return None
        mode = last.get("objective_mode")
        if mode not in OBJECTIVE_MODES:
            return None
        if file_mode_then is not None and file_mode_then != self.cfg.control.mode:
            return None
        self.operator_mode = (str(mode), int(last["mode_command_id"]))
        return f"control objective {mode} (operator command #{last['mode_command_id']})"

    def update(self, *, now_mono_s: float, now_s: float, read_back: Command | None,
               expected: Command | None, input_active: bool | None, input_where: str
               ) -> HoldUpdate:
        """This cycle's hold and objective, with the commands picked up now."""
        holds: list[PendingCommand] = []
        others: list[PendingCommand] = []  # mode and occupancy: no hold
        for pending in self._claim():
            kind = pending.command.kind if isinstance(pending.command, OperatorCommand) \
                else None
            (others if kind in ("mode", "occupancy", "ack") else holds).append(pending)
        up = self.tracker.update(now_mono_s=now_mono_s, now_s=now_s, read_back=read_back,
                                 expected=expected, input_active=input_active,
                                 input_where=input_where, commands=holds)
        up.events[:0] = [*self._events, *self.occupancy.expire(now_s)]
        self._events = []
        for pending in others:
            kind = pending.command.kind if isinstance(pending.command, OperatorCommand) \
                else None
            if kind == "occupancy":
                self._set_occupancy(up, pending, now_s)
            elif kind == "ack":
                self._acknowledge(up, pending, now_s)
            else:
                self._set_mode(up, pending)
        return up

    def _set_occupancy(self, up: HoldUpdate, pending: PendingCommand, now_s: float) -> None:
        """An ``occupancy`` command (an input hold does not refuse it: it moves nothing)."""
        assert isinstance(pending.command, OperatorCommand)
        result, event = self.occupancy.command(
            pending.command, pending.command_id, now_s=now_s,
            utc_offset_h=self.cfg.site.utc_offset_h,
            who=f"{pending.source} {pending.requester}")
        up.results.append(result)
        if event is not None:
            up.events.append(event)

    def _acknowledge(self, up: HoldUpdate, pending: PendingCommand, now_s: float) -> None:
        """An ``ack`` command: the finding closes now (dsfd.storage.findings.acknowledge;
        one short transaction on the loop's reading connection)."""
        assert isinstance(pending.command, OperatorCommand)
        cid, fid = pending.command_id, int(pending.command.finding or 0)
        who = f"#{cid} {pending.source} {pending.requester}"
        try:
            status, reason = finding_table.acknowledge(self.store.reader(), fid, command_id=cid,
                                                       now_s=now_s, who=who)
        except sqlite3.Error as exc:
            status, reason = "rejected", f"finding: {fid}: not acknowledged: {exc}"
        up.results.append((cid, status, reason))
        if status == "applied":
            up.events.append(("info", "finding_acknowledged", f"{reason} (by {who})"))

    def _set_mode(self, up: HoldUpdate, pending: PendingCommand) -> None:
        """A ``mode`` command: the objective from this cycle on (an input hold does not
        refuse it: the objective moves nothing while the panel is held)."""
        assert isinstance(pending.command, OperatorCommand)
        mode, cid = str(pending.command.mode), pending.command_id
        before, by = self.objective_mode
        self.operator_mode = (mode, cid)
        was = f"was {before}, " + ("the panel file's control.mode" if by is None else
                                   f"operator command #{by}")
        up.results.append((cid, "applied", f"control objective {mode} ({was})"))
        up.events.append(("info", "mode_set", f"control objective {mode} by #{cid} "
                          f"{pending.source} {pending.requester} ({was})"))

    def handled(self, results: list[tuple[int, str, str]]) -> None:
        """Remember results until their cycle is stored."""
        for cid, status, reason in results:
            self._handled[cid] = (status, reason)

    def _claim(self) -> list[PendingCommand]:
        # A command's age is the host's business (the operator typed it), not the loop's
        # clock, which may be simulated.
        now_s = time.time()
        try:
            rows = command_table.pending(self.store.reader())
        except sqlite3.Error as exc:  # a database problem must not stop the cycle
            if not self._read_failing:
                log.warning("operator commands not read: %s", exc)
            self._read_failing = True
            return []
        self._read_failing = False
        waiting = {r.command_id for r in rows}
        # Rows no longer pending were stored with their result: forget them.
        self._handled = {k: v for k, v in self._handled.items() if k in waiting}
        out = []
        for row in rows:
            if row.command_id in self._handled:
                continue
            try:
                if now_s - row.requested_s > command_table.MAX_AGE_S:
                    raise CommandError("command", row.kind, "expired: requested "
                                       f"{(now_s - row.requested_s) / 60:.0f} min before the "
                                       "daemon read it")
                cmd: Any = validate_command(self.cfg, row.request())
            except CommandError as exc:
                cmd = exc
            except Exception as exc:  # a bug in validation must not fail every cycle
                log.exception("operator command #%d could not be validated", row.command_id)
                cmd = CommandError("command", row.kind, f"could not be validated: "
                                   f"{type(exc).__name__}")
            log.info("operator command #%d from %s (%s): %s", row.command_id, row.source,
                     row.requester, cmd if isinstance(cmd, CommandError) else cmd.describe())
            out.append(PendingCommand(row.command_id, cmd, row.source, row.requester))
        return out
