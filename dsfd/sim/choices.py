"""Names of the closed-loop controllers and calibrations (no imports: the CLI lists them
without loading the simulation, so ``dsfd run`` does not carry the truth plant)."""

from __future__ import annotations

__all__ = ["CALIBRATIONS", "CONTROLLERS", "TRUE_THETA"]

CONTROLLERS = ("mpc", "paper-sqp", "rule", "fixed", "oracle", "plant-oracle",
               "mpc-true-weather", "mpc-true-state", "mpc-true-params")
CALIBRATIONS = ("online", "offline", "none")
#: Controllers that plan with the plant's own parameters (no calibration).
TRUE_THETA = ("oracle", "plant-oracle", "mpc-true-params")
