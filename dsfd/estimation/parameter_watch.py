"""What the parameter detector watches, and what a change of each parameter means
(docs/model.md#diagnostics-parameters, docs/model.md#findings).

Pure (no files, clocks or logging).

* :func:`daily_estimates` — one value a day from a parameter's on-line estimates (UTC days,
  or the 24-h periods ending at a given time): the precision-weighted mean of the day's
  estimates, with the sd of *one* estimate of the day's
  typical precision (consecutive on-line estimates share most of their window and each is
  the prior of the next, so the day holds about one estimate's worth of evidence, not n).
* :func:`parameter_action` — what a person should check when a calibrated parameter has
  risen or fallen beyond its posterior sd: what that parameter is in the façade, the
  physical changes that move it that way, and the sensors the fit of it rests on (named
  together where the evidence cannot separate them).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["DAY_MIN_SPAN_S", "LOG_UNIT", "OFFSET_UNIT", "PARAMETER_MEANING", "daily_estimates",
           "day_start_s", "parameter_action"]

SECONDS_PER_DAY = 86400.0
#: A day's estimates must span this long (first to last) to make a daily value: a day the
#: daemon started late or was down most of is left out, since a lumped model's parameters
#: have a daily cycle (what a 4-h window at night determines differs from one in the sun)
#: and a part of a day would carry only part of it.
DAY_MIN_SPAN_S = 18 * 3600.0
#: Evidence unit of a parameter fitted in log coordinates: the shift is a natural log, so
#: exp(shift) is the factor by which the parameter changed.
LOG_UNIT = "log"
#: Evidence unit of a heat-flux offset q_x1 … q_x4.
OFFSET_UNIT = "W/m2"


def day_start_s(time_s: float, *, end_s: float | None = None) -> float:
    """Start [s] of the day of :func:`daily_estimates` that holds ``time_s``: its UTC day, or
    with ``end_s`` its 24-h period of those ending at ``end_s``."""
    origin = 0.0 if end_s is None else end_s
    return origin + math.floor((time_s - origin) / SECONDS_PER_DAY) * SECONDS_PER_DAY


def daily_estimates(times_s: np.ndarray, values: np.ndarray, sds: np.ndarray, *,
                    end_s: float | None = None, min_span_s: float = DAY_MIN_SPAN_S
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One estimate per day of a parameter's on-line estimates.

    Parameters
    ----------
    times_s : array (n,), [s]
        Times of the estimates (any order).
    values, sds : array (n,)
        The estimates and their posterior sd in the fitting coordinates (log θ for a
        positive parameter). Non-finite values or sds, and sds ≤ 0, are left out.
    end_s : float, optional, [s]
        The days are the 24-h periods ending at ``end_s`` (…, [end − 2 d, end − 1 d),
        [end − 1 d, end)) instead of UTC days: the detector judges the last 24 h whole
        whenever it runs, so how soon a change shows no longer depends on the hour at which
        it began (with UTC days a change just after midnight waited a whole day more).
    min_span_s : float, [s]
        Days whose estimates span less (first to last) are left out.

    Returns
    -------
    times_s, values, sds : arrays (days,)
        Per day kept, in time order: the time of its last estimate (when its value was
        complete), the precision-weighted mean θ̄ = Σwθ/Σw (w = 1/σ²), and the sd
        (Σw/n)^(-1/2), the sd of one estimate of the day's mean precision.

    Notes
    -----
    The standard error of a mean of n estimates is σ/√n only when they are independent;
    when they are fully correlated it is σ. Consecutive on-line estimates are nearly the
    latter (windows of hours moved by minutes, each update regularised by the previous
    one), and an sd claimed √n ≈ 12 times too small (144 updates a day) turns a clean
    façade's daily wander into findings.
    """
    t = np.asarray(times_s, float)
    v = np.asarray(values, float)
    sd = np.asarray(sds, float)
    ok = np.isfinite(t) & np.isfinite(v) & np.isfinite(sd) & (sd > 0)
    t, v, w = t[ok], v[ok], 1.0 / sd[ok] ** 2
    if t.size == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    origin = 0.0 if end_s is None else end_s
    days, inverse = np.unique(np.floor((t - origin) / SECONDS_PER_DAY), return_inverse=True)
    first = np.full(days.size, np.inf)
    last = np.full(days.size, -np.inf)
    np.minimum.at(first, inverse, t)
    np.maximum.at(last, inverse, t)
    sum_w = np.bincount(inverse, weights=w)
    mean = np.bincount(inverse, weights=w * v) / sum_w
    typical_sd = np.sqrt(np.bincount(inverse) / sum_w)
    keep = last - first >= min_span_s
    return last[keep], mean[keep], typical_sd[keep]


