"""The manual hold: when a person has the panel, the daemon leaves it alone. Pure logic.

A hold starts three ways (issue 20):

* **detected** — the actuators' read-back differs from where the daemon last put them
  (:func:`moved_actuators`: the louver by at least half a motor step, the regime at all, the
  dampers by more than ``safety.or_deadband_pct``), while no write of the daemon is unverified;
* **input** — the panel's ``override_input`` (wall switch, BMS hand flag) is active; the hold
  lasts while it is;
* **operator** — an ``override`` command (:mod:`dsfd.daemon.commands`), optionally with
  positions the daemon writes once.

A timed hold (detected, operator) ends after ``safety.manual_hold_min`` or the operator's
``hold``; without an explicit ``hold`` it ends at the latest at the daily
``safety.manual_reset_local`` (panel local time). Any hold but an input hold ends on
``resume``. The latest human action wins: a person moving the panel during an operator hold
starts a detected hold; an operator override replaces a detected one; while the input is set,
neither an override nor a resume is accepted (the switch on the wall is the stronger word).

Durations run on the monotonic cycle grid (``now_mono_s``), so a wall-clock step neither
shortens nor lengthens a hold; ``expires_s`` (UTC) is for display, the database and a restart.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

from dsfd.config.panel import CLOSED_REGIME, PanelConfig
from dsfd.daemon.commands import CommandError, OperatorCommand
from dsfd.drivers.base import Command
from dsfd.measured import iso_utc

__all__ = ["HOLD_SOURCES", "Hold", "HoldTracker", "HoldUpdate", "PendingCommand",
           "hold_seconds", "moved_actuators", "position_text"]

HOLD_SOURCES = ("detected", "input", "operator")


@dataclass(frozen=True)
class Hold:
    """An active hold.

    Attributes
    ----------
    source : {"detected", "input", "operator"}
    position : Command or None
        Where the panel is held (None: wherever it is; nothing is ever written).
    since_s : float, [s]
        UTC unix time the hold started.
    expires_s, until_mono_s : float or None, [s]
        End in UTC and on the monotonic grid; None while an input holds.
    ends_by : str
        What ends it: ``"time"``, ``"reset"`` (the daily reset comes first) or ``"input"``.
    command_id : int or None
        The operator command behind an operator hold.
    by : str
        Who: the command's source and requester, the input's device and address.
    """

    source: str
    position: Command | None
    since_s: float
    expires_s: float | None
    until_mono_s: float | None
    ends_by: str = "time"
    command_id: int | None = None
    by: str = ""

    def describe(self) -> str:
        who = f" ({self.by})" if self.by else ""
        until = "while the input is set" if self.expires_s is None else \
            f"until {_utc(self.expires_s)}"
        return f"{self.source} hold{who} {until}"


@dataclass(frozen=True)
class PendingCommand:
    """An operator command the loop picked up: validated, or why it cannot be."""

    command_id: int
    command: OperatorCommand | CommandError
    source: str
    requester: str


@dataclass
class HoldUpdate:
    """What one cycle's update did: the hold now, events and command results."""

    hold: Hold | None
    events: list[tuple[str, str, str]] = field(default_factory=list)
    results: list[tuple[int, str, str]] = field(default_factory=list)
    #: Actuators a person moved this cycle (detection), empty if none.
    moved: list[str] = field(default_factory=list)
    #: True if this cycle started a hold at the read-back (the daemon's new reference).
    adopted: bool = False


def moved_actuators(cfg: PanelConfig, now: Command, expected: Command) -> list[str]:
    """Actuators whose read-back ``now`` differs from ``expected`` by more than the motor's
    resolution: louver by half a grid step or more, any regime change, dampers by more than
    the dead-band."""
    out = []
    lv = cfg.louver
    if lv is not None and abs(now.phi_deg - expected.phi_deg) >= 0.5 * lv.step_deg:
        out.append("phi_deg")
    if now.afr != expected.afr:
        out.append("afr")
    if abs(now.or_pct - expected.or_pct) > max(cfg.safety.or_deadband_pct, 1e-9):
        out.append("or_pct")
    return out


