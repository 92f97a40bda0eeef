"""In-process null-modem cable made of two pseudo-terminals, for Modbus RTU without hardware.

::

    client ── port_a (pty slave A) ══ master A ─┐ relay thread ┌─ master B ══ port_b ── server
                                                 └─────────────┘

Each side opens its ``port_*`` path like a real serial port (pyserial, pymodbus). The relay
copies bytes between the two masters in a daemon thread with ``select``, so it works whatever
event loop (or none) the two ends run. No external tools (socat) are needed.

Fault injection: :meth:`PtyPair.unplug` drops every byte in both directions until
:meth:`PtyPair.plug` — to both ends it looks like a cable pulled out of an RS-485 line.

The slave file descriptors stay open for the life of the pair: on Linux, reading a pty master
whose slave has no open descriptor fails with EIO, which would end the relay as soon as one
side closed its port (a device "reboot").
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import tty
from types import TracebackType

__all__ = ["PtyPair"]

_CHUNK = 4096


class PtyPair:
    """Two cross-connected ptys; open :attr:`port_a` on one end and :attr:`port_b` on the other."""

    def __init__(self) -> None:
        self._master_a, self._slave_a = os.openpty()
        self._master_b, self._slave_b = os.openpty()
        for fd in (self._slave_a, self._slave_b):
            tty.setraw(fd)  # no echo, no line discipline: binary RTU frames pass unchanged
        #: Path of end A (e.g. ``/dev/pts/7``).
        self.port_a: str = os.ttyname(self._slave_a)
        #: Path of end B.
        self.port_b: str = os.ttyname(self._slave_b)
        #: Bytes relayed A→B and B→A, and bytes dropped while unplugged.
        self.relayed_a_to_b = 0
        self.relayed_b_to_a = 0
        self.dropped = 0
        self._plugged = threading.Event()
        self._plugged.set()
        self._stop_read, self._stop_write = os.pipe()
        self._closed = False
        self._thread = threading.Thread(target=self._relay, name="pty-null-modem", daemon=True)
        self._thread.start()

    def unplug(self) -> None:
        """Drop all traffic (both directions) until :meth:`plug`."""
        self._plugged.clear()

    def plug(self) -> None:
        """Relay traffic again."""
        self._plugged.set()

    @property
    def plugged(self) -> bool:
        """True while traffic is relayed."""
        return self._plugged.is_set()

    def _relay(self) -> None:
        peer = {self._master_a: self._master_b, self._master_b: self._master_a}
        watched = [self._master_a, self._master_b, self._stop_read]
        while True:
            ready, _, _ = select.select(watched, [], [])
            if self._stop_read in ready:
                return
            for fd in ready:
                try:
                    data = os.read(fd, _CHUNK)
                except OSError:
                    return  # pair is being closed
                if not self._plugged.is_set():
                    self.dropped += len(data)
                    continue
                _write_all(peer[fd], data)
                if fd == self._master_a:
                    self.relayed_a_to_b += len(data)
                else:
                    self.relayed_b_to_a += len(data)

    def close(self) -> None:
        """Stop the relay and close all descriptors; idempotent."""
        if self._closed:
            return
        self._closed = True
        os.write(self._stop_write, b"x")
        self._thread.join(timeout=5)
        for fd in (self._master_a, self._master_b, self._slave_a, self._slave_b,
                   self._stop_read, self._stop_write):
            with contextlib.suppress(OSError):
                os.close(fd)

    def __enter__(self) -> PtyPair:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        try:
            n = os.write(fd, view)
        except OSError:
            return  # other end gone; a real cable would lose the bytes too
        view = view[n:]
