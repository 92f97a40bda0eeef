"""End to end: a damper stuck shut in the simulated plant of a real ``dsfd run`` shows in
what the daemon stores, and the cavity cross-check on those rows names it
(docs/model.md#diagnostics-crosschecks); the same run without the fault gives no finding.

The daemon runs that check itself (docs/model.md#findings): its ``findings`` table and
``dsfd status`` name the stuck damper, and the clean run has no finding; ``dsfd report``
lists it with a figure of its evidence."""

from __future__ import annotations

import itertools
import json
import sqlite3
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


def _status(db: Path) -> dict:
    done = subprocess.run(dsfd_command("status", "--state-dir", str(db.parent), "--json"),
                          cwd=ROOT, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 3, done.stderr  # 3: no daemon runs now (LSB)
    return json.loads(done.stdout)


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
    dbs = {"clean": _dry_run(tmp, "clean"),
           "stuck": _dry_run(tmp, "stuck", "damper-stuck.IT:+30min:0")}
    return {name: {**_stored(db), "db": db} for name, db in dbs.items()}


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


def test_the_daemon_itself_stores_the_stuck_damper_finding_and_status_shows_it(runs):
    db = runs["stuck"]["db"]
    rows = query(db, "SELECT finding_id, kind, subject, state, start_s, detected_s, opened_s, "
                     "evidence, action FROM findings ORDER BY finding_id")
    open_ = [r for r in rows if r[3] == "open"]
    # one open finding at the end, naming IT — alone, or with IB when the supply path EB+IT
    # that would clear IB is one the model expects to move too little air to judge (it
    # runs against the room's stack); an earlier check may have blamed a damper the early,
    # pre-fault readings did not exonerate: that one must have ended
    assert [r[1] for r in open_] == ["damper_no_flow"]
    subject = open_[0][2]
    assert "IT" in subject.split("+") and set(subject.split("+")) <= {"IB", "IT"}
    assert {r[3] for r in rows if r not in open_} <= {"ended"}
    fid, *_, detected_s, opened_s, evidence, action = open_[0]
    named = ", ".join(subject.split("+"))
    assert f"check damper {named}" in action
    assert all("IT" in e["signal"] for e in json.loads(evidence))
    onset_s, last_s = query(db, "SELECT MIN(time_s) + ?, MAX(time_s) FROM decisions",
                            ONSET_CYCLE * 60.0)[0]
    # found by a check during the run, after the onset; refreshed by the later checks
    assert onset_s < opened_s <= detected_s <= last_s
    status = _status(db)
    assert [(f["finding_id"], f["kind"], f["subject"]) for f in status["findings"]] == [
        (fid, "damper_no_flow", subject)]
    text = subprocess.run(dsfd_command("status", "--state-dir", str(db.parent)), cwd=ROOT,
                          capture_output=True, text=True, timeout=120, check=False).stdout
    assert f"#{fid} damper_no_flow {subject}" in text and f"check damper {named}" in text


def test_the_clean_run_stores_no_finding(runs):
    db = runs["clean"]["db"]
    assert query(db, "SELECT COUNT(*) FROM findings") == [(0,)]
    assert _status(db)["findings"] == []


def test_dsfd_report_shows_the_stuck_damper_finding_with_a_figure_of_its_evidence(runs,
                                                                                    tmp_path):
    """``dsfd report`` of the stuck run: its Diagnostics section lists the open finding
    with its evidence and draws it (docs/operating.md#seeing-what-the-controller-did)."""
    import base64
    import io
    import re

    from PIL import Image

    from dsfd.report.finding_figures import flow_figure
    from dsfd.storage.findings import open_findings

    db = runs["stuck"]["db"]
    html = tmp_path / "report.html"
    done = subprocess.run(dsfd_command("report", "--state-dir", str(db.parent), "--out",
                                       str(html), "--dpi", "50"), cwd=ROOT,
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    page = html.read_text()
    section = page[page.index('<h2 id="diagnostics">'):page.index("<h2>Figures</h2>")]
    conn = sqlite3.connect(db)
    try:
        stored = conn.execute("SELECT COUNT(*) FROM findings").fetchone()[0]
        assert done.stdout.rstrip().endswith(
            f"7 figures, {stored} finding{'s' if stored != 1 else ''}")
        (row,) = open_findings(conn)
        fid = row["finding_id"]
        subject = str(row["subject"])
        for text in (f"#{fid}", "damper_no_flow", f">{subject}<", ">open<",
                     f"check damper {', '.join(subject.split('+'))}",
                     "crosscheck:v_cav_ms[IB+IT]", "0.02 m/s"):
            assert text in section, text
        m = re.search(rf'<figure id="finding-{fid}">.*?base64,([^"]+)"', section, re.S)
        assert m is not None
        assert Image.open(io.BytesIO(base64.b64decode(m.group(1)))).size[0] > 300
        # What it draws: after the onset, the readings of every path through the stuck
        # damper lie below the stored threshold the open path had to pass (the air does not
        # move), and the commanded opening of those cycles was not zero.
        fig = flow_figure(conn, row, 9.0)
    finally:
        conn.close()
    speed = fig.axes[0]
    onset = np.datetime64(int((runs["stuck"]["time_s"][0] + 9 * 3600) * 1e3), "ms")
    paths = {str(line.get_label()): line for line in speed.get_lines()}
    through_it = [k for k in paths if k.endswith(" open") and "IT" in k]
    assert through_it
    for k in through_it:
        x, y = np.asarray(paths[k].get_xdata()), np.asarray(paths[k].get_ydata(), float)
        assert np.median(y[x >= onset]) < 0.02, k
    threshold = next(v for k, v in paths.items() if k.startswith("threshold"))
    assert threshold.get_ydata()[0] == pytest.approx(row["evidence"][0]["threshold"])
    assert np.asarray(fig.axes[2].get_lines()[0].get_ydata(), float).max() > 0


def test_the_bench_replay_of_the_stored_run_finds_what_the_daemon_found(runs, tmp_path):
    """``dsfd bench diagnostics --recheck`` replays the detectors over a kept run: on the
    stuck run it opens the damper finding the daemon opened, within one check interval of
    it, naming IT as the daemon did, and on the clean run it finds nothing."""
    from dsfd.bench.diagnostics import recheck, scenarios, score
    from dsfd.daemon.findings import CHECK_EVERY_S

    stuck = next(s for s in scenarios(clean_days=1.0) if s.name == "stuck-damper")
    assert stuck.fault == "damper-stuck.IT:+30min:0" and stuck.onset_s == ONSET_CYCLE * 60.0
    db = runs["stuck"]["db"]
    fig = recheck(db.parent, stuck, db.parent.parent / "panel.yaml", tmp_path / "stuck")
    assert fig["named"] == 1.0 and fig["false_findings"] == 0.0
    own_fig = score(db, stuck)  # what the daemon's own checks stored
    assert own_fig["named"] == 1.0
    assert abs(fig["name_delay_min"] - own_fig["name_delay_min"]) <= CHECK_EVERY_S / 60.0
    (own,), = query(db, "SELECT MIN(opened_s) FROM findings WHERE kind = 'damper_no_flow'")
    (replayed,), = query(tmp_path / "stuck" / "timeseries.sqlite",
                         "SELECT MIN(opened_s) FROM findings WHERE kind = 'damper_no_flow'")
    assert abs(replayed - own) <= CHECK_EVERY_S
    clean = next(s for s in scenarios(clean_days=CYCLES / 1440) if s.name == "clean")
    c = runs["clean"]["db"]
    assert recheck(c.parent, clean, c.parent.parent / "panel.yaml",
                   tmp_path / "clean")["false_findings"] == 0.0
