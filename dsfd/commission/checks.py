"""Plausibility checks of a commissioning read-out: what a person would notice, and the likely
mistake behind it (pure: values in, findings out; docs/commissioning.md explains each).

* **scale** — a value outside what the signal can show in service (a room at 2.1 °C, a pane
  at 210 °C) that a power of ten brings inside: the register's ``scale`` is off by that factor;
* **night** — with the sun below −6° (civil twilight): irradiance near 0, and the exterior
  pane near the outdoor air;
* **order** — temperatures along the heat path must be ordered: on a heating-season night
  room ≥ x3 ≥ x2 ≥ x4, x5 ≥ x1 (no source inside the panel, heat flows out); in winter sun the
  black louver is the hottest element and heats the cavity air, which heats the exterior pane
  (x4 ≥ x5 ≥ x1), and the inner pane is not below the room (x3 ≥ room). When an ordering is
  broken and exchanging two thermocouples repairs *every* constraint, the two registers are
  named as swapped;
* **duplicate** — two temperatures identical in every read (thermocouple noise makes that
  unlikely for two live channels): a copied register or one sensor wired twice;
* **feedback** — an actuator's position feedback against its set-point: the louver at the
  mirror angle is an inverted sign; a power of ten is a wrong scale.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from dsfd.signals import SIGNALS

__all__ = [
    "DEEP_NIGHT_ELEVATION_DEG",
    "EXPECTED",
    "NIGHT_ELEVATION_DEG",
    "Conditions",
    "Constraint",
    "Finding",
    "check_duplicates",
    "check_feedback",
    "check_louver_range",
    "check_night",
    "check_order",
    "check_scales",
    "order_constraints",
    "scale_factor",
]

#: Sun elevation below which it is night for the checks [deg] (end of civil twilight).
NIGHT_ELEVATION_DEG = -6.0
#: ... and below which the panel has given up the day's stored heat, so the heat-path
#: ordering holds [deg]: the stratified truth plant's cavity keeps the exterior pane 7 K
#: above outdoors at -10 deg, and with the louver closed the interior glass 1.9 K above the
#: room at -24 deg (Suwon, January); -30 deg is about 2.5 h after sunset there.
DEEP_NIGHT_ELEVATION_DEG = -30.0
#: What a signal can show on a façade in service (tighter than the plausibility ranges of
#: dsfd.signals for the room and the cavity anemometer) [signal unit].
EXPECTED: Mapping[str, tuple[float, float]] = {
    **{f"x{i}_c": (-35.0, 95.0) for i in range(1, 6)},
    "t_room_c": (10.0, 35.0),
    "t_out_c": (-45.0, 50.0),
    "ghi_wm2": (-10.0, 1400.0),
    "wind_speed_ms": (0.0, 60.0),
    "wind_dir_deg": (0.0, 360.0),
    "v_cav_ms": (0.0, 5.0),
    "rh_pct": (1.0, 100.0),
    "pressure_hpa": (800.0, 1100.0),
    "phi_deg": (-90.0, 90.0),
    "afr": (1.0, 10.0),
    "or_pct": (0.0, 100.0),
}
_FACTORS = (10.0, 100.0, 1000.0, 0.1, 0.01, 0.001)
#: Irradiance a thermopile pyranometer may read at night (thermal offset) [W/m2].
NIGHT_GHI_WM2 = 15.0
#: Exterior pane against outdoor air at night: below it by sky cooling, above by the
#: cavity's heat [K].
PANE_BELOW_OUT_K, PANE_ABOVE_OUT_K = 5.0, 6.0
#: Room warmer than outdoors by at least this for the heating-season orderings [K].
HEATING_DT_K = 5.0
#: Winter sun: sun elevation [deg] and irradiance [W/m2] from which the louver heats.
SUN_ELEVATION_DEG, SUN_GHI_WM2 = 10.0, 200.0
_THERMOCOUPLES = ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c", "t_room_c")


@dataclass(frozen=True)
class Conditions:
    """When the read-out was taken: sun elevation [deg] at the site, and the room air the
    panel file assumes [°C] (``room.t_in_c``: the heating-season test when the room sensor
    is missing or mis-scaled)."""

    sun_elevation_deg: float
    t_room_default_c: float = 22.0

    @property
    def night(self) -> bool:
        return self.sun_elevation_deg < NIGHT_ELEVATION_DEG


@dataclass(frozen=True)
class Finding:
    """Something a person should look at: which check, which signals, what and why."""

    check: str
    signals: tuple[str, ...]
    message: str
    likely: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"check": self.check, "signals": list(self.signals), "message": self.message,
                "likely": self.likely}


@dataclass(frozen=True)
class Constraint:
    """``hi`` ≥ ``lo`` − ``margin_k`` [K], because ``why``."""

    hi: str
    lo: str
    margin_k: float
    why: str
    #: True: usual, not required (it only ranks the exchanges that repair the others).
    soft: bool = False

    def holds(self, values: Mapping[str, float]) -> bool:
        return values[self.hi] >= values[self.lo] - self.margin_k


def _fmt(value: float, unit: str) -> str:
    return f"{value:.4g} {unit}"


def scale_factor(name: str, value: float) -> float | None:
    """The power of ten that brings ``value`` into :data:`EXPECTED` (None: in range already,
    or no single factor does)."""
    lo, hi = EXPECTED[name]
    if lo <= value <= hi:
        return None
    fits = [f for f in _FACTORS if lo <= value * f <= hi and value * f != 0.0]
    return fits[0] if fits else None


def check_scales(values: Mapping[str, float], scales: Mapping[str, float]
                 ) -> tuple[list[Finding], set[str]]:
    """Findings for values outside :data:`EXPECTED`, and the signals they concern (the other
    checks leave those out: a mis-scaled value says nothing about the physics)."""
    out: list[Finding] = []
    for name, value in values.items():
        if name not in EXPECTED:
            continue
        lo, hi = EXPECTED[name]
        if lo <= value <= hi:
            continue
        unit = SIGNALS[name].unit
        what = "the room" if name == "t_room_c" else name
        f = scale_factor(name, value)
        msg = f"{name} reads {_fmt(value, unit)}, outside {lo:g}..{hi:g} {unit} for {what}"
        if f is None:
            out.append(Finding("range", (name,), msg,
                               "not a power of ten away: the wrong register, type or offset?"))
            continue
        scale = scales.get(name)
        fix = f" (scale {scale:g} -> {scale * f:g})" if scale is not None else ""
        out.append(Finding("scale", (name,), msg,
                           f"wrong scale: x{f:g} gives {_fmt(value * f, unit)}{fix}"))
    return out, {f.signals[0] for f in out}


def check_night(values: Mapping[str, float], cond: Conditions) -> list[Finding]:
    """Irradiance near 0 at night (the pane check is a constraint of :func:`order_constraints`)."""
    ghi = values.get("ghi_wm2")
    if not cond.night or ghi is None or abs(ghi) <= NIGHT_GHI_WM2:
        return []
    return [Finding("night", ("ghi_wm2",),
                    f"ghi_wm2 reads {ghi:.4g} W/m2 with the sun {-cond.sun_elevation_deg:.0f} "
                    f"deg below the horizon (expected within {NIGHT_GHI_WM2:g} W/m2 of 0)",
                    "a wrong field or offset, a covered or lit sensor, or the site/clock "
                    "(site.latitude_deg, longitude_deg) is wrong")]


def order_constraints(values: Mapping[str, float], cond: Conditions) -> list[Constraint]:
    """The orderings that hold now (module docstring); only over signals present."""
    t_out, room = values.get("t_out_c"), values.get("t_room_c", cond.t_room_default_c)
    heating = t_out is not None and room is not None and room - t_out >= HEATING_DT_K
    out: list[Constraint] = []
    deep = cond.sun_elevation_deg < DEEP_NIGHT_ELEVATION_DEG
    if deep and t_out is not None:
        out += [Constraint("x1_c", "t_out_c", PANE_BELOW_OUT_K,
                           "at night the exterior pane sits near the outdoor air"),
                Constraint("t_out_c", "x1_c", PANE_ABOVE_OUT_K,
                           "at night the exterior pane sits near the outdoor air")]
    if deep and heating:
        glass = "on a heating night heat flows from the room out through x3, x2, x1"
        cavity = "on a heating night the cavity lies between the exterior pane and the room"
        out += [Constraint("t_room_c", "x3_c", 2.0, glass),
                Constraint("x3_c", "x2_c", 2.0, glass),
                Constraint("x2_c", "x1_c", 2.0, glass)]
        out += [Constraint(a, b, 1.5, cavity) for a, b in (
            ("t_room_c", "x4_c"), ("t_room_c", "x5_c"), ("x4_c", "x1_c"), ("x5_c", "x1_c"))]
        closed = "usually the cavity is colder than the interior pane (not with room air in it)"
        out += [Constraint("x2_c", n, 1.0, closed, soft=True) for n in ("x4_c", "x5_c")]
    ghi = values.get("ghi_wm2")
    sunny = (cond.sun_elevation_deg >= SUN_ELEVATION_DEG and ghi is not None
             and ghi >= SUN_GHI_WM2)
    if sunny and heating:
        out += [Constraint("x4_c", "x5_c", 1.0, "in winter sun the black louver heats the "
                           "cavity air"),
                Constraint("x4_c", "x1_c", 1.0, "in winter sun the black louver is warmer "
                           "than the exterior pane")]
    return [c for c in out if c.hi in values and c.lo in values]


def check_order(values: Mapping[str, float], constraints: Sequence[Constraint],
                where: Mapping[str, str]) -> list[Finding]:
    """Broken orderings, and the two swapped thermocouples if one exchange repairs all (the
    usual, soft, orderings choose among several exchanges that repair the required ones)."""
    hard = [c for c in constraints if not c.soft]
    broken = [c for c in hard if not c.holds(values)]
    if not broken:
        return []
    names = sorted({s for c in hard for s in (c.hi, c.lo) if s in _THERMOCOUPLES})
    repairs, usual = [], []
    for a, b in itertools.combinations(names, 2):
        swapped = {**values, a: values[b], b: values[a]}
        if all(c.holds(swapped) for c in hard):
            repairs.append((a, b))
            if all(c.holds(swapped) for c in constraints):
                usual.append((a, b))
    text = "; ".join(f"{c.hi} {values[c.hi]:.4g} < {c.lo} {values[c.lo]:.4g}"
                     + (f" - {c.margin_k:g} K" if c.margin_k else "") + f" ({c.why})"
                     for c in broken)
    best = repairs if len(repairs) == 1 else usual
    if len(best) == 1:
        a, b = best[0]
        others = [f"{x}/{y}" for x, y in repairs if (x, y) != (a, b)]
        rest = f" (less likely: {', '.join(others)})" if others else ""
        return [Finding("swap", (a, b), f"ordering broken: {text}",
                        f"{a} and {b} swapped: {a} at {where.get(a, '?')} and {b} at "
                        f"{where.get(b, '?')}; exchanging their readings satisfies every "
                        f"ordering{rest}")]
    involved = tuple(sorted({s for c in broken for s in (c.hi, c.lo)}))
    hint = ("exchanging any one of " + ", ".join(f"{a}/{b}" for a, b in repairs)
            + " would repair it") if repairs else "no single exchange of two sensors repairs it"
    return [Finding("order", involved, f"ordering broken: {text}",
                    f"a misplaced sensor or register; {hint}")]


def check_duplicates(series: Mapping[str, Sequence[float]], where: Mapping[str, str]
                     ) -> list[Finding]:
    """Temperatures identical in every read (at least two reads)."""
    names = [n for n in _THERMOCOUPLES if n in series and len(series[n]) >= 2
             and all(math.isfinite(v) for v in series[n])]
    out = []
    for a, b in itertools.combinations(names, 2):
        if list(series[a]) == list(series[b]):
            out.append(Finding("duplicate", (a, b),
                               f"{a} and {b} read the same value in all {len(series[a])} reads "
                               f"({series[a][-1]:.4g} degC)",
                               f"a copied register or one sensor wired twice: {a} at "
                               f"{where.get(a, '?')}, {b} at {where.get(b, '?')}"))
    return out


#: Position feedback tolerance against the set-point [signal unit].
FEEDBACK_TOLERANCE = {"phi_deg": 2.0, "or_pct": 2.0, "afr": 0.0}


def check_feedback(name: str, set_point: float, feedback: float, where: str) -> Finding | None:
    """The feedback of actuator ``name`` against its set-point (None: they agree)."""
    tol = FEEDBACK_TOLERANCE.get(name, 0.0)
    if abs(feedback - set_point) <= tol:
        return None
    unit = SIGNALS[name].unit
    msg = (f"{name}: set-point {_fmt(set_point, unit)}, feedback {_fmt(feedback, unit)} "
           f"({where})")
    if name == "phi_deg" and abs(set_point) > tol and abs(feedback + set_point) <= tol:
        return Finding("sign", (name,), msg, "inverted sign: the louver stands at the mirror "
                       "angle; the set-point or the feedback register has its scale's sign "
                       "wrong (look at the slats to tell which)")
    ratio = feedback / set_point if set_point else math.inf
    for f in _FACTORS:
        if math.isfinite(ratio) and abs(ratio - f) <= 0.02 * f:
            return Finding("scale", (name,), msg, f"wrong scale: the feedback is x{f:g} the "
                           "set-point; one of the two scales is off by that factor")
    return Finding("feedback", (name,), msg, "still moving, stalled, or the wrong register")


def check_louver_range(angle_deg: float, lo_deg: float, hi_deg: float, where: str
                       ) -> Finding | None:
    """The louver read outside its mechanical range ``safety.phi_min_deg..phi_max_deg``
    (None: inside). A mirror angle inside the range points at an inverted sign."""
    if lo_deg - 0.5 <= angle_deg <= hi_deg + 0.5:
        return None
    msg = (f"phi_deg reads {angle_deg:.4g} deg ({where}), outside the mechanical range "
           f"{lo_deg:g}..{hi_deg:g} deg (safety.phi_min_deg, phi_max_deg)")
    if lo_deg - 0.5 <= -angle_deg <= hi_deg + 0.5:
        return Finding("sign", ("phi_deg",), msg, f"inverted sign: the mirror angle "
                       f"{-angle_deg:.4g} deg is inside the range; check the scale's sign")
    return Finding("range", ("phi_deg",), msg, "a wrong scale or offset, or the range in the "
                   "safety section is wrong")
