"""bacpypes3's log records, as the daemon's log shows them.

bacpypes3 drops a malformed datagram after logging it at error level with the decoding
traceback (``IPv4DatagramServer``: "error processing incoming PDU", ``UDPMultiplexer``:
"unsupported message", ``Application``: a reject of an unconfirmed request). Anyone who can
send UDP to the device could fill the journal that way, and the tracebacks would look like
faults of the daemon. :class:`BacpypesLogs` takes over the ``bacpypes3`` logger tree: such a
record becomes one warning line without traceback ("BACnet datagram dropped: …"), at most
:data:`LOGGED_PER_MINUTE` a minute, the rest counted in a line once the minute is over.

An unexpected exception in a service handler (bacpypes3's ``Application`` logs "exception:
…" and answers operational-problem) is not input's fault: it stays an error with its
traceback.
"""

from __future__ import annotations

import logging
import time

from dsfd.daemon.logging_setup import get_logger

__all__ = ["LOGGED_PER_MINUTE", "BacpypesLogs"]

log = get_logger("dsfd.bacnet")

#: Dropped-datagram lines logged per minute at most; the rest are counted.
LOGGED_PER_MINUTE = 10


class BacpypesLogs(logging.Handler):
    """The handler of the ``bacpypes3`` logger while the device runs."""

    def __init__(self) -> None:
        super().__init__(level=logging.WARNING)
        self.dropped = 0
        self._window_start = time.monotonic()
        self._logged = self._suppressed = 0
        self._saved: tuple[bool, int] | None = None

    def install(self) -> None:
        root = logging.getLogger("bacpypes3")
        self._saved = (root.propagate, root.level)
        root.addHandler(self)
        root.propagate = False
        root.setLevel(logging.WARNING)

    def remove(self) -> None:
        root = logging.getLogger("bacpypes3")
        root.removeHandler(self)
        if self._saved is not None:
            root.propagate, level = self._saved
            root.setLevel(level)
        self._flush_count(force=True)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            message = record.getMessage()
        except Exception:  # a record whose arguments do not format
            message = str(record.msg)
        if record.name.startswith("bacpypes3.app") and message.startswith("exception:"):
            log.error("BACnet service handler failed: %s", message, exc_info=record.exc_info)
            return
        self.dropped += 1
        self._flush_count()
        if self._logged < LOGGED_PER_MINUTE:
            self._logged += 1
            log.warning("BACnet datagram dropped: %s", message, origin=record.name)
        else:
            self._suppressed += 1

    def _flush_count(self, *, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self._window_start < 60.0:
            return
        if self._suppressed:
            log.warning("%d more BACnet datagram(s) dropped in the last minute (not logged "
                        "one by one)", self._suppressed, dropped_total=self.dropped)
        self._window_start, self._logged, self._suppressed = now, 0, 0
