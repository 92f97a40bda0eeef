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
"""

from __future__ import annotations

import logging
import sqlite3
import time
from collections.abc import Mapping
from typing import Any

from dsfd.config.panel import PanelConfig
from dsfd.daemon.commands import CommandError, validate_command
from dsfd.daemon.hold import Hold, HoldTracker, HoldUpdate, PendingCommand
from dsfd.drivers.base import Command
from dsfd.storage import commands as command_table
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

    @property
    def hold(self) -> Hold | None:
        return self.tracker.hold

    def reconfigure(self, cfg: PanelConfig) -> None:
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

    def update(self, *, now_mono_s: float, now_s: float, read_back: Command | None,
               expected: Command | None, input_active: bool | None, input_where: str
               ) -> HoldUpdate:
        """This cycle's hold, with the commands picked up now."""
        return self.tracker.update(now_mono_s=now_mono_s, now_s=now_s, read_back=read_back,
                                   expected=expected, input_active=input_active,
                                   input_where=input_where, commands=self._claim())

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
            log.info("operator command #%d from %s (%s): %s", row.command_id, row.source,
                     row.requester, cmd if isinstance(cmd, CommandError) else cmd.describe())
            out.append(PendingCommand(row.command_id, cmd, row.source, row.requester))
        return out
