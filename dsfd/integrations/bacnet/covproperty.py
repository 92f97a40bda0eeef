"""SubscribeCOVProperty (ASHRAE 135-2020 clause 13.15), which bacpypes3 0.0.110 lacks.

A subscriber names an object, one of its properties and optionally a COV increment; it is
notified when the property changes — by at least the increment for a REAL (the request's,
else the object's ``covIncrement``), by any change otherwise — with the property's value and
the object's status flags (clause 13.15.1.1.6, 13.1.4), and once right after subscribing.
A request without ``issueConfirmedNotifications`` and ``lifetime`` cancels the subscription.
A lifetime of 0 is indefinite, as for SubscribeCOV.

Changes are observed through bacpypes3's per-property monitors of local objects (the hooks its
own COV detection uses), so the device's updates need nothing else. At most
:data:`MAX_SUBSCRIPTIONS` subscriptions are kept (the device's memory is the operator's, not
the network's): more are refused with services / cov-subscription-failed.
"""

from __future__ import annotations

import asyncio
import math
from dataclasses import dataclass, field
from typing import Any

from bacpypes3.apdu import (
    ConfirmedCOVNotificationRequest,
    SimpleAckPDU,
    SubscribeCOVPropertyRequest,
    UnconfirmedCOVNotificationRequest,
)
from bacpypes3.basetypes import PropertyValue
from bacpypes3.constructeddata import Any as AnyValue
from bacpypes3.errors import ExecutionError, ObjectError, PropertyError

__all__ = ["MAX_SUBSCRIPTIONS", "CovPropertyServices"]

#: Subscriptions kept at most, of each kind (SubscribeCOV, SubscribeCOVProperty).
MAX_SUBSCRIPTIONS = 256


@dataclass(eq=False)
class _Subscription:
    client: Any
    process: int
    obj: Any
    attr: str
    confirmed: bool
    increment: float | None
    expires_s: float | None  # on the loop's clock; None: indefinite
    last: Any = None
    pending: bool = False
    monitor: Any = field(default=None, repr=False)

    def key(self) -> tuple[str, int, Any, str]:
        return (str(self.client), self.process, self.obj.objectIdentifier, self.attr)


class CovPropertyServices:
    """Mixin of the device's application: SubscribeCOVProperty and its notifications."""

    _property_subscriptions: dict[tuple[str, int, Any, str], _Subscription]

    async def do_SubscribeCOVPropertyRequest(self, apdu: SubscribeCOVPropertyRequest
                                             ) -> None:
        subs = self.__dict__.setdefault("_property_subscriptions", {})
        obj = self.get_object_id(apdu.monitoredObjectIdentifier)  # type: ignore[attr-defined]
        if not obj:
            raise ObjectError("unknownObject")
        ref = apdu.monitoredPropertyIdentifier
        if ref.propertyArrayIndex is not None:
            raise PropertyError("propertyIsNotAnArray")
        attr = ref.propertyIdentifier.attr
        if attr not in obj._elements or not obj.get_property_type(ref.propertyIdentifier) \
                or getattr(obj, attr) is None:  # a property the object does not have
            raise PropertyError("unknownProperty")
        key = (str(apdu.pduSource), int(apdu.subscriberProcessIdentifier),
               obj.objectIdentifier, attr)
        if apdu.issueConfirmedNotifications is None and apdu.lifetime is None:
            old = subs.pop(key, None)
            if old is not None:
                obj._property_monitors[attr].remove(old.monitor)
            await self.response(SimpleAckPDU(context=apdu))  # type: ignore[attr-defined]
            return
        if key not in subs and len(subs) >= MAX_SUBSCRIPTIONS:
            raise ExecutionError(errorClass="services", errorCode="covSubscriptionFailed")
        loop = asyncio.get_running_loop()
        lifetime = int(apdu.lifetime or 0)
        increment = apdu.covIncrement
        if increment is None:
            increment = getattr(obj, "covIncrement", None) if attr == "presentValue" else None
        sub = subs.get(key)
        if sub is None:
            sub = _Subscription(apdu.pduSource, key[1], obj, attr, False, None, None)
            sub.monitor = lambda old, new, s=sub: self._property_changed(s, new)
            obj._property_monitors[attr].append(sub.monitor)
            subs[key] = sub
        sub.confirmed = bool(apdu.issueConfirmedNotifications)
        sub.increment = None if increment is None else float(increment)
        sub.expires_s = loop.time() + lifetime if lifetime else None
        await self.response(SimpleAckPDU(context=apdu))  # type: ignore[attr-defined]
        loop.call_soon(self._notify_property, sub)

    def _property_changed(self, sub: _Subscription, new: Any) -> None:
        if sub.pending or not _changed(sub.last, new, sub.increment):
            return
        sub.pending = True
        asyncio.get_running_loop().call_soon(self._notify_property, sub)

    def _notify_property(self, sub: _Subscription) -> None:
        sub.pending = False
        subs = self._property_subscriptions
        loop = asyncio.get_running_loop()
        if sub.expires_s is not None and loop.time() >= sub.expires_s:
            if subs.pop(sub.key(), None) is not None:
                sub.obj._property_monitors[sub.attr].remove(sub.monitor)
            return
        value = getattr(sub.obj, sub.attr)
        if value is None:
            return
        values = [PropertyValue(propertyIdentifier=sub.attr, value=AnyValue(value))]
        if sub.attr != "statusFlags" and "statusFlags" in sub.obj._elements:
            values.append(PropertyValue(propertyIdentifier="statusFlags",
                                        value=AnyValue(sub.obj.statusFlags)))
        request = (ConfirmedCOVNotificationRequest() if sub.confirmed
                   else UnconfirmedCOVNotificationRequest())
        request.pduDestination = sub.client
        request.subscriberProcessIdentifier = sub.process
        request.initiatingDeviceIdentifier = self.device_object.objectIdentifier  # type: ignore
        request.monitoredObjectIdentifier = sub.obj.objectIdentifier
        request.timeRemaining = 0 if sub.expires_s is None else max(
            1, int(sub.expires_s - loop.time()))
        request.listOfValues = values
        sub.last = value
        sent = self.request(request)  # type: ignore[attr-defined]
        sent.add_done_callback(_answered)


def _answered(future: asyncio.Future[Any]) -> None:
    """A confirmed notification's answer: an error or no answer only ends that one."""
    if not future.cancelled():
        future.exception()


def _changed(last: Any, new: Any, increment: float | None) -> bool:
    if last is None:
        return True
    if increment is not None and isinstance(new, float) and isinstance(last, float):
        if math.isnan(new) or math.isnan(last):
            return math.isnan(new) != math.isnan(last)
        return abs(new - last) >= increment
    return bool(new != last)
