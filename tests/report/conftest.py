"""One short faulted dry run of the real daemon, shared by the report, export and metrics
tests (lumped-fidelity plant: seconds, not minutes)."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from dsfd.cli import main
from tests.daemon.harness import MORNING_ISO, ROOT, write_panel

#: 75 one-minute cycles from 08:30 local time: with the test panel's 5-step horizon and
#: its 30-minute first calibration, the log has horizon errors and calibration updates.
CYCLES = 75


def dry_run(panel: Path, state_dir: Path, cycles: int, start_iso: str, *,
            faults: bool = False) -> None:
    """The daemon against the simulated plant (tests/report/dryrun.py) in its own process."""
    cmd = [sys.executable, "-m", "tests.report.dryrun", str(panel), str(state_dir),
           str(cycles), start_iso]
    subprocess.run([*cmd, *(["--faults"] if faults else [])], cwd=ROOT, check=True,
                   timeout=300)


@dataclass(frozen=True)
class ReportRun:
    panel: Path
    state_dir: Path
    html: Path
    doc: dict[str, Any]


@pytest.fixture(scope="session")
def test_panel(tmp_path_factory) -> Path:
    return write_panel(tmp_path_factory.mktemp("panel") / "suwon-test.yaml", devices=False)


@pytest.fixture(scope="session")
def faulted_run(tmp_path_factory, test_panel) -> ReportRun:
    """The state directory of a faulted dry run and its report (HTML and JSON)."""
    base = tmp_path_factory.mktemp("faulted")
    state = base / "state"
    dry_run(test_panel, state, CYCLES, MORNING_ISO, faults=True)
    html, js = base / "report.html", base / "report.json"
    assert main(["report", "--state-dir", str(state), "--out", str(html), "--json",
                 str(js), "--dpi", "60"]) == 0
    return ReportRun(test_panel, state, html, json.loads(js.read_text()))