# What moves each θ parameter up or down in a double-skin façade, and what to check
# (docs/model.md#diagnostics-parameters gives the reasoning). The air-path pair f and c
# share their causes: more resistance is f risen or c fallen.
_MORE_RESISTANCE = (
    "clean the insect screens and check that every damper opens fully (a clogged screen, or "
    "a damper that no longer opens or is stuck shut); a cavity anemometer that lost "
    "sensitivity looks the same: check it if screens and dampers are fine")
_LESS_RESISTANCE = (
    "check for a damper open further than its read-back or stuck open, and for a torn or "
    "missing insect screen; a cavity anemometer reading high looks the same")


def _cavity_face(surface: str, sensor: str, *, risen_also: str = "") -> dict[int, str]:
    check = (f"check the sensors {sensor} and x5, and the cavity anemometer (the flow it "
             "reports sets the convection expected); this parameter alone cannot tell them "
             "apart")
    return {+1: f"{surface} and the cavity air exchange more heat at the measured cavity "
                f"speed than before: {check}{risen_also}",
            -1: f"{surface} and the cavity air exchange less heat at the measured cavity "
                f"speed than before: {check} (a sensor loose from its surface reads nearer "
                "the air beside it)"}


def _slats(word: str) -> str:
    return (f"the louver slats exchange {word} heat with the cavity air than before: they "
            "may sit at another angle than their read-back (a slipped step changes the sun "
            "they take and the air passing them: compare the angle by eye with the "
            "read-back), or the louver sensor x4 reads wrong; h_ca2 alone cannot tell these "
            "apart")


def _offset(node: str, sensor: str, *, warmer: str, cooler: str) -> dict[int, str]:
    """A heat-flux offset: a constant heat flux the fit adds to a node's balance, so that
    node reads warmer (risen) or cooler (fallen) than its modelled heat paths explain."""
    head = (f"{node} reads {{}} than its heat paths explain, by a constant: first check its "
            f"sensor {sensor} (a thermocouple offset, a loose or shifted sensor, a wrong "
            f"calibration in the logger) against a reference thermometer")
    return {+1: f"{head.format('warmer')}; otherwise {warmer}",
            -1: f"{head.format('cooler')}; otherwise {cooler}"}


