"""BACnet/IP: each panel is a device on the building's BACnet network (ASHRAE 135).

* :class:`~dsfd.integrations.bacnet.device.BacnetDevice` — the device beside the loop
  (``dsfd run`` with a ``bacnet:`` section), fed from the database; writes to its
  commandable points become rows of the ``commands`` table;
* :mod:`~dsfd.integrations.bacnet.points` — the object table (docs/bacnet.md);
* :mod:`~dsfd.integrations.bacnet.commands` — priority arrays and the checks of a write.

bacpypes3 is the optional extra ``dsfd[bacnet]``: :func:`device_for_run` raises
:class:`MissingExtraError` naming the install command without it.
"""

from __future__ import annotations

import errno
import ipaddress
import socket
from typing import TYPE_CHECKING

from dsfd.config import ConfigError, ConfigIssue, PanelConfig
from dsfd.integrations.mqtt.link import MissingExtraError

if TYPE_CHECKING:
    from dsfd.integrations.bacnet.device import BacnetDevice

__all__ = ["INSTALL_HINT", "MissingExtraError", "device_for_run", "require_bacpypes3"]

INSTALL_HINT = "pip install 'dsfd[bacnet]'"


def require_bacpypes3() -> None:
    """Raise :class:`MissingExtraError` naming the install command if bacpypes3 is missing."""
    try:
        import bacpypes3  # noqa: F401
    except ImportError:
        raise MissingExtraError(
            f"BACnet needs the bacpypes3 library, which is not installed: {INSTALL_HINT}"
        ) from None


def _check_bind(cfg: PanelConfig) -> None:
    """The address must be this host's and the port free: bacpypes3 would otherwise retry
    the bind for ever without a word."""
    s = cfg.bacnet
    assert s is not None
    host = str(ipaddress.IPv4Interface(s.address).ip)
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        probe.bind((host, s.port))
    except OSError as exc:
        in_use = exc.errno == errno.EADDRINUSE
        key, value = ("bacnet.port", s.port) if in_use else ("bacnet.address", s.address)
        raise ConfigError([ConfigIssue(key, value, f"cannot bind UDP {host}:{s.port}: "
                                       f"{exc.strerror or exc}")]) from None
    finally:
        probe.close()


def device_for_run(cfg: PanelConfig, *, version: str) -> BacnetDevice:
    """The device of a panel with a ``bacnet:`` section, checked before anything opens."""
    require_bacpypes3()
    _check_bind(cfg)
    from dsfd.integrations.bacnet.device import BacnetDevice

    return BacnetDevice(cfg, version=version)
