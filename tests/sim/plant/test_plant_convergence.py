"""docs/model.md#plant-switches: the stratified plant converges in the number of segments (default
options).

Mid-height x1…x5 and the outlet air may change by less than 0.1 K between N = 10 and
N = 20 (inside-circulation and outside-circulation regimes, clear winter afternoon).
"""

from __future__ import annotations

import numpy as np
import pytest

from dsfd.sim.plant.actuators import Command
from dsfd.sim.plant.config import PlantOptions
from dsfd.sim.plant.plant import Plant
from tests.sim.conftest import HOUR, day_start

HOURS = 3


def _run(cfg, series, n_segments: int, command: Command, start: float) -> np.ndarray:
    plant = Plant(cfg, PlantOptions(n_segments=n_segments), seed=2, weather_series=series)
    plant.reset(start, command=command)
    out = []
    for _ in range(HOURS * 60):
        plant.advance(60.0)
        st = plant.true_state()
        out.append(np.append(st.x_mid_k[:5], st.t_outlet_k))
    return np.array(out)


@pytest.mark.parametrize("command", [Command(0.0, 1, 100.0), Command(36.0, 3, 100.0)])
def test_n10_and_n20_agree(suwon, rmis, command):
    start = day_start(rmis, 1) + 9 * HOUR  # late morning to early afternoon at the site
    coarse = _run(suwon, rmis, 10, command, start)
    fine = _run(suwon, rmis, 20, command, start)
    diff = np.abs(coarse - fine)[30:]
    assert diff.max() < 0.1, diff.max(axis=0)
    # ... and the run was not trivial: sun and flow in the cavity.
    assert coarse[:, 3].max() - coarse[:, 3].min() > 3.0
    assert np.all(np.isfinite(coarse[:, 5]))
