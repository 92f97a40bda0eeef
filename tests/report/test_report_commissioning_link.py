"""``dsfd report`` links to the newest ``dsfd commission`` record of its state directory."""

from __future__ import annotations

import shutil

from dsfd.cli import main
from dsfd.commission.record import write_record


def _doc(made_utc: str, findings: list[dict[str, object]]) -> dict[str, object]:
    return {"kind": "dsfd-commissioning", "panel": "suwon-south", "config": "panel.yaml",
            "made_utc": made_utc, "dsfd": "test", "time_utc": "2022-01-01T15:00:00Z",
            "sun_elevation_deg": -73.7, "night": True, "signals": None, "stroke": None,
            "findings": findings, "verdict": "findings" if findings else "good"}


def test_the_report_links_the_latest_commissioning_record(faulted_run, tmp_path):
    assert "commissioning record" not in faulted_run.html.read_text()  # none was made
    state = tmp_path / "state"
    shutil.copytree(faulted_run.state_dir, state)
    old = _doc("2026-11-20T08:00:00.000Z", [{"check": "swap", "signals": ["x1_c", "x3_c"],
                                             "message": "m", "likely": "l"}])
    _, old_page = write_record(old, state / "commissioning")
    _, new_page = write_record(_doc("2026-11-27T09:30:00.000Z", []), state / "commissioning")
    out = tmp_path / "report.html"
    assert main(["report", "--state-dir", str(state), "--out", str(out), "--dpi", "30"]) == 0
    html = out.read_text()
    assert f'<a href="{new_page.resolve().as_uri()}">{new_page.name}</a>' in html
    assert old_page.name not in html
