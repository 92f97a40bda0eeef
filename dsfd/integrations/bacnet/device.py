"""The panel's BACnet/IP device: a thread of its own beside the control loop, fed from the
database.

Why a thread with its own asyncio loop (not the daemon's loop, not a process): bacpypes3 is
asyncio-based, and on the daemon's loop a flood of requests or a bug in a handler would sit
between the cycle's awaits; in its own loop it can only take CPU time, which the tests bound
(2,000 malformed datagrams, no skipped slot). The MQTT publisher runs the same way; the
device reads what the loop stored, exactly as the publisher does, and its commands go through
the database. A process of its own would isolate the interpreter too but would need its own
lifecycle under systemd and could outlive the daemon while claiming to be it.

After each stored cycle the runner calls :meth:`BacnetDevice.cycle_stored`, which only wakes
the device's loop; the device then reads the new cycles in stored order
(:class:`~dsfd.integrations.mqtt.outbox.Outbox`, the MQTT publisher's reader), builds each
one's state message (:func:`~dsfd.integrations.mqtt.messages.state_message`) and sets the
points from it one cycle at a time, so a COV subscriber is notified of every stored cycle
(the ``stored cycle`` point changes by 1 per cycle, its COV increment). At a clean stop every
object goes out of service (a last COV notification) before the socket closes.

Writes (:meth:`BacnetDevice.write`): refused unless ``bacnet.writable``; checked against the
panel (:mod:`dsfd.integrations.bacnet.commands`); then filed in the ``commands`` table with
source ``bacnet`` and the writer's address and priority as requester. The priority arrays
follow the daemon: when the hold they made has ended (expired, resumed by another operator,
superseded, or the command was rejected), every slot is relinquished.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import sqlite3
import threading
from pathlib import Path
from typing import Any

from dsfd.config import PanelConfig
from dsfd.config.bacnet import Bacnet
from dsfd.daemon.commands import CommandError, validate_command
from dsfd.daemon.logging_setup import get_logger
from dsfd.integrations.bacnet.commands import (
    CONTROLLER_PRIORITY,
    BacnetWriteError,
    PriorityArrays,
    check_value,
    objective_request,
)
from dsfd.integrations.bacnet.logs import BacpypesLogs
from dsfd.integrations.bacnet.points import Point, point_values, points_for
from dsfd.integrations.mqtt.messages import state_message
from dsfd.integrations.mqtt.outbox import Key, Outbox
from dsfd.storage import commands as command_table

__all__ = ["BacnetDevice"]

log = get_logger("dsfd.bacnet")

#: Cycles read from the database per wake-up at most (the rest at the next one).
BATCH = 200
#: At a clean stop, how long the out-of-service notifications may take to go out [s].
NOTIFY_ON_STOP_S = 0.5
#: How often the device looks at the database without being woken [s].
IDLE_POLL_S = 5.0


class BacnetDevice:
    """One panel's BACnet/IP device (bacpypes3), run on a thread of its own."""

    name = "bacnet"

    def __init__(self, cfg: PanelConfig, *, version: str) -> None:
        assert cfg.bacnet is not None
        self.cfg = cfg
        self.settings: Bacnet = cfg.bacnet
        self.version = version
        self.points: tuple[Point, ...] = points_for(cfg)
        self.arrays = PriorityArrays()
        self.objects: dict[str, Any] = {}
        self.app: Any = None
        self.database: Path | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._wake: asyncio.Event | None = None
        self._write_lock = asyncio.Lock()
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._thread: threading.Thread | None = None
        self._after: Key = (0, 0)
        #: The command the priority arrays made, while it may be in force.
        self._our_command: int | None = None
        #: Counts for the log and the tests.
        self.cycles_shown = self.writes_accepted = self.writes_refused = 0
        self.show_failures = 0
        self.failed: str | None = None
        self.logs = BacpypesLogs()

    # ------------------------------------------------------------------ the runner's hooks
    def start(self, *, database: Path) -> None:
        self.database = database
        ctx = contextvars.copy_context()  # the log lines keep the panel
        self._thread = threading.Thread(target=ctx.run, args=(self._run,), name="dsfd-bacnet",
                                        daemon=True)
        self._thread.start()
        self._ready.wait(10.0)

    def cycle_stored(self, cycle: int) -> None:
        loop, wake = self._loop, self._wake
        if loop is not None and wake is not None:
            with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
                loop.call_soon_threadsafe(wake.set)

    def stop(self, *, timeout_s: float = 5.0) -> None:
        self._stop.set()
        self.cycle_stored(0)
        if self._thread is not None:
            self._thread.join(timeout_s)
            if self._thread.is_alive():
                log.warning("BACnet device did not stop within %g s; abandoned", timeout_s)

    def health(self) -> dict[str, Any]:
        return {"cycles_shown": self.cycles_shown, "writes_accepted": self.writes_accepted,
                "writes_refused": self.writes_refused, "datagrams_dropped": self.logs.dropped,
                "failed": self.failed}

    # ------------------------------------------------------------------ the thread
    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except Exception as exc:  # the device is lost; control goes on
            self.failed = f"{type(exc).__name__}: {exc}"
            log.exception("BACnet device failed; control goes on without it")
        finally:
            self._ready.set()

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._wake = asyncio.Event()
        assert self.database is not None
        self.logs.install()
        outbox = Outbox.open(self.database, "bacnet")
        try:
            await self._serve(outbox)
        finally:
            if self.app is not None:
                self.app.close()
            outbox.close()
            self.logs.remove()

    async def _serve(self, outbox: Outbox) -> None:
        from dsfd.integrations.bacnet.build import build_application

        self.app, self.objects = build_application(self.cfg, self.points, version=self.version)
        self.app.write_handler = self.write
        s = self.settings
        log.info("BACnet device listening", device=f"device,{s.device_instance}",
                 address=s.bind_address(), writable=s.writable,
                 foreign_device=None if s.foreign_device is None else s.foreign_device.bbmd)
        newest = outbox.conn.execute(
            "SELECT run_id, cycle FROM decisions ORDER BY run_id DESC, cycle DESC "
            "LIMIT 1 OFFSET 1").fetchone()
        self._after = (0, 0) if newest is None else (int(newest[0]), int(newest[1]))
        self._ready.set()
        assert self._wake is not None
        while not self._stop.is_set():
            await self._show_new(outbox)
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(IDLE_POLL_S):
                    await self._wake.wait()
            self._wake.clear()
        await self._show_new(outbox)
        self._out_of_service()
        log.info("BACnet device out of service: the daemon stops")
        await asyncio.sleep(NOTIFY_ON_STOP_S)

    async def _show_new(self, outbox: Outbox) -> None:
        """Show the cycles stored since the last look, one at a time."""
        while True:
            try:
                cycles, _, _ = outbox.pending(self._after, limit=BATCH, max_age_s=1e12)
            except sqlite3.Error as exc:
                log.warning("BACnet device cannot read the database: %s", exc)
                return
            for p in cycles:
                message = state_message(self.cfg.panel.id, p.row, p.samples,
                                        calibrated_s=p.calibrated_s)
                try:
                    self._follow_daemon(outbox.conn, message)
                    self.show(message)
                except Exception:  # a bug here must not end the device for good
                    self.show_failures += 1
                    if self.show_failures == 1:
                        log.exception("BACnet device could not show cycle %d", p.key[1])
                self._after = p.key
                self.cycles_shown += 1
                await asyncio.sleep(0)  # COV detection runs between cycles
            if len(cycles) < BATCH:
                return

    # ------------------------------------------------------------------ points
    def show(self, message: dict[str, Any]) -> None:
        """Set every point from one cycle's state message."""
        from dsfd.integrations.bacnet.build import update_point

        values = point_values(self.points, message)
        hold = bool(message.get("hold"))
        overridden = hold and message.get("hold_source") != "operator"
        for p in self.points:
            update_point(self.objects[p.key], p, values[p.key], overridden=overridden,
                         controller=not hold)

    def _out_of_service(self) -> None:
        for obj in self.objects.values():
            flags = list(obj.statusFlags)
            flags[3] = 1
            obj.statusFlags = flags  # first: COV detection watches the flags, and
            obj.outOfService = True  # bacpypes3 sets the flag quietly with this one

    def _follow_daemon(self, conn: sqlite3.Connection, message: dict[str, Any]) -> None:
        """Relinquish every slot when the hold the arrays made is over."""
        cid = self._our_command
        if cid is None:
            return
        row = conn.execute("SELECT status, run_id, cycle, reason FROM commands WHERE "
                           "command_id = ?", (cid,)).fetchone()
        if row is None or row[0] == "pending":
            return
        status, run_id, cycle, reason = row
        if status == "rejected":
            why = f"the daemon rejected command #{cid}: {reason}"
        elif (message["run"], message["cycle"]) > (run_id or 0, cycle or 0) and \
                message.get("hold_command_id") != cid:
            why = f"the hold of command #{cid} ended ({message.get('set_by')} now)"
        else:
            return
        self._our_command = None
        from dsfd.integrations.bacnet.build import clear_slots

        if self.arrays.clear():
            clear_slots(self.objects)
            log.info("BACnet priority arrays relinquished: %s", why)

    # ------------------------------------------------------------------ writes
    async def write(self, obj: Any, value: Any, priority: int | None, source: str) -> None:
        """A WriteProperty of a present value (None: NULL); raises the BACnet error."""
        from dsfd.integrations.bacnet.objects import refusal

        key = next((k for k, o in self.objects.items() if o is obj), None)
        try:
            async with self._write_lock:  # one write at a time: each sees the last's arrays
                await self._write(key, value, priority, source)
        except BacnetWriteError as exc:
            self.writes_refused += 1
            log.warning("BACnet write refused: %s", exc.reason, point=key, value=str(value),
                        priority=priority, source=source, error=exc.error_code)
            raise refusal(exc.error_code) from None
        self.writes_accepted += 1

    async def _write(self, key: str | None, value: Any, priority: int | None,
                     source: str) -> None:
        point = next((p for p in self.points if p.key == key), None)
        if not self.settings.writable:
            raise BacnetWriteError("writeAccessDenied", "bacnet.writable is false")
        if point is None or not point.writable:
            raise BacnetWriteError("writeAccessDenied", f"{key or 'this object'} is read-only")
        if point.key == "objective":
            if value is None:
                raise BacnetWriteError("invalidDataType", "NULL: the objective has no "
                                       "priority array; write 1 heating, 2 cooling or 3 auto")
            request = objective_request(int(value))
            await self._file(request, f"{source} objective")
            return
        p = CONTROLLER_PRIORITY if priority is None else int(priority)
        if not 1 <= p <= CONTROLLER_PRIORITY:
            raise BacnetWriteError("valueOutOfRange", f"priority {p}: expected 1..16")
        if p == CONTROLLER_PRIORITY:
            raise BacnetWriteError("writeAccessDenied", "priority 16 is the controller's "
                                   "own command; an operator writes at 1..15")
        number = None if value is None else check_value(self.cfg, point.key, value)
        writer = f"{source} priority {p}"
        trial = PriorityArrays({k: dict(v) for k, v in self.arrays.slots.items()})
        if not trial.write(point.key, p, number, writer):
            self._commit(trial, point.key, p, number)  # in force unchanged: no command
            return
        request, by = trial.request(until_relinquished=self.settings.hold_until_relinquished)
        cid = await self._file(request, by or writer)  # checks the combined request too
        self._commit(trial, point.key, p, number)
        self._our_command = None if request["command"] == "resume" else cid

    def _commit(self, trial: PriorityArrays, key: str, priority: int,
                number: float | int | None) -> None:
        from dsfd.integrations.bacnet.objects import set_slot

        self.arrays = trial
        set_slot(self.objects[key], priority, number)

    async def _file(self, request: dict[str, Any], requester: str) -> int:
        """Put a request into the ``commands`` table (off the device's loop)."""
        assert self.database is not None
        try:
            validate_command(self.cfg, request)
        except CommandError as exc:
            raise BacnetWriteError("valueOutOfRange", str(exc)) from None
        args = {k: v for k, v in request.items() if k != "command"}
        loop = asyncio.get_running_loop()
        try:
            cid = await loop.run_in_executor(None, lambda: command_table.submit(
                self.database, kind=str(request["command"]), args=args, source="bacnet",
                requester=requester))
        except sqlite3.Error as exc:
            raise BacnetWriteError("operationalProblem", f"not queued: the database cannot "
                                f"be written ({exc})") from None
        log.info("BACnet command #%d queued: %s", cid, request, requester=requester)
        return cid
