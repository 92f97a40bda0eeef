"""One pymodbus async client per physical link, with reconnects owned by dsfd.

pymodbus 3.16.1 facts this relies on (pinned by tests/drivers/test_modbus_tcp.py):

* clients must be built inside a running event loop (the transport grabs
  ``asyncio.get_running_loop()`` in ``__init__``), so :class:`ModbusLink` builds lazily;
* ``connect()`` returns False on failure (no exception) and, when the *first* connect fails,
  starts no background retry: later requests raise ``ConnectionException`` even after the
  device came up. dsfd passes ``reconnect_delay=0`` (pymodbus starts no reconnect task after a
  drop either) and calls ``connect()`` itself under an exponential :class:`Backoff`;
* one client serialises its requests with an ``asyncio.Lock``: one client per TCP endpoint or
  serial line, shared by every device id on it.

Logging: pymodbus logs through the stdlib logger ``pymodbus.logging``;
:func:`configure_pymodbus_logging` sets its level and adds no handler (unlike
``pymodbus_apply_logging_config``), so the daemon's handlers (structlog) render it.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections import Counter
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from pymodbus.client import AsyncModbusSerialClient, AsyncModbusTcpClient
from pymodbus.framer import FramerType

from dsfd.drivers.resilience import Backoff

if TYPE_CHECKING:
    from dsfd.config.devices import DeviceConfig

__all__ = ["Clock", "ModbusClient", "ModbusLink", "configure_pymodbus_logging"]

log = logging.getLogger(__name__)
Clock = Callable[[], float]
ModbusClient = AsyncModbusTcpClient | AsyncModbusSerialClient


def configure_pymodbus_logging(*, level: int = logging.WARNING) -> None:
    """Let pymodbus' stdlib logging flow to the application's handlers at ``level``.

    Note pymodbus logs each timed-out request at ERROR, with a dump of the last frames, and a
    refused connect at WARNING; dsfd reports both as reading qualities and logs the first of a
    series itself, so a daemon may prefer ``level=logging.CRITICAL`` here.
    """
    logger = logging.getLogger("pymodbus")
    logger.setLevel(level)
    logger.propagate = True


class ModbusLink:
    """One pymodbus async client for one TCP endpoint or serial line, with owned reconnects.

    The client is built lazily inside the running event loop (pymodbus 3.16 clients grab
    ``asyncio.get_running_loop()`` in ``__init__``). ``lock`` is held by one device for the
    whole of its poll, so the hard time cap of a device never counts time spent waiting for
    another device on the same line.
    """

    def __init__(self, *, key: str, client_factory: Callable[[], ModbusClient], is_tcp: bool,
                 backoff: Backoff, clock: Clock = time.monotonic) -> None:
        self.key = key
        self.is_tcp = is_tcp
        self.backoff = backoff
        self.lock = asyncio.Lock()
        #: connect_attempts, connect_failures, connects, drops.
        self.counters: Counter[str] = Counter()
        self._factory = client_factory
        self._clock = clock
        self._client: ModbusClient | None = None
        self._down = False  # inside an outage: log its first failure loudly, repeats quietly

    @classmethod
    def for_device(cls, cfg: DeviceConfig, *, clock: Clock = time.monotonic) -> ModbusLink:
        """The link of a ``modbus_tcp``/``modbus_rtu`` device config."""
        backoff = Backoff(min_s=cfg.reconnect_backoff_min_s, max_s=cfg.reconnect_backoff_max_s)
        key = cfg.link_key()
        common: dict[str, Any] = {"name": key, "reconnect_delay": 0, "timeout": cfg.timeout_s,
                                  "retries": cfg.retries}
        if cfg.kind == "modbus_tcp":
            assert cfg.tcp is not None
            tcp = cfg.tcp
            return cls(key=key, is_tcp=True, backoff=backoff, clock=clock,
                       client_factory=lambda: AsyncModbusTcpClient(tcp.host, port=tcp.port,
                                                                   **common))
        assert cfg.serial is not None
        line = cfg.serial
        return cls(key=key, is_tcp=False, backoff=backoff, clock=clock,
                   client_factory=lambda: AsyncModbusSerialClient(
                       line.port, framer=FramerType.RTU, baudrate=line.baudrate,
                       bytesize=line.bytesize, parity=line.parity, stopbits=line.stopbits,
                       **common))

    @property
    def client(self) -> ModbusClient:
        """The pymodbus client (created on first use)."""
        if self._client is None:
            self._client = self._factory()
        return self._client

    @property
    def connected(self) -> bool:
        return self._client is not None and self._client.connected

    async def ensure_connected(self) -> str | None:
        """Connect if needed and allowed by the backoff; None if connected, else why not."""
        client = self.client
        if client.connected:
            return None
        now = self._clock()
        if not self.backoff.ready(now):
            return (f"link {self.key} down, next connect attempt in "
                    f"{self.backoff.wait_s(now):.1f} s")
        self.counters["connect_attempts"] += 1
        try:
            ok = await client.connect()
        except Exception as exc:  # a pyserial/OS error must not escape the driver
            log.debug("connect %s raised", self.key, exc_info=True)
            ok, why = False, f"{type(exc).__name__}: {exc}"
        else:
            why = "connect failed (refused, unreachable or port missing)"
        if ok and client.connected:
            if self._down:
                log.info("modbus link %s connected again", self.key)
                self._down = False
            self.backoff.succeeded()
            self.counters["connects"] += 1
            return None
        delay = self.backoff.failed(now)
        self.counters["connect_failures"] += 1
        log.log(logging.DEBUG if self._down else logging.WARNING,
                "modbus link %s: %s; retry in %.1f s", self.key, why, delay)
        self._down = True
        return f"link {self.key}: {why}"

    def drop(self) -> None:
        """Close a TCP connection after a timeout, so a late answer cannot be taken for the
        next request's and the next cycle starts on a fresh connection. Serial lines stay
        open: reopening the port does not wake a silent slave."""
        if self.is_tcp and self._client is not None and self._client.connected:
            self.counters["drops"] += 1
            self._client.close()

    def close(self) -> None:
        """Close the client; idempotent."""
        if self._client is not None:
            self._client.close()
            self._client = None


