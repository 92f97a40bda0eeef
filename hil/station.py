"""Weather-station emulator: writes protocol lines to a pseudo-terminal, with faults.

The driver under test opens :attr:`StationEmulator.port` (the pty slave path) like the real
serial port; the emulator writes to the master side. Faults are explicit calls, so tests are
deterministic: :meth:`send_garbage`, :meth:`send_bad_checksum`, :meth:`send_split` (first part
now, the rest later), and silence (send nothing). :meth:`start_periodic` runs a background
thread that sends a line every ``interval_s`` for longer HIL runs.

Bytes written before the driver opened the port are flushed by the driver at open (it only
wants lines received since its last cycle).
"""

from __future__ import annotations

import array
import contextlib
import fcntl
import os
import random
import termios
import threading
import time
import tty
from collections.abc import Callable, Mapping
from types import TracebackType

from dsfd.drivers.station import checksum, format_line

__all__ = ["StationEmulator"]

Values = Mapping[str, float | None]


class StationEmulator:
    """One station on its own pty."""

    def __init__(self) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # the slave fd stays open so the master never sees EIO
        #: Path the driver opens, e.g. ``/dev/pts/5``.
        self.port: str = os.ttyname(self._slave)
        #: Sequence number of the next line.
        self.seq = 0
        #: Bytes written so far.
        self.bytes_sent = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def queued(self) -> int:
        """Bytes waiting in the tty's input queue, i.e. sent but not yet read by the driver."""
        buf = array.array("i", [0])
        fcntl.ioctl(self._slave, termios.TIOCINQ, buf, True)
        return int(buf[0])

    def wait_queued(self, n_bytes: int, *, limit_s: float = 5.0) -> None:
        """Block until ``n_bytes`` are readable at the port (pty delivery is asynchronous in
        the kernel). ``limit_s`` only guards against a hang; TimeoutError past it."""
        deadline = time.monotonic() + limit_s
        while self.queued() < n_bytes:
            if time.monotonic() > deadline:
                raise TimeoutError(f"only {self.queued()} of {n_bytes} bytes reached the port")
            time.sleep(0.001)

    def line(self, values: Values, *, seq: int | None = None) -> bytes:
        """The protocol line for ``values`` (does not send, does not advance ``seq``)."""
        return format_line(self.seq if seq is None else seq, values)

    def send_raw(self, data: bytes) -> bytes:
        """Write ``data`` to the line as is; returns it."""
        with self._lock:
            view = memoryview(data)
            while view:
                n = os.write(self._master, view)
                view = view[n:]
            self.bytes_sent += len(data)
        return data

    def send_framed(self, body: str) -> bytes:
        """Send ``$<body>*HH`` CR LF with a *correct* checksum around any ``body`` (for lines
        that pass the checksum but break the field rules); returns it."""
        raw = body.encode("ascii")
        return self.send_raw(b"$" + raw + f"*{checksum(raw):02X}\r\n".encode("ascii"))

    def send(self, values: Values, *, seq: int | None = None) -> bytes:
        """Send one valid line; returns it. ``seq`` overrides (and resets) the counter."""
        if seq is not None:
            self.seq = seq
        data = self.line(values)
        self.seq = (self.seq + 1) % 65536
        self.send_raw(data)
        return data

    def send_bad_checksum(self, values: Values) -> bytes:
        """Send a line whose checksum is off by one bit; returns it."""
        good = self.line(values)
        star = good.rindex(b"*")
        wrong = int(good[star + 1:star + 3], 16) ^ 0x01
        data = good[:star + 1] + f"{wrong:02X}".encode() + b"\r\n"
        self.seq = (self.seq + 1) % 65536
        self.send_raw(data)
        return data

    def send_garbage(self, n: int = 24, *, seed: int = 0) -> bytes:
        """Send ``n`` random bytes containing neither ``$`` nor LF (line noise)."""
        rng = random.Random(seed)
        data = bytes(b for b in (rng.randrange(256) for _ in range(4 * n)) if b not in b"$\n")[:n]
        self.send_raw(data)
        return data

    def send_split(self, values: Values, *, at: int) -> bytes:
        """Send the first ``at`` bytes of a valid line; return the rest (send it later)."""
        data = self.line(values)
        self.seq = (self.seq + 1) % 65536
        self.send_raw(data[:at])
        return data[at:]

    def start_periodic(self, interval_s: float, values: Callable[[], Values]) -> None:
        """Send ``values()`` every ``interval_s`` [s] from a daemon thread until stopped."""
        self.stop_periodic()
        self._stop.clear()

        def run() -> None:
            while not self._stop.wait(interval_s):
                self.send(values())

        self._thread = threading.Thread(target=run, name="station-emulator", daemon=True)
        self._thread.start()

    def stop_periodic(self) -> None:
        if self._thread is not None:
            self._stop.set()
            self._thread.join(timeout=5)
            self._thread = None

    def close(self) -> None:
        """Stop sending and close the pty; idempotent."""
        self.stop_periodic()
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._master = self._slave = -1

    def __enter__(self) -> StationEmulator:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
