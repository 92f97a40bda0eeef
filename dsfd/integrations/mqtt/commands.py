"""Commands that arrive on ``<base>/cmd/...``: MQTT payloads turned into operator requests.

Pure (no I/O): :func:`request_of` maps a command topic and its payload to the request mapping
of :func:`dsfd.daemon.commands.validate_command`, the one validation of every command
source, which the receiver (:mod:`dsfd.integrations.mqtt.receiver`) applies next; the request
then goes into the daemon's ``commands`` table with source ``mqtt``, exactly as ``dsfd
override``/``resume``/``mode`` put theirs. A payload that is not a command raises
:class:`~dsfd.daemon.commands.CommandError` naming what is wrong; :func:`error_message` is the
answer published on ``<base>/error``.

==================  ===========================================================================
subtopic            payload
==================  ===========================================================================
``override``        a JSON object with the fields of ``dsfd override``: ``hold`` (``"2h"``,
                    ``"90min"`` or minutes), ``louver_deg``, ``regime``, ``or_pct``; ``{}``
                    holds where the panel is for ``safety.manual_hold_min``
``regime``          the regime select's option as Home Assistant sends it (``"7: supply
                    out→EB→IT→room"``) or the number alone (``7``): a hold in that regime
``louver_deg``      a number (Home Assistant's number entity sends ``36`` or ``-36``): a hold
                    with the louver there
``damper_pct``      a number: a hold with the dampers open that far (``or_pct``)
``resume``          ``resume`` (the button's ``payload_press``) or ``{}``
``mode``            ``heating``, ``cooling`` or ``auto`` (or ``{"mode": "cooling"}``)
``occupancy``       ``occupied until 18:00``, ``unoccupied until 2026-12-01T08:00`` or ``auto``
                    (or ``{"state": "occupied", "until": "18:00"}``): the occupancy override
                    of ``dsfd occupancy``
``ack``             the id of an open finding (``3``, or ``{"finding": 3}``): it closes until
                    new evidence opens a new one, as ``dsfd ack``
==================  ===========================================================================

Every hold from the single-value topics lasts ``safety.manual_hold_min`` (to the daily reset
at the latest), as ``dsfd override`` without ``--hold``; a JSON override may say ``hold``.
An empty payload is never a command (an empty retained message only clears a retained one).

Home Assistant's payloads (home-assistant.io/integrations/select.mqtt, number.mqtt,
button.mqtt): a select publishes the chosen option's text; a number publishes the value, as
an integer when it is whole; a button publishes ``payload_press``.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

from dsfd.config.panel import REGIME_NAMES
from dsfd.daemon.commands import CommandError, occupancy_request

__all__ = ["MAX_PAYLOAD_BYTES", "SHOWN_BYTES", "SUBTOPICS", "error_message", "request_of",
           "shown"]

#: A command payload longer than this is refused unread [bytes] (the longest sensible one,
#: a JSON override with every field, is about 80).
MAX_PAYLOAD_BYTES = 1024
#: How much of a refused payload the answer and the log show [bytes].
SHOWN_BYTES = 200
#: Command subtopics under ``<base>/cmd/``, as the discovery configs name them.
SUBTOPICS: tuple[str, ...] = ("override", "regime", "louver_deg", "damper_pct", "resume",
                              "mode", "occupancy", "ack")
_OPTION = re.compile(r"^\s*(\d{1,2})\s*(?::\s*(.*?))?\s*$", re.DOTALL)


def request_of(subtopic: str, payload: bytes) -> dict[str, Any]:
    """The request that ``payload`` on ``<base>/cmd/<subtopic>`` asks for.

    Raises :class:`CommandError` for an unknown subtopic or a payload that does not fit it;
    whether the request fits the panel is :func:`~dsfd.daemon.commands.validate_command`'s
    question.
    """
    if subtopic not in SUBTOPICS:
        raise CommandError("topic", f"cmd/{subtopic}",
                           f"unknown command; expected cmd/ followed by one of "
                           f"{', '.join(SUBTOPICS)}")
    if len(payload) > MAX_PAYLOAD_BYTES:
        raise CommandError("payload", f"{len(payload)} bytes",
                           f"longer than {MAX_PAYLOAD_BYTES} bytes: not read")
    try:
        text = payload.decode("utf-8").strip()
    except UnicodeDecodeError:
        raise CommandError("payload", shown(payload), "not UTF-8 text") from None
    if not text:
        raise CommandError("payload", "", "empty: no command")
    if subtopic == "override":
        return {"command": "override", **_object(text)}
    if subtopic == "resume":
        return {"command": "resume", **({} if text == "resume" else _object(text))}
    if subtopic == "mode":
        fields = _object(text) if text.startswith("{") else {"mode": text}
        return {"command": "mode", **fields}
    if subtopic == "occupancy":
        if text.startswith("{"):
            return {"command": "occupancy", **_object(text)}
        return occupancy_request(text)
    if subtopic == "ack":
        fields = _object(text) if text.startswith("{") else {"finding": _number("finding", text)}
        return {"command": "ack", **fields}
    if subtopic == "regime":
        return {"command": "override", "regime": _regime(text)}
    field = "louver_deg" if subtopic == "louver_deg" else "or_pct"
    return {"command": "override", field: _number(field, text)}


def _object(text: str) -> dict[str, Any]:
    """A JSON object's fields ("command" is the topic's to say, not the payload's)."""
    try:
        value = json.loads(text)
    except (ValueError, RecursionError):
        raise CommandError("payload", shown(text), "not JSON (expected an object such as "
                           '{"hold": "2h", "louver_deg": 36})') from None
    if not isinstance(value, dict):
        raise CommandError("payload", shown(text), "expected a JSON object of fields")
    if "command" in value:
        raise CommandError("command", value["command"], "the topic names the command; "
                           "leave the field out")
    return value


