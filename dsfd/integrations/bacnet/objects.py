"""bacpypes3 objects and application of the panel's device (imported only with the extra).

bacpypes3 0.0.110's local objects (``bacpypes3.local``) keep the properties, answer
ReadProperty/ReadPropertyMultiple and run COV detection when a property is set
(``local.cov``: ``COVIncrementCriteria`` for analog and multi-state objects,
``GenericCriteria`` for the others). Two things are changed here:

* Every object refuses a write of its own (write-access-denied): a write reaches a point only
  through :meth:`PanelApplication.do_WritePropertyRequest`, which knows the writer's address
  and hands the write to the device (:mod:`dsfd.integrations.bacnet.device`). A
  WritePropertyMultiple therefore changes nothing and is answered write-access-denied.
* The commandable objects keep bacpypes3's priority array, relinquish default and current
  command priority, but their present value is the position in force at the panel's last
  cycle (set by the device from the database), not the array's winner: a write is a request
  that the daemon applies at its next cycle, and the point shows what the panel does.

A value of the wrong datatype in a WriteProperty is answered with the error
invalid-data-type (clause 15.9.1.3.1) instead of bacpypes3's reject.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from bacpypes3.apdu import SimpleAckPDU, WritePropertyRequest
from bacpypes3.app import Application
from bacpypes3.basetypes import PropertyIdentifier
from bacpypes3.constructeddata import Array
from bacpypes3.errors import (
    ExecutionError,
    MissingRequiredParameter,
    ObjectError,
    PropertyError,
    RejectException,
)
from bacpypes3.local.analog import AnalogInputObject, AnalogValueObject
from bacpypes3.local.binary import BinaryValueObject
from bacpypes3.local.cmd import Commandable
from bacpypes3.local.cov import GenericCriteria
from bacpypes3.local.multistate import MultiStateValueObject
from bacpypes3.local.object import Object as LocalObject
from bacpypes3.object import CharacterStringValueObject
from bacpypes3.primitivedata import Null, Unsigned

from dsfd.integrations.bacnet.covproperty import MAX_SUBSCRIPTIONS, CovPropertyServices

__all__ = ["CommandableAV", "CommandableMSV", "PanelApplication", "ReadOnlyAI", "ReadOnlyAV",
           "ReadOnlyBV", "ReadOnlyCSV", "ReadOnlyMSV", "WriteHandler", "refusal",
           "set_present_value", "set_slot"]

#: The device's write handler: (object, value or None for NULL, priority, source) → None,
#: or raises ExecutionError with the answer.
WriteHandler = Callable[[Any, Any, int | None, str], Awaitable[None]]


class _NoDirectWrite:
    """Writes go through :class:`PanelApplication`, never to the object itself."""

    async def write_property(self, attr: Any, value: Any, index: int | None = None,
                             priority: int | None = None) -> None:
        raise PropertyError("writeAccessDenied")


class ReadOnlyAI(_NoDirectWrite, AnalogInputObject):
    pass


class ReadOnlyAV(_NoDirectWrite, AnalogValueObject):
    pass


class ReadOnlyMSV(_NoDirectWrite, MultiStateValueObject):
    # bacpypes3 0.0.110 gives multi-state objects the COV-increment criteria, which need a
    # covIncrement they do not have (the first subscription fails); clause 13.1.2: any
    # change of the present value or the status flags is notified.
    _cov_criteria = GenericCriteria


class ReadOnlyBV(_NoDirectWrite, BinaryValueObject):
    pass


class ReadOnlyCSV(_NoDirectWrite, LocalObject, CharacterStringValueObject):
    _cov_criteria = GenericCriteria


class _InForce(Commandable):
    """A commandable object whose present value is set from outside (the position in
    force); the priority array only decides the current command priority."""

    def recalculating(self) -> None:
        from bacpypes3.basetypes import OptionalUnsigned

        for i, pv in enumerate(self.priorityArray):
            if pv.null is None:
                object.__setattr__(self, "_top_priority", i + 1)
                LocalObject.__setattr__(self, "currentCommandPriority",
                                        OptionalUnsigned(unsigned=i + 1))
                return
        object.__setattr__(self, "_top_priority", None)
        LocalObject.__setattr__(self, "currentCommandPriority", OptionalUnsigned(null=()))


class CommandableAV(_NoDirectWrite, _InForce, AnalogValueObject):
    _required = ("priorityArray",)


class CommandableMSV(_NoDirectWrite, _InForce, MultiStateValueObject):
    _required = ("priorityArray",)
    _cov_criteria = GenericCriteria  # as ReadOnlyMSV


def set_present_value(obj: Any, value: Any) -> None:
    """Set a present value so that COV detection sees it (past a commandable object's
    priority-array redirection)."""
    LocalObject.__setattr__(obj, "presentValue", value)


def set_slot(obj: Any, priority: int, value: Any) -> None:
    """Set (a value) or clear (None) one slot of a commandable object's priority array."""
    from bacpypes3.basetypes import PriorityValue

    if value is None:
        obj.priorityArray[priority - 1] = PriorityValue(null=())
        return
    kind = obj._elements["presentValue"]  # Real or Unsigned
    obj.priorityArray[priority - 1] = PriorityValue(kind(kind.cast(value)))


