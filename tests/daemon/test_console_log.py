"""The daemon's log for people (a terminal) and for machines (journald, a pipe).

A real ``dsfd run --dry-run --plant sim`` runs on a pseudo-terminal: one aligned line per
cycle under a header, events marked, colours. With stdout redirected the JSON lines keep
exactly the keys they had before the console renderer existed (commit c52b099), and
``--log-format`` overrides the choice either way.
"""

from __future__ import annotations

import errno
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import yaml

from dsfd.daemon.console import CycleConsoleRenderer
from tests.daemon.harness import ROOT, SUWON

#: The keys of a cycle line and of the "daemon ready" line in the journal, as ``dsfd run``
#: wrote them at commit c52b099 (before this renderer): log shippers and the HIL tests parse
#: them, so they must not change.
CYCLE_KEYS = ["time_utc", "slot", "method", "phi_deg", "afr", "or_pct", "write", "flagged",
              "fallback", "wind_override", "calibration", "read_ms", "decide_ms", "cycle_ms",
              "skipped", "hold", "stored", "event", "cycle", "panel", "level", "logger",
              "timestamp"]
READY_KEYS = ["mode", "state_dir", "database", "writes", "event", "panel", "level", "logger",
              "timestamp"]
def _same_keys(record: dict, expected: list[str]) -> bool:
    """The event's own keys in their order, then the context's (``panel``, ``cycle``: their
    order comes from contextvars' hash map, which differs between processes, also before
    the console existed) and the processors' keys."""
    keys = list(record)
    cut = expected.index("event")
    return keys[:cut + 1] == expected[:cut + 1] and sorted(keys) == sorted(expected)


ANSI = re.compile(r"\x1b\[[0-9;]*m")
CYCLE_LINE = re.compile(r"^ +(\d+)  2022-01-0\d \d\d:\d\d  (\w+) +([+-]\d+)° +(\d+) ")
RUN = ["--dry-run", "--plant", "sim", "--plant-fidelity", "lumped",
       "--start", "2022-01-01T23:00:00Z"]


def _panel(tmp_path: Path) -> Path:
    """suwon-south whose rate check flags x1_c at once (a plausible 0.001 K/min limit), so the
    console has a flagged signal to mark; x1 is not a fault signal, so mpc keeps deciding."""
    data = yaml.safe_load(SUWON.read_text())
    data["daemon"] = {"quality": {"max_rate_k_per_min": 0.001, "rate_signals": ["x1_c"]}}
    path = tmp_path / "panel.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _in_a_pty(args: list[str]) -> str:
    """Run ``dsfd`` with stdin/stdout/stderr on a pseudo-terminal; its whole output."""
    master, slave = os.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "dsfd", *args], stdin=slave, stdout=slave,
                            stderr=slave, cwd=ROOT, close_fds=True)
    os.close(slave)
    chunks = []
    try:
        while True:
            try:
                data = os.read(master, 65536)
            except OSError as exc:  # EIO: the child closed the terminal
                if exc.errno != errno.EIO:
                    raise
                break
            if not data:
                break
            chunks.append(data)
    finally:
        os.close(master)
        proc.wait(timeout=300)  # hang guard
    assert proc.returncode == 0, b"".join(chunks).decode(errors="replace")
    return b"".join(chunks).decode("utf-8").replace("\r\n", "\n")


def test_on_a_terminal_each_cycle_is_one_aligned_line_with_flags_marked(tmp_path):
    panel = _panel(tmp_path)
    raw = _in_a_pty(["run", "--config", str(panel), *RUN, "--cycles", "4"])
    assert "\x1b[" in raw  # colours on a terminal
    text = ANSI.sub("", raw)
    lines = text.splitlines()
    assert not [ln for ln in lines if ln.lstrip().startswith("{")]  # no JSON
    header = [i for i, ln in enumerate(lines) if ln.split()[:3] == ["cycle", "time", "(UTC)"]]
    cycles = [(i, m) for i, ln in enumerate(lines) if (m := CYCLE_LINE.match(ln))]
    assert [int(m.group(1)) for _, m in cycles] == [1, 2, 3, 4]
    assert header and header[0] < cycles[0][0]  # the header comes first
    for _, m in cycles:
        assert m.group(2) == "mpc" and int(m.group(4)) in range(1, 11)
    # aligned: the louver, the dampers' % and the decision's ms end in the same columns
    cycle_lines = [lines[i] for i, _ in cycles]
    for mark in ("°", " %", " ms"):
        assert len({ln.index(mark) for ln in cycle_lines}) == 1, (mark, cycle_lines)
    hdr = lines[header[0]]
    assert hdr.index("louver") + len("louver") == cycle_lines[0].index("°") + 1
    # the flagged signal: an event line when it is first flagged, and a mark on each cycle
    assert any(re.match(r"^ +2  ▲ sensor x1_c flagged rate", ln) for ln in lines), text
    assert all(ln.endswith("⚑ x1_c") for ln in cycle_lines[1:]), cycle_lines


