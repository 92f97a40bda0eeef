"""systemd's notification protocol (sd_notify) in a few lines, without libsystemd.

``$NOTIFY_SOCKET`` names an ``AF_UNIX``/``SOCK_DGRAM`` socket: a filesystem path, or ``@name``
for the abstract namespace. Each message is one datagram of newline-separated ``KEY=VALUE``
lines (sd_notify(3)); the protocol is declared stable by systemd. Without the variable every
call is a no-op, so the same code runs under systemd, in a terminal and in tests.

Messages used by the daemon: ``READY=1`` (after start-up), ``WATCHDOG=1`` (after each healthy
cycle), ``STATUS=…`` (one line for ``systemctl status``), ``RELOADING=1`` with
``MONOTONIC_USEC=`` then ``READY=1`` (around a SIGHUP reload; systemd 252 has no
``Type=notify-reload``), ``STOPPING=1``.
"""

from __future__ import annotations

import logging
import os
import socket
import time

__all__ = ["Notifier"]

log = logging.getLogger(__name__)


class Notifier:
    """Sends sd_notify messages to ``$NOTIFY_SOCKET`` (or ``address``); no-op without one."""

    def __init__(self, address: str | None = None) -> None:
        self.address = address if address is not None else os.environ.get("NOTIFY_SOCKET")
        self._sock: socket.socket | None = None
        #: Messages that could not be sent (counted, logged once).
        self.failures = 0
        watchdog_usec = os.environ.get("WATCHDOG_USEC", "")
        #: Watchdog interval systemd expects pings within [s], None if not enabled.
        self.watchdog_s: float | None = (int(watchdog_usec) / 1e6 if watchdog_usec.isdigit()
                                         else None)

    @property
    def enabled(self) -> bool:
        return bool(self.address)

    def _socket(self) -> socket.socket:
        if self._sock is None:
            assert self.address
            addr = "\0" + self.address[1:] if self.address.startswith("@") else self.address
            # Non-blocking: a receiver that does not keep up (its queue holds ~10 datagrams)
            # must never stall the control loop; the message is dropped and counted instead.
            sock = socket.socket(socket.AF_UNIX,
                                 socket.SOCK_DGRAM | socket.SOCK_CLOEXEC | socket.SOCK_NONBLOCK)
            sock.connect(addr)
            self._sock = sock
        return self._sock

    def send(self, **fields: str | int) -> bool:
        """Send one message, e.g. ``send(READY=1, STATUS="cycling")``; True if sent."""
        if not self.enabled:
            return False
        payload = "\n".join(f"{k}={v}" for k, v in fields.items()).encode("utf-8")
        try:
            self._socket().sendall(payload)
        except BlockingIOError:
            self.failures += 1  # receiver's queue full: drop, never wait
            return False
        except OSError as exc:
            self.failures += 1
            if self.failures == 1:
                log.warning("sd_notify to %s failed: %s", self.address, exc)
            self.close()  # reconnect next time (systemd may have been restarted)
            return False
        return True

    def ready(self, status: str) -> bool:
        return self.send(READY=1, STATUS=status)

    def watchdog(self, status: str | None = None) -> bool:
        """The keep-alive ping after a healthy cycle, with an optional new status line."""
        return self.send(WATCHDOG=1) if status is None else self.send(WATCHDOG=1, STATUS=status)

    def status(self, status: str) -> bool:
        return self.send(STATUS=status)

    def reloading(self) -> bool:
        return self.send(RELOADING=1, MONOTONIC_USEC=time.clock_gettime_ns(
            time.CLOCK_MONOTONIC) // 1000)

    def stopping(self, status: str = "stopping") -> bool:
        return self.send(STOPPING=1, STATUS=status)

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None
