"""Physical cross-checks (docs/model.md#diagnostics): the cavity speed against the commanded
regime, a pane against the outdoor air at night."""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.estimation.crosschecks import cavity_flow_check, night_pane_check

EXT, INT, DIAG, CLOSED = (frozenset({"EB", "ET"}), frozenset({"IB", "IT"}),
                          frozenset({"IB", "ET"}), frozenset())
T0 = 1_640_995_200.0


def _flow_day(speeds: dict[frozenset, float], *, seed: int = 0, n: int = 120,
              drive_k: float = 8.0):
    """``n`` one-minute readings per damper set in turn, speed ~ N(mean, 0.02) ≥ 0."""
    rng = np.random.default_rng(seed)
    sets, v = [], []
    for s, mean in speeds.items():
        sets += [s] * n
        v.append(np.clip(mean + 0.02 * rng.standard_normal(n), 0.0, None))
    v = np.concatenate(v)
    return T0 + 60.0 * np.arange(v.size), v, sets, np.full(v.size, drive_k)


def test_a_damper_that_no_flowing_path_uses_is_named():
    """EB stuck shut: the exterior path is dead, the interior and diagonal ones move air."""
    t, v, sets, drive = _flow_day({CLOSED: 0.02, EXT: 0.0, INT: 0.20, DIAG: 0.15})
    f = cavity_flow_check(t, v, sets, drive)
    assert f is not None and f.kind == "damper_no_flow"
    assert "check damper EB" in f.action
    ev, = f.evidence
    assert ev.signal == "crosscheck:v_cav_ms[EB+ET]" and ev.unit == "m/s"
    assert ev.statistic < ev.threshold
    # judged on the path's latest 15 readings, dated from when the path stopped moving air:
    # every one of its two hours here
    first_ext = min(i for i, x in enumerate(sets) if x == EXT)
    assert ev.since_s == t[first_ext]
    assert f.confidence > 0.9


def test_the_evidence_of_a_damper_that_stays_stuck_keeps_its_start():
    """EB sticks shut after the exterior path flowed for two hours. As the stuck readings go
    on, the finding keeps dating from the sticking (within 15 readings of it), not
    from the first of the latest 15, which moved on with every reading: an acknowledged
    finding's evidence then seemed to start after the acknowledgement, and the same stuck
    damper was filed again (the MQTT findings test on a loaded machine)."""
    t, v, sets, drive = _flow_day({CLOSED: 0.02, EXT: 0.25, INT: 0.20})
    stuck_t, stuck_v, stuck_sets, stuck_drive = _flow_day({EXT: 0.0}, seed=3, n=120)
    stuck_at = t[-1] + 60.0
    t = np.concatenate([t, stuck_t + (stuck_at - T0)])
    v, sets = np.concatenate([v, stuck_v]), sets + stuck_sets
    drive = np.concatenate([drive, stuck_drive])
    starts = []
    for end in range(len(sets) - 100, len(sets) + 1, 7):
        f = cavity_flow_check(t[:end], v[:end], sets[:end], drive[:end])
        assert f is not None and f.kind == "damper_no_flow"
        starts.append(f.start_s)
    assert all(stuck_at <= s < stuck_at + 15 * 60.0 for s in starts), starts


def test_a_damper_that_sticks_after_its_path_flowed_is_found_on_the_recent_readings():
    """EB sticks shut after the exterior path flowed for two hours: the day's median of the
    path is still that of a flowing path, its latest readings are not."""
    t, v, sets, drive = _flow_day({CLOSED: 0.02, EXT: 0.25, INT: 0.20})
    stuck_t, stuck_v, stuck_sets, stuck_drive = _flow_day({EXT: 0.0}, seed=2, n=15)
    t = np.concatenate([t, stuck_t + (t[-1] - T0) + 60.0])
    v = np.concatenate([v, stuck_v])
    sets, drive = sets + stuck_sets, np.concatenate([drive, stuck_drive])
    ext = np.array([s == EXT for s in sets])
    assert np.median(v[ext]) > 0.2  # the whole day's readings of the path: flowing
    f = cavity_flow_check(t, v, sets, drive)
    assert f is not None and f.kind == "damper_no_flow" and "check damper" in f.action
    assert set(f.subject.split("+")) <= {"EB", "ET"}  # no flowing path uses them
    # the median of the latest 15 turns once 8 of them are dead: 7 are not enough
    for dead, found in ((7, False), (8, True)):
        end = len(sets) - 15 + dead
        f = cavity_flow_check(t[:end], v[:end], sets[:end], drive[:end])
        assert (f is not None) == found, dead


def test_a_path_the_model_expects_to_be_weak_is_not_judged_one_it_expects_to_flow_is():
    """A supply path against the room's stack: 0.01 m/s read, the model expecting about
    that, is healthy; the same readings where the model expected 0.06 m/s are a dead path."""
    t, v, sets, drive = _flow_day({CLOSED: 0.0, EXT: 0.01, INT: 0.20}, seed=3)
    ext = np.array([s == EXT for s in sets])
    weak = np.where(ext, 0.012, 0.2)
    assert cavity_flow_check(t, v, sets, drive, expected_ms=weak) is None
    f = cavity_flow_check(t, v, sets, drive, expected_ms=np.where(ext, 0.06, 0.2))
    assert f is not None and f.kind == "damper_no_flow"
    # no prediction stored (NaN): the drive alone decides, as before
    nan = np.full(v.size, np.nan)
    assert cavity_flow_check(t, v, sets, drive, expected_ms=nan) == \
        cavity_flow_check(t, v, sets, drive)


