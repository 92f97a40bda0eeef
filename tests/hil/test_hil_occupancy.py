"""The ``occupied`` signal and ``dsfd occupancy`` on the HIL rig (issue 36): the real
``dsfd run`` process reads a presence flag from the Modbus I/O module (a pymodbus server, a
holding register beside the façade's sensors) coupled to the simulated plant.

The panel's schedule says occupied all day, so the schedule and the signal disagree
whenever the signal reads 0:

* the signal reading 0 makes the room unoccupied (source ``signal``), reading 1 occupied;
* a register reading 2 is no bit: the quality checks flag it out of range, the schedule
  decides (occupied), it is logged once, and the signal counts again when it reads 0/1;
* ``dsfd occupancy occupied until HH:MM`` overrides the signal's 0 from the next cycle on;
  a malformed one exits 2 and queues nothing.
"""

from __future__ import annotations

import asyncio
import datetime as dt
import json
from pathlib import Path
from typing import Any

import pytest

from hil.station import StationEmulator
from tests.daemon.harness import query, run_dsfd, suwon_mapping
from tests.hil.test_hil_operator import Rig, rig, settled

pytestmark = [pytest.mark.hil, pytest.mark.slow]

ALWAYS = ["00:00-24:00"]
EVERY_DAY = {d: ALWAYS for d in ("mon", "tue", "wed", "thu", "fri", "sat", "sun")}
OCCUPIED_POINT = {"signal": "occupied", "table": "holding", "address": 10,
                  "data_type": "uint16"}


def _comfort(db: Path) -> dict[int, tuple[int, str]]:
    return {c: (o, s) for c, o, s in query(db, "SELECT cycle, occupied, occupancy_source "
                                               "FROM comfort ORDER BY cycle")}


async def _until_stored(r: Rig, want: tuple[int, str]) -> int:
    """The first cycle from now whose stored occupancy is ``want``."""
    start = r.last_cycle()
    async with asyncio.timeout(60.0):
        while True:
            got = [c for c, v in _comfort(r.db).items() if c > start and v == want]
            if got:
                return got[0]
            await asyncio.sleep(0.1)


def test_the_occupied_signal_decides_unless_flagged_or_overridden(
        tmp_path: Path, station: StationEmulator) -> None:
    io_sensors = suwon_mapping()["devices"]["entries"][0]["sensors"]
    seen: dict[str, Any] = {}

    async def scenario() -> Rig:
        async with rig(tmp_path, station, extra={"occupancy": EVERY_DAY},
                       io_extra={"sensors": [*io_sensors, OCCUPIED_POINT]}) as r:
            await r.io.set_sensor("occupied", 0.0)
            await settled(r, 3)
            seen["signal_0"] = await _until_stored(r, (0, "signal"))
            await r.io.set_sensor("occupied", 1.0)
            seen["signal_1"] = await _until_stored(r, (1, "signal"))
            await r.io.set_registers("occupied", [2])  # a mis-mapped register: no bit
            seen["flagged"] = await _until_stored(r, (1, "schedule"))
            await r.io.set_sensor("occupied", 0.0)
            seen["back"] = await _until_stored(r, (0, "signal"))
            # the operator says occupied for a while, whatever the signal says
            bad = await run_dsfd("occupancy", "--config", str(r.panel), "--state-dir",
                                 str(r.state), "maybe", "until", "10:00")
            seen["bad"] = bad
            now_s = query(r.db, "SELECT MAX(time_s) FROM decisions")[0][0]
            until = dt.datetime.fromtimestamp(now_s + 3600.0, dt.timezone(
                dt.timedelta(hours=9))).strftime("%H:%M")
            seen["good"] = await run_dsfd("occupancy", "--config", str(r.panel),
                                          "--state-dir", str(r.state), "occupied", "until",
                                          until)
            seen["override"] = await _until_stored(r, (1, "override"))
            await r.daemon.wait_cycle(seen["override"] + 1)
        return r

    r = asyncio.run(scenario())
    occ = _comfort(r.db)
    samples = dict(((c, q), v) for c, q, v in query(
        r.db, "SELECT cycle, quality, value FROM samples WHERE signal = 'occupied'"))
    # The flagged cycle stored the register's 2 with its flag, and the schedule decided.
    flagged = seen["flagged"]
    assert samples[(flagged, "out_of_range")] == 2.0
    (trace,), = query(r.db, "SELECT trace FROM decisions WHERE cycle = ?", flagged)
    (why,) = [t["why"] for t in json.loads(trace) if t["stage"] == "occupancy"]
    assert "occupied signal not usable: range" in why
    assert seen["signal_0"] < seen["signal_1"] < flagged < seen["back"]
    assert all(occ[c] == (1, "schedule") for c in range(flagged, seen["back"]))
    # logged once when it went bad, once when it came back
    events = [str(x.get("event")) for x in r.daemon.records]
    assert sum(e.startswith("occupied signal not usable (range)") for e in events) == 1
    assert sum(e.startswith("occupied signal GOOD again") for e in events) == 1
    # the CLI: the malformed command changed nothing, the good one overrides the signal's 0
    rc, _, err = seen["bad"]
    assert rc == 2 and "STATE maybe: expected one of occupied" in err
    assert "nothing was sent" in err
    rc, out, err = seen["good"]
    assert rc == 0, err
    assert "applied at cycle" in out
    cmds = query(r.db, "SELECT kind, source, status FROM commands")
    assert cmds == [("occupancy", "cli", "applied")]
    assert occ[seen["override"]] == (1, "override")
    assert samples[(seen["override"], "good")] == 0.0  # the signal still said empty
