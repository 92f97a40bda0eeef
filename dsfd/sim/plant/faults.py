"""Slow physical faults of the truth plant (simulation only; docs/faults.md#simulated-faults).

What a single signal cannot show, only the physics (issue 38): dirty glass, a clogging insect
screen, a damper whose blade stays put while its position switch reports the command, a
louver whose slats sit one step off the motor's read-back, a drifting or stepped
thermocouple, an anemometer that lost sensitivity. Each fault has a start and one size
(``RATE``), written on the command line as ``KIND[.TARGET]:START:RATE``
(:func:`parse_fault`):

==================  ========================  =============================================
KIND[.TARGET]       RATE                      what the plant does from START
==================  ========================  =============================================
soiling             % per day (≥ 0)           every solar gain of the façade (absorbed in
                                              each layer, transmitted, daylight) × (1 − s),
                                              s = RATE/100 · days since START, at most 1
screen              factor per day (≥ 0)      every opening's flow resistance, so the whole
                                              path resistance, × (1 + RATE · days)
damper-stuck.D      position % (0..100)       damper D (EB, ET, IB, IT) moves to RATE % and
                                              stays; its read-back reports the command
louver-slip         steps (non-zero integer)  the slats sit RATE motor steps from the
                                              command (held at the end stops); the read-back
                                              reports the command
tc-drift.S          K per day                 thermocouple S reads + RATE · days
tc-offset.S         K                         thermocouple S reads + RATE
anemometer[.S]      factor (> 0)              anemometer S (default ``v_cav_ms``; or
                                              ``wind_speed_ms``) reads RATE × its reading
==================  ========================  =============================================

START is an ISO-8601 UTC time (``2022-01-02T06:00:00Z``) or an offset from the start of
the run: ``+`` a number and a unit ``s``, ``min``, ``h`` or ``d`` (``+90min``, ``+2h``,
``+1.5d``, ``+0s``). Parsing is pure; a relative start is resolved by
:meth:`FaultSpec.start_at` when the run's start is known.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dsfd.measured import parse_iso_utc
from dsfd.sim.plant.sensors import THERMOCOUPLES, SensorFault

__all__ = ["DAMPERS", "KINDS", "FaultSpec", "FaultSpecError", "PlantFaults", "parse_fault"]

SECONDS_PER_DAY = 86400.0
#: Damper names of ``damper-stuck.D``, in the plant's opening order.
DAMPERS = ("EB", "ET", "IB", "IT")
#: Fault kinds and what their RATE is.
KINDS = {
    "soiling": "solar transmittance loss [% per day]",
    "screen": "growth of the path-resistance factor [1 per day]",
    "damper-stuck": "blade position [%]",
    "louver-slip": "offset of the slats [motor steps]",
    "tc-drift": "thermocouple drift [K per day]",
    "tc-offset": "thermocouple step [K]",
    "anemometer": "sensitivity factor [-]",
}
_ANEMOMETERS = ("v_cav_ms", "wind_speed_ms")
_UNITS_S = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": SECONDS_PER_DAY}
_OFFSET = re.compile(r"^\+(\d+(?:\.\d*)?|\.\d+)(s|min|h|d)$")


class FaultSpecError(ValueError):
    """A ``--fault`` argument that does not parse; the message names the bad part."""


@dataclass(frozen=True, kw_only=True)
class FaultSpec:
    """One simulated fault.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    target : str or None
        The damper (``damper-stuck``), the thermocouple (``tc-*``, canonical name such as
        ``x3_c``) or the anemometer (``anemometer``); None for the others.
    rate : float
        The size, in the unit :data:`KINDS` gives for the kind.
    start_s : float or None, [s]
        Absolute UTC start; None when the start is relative.
    start_offset_s : float or None, [s]
        Start after the run's start; None when the start is absolute.
    text : str
        The argument it came from (for messages).
    """

    kind: str
    target: str | None
    rate: float
    start_s: float | None = None
    start_offset_s: float | None = None
    text: str = ""

    def start_at(self, run_start_s: float) -> float:
        """The fault's UTC start [s] in a run that starts at ``run_start_s``."""
        if self.start_s is not None:
            return self.start_s
        return run_start_s + float(self.start_offset_s or 0.0)


