"""End to end: a damper stuck shut in the simulated plant of a real ``dsfd run`` shows in
what the daemon stores, and the cavity cross-check on those rows names it
(docs/model.md#diagnostics-crosschecks); the same run without the fault gives no finding."""

from __future__ import annotations

import itertools
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dsfd.config.panel import REGIME_OPENINGS
from dsfd.estimation.crosschecks import cavity_flow_check
from tests.daemon.harness import MORNING_ISO, ROOT, dsfd_command, query, write_panel

SHORT = {"exterior_bottom": "EB", "exterior_top": "ET", "interior_bottom": "IB",
         "interior_top": "IT"}
CYCLES = 150
ONSET_CYCLE = 30  # the fault starts 30 min in: +30min


def _dry_run(tmp_path: Path, name: str, *faults: str) -> Path:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / name
    args = [a for f in faults for a in ("--fault", f)]
    done = subprocess.run(dsfd_command(
        "run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
        "lumped", "--start", MORNING_ISO, "--cycles", str(CYCLES), "--state-dir", str(state),
        "--log-format", "json", *args), cwd=ROOT, capture_output=True, text=True,
        timeout=600, check=False)
    assert done.returncode == 0, done.stderr
    return state / "timeseries.sqlite"


def _stored(db: Path) -> dict[str, np.ndarray | list]:
    """Per cycle from the onset: time, measured cavity speed, the dampers the command in force
    during the step opened, and the larger of |x5 − t_room| and |x5 − t_out| [K]."""
    wide: dict[int, dict[str, float]] = {}
    for cycle, signal, value in query(db, "SELECT cycle, signal, value FROM samples "
                                          "WHERE quality = 'good'"):
        wide.setdefault(cycle, {})[signal] = value
    rows = query(db, "SELECT cycle, time_s, applied_afr, applied_or_pct FROM model "
                     "ORDER BY cycle")
    out: dict[str, list] = {"time_s": [], "v": [], "open": [], "drive": [], "v_pred": []}
    preds = dict(query(db, "SELECT cycle, pred_v_cav_ms FROM model"))
    for (_, _, afr, or_pct), (cycle, t, *_) in itertools.pairwise(rows):
        r = wide.get(cycle, {})
        if cycle < ONSET_CYCLE or afr is None or not {"v_cav_ms", "x5_c"} <= r.keys():
            continue
        names = frozenset(SHORT[n] for n in REGIME_OPENINGS[int(afr)]) if or_pct else frozenset()
        out["time_s"].append(t)
        out["v"].append(r["v_cav_ms"])
        out["v_pred"].append(np.nan if preds.get(cycle) is None else preds[cycle])
        out["open"].append(names)
        out["drive"].append(max(abs(r["x5_c"] - r.get("t_room_c", np.nan)),
                                abs(r["x5_c"] - r.get("t_out_c", np.nan))))
    return {k: (v if k == "open" else np.array(v, float)) for k, v in out.items()}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("stuck")
    return {"clean": _stored(_dry_run(tmp, "clean")),
            "stuck": _stored(_dry_run(tmp, "stuck", "damper-stuck.IT:+30min:0"))}


def test_a_damper_stuck_shut_is_named_from_the_stored_rows(runs):
    s = runs["stuck"]
    f = cavity_flow_check(s["time_s"], s["v"], s["open"], s["drive"])
    assert f is not None and f.kind == "damper_no_flow"
    assert "check damper IT" in f.action
    assert all("IT" in e.signal for e in f.evidence)
    # the stored one-step error shows it too: no flow measured where the model expects some,
    # and far more of it than on the clean run (the calibration takes some of it into f)
    c = runs["clean"]
    error = {}
    for name, r in (("stuck", s), ("clean", c)):
        uses_it = np.array(["IT" in o for o in r["open"]])
        error[name] = float(np.nanmedian(r["v_pred"][uses_it] - r["v"][uses_it]))
        if name == "stuck":
            assert np.nanmedian(r["v"][uses_it]) < 0.015
    assert error["stuck"] > 0.015 > abs(error["clean"])


def test_the_same_run_without_the_fault_gives_no_finding(runs):
    c = runs["clean"]
    assert cavity_flow_check(c["time_s"], c["v"], c["open"], c["drive"]) is None
    assert any("IT" in o for o in c["open"])  # the paths through IT were used and flowed
