"""Commands from the broker into the daemon's ``commands`` table, on a thread of their own.

paho-mqtt's network thread hands every message on ``<base>/cmd/#`` to
:meth:`CommandReceiver.offer`, which only puts it into a bounded queue: it never blocks and
never raises, so neither the publisher nor paho's keep-alive and acknowledgements wait for a
command, and the control loop knows nothing of them. The receiver's thread then, per message:

1. refuses a *retained* command (the broker replays it at every subscription: it is old),
   one longer than :data:`~dsfd.integrations.mqtt.commands.MAX_PAYLOAD_BYTES`, or one on an
   unknown subtopic;
2. turns the payload into a request (:func:`~dsfd.integrations.mqtt.commands.request_of`)
   and checks it with :func:`~dsfd.daemon.commands.validate_command`, the validation of
   ``dsfd override``/``resume``/``mode``/``occupancy``;
3. inserts it into the ``commands`` table (:func:`dsfd.storage.commands.submit`) with source
   ``mqtt`` and as requester the broker and the topic (MQTT 3.1.1 does not tell a receiver
   who published). The loop picks it up at its next cycle, validates it again against the
   configuration it runs, applies it and records the answer, as for the CLI.

A refusal changes nothing: it is published on ``<base>/error`` (QoS 0, not retained; JSON
with the topic, the reason and the payload cut to
:data:`~dsfd.integrations.mqtt.commands.SHOWN_BYTES`) and logged with the same. A command the
daemon rejects when it applies it (an override input is set, it expired) is answered there
too, with its ``command_id``. Commands given while the daemon was not connected do not count:
the session is clean, so the broker keeps nothing for it (docs/mqtt.md, "Commands over MQTT").
"""

from __future__ import annotations

import contextvars
import queue
import sqlite3
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from dsfd.config import PanelConfig
from dsfd.daemon.commands import CommandError, validate_command
from dsfd.daemon.logging_setup import get_logger
from dsfd.integrations.mqtt.commands import MAX_PAYLOAD_BYTES, error_message, request_of, shown
from dsfd.integrations.mqtt.messages import dumps
from dsfd.storage import commands as command_table
from dsfd.storage.timeseries import BUSY_TIMEOUT_MS

__all__ = ["QUEUE_SIZE", "CommandReceiver"]

log = get_logger("dsfd.mqtt")

#: Command messages waiting for the receiver's thread at most; more are dropped and counted.
QUEUE_SIZE = 256
#: Refusals logged at warning level per minute; the rest at debug level, with a count.
LOGGED_PER_MINUTE = 50
#: Commands whose answer from the loop is awaited (to publish a rejection) at most.
AWAITED = 256


@dataclass(frozen=True)
class _Message:
    topic: str
    payload: bytes  # at most MAX_PAYLOAD_BYTES + 1 bytes of it
    size: int
    retained: bool


