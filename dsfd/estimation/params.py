"""The calibrated vector: θ of the paper plus heat-flux offsets; coordinates, bounds, priors.

The fit vector is ϑ = (θ, q) with

* θ = (h_out, h_ca1, h_ca2, h_ca3, h_ca4, h_in, f, c, n) (:data:`PARAMETER_NAMES`), the
  paper's parameters, fitted in the coordinates z = log θ except the exponent n (its range
  [0.5, 1] is narrow and not a scale); bounds from the panel configuration (f per
  docs/model.md#parameters);
* q = (q_x1, q_x2, q_x3, q_x4) [W/m2] (:data:`OFFSET_NAMES`), a constant heat flux added to
  the absorbed short-wave of nodes 1–4 (``StepInputs.sources``), fitted as is within
  ±``offset_bound_wm2``. They absorb what the lumped model cannot represent and the
  window makes evident — the sky temperature under overcast skies, hourly-averaged
  irradiance, sensor offsets — the input-disturbance model of offset-free estimation
  (Pannocchia & Rawlings 2003). ``calibration.heat_offsets: false`` fixes them at 0.

Which components a fit may move:

* never — what the panel cannot excite: h_ca2 and q_x4 without a louver; f when no regime
  of 1–4 or 9 (orifice paths) is available; c and n when none of 5–8 is, or when 5–8 are
  orifice paths too (``model.diagonal_flow: orifice``, docs/model.md#diagonal-flow); and
  those listed in ``calibration.fixed``;
* per window — f only from windows containing an orifice path (1–4 and 9, and 5–8 under
  ``diagonal_flow: orifice``), c and n only from windows containing a regime 5–8, q_xi
  only when x_i is measured in the window (the others are held at their prior).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dsfd.config.calibration import Calibration
from dsfd.config.panel import PanelConfig
from dsfd.config.parameters import (
    FIT_NAMES,
    N_FIT,
    N_PARAMS,
    OFFSET_NAMES,
    PARAMETER_NAMES,
    Param,
)
from dsfd.physics.coupling import StepInputs

__all__ = ["FIT_NAMES", "LINEAR_NAMES", "N_FIT", "N_PARAMS", "OFFSET_NAMES", "ORIFICE_REGIMES",
           "PARAMETER_NAMES", "POWER_LAW_REGIMES", "Param", "ParameterSpace", "full_vector",
           "with_offsets"]

#: The offsets q in ϑ.
I_Q = np.arange(N_PARAMS, N_FIT)
#: Components fitted as they are, not as their log: the exponent n (its range is not a
#: scale) and the offsets (which change sign).
LINEAR_NAMES = frozenset({"n", *OFFSET_NAMES})
#: Regimes whose flow law uses f (orifice paths) and c, n (power-law paths).
ORIFICE_REGIMES = frozenset({1, 2, 3, 4, 9})
POWER_LAW_REGIMES = frozenset({5, 6, 7, 8})


def full_vector(theta: np.ndarray) -> np.ndarray:
    """ϑ (..., 13) from θ (..., 9) (zero offsets) or ϑ itself."""
    theta = np.asarray(theta, float)
    if theta.shape[-1] == N_FIT:
        return theta
    pad = np.zeros((*theta.shape[:-1], N_FIT - N_PARAMS))
    return np.concatenate([theta, pad], axis=-1)


def with_offsets(inputs: StepInputs, q: np.ndarray) -> StepInputs:
    """Inputs with heat-flux offsets ``q`` (broadcastable to ``sources``) [W/m2] added."""
    q = np.asarray(q, float)
    if not np.any(q):
        return inputs
    return inputs._replace(sources=np.asarray(inputs.sources) + q)


@dataclass(frozen=True, eq=False)
class ParameterSpace:
    """Coordinates, bounds and structural freedom of the fit vector ϑ for one panel.

    Attributes
    ----------
    default, lower, upper : ndarray (13,)
        Panel defaults (the first prior; offsets 0) and bounds, in ϑ units.
    is_log : ndarray (13,), bool
        Fitted as log ϑ (the h's, f and c).
    prior_sd : ndarray (13,)
        Spread of the first prior in fitting coordinates.
    drift_sd : ndarray (13,)
        Random-walk growth of the prior spread per √hour, fitting coordinates.
    fixed : ndarray (13,), bool
        Never calibrated on this panel.
    orifice_regimes : frozenset of int
        Regimes whose flow uses f (:data:`ORIFICE_REGIMES`, and 5–8 under
        ``model.diagonal_flow: orifice``).
    """

    default: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    is_log: np.ndarray
    prior_sd: np.ndarray
    drift_sd: np.ndarray
    fixed: np.ndarray
    orifice_regimes: frozenset[int] = ORIFICE_REGIMES

    @classmethod
    def from_panel(cls, cfg: PanelConfig, settings: Calibration | None = None) -> ParameterSpace:
        """Space of panel ``cfg`` with the calibration settings (default ``cfg.calibration``)."""
        s = settings or cfg.calibration
        p = cfg.parameters
        n_q = len(OFFSET_NAMES)
        default = np.array([*p.values("default"), *[0.0] * n_q])
        lower = np.array([*p.values("lower"), *[-s.offset_bound_wm2] * n_q])
        upper = np.array([*p.values("upper"), *[s.offset_bound_wm2] * n_q])
        is_log = np.array([k not in LINEAR_NAMES for k in FIT_NAMES])
        prior_sd = np.array([s.prior_sd_n if k == "n" else s.offset_sd_wm2 if k in OFFSET_NAMES
                             else s.prior_log_sd for k in FIT_NAMES])
        drift_sd = np.where(np.isin(FIT_NAMES, OFFSET_NAMES), s.offset_drift_wm2_per_h,
                            s.drift_log_sd_per_h)
        fixed = np.array([k in s.fixed for k in FIT_NAMES])
        regimes = set(cfg.openings.available_regimes())
        diagonal_orifice = cfg.model.diagonal_flow == "orifice"
        orifice = ORIFICE_REGIMES | POWER_LAW_REGIMES if diagonal_orifice else ORIFICE_REGIMES
        if cfg.louver is None:
            fixed[[Param.H_CA2, Param.Q_X4]] = True
        if not regimes & orifice:
            fixed[Param.F] = True
        if diagonal_orifice or not regimes & POWER_LAW_REGIMES:
            fixed[[Param.C, Param.N]] = True
        if not s.heat_offsets:
            fixed[I_Q] = True
        return cls(default, lower, upper, is_log, prior_sd, drift_sd, fixed, orifice)

    # ----------------------------------------------------------------- coordinates
    def to_z(self, theta: np.ndarray) -> np.ndarray:
        """Fitting coordinates z of ϑ (log where :attr:`is_log`)."""
        theta = full_vector(theta)
        return np.where(self.is_log, np.log(np.where(self.is_log, theta, 1.0)), theta)

    def to_theta(self, z: np.ndarray) -> np.ndarray:
        """ϑ from z, clipped into the bounds."""
        z = np.asarray(z, float)
        theta = np.where(self.is_log, np.exp(np.where(self.is_log, z, 0.0)), z)
        return np.clip(theta, self.lower, self.upper)

    @property
    def z_lower(self) -> np.ndarray:
        return self.to_z(self.lower)

    @property
    def z_upper(self) -> np.ndarray:
        return self.to_z(self.upper)

    def clip(self, theta: np.ndarray) -> np.ndarray:
        """ϑ clipped into the bounds."""
        return np.clip(full_vector(theta), self.lower, self.upper)

    def theta_std_error(self, theta: np.ndarray, cov_z: np.ndarray) -> np.ndarray:
        """Standard errors in ϑ units from the z covariance (delta method: σ_θ = θ σ_logθ)."""
        sd_z = np.sqrt(np.clip(np.diag(cov_z), 0.0, None))
        return np.where(self.is_log, full_vector(theta) * sd_z, sd_z)

    # ----------------------------------------------------------------- freedom
    def free_in_window(self, regimes: np.ndarray,
                       measured: tuple[str, ...] = ("x1", "x2", "x3", "x4")) -> np.ndarray:
        """Components a window may move [bool (13,)].

        ``regimes`` are the commanded regimes of the window, ``measured`` the states with
        residuals in it (offsets of unmeasured nodes are not identifiable).
        """
        present = set(np.unique(np.asarray(regimes, int)).tolist())
        free = ~self.fixed
        if not present & self.orifice_regimes:
            free[Param.F] = False
        if not present & POWER_LAW_REGIMES:
            free[[Param.C, Param.N]] = False
        for i, name in zip(I_Q, OFFSET_NAMES, strict=True):
            if name[2:] not in measured:
                free[i] = False
        return free

    def first_prior(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean (z of the defaults) and covariance (diagonal) of the first prior."""
        return self.to_z(self.default), np.diag(self.prior_sd ** 2)

    def grown_prior(self, cov_z: np.ndarray, hours: float) -> np.ndarray:
        """Arrival-cost covariance after ``hours`` of random-walk drift, capped by the first prior.

        Notes
        -----
        P ← P + diag(q²) Δt with q = :attr:`drift_sd` per √hour; a component whose
        variance would exceed that of the first prior is reset to it (and decorrelated),
        so an unexcited parameter never becomes freer than its default allows.
        """
        cov = np.array(cov_z, float) + np.diag(self.drift_sd ** 2) * max(hours, 0.0)
        cap = self.prior_sd ** 2
        over = np.diag(cov) > cap
        if over.any():
            cov[over, :] = 0.0
            cov[:, over] = 0.0
            cov[over, over] = cap[over]
        return 0.5 * (cov + cov.T)
