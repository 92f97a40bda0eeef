"""Device faults with the real ``dsfd run`` process: the I/O module is down at start, comes up,
disappears mid-run and comes back.

Throughout, the daemon keeps cycling (one decision per cycle), the module's readings are
flagged, the decisions come from the baseline (the state estimate lacks x1..x5), and after
each return of the module its readings are GOOD again within two cycles.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from dsfd.config import load_panel
from dsfd.measured import parse_iso_utc
from dsfd.sim.daemon_plant import plant_options, simulated_plant
from hil.modbus_device import EmulatedModbusDevice
from hil.plant_bridge import PlantBridge
from hil.station import StationEmulator
from tests.daemon.harness import MORNING_ISO, DaemonProcess, free_port, query, write_panel

pytestmark = [pytest.mark.hil, pytest.mark.slow]

SPEED = 400.0
CYCLES = 32
#: Cycles the daemon may carry a missing state by prediction (harness FAST settings).
PREDICTED = 1


def test_device_down_at_start_and_gone_mid_run_recovers_within_two_cycles(
        tmp_path: Path, station: StationEmulator) -> None:
    port = free_port()
    panel = write_panel(tmp_path / "panel.yaml", tcp_port=port, station_port=station.port)
    cfg = load_panel(panel)
    io = EmulatedModbusDevice.from_config(cfg.devices.entries[0])
    state = tmp_path / "state"
    marks: dict[str, int] = {}

    async def scenario() -> None:
        plant = simulated_plant(cfg, start_s=parse_iso_utc(MORNING_ISO), cycles=4 * CYCLES,
                                options=plant_options("lumped")).plant
        bridge = PlantBridge(plant, io=io, station=station, speed=SPEED)
        await bridge.start()  # the station talks; the I/O module is not there yet
        daemon = await DaemonProcess(["run", "--config", str(panel), "--speed", str(SPEED),
                                      "--start", MORNING_ISO, "--cycles", str(CYCLES),
                                      "--state-dir", str(state)]).start()
        try:
            await daemon.wait_cycle(4)
            marks["up"] = daemon.cycles_logged[-1]
            await io.start_tcp(port=port)  # the module boots
            await daemon.wait_cycle(marks["up"] + 7)
            marks["down"] = daemon.cycles_logged[-1]
            await io.stop()  # ... and disappears
            await daemon.wait_cycle(marks["down"] + 7)
            marks["back"] = daemon.cycles_logged[-1]
            await io.resume()  # ... and comes back
            assert await daemon.wait_exit() == 0, daemon.stderr
        finally:
            await bridge.stop()
            await io.stop()

    asyncio.run(scenario())
    db = state / "timeseries.sqlite"
    up, down, back = marks["up"], marks["down"], marks["back"]
    assert back + 6 <= CYCLES
    # The daemon kept cycling: one decision per cycle, none lost to the faults.
    decisions = {c: (m, w) for c, m, w in query(
        db, "SELECT cycle, method, write_status FROM decisions")}
    assert sorted(decisions) == list(range(1, CYCLES + 1))
    x1 = dict(query(db, "SELECT cycle, quality FROM samples WHERE signal = 'x1_c'"))
    t_out = dict(query(db, "SELECT cycle, quality FROM samples WHERE signal = 't_out_c'"))

    def first_good_after(cycle: int) -> int:
        return min(c for c, q in x1.items() if c > cycle and q == "good")

    # Down at start: flagged, the baseline decides, writes fail (the module has the
    # actuators), the station still delivers.
    for c in range(1, up + 1):
        assert x1[c] == "disconnected", (c, x1[c])
        # The station's very first reading may miss cycle 1 (it starts with the daemon):
        # without outdoor air even the baseline cannot decide, and the safe state holds.
        expected = "rule" if t_out[c] == "good" else "safe"
        assert decisions[c] == (expected, "failed"), (c, t_out[c], decisions[c])
    assert all(t_out[c] == "good" for c in range(2, CYCLES + 1))
    # The module boots: GOOD within two cycles, then the optimiser decides again.
    assert first_good_after(up) <= up + 2
    ok_from = first_good_after(up)
    assert all(x1[c] == "good" for c in range(ok_from, down + 1))
    assert decisions[down][1] == "verified"
    # It disappears: flagged, the baseline (or a short prediction) decides, cycles go on.
    outage = [c for c in range(down + 2, back + 1)]
    assert all(x1[c] != "good" for c in outage)
    assert all(decisions[c][0] == "rule" for c in outage[PREDICTED + 1:])
    assert all(decisions[c][1] == "failed" for c in outage)
    # It comes back: GOOD within two cycles, commands verified again.
    recovered = first_good_after(back)
    assert recovered <= back + 2
    assert all(x1[c] == "good" for c in range(recovered, CYCLES + 1))
    assert decisions[CYCLES][1] == "verified"
