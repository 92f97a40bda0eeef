"""A third-party BACnet client in a process of its own: bacpypes3's client side, driven by
JSON lines on stdin, answering with JSON lines on stdout (the transcript of the exchange).
The BACnet tests and ``dsfd bench bacnet`` run it against the daemon's device:

    python -m dsfd.bench.bacnet_client --bind 127.0.0.1:47810 --device 127.0.0.1:47809

Requests (one JSON object per line), each answered by one line with the same ``id``:

* ``{"op": "who-is"}`` — unicast Who-Is to the device; the I-Am answers;
* ``{"op": "who-has", "name": "louver angle"}`` — Who-Has by object name; the I-Haves;
* ``{"op": "rpm", "objects": [["analog-input,1", ["present-value", "units"]], ...]}`` —
  one ReadPropertyMultiple; the values;
* ``{"op": "read", "object": "analog-value,1", "property": "priority-array"}``;
* ``{"op": "write", "object": ..., "value": ..., "type": "real"|"unsigned"|"null"|"string"
  |"enumerated", "priority": 8}`` — one WriteProperty of the present value, the value
  encoded as ``type`` says (a wrong type on purpose, too); ``ack`` or the error;
* ``{"op": "cov", "object": ..., "process": 7, "confirmed": false, "lifetime": 600}`` —
  SubscribeCOV; every notification is then printed as ``{"cov": ...}`` with the time it
  arrived (``received_s``, the host's wall clock);
* ``{"op": "cov-property", "object": ..., "property": "present-value", "increment": 0.5,
  "process": 9}`` — SubscribeCOVProperty (bacpypes3 has no client helper for it: the
  request is sent as it is and the notifications for that process are printed as above);
* ``{"op": "rpm-bench", "count": 500, "objects": [...]}`` — that many
  ReadPropertyMultiple requests one after the other; the elapsed time;
* ``{"op": "quit"}``.

Notification lines carry ``received_s`` (wall clock) and ``received_mono_s`` (the host's
monotonic clock, CLOCK_MONOTONIC, the same in every process of the machine).

Only bacpypes3's client API is used (``Application.from_args``, ``who_is``, ``who_has``,
``read_property``, ``read_property_multiple``, ``change_of_value``, ``request`` with its
request classes), as a building management system built on it would.
"""

from __future__ import annotations

import asyncio
import json
import sys
import time
from typing import Any

from bacpypes3.apdu import (
    ErrorRejectAbortNack,
    SimpleAckPDU,
    SubscribeCOVPropertyRequest,
    WritePropertyRequest,
)
from bacpypes3.app import Application
from bacpypes3.argparse import SimpleArgumentParser
from bacpypes3.basetypes import PropertyIdentifier
from bacpypes3.constructeddata import Any as AnyValue
from bacpypes3.pdu import Address
from bacpypes3.primitivedata import (
    Boolean,
    CharacterString,
    Enumerated,
    Null,
    ObjectIdentifier,
    Real,
    Unsigned,
)
from bacpypes3.vendor import get_vendor_info

__all__ = ["Client", "ClientApplication", "main", "plain"]


def plain(value: Any) -> Any:
    """A bacpypes3 value as JSON."""
    if isinstance(value, ErrorRejectAbortNack):
        return {"error": type(value).__name__, **_error_fields(value)}
    if isinstance(value, Boolean):
        return bool(value)
    if isinstance(value, bool | int | float | str) or value is None:
        if isinstance(value, Enumerated):
            return str(value.attr) if hasattr(value, "attr") else int(value)
        return value
    if isinstance(value, ObjectIdentifier):
        return f"{value[0].attr},{value[1]}"
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if hasattr(value, "_choice"):  # PriorityValue and other choices
        choice = value._choice
        return None if choice == "null" else plain(getattr(value, choice))
    return str(value)


def _error_fields(pdu: Any) -> dict[str, Any]:
    out = {}
    for name in ("errorClass", "errorCode", "apduAbortRejectReason"):
        v = getattr(pdu, name, None)
        if v is not None:
            out[name] = str(v.attr) if hasattr(v, "attr") else v
    return out


_TYPES = {"real": Real, "unsigned": Unsigned, "string": CharacterString,
          "enumerated": Enumerated}