def test_json_lines_keep_their_keys_when_stdout_is_redirected(tmp_path):
    done = subprocess.run([sys.executable, "-m", "dsfd", "run", "--config",
                           str(_panel(tmp_path)), *RUN, "--cycles", "2"],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr
    records = [json.loads(ln) for ln in done.stdout.splitlines() if ln.startswith("{")]
    cycles = [r for r in records if r["event"] == "cycle"]
    assert len(cycles) == 2 and all(_same_keys(r, CYCLE_KEYS) for r in cycles)
    assert cycles[1]["flagged"] == 1  # the flag is counted as before, not named
    ready = [r for r in records if r["event"] == "daemon ready"]
    assert len(ready) == 1 and _same_keys(ready[0], READY_KEYS)
    assert "\x1b[" not in done.stdout


def test_log_format_overrides_the_terminal_test(tmp_path):
    panel = str(_panel(tmp_path))
    on_tty = _in_a_pty(["run", "--config", panel, *RUN, "--cycles", "1",
                        "--log-format", "json"])
    records = [json.loads(ln) for ln in on_tty.splitlines() if ln.startswith("{")]
    cycles = [r for r in records if r["event"] == "cycle"]
    assert len(cycles) == 1 and _same_keys(cycles[0], CYCLE_KEYS)
    piped = subprocess.run([sys.executable, "-m", "dsfd", "run", "--config", panel, *RUN,
                            "--cycles", "1", "--log-format", "console"],
                           capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert piped.returncode == 0, piped.stderr
    assert "\x1b[" not in piped.stdout  # no colours into a file
    assert [m.group(1) for ln in piped.stdout.splitlines() if (m := CYCLE_LINE.match(ln))] \
        == ["1"]
    bad = subprocess.run([sys.executable, "-m", "dsfd", "run", "--config", panel,
                          "--log-format", "xml"], capture_output=True, text=True, cwd=ROOT,
                         timeout=60)
    assert bad.returncode == 2 and "--log-format" in bad.stderr


def test_holds_wind_write_failures_and_calibration_updates_stand_out():
    """The renderer alone (pure formatting) on the events a real hold, gust and update log."""
    r = CycleConsoleRenderer(colors=False)
    cycle = {"event": "cycle", "cycle": 12, "time_utc": "2022-01-02T01:00:00Z",
             "method": "manual", "phi_deg": 36.0, "afr": 7, "or_pct": 100.0,
             "write": "failed", "flagged": 2, "wind_override": True,
             "calibration": "not due", "decide_ms": 0.4,
             "hold": "operator hold (cli root@vm) until 2022-01-02T02:55:01Z",
             "flagged_signals": ("x2_c", "t_out_c")}
    line = r(None, "info", dict(cycle)).splitlines()[-1]
    assert line.startswith("    12  2022-01-02 01:00  manual")
    assert "⚑ x2_c,t_out_c" in line and "✋ operator hold (cli root@vm) until 02:55Z" in line
    assert "WIND" in line and "write failed" in line
    update = r(None, "info", {"event": "calibration updated", "cycle": 61, "level": "info",
                              "h_out": 8.414, "n": 1.0, "q_x1": -10.8, "q_x2": 20.3,
                              "residuals": 900})
    assert update == "    61  ★ calibration updated  h_out 8.41  n 1  q_x1..x2 -10.8/20.3 W/m²"
    hold = r(None, "info", {"event": "operator hold (cli) until 02:55Z: louver +36 deg",
                            "event_kind": "hold_started", "level": "info", "cycle": 80})
    assert hold.startswith("    80  ✋ operator hold")
    warn = r(None, "warning", {"event": "sensor x2_c flagged range", "level": "warning"})
    err = r(None, "error", {"event": "write failed", "level": "error", "cycle": 3,
                            "exception": "Traceback ...\nTimeoutError"})
    assert warn.startswith("        ▲ sensor x2_c") and err.startswith("     3  ✖ write failed")
    assert err.endswith("TimeoutError")
    painted = CycleConsoleRenderer(colors=True)(None, "info", dict(cycle))
    assert "\x1b[35m\x1b[1m✋" in painted  # the hold in bold magenta
