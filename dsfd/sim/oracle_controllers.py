"""The closed loop's controllers with perfect information (``oracle``, ``plant-oracle``,
``mpc-true-weather``, ``mpc-true-state``; ``mpc-true-params`` is the plain cycle with the
oracle's parameters) and the frozen calibration of ``offline``, ``none``
and the oracles: the daemon's :class:`~dsfd.daemon.loop.Controller` with its state estimate,
forecast or optimiser taken from the truth plant (:mod:`dsfd.sim.closed_loop` runs them).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import Param
from dsfd.control.optimiser import ControlProblem, Decision
from dsfd.daemon.calibration import CalibrationStage
from dsfd.daemon.loop import Controller
from dsfd.daemon.observer import StateEstimate
from dsfd.daemon.weather import CycleWeather
from dsfd.drivers.base import Command as DriverCommand
from dsfd.estimation.params import ParameterSpace, full_vector
from dsfd.estimation.state import CalibrationState
from dsfd.physics.airflow import ET, IB
from dsfd.physics.boundary import WeatherInputs
from dsfd.physics.forcing import Forcing, facade_forcing
from dsfd.physics.model import LumpedModel
from dsfd.sim.oracle_search import Candidate, PlantOracle
from dsfd.sim.plant.flow import opening_resistance
from dsfd.sim.plant.plant import Plant

__all__ = ["CONTROLLER_CLASSES", "FrozenCalibration", "OracleController",
           "PlantOracleController", "oracle_theta"]


class FrozenCalibration(CalibrationStage):
    """A calibration stage whose estimate never changes (``offline``, ``none``, oracle)."""

    def __init__(self, cfg: PanelConfig, model: LumpedModel, *, state_dir: Path,
                 theta: np.ndarray | None) -> None:
        super().__init__(cfg, model, state_dir=state_dir)
        if theta is not None:
            space = ParameterSpace.from_panel(cfg)
            state = CalibrationState.initial(cfg.panel.id, space)
            self.calibrator.state = dataclasses.replace(state, theta=full_vector(theta))

    def due(self, now_s: float) -> bool:
        return False


class OracleController(Controller):
    """The controller with the plant's true state and/or true weather (module docstring)."""

    plant: Plant
    true_state: bool = True
    true_weather: bool = True

    def _estimate(self, checked, weather: CycleWeather, current: DriverCommand | None
                  ) -> StateEstimate:
        if not self.true_state:
            return super()._estimate(checked, weather, current)
        x = np.asarray(self.plant.true_state().x_mid_k, float)
        return StateEstimate(x_k=x, age_cycles=(0,) * 5, usable=True)

    def _forecast(self, measured: WeatherInputs, now_s: float) -> Forcing:
        if not self.true_weather:
            return super()._forecast(measured, now_s)
        return facade_forcing(self.cfg, self.plant.perfect_forecast(self.cfg.control.horizon_steps))


class PlantOracleController(OracleController):
    """Decisions by plant rollouts (:class:`~dsfd.sim.oracle_search.PlantOracle`)."""

    search: PlantOracle

    def _optimiser(self, problem: ControlProblem) -> Callable[[], Decision]:
        current = None
        if problem.previous_phi_deg is not None and problem.previous_afr is not None:
            current = Candidate.of(problem.previous_phi_deg, problem.previous_afr,
                                   problem.previous_or_pct or 0.0)
        return lambda: self.search.decide(self.plant, problem, current=current,
                                          feasible=self._as_applied(current))

    def _as_applied(self, current: Candidate | None) -> Callable[[Candidate], Candidate]:
        """What the safety pipeline's rate stage would let through this cycle (the louver
        move interval and the OR dead-band): the command the plant would really get."""
        s = self.cfg.safety
        last = self.safety.last_louver_move_s
        louver_held = (current is not None and last is not None
                       and self.clock.monotonic() - last < s.min_louver_move_interval_s)

        def applied(c: Candidate) -> Candidate:
            if current is None:
                return c
            phi = current.phi_deg if louver_held else c.phi_deg
            or_pct = c.or_pct
            if (c.afr == current.afr and or_pct != current.or_pct
                    and abs(or_pct - current.or_pct) < s.or_deadband_pct):
                or_pct = current.or_pct
            return Candidate.of(phi, c.afr, or_pct)

        return applied


def oracle_theta(cfg: PanelConfig, plant: Plant) -> np.ndarray:
    """The plant's parameters on the lumped model's terms, for the controllers that plan with
    them (``oracle``, ``plant-oracle``'s candidate ranking).

    :meth:`~dsfd.sim.plant.config.TrueParameters.lumped_theta`, except for a plant whose
    diagonal regimes are orifices (the full plant): there the lumped power law's c and n have
    no true value, and the config's defaults (c 0.05, n 0.6) gave a regime-5 flow less than
    half the plant's. They are the orifice law's instead: n = ½ and c = √(2/(ρ K)) with K the
    plant's own diagonal path resistance at OR = 1 (both dampers and the cavity loss f_true,
    docs/model.md#plant-airflow). The slats' K_L(φ) is left out when the lumped model puts it
    in series with the power law (``model.louver_flow_loss``, docs/model.md#louver-flow-loss);
    otherwise it is in the path and c is averaged over the louver positions.
    """
    theta = plant.params.lumped_theta(cfg)
    if plant.options.diagonal_flow != "orifice":
        return theta
    model = plant.model
    rho = cfg.model.air_density_kgm3
    in_series = cfg.model.louver_flow_loss and cfg.louver is not None
    k_louver = [0.0] if in_series else [model.louver_terms(float(phi))[1] for phi in model.phis]
    coefs = []
    for k_l in k_louver:
        k = opening_resistance(model.openings, [1.0] * 4, [True] * 4, plant.params.f, k_l)
        coefs.append(math.sqrt(2.0 / (rho * (k[IB] + k[ET]))))
    theta[Param.C], theta[Param.N] = float(np.mean(coefs)), 0.5
    return theta


#: Controller classes and the information they get: (class, true state, true weather).
CONTROLLER_CLASSES: dict[str, tuple[type[Controller], bool, bool]] = {
    "oracle": (OracleController, True, True),
    "plant-oracle": (PlantOracleController, True, True),
    "mpc-true-weather": (OracleController, False, True),
    "mpc-true-state": (OracleController, True, False),
}
