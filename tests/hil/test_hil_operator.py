"""Sharing the façade with people, on the HIL rig: the real ``dsfd run`` process, the Modbus
server (the I/O module with the actuator registers) and the weather station on a pty, coupled
to the simulated plant.

* A person moves the louver at the motor controller (the registers change without a client
  write): the daemon holds — it writes nothing for ``safety.manual_hold_min`` — and then
  controls again; ``dsfd status`` reports the hold; a gale during the hold still drives the
  louver to the wind-safe angle and closes the exterior dampers, and the person's position
  comes back once the wind has dropped.
* The wall switch (a coil) holds the panel while it is on and releases it when it is off.
* ``dsfd override`` and ``dsfd resume`` take effect at the first cycle that starts after they
  were given; a malformed override changes nothing.

"Wrote nothing" is counted twice, independently: cycles stored as ``held`` and the Modbus
write requests the I/O module received.
"""

from __future__ import annotations

import asyncio
import json
import signal
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from dsfd.config import load_panel
from dsfd.measured import parse_iso_utc
from dsfd.sim.daemon_plant import plant_options, simulated_plant
from hil.modbus_device import EmulatedModbusDevice
from hil.plant_bridge import PlantBridge
from hil.station import StationEmulator
from tests.daemon.harness import (
    MORNING_ISO,
    DaemonProcess,
    free_port,
    query,
    run_dsfd,
    write_panel,
)

pytestmark = [pytest.mark.hil, pytest.mark.slow]

#: 60 simulated seconds every 0.3 s: time for the test to act between two cycles.
SPEED = 200.0
HOLD_MIN = 40
WIND_SAFE_DEG = 90.0


@dataclass
class Rig:
    daemon: DaemonProcess
    io: EmulatedModbusDevice
    bridge: PlantBridge
    panel: Path
    state: Path

    @property
    def db(self) -> Path:
        return self.state / "timeseries.sqlite"

    def last_cycle(self) -> int:
        return self.daemon.cycles_logged[-1]


@asynccontextmanager
async def rig(tmp_path: Path, station: StationEmulator, *,
              extra: dict[str, Any] | None = None, io_extra: dict[str, Any] | None = None
              ) -> AsyncIterator[Rig]:
    port = free_port()
    panel = write_panel(tmp_path / "panel.yaml", tcp_port=port, station_port=station.port,
                        extra=extra, io_extra=io_extra)
    cfg = load_panel(panel)
    io = EmulatedModbusDevice.from_config(cfg.devices.entries[0])
    plant = simulated_plant(cfg, start_s=parse_iso_utc(MORNING_ISO), cycles=400,
                            options=plant_options("lumped")).plant
    await io.start_tcp(port=port)
    bridge = PlantBridge(plant, io=io, station=station, speed=SPEED)
    await bridge.start()
    state = tmp_path / "state"
    # Stopped by SIGTERM when the scenario is done: a slow machine only makes it longer.
    daemon = await DaemonProcess(["run", "--config", str(panel), "--speed", str(SPEED),
                                  "--start", MORNING_ISO, "--cycles", "2000",
                                  "--state-dir", str(state)]).start()
    try:
        yield Rig(daemon, io, bridge, panel, state)
        daemon.signal(signal.SIGTERM)
        assert await daemon.wait_exit() == 0, daemon.stderr
    finally:
        if daemon.proc is not None and daemon.proc.returncode is None:
            daemon.signal(signal.SIGKILL)
        await bridge.stop()
        await io.stop()


def last(d: DaemonProcess, key: str) -> object:
    """``key`` of the newest end-of-cycle log line (``...`` before the first)."""
    cycles = [r for r in d.records if r.get("event") == "cycle"]
    return cycles[-1][key] if cycles else ...


async def settled(r: Rig, cycle: int) -> None:
    """Until ``cycle`` and a cycle without wind override (a station line lost at start
    makes the wind unknown, which counts as a gale until it has been calm for a while)."""
    await r.daemon.wait_cycle(cycle)
    await r.daemon.wait_for(lambda d: last(d, "wind_override") is False)


def decisions(db: Path) -> dict[int, dict[str, Any]]:
    cols = ("cycle", "time_s", "run_elapsed_s", "method", "phi_deg", "afr", "or_pct",
            "write_status", "hold_source", "hold_expires_s", "hold_command_id", "trace")
    rows = query(db, f"SELECT {', '.join(cols)} FROM decisions ORDER BY cycle")
    return {r[0]: dict(zip(cols, r, strict=True)) for r in rows}