class Client:
    def __init__(self, app: Application, device: Address) -> None:
        self.app = app
        self.device = device
        self.subscriptions: list[asyncio.Task[None]] = []

    async def handle(self, req: dict[str, Any]) -> dict[str, Any]:
        op = req["op"]
        if op == "who-is":
            i_ams = await self.app.who_is(address=self.device, timeout=3)
            return {"i_am": [{"device": plain(i.iAmDeviceIdentifier),
                              "vendor": int(i.vendorID), "source": str(i.pduSource)}
                             for i in i_ams]}
        if op == "who-has":
            i_haves = await self.app.who_has(object_name=req["name"], address=self.device,
                                             timeout=3)
            return {"i_have": [{"device": plain(i.deviceIdentifier),
                                "object": plain(i.objectIdentifier),
                                "name": str(i.objectName)} for i in i_haves]}
        if op == "rpm":
            args: list[Any] = []
            for obj, props in req["objects"]:
                args += [obj, props]
            result = await self.app.read_property_multiple(self.device, args)
            if isinstance(result, ErrorRejectAbortNack):
                return {"values": plain(result)}
            return {"values": [[plain(o), str(p.attr) if hasattr(p, "attr") else str(p),
                                i, plain(v)] for o, p, i, v in result]}
        if op == "read":
            value = await self.app.read_property(self.device, req["object"], req["property"])
            return {"value": plain(value)}
        if op == "write":
            return {"answer": await self._write(req)}
        if op == "cov":
            self.subscriptions.append(asyncio.create_task(self._cov(req)))
            await asyncio.sleep(0.2)
            return {"subscribed": req["object"]}
        if op == "rpm-bench":
            args = [x for obj, props in req["objects"] for x in (obj, props)]
            start = time.monotonic()
            for _ in range(int(req["count"])):
                result = await self.app.read_property_multiple(self.device, list(args))
                if isinstance(result, ErrorRejectAbortNack):
                    return {"values": plain(result)}
            return {"count": int(req["count"]), "elapsed_s": time.monotonic() - start}
        if op == "cov-property":
            return {"answer": await self._cov_property(req)}
        raise ValueError(f"unknown op {op!r}")

    async def _write(self, req: dict[str, Any]) -> Any:
        kind = req.get("type", "real")
        value = Null(()) if kind == "null" else _TYPES[kind](req["value"])
        objid = ObjectIdentifier(req["object"])
        wp = WritePropertyRequest(objectIdentifier=objid, propertyIdentifier="present-value",
                                  propertyValue=AnyValue(value), destination=self.device)
        if req.get("priority") is not None:
            wp.priority = int(req["priority"])
        try:
            response = await self.app.request(wp)
        except ErrorRejectAbortNack as err:
            return plain(err)
        return "ack" if response is not None else None

    async def _cov_property(self, req: dict[str, Any]) -> Any:
        process = int(req.get("process", 9))
        request = SubscribeCOVPropertyRequest(
            subscriberProcessIdentifier=process,
            monitoredObjectIdentifier=ObjectIdentifier(req["object"]),
            issueConfirmedNotifications=bool(req.get("confirmed", False)),
            lifetime=int(req.get("lifetime", 600)), destination=self.device)
        reference = request._elements["monitoredPropertyIdentifier"]  # the context-tagged
        request.monitoredPropertyIdentifier = reference(
            propertyIdentifier=PropertyIdentifier(req.get("property", "present-value")))
        if req.get("increment") is not None:
            request.covIncrement = float(req["increment"])
        self.app.property_processes[process] = req["object"]
        try:  # bacpypes3 0.0.110's client does not resolve an Error to this service
            await asyncio.wait_for(self.app.request(request), 5.0)
        except ErrorRejectAbortNack as err:
            return plain(err)
        except TimeoutError:
            return {"error": "no answer the client library decodes"}
        return "ack"

    async def _cov(self, req: dict[str, Any]) -> None:
        objid = ObjectIdentifier(req["object"])
        async with self.app.change_of_value(
                self.device, objid, int(req.get("process", 1)),
                bool(req.get("confirmed", False)), int(req.get("lifetime", 600))) as scm:
            while True:
                prop, value = await scm.get_value()
                emit({"cov": req["object"], "property": str(prop), "value": plain(value),
                      "received_s": time.time(),
                      "received_mono_s": time.monotonic()})


class ClientApplication(Application):
    """Prints the notifications of SubscribeCOVProperty subscriptions (process numbers in
    :attr:`property_processes`); the rest as bacpypes3 does."""

    property_processes: dict[int, str]

    def _printed(self, apdu: Any) -> bool:
        name = self.property_processes.get(int(apdu.subscriberProcessIdentifier))
        if name is None:
            return False
        object_class = get_vendor_info(0).get_object_class(
            apdu.monitoredObjectIdentifier[0])
        for pv in apdu.listOfValues:
            prop = pv.propertyIdentifier
            value = pv.value.cast_out(object_class.get_property_type(prop))
            emit({"cov": name, "property": str(prop), "value": plain(value),
                  "received_s": time.time(), "received_mono_s": time.monotonic(),
                  "process": int(apdu.subscriberProcessIdentifier)})
        return True

    async def do_UnconfirmedCOVNotificationRequest(self, apdu: Any) -> None:
        if not self._printed(apdu):
            await super().do_UnconfirmedCOVNotificationRequest(apdu)

    async def do_ConfirmedCOVNotificationRequest(self, apdu: Any) -> None:
        if self._printed(apdu):
            await self.response(SimpleAckPDU(context=apdu))
        else:
            await super().do_ConfirmedCOVNotificationRequest(apdu)


def emit(line: dict[str, Any]) -> None:
    sys.stdout.write(json.dumps(line) + "\n")
    sys.stdout.flush()


async def main() -> None:
    parser = SimpleArgumentParser()
    parser.add_argument("--bind", required=True, help="this client's address:port")
    parser.add_argument("--device", required=True, help="the device's address:port")
    args = parser.parse_args()
    args.address = args.bind
    args.instance = 4190001
    args.name = "test-bms-client"
    app = ClientApplication.from_args(args)
    app.property_processes = {}
    client = Client(app, Address(args.device))
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    emit({"ready": True})
    try:
        while line := await reader.readline():
            req = json.loads(line)
            if req["op"] == "quit":
                break
            try:
                answer = await client.handle(req)
            except Exception as exc:  # the transcript shows it; the client goes on
                answer = {"exception": f"{type(exc).__name__}: {exc}"}
            emit({"id": req.get("id"), "op": req["op"], **answer})
    finally:
        for task in client.subscriptions:
            task.cancel()
        app.close()


if __name__ == "__main__":
    asyncio.run(main())
