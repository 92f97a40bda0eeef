"""Physical constants used across the physics modules (SI units)."""

from __future__ import annotations

#: Stefan–Boltzmann constant [W/(m2 K4)] (CODATA 2018).
SIGMA = 5.670374419e-8
#: Gravitational acceleration [m/s2] (docs/model.md#airflow uses 9.81).
GRAVITY = 9.81
#: Specific gas constant of dry air [J/(kg K)].
R_AIR = 287.05
#: Standard atmospheric pressure [Pa].
STANDARD_PRESSURE_PA = 101325.0
#: 0 °C in kelvin [K].
T_ZERO = 273.15
