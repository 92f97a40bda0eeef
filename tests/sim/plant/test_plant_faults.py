"""Slow faults of the truth plant (docs/faults.md#simulated-faults): each changes the physics
(or the reading) by what its definition says, from its start and not before."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dsfd.physics.constants import T_ZERO
from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.faults import DAMPERS, parse_fault
from dsfd.sim.plant.plant import Plant
from tests.sim.conftest import HOUR, day_start

OPTIONS = PlantOptions(n_segments=2)
IDEAL = OPTIONS.replace(sensors="ideal")
X0 = np.full(6, T_ZERO + 5.0)  # the same start for plants whose flows differ
EXTERIOR_PATH = Command(0.0, 3, 100.0)  # EB + ET open


def _sunny(rmis) -> float:
    """09:00 at the site on the clear second day (the sun on the façade until ~17 h)."""
    return day_start(rmis, 1) + 9 * HOUR


def _pair(suwon, rmis, *faults: str, options: PlantOptions = OPTIONS,
          command: Command = EXTERIOR_PATH, start: float | None = None):
    """A clean plant and the same plant (same seed) with ``faults``, both reset alike."""
    start = _sunny(rmis) if start is None else start
    out = []
    for specs in ((), tuple(parse_fault(f) for f in faults)):
        p = Plant(suwon, options, seed=0, weather_series=rmis, faults=specs)
        p.reset(start, command=command, x0=X0)
        out.append(p)
    return out


def _solar(p: Plant) -> tuple[float, float]:
    """Absorbed (∫S_abs) and transmitted solar into the room since the reset [J]."""
    return p.energy_balance()["solar_j"], p.room_heat_j()["q_sol_trans"]


def test_soiling_cuts_every_solar_gain_by_its_fraction_after_the_start_only(suwon, rmis):
    rate_pct_per_day = 48.0  # 2 % per hour: well visible within a test's hours
    clean, dirty = _pair(suwon, rmis, f"soiling:+1h:{rate_pct_per_day}")
    for p in (clean, dirty):
        p.advance(HOUR)
    assert _solar(dirty) == _solar(clean)  # before the start: the same plant, bit for bit
    assert _solar(clean)[0] > 1e5  # and the sun is on the façade
    onset = clean.time_s
    for _ in range(12):  # ten-minute intervals over two hours after the start
        before = [_solar(p) for p in (clean, dirty)]
        for p in (clean, dirty):
            p.advance(600.0)
        mid_days = (clean.time_s - 300.0 - onset) / 86400.0
        expected = 1.0 - rate_pct_per_day / 100.0 * mid_days
        for k in range(2):  # absorbed, transmitted
            d_clean = _solar(clean)[k] - before[0][k]
            d_dirty = _solar(dirty)[k] - before[1][k]
            # the factor changes by 0.33 % over an interval; the mid value is exact to 1e-5
            assert d_dirty == pytest.approx(expected * d_clean, rel=2e-4)
    assert expected < 0.97


def test_a_clogged_screen_scales_the_path_resistance(suwon, rmis):
    """An orifice path's mass flow goes as 1/sqrt(resistance): resistance × 4 halves it.
    The factor ramps as 1 + rate·days: rate 3 per day started a day ago gives 4."""
    start = _sunny(rmis)
    from dsfd.measured import iso_utc

    day_ago = iso_utc(start - 86400.0)
    clean, clogged = _pair(suwon, rmis, f"screen:{day_ago}:3", start=start)
    m_clean = clean.true_state().m_dot_kgs
    m_clog = clogged.true_state().m_dot_kgs
    assert np.count_nonzero(m_clean) == 2 and abs(m_clean).max() > 1e-3
    np.testing.assert_allclose(m_clog, m_clean / 2.0, rtol=1e-9)
    # a screen that starts clogging in an hour changes nothing yet
    clean, later = _pair(suwon, rmis, "screen:+1h:3", start=start)
    np.testing.assert_array_equal(later.true_state().m_dot_kgs, clean.true_state().m_dot_kgs)


def test_a_damper_stuck_shut_blocks_its_path_while_reading_back_the_command(suwon, rmis):
    """EB stuck at 0 % under regime 3 (EB + ET): no path through the cavity, as a clean
    plant commanded closed; the read-back reports the command."""
    start = _sunny(rmis)
    clean, stuck = _pair(suwon, rmis, "damper-stuck.EB:+30min:0", start=start)
    closed = Plant(suwon, OPTIONS, seed=0, weather_series=rmis)
    closed.reset(start, command=Command(0.0, 10, 100.0), x0=X0)
    for p in (clean, stuck, closed):
        p.advance(1800.0)
    # before the start: the stuck plant is the clean one
    np.testing.assert_array_equal(stuck.true_state().m_dot_kgs, clean.true_state().m_dot_kgs)
    assert abs(clean.true_state().m_dot_kgs).max() > 1e-3
    executed = stuck.apply(Command(0.0, 3, 100.0))
    assert executed == Command(0.0, 3, 100.0)  # the position switch reports the command
    for p in (clean, stuck, closed):
        p.advance(HOUR)
    st = stuck.true_state()
    assert st.dampers[DAMPERS.index("EB")] == 0.0
    assert st.dampers[DAMPERS.index("ET")] == pytest.approx(1.0)
    assert np.all(st.m_dot_kgs == 0.0) and np.all(closed.true_state().m_dot_kgs == 0.0)
    assert stuck.command == Command(0.0, 3, 100.0)


def test_a_damper_stuck_open_adds_its_path(suwon, rmis):
    """EB stuck at 60 % under regime 1 (IB + IT): EB carries flow although commanded shut,
    and its blade sits at 60 %."""
    clean, stuck = _pair(suwon, rmis, "damper-stuck.EB:+0s:60",
                         command=Command(0.0, 1, 100.0))
    for p in (clean, stuck):
        p.advance(600.0)
    eb = DAMPERS.index("EB")
    assert clean.true_state().m_dot_kgs[eb] == 0.0
    st = stuck.true_state()
    assert st.dampers[eb] == pytest.approx(0.6, abs=1e-4)
    assert abs(st.m_dot_kgs[eb]) > 1e-4
    assert stuck.command.afr == 1


def test_a_slipped_louver_sits_one_step_off_and_absorbs_as_that_angle(suwon, rmis):
    """louver-slip by +1 step: commanded 0° the slats sit at 18°, and the plant absorbs the
    sun exactly as a clean plant commanded 18°; at the end stop (90°) they stay at 90°."""
    start = _sunny(rmis)
    clean_18, slipped = _pair(suwon, rmis, "louver-slip:+0s:1", start=start,
                              command=Command(18.0, 10, 100.0))
    slipped.reset(start, command=Command(0.0, 10, 100.0), x0=X0)
    assert slipped.true_state().phi_deg == 18.0
    assert slipped.command.phi_deg == 0.0
    for p in (clean_18, slipped):
        p.advance(HOUR)
    a, b = _solar(clean_18), _solar(slipped)
    assert b[0] == pytest.approx(a[0], rel=1e-9) and b[1] == pytest.approx(a[1], rel=1e-9)
    assert slipped.apply(Command(90.0, 10, 100.0)).phi_deg == 90.0
    slipped.advance(60.0)
    assert slipped.true_state().phi_deg == 90.0


def test_a_louver_slip_starts_at_its_start(suwon, rmis):
    _, slipped = _pair(suwon, rmis, "louver-slip:+10min:-1",
                           command=Command(36.0, 10, 100.0))
    slipped.advance(540.0)
    assert slipped.true_state().phi_deg == 36.0
    slipped.advance(120.0)  # the motor needs 6 s for a step
    assert slipped.true_state().phi_deg == 18.0
    assert slipped.command.phi_deg == 36.0


@pytest.mark.parametrize(("fault", "sensor"), [("tc-drift.x3:+1h:0.5", "x3_c"),
                                              ("tc-offset.t_out:+1h:-1.5", "t_out_c"),
                                              ("anemometer:+1h:0.7", "v_cav_ms")])
def test_faulty_sensors_read_truth_changed_by_the_fault(suwon, rmis, fault, sensor):
    """With ideal sensors the reading is the truth until the start, then truth + drift·t,
    truth + offset or factor × truth."""
    spec = parse_fault(fault)
    p = Plant(suwon, IDEAL, seed=0, weather_series=rmis, faults=(spec,))
    start = _sunny(rmis)
    p.reset(start, command=Command(0.0, 3, 100.0))
    checked = 0
    for _ in range(8):
        p.advance(900.0)
        st = p.true_state()
        truth = {"x3_c": st.x_sensor_k[2] - T_ZERO, "v_cav_ms": abs(st.v_probe_ms),
                 "t_out_c": p.station_weather()["t_out_c"]}[sensor]
        reading = p.read_sensors()[sensor]
        since_s = p.time_s - (start + HOUR)
        if since_s < 0:
            assert reading == pytest.approx(truth, abs=1e-12)
            continue
        checked += 1
        expected = {"tc-drift": truth + spec.rate * since_s / 86400.0,
                    "tc-offset": truth + spec.rate,
                    "anemometer": spec.rate * truth}[spec.kind]
        assert reading == pytest.approx(expected, abs=1e-12)
        assert not math.isclose(reading, truth, abs_tol=1e-6) or since_s == 0
    assert checked == 5


def test_a_louver_slip_needs_a_louver(suwon, rmis):
    import dataclasses

    bare = dataclasses.replace(suwon, louver=None)
    with pytest.raises(ValueError, match="the panel has no louver"):
        Plant(bare, OPTIONS, seed=0, weather_series=rmis,
              faults=(parse_fault("louver-slip:+0s:1"),))
