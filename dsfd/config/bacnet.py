"""Settings of the optional BACnet/IP device of a panel (a building management system's view).

YAML shape (the ``bacnet:`` section of a panel file; absent or ``null``: no BACnet, nothing
listens)::

    bacnet:
      device_instance: 41001        # unique on the BACnet internetwork, 0..4194302
      device_name: null             # null: dsfd-<panel id>
      address: 192.0.2.10/24        # the interface to bind, with its prefix (broadcasts)
      port: 47808                   # UDP, 0xBAC0
      network_number: null          # null: the local network (no router configured here)
      foreign_device:               # register with a BBMD (routed networks); null: none
        bbmd: 198.51.100.7:47808
        ttl_s: 300
      writable: false               # true: priority-array writes become operator holds
      hold_until_relinquished: false  # true: a hold lasts until relinquished (at most 7 d)
      vendor_identifier: 999

The device binds only the configured address and port. It is read-only until ``writable``
is true; then a write at priority 1..15 of the louver, regime or damper object is an operator
hold through the ``commands`` table, as ``dsfd override`` (docs/bacnet.md).

Instance ranges: ASHRAE 135-2020 clause 12.11.1 (Object_Identifier: a 22-bit instance; 4194303
is reserved as "unconfigured"); the BBMD and foreign-device registration: Annex J.4, J.5.
"""

from __future__ import annotations

import ipaddress
from dataclasses import dataclass

from dsfd.config.loader import Problem, setting

__all__ = ["MAX_INSTANCE", "Bacnet", "BacnetForeignDevice", "host_port_problem"]

#: Highest device instance a device may have (4194303 means "not configured").
MAX_INSTANCE = 4194302


def host_port_problem(text: str) -> str:
    """Why ``text`` is not ``IPv4:port`` ('' if it is)."""
    host, sep, port = text.rpartition(":")
    if not sep:
        return "expected an IPv4 address and a UDP port, e.g. 198.51.100.7:47808"
    try:
        ipaddress.IPv4Address(host)
    except ValueError:
        return f"{host!r} is not an IPv4 address"
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        return f"{port!r} is not a UDP port 1..65535"
    return ""


@dataclass(frozen=True, kw_only=True)
class BacnetForeignDevice:
    """Registration with a BBMD, for a device on a subnet without one (Annex J.5)."""

    bbmd: str = setting(doc="The BBMD's IPv4 address and UDP port, e.g. 198.51.100.7:47808")
    ttl_s: int = setting(300, doc="Time-to-live of the registration; re-registered before it "
                         "ends", unit="s", ge=30, le=65535)

    def check(self) -> list[Problem]:
        why = host_port_problem(self.bbmd)
        return [Problem("bbmd", self.bbmd, why)] if why else []


@dataclass(frozen=True, kw_only=True)
class Bacnet:
    """The panel's BACnet/IP device: points for the BMS, commands through priority arrays."""

    device_instance: int = setting(doc="Device object instance, unique on the BACnet "
                                   "internetwork", ge=0, le=MAX_INSTANCE)
    device_name: str | None = setting(
        None, doc="Device object name, unique on the internetwork; null: dsfd-<panel id>")
    address: str = setting(
        doc="IPv4 address to bind, with the subnet's prefix length for its broadcasts "
        "(e.g. 192.0.2.10/24); it must be an address of this host")
    port: int = setting(47808, doc="UDP port (BACnet/IP's is 47808, 0xBAC0)", ge=1, le=65535)
    network_number: int | None = setting(
        None, doc="BACnet network number of the local network; null: unknown (no router "
        "here)", ge=1, le=65534)
    foreign_device: BacnetForeignDevice | None = setting(
        None, doc="Register as a foreign device with a BBMD (routed IP networks); null: none")
    writable: bool = setting(
        False, doc="false: every write is refused (write-access-denied); true: writes to the "
        "louver, regime, damper and objective objects become operator commands")
    hold_until_relinquished: bool = setting(
        False, doc="false: a BACnet hold lasts safety.manual_hold_min as other holds; true: "
        "until relinquished (at most 7 days, the longest operator hold)")
    vendor_identifier: int = setting(
        999, doc="Vendor-Identifier of the device object (ASHRAE assigns them; 999 is "
        "bacpypes3's sample identifier)", ge=0, le=65535)

    def check(self) -> list[Problem]:
        out: list[Problem] = []
        try:
            iface = ipaddress.IPv4Interface(self.address)
        except ValueError as exc:
            out.append(Problem("address", self.address, f"expected an IPv4 address with an "
                               f"optional /prefix, e.g. 192.0.2.10/24 ({exc})"))
        else:
            if iface.ip.is_unspecified or iface.ip.is_multicast:
                out.append(Problem("address", self.address, "must be one address of this "
                                   "host (the device binds only there), not 0.0.0.0 or a "
                                   "multicast group"))
        name = self.device_name
        if name is not None and not 1 <= len(name) <= 150:
            out.append(Problem("device_name", name, "1 to 150 characters"))
        return out

    def device_name_for(self, panel_id: str) -> str:
        return self.device_name if self.device_name is not None else f"dsfd-{panel_id}"

    def bind_address(self) -> str:
        """The address as bacpypes3 takes it: ``a.b.c.d/prefix:port``."""
        iface = ipaddress.IPv4Interface(self.address)
        return f"{iface.ip}/{iface.network.prefixlen}:{self.port}"