def wind_acted(d: dict[str, Any]) -> bool:
    return any(t["stage"] == "wind" and t["set"] for t in json.loads(d["trace"]))


def test_a_person_moves_the_louver_and_the_daemon_holds_then_resumes(
        tmp_path: Path, station: StationEmulator) -> None:
    extra = {"safety": {"manual_hold_min": HOLD_MIN, "wind_release_cycles": 2,
                        "wind_safe_angle_deg": WIND_SAFE_DEG}}
    seen: dict[str, Any] = {}

    async def scenario() -> Rig:
        async with rig(tmp_path, station, extra=extra) as r:
            await settled(r, 5)
            before = await r.io.actuator_values()
            target = -72.0 if before["phi_deg"] != -72.0 else 72.0
            seen["target"] = target
            for _ in range(5):  # a move that lands between a cycle's read and its write is
                # overwritten (as with any controller): the person tries again
                seen["moved_after"] = r.last_cycle()
                await r.io.move_actuators({"phi_deg": target})  # at the motor controller
                try:
                    await r.daemon.wait_for(
                        lambda d: bool(d.events("actuators moved by someone")), limit_s=3.0)
                    break
                except TimeoutError:
                    continue
            # Ask while the hold lasts; meanwhile a gale blows, then calm again.
            status = asyncio.ensure_future(run_dsfd(
                "status", "--config", str(r.panel), "--state-dir", str(r.state), "--json"))
            r.bridge.station_override = {"wind_speed_ms": 25.0}
            await r.daemon.wait_for(lambda d: last(d, "wind_override") is True)
            r.bridge.station_override = {"wind_speed_ms": 3.0}
            await r.daemon.wait_for(lambda d: last(d, "wind_override") is False)
            rc, out, err = await status
            seen["status"] = (rc, json.loads(out) if out else err)
            await r.daemon.wait_for(lambda d: last(d, "hold") is None)  # it ended
            await r.daemon.wait_cycle(r.last_cycle() + 1)
        seen["writes"] = list(r.io.writes)
        return r

    r = asyncio.run(scenario())
    d = decisions(r.db)
    assert sorted(d) == r.daemon.cycles_logged
    target = seen["target"]
    # Detected at the first cycle after the move, held by "detected".
    held = [c for c in d if d[c]["hold_source"] == "detected"]
    first = held[0]
    assert first <= seen["moved_after"] + 2
    assert d[first]["method"] == "manual" and d[first]["write_status"] == "held"
    assert d[first]["phi_deg"] == target  # the stored command is the read-back
    # It holds for manual_hold_min on the cycle grid, then the controller decides again.
    start_s, grid_s = d[first]["time_s"], d[first]["run_elapsed_s"]
    assert held == list(range(first, held[-1] + 1))
    assert all(d[c]["run_elapsed_s"] - grid_s < HOLD_MIN * 60 for c in held)
    after = held[-1] + 1
    assert d[after]["run_elapsed_s"] - grid_s >= HOLD_MIN * 60
    assert d[after]["hold_source"] is None and d[after]["method"] in {"mpc", "rule"}
    assert d[after]["write_status"] == "verified"
    assert all(d[c]["hold_expires_s"] == pytest.approx(start_s + HOLD_MIN * 60, abs=1e-3)
               for c in held)
    # No writes while held, unless the wind acted or the held position was restored.
    wind = [c for c in held if wind_acted(d[c])]
    assert wind, "the gale came during the hold"
    for c in wind:
        assert d[c]["phi_deg"] == WIND_SAFE_DEG and d[c]["write_status"] == "verified"
        assert d[c]["method"] == "manual" and d[c]["hold_source"] == "detected"
    restored = [c for c in held if c > wind[-1] and d[c]["write_status"] == "verified"]
    assert restored and d[restored[0]]["phi_deg"] == target  # the person's position back
    quiet = [c for c in held if c not in wind and c not in restored]
    assert quiet and all(d[c]["write_status"] == "held" for c in quiet)
    # The I/O module saw exactly one write request per cycle that says it wrote.
    wrote = [c for c in d if d[c]["write_status"] in ("verified", "failed")]
    assert len(seen["writes"]) == len(wrote)
    # dsfd status reported the hold while it lasted.
    rc, status = seen["status"]
    assert rc == 0 and status["daemon"]["running"]
    assert status["hold"]["source"] == "detected"
    assert parse_iso_utc(status["hold"]["expires_utc"]) == pytest.approx(
        start_s + HOLD_MIN * 60, abs=1.0)
    assert status["last_cycle"]["method"] == "manual"
    kinds = [k for (k,) in query(r.db, "SELECT kind FROM events ORDER BY event_id")]
    assert kinds.count("manual_override") == 1 and "hold_ended" in kinds
    # While held, the daemon kept estimating and calibrating, with the position read back
    # (the person's) as the applied control.
    model = {c: (x1, phi) for c, x1, phi in query(
        r.db, "SELECT cycle, est_x1_c, applied_phi_deg FROM model")}
    assert all(model[c][0] is not None for c in held)
    assert all(model[c][1] == target for c in quiet)
    updates = [c for (c,) in query(r.db, "SELECT cycle FROM parameters WHERE source = 'online'")]
    assert any(first <= c <= held[-1] for c in updates), (updates, first, held[-1])


