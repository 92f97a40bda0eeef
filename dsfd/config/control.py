"""Settings of the optimal controller and its rule-based baseline (issue: optimal control).

Objective and horizon follow the paper (Eq. 4–6, 15 one-minute steps); the search and
the baseline thresholds are engineering choices, each documented here.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise
from typing import Literal

from dsfd.config.loader import Problem, setting


@dataclass(frozen=True, kw_only=True)
class Baseline:
    """Rule-based controller: the comparison and the fallback (physics-free rules)."""

    sun_threshold_wm2: float = setting(
        20.0, doc="Façade beam irradiance above which the louver tracks the sun",
        unit="W/m2", ge=0)
    night_angle_deg: float = setting(
        90.0, doc="Louver angle with no sun (closed; the paper's night position)", unit="deg",
        ge=-90, le=90)
    heating_open_above_room_k: float = setting(
        2.0, doc="Heating: inside circulation when the cavity is this much warmer than the room",
        unit="K", ge=0, le=30)
    hysteresis_k: float = setting(
        1.0, doc="Hysteresis of the temperature thresholds", unit="K", ge=0, le=10)
    cooling_flush_above_outdoor_k: float = setting(
        1.0, doc="Cooling: outside circulation when the cavity is this much warmer than outdoors",
        unit="K", ge=0, le=30)
    night_cooling_below_room_k: float = setting(
        3.0, doc="Cooling: supply outdoor air through the cavity when outdoors is this much "
        "cooler than the room (night flush)", unit="K", ge=0, le=30)


@dataclass(frozen=True, kw_only=True)
class Control:
    """Model-predictive control of louver angle, airflow regime and damper opening."""

    mode: Literal["heating", "cooling", "auto"] = setting(
        "auto", doc="Season: fixed, or auto by outdoor temperature "
        "(docs/model.md#control-objective)")
    auto_heating_below_c: float = setting(
        15.0, doc="Auto mode: heating while the outdoor air is below this", unit="degC",
        ge=-20, le=35)
    horizon_steps: int = setting(15, doc="Prediction horizon in model steps (paper: 15 min)",
                                 ge=1, le=240)
    optimiser: Literal["mpc", "paper-sqp", "rule"] = setting(
        "mpc", doc="mpc: exact over the louver grid and regimes with a bounded OR search; "
        "paper-sqp: the paper's relaxation (AFR*, SLSQP, louver rounded); rule: baseline only")
    or_grid_pct: tuple[float, ...] = setting(
        (0.0, 100.0), doc="Coarse damper openings evaluated for every louver/regime pair (an "
        "interior opening is then searched around the better end; in 600 random cases on "
        "full 1 % grids the best opening was never interior, and the gap to brute force "
        "over 720 cases was the same as with (0, 50, 100) at 14 % less time)",
        unit="%", ge=0, le=100)
    or_refine_points: int = setting(
        2, doc="Openings evaluated inside the coarse-grid bracket of each refined pair (4 "
        "before issue 24: over 200 random cases the same gap to brute force as 2, for 4 % "
        "more decision time)", ge=1, le=50)
    or_refine_rounds: int = setting(
        0, doc="Parabolic refinement rounds of the best pair's opening (each a further "
        "sequential full-resolution batch; over 600 random cases the OR brackets alone stayed "
        "within 0.003 % of brute force)", ge=0, le=10)
    flat_tolerance_pct: float = setting(
        0.01, doc="Skip the parabolic refinement when the best pair's cost varies less than "
        "this over its OR bracket", unit="%", ge=0, le=10)
    refine_max_pairs: int = setting(
        1, doc="Louver/regime pairs whose OR is refined at full resolution (the best screened; "
        "over 600 random cases one pair already gave the same gap to brute force as four)",
        ge=1, le=200)
    screening_step_s: float = setting(
        300.0, doc="Model step of the screening pass over all candidates (the best ones are "
        "then evaluated at the model's own step)", unit="s", gt=0, le=3600)
    screening_tolerance_k: float = setting(
        0.1, doc="Coupling tolerance of the screening pass (it only ranks candidates for the "
        "full-resolution stage: 0.1 K moves Q_air by ~1 W, and over 600 random cases the "
        "gap to brute force was the same as with 1e-3 K)", unit="K", gt=0, le=0.5)
    coupling_tolerance_k: float = setting(
        1e-4, doc="Coupling tolerance of the full-resolution evaluations (the model's own "
        "1e-6 K default is for reference runs; 1e-4 K moves Q_air by milliwatts)", unit="K",
        gt=0, le=0.1)
    full_candidates: int = setting(
        8, doc="Screened candidates evaluated at full resolution", ge=1, le=500)
    louver_neighbours: int = setting(
        2, doc="Louver positions on either side of the best that are re-evaluated at full "
        "resolution at its regime and opening (the screening can misrank neighbouring "
        "angles by a tenth of a per cent)", ge=0, le=10)
    finalist_margin_pct: float = setting(
        20.0, doc="The best screened candidate of every damper set within this much of the "
        "screened best (relative to max(|J|, 1 Wh)) is also evaluated at full resolution: the "
        "coarse screening step distorts costs by up to a few per cent after a regime change "
        "(2.2 % seen), enough to misrank damper sets", unit="%", ge=0, le=1000)
    louver_move_penalty_wh: float = setting(
        0.1, doc="Cost added per 18° louver step moved (motor wear, occupants' distraction). "
        "The paper has none; without it the louver moved ~100 times a day for gains of "
        "milliwatt-hours. 0.1 Wh: 9 moves a day and 0.4 % less heat gain in the winter "
        "closed loop (RMIS, 4 days)", unit="Wh", ge=0)
    heat_offsets: bool = setting(
        False, doc="Roll the candidates out with the calibration's heat-flux offsets q_x1..q_x4 "
        "(the state update and the report's predictions always use them). They carry the "
        "lumped model's solar error, fitted in the sun and still in force at dusk: on the "
        "mixed cooling day (seed 1) they put the model's supply air within 0.3 K of the "
        "outdoor air from 16:25 and the controller let warm cavity air in, 1.140 kWh against 1.016 "
        "without them; clear cooling seeds 1-3 1.041, 1.470, 0.995 against 1.030, 1.471, "
        "0.964 kWh; the README dry run (heating) 17.61 against 17.58 kWh of heat gained "
        "(docs/model.md#heat-offsets)")
    time_budget_s: float = setting(
        20.0, doc="A decision taking longer than this falls back to the baseline", unit="s",
        gt=0, le=60)
    baseline: Baseline = setting(default_factory=Baseline, doc="Rule-based baseline")

    def check(self) -> list[Problem]:
        grid = self.or_grid_pct
        if len(grid) < 2 or any(b <= a for a, b in pairwise(grid)):
            return [Problem("or_grid_pct", grid, "need at least two strictly ascending values")]
        return []
