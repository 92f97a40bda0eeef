"""Operator commands: one validation for every source (``dsfd override``/``resume``/``mode``,
MQTT's ``<base>/cmd/...`` and writes to the BACnet device's priority arrays). Pure: a panel
configuration and a request mapping in, a validated :class:`OperatorCommand` or a
:class:`CommandError` naming the field and the bad value out.

A request is a mapping of fields (JSON-ready, as stored in the ``commands`` table):

=============  ==============================================================================
``command``    ``override``, ``resume``, ``mode``, ``occupancy`` or ``ack``
``hold``       override only: how long, e.g. ``"2h"``, ``"90min"``, ``"1h30m"``, ``"45m"``,
               or a number of minutes; absent: ``safety.manual_hold_min`` (cut at the daily
               ``safety.manual_reset_local``)
``louver_deg`` override only: louver angle on the motor's grid inside the safety limits
``regime``     override only: airflow regime 1..10 the panel's dampers allow
``or_pct``     override only: damper opening on ``safety.or_step_pct`` steps, 0 in regime 10
``mode``       mode only (required): the control objective, ``heating``, ``cooling`` or
               ``auto`` (as ``control.mode``)
``state``      occupancy only (required): ``occupied``, ``unoccupied`` or ``auto`` (end an
               override: the occupied signal, else the schedule, decides again)
``until``      occupancy only (required with occupied/unoccupied): when the override ends,
               ``"HH:MM"`` panel local time (the next such time) or an ISO 8601 date-time
               (``2026-12-01T08:00``: panel local time; with ``Z`` or ``+09:00``: that zone)
``finding``    ack only (required): the id of the open finding an operator acknowledges
               (``dsfd status`` lists them; docs/model.md#findings)
=============  ==============================================================================

Positions left out stay where the actuators are when the daemon applies the command; an
override without positions holds the panel where it is. ``mode`` sets the objective the
optimiser and the baseline pursue (docs/model.md#control-objective) in place of the panel
file's ``control.mode``; it moves nothing by itself and is no hold (docs/operating.md,
"Sharing the panel with people"). ``occupancy`` overrides the occupancy the comfort limits
follow until a time (docs/model.md#occupancy); it moves nothing by itself either. An
``until`` is checked here for its form; its instant depends on the time the daemon applies
it (:func:`resolve_until`, on the daemon's clock), where one already past is rejected.
"""

from __future__ import annotations

import datetime
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from dsfd.config.panel import CLOSED_REGIME, REGIME_OPENINGS, PanelConfig

__all__ = [
    "COMMAND_KINDS",
    "MAX_HOLD_S",
    "MIN_HOLD_S",
    "OBJECTIVE_MODES",
    "OCCUPANCY_STATES",
    "CommandError",
    "OperatorCommand",
    "occupancy_request",
    "parse_duration",
    "resolve_until",
    "validate_command",
]

COMMAND_KINDS = ("override", "resume", "mode", "occupancy", "ack")
_FIELDS = {"override": ("hold", "louver_deg", "regime", "or_pct"), "resume": (),
           "mode": ("mode",), "occupancy": ("state", "until"), "ack": ("finding",)}
#: What an ``occupancy`` command may say.
OCCUPANCY_STATES = ("occupied", "unoccupied", "auto")
_CLOCK = re.compile(r"^([01][0-9]|2[0-3]):([0-5][0-9])$")
#: The control objectives an operator may choose (the values of ``control.mode``).
OBJECTIVE_MODES = ("heating", "cooling", "auto")
#: Shortest and longest hold an operator may ask for [s].
MIN_HOLD_S = 60.0
MAX_HOLD_S = 7 * 86400.0
_DURATION = re.compile(r"(\d+(?:\.\d+)?)\s*(d|h|min|m|s)", re.IGNORECASE)
_SECONDS = {"d": 86400.0, "h": 3600.0, "min": 60.0, "m": 60.0, "s": 1.0}


class CommandError(ValueError):
    """A request that cannot be applied; names the field and the bad value."""

    def __init__(self, field: str, value: Any, message: str) -> None:
        self.field = field
        self.value = value
        self.message = message
        super().__init__(f"{field}: {_shown(value)}: {message}")


