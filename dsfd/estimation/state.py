"""Calibration state: what a restart needs to resume the self-calibration.

:class:`CalibrationState` holds the current estimate θ̂, its covariance in the fitting
coordinates (which is the arrival-cost prior of the next update), the first prior, the
time of the last update and counters. :meth:`CalibrationState.to_dict` gives a JSON-ready
mapping with a schema version; :func:`state_from_dict` validates such a mapping and names
the offending key. Files are read and written by :mod:`dsfd.storage.calibration_file`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dsfd.estimation.params import FIT_NAMES, N_FIT, ParameterSpace

SCHEMA = "dsfd.calibration-state"
SCHEMA_VERSION = 2
#: Versions this dsfd reads, and the names version 1 gave the keys that have changed since:
#: version 2 calls the fit coordinates z (``cov_z``), version 1 called them φ.
READABLE_VERSIONS = (1, 2)
RENAMED_IN_VERSION_2 = {"cov_z": "cov_phi", "prior_sd_z": "prior_sd_phi"}


class CalibrationStateError(ValueError):
    """A calibration-state mapping that cannot be used; the message names the key."""


@dataclass(frozen=True, eq=False)
class CalibrationState:
    """Self-calibration state of one panel.

    Attributes
    ----------
    panel_id : str
    theta : ndarray (13,)
        Current estimate ϑ̂ = (θ̂, q̂): h [W/(m2 K)], f [-], c [m3/(s Pa^n)], n [-] and the
        heat-flux offsets q_x1..q_x4 [W/m2] (:mod:`dsfd.estimation.params`).
    cov_z : ndarray (13, 13)
        Covariance of ϑ̂ in the fitting coordinates (log θ; n and q linear).
    prior_theta : ndarray (13,)
        Mean of the first prior (the panel defaults when the state was created).
    prior_sd_z : ndarray (13,)
        Spread of the first prior in fitting coordinates.
    last_update_s : float or None, [s]
        UTC unix time of the newest data in the last successful update.
    updates, failed_updates : int
        Successful and failed on-line updates since the state was created.
    residuals_last : int
        Residuals in the last successful update.
    cost_last : float
        Objective value (robust, weighted) of the last successful update.
    free_last : tuple of str
        Parameters the last update was allowed to move.
    """

    panel_id: str
    theta: np.ndarray
    cov_z: np.ndarray
    prior_theta: np.ndarray
    prior_sd_z: np.ndarray
    last_update_s: float | None = None
    updates: int = 0
    failed_updates: int = 0
    residuals_last: int = 0
    cost_last: float = math.nan
    free_last: tuple[str, ...] = field(default_factory=tuple)

    @classmethod
    def initial(cls, panel_id: str, space: ParameterSpace) -> CalibrationState:
        """The state before any data: θ̂ = defaults, covariance = first prior."""
        _mean, cov = space.first_prior()
        return cls(panel_id=panel_id, theta=space.default.copy(), cov_z=cov,
                   prior_theta=space.default.copy(), prior_sd_z=space.prior_sd.copy())

    def std_error(self, space: ParameterSpace) -> np.ndarray:
        """Standard errors of θ̂ in θ units."""
        return space.theta_std_error(self.theta, self.cov_z)

    def to_dict(self, space: ParameterSpace | None = None) -> dict[str, Any]:
        """JSON-ready mapping (parameters by name; covariance rows in name order)."""
        names = list(FIT_NAMES)
        doc: dict[str, Any] = {
            "schema": SCHEMA,
            "schema_version": SCHEMA_VERSION,
            "panel_id": self.panel_id,
            "parameter_names": names,
            "theta": {k: float(v) for k, v in zip(names, self.theta, strict=True)},
            "cov_z": [[float(v) for v in row] for row in self.cov_z],
            "prior_theta": {k: float(v) for k, v in zip(names, self.prior_theta, strict=True)},
            "prior_sd_z": {k: float(v) for k, v in zip(names, self.prior_sd_z,
                                                         strict=True)},
            "last_update_s": self.last_update_s,
            "updates": self.updates,
            "failed_updates": self.failed_updates,
            "residuals_last": self.residuals_last,
            "cost_last": None if not math.isfinite(self.cost_last) else self.cost_last,
            "free_last": list(self.free_last),
        }
        if space is not None:
            se = self.std_error(space)
            doc["std_error"] = {k: float(v) for k, v in zip(names, se, strict=True)}
        return doc


def _number(doc: dict, key: str, *, allow_none: bool = False) -> float | None:
    value = doc.get(key)
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise CalibrationStateError(f"key {key!r}: expected a finite number, got {value!r}")
    return float(value)


def _count(doc: dict, key: str) -> int:
    value = doc.get(key, 0)
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise CalibrationStateError(f"key {key!r}: expected a count >= 0, got {value!r}")
    return value


def _vector(doc: dict, key: str) -> np.ndarray:
    value = doc.get(key)
    if not isinstance(value, dict):
        raise CalibrationStateError(f"key {key!r}: expected a mapping of parameter values")
    out = np.empty(N_FIT)
    for i, name in enumerate(FIT_NAMES):
        out[i] = _number(value, name) if name in value else _missing(f"{key}.{name}")
    extra = sorted(set(value) - set(FIT_NAMES))
    if extra:
        raise CalibrationStateError(f"key {key}.{extra[0]}: unknown parameter")
    return out


def _missing(key: str) -> float:
    raise CalibrationStateError(f"key {key!r}: missing")


def state_from_dict(doc: Any, *, space: ParameterSpace, panel_id: str) -> CalibrationState:
    """Validate a mapping written by :meth:`CalibrationState.to_dict`.

    Checks the schema name and version, the panel id, the parameter names, finite values,
    θ inside the current bounds, and a symmetric covariance with positive diagonal.

    Raises
    ------
    CalibrationStateError
        Naming the first offending key.
    """
    if not isinstance(doc, dict):
        raise CalibrationStateError("top level: expected a JSON object")
    if doc.get("schema") != SCHEMA:
        raise CalibrationStateError(f"key 'schema': expected {SCHEMA!r}, got "
                                    f"{doc.get('schema')!r}")
    version = doc.get("schema_version")
    if version not in READABLE_VERSIONS:
        raise CalibrationStateError(f"key 'schema_version': {version!r} is not supported "
                                    f"(this dsfd reads {', '.join(map(str, READABLE_VERSIONS))})")
    renamed = RENAMED_IN_VERSION_2 if version == 1 else {}
    cov_key, prior_sd_key = (renamed.get(k, k) for k in ("cov_z", "prior_sd_z"))
    if doc.get("panel_id") != panel_id:
        raise CalibrationStateError(f"key 'panel_id': state is for panel "
                                    f"{doc.get('panel_id')!r}, not {panel_id!r}")
    if doc.get("parameter_names") != list(FIT_NAMES):
        raise CalibrationStateError("key 'parameter_names': expected "
                                    f"{list(FIT_NAMES)}")
    theta = _vector(doc, "theta")
    for i, name in enumerate(FIT_NAMES):
        if not space.lower[i] <= theta[i] <= space.upper[i]:
            raise CalibrationStateError(
                f"key 'theta.{name}': {theta[i]:g} outside the panel bounds "
                f"[{space.lower[i]:g}, {space.upper[i]:g}]")
    cov = doc.get(cov_key)
    try:
        cov = np.array(cov, dtype=float)
    except (TypeError, ValueError):
        raise CalibrationStateError(f"key {cov_key!r}: expected a 13 x 13 list of "
                                    "numbers") from None
    if cov.shape != (N_FIT, N_FIT) or not np.all(np.isfinite(cov)):
        raise CalibrationStateError(f"key {cov_key!r}: expected a 13 x 13 list of finite "
                                    "numbers")
    if not np.allclose(cov, cov.T, rtol=1e-6, atol=1e-12) or np.any(np.diag(cov) <= 0):
        raise CalibrationStateError(f"key {cov_key!r}: not a covariance (asymmetric or "
                                    "non-positive diagonal)")
    free = doc.get("free_last", [])
    if not isinstance(free, list) or any(k not in FIT_NAMES for k in free):
        raise CalibrationStateError("key 'free_last': expected a list of parameter names")
    cost = doc.get("cost_last")
    return CalibrationState(
        panel_id=panel_id,
        theta=theta,
        cov_z=0.5 * (cov + cov.T),
        prior_theta=_vector(doc, "prior_theta"),
        prior_sd_z=_vector(doc, prior_sd_key),
        last_update_s=_number(doc, "last_update_s", allow_none=True),
        updates=_count(doc, "updates"),
        failed_updates=_count(doc, "failed_updates"),
        residuals_last=_count(doc, "residuals_last"),
        cost_last=math.nan if cost is None else float(_number(doc, "cost_last")),
        free_last=tuple(free),
    )