def test_wall_switch_and_operator_commands_take_effect_within_one_cycle(
        tmp_path: Path, station: StationEmulator) -> None:
    switch = {"override_input": {"table": "coil", "address": 3}}
    seen: dict[str, Any] = {}

    async def scenario() -> Rig:
        async with rig(tmp_path, station, io_extra=switch) as r:
            await settled(r, 4)
            await r.io.set_override_input(True)  # the wall switch: hand
            seen["switch_on"] = r.last_cycle()
            await r.daemon.wait_cycle(seen["switch_on"] + 4)
            await r.io.set_override_input(False)  # auto
            seen["switch_off"] = r.last_cycle()
            await r.daemon.wait_cycle(seen["switch_off"] + 3)
            bad = await run_dsfd("override", "--config", str(r.panel), "--state-dir",
                                 str(r.state), "--regime", "11")
            seen["bad"] = bad
            good = await run_dsfd("override", "--config", str(r.panel), "--state-dir",
                                  str(r.state), "--louver-deg", "-36", "--regime", "10",
                                  "--hold", "30min")
            seen["override"] = good
            seen["registers"] = await r.io.actuator_values()
            await r.daemon.wait_cycle(r.last_cycle() + 2)
            seen["resume"] = await run_dsfd("resume", "--state-dir", str(r.state))
        return r

    r = asyncio.run(scenario())
    d = decisions(r.db)
    # The switch holds while it is on (no expiry), and releases at once when it is off.
    on = [c for c in d if d[c]["hold_source"] == "input"]
    assert on and on[0] <= seen["switch_on"] + 2 and on[-1] <= seen["switch_off"] + 1
    assert on == list(range(on[0], on[-1] + 1))
    assert all(d[c]["write_status"] == "held" and d[c]["hold_expires_s"] is None
               for c in on)
    released = on[-1] + 1
    assert d[released]["hold_source"] is None and d[released]["write_status"] == "verified"
    # A malformed override is refused before anything is queued.
    rc, _, err = seen["bad"]
    assert rc == 2 and "--regime 11" in err and "nothing was sent" in err
    # The override is answered "applied" and took effect at the first cycle after it.
    rc, out, err = seen["override"]
    assert rc == 0, err
    assert "applied" in out
    rows = query(r.db, "SELECT command_id, kind, status, cycle, requested_s, source, "
                 "requester, reason FROM commands ORDER BY command_id")
    assert [(k, s) for _, k, s, *_ in rows] == [("override", "applied"), ("resume", "applied")]
    for _, kind, _, cycle, requested_s, source, who, _ in rows:
        assert source == "cli" and "@" in who
        first_after = min(c for c in r.daemon.cycles_logged
                          if r.daemon.cycle_ended_s(c) > requested_s)
        assert cycle <= first_after + 1, (kind, cycle, first_after)
    override_cycle, resume_cycle = rows[0][3], rows[1][3]
    assert d[override_cycle]["hold_source"] == "operator"
    assert d[override_cycle]["hold_command_id"] == rows[0][0]
    assert (d[override_cycle]["phi_deg"], d[override_cycle]["afr"],
            d[override_cycle]["or_pct"]) == (-36.0, 10, 0.0)
    assert d[override_cycle]["write_status"] == "verified"
    assert seen["registers"] == {"phi_deg": -36.0, "afr": 10.0, "or_pct": 0.0}
    expires = d[override_cycle]["hold_expires_s"] - d[override_cycle]["time_s"]
    assert expires == pytest.approx(30 * 60, abs=1e-3)
    assert all(d[c]["write_status"] == "held" for c in range(override_cycle + 1, resume_cycle))
    # Resume: the controller decides again from that cycle on.
    assert d[resume_cycle]["hold_source"] is None
    assert d[resume_cycle]["method"] in {"mpc", "rule"}
    assert seen["resume"][0] == 0 and "applied" in seen["resume"][1]