class PanelApplication(CovPropertyServices, Application):
    """bacpypes3's application (Who-Is, Who-Has, ReadProperty(Multiple), SubscribeCOV) with
    SubscribeCOVProperty added, WriteProperty handed to the panel device and
    DeviceCommunicationControl refused."""

    write_handler: WriteHandler | None = None

    async def do_SubscribeCOVRequest(self, apdu: Any) -> None:
        """bacpypes3's SubscribeCOV, with its parameters checked first (clause 13.14.1.1):
        a lifetime without Issue Confirmed Notifications is rejected, Issue Confirmed
        Notifications without a lifetime means an indefinite one (bacpypes3 fails on it),
        and at most :data:`~dsfd.integrations.bacnet.covproperty.MAX_SUBSCRIPTIONS`
        subscriptions are kept."""
        confirmed, lifetime = apdu.issueConfirmedNotifications, apdu.lifetime
        if confirmed is None and lifetime is not None:
            raise MissingRequiredParameter("issueConfirmedNotifications goes with lifetime")
        if confirmed is not None:
            if lifetime is None:
                apdu.lifetime = 0
            if self._cov_subscriptions() >= MAX_SUBSCRIPTIONS and not self._subscribed(apdu):
                raise ExecutionError(errorClass="services", errorCode="covSubscriptionFailed")
        await super().do_SubscribeCOVRequest(apdu)

    def _cov_subscriptions(self) -> int:
        return sum(len(d.cov_subscriptions) for d in self._cov_detections.values())

    def _subscribed(self, apdu: Any) -> bool:
        detection = self._cov_detections.get(apdu.monitoredObjectIdentifier)
        return detection is not None and any(
            c.client_addr == apdu.pduSource and c.proc_id == apdu.subscriberProcessIdentifier
            for c in detection.cov_subscriptions)

    def cov_confirmation(self, cov: Any, future: Any) -> None:
        """The answer to a confirmed COV notification. bacpypes3 re-raises an error, a reject
        or a time-out here, in a loop callback; a subscriber that does not acknowledge only
        misses that notification (its subscription ends with its lifetime)."""
        if not future.cancelled():
            future.exception()

    async def do_DeviceCommunicationControlRequest(self, apdu: Any) -> None:
        """Refused (services / service-request-denied): without a password (bacpypes3 checks
        none unless one is set) anyone on the network could silence the device."""
        raise ExecutionError(errorClass="services", errorCode="serviceRequestDenied")

    async def do_WritePropertyRequest(self, apdu: WritePropertyRequest) -> None:
        obj = self.get_object_id(apdu.objectIdentifier)
        if not obj:
            raise ObjectError("unknownObject")
        property_type = obj.get_property_type(apdu.propertyIdentifier)
        if not property_type:
            raise PropertyError("unknownProperty")
        if issubclass(property_type, Array) and apdu.propertyArrayIndex is not None:
            property_type = Unsigned if apdu.propertyArrayIndex == 0 else \
                property_type._subtype
        priority = apdu.priority
        try:
            value = apdu.propertyValue.cast_out(property_type, null=True)
        except (RejectException, ValueError, TypeError, AttributeError, IndexError):
            # AttributeError: bacpypes3 reads past an empty value's tags
            raise PropertyError("invalidDataType") from None
        if isinstance(value, Null):
            value = None
        if apdu.propertyIdentifier != PropertyIdentifier.presentValue or self.write_handler is None:
            raise PropertyError("writeAccessDenied")
        await self.write_handler(obj, value, priority, str(apdu.pduSource))
        await self.response(SimpleAckPDU(context=apdu))


def refusal(error_code: str) -> ExecutionError:
    """The BACnet error of a refused write (class property; a database failure: class
    device, operational-problem)."""
    if error_code == "operationalProblem":
        return ExecutionError(errorClass="device", errorCode=error_code)
    return PropertyError(error_code)
