"""The "Python API" example of docs/development.md (moved there from the README) runs as
written (examples double as tests)."""

from __future__ import annotations

import re

import numpy as np

from tests.conftest import ROOT


def readme_example() -> str:
    """The first ```python block of docs/development.md's "## Python API" section."""
    text = (ROOT / "docs" / "development.md").read_text(encoding="utf-8")
    section = text[text.index("\n## Python API\n"):]
    section = section[:section.index("\n## ", 1)]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_python_api_example_runs_and_decides_on_the_panels_actuators(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)  # the example names config/panels/... relative to the checkout
    namespace: dict = {}
    exec(compile(readme_example(), "docs/development.md (Python API)", "exec"), namespace)
    panel, decision, update = namespace["panel"], namespace["decision"], namespace["update"]
    assert update.fit is not None and update.state.updates == 1  # the update ran
    assert np.all(update.state.theta >= namespace["calibrator"].space.lower)
    assert decision.method == "mpc" and np.isfinite(decision.cost_j)
    assert decision.afr in panel.openings.available_regimes()
    assert decision.phi_deg in panel.louver.angles_deg()
    assert 0.0 <= decision.or_pct <= 100.0
    out = capsys.readouterr().out
    assert f"louver {decision.phi_deg:+.0f} deg, regime {decision.afr}" in out
    assert "stage 1: screened" in out