def hold_seconds(cfg: PanelConfig, *, now_s: float, requested_s: float | None) -> tuple[float,
                                                                                       str]:
    """How long a timed hold starting at UTC ``now_s`` lasts [s], and what ends it.

    An explicit ``requested_s`` is taken as it is; otherwise ``safety.manual_hold_min``, cut
    at the next daily ``safety.manual_reset_local`` (local time = UTC + ``site.utc_offset_h``).
    """
    if requested_s is not None:
        return requested_s, "time"
    duration = cfg.safety.manual_hold_min * 60.0
    reset = cfg.safety.manual_reset_minute
    if reset is None:
        return duration, "time"
    local_s = now_s + cfg.site.utc_offset_h * 3600.0
    to_reset = (reset * 60.0 - local_s) % 86400.0 or 86400.0
    return (to_reset, "reset") if to_reset < duration else (duration, "time")


class HoldTracker:
    """The hold of one panel, updated once per cycle."""

    def __init__(self, cfg: PanelConfig) -> None:
        self.cfg = cfg
        self.hold: Hold | None = None

    def restore(self, hold: Hold) -> None:
        """Take over a hold a previous run left active (after a restart)."""
        self.hold = hold

    def update(self, *, now_mono_s: float, now_s: float, read_back: Command | None,
               expected: Command | None, input_active: bool | None, input_where: str = "",
               commands: Sequence[PendingCommand] = ()) -> HoldUpdate:
        """One cycle: expiry, the override input, detection, then the operator commands.

        Parameters
        ----------
        now_mono_s, now_s : float, [s]
            The cycle's time on the monotonic grid and in UTC.
        read_back : Command or None
            The actuators now (None: not readable).
        expected : Command or None
            Where the daemon believes they are: its last verified write, or the position a
            hold adopted (None: unknown, e.g. after a failed write; no detection then).
        input_active : bool or None
            The override input (None: none configured, or not readable this cycle).
        commands : sequence of PendingCommand
            Operator commands picked up this cycle, oldest first.
        """
        up = HoldUpdate(self.hold)
        if up.hold is not None and up.hold.position is None and read_back is not None:
            up.hold = replace(up.hold, position=read_back)  # held where it is found
            up.adopted = True
        self._expire(up, now_mono_s)
        self._input(up, input_active, input_where, now_s, read_back, expected)
        if read_back is not None and expected is not None:
            up.moved = moved_actuators(self.cfg, read_back, expected)
        if up.moved:
            self._detected(up, now_mono_s, now_s, read_back)
        for pending in commands:
            self._command(up, pending, now_mono_s, now_s, read_back, expected)
        self.hold = up.hold
        return up

    # ------------------------------------------------------------------ the steps
    def _end(self, up: HoldUpdate, why: str) -> None:
        if up.hold is not None:
            up.events.append(("info", "hold_ended", f"{up.hold.describe()} ended: {why}"))
        up.hold = None

    def _start(self, up: HoldUpdate, hold: Hold) -> None:
        up.hold = hold
        where = "position kept" if hold.position is None else position_text(hold.position)
        up.events.append(("info", "hold_started", f"{hold.describe()}: {where}"))

    def _timed(self, source: str, position: Command | None, now_mono_s: float, now_s: float,
               requested_s: float | None, **extra: object) -> Hold:
        seconds, ends_by = hold_seconds(self.cfg, now_s=now_s, requested_s=requested_s)
        return Hold(source, position, now_s, now_s + seconds, now_mono_s + seconds,
                    ends_by, **extra)  # type: ignore[arg-type]

    def _expire(self, up: HoldUpdate, now_mono_s: float) -> None:
        hold = up.hold
        if hold is None or hold.until_mono_s is None or now_mono_s < hold.until_mono_s:
            return
        self._end(up, f"daily reset at {self.cfg.safety.manual_reset_local} local time"
                  if hold.ends_by == "reset" else
                  f"held for {(hold.expires_s - hold.since_s) / 60:g} min")  # type: ignore

    def _input(self, up: HoldUpdate, active: bool | None, where: str, now_s: float,
               read_back: Command | None, expected: Command | None) -> None:
        held_by_input = up.hold is not None and up.hold.source == "input"
        if active is True and not held_by_input:
            if up.hold is not None:
                self._end(up, f"superseded by the override input ({where})")
            self._start(up, Hold("input", read_back or expected, now_s, None, None, "input",
                                 by=where))
            up.adopted = read_back is not None
        elif active is False and held_by_input:
            self._end(up, f"override input ({where}) released")

    def _detected(self, up: HoldUpdate, now_mono_s: float, now_s: float,
                  read_back: Command) -> None:
        up.events.append(("warning", "manual_override", "actuators moved by someone else: "
                          f"{', '.join(up.moved)} now {position_text(read_back)}"))
        up.adopted = True
        if up.hold is not None and up.hold.source == "input":
            up.hold = replace(up.hold, position=read_back)  # adjusted by hand while held
            return
        if up.hold is not None:
            self._end(up, "superseded by a manual move")
        self._start(up, self._timed("detected", read_back, now_mono_s, now_s, None,
                                    by="actuators moved by hand"))

    def _command(self, up: HoldUpdate, pending: PendingCommand, now_mono_s: float,
                 now_s: float, read_back: Command | None, expected: Command | None) -> None:
        cmd = pending.command
        cid = pending.command_id
        if isinstance(cmd, CommandError):
            up.results.append((cid, "rejected", str(cmd)))
            return
        if up.hold is not None and up.hold.source == "input":
            up.results.append((cid, "rejected", f"the override input ({up.hold.by}) is set: "
                               f"release it first"))
            return
        if cmd.kind == "resume":
            note = "no hold was active" if up.hold is None else \
                f"{up.hold.describe()} ended"
            self._end(up, f"resume ({pending.source}, {pending.requester})")
            up.results.append((cid, "applied", note))
            return
        base = read_back or expected
        try:
            position = _merge(base, cmd)
        except ValueError as exc:
            up.results.append((cid, "rejected", str(exc)))
            return
        if up.hold is not None:
            self._end(up, f"superseded by operator command #{cid}")
        up.adopted = not cmd.positions() and read_back is not None  # held where it is
        hold = self._timed("operator", position, now_mono_s, now_s, cmd.hold_s,
                           command_id=cid, by=f"#{cid} {pending.source} {pending.requester}")
        self._start(up, hold)
        up.results.append((cid, "applied", f"{hold.describe()}: "
                           + ("position kept" if position is None else position_text(position))))


def _merge(base: Command | None, cmd: OperatorCommand) -> Command | None:
    """The operator's positions over ``base`` (None if neither gives a full position)."""
    given = cmd.positions()
    if not given:
        return base
    if base is None and len(given) < 3:
        raise ValueError("actuator position unknown (no read-back): give louver_deg, "
                         "regime and or_pct")
    values = {**(base.as_dict() if base is not None else {}), **given}
    if "afr" in given and values["afr"] == CLOSED_REGIME and "or_pct" not in given:
        values["or_pct"] = 0.0
    return Command(phi_deg=values["phi_deg"], afr=int(values["afr"]), or_pct=values["or_pct"])


def position_text(c: Command) -> str:
    """An actuator position as the log, the events and the watchdog status show it."""
    return f"louver {c.phi_deg:+.0f} deg, regime {c.afr}, dampers {c.or_pct:g} %"


def _utc(t: float) -> str:
    return iso_utc(round(t)) if math.isfinite(t) else "?"
