"""Brute force over the whole actuator grid: the reference the optimiser is judged by.

Every louver position × every damper set × OR in 1 % steps (closed once per louver
position), each rolled out over the full horizon at full resolution. Far too slow for a
controller (thousands of rollouts), exact by construction on its grid.
"""

from __future__ import annotations

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.control.horizon import (
    CLOSED,
    Best,
    Candidates,
    ControlProblem,
    Decision,
    HorizonEvaluator,
    distinct_regimes,
)
from dsfd.physics.forcing import FacadeOptics
from dsfd.physics.model import LumpedModel


def brute_force(cfg: PanelConfig, model: LumpedModel, optics: FacadeOptics,
                problem: ControlProblem, *, or_step_pct: float = 1.0,
                batch: int = 600) -> Decision:
    """The best control on the full grid (OR in ``or_step_pct`` steps)."""
    angles = np.asarray(cfg.louver.angles_deg() if cfg.louver is not None else (0.0,))
    regimes = distinct_regimes(cfg.openings.available_regimes())
    open_regimes = np.array([r for r in regimes if r != CLOSED], int)
    ors = np.arange(0.0, 100.0 + 1e-9, or_step_pct) / 100.0
    a, r, o = (m.ravel() for m in np.meshgrid(np.arange(len(angles)), open_regimes, ors,
                                              indexing="ij"))
    if CLOSED in regimes:
        a = np.concatenate([a, np.arange(len(angles))])
        r = np.concatenate([r, np.full(len(angles), CLOSED)])
        o = np.concatenate([o, np.zeros(len(angles))])
    ev = HorizonEvaluator(cfg, model, optics, problem, angles)
    best: Best | None = None
    for start in range(0, a.size, batch):
        sl = slice(start, start + batch)
        found = ev.evaluate_all(Candidates(a[sl], r[sl], o[sl])).best()
        best = found if best is None else best.better(found)
    assert best is not None
    return best.decision(angles, method="brute-force", rollouts=ev.rollouts,
                         trace=(f"{a.size} candidates, OR step {or_step_pct:g} %",))