def _number(field: str, text: str) -> float | int:
    """A plain decimal number (JSON's grammar: no NaN, no hex, no words)."""
    try:
        value = json.loads(text, parse_constant=_no_constant)
    except (ValueError, RecursionError):
        value = None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise CommandError(field, shown(text), "expected a number")
    if isinstance(value, float) and not math.isfinite(value):
        raise CommandError(field, shown(text), "expected a finite number")
    return value


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number here")


def _regime(text: str) -> int | float:
    """The regime of a select option ``"N: name"`` (the name must be N's) or of ``N``."""
    m = _OPTION.match(text)
    if m is None:
        return _number("regime", text)  # 7.5, -1: validate_command names the range
    number, name = int(m.group(1)), m.group(2)
    if name is not None and name != REGIME_NAMES.get(number):
        raise CommandError("regime", shown(text), f"not a regime option (regime {number} is "
                           f"{number}: {REGIME_NAMES.get(number, 'unknown')!s})")
    return number


def shown(payload: bytes | str, *, size: int | None = None) -> str:
    """A payload as the answer and the log show it: text, cut to :data:`SHOWN_BYTES`, bytes
    that are not UTF-8 as ``\\xNN`` (``size``: the whole payload's length when ``payload``
    is its beginning)."""
    raw = payload.encode("utf-8", "surrogateescape") if isinstance(payload, str) else payload
    size = len(raw) if size is None else size
    text = raw[:SHOWN_BYTES].decode("utf-8", "backslashreplace")
    if size <= SHOWN_BYTES and len(text) <= SHOWN_BYTES:
        return text
    return f"{text[:SHOWN_BYTES]}… ({size} bytes)"


def error_message(topic: str, reason: str, payload: bytes, *, size: int | None = None,
                  command_id: int | None = None) -> dict[str, Any]:
    """The answer on ``<base>/error`` to a command that changed nothing (``size``: the whole
    payload's length when ``payload`` is its beginning)."""
    return {"topic": topic, "reason": reason, "payload": shown(payload, size=size),
            "payload_bytes": len(payload) if size is None else size,
            "command_id": command_id}
