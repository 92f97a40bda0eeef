"""Physical cross-checks that need no model (docs/model.md#diagnostics).

Pure functions over what the daemon stores (commands, readings):

* :func:`cavity_flow_check` — the cavity speed against the commanded regime: with every
  damper shut the cavity air barely moves; with an open path and a driving temperature
  difference it must move clearly more. Comparing the paths that move air with those that
  do not names the damper they have in common.
* :func:`night_pane_check` — a pane against the outdoor air at night: with no sun, each
  pane is a weighted mean of its neighbours (the room, the outdoor air, the sky), so its
  temperature lies between the sky's and the room's; and its offset from the outdoor air
  changes from night to night only with the weather.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dsfd.estimation.diagnostics import Cusum, Evidence, Finding, cusum_confidence

__all__ = ["FlowCheckSettings", "NightCheckSettings", "NightlyOffsets", "cavity_flow_check",
           "night_pane_check", "nightly_offsets"]


#: A damper set and the mask of its judged readings.
_Path = tuple[frozenset[str], np.ndarray]

@dataclass(frozen=True, kw_only=True)
class FlowCheckSettings:
    """Parameters of :func:`cavity_flow_check`.

    Attributes
    ----------
    min_samples : int
        Each damper set (and the closed cavity) is judged on its latest ``min_samples``
        readings (that it had to move air at, for an open path), and not before it has that
        many (15): a path is judged on what it does now, so a damper that sticks after its
        path flowed all morning is seen once about half of them are dead, not half of the
        day's. At the anemometer's noise (0.02 m/s sd) the median of 15 readings has a
        standard error of about 0.0065 m/s (1.25 σ/√n for the median of normal data), a
        third of the contrast below. 15 rather than 20: in cooling weather a stuck IT's
        interior loop had 19 readings in half a day that the model expected to flow.
    min_drive_k : float, [K]
        Without the model's expectation, an open path is judged only on readings with at
        least this driving temperature difference (3 K: a stack of a few kelvin moves
        ~0.1 m/s through the paper's façade).
    min_contrast_ms : float, [m/s]
        An open path "moves air" when its median speed exceeds the closed cavity's median
        (0 when the cavity was not closed) by this much (0.02 m/s). An unsigned anemometer
        at zero flow reads its noise clipped at zero, whose median is about 0; a path that
        moves air at all lifts the median above the noise sd (0.02 m/s). On the truth plant
        a winter supply path (EB → IT) moved 0.03–0.05 m/s (medians), the same path with a
        damper stuck shut 0.000–0.011 m/s.
    closed_max_ms : float, [m/s]
        A closed cavity whose median speed is above this moves air it should not (0.15 m/s).
    min_expected_ms : float, [m/s]
        Where the model's one-step prediction is given, an open path is judged on the
        readings it expected to be at least this fast (0.04 m/s, twice the contrast), and
        the drive is not asked: the calibrated model knows the path's physics (stack,
        wind, which way the room pulls) better than a temperature difference does. A path
        whose flow the model itself says is weak cannot be told from a dead one by an
        anemometer with 0.02 m/s of noise: a winter supply path (EB → IT) often runs
        against the room's stack at 0.01 m/s, healthy, and was called dead on the drive
        alone; with IT stuck shut the model expected 0.05-0.09 m/s where 0.00-0.015 m/s
        was read (bench diagnostics, winter seed 1). In cooling weather the same stuck
        damper's paths mostly had less than 3 K of drive while the model expected
        0.17 m/s through them.
    """

    min_samples: int = 15
    min_drive_k: float = 3.0
    min_contrast_ms: float = 0.02
    closed_max_ms: float = 0.15
    min_expected_ms: float = 0.04


def cavity_flow_check(times_s: np.ndarray, v_cav_ms: np.ndarray,
                      commanded_open: Sequence[frozenset[str]], drive_k: np.ndarray, *,
                      expected_ms: np.ndarray | None = None,
                      settings: FlowCheckSettings | None = None) -> Finding | None:
    """Does the cavity air move as the commanded dampers say it must?

    Parameters
    ----------
    times_s : array (n,), [s]
    v_cav_ms : array (n,), [m/s]
        Measured cavity speed (NaN where missing).
    commanded_open : sequence (n,) of frozenset of str
        The dampers commanded open at each reading (e.g. ``{"EB", "ET"}``; empty: closed).
    drive_k : array (n,), [K]
        Driving temperature difference of each reading, e.g. |cavity air − outdoor air|.
    expected_ms : array (n,), optional, [m/s]
        The calibrated model's one-step prediction of each reading (NaN: none; then the
        drive alone decides whether an open path's reading is judged).

    Returns
    -------
    Finding or None
        ``damper_no_flow`` naming the damper(s) every dead path shares and no live path uses;
        ``cavity_no_flow`` when the dead paths share no such damper (dampers, a clogged screen
        or the anemometer: the check cannot tell which); ``cavity_flow_when_closed`` when the
        closed cavity moves air.
    """
    st = settings or FlowCheckSettings()
    t = np.asarray(times_s, float)
    v = np.asarray(v_cav_ms, float)
    drive = np.asarray(drive_k, float)
    expected = np.full(v.shape, np.nan) if expected_ms is None else np.asarray(expected_ms,
                                                                             float)
    sets = [frozenset(s) for s in commanded_open]
    closed = _latest(np.array([not s for s in sets]) & np.isfinite(v), st.min_samples)
    base = 0.0
    if np.count_nonzero(closed) >= st.min_samples:
        base = float(np.median(v[closed]))
        if base > st.closed_max_ms:
            ev = Evidence(signal="crosscheck:v_cav_ms[closed]", shift=base, shift_sd=np.nan,
                          unit="m/s", since_s=float(t[closed][0]), statistic=base,
                          threshold=st.closed_max_ms)
            return Finding(kind="cavity_flow_when_closed", confidence=_share(
                v[closed] > st.closed_max_ms), start_s=ev.since_s,
                detected_s=float(t[closed][-1]), evidence=(ev,), action=(
                    f"the cavity air moves at {base:.2f} m/s with every damper commanded "
                    "shut: check for a damper stuck open, or the anemometer"))
    need = base + st.min_contrast_ms
    # readings an open path must move air at: what the model expected, else the drive
    should_move = np.where(np.isfinite(expected), expected >= st.min_expected_ms,
                           drive >= st.min_drive_k)
    live: list[_Path] = []
    dead: list[_Path] = []
    for s in sorted({s for s in sets if s}, key=sorted):
        judged = np.array([x == s for x in sets]) & np.isfinite(v) & should_move
        sel = _latest(judged, st.min_samples)
        if np.count_nonzero(sel) >= st.min_samples:
            if np.median(v[sel]) >= need:
                live.append((s, sel))
            else:
                dead.append((s, _dead_run(v, judged, need, st.min_samples)))
    if not dead:
        return None
    return _dead_paths(t, v, dead, live, base, need)


def _dead_run(v: np.ndarray, judged: np.ndarray, need: float, n: int) -> np.ndarray:
    """The judged readings of a dead path since it stopped moving air: its latest ``n`` and,
    going back, each earlier block of ``n`` whose median stays below ``need``, from the first
    reading below ``need`` of the earliest.

    They date the evidence from when the path stopped moving air, not from the first of the
    latest readings: that moves on with every reading, and an acknowledged finding whose
    evidence seemed to start after the acknowledgement came back although the same damper
    had stayed stuck all along (docs/model.md#findings).
    """
    idx = np.flatnonzero(judged)
    start = idx.size - n
    while start - n >= 0 and np.median(v[idx[start - n:start]]) < need:
        start -= n
    while start < idx.size - n and v[idx[start]] >= need:  # the earliest block's live part
        start += 1
    out = np.zeros_like(judged, dtype=bool)
    out[idx[start:]] = True
    return out


def _dead_paths(t: np.ndarray, v: np.ndarray, dead: list[_Path], live: list[_Path],
                base: float, need: float) -> Finding:
    """The finding of paths that moved no air: the damper every dead path shares and no
    live path uses, else the paths without a common cause."""
    evidence = tuple(Evidence(
        signal=f"crosscheck:v_cav_ms[{'+'.join(sorted(s))}]",
        shift=float(np.median(v[sel])) - base, shift_sd=np.nan, unit="m/s",
        since_s=float(t[sel][0]), statistic=float(np.median(v[sel])), threshold=need)
        for s, sel in dead)
    suspects = frozenset.intersection(*(s for s, _ in dead)) - frozenset().union(
        *(s for s, _ in live))
    all_dead = np.logical_or.reduce([sel for _, sel in dead])
    common = dict(confidence=_share(v[all_dead] < need),
                  start_s=min(e.since_s for e in evidence),
                  detected_s=float(t[all_dead][-1]), evidence=evidence)
    if suspects:
        names = ", ".join(sorted(suspects))
        return Finding(kind="damper_no_flow", **common, subject="+".join(sorted(suspects)),
                       action=(
            f"no air through the paths that need damper {names}, while "
            + ("the other paths move air" if live else "no other path was tried")
            + f": check damper {names} (its blade may not follow its motor)"
            + ("" if live else "; a clogged screen or the anemometer would look the same")))
    return Finding(kind="cavity_no_flow", **common, action=(
        "open paths move no more air than the closed cavity: check the dampers, the insect "
        "screens and the anemometer (this check cannot tell which)"))


def _latest(mask: np.ndarray, n: int) -> np.ndarray:
    """``mask`` with only its last ``n`` True entries kept (the readings in time order)."""
    idx = np.flatnonzero(mask)
    out = np.zeros_like(mask, dtype=bool)
    out[idx[-n:]] = True
    return out


def _share(mask: np.ndarray) -> float:
    return float(np.mean(mask)) if mask.size else 0.0


@dataclass(frozen=True, kw_only=True)
class NightCheckSettings:
    """Parameters of :func:`night_pane_check`.

    Attributes
    ----------
    sky_depression_k : float, [K]
        How far below the outdoor air a pane may sit at night (8 K: a clear sky's effective
        temperature is 10–30 K below the air, and the pane, also held by the air and the
        room, sits well above it) [ENG].
    tolerance_k : float, [K]
        Allowance above the room temperature (sensor bias, thermal lag) (1 K).
    min_samples : int
        Readings a night needs (30).
    split_s : float, [s]
        A pause longer than this starts a new night (2 h).
    reference_nights, min_reference_nights : int
        The trailing nights a night is compared with (14), and how many are needed (7).
    k_sd, h_sd : float
        CUSUM allowance and threshold on the nightly medians in the reference's sample sd
        (1.5 and 6: the sd of a week or two of nights is itself uncertain, so z has heavier
        tails than a normal; a shift of five sd is found within two or three nights).
    floor_k : float, [K]
        Least spread of the nightly medians (0.2 K).
    """

    sky_depression_k: float = 8.0
    tolerance_k: float = 1.0
    min_samples: int = 20
    split_s: float = 7200.0
    reference_nights: int = 14
    min_reference_nights: int = 7
    k_sd: float = 1.5
    h_sd: float = 6.0
    floor_k: float = 0.2


def _nights(t: np.ndarray, night: np.ndarray, split_s: float) -> list[np.ndarray]:
    idx = np.flatnonzero(night)
    if idx.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(t[idx]) > split_s) + 1
    return np.split(idx, cuts)


def _night_cusum(medians: np.ndarray, st: NightCheckSettings) -> tuple[Cusum, np.ndarray]:
    """Two-sided CUSUM of the nightly medians, each standardised by the nights before it;
    while either side is above zero the reference stays where the excursion began, so a
    step is not absorbed into its own reference before it is found."""
    z = np.full(medians.size, np.nan)
    stat = np.zeros(medians.size)
    s_pos = s_neg = 0.0
    zero = [0, 0]  # index after each side's last zero
    for i in range(medians.size):
        end = min(zero) if s_pos > 0 or s_neg > 0 else i
        ref = medians[max(0, end - st.reference_nights):end]
        if ref.size >= st.min_reference_nights:
            # a handful of nights: the sample sd is the steadier estimate (MAD of five
            # values is often far too small); the median keeps one odd night from the centre
            z[i] = ((medians[i] - float(np.median(ref)))
                    / max(float(np.std(ref, ddof=1)), st.floor_k))
            s_pos = max(0.0, s_pos + z[i] - st.k_sd)
            s_neg = max(0.0, s_neg - z[i] - st.k_sd)
        zero = [i + 1 if s_pos == 0.0 else zero[0], i + 1 if s_neg == 0.0 else zero[1]]
        stat[i] = max(s_pos, s_neg)
        if max(s_pos, s_neg) > st.h_sd:
            side = 1 if s_pos >= s_neg else -1
            return Cusum(i, side, zero[0] if side > 0 else zero[1], stat[:i + 1]), z
    return Cusum(None, 0, medians.size, stat), z


@dataclass(frozen=True, eq=False)
class NightlyOffsets:
    """The nights :func:`night_pane_check` judges: per night the indices of its readings,
    the median of pane − outdoor air and the upper bound (the room's median excess over the
    outdoor air + ``tolerance_k``) [K]; the lower bound is −``sky_depression_k``. ``offset_k``
    is pane − outdoor air of every reading (NaN where it is not judged)."""

    nights: list[np.ndarray]
    medians: np.ndarray
    upper_k: np.ndarray
    offset_k: np.ndarray


def nightly_offsets(times_s: np.ndarray, pane_c: np.ndarray, t_out_c: np.ndarray,
                    t_room_c: np.ndarray, night: np.ndarray, *,
                    settings: NightCheckSettings | None = None) -> NightlyOffsets:
    """The nights with enough readings and their median offsets (the first step of
    :func:`night_pane_check`; ``dsfd report`` draws them)."""
    st = settings or NightCheckSettings()
    t = np.asarray(times_s, float)
    d = np.asarray(pane_c, float) - np.asarray(t_out_c, float)
    span = np.asarray(t_room_c, float) - np.asarray(t_out_c, float)
    ok = np.isfinite(d) & np.isfinite(span) & np.asarray(night, bool)
    nights = [n for n in _nights(t, ok, st.split_s) if n.size >= st.min_samples]
    return NightlyOffsets(nights, np.array([np.median(d[n]) for n in nights]),
                          np.array([float(np.median(span[n])) + st.tolerance_k
                                    for n in nights]), np.where(ok, d, np.nan))


def night_pane_check(times_s: np.ndarray, pane_c: np.ndarray, t_out_c: np.ndarray,
                     t_room_c: np.ndarray, night: np.ndarray, *, pane: str = "x1_c",
                     settings: NightCheckSettings | None = None) -> Finding | None:
    """A pane's temperature against the outdoor air at night.

    Parameters
    ----------
    times_s : array (n,), [s]
    pane_c, t_out_c, t_room_c : array (n,), [°C]
        The pane's, the outdoor air's and the room air's readings.
    night : array (n,) of bool
        Readings with no sun on the façade (and an hour or two after sunset, so the day's
        heat has left the panes).
    pane : str
        The pane's signal name, for the evidence.

    Returns
    -------
    Finding or None
        ``pane_out_of_bounds`` for the first night whose median pane temperature lies
        below the outdoor air by more than ``sky_depression_k`` or above the room by more
        than ``tolerance_k``; else ``pane_offset_shift`` when the nightly median offset
        pane − outdoor air changes (CUSUM over nights); else None.
    """
    st = settings or NightCheckSettings()
    t = np.asarray(times_s, float)
    o = nightly_offsets(t, pane_c, t_out_c, t_room_c, night, settings=st)
    nights, medians = o.nights, o.medians
    signal = f"crosscheck:{pane}-t_out_c"
    who = f"the {pane} thermocouple or the outdoor-air sensor (this check cannot tell which)"
    for n, m, upper in zip(nights, medians, o.upper_k, strict=True):
        if m < -st.sky_depression_k or m > upper:
            limit = -st.sky_depression_k if m < 0 else upper
            ev = Evidence(signal=signal, shift=float(m - limit), shift_sd=np.nan, unit="K",
                          since_s=float(t[n[0]]), statistic=float(m), threshold=limit)
            return Finding(kind="pane_out_of_bounds", confidence=1.0, start_s=ev.since_s,
                           detected_s=float(t[n[-1]]), evidence=(ev,), action=(
                               f"at night {pane} reads {m:+.1f} K from the outdoor air, "
                               f"outside what a pane between the sky and the room can: "
                               f"check {who}"))
    cs, z = _night_cusum(medians, st)
    if cs.alarm is None:
        return None
    first = nights[cs.start]
    shift = float(np.mean(medians[cs.start:cs.alarm + 1])
                  - np.median(medians[max(0, cs.start - st.reference_nights):cs.start]))
    ev = Evidence(signal=signal, shift=shift, shift_sd=float(np.nanmean(z[cs.start:cs.alarm + 1])),
                  unit="K", since_s=float(t[first[0]]), statistic=float(cs.statistic[-1]),
                  threshold=st.h_sd)
    return Finding(kind="pane_offset_shift", confidence=cusum_confidence(ev.statistic, st.h_sd),
                   start_s=ev.since_s, detected_s=float(t[nights[cs.alarm][-1]]),
                   evidence=(ev,), action=(f"at night {pane} sits {shift:+.2f} K from where it "
                                           f"sat on the nights before: check {who}"))