@dataclass(frozen=True)
class OperatorCommand:
    """A validated request. ``hold_s`` None: the panel's default hold (with its daily reset);
    a position None: keep that actuator where it is; ``mode``: the objective of a ``mode``
    command."""

    kind: str
    hold_s: float | None = None
    phi_deg: float | None = None
    afr: int | None = None
    or_pct: float | None = None
    mode: str | None = None
    #: occupancy only: ``occupied``, ``unoccupied`` or ``auto``, and the ``until`` as given.
    state: str | None = None
    until: str | None = None
    #: ack only: the finding acknowledged.
    finding: int | None = None

    def positions(self) -> dict[str, float]:
        """The positions given, by actuator name."""
        return {k: v for k, v in (("phi_deg", self.phi_deg), ("afr", self.afr),
                                  ("or_pct", self.or_pct)) if v is not None}

    def describe(self) -> str:
        if self.kind == "resume":
            return "resume"
        if self.kind == "mode":
            return f"mode {self.mode}"
        if self.kind == "ack":
            return f"ack finding #{self.finding}"
        if self.kind == "occupancy":
            return f"occupancy {self.state}" + (f" until {self.until}" if self.until else "")
        parts = [f"{k} {v:g}" for k, v in self.positions().items()] or ["positions kept"]
        hold = "default hold" if self.hold_s is None else f"hold {_minutes(self.hold_s)}"
        return f"override ({hold}; {', '.join(parts)})"


def parse_duration(value: Any) -> float:
    """Seconds of a duration: ``"2h"``, ``"90min"``, ``"1h30m"``, ``"45s"``, ``"1d"``, or a
    number (or digits) of minutes. ``ValueError`` for anything else."""
    if isinstance(value, bool):
        raise ValueError("expected a duration such as 2h, 90min or 45m")
    if isinstance(value, int | float) or (
            isinstance(value, str) and value.strip().replace(".", "", 1).isdigit()):
        try:
            seconds = float(value) * 60.0
        except OverflowError:  # an int beyond float's range
            raise ValueError("expected a finite duration") from None
    elif isinstance(value, str) and value.strip():
        text = value.strip()
        parts = list(_DURATION.finditer(text))
        if not parts or "".join(p.group(0) for p in parts).replace(" ", "") != \
                text.replace(" ", ""):
            raise ValueError("expected a duration such as 2h, 90min, 1h30m or 45m")
        seconds = sum(float(p.group(1)) * _SECONDS[p.group(2).lower()] for p in parts)
    else:
        raise ValueError("expected a duration such as 2h, 90min or 45m")
    if not math.isfinite(seconds):
        raise ValueError("expected a finite duration")
    return seconds


def validate_command(cfg: PanelConfig, request: Mapping[str, Any]) -> OperatorCommand:
    """The command ``request`` asks for on panel ``cfg``; :class:`CommandError` if it is
    malformed or does not fit the panel (grid, limits, regimes the dampers allow)."""
    if not isinstance(request, Mapping):
        raise CommandError("request", request, "expected a mapping of fields")
    kind = request.get("command")
    if kind not in COMMAND_KINDS:
        raise CommandError("command", kind, f"expected one of {', '.join(COMMAND_KINDS)}")
    allowed = _FIELDS[kind]
    for key in request:
        if key != "command" and key not in allowed:
            hint = f"expected one of {', '.join(allowed)}" if allowed else \
                "resume takes no other fields"
            raise CommandError(str(key), request[key], f"unknown field for {kind}; {hint}")
    if kind == "resume":
        return OperatorCommand("resume")
    if kind == "mode":
        mode = request.get("mode")
        if not isinstance(mode, str) or mode not in OBJECTIVE_MODES:
            raise CommandError("mode", mode, f"expected one of {', '.join(OBJECTIVE_MODES)}")
        return OperatorCommand("mode", mode=mode)
    if kind == "occupancy":
        return _occupancy(request)
    if kind == "ack":
        return OperatorCommand("ack", finding=_finding_id(request.get("finding")))
    hold_s = _hold(request["hold"]) if request.get("hold") is not None else None
    phi = _louver(cfg, request["louver_deg"]) if request.get("louver_deg") is not None \
        else None
    afr = _regime(cfg, request["regime"]) if request.get("regime") is not None else None
    or_pct = _opening(cfg, request["or_pct"], afr) if request.get("or_pct") is not None \
        else None
    if afr == CLOSED_REGIME and or_pct is None:
        or_pct = 0.0
    return OperatorCommand("override", hold_s=hold_s, phi_deg=phi, afr=afr, or_pct=or_pct)