def parse_fault(text: str) -> FaultSpec:
    """Parse ``KIND[.TARGET]:START:RATE`` (grammar in the module docstring).

    Raises
    ------
    FaultSpecError
        Naming the part that is wrong (kind, target, start or rate) and what is allowed.
    """
    head, sep1, rest = text.partition(":")
    start_text, sep2, rate_text = rest.rpartition(":")
    if not (sep1 and sep2) or not head or not start_text or not rate_text:
        raise FaultSpecError(f"{text!r}: expected KIND:START:RATE, e.g. soiling:+2h:1.5")
    kind, _, target = head.partition(".")
    if kind not in KINDS:
        raise FaultSpecError(f"{text!r}: kind {kind!r} is unknown; choose one of "
                             f"{', '.join(KINDS)}")
    target_name = _target(text, kind, target or None)
    rate = _rate(text, kind, rate_text)
    start_s, offset_s = _start(text, start_text)
    return FaultSpec(kind=kind, target=target_name, rate=rate, start_s=start_s,
                     start_offset_s=offset_s, text=text)


def _target(text: str, kind: str, target: str | None) -> str | None:
    if kind == "damper-stuck":
        if target is None or target.upper() not in DAMPERS:
            raise FaultSpecError(f"{text!r}: damper-stuck needs a damper target "
                                 f"({', '.join(f'damper-stuck.{d}' for d in DAMPERS)}), "
                                 f"got {target!r}")
        return target.upper()
    if kind in ("tc-drift", "tc-offset"):
        name = None if target is None else (target if target.endswith("_c") else f"{target}_c")
        if name not in THERMOCOUPLES:
            raise FaultSpecError(f"{text!r}: {kind} needs a thermocouple target (one of "
                                 f"{', '.join(THERMOCOUPLES)}), got {target!r}")
        return name
    if kind == "anemometer":
        name = target or "v_cav_ms"
        if name not in _ANEMOMETERS:
            raise FaultSpecError(f"{text!r}: anemometer target {target!r}; choose one of "
                                 f"{', '.join(_ANEMOMETERS)}")
        return name
    if target is not None:
        raise FaultSpecError(f"{text!r}: {kind} takes no target, got {target!r}")
    return None


def _rate(text: str, kind: str, rate_text: str) -> float:
    try:
        rate = float(rate_text)
    except ValueError:
        rate = math.nan
    what = f"{text!r}: rate {rate_text!r} ({KINDS[kind]})"
    if not math.isfinite(rate):
        raise FaultSpecError(f"{what} is not a finite number")
    if kind in ("soiling", "screen") and rate < 0:
        raise FaultSpecError(f"{what} must be at least 0")
    if kind == "damper-stuck" and not 0.0 <= rate <= 100.0:
        raise FaultSpecError(f"{what} must be within 0..100")
    if kind == "louver-slip" and (rate != round(rate) or rate == 0):
        raise FaultSpecError(f"{what} must be a non-zero whole number of steps")
    if kind == "anemometer" and not rate > 0:
        raise FaultSpecError(f"{what} must be above 0")
    return rate


def _start(text: str, start_text: str) -> tuple[float | None, float | None]:
    if start_text.startswith("+"):
        m = _OFFSET.match(start_text)
        if m is None:
            raise FaultSpecError(f"{text!r}: start {start_text!r} is not an offset such as "
                                 f"+90min, +2h, +1.5d (units {', '.join(_UNITS_S)})")
        return None, float(m.group(1)) * _UNITS_S[m.group(2)]
    try:
        return parse_iso_utc(start_text), None
    except ValueError as exc:
        raise FaultSpecError(f"{text!r}: start {start_text!r} is neither an ISO-8601 UTC "
                             f"time (2022-01-02T06:00:00Z) nor an offset (+2h): {exc}"
                             ) from None


