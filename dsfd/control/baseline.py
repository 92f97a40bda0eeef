"""Rule-based control: the comparison for the optimiser and its fallback.

Rules of the kind double-skin façades use today (CIBSE, *Natural ventilation in
non-domestic buildings*, AM10, 1996, as cited by the paper; OBC-style hysteresis):

* louver — in sun (façade beam above a threshold) it tracks the solar profile angle:
  parallel to the rays to admit the sun when heating, perpendicular to block it when
  cooling; with no sun it closes (the paper's night position, 90°);
* airflow regime — heating: inside circulation (1) while the cavity is warmer than the
  room by a margin, otherwise closed (10); cooling: outside circulation (3) while the
  cavity is warmer than outdoors, night flushing with outdoor air (7) when outdoors is
  much cooler than the room, otherwise closed; all thresholds with hysteresis;
* dampers fully open in an open regime, shut when closed.

Every choice is snapped to the actuator grid (18° louver steps) and to the regimes the
panel's dampers allow, and the decision carries a trace saying which rule fired.

While the room is occupied (``occupied=True``) two comfort rules of commercial shading follow
(docs/model.md#rule-comfort): a sun-tracking **cut-off** — when the beam the chosen position
would let through could exceed ``comfort.direct_sun_max_wm2``, the louver goes to the most
open motor position that blocks the direct beam (:func:`cut_off_position`) — and a **draught
limit** — no regime that blows cavity air into the room while that air (the cavity air now)
is colder than the supply-air limit. Unoccupied (the default), the rules are energy only.
"""

from __future__ import annotations

import math

import numpy as np

from dsfd.config.panel import Louver, PanelConfig
from dsfd.control.comfort import INFLOW_REGIMES
from dsfd.control.optimiser import Decision
from dsfd.physics.comfort_thermal import supply_air_min_c
from dsfd.physics.comfort_visual import cutoff_angles
from dsfd.physics.optics_slat_cell import direct_transmittance

__all__ = ["cut_off_position", "quantise_louver", "rule_decision"]

INSIDE_CIRCULATION, OUTSIDE_CIRCULATION, NIGHT_FLUSH, CLOSED = 1, 3, 7, 10


def quantise_louver(phi_deg: float, louver: Louver | None) -> float:
    """Nearest louver position the motor can reach [deg] (0 without a louver)."""
    if louver is None or not math.isfinite(phi_deg):
        return 0.0
    angles = np.asarray(louver.angles_deg())
    return float(angles[np.argmin(np.abs(angles - np.clip(phi_deg, -90.0, 90.0)))])


def cut_off_position(louver: Louver, profile_deg: float) -> float:
    """The most open motor position [deg] that blocks the direct beam at ``profile_deg``.

    The positions at or beyond either cut-off angle of the flat slats
    (:func:`dsfd.physics.comfort_visual.cutoff_angles`, docs/model.md#visual-comfort) block
    it; of those the one nearest to level (the widest view out), on the lower side (slats
    tilted against the sun) when two are as near. Where no position blocks it (slats
    narrower than the gap the ray sees), the one with the least beam transmittance.
    """
    angles = np.asarray(louver.angles_deg())
    cut = cutoff_angles(math.radians(profile_deg), width=louver.slat_width_m,
                        pitch=louver.slat_pitch_m)
    lower, upper = (math.degrees(float(v)) for v in cut)
    # (a hair of tolerance: a position exactly at the cut-off angle blocks the beam)
    blocks = np.zeros(angles.size, bool)
    if math.isfinite(lower):
        blocks |= angles <= lower + 1e-9
    if math.isfinite(upper):
        blocks |= angles >= upper - 1e-9
    if not blocks.any():
        tau = direct_transmittance(np.radians(angles), math.radians(profile_deg),
                                   width=louver.slat_width_m, pitch=louver.slat_pitch_m)
        return float(angles[int(np.argmin(tau))])
    candidates = angles[blocks]
    return float(min(candidates, key=lambda a: (abs(a), a)))