#: Per parameter and direction (+1 risen, -1 fallen): what it means for the façade and
#: what to check.
PARAMETER_MEANING: dict[str, dict[int, str]] = {
    "h_out": {
        +1: "the exterior glass loses more heat to the outdoor air than on the days before. "
            "A windier spell does that (weather, not a fault); if the wind has not changed, "
            "check the exterior-pane sensor x1 against the outdoor-air sensor at night, and "
            "the exterior glass for dirt (less sun absorbed in the pane looks like more "
            "cooling)",
        -1: "the exterior glass loses less heat to the outdoor air than on the days before. "
            "A calmer spell does that (weather, not a fault); if the wind has not changed, "
            "check the exterior-pane sensor x1 (loose from the glass?) against the "
            "outdoor-air sensor (in the sun?) at night"},
    "h_ca1": _cavity_face("the exterior glass", "x1", risen_also=(
        "; dirt on the exterior glass looks the same (the pane takes less sun than modelled, "
        "which the fit can render only as more cooling)")),
    "h_ca2": {+1: _slats("more"), -1: _slats("less")},
    "h_ca3": _cavity_face("the inner glazing's cavity face", "x2"),
    "h_ca4": {
        +1: "the insulating glass unit passes more heat across its gap than before: its gas "
            "fill leaking out through a failed edge seal (look for condensation or fogging "
            "between its panes), or the sensors x2 and x3 of its two panes",
        -1: "the insulating glass unit passes less heat across its gap than before, which no "
            "fault of the unit does: check the sensors x2 and x3 of its two panes (one loose "
            "from the glass reads nearer the air beside it)"},
    "h_in": {
        +1: "the inner glass exchanges more heat with the room air than before: air blown at "
            "the glass (a fan coil, heater or diffuser below the window newly running) or a "
            "blind or curtain no longer in front of it; otherwise check the sensors x3 and "
            "room air",
        -1: "the inner glass exchanges less heat with the room air than before: something "
            "in front of it traps the air at the glass (a blind or curtain drawn, furniture "
            "against the window); otherwise check the sensors x3 and room air"},
    "q_x1": _offset("the exterior pane", "x1",
                    warmer="the glass absorbs more sun than before (dirt on the pane)",
                    cooler="the glass absorbs less sun than before (cleaned)"),
    "q_x2": _offset("the insulating glass unit's cavity-side pane", "x2",
                    warmer="the pane absorbs more sun than before (dirt on the cavity face)",
                    cooler="the pane absorbs less sun than before"),
    "q_x3": _offset("the inner (room-side) pane", "x3",
                    warmer="a heat source at the inner glass (a heater or radiator below the "
                           "window newly running, equipment against the glass)",
                    cooler="cold air at the inner glass (a cooling diffuser aimed at it)"),
    "q_x4": _offset("the louver", "x4",
                    warmer="the slats take more sun than their read-back angle says (a "
                           "slipped step: compare the angle by eye with the read-back)",
                    cooler="the slats take less sun than their read-back angle says (a "
                           "slipped step: compare the angle by eye with the read-back)"),
    "f": {+1: f"the damper paths resist the air more than before: {_MORE_RESISTANCE}",
          -1: f"the damper paths resist the air less than before: {_LESS_RESISTANCE}"},
    "c": {+1: "the diagonal paths pass more air at the same pressure than before: "
              f"{_LESS_RESISTANCE}",
          -1: "the diagonal paths pass less air at the same pressure than before: "
              f"{_MORE_RESISTANCE}"},
    "n": {
        +1: "the diagonal paths' flow has become more laminar-like (n towards 1, as through "
            "narrow gaps: a clogging screen would do it), but n is weakly identifiable and "
            "trades against c: look at c and at the cavity speed's residual before acting",
        -1: "the diagonal paths' flow has become more orifice-like (n towards 0.5, as "
            "through wider openings: a torn screen or a damper opening further would do it), "
            "but n is weakly identifiable and trades against c: look at c and at the cavity "
            "speed's residual before acting"},
}


def parameter_action(name: str, *, side: int, shift: float, shift_sd: float,
                     unit: str = "") -> str:
    """What a person should check when calibrated parameter ``name`` has risen (``side``
    +1) or fallen (−1) by ``shift`` (in ``unit``; :data:`LOG_UNIT`: a natural log, told as a
    factor), ``shift_sd`` posterior sd."""
    direction = "risen" if side > 0 else "fallen"
    if unit == LOG_UNIT:
        size = f"×{math.exp(shift):.2f}"
    else:
        size = f"by {abs(shift):.3g}{' ' + unit if unit else ''}"
    head = f"{name} has {direction} {size} ({abs(shift_sd):.1f} sd of its daily spread)"
    meaning = PARAMETER_MEANING.get(name)
    if meaning is None:
        return (f"the calibrated {head}: the façade changed (glass, screen, dampers) or the "
                "sensors the fit rests on did")
    return f"{head}: {meaning[1 if side > 0 else -1]}"
