"""Names of the closed-loop controllers and calibrations (nothing but ``typing``: the CLI lists
them without loading the simulation, so ``dsfd run`` does not carry the truth plant).

Each set of names is one ``Literal`` type, and its tuple is read off the type, so a new
controller is added in one place.
"""

from __future__ import annotations

from typing import Literal, get_args

__all__ = ["BENCH_CONTROLLERS", "CALIBRATIONS", "CONTROLLERS", "OCCUPANCY_CHOICES", "TRUE_THETA",
           "CalibrationName", "ControllerName", "OccupancyName"]

ControllerName = Literal["mpc", "paper-sqp", "rule", "fixed", "oracle", "plant-oracle",
                         "mpc-true-weather", "mpc-true-state", "mpc-true-params"]
CalibrationName = Literal["online", "offline", "none"]
#: Occupancy schedules of the closed-loop bench (dsfd.sim.comfort_kpis.occupancy_for).
OccupancyName = Literal["office-every-day", "office-weekdays", "panel", "none"]
CONTROLLERS: tuple[str, ...] = get_args(ControllerName)
CALIBRATIONS: tuple[str, ...] = get_args(CalibrationName)
OCCUPANCY_CHOICES: tuple[str, ...] = get_args(OccupancyName)
#: Controllers that plan with the plant's own parameters (no calibration).
TRUE_THETA = ("oracle", "plant-oracle", "mpc-true-params")
#: What ``dsfd bench closed-loop`` runs by default, in its table's order: the baseline, the
#: controller, the two references and the three legs of the split.
BENCH_CONTROLLERS = ("rule", "mpc", "oracle", "plant-oracle", "mpc-true-weather",
                     "mpc-true-state", "mpc-true-params")