def occupancy_request(text: str) -> dict[str, Any]:
    """The request of an occupancy command written out: ``"occupied until 18:00"``,
    ``"unoccupied until 2026-12-01T08:00"``, ``"auto"`` (the CLI's words, MQTT's payload).
    :class:`CommandError` if it is not of that form; the fields are checked by
    :func:`validate_command`."""
    words = text.split()
    if not words:
        raise CommandError("state", text, f"expected one of {', '.join(OCCUPANCY_STATES)}, "
                           "e.g. 'occupied until 18:00'")
    request: dict[str, Any] = {"command": "occupancy", "state": words[0]}
    rest = words[1:]
    if rest and (rest[0] != "until" or len(rest) != 2):
        raise CommandError("until", " ".join(rest), "expected 'until TIME' after the state, "
                           "e.g. 'occupied until 18:00'")
    if rest:
        request["until"] = rest[1]
    return request


_MAX_ROWID = 2**63 - 1


def _finding_id(value: Any) -> int:
    """A finding id: a whole number from 1 to SQLite's largest integer (digits in a string
    too: a CLI argument)."""
    if isinstance(value, str) and value.strip().isdigit() and len(value.strip()) <= 19:
        value = int(value.strip())
    if isinstance(value, bool) or not isinstance(value, int | float) or value != value \
            or value in (math.inf, -math.inf) or value != int(value) \
            or not 1 <= value <= _MAX_ROWID:
        raise CommandError("finding", value, "expected the id of a finding, a whole number "
                           "from 1 (dsfd status lists the open ones)")
    return int(value)


def _occupancy(request: Mapping[str, Any]) -> OperatorCommand:
    state, until = request.get("state"), request.get("until")
    if not isinstance(state, str) or state not in OCCUPANCY_STATES:
        raise CommandError("state", state, f"expected one of {', '.join(OCCUPANCY_STATES)}")
    if state == "auto":
        if until is not None:
            raise CommandError("until", until, "auto ends the override: give no time")
        return OperatorCommand("occupancy", state=state)
    if until is None:
        raise CommandError("until", until, f"{state} needs an end time, e.g. 18:00 or "
                           "2026-12-01T08:00")
    _parse_until(until)  # the form; the instant is the daemon's to resolve
    return OperatorCommand("occupancy", state=state, until=str(until).strip())


def _parse_until(value: Any) -> tuple[int, int] | datetime.datetime:
    """``until`` as a local clock time (hours, minutes) or a date-time (naive: panel local
    time); :class:`CommandError` for anything else."""
    text = value.strip() if isinstance(value, str) else None
    if text:
        m = _CLOCK.match(text)
        if m is not None:
            return int(m.group(1)), int(m.group(2))
        if len(text) > 10:  # a date alone is no end time
            try:
                return datetime.datetime.fromisoformat(text)
            except ValueError:
                pass
    raise CommandError("until", value, "expected a local time HH:MM (e.g. 18:00) or an ISO "
                       "8601 date-time (e.g. 2026-12-01T08:00, 2026-12-01T08:00+09:00)")


