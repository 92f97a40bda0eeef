"""The catalogue of calibrated parameters: one list for the configuration, the calibration,
the estimation and the truth plant.

The fit vector ϑ = (θ, q) (docs/model.md#parameters, docs/model.md#heat-offsets) is
indexed by :class:`Param`: ``theta[..., Param.F]``, never ``theta[..., 6]``. Its first
:data:`N_PARAMS` components are the paper's θ, the model's parameters; the rest are the
heat-flux offsets on nodes x1..x4. The convective multipliers of the truth plant are the
first six, :data:`CONVECTIVE_NAMES`, in the same order.

The panel file's ``parameters`` section (:class:`dsfd.config.panel.Parameters`) has one
entry per name of :data:`PARAMETER_NAMES`; ``calibration.fixed`` may name any of
:data:`FIT_NAMES`.
"""

from __future__ import annotations

from enum import IntEnum

__all__ = ["CONVECTIVE_NAMES", "FIT_NAMES", "N_FIT", "N_PARAMS", "OFFSET_NAMES",
           "PARAMETER_NAMES", "Param"]


class Param(IntEnum):
    """Position of each component in ϑ (and of the first nine in θ)."""

    H_OUT = 0  # L1 exterior ↔ outdoor air [W/(m2 K)]
    H_CA1 = 1  # L1 cavity face ↔ cavity air
    H_CA2 = 2  # louver (slat area) ↔ cavity air
    H_CA3 = 3  # L2 cavity face ↔ cavity air
    H_CA4 = 4  # DGU faces ↔ gap gas
    H_IN = 5  # L3 room face ↔ room air
    F = 6  # cavity form-loss factor [-] (regimes 1–4, 9)
    C = 7  # power-law flow coefficient [m3/(s Pa^n)] (regimes 5–8)
    N = 8  # power-law exponent [-]
    Q_X1 = 9  # heat-flux offsets on nodes x1..x4 [W/m2]
    Q_X2 = 10
    Q_X3 = 11
    Q_X4 = 12

    @property
    def key(self) -> str:
        """The name in files and messages (``h_out``, ``q_x1``)."""
        return self.name.lower()


#: ϑ in order: θ then the offsets.
FIT_NAMES: tuple[str, ...] = tuple(p.key for p in Param)
#: θ, the model's parameters (the panel file's ``parameters`` section).
N_PARAMS = Param.Q_X1.value
PARAMETER_NAMES: tuple[str, ...] = FIT_NAMES[:N_PARAMS]
#: The heat-flux offsets q.
OFFSET_NAMES: tuple[str, ...] = FIT_NAMES[N_PARAMS:]
N_FIT = len(FIT_NAMES)
#: The convective coefficients h (the truth plant's multipliers, in this order).
CONVECTIVE_NAMES: tuple[str, ...] = FIT_NAMES[Param.H_OUT:Param.H_IN + 1]
