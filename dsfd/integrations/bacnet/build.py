"""The device's bacpypes3 objects: built from the point table, updated from a cycle.

Imported only inside the device's thread (bacpypes3 is the optional extra; its local objects
must be created in a running asyncio loop). Properties per object type follow ASHRAE
135-2020 clause 12 (required ones: present value, status flags, event state, out of service,
units for analog objects, number of states for multi-state ones, priority array and
relinquish default for commandable ones); the device object's are bacpypes3's
``local.device.DeviceObject`` with the panel's identity.
"""

from __future__ import annotations

from typing import Any

from bacpypes3.basetypes import HostNPort, IPMode
from bacpypes3.local.device import DeviceObject
from bacpypes3.local.networkport import NetworkPortObject

from dsfd.config import PanelConfig
from dsfd.integrations.bacnet.objects import (
    CommandableAV,
    CommandableMSV,
    PanelApplication,
    ReadOnlyAI,
    ReadOnlyBV,
    ReadOnlyCSV,
    ReadOnlyMSV,
    set_present_value,
    set_slot,
)
from dsfd.integrations.bacnet.points import (
    OBJECTIVE_STATES,
    Point,
    PointValue,
    regime_states,
)

__all__ = ["build_application", "clear_slots", "update_point"]

_TYPES = {"ai": "analog-input", "av": "analog-value", "msv": "multi-state-value",
          "bv": "binary-value", "csv": "characterstring-value"}


def _device(cfg: PanelConfig, *, version: str) -> DeviceObject:
    s = cfg.bacnet
    assert s is not None
    return DeviceObject(
        objectIdentifier=("device", s.device_instance),
        objectName=s.device_name_for(cfg.panel.id),
        vendorIdentifier=s.vendor_identifier, vendorName="dsfd",
        modelName="dsfd double-skin facade panel controller",
        firmwareRevision=version, applicationSoftwareVersion=version,
        description=f"double-skin facade panel {cfg.panel.id}")


def _network_port(cfg: PanelConfig) -> NetworkPortObject:
    s = cfg.bacnet
    assert s is not None
    extra: dict[str, Any] = {}
    if s.network_number is not None:
        extra = {"networkNumber": s.network_number, "networkNumberQuality": "configured"}
    port = NetworkPortObject(s.bind_address(), objectIdentifier=("network-port", 1),
                             objectName="NetworkPort-1", **extra)
    if s.foreign_device is not None:
        port.bacnetIPMode = IPMode.foreign
        port.fdBBMDAddress = HostNPort(s.foreign_device.bbmd)
        port.fdSubscriptionLifetime = s.foreign_device.ttl_s
    return port


def _point_object(p: Point) -> Any:
    common: dict[str, Any] = {
        "objectIdentifier": (_TYPES[p.kind], p.instance), "objectName": p.name,
        "statusFlags": [0, 1, 0, 0], "eventState": "normal", "outOfService": False,
        "reliability": "communicationFailure",  # until the first cycle is shown
    }
    if p.kind in ("ai", "av"):
        common.update(units=p.units, covIncrement=p.cov_increment, presentValue=0.0)
        if p.kind == "ai":
            return ReadOnlyAI(**common)
        return CommandableAV(**common, relinquishDefault=0.0)
    if p.kind == "msv":
        states = regime_states() if p.key == "regime" else list(OBJECTIVE_STATES)
        common.update(numberOfStates=len(states), stateText=states, presentValue=1)
        if p.commandable:
            return CommandableMSV(**common, relinquishDefault=1)
        return ReadOnlyMSV(**common)
    if p.kind == "bv":
        return ReadOnlyBV(**common, presentValue="inactive", inactiveText="no fault",
                          activeText="fault")
    return ReadOnlyCSV(**common, presentValue="")


def build_application(cfg: PanelConfig, points: tuple[Point, ...], *, version: str
                      ) -> tuple[PanelApplication, dict[str, Any]]:
    """The application (bound to ``bacnet.address``:``port``) and its point objects."""
    objects = {p.key: _point_object(p) for p in points}
    app = PanelApplication.from_object_list(
        [_device(cfg, version=version), _network_port(cfg), *objects.values()])
    return app, objects


def update_point(obj: Any, p: Point, pv: PointValue, *, overridden: bool,
                 controller: bool) -> None:
    """Show one cycle's value and status of a point (``controller``: the cycle's command
    is the controller's own, which becomes the relinquish default)."""
    if pv.value is not None:
        value: Any = pv.value
        if p.kind == "bv":
            value = "active" if pv.value else "inactive"
        if p.commandable:
            set_present_value(obj, value)
            if controller:
                obj.relinquishDefault = value
        else:
            obj.presentValue = value
    obj.reliability = "unreliableOther" if pv.fault else "noFaultDetected"
    obj.statusFlags = [0, int(pv.fault), int(overridden and p.commandable), 0]


def clear_slots(objects: dict[str, Any]) -> None:
    """Relinquish every priority of the commandable objects."""
    for obj in objects.values():
        if not hasattr(obj, "priorityArray"):
            continue
        for i, slot in enumerate(obj.priorityArray):
            if slot.null is None:
                set_slot(obj, i + 1, None)