@dataclass(frozen=True)
class _Active:
    spec: FaultSpec
    start_s: float

    def days(self, t: float) -> float:
        """Days since the start; negative before it."""
        return (t - self.start_s) / SECONDS_PER_DAY


class PlantFaults:
    """The faults of one plant run, their starts resolved (what :class:`Plant` asks).

    Parameters
    ----------
    specs : sequence of FaultSpec
    run_start_s : float, [s]
        Start of the run (for relative starts).
    step_deg : float or None, [deg]
        The louver's motor step (None: the panel has no louver).
    """

    def __init__(self, specs: Sequence[FaultSpec], run_start_s: float, *,
                 step_deg: float | None) -> None:
        for s in specs:
            if s.kind == "louver-slip" and step_deg is None:
                raise ValueError(f"fault {s.text or s.kind!r}: the panel has no louver")
        self._all = tuple(_Active(s, s.start_at(run_start_s)) for s in specs)
        self.step_deg = step_deg

    def _of(self, kind: str, t: float) -> list[_Active]:
        return [a for a in self._all if a.spec.kind == kind and t >= a.start_s]

    @property
    def onsets_s(self) -> tuple[float, ...]:
        """Starts of the actuator faults, sorted: the actuators take new targets there."""
        return tuple(sorted({a.start_s for a in self._all
                             if a.spec.kind in ("damper-stuck", "louver-slip")}))

    def solar_factor(self, t: float) -> float:
        """Fraction of the clean façade's solar gains that passes the dirt at ``t`` [-]."""
        f = 1.0
        for a in self._of("soiling", t):
            f *= 1.0 - min(1.0, a.spec.rate / 100.0 * a.days(t))
        return f

    def resistance_factor(self, t: float) -> float:
        """Multiplier of every opening's flow resistance at ``t`` [-]."""
        f = 1.0
        for a in self._of("screen", t):
            f *= 1.0 + a.spec.rate * a.days(t)
        return f

    def actuate(self, t: float, phi_deg: float, targets: np.ndarray,
                grid_deg: Sequence[float] | None) -> tuple[float, np.ndarray]:
        """Where a command (louver ``phi_deg``, blade ``targets`` (4,) [-]) really sends the
        slats and blades at ``t``: stuck blades at their position, slipped slats off by
        their steps (``grid_deg`` None: no louver)."""
        out = np.array(targets, float)
        for j, pos in self.stuck(t).items():
            out[j] = pos
        if grid_deg is not None:
            phi_deg = self.louver(t, phi_deg, grid_deg)
        return phi_deg, out

    def open_mask(self, t: float, commanded: np.ndarray) -> np.ndarray:
        """Dampers that are open or opening at ``t`` (bool (4,)): the commanded set, a stuck
        one open only if stuck open."""
        out = np.array(commanded, bool)
        for j, pos in self.stuck(t).items():
            out[j] = pos > 0.0
        return out

    def stuck(self, t: float) -> dict[int, float]:
        """Stuck dampers at ``t``: opening index → position [-]."""
        return {DAMPERS.index(str(a.spec.target)): a.spec.rate / 100.0
                for a in self._of("damper-stuck", t)}

    def louver(self, t: float, phi_deg: float, grid_deg: Sequence[float]) -> float:
        """True slat angle [deg] for the commanded ``phi_deg``: off by the slip, held at the
        ends of the grid (the end stops)."""
        steps = sum(a.spec.rate for a in self._of("louver-slip", t))
        if not steps or self.step_deg is None:
            return phi_deg
        return float(np.clip(phi_deg + steps * self.step_deg, min(grid_deg), max(grid_deg)))

    def sensor_faults(self) -> tuple[SensorFault, ...]:
        """The sensor faults in the form :class:`~dsfd.sim.plant.sensors.SensorBank` takes."""
        kinds = {"tc-drift": "drift", "tc-offset": "offset", "anemometer": "gain"}
        return tuple(SensorFault(sensor=str(a.spec.target), kind=kinds[a.spec.kind],
                                 start_s=a.start_s, value=a.spec.rate)
                     for a in self._all if a.spec.kind in kinds)
