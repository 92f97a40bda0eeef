"""Writes to the commandable points turned into operator requests. Pure (no bacpypes3, no I/O).

A BACnet write (ASHRAE 135-2020 clause 15.9, WriteProperty; clause 19.2, prioritized
commanding) carries a value or NULL and a priority 1..16. Here:

* priority 1..15 with a value: an operator hold at that position, through
  :func:`dsfd.daemon.commands.validate_command` and the ``commands`` table as ``dsfd
  override``; the value is checked alone first (:func:`check_value`), so a write that does
  not fit the panel is answered with a BACnet error and stored nowhere;
* NULL at a priority: relinquish. When that changes what is in force — the highest active
  priority of a point went away — the request becomes the positions still commanded at
  other priorities, or ``resume`` when none is left;
* priority 16 (and a write without a priority, which means 16, clause 19.2.1) is the
  controller's own: refused (write-access-denied); the controller's command is the
  relinquish default.

The three commandable points (louver, regime, dampers) share one hold: the panel has one. The
request in force holds every point that has an active priority at its highest one; a point
without one stays where it is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from dsfd.config import PanelConfig
from dsfd.daemon.commands import MAX_HOLD_S, CommandError, validate_command
from dsfd.integrations.bacnet.points import COMMAND_FIELDS, OBJECTIVE_STATES

__all__ = ["CONTROLLER_PRIORITY", "BacnetWriteError", "PriorityArrays", "check_value",
           "objective_request"]

#: The priority of the controller's own command (the relinquish default stands for it).
CONTROLLER_PRIORITY = 16


class BacnetWriteError(Exception):
    """A write answered with a BACnet error (``error_code``, property class) and why."""

    def __init__(self, error_code: str, reason: str) -> None:
        super().__init__(f"{error_code}: {reason}")
        self.error_code = error_code
        self.reason = reason


def check_value(cfg: PanelConfig, key: str, value: Any) -> float | int:
    """The value a write to commandable point ``key`` commands, checked against the panel
    (grid, limits, regimes the dampers allow); :class:`BacnetWriteError` value-out-of-range."""
    field_name = COMMAND_FIELDS[key]
    number = int(value) if key == "regime" else float(value)
    try:
        validate_command(cfg, {"command": "override", field_name: number})
    except CommandError as exc:
        raise BacnetWriteError("valueOutOfRange", str(exc)) from None
    return number


def objective_request(value: int) -> dict[str, Any]:
    """The ``mode`` request of a write to the objective's multi-state value (1, 2, 3)."""
    if not 1 <= value <= len(OBJECTIVE_STATES):
        raise BacnetWriteError("valueOutOfRange", f"state {value}: expected 1..."
                            f"{len(OBJECTIVE_STATES)} ({', '.join(OBJECTIVE_STATES)})")
    return {"command": "mode", "mode": OBJECTIVE_STATES[value - 1]}


@dataclass
class PriorityArrays:
    """The priority arrays of the commandable points as the device keeps them: per point,
    priority → (value, who wrote it)."""

    slots: dict[str, dict[int, tuple[float | int, str]]] = field(default_factory=dict)

    def highest(self, key: str) -> tuple[int, float | int, str] | None:
        """(priority, value, writer) in force for a point, None if all are relinquished."""
        active = self.slots.get(key) or {}
        if not active:
            return None
        p = min(active)
        return (p, *active[p])

    def in_force(self) -> dict[str, tuple[int, float | int, str]]:
        out = {}
        for key in COMMAND_FIELDS:
            top = self.highest(key)
            if top is not None:
                out[key] = top
        return out

    def write(self, key: str, priority: int, value: float | int | None, writer: str
              ) -> bool:
        """Set (value) or relinquish (None) one slot; True if what is in force changed."""
        before = self.in_force()
        slots = self.slots.setdefault(key, {})
        if value is None:
            slots.pop(priority, None)
        else:
            slots[priority] = (value, writer)
        return self.in_force() != before

    def clear(self) -> bool:
        """Relinquish every slot (the hold they made ended); True if any was active."""
        had = any(self.slots.values())
        self.slots.clear()
        return had

    def request(self, *, until_relinquished: bool) -> tuple[dict[str, Any], str]:
        """The request in force and its requester (the writer of the highest priority among
        the points in force); ``resume`` when nothing is commanded."""
        top = self.in_force()
        if not top:
            return {"command": "resume"}, ""
        request: dict[str, Any] = {"command": "override"}
        if until_relinquished:
            request["hold"] = f"{MAX_HOLD_S / 60:g}"  # minutes
        for key, (_, value, _) in top.items():
            request[COMMAND_FIELDS[key]] = value
        writer = min(top.values(), key=lambda t: t[0])[2]
        return request, writer