def _comfort_rules(cfg: PanelConfig, phi_deg: float, afr: int, *, t5_c: float | None,
                   beam_wm2: float, profile_deg: float, trace: list[str]) -> tuple[float, int]:
    """The occupied room's cut-off and draught rules (module docstring) on a choice."""
    lim, lv = cfg.comfort, cfg.louver
    if lv is not None:
        # The unscattered beam through the slats, before the glass takes its share: an
        # upper bound of the direct sun the position lets into the room.
        tau = float(direct_transmittance(math.radians(phi_deg), math.radians(profile_deg),
                                         width=lv.slat_width_m, pitch=lv.slat_pitch_m))
        if beam_wm2 * tau > lim.direct_sun_max_wm2:
            cut = cut_off_position(lv, profile_deg)
            trace.append(f"comfort: occupied, {beam_wm2 * tau:.0f} W/m2 of beam would pass "
                         f"the slats at {phi_deg:+.0f} deg -> cut-off {cut:+.0f} deg "
                         f"(profile {profile_deg:+.1f} deg)")
            phi_deg = cut
    air_min = supply_air_min_c(lim)
    if afr in INFLOW_REGIMES and t5_c is not None and t5_c < air_min:
        trace.append(f"comfort: occupied, cavity air {t5_c:.1f} < supply limit {air_min:.1f} "
                     f"°C -> closed (draught)")
        afr = CLOSED
    return phi_deg, afr


def rule_decision(cfg: PanelConfig, *, heating: bool, t5_c: float | None, t_in_c: float,
                  t_out_c: float, beam_wm2: float, profile_deg: float,
                  previous_afr: int | None = None, occupied: bool = False) -> Decision:
    """Baseline decision from the current measurements (°C, W/m2, deg at this boundary).

    Parameters
    ----------
    heating : bool
        Season of the objective.
    t5_c : float or None, [degC]
        Cavity air temperature; ``None`` when the sensor is not usable (then closed).
    t_in_c, t_out_c : float, [degC]
        Room and outdoor air.
    beam_wm2 : float, [W/m2]
        Beam irradiance on the façade plane.
    profile_deg : float, [deg]
        Solar profile angle on the façade.
    previous_afr : int, optional
        The regime now applied (for hysteresis).
    occupied : bool
        Whether the room is occupied now: the comfort rules apply (module docstring).
    """
    b = cfg.control.baseline
    trace = []
    sunny = beam_wm2 > b.sun_threshold_wm2
    if not sunny:
        phi = b.night_angle_deg
        trace.append(f"louver: no sun (beam {beam_wm2:.0f} W/m2) -> closed {phi:+.0f} deg")
    elif heating:
        phi = profile_deg
        trace.append(f"louver: heating in sun -> along the rays (profile {profile_deg:+.1f} deg)")
    else:
        phi = profile_deg - 90.0 if profile_deg >= 0 else profile_deg + 90.0
        trace.append(f"louver: cooling in sun -> across the rays ({phi:+.1f} deg)")
    phi_q = quantise_louver(phi, cfg.louver)

    was_open = previous_afr is not None and previous_afr != CLOSED
    band = b.hysteresis_k if was_open else 0.0
    if t5_c is None:
        afr = CLOSED
        trace.append("regime: cavity temperature unusable -> closed")
    elif heating:
        margin = b.heating_open_above_room_k - band
        if t5_c > t_in_c + margin:
            afr = INSIDE_CIRCULATION
            trace.append(f"regime: cavity {t5_c:.1f} > room {t_in_c:.1f} + {margin:.1f} K -> "
                         "inside circulation")
        else:
            afr = CLOSED
            trace.append("regime: cavity not warm enough -> closed")
    else:
        flush = b.cooling_flush_above_outdoor_k - band
        night = b.night_cooling_below_room_k - band
        if sunny and t5_c > t_out_c + flush:
            afr = OUTSIDE_CIRCULATION
            trace.append(f"regime: cavity {t5_c:.1f} > outdoor {t_out_c:.1f} + {flush:.1f} K -> "
                         "outside circulation")
        elif not sunny and t_out_c < t_in_c - night:
            afr = NIGHT_FLUSH
            trace.append(f"regime: outdoor {t_out_c:.1f} < room {t_in_c:.1f} - {night:.1f} K -> "
                         "night flush")
        else:
            afr = CLOSED
            trace.append("regime: no useful air exchange -> closed")
    if afr not in cfg.openings.available_regimes():
        trace.append(f"regime {afr} needs dampers this panel lacks -> closed")
        afr = CLOSED
    comfort = ""
    if occupied:
        n_before = len(trace)
        phi_q, afr = _comfort_rules(cfg, phi_q, afr, t5_c=t5_c, beam_wm2=beam_wm2,
                                    profile_deg=profile_deg, trace=trace)
        comfort = "; ".join(t.removeprefix("comfort: occupied, ") for t in trace[n_before:])
        comfort = comfort or "no comfort rule fired"
    or_pct = 0.0 if afr == CLOSED else 100.0
    return Decision(phi_deg=phi_q, afr=afr, or_pct=or_pct, method="rule", cost_j=math.nan,
                    trace=tuple(trace), comfort=comfort)