def resolve_until(value: Any, *, now_s: float, utc_offset_h: float) -> float:
    """The UTC instant [s] an occupancy command's ``until`` means at ``now_s``: ``HH:MM`` is
    the next such panel local time after ``now_s``, a date-time without a zone is panel
    local time. :class:`CommandError` if it is not after ``now_s`` or more than
    :data:`MAX_HOLD_S` ahead."""
    parsed = _parse_until(value)
    local = datetime.timezone(datetime.timedelta(hours=utc_offset_h))
    if isinstance(parsed, tuple):
        now_local = datetime.datetime.fromtimestamp(now_s, local)
        at = now_local.replace(hour=parsed[0], minute=parsed[1], second=0, microsecond=0)
        if at.timestamp() <= now_s:
            at += datetime.timedelta(days=1)
        return at.timestamp()
    at_s = (parsed if parsed.tzinfo is not None else parsed.replace(tzinfo=local)).timestamp()
    if at_s <= now_s:
        raise CommandError("until", value, "already past: give a time in the future")
    if at_s - now_s > MAX_HOLD_S:
        raise CommandError("until", value, f"more than {_minutes(MAX_HOLD_S)} ahead")
    return at_s


def _hold(value: Any) -> float:
    try:
        seconds = parse_duration(value)
    except ValueError as exc:
        raise CommandError("hold", value, str(exc)) from None
    if not MIN_HOLD_S <= seconds <= MAX_HOLD_S:
        raise CommandError("hold", value, f"must be between {_minutes(MIN_HOLD_S)} and "
                           f"{_minutes(MAX_HOLD_S)}")
    return seconds


def _number(field: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise CommandError(field, value, "expected a finite number")
    try:
        number = float(value)  # an int beyond float's range raises (JSON allows any size)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise CommandError(field, value, "expected a finite number")
    return number


def _louver(cfg: PanelConfig, value: Any) -> float:
    phi = _number("louver_deg", value)
    lv, s = cfg.louver, cfg.safety
    if lv is None:
        raise CommandError("louver_deg", value, "this panel has no louver")
    if not s.phi_min_deg <= phi <= s.phi_max_deg:
        raise CommandError("louver_deg", value, f"outside the louver limits "
                           f"{s.phi_min_deg:g}..{s.phi_max_deg:g} deg (safety.phi_*_deg)")
    grid = lv.angles_deg()
    if not any(abs(phi - a) < 1e-6 for a in grid):
        lower = max((a for a in grid if a < phi), default=None)
        upper = min((a for a in grid if a > phi), default=None)
        near = " or ".join(f"{a:g}" for a in (lower, upper) if a is not None)
        raise CommandError("louver_deg", value, f"not on the louver motor's {lv.step_deg:g} deg "
                           f"grid (nearest: {near})")
    return phi


def _regime(cfg: PanelConfig, value: Any) -> int:
    number = _number("regime", value)
    if number != int(number) or not 1 <= number <= 10:
        raise CommandError("regime", value, "expected an airflow regime 1..10")
    afr = int(number)
    available = cfg.openings.available_regimes()
    if afr not in available:
        lacking = ", ".join(sorted(REGIME_OPENINGS[afr] - set(cfg.openings.present())))
        raise CommandError("regime", value, f"needs dampers this panel lacks ({lacking}); "
                           f"available: {', '.join(str(r) for r in available)}")
    return afr


def _opening(cfg: PanelConfig, value: Any, afr: int | None) -> float:
    or_pct = _number("or_pct", value)
    s = cfg.safety
    if not 0.0 <= or_pct <= s.or_max_pct:
        raise CommandError("or_pct", value, f"outside 0..{s.or_max_pct:g} % "
                           "(safety.or_max_pct)")
    steps = or_pct / s.or_step_pct
    if abs(steps - round(steps)) > 1e-6:
        raise CommandError("or_pct", value, f"not on the damper's {s.or_step_pct:g} % steps "
                           "(safety.or_step_pct)")
    if afr == CLOSED_REGIME and or_pct != 0.0:
        raise CommandError("or_pct", value, "regime 10 closes every damper: use 0 or leave "
                           "it out")
    return or_pct


def _shown(value: Any) -> str:
    """``repr`` of a bad value, cut (a request may carry a thousand-digit number)."""
    try:
        text = repr(value)
    except ValueError:  # an int too long for str() (sys.get_int_max_str_digits)
        return "<a number too long to show>"
    return text if len(text) <= 120 else f"{text[:100]}… ({len(text)} characters)"


def _minutes(seconds: float) -> str:
    if seconds % 3600 == 0:
        return f"{seconds / 3600:g} h"
    return f"{seconds / 60:g} min"