class CommandReceiver:
    """Takes command messages from paho's thread and files them as the CLI does.

    ``answer(text)`` publishes ``text`` on ``<base>/error`` if connected (the publisher's).
    """

    def __init__(self, cfg: PanelConfig, *, base_topic: str, broker: str,
                 answer: Callable[[str], None]) -> None:
        self.cfg = cfg
        self.prefix = f"{base_topic}/cmd/"
        self.broker = broker
        self.answer = answer
        self.queue: queue.Queue[_Message] = queue.Queue(maxsize=QUEUE_SIZE)
        self.dropped = 0
        self._dropped_answered = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._awaited: OrderedDict[int, tuple[_Message, float]] = OrderedDict()
        self._window_start = time.monotonic()
        self._logged = self._suppressed = 0
        #: Counts for the tests and the log: queued, refused here, rejected by the loop.
        self.queued = self.refused = self.rejected = 0

    # ------------------------------------------------------------------ paho's thread
    def offer(self, topic: str, payload: bytes, retained: bool) -> None:
        """Queue one message (paho's network thread: returns at once, never raises)."""
        try:
            self.queue.put_nowait(_Message(topic, bytes(payload[:MAX_PAYLOAD_BYTES + 1]),
                                           len(payload), bool(retained)))
        except queue.Full:
            self.dropped += 1

    # ------------------------------------------------------------------ own thread
    def start(self, *, database: Path) -> None:
        ctx = contextvars.copy_context()  # the log lines keep the panel
        self._thread = threading.Thread(target=ctx.run, args=(self._main, database),
                                        name="dsfd-mqtt-commands", daemon=True)
        self._thread.start()

    def stop(self, *, timeout_s: float = 2.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)

    def _main(self, database: Path) -> None:
        conn = None
        try:
            conn = sqlite3.connect(f"file:{database}?mode=ro", uri=True,
                                   timeout=BUSY_TIMEOUT_MS / 1000)
            while not self._stop.is_set():
                try:
                    msg = self.queue.get(timeout=0.25)
                except queue.Empty:
                    msg = None
                try:
                    if msg is not None:
                        self.handle(msg, database=database)
                    self._answer_drops()
                    self._answer_rejections(conn)
                except Exception:  # a bug must not end command handling for good
                    log.exception("MQTT command handling failed")
        except sqlite3.Error as exc:
            log.error("MQTT commands cannot read the database: %s; commands over MQTT are "
                      "refused", exc)
        finally:
            if conn is not None:
                conn.close()

    def handle(self, msg: _Message, *, database: Path) -> int | None:
        """File one command message; its ``command_id``, or None if it was refused."""
        try:
            if not msg.topic.startswith(self.prefix):
                raise CommandError("topic", msg.topic, f"not under {self.prefix}")
            if msg.retained:
                raise CommandError("retain", True, "a retained command is an old one, replayed "
                                   "by the broker: ignored (publish commands without the "
                                   "retain flag; an empty retained message clears it)")
            if msg.size > MAX_PAYLOAD_BYTES:
                raise CommandError("payload", f"{msg.size} bytes", f"longer than "
                                   f"{MAX_PAYLOAD_BYTES} bytes: not read")
            request = request_of(msg.topic[len(self.prefix):], msg.payload)
            validated = validate_command(self.cfg, request)
        except CommandError as exc:
            self._refuse(msg, str(exc))
            return None
        args = {k: v for k, v in request.items() if k != "command"}
        try:
            cid = command_table.submit(database, kind=str(request["command"]), args=args,
                                       source="mqtt", requester=f"{self.broker} {msg.topic}")
        except sqlite3.Error as exc:
            self._refuse(msg, f"not queued: the database cannot be written ({exc})")
            return None
        self.queued += 1
        log.info("MQTT command #%d queued: %s", cid, validated.describe(), topic=msg.topic)
        self._awaited[cid] = (msg, time.monotonic())
        while len(self._awaited) > AWAITED:
            self._awaited.popitem(last=False)
        return cid

    def _refuse(self, msg: _Message, reason: str, *, command_id: int | None = None) -> None:
        answer = error_message(msg.topic, reason, msg.payload, size=msg.size,
                               command_id=command_id)
        if command_id is None:
            self.refused += 1
        else:
            self.rejected += 1
        what = "refused" if command_id is None else "rejected"
        self._log(f"MQTT command {what}: {reason}", topic=msg.topic,
                  payload=shown(msg.payload, size=msg.size), payload_bytes=msg.size)
        self.answer(dumps(answer))

    def _answer_drops(self) -> None:
        dropped = self.dropped
        if dropped == self._dropped_answered:
            return
        n = dropped - self._dropped_answered
        self._dropped_answered = dropped
        reason = (f"{n} command message(s) dropped unread: more than {QUEUE_SIZE} were "
                  "waiting")
        log.warning("MQTT %s", reason, dropped_total=dropped)
        self.answer(dumps(error_message(f"{self.prefix}#", reason, b"")))

    def _answer_rejections(self, conn: sqlite3.Connection) -> None:
        """Publish the loop's rejections of commands filed here."""
        if not self._awaited:
            return
        now = time.monotonic()
        ids = list(self._awaited)
        rows = conn.execute(
            f"SELECT command_id, status, reason FROM commands WHERE command_id IN "
            f"({', '.join('?' for _ in ids)}) AND status != 'pending'", ids).fetchall()
        for cid, status, reason in rows:
            msg, _ = self._awaited.pop(cid)
            if status == "rejected":
                self._refuse(msg, f"rejected by the daemon: {reason}", command_id=cid)
        limit = command_table.MAX_AGE_S + 60.0
        for cid, (_, since) in list(self._awaited.items()):
            if now - since > limit:
                del self._awaited[cid]

    def _log(self, message: str, **fields: object) -> None:
        """Warning level up to :data:`LOGGED_PER_MINUTE` a minute, debug after that."""
        now = time.monotonic()
        if now - self._window_start >= 60.0:
            if self._suppressed:
                log.warning("%d more MQTT command(s) refused in the last minute (logged at "
                            "debug level)", self._suppressed)
            self._window_start, self._logged, self._suppressed = now, 0, 0
        if self._logged < LOGGED_PER_MINUTE:
            self._logged += 1
            log.warning(message, **fields)
        else:
            self._suppressed += 1
            log.debug(message, **fields)