def test_a_healthy_cavity_gives_nothing():
    t, v, sets, drive = _flow_day({CLOSED: 0.02, EXT: 0.25, INT: 0.20, DIAG: 0.15})
    assert cavity_flow_check(t, v, sets, drive) is None
    # a weak path (a winter supply path moves 0.03-0.05 m/s) is weak, not dead
    t, v, sets, drive = _flow_day({EXT: 0.04, INT: 0.20}, seed=1)
    assert cavity_flow_check(t, v, sets, drive) is None


def test_an_open_path_without_drive_is_not_judged():
    t, v, sets, drive = _flow_day({CLOSED: 0.02, EXT: 0.02, INT: 0.20}, drive_k=1.0)
    assert cavity_flow_check(t, v, sets, drive) is None


def test_dead_paths_with_no_damper_in_common_cannot_be_told_apart():
    t, v, sets, drive = _flow_day({CLOSED: 0.02, EXT: 0.03, INT: 0.02})
    f = cavity_flow_check(t, v, sets, drive)
    assert f is not None and f.kind == "cavity_no_flow"
    assert "cannot tell which" in f.action and len(f.evidence) == 2


def test_a_single_dead_path_says_what_else_looks_the_same():
    t, v, sets, drive = _flow_day({CLOSED: 0.02, EXT: 0.02})
    f = cavity_flow_check(t, v, sets, drive)
    assert f is not None and f.kind == "damper_no_flow"
    assert "damper EB, ET" in f.action and "clogged screen or the anemometer" in f.action


def test_a_closed_cavity_that_moves_air():
    t, v, sets, drive = _flow_day({CLOSED: 0.30, INT: 0.35})
    f = cavity_flow_check(t, v, sets, drive)
    assert f is not None and f.kind == "cavity_flow_when_closed"
    assert f.evidence[0].statistic == pytest.approx(0.30, abs=0.01)


# --------------------------------------------------------------------------------- night
def _nights(n_nights: int, seed: int, *, step_k: float = 0.0, step_night: int = 10,
            offset_k: float = 0.0):
    """Hourly readings over ``n_nights`` days; nights 20-06 h. The exterior pane sits
    0.5 ± 0.3 K (night to night) above the outdoor air, ± 0.2 K noise; room 21 °C."""
    rng = np.random.default_rng(seed)
    t = T0 + 600.0 * np.arange(n_nights * 144)
    day = ((t - T0) // 86400).astype(int)
    hour = (t - T0) / 3600.0 % 24
    night = (hour >= 20) | (hour < 6)
    t_out = 2.0 + 4.0 * np.sin(2 * np.pi * hour / 24) + rng.normal(0, 0.5, n_nights)[day]
    nightly = rng.normal(0.5, 0.3, n_nights + 1)
    # a night runs 20-06 h across midnight: its offset is that of the evening's day
    night_id = np.where(hour >= 20, day, day - 1).clip(0)
    pane = t_out + nightly[night_id] + 0.2 * rng.standard_normal(t.size) + offset_k
    pane = pane + np.where(night_id >= step_night, step_k, 0.0)
    return t, pane, t_out, np.full(t.size, 21.0), night


@pytest.mark.parametrize("seed", range(5))
def test_quiet_nights_give_nothing(seed):
    t, pane, t_out, room, night = _nights(60, seed)
    assert night_pane_check(t, pane, t_out, room, night) is None


@pytest.mark.parametrize("seed", range(3))
def test_a_thermocouple_step_shows_against_the_outdoor_air_at_night(seed):
    t, pane, t_out, room, night = _nights(20, seed, step_k=1.5, step_night=12)
    f = night_pane_check(t, pane, t_out, room, night, pane="x1_c")
    assert f is not None and f.kind == "pane_offset_shift"
    first_night = T0 + 12 * 86400 + 20 * 3600
    assert f.start_s == first_night  # the evening the step began
    assert first_night <= f.detected_s <= first_night + 6 * 86400
    assert f.evidence[0].shift == pytest.approx(1.5, abs=0.6)
    assert "x1_c thermocouple or the outdoor-air sensor" in f.action
    t, pane, t_out, room, night = _nights(12, seed, step_k=1.5, step_night=12)
    assert night_pane_check(t, pane, t_out, room, night) is None  # before: nothing


@pytest.mark.parametrize(("offset_k", "bound"), [(-10.0, -8.0), (25.0, None)])
def test_a_pane_outside_sky_and_room_is_out_of_bounds(offset_k, bound):
    t, pane, t_out, room, night = _nights(3, 0, offset_k=offset_k)
    f = night_pane_check(t, pane, t_out, room, night)
    assert f is not None and f.kind == "pane_out_of_bounds"
    ev = f.evidence[0]
    if bound is not None:
        assert ev.threshold == bound and ev.statistic < bound
    else:  # above the room: the limit is the room minus the outdoor air, plus 1 K
        assert ev.statistic > ev.threshold > 10.0
