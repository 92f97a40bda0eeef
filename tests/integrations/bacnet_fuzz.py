"""Malformed BACnet/IP datagrams for the robustness test: built byte by byte (ASHRAE 135-2020
Annex J.2 for the BVLL header, clause 6.2 for the NPDU, clause 20.1 for the APDU headers and
20.2 for the tags), from a seeded generator.

Kinds, drawn in turn: random bytes; a BVLL header whose length disagrees with the datagram;
NPDUs with random control bits and network-layer messages; every APDU type with random
contents; confirmed and unconfirmed requests of unknown services; well-formed requests of the
services the device has (ReadProperty, ReadPropertyMultiple, WriteProperty, SubscribeCOV,
SubscribeCOVProperty, Who-Is, Who-Has) truncated, extended or with flipped bytes; segmented
requests; tags that claim huge lengths.
"""

from __future__ import annotations

import random
import struct

__all__ = ["KINDS", "datagrams"]

#: Confirmed services the device implements (clause 21, BACnetConfirmedServiceChoice).
SUBSCRIBE_COV, READ_PROPERTY, READ_PROPERTY_MULTIPLE, WRITE_PROPERTY = 5, 12, 14, 15
SUBSCRIBE_COV_PROPERTY = 28
#: Unconfirmed ones (BACnetUnconfirmedServiceChoice).
WHO_HAS, WHO_IS = 7, 8


def bvll(npdu_apdu: bytes, *, function: int = 0x0A, length: int | None = None) -> bytes:
    """Original-Unicast-NPDU (0x0A) around an NPDU; ``length`` overrides the true one."""
    size = len(npdu_apdu) + 4 if length is None else length
    return bytes([0x81, function]) + struct.pack(">H", size & 0xFFFF) + npdu_apdu


def npdu(apdu: bytes, *, expecting_reply: bool = True) -> bytes:
    return bytes([0x01, 0x04 if expecting_reply else 0x00]) + apdu


def object_id(kind: int, instance: int) -> bytes:
    return struct.pack(">I", (kind << 22) | instance)


def confirmed(service: int, params: bytes, invoke_id: int, *, flags: int = 0) -> bytes:
    return bytes([0x00 | flags, 0x05, invoke_id & 0xFF, service]) + params


def unconfirmed(service: int, params: bytes) -> bytes:
    return bytes([0x10, service]) + params


def _valid_requests(rng: random.Random) -> list[bytes]:
    """APDUs of the services the device has, well formed."""
    kind = rng.choice([0, 2, 5, 19, 40, 8])
    obj = object_id(kind, 41001 if kind == 8 and rng.random() < 0.5 else rng.randrange(0, 20))
    prop = bytes([0x19, rng.choice([85, 77, 87, 111, 0, 8, 255])])
    real = b"\x44" + struct.pack(">f", rng.uniform(-1e6, 1e6))
    return [
        confirmed(READ_PROPERTY, b"\x0c" + obj + prop, rng.randrange(256)),
        confirmed(READ_PROPERTY_MULTIPLE, b"\x0c" + obj + b"\x1e\x09\x55\x09\x08\x1f",
                  rng.randrange(256)),
        confirmed(WRITE_PROPERTY, b"\x0c" + obj + prop + b"\x3e" + real + b"\x3f\x49\x08",
                  rng.randrange(256)),
        confirmed(SUBSCRIBE_COV, b"\x09\x01\x1c" + obj + b"\x29\x00\x39\x3c",
                  rng.randrange(256)),
        confirmed(SUBSCRIBE_COV_PROPERTY, b"\x09\x02\x1c" + obj + b"\x29\x00\x39\x3c\x4e\x09"
                  + bytes([rng.choice([85, 77, 111, 87, 28, 36, 103, 117, 76, 104])])
                  + b"\x4f", rng.randrange(256)),
        unconfirmed(WHO_IS, b"\x09\x00\x1b\x3f\xff\xfe"),
        unconfirmed(WHO_HAS, b"\x3d\x06\x00louver"),
    ]


def _mutate(rng: random.Random, data: bytes) -> bytes:
    b = bytearray(data)
    how = rng.randrange(4)
    if how == 0 and b:
        del b[rng.randrange(len(b)):]  # truncated
    elif how == 1:
        b += rng.randbytes(rng.randrange(1, 64))  # trailing garbage
    elif how == 2 and b:
        for _ in range(rng.randrange(1, 4)):
            b[rng.randrange(len(b))] = rng.randrange(256)  # flipped bytes
    else:
        b[4:4] = bytes([0x0E, 0xFE]) + struct.pack(">I", rng.randrange(2 ** 32))  # huge tag
    return bytes(b)


def _random_bytes(rng: random.Random) -> bytes:
    return rng.randbytes(rng.randrange(0, 1500))


def _wrong_length(rng: random.Random) -> bytes:
    body = npdu(rng.choice(_valid_requests(rng)))
    return bvll(body, length=rng.choice([0, 3, 4, len(body) + 5, 0xFFFF, rng.randrange(2**16)]),
                function=rng.choice([0x0A, 0x0B, 0x04, 0x09, 0x0C, rng.randrange(256)]))


def _network_layer(rng: random.Random) -> bytes:
    control = rng.randrange(256)
    return bvll(bytes([rng.choice([0x01, 0x00, 0x02]), control]) + rng.randbytes(
        rng.randrange(0, 40)))


def _any_apdu_type(rng: random.Random) -> bytes:
    first = (rng.randrange(16) << 4) | rng.randrange(16)
    return bvll(npdu(bytes([first]) + rng.randbytes(rng.randrange(0, 30))))


def _unknown_service(rng: random.Random) -> bytes:
    if rng.random() < 0.5:
        return bvll(npdu(confirmed(rng.randrange(34, 256), rng.randbytes(rng.randrange(20)),
                                   rng.randrange(256))))
    return bvll(npdu(unconfirmed(rng.randrange(13, 256), rng.randbytes(rng.randrange(20))),
                     expecting_reply=False))


def _mutated_request(rng: random.Random) -> bytes:
    return bvll(npdu(_mutate(rng, rng.choice(_valid_requests(rng)))))


def _segmented(rng: random.Random) -> bytes:
    head = bytes([0x0C | rng.choice([0, 2]), 0x75, rng.randrange(256), rng.randrange(256),
                  rng.randrange(1, 127), rng.randrange(256)])
    return bvll(npdu(head + rng.randbytes(rng.randrange(0, 200))))


KINDS = (_random_bytes, _wrong_length, _network_layer, _any_apdu_type, _unknown_service,
         _mutated_request, _segmented)


def datagrams(count: int, *, seed: int) -> list[bytes]:
    """``count`` malformed datagrams, the kinds in turn."""
    rng = random.Random(seed)
    return [KINDS[i % len(KINDS)](rng) for i in range(count)]
