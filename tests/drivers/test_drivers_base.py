"""Readings, samples, commands, write results, the composite driver (pure logic), policies."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import FrozenInstanceError

import pytest

from dsfd.drivers.base import (
    Command,
    CompositeDriver,
    Driver,
    Quality,
    Reading,
    Sample,
    WriteResult,
    command_from_values,
)
from dsfd.drivers.resilience import Backoff, CircuitBreaker
from dsfd.signals import ACTUATOR_NAMES, SENSOR_NAMES, SIGNALS, signal


def test_signal_catalogue() -> None:
    assert set(SENSOR_NAMES) == {"x1_c", "x2_c", "x3_c", "x4_c", "x5_c", "t_room_c", "t_out_c",
                                 "ghi_wm2", "wind_speed_ms", "wind_dir_deg", "v_cav_ms",
                                 "rh_pct", "pressure_hpa", "occupied"}
    assert ACTUATOR_NAMES == ("phi_deg", "afr", "or_pct")
    assert (signal("phi_deg").lower, signal("phi_deg").upper) == (-90.0, 90.0)
    assert signal("afr").integer and (signal("afr").lower, signal("afr").upper) == (1, 10)
    assert signal("v_cav_ms").lower == 0.0  # unsigned anemometer
    assert all(s.lower < s.upper for s in SIGNALS.values())
    assert not signal("rh_pct").plausible(math.nan)
    # a 0/1 signal: a register reading 0.5 or 2 is a mis-mapping, not a state
    occupied = signal("occupied")
    assert occupied.plausible(0.0) and occupied.plausible(1.0)
    assert not occupied.plausible(0.5) and not occupied.plausible(2.0)
    with pytest.raises(KeyError, match="known"):
        signal("t_out_f")


def test_reading_and_sample_helpers() -> None:
    s = Sample(5.0, {"x1_c": Reading.good(20.5, "io"),
                     "x2_c": Reading.bad(Quality.TIMEOUT, "io", "io: input register 2")})
    assert s.good("x1_c") == 20.5
    assert s.good("x2_c") is None and s.good("absent") is None
    assert s.quality("absent") is Quality.MISSING
    assert set(s.bad()) == {"x2_c"}
    assert math.isnan(s.readings["x2_c"].value)
    assert Reading.good(math.inf, "io").quality is Quality.NOT_FINITE
    with pytest.raises(TypeError):
        s.readings["x3_c"] = Reading.good(1.0, "io")  # type: ignore[index]
    with pytest.raises(FrozenInstanceError):
        s.time_s = 1.0  # type: ignore[misc]
    with pytest.raises(ValueError):
        Reading.bad(Quality.GOOD, "io", "")


def test_command_validation_and_read_back() -> None:
    cmd = Command(phi_deg=18, afr=3.0, or_pct=40)  # type: ignore[arg-type]
    assert cmd.afr == 3 and isinstance(cmd.afr, int)
    for bad in ({"phi_deg": 91}, {"afr": 0}, {"afr": 2.5}, {"or_pct": math.nan},
                {"or_pct": -1}, {"afr": True}):
        kw = {"phi_deg": 0.0, "afr": 1, "or_pct": 0.0} | bad
        with pytest.raises(ValueError):
            Command(**kw)  # type: ignore[arg-type]
    assert command_from_values({"phi_deg": 18.0, "afr": 3.0, "or_pct": 40.0}) == cmd
    assert command_from_values({"phi_deg": 18.0, "afr": 3.0}) is None
    assert command_from_values({"phi_deg": 18.0, "afr": 0.0, "or_pct": 1.0}) is None


def test_write_result_ok_and_merge() -> None:
    cmd = Command(phi_deg=0.0, afr=1, or_pct=0.0)
    a = WriteResult(requested=cmd, owned=frozenset({"phi_deg"}), written={"phi_deg": 0.0},
                    verified=frozenset({"phi_deg"}))
    b = WriteResult(requested=cmd, owned=frozenset({"afr", "or_pct"}), written={"afr": 1.0},
                    verified=frozenset({"afr"}), errors=("dampers: read-back differs",))
    assert a.ok and not b.ok
    m = a.merged(b)
    assert m.owned == {"phi_deg", "afr", "or_pct"} and m.verified == {"phi_deg", "afr"}
    assert m.errors == ("dampers: read-back differs",) and not m.ok


class MemoryDriver:
    """In-memory driver for composite logic (no I/O involved)."""

    def __init__(self, name: str, sensors: dict[str, float], actuators: tuple[str, ...] = ()):
        self.name = name
        self.values = sensors
        self.commanded: dict[str, float] = {}
        self._actuators = actuators
        self.closed = False

    @property
    def sensor_names(self) -> frozenset[str]:
        return frozenset(self.values)

    @property
    def actuator_names(self) -> frozenset[str]:
        return frozenset(self._actuators)

    async def start(self) -> None:
        pass

    async def read(self, time_s: float) -> Sample:
        return Sample(time_s, {k: Reading.good(v, self.name) for k, v in self.values.items()})

    async def write(self, cmd: Command) -> WriteResult:
        mine = {k: v for k, v in cmd.as_dict().items() if k in self._actuators}
        self.commanded.update(mine)
        return WriteResult(requested=cmd, owned=self.actuator_names, written=mine,
                           verified=frozenset(mine), read_back=mine)

    async def read_actuators(self) -> Mapping[str, float]:
        return dict(self.commanded)

    async def read_back(self) -> Command | None:
        return command_from_values(self.commanded)

    @property
    def override_input(self) -> str | None:
        return None

    async def read_override_input(self) -> bool | None:
        return None

    async def close(self) -> None:
        self.closed = True


def test_composite_merges_samples_and_routes_actuators(run) -> None:
    louver = MemoryDriver("louver", {"x1_c": 20.0}, ("phi_deg",))
    dampers = MemoryDriver("dampers", {"v_cav_ms": 0.4}, ("afr", "or_pct"))
    station = MemoryDriver("station", {"t_out_c": 5.0})
    comp = CompositeDriver([louver, dampers, station])
    assert isinstance(comp, Driver) and isinstance(louver, Driver)
    assert comp.driver_for("afr") is dampers and comp.driver_for("t_out_c") is station

    async def scenario() -> None:
        await comp.start()
        s = await comp.read(60.0)
        assert s.time_s == 60.0
        assert {k: s.good(k) for k in s.readings} == {"x1_c": 20.0, "v_cav_ms": 0.4,
                                                      "t_out_c": 5.0}
        result = await comp.write(Command(phi_deg=36.0, afr=4, or_pct=25.0))
        assert result.ok and result.owned == {"phi_deg", "afr", "or_pct"}
        assert louver.commanded == {"phi_deg": 36.0}
        assert dampers.commanded == {"afr": 4, "or_pct": 25.0}
        assert await comp.read_back() == Command(phi_deg=36.0, afr=4, or_pct=25.0)
        await comp.close()
        assert louver.closed and station.closed

    run(scenario())


def test_composite_rejects_a_signal_from_two_drivers() -> None:
    with pytest.raises(ValueError, match="t_out_c"):
        CompositeDriver([MemoryDriver("a", {"t_out_c": 1.0}), MemoryDriver("b", {"t_out_c": 2.0})])


def test_backoff_doubles_to_the_cap_and_resets() -> None:
    b = Backoff(min_s=1.0, max_s=5.0)
    assert b.ready(0.0)
    assert [b.failed(t) for t in (0.0, 1.0, 3.0, 7.0, 12.0)] == [1.0, 2.0, 4.0, 5.0, 5.0]
    assert not b.ready(16.9) and b.ready(17.0)
    assert b.wait_s(16.0) == pytest.approx(1.0)
    assert b.ready(11.0)  # clock stepped back before the last failure: allow an attempt
    b.succeeded()
    assert b.ready(12.0) and b.failed(12.0) == 1.0


def test_breaker_opens_after_consecutive_failures_and_half_opens() -> None:
    br = CircuitBreaker(failures=2, open_cycles=3)
    polled = []
    outcomes = iter([False, False, False, True, True])  # device dead for 3 polls, then back
    for _cycle in range(12):
        if br.should_skip():
            polled.append("skip")
            continue
        ok = next(outcomes, True)
        polled.append("ok" if ok else "fail")
        br.record_success() if ok else br.record_failure()
    assert polled == ["fail", "fail", "skip", "skip", "skip", "fail",  # half-open trial fails
                      "skip", "skip", "skip", "ok", "ok", "ok"]
    assert br.trips == 2 and not br.is_open
    never = CircuitBreaker(failures=1, open_cycles=0)
    never.record_failure()
    assert not never.should_skip()
