"""The real ``dsfd run`` names the comfort limits a command would break, and decides the same.

A simulated winter morning (08:30 local, Suwon) twice: without an ``occupancy:`` section
(never occupied) and with one that marks every day occupied. The decision trace carries a
``comfort`` stage either way; only the occupied run names limits; the commands are the same,
because comfort does not yet weigh in the decision (issue 36).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tests.daemon.harness import MORNING_ISO, ROOT, query, write_panel

ALWAYS = ["00:00-24:00"]
OCCUPIED = {"occupancy": {day: ALWAYS for day in ("mon", "tue", "wed", "thu", "fri", "sat",
                                                  "sun")},
            "comfort": {"dgp_max": 0.35, "supply_air_min_c": 30.0}}


def _run(tmp: Path, extra: dict | None) -> list[tuple[float, int, float, list[dict]]]:
    tmp.mkdir()
    panel = write_panel(tmp / "panel.yaml", devices=False, extra=extra)
    state = tmp / "state"
    done = subprocess.run(
        [sys.executable, "-m", "dsfd", "run", "--config", str(panel), "--dry-run", "--plant",
         "sim", "--plant-fidelity", "lumped", "--start", MORNING_ISO, "--cycles", "3",
         "--state-dir", str(state)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    rows = query(state / "timeseries.sqlite",
                 "SELECT phi_deg, afr, or_pct, trace FROM decisions ORDER BY cycle")
    return [(phi, afr, or_pct, json.loads(trace)) for phi, afr, or_pct, trace in rows]


def _comfort(trace: list[dict]) -> str:
    (why,) = [t["why"] for t in trace if t["stage"] == "comfort"]
    return why


def test_the_trace_names_comfort_limits_without_changing_decisions(tmp_path: Path) -> None:
    free = _run(tmp_path / "free", None)
    busy = _run(tmp_path / "busy", OCCUPIED)
    assert len(free) == len(busy) == 3
    assert [r[:3] for r in free] == [r[:3] for r in busy]  # the same commands
    for *_, trace in free:
        assert _comfort(trace).startswith("unoccupied (no limit)")
        assert "would violate" not in _comfort(trace)
    whys = [_comfort(trace) for *_, trace in busy]
    assert all(w.startswith("occupied; direct sun") for w in whys)
    # The supply air is judged only when the command blows air into the room, and named
    # when it is colder than the 30 °C limit set above.
    for (_, afr, or_pct, _), why in zip(busy, whys, strict=True):
        blows = afr in (1, 2, 7, 8, 9) and or_pct > 0
        assert ("supply air none" in why) == (not blows), why
        if blows:
            t_supply = float(why.split("supply air ")[1].split(" °C")[0])
            assert ("supply air" in why.split("would violate")[-1]) == (t_supply < 30.0), why
