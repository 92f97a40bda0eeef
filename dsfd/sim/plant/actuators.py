"""Louver motor and damper actuators of the simulated plant (docs/model.md#plant-sensors).

Commands are validated, never clipped: an angle off the motor's 18° grid, a regime the
panel's dampers cannot realise or an opening outside 0..100 % raises :class:`CommandError`,
which the daemon can catch and log. Accepted commands drive analytic trajectories:

* louver: moves towards the target at a constant rate (3 °/s default), so it reaches the
  target after |Δφ|/rate;
* dampers: first-order lag towards their targets (the open set of the regime at the
  commanded OR, quantised to 1 %, the others 0), time constant τ = t_rise / ln 9 so that
  the 10–90 % rise time is 15 s (Modelica Buildings ``riseTime`` default).

With ``ideal=True`` both follow the command instantly (docs/model.md#plant-switches).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import REGIME_OPENINGS, PanelConfig
from dsfd.physics.airflow import OPENING_NAMES

#: Below this blade position a closing damper counts as shut (flow set changes) [-].
DAMPER_SHUT = 1e-4
_GRID_TOL_DEG = 1e-6


class CommandError(ValueError):
    """A control command the plant (or the real façade) cannot execute."""


@dataclass(frozen=True)
class Command:
    """One control vector of the paper (Eq. 6).

    Attributes
    ----------
    phi_deg : float, [deg]
        Louver slat angle, −90…90 on the motor grid.
    afr : int
        Commanded airflow regime 1..10 (selects the damper set).
    or_pct : float, [%]
        Damper opening ratio 0..100.
    """

    phi_deg: float
    afr: int
    or_pct: float

    def as_dict(self) -> dict[str, float]:
        return {"phi_deg": float(self.phi_deg), "afr": int(self.afr),
                "or_pct": float(self.or_pct)}


def damper_mask(afr: int) -> np.ndarray:
    """Open dampers (EB, ET, IB, IT) of a regime as a bool array (docs/model.md#regimes)."""
    return np.array([name in REGIME_OPENINGS[afr] for name in OPENING_NAMES])


def validate_command(cfg: PanelConfig, command: Command | Mapping[str, float], *,
                     or_quantum_pct: float | None = 1.0) -> Command:
    """Check a command against the panel and quantise the opening.

    Parameters
    ----------
    cfg : PanelConfig
    command : Command or mapping with ``phi_deg``, ``afr``, ``or_pct``
    or_quantum_pct : float or None, [%]
        Opening resolution; OR is rounded to a multiple of it (None: no rounding).

    Returns
    -------
    Command
        With ``afr`` as int and ``or_pct`` quantised.

    Raises
    ------
    CommandError
        Missing field, non-finite value, φ outside −90…90 or off the louver's step grid,
        regime outside 1..10 or needing dampers the panel lacks, OR outside 0..100.
    """
    if isinstance(command, Mapping):
        missing = [k for k in ("phi_deg", "afr", "or_pct") if k not in command]
        if missing:
            raise CommandError(f"command lacks {', '.join(missing)}")
        phi, afr, or_pct = command["phi_deg"], command["afr"], command["or_pct"]
    else:
        phi, afr, or_pct = command.phi_deg, command.afr, command.or_pct
    try:
        phi, afr_f, or_pct = float(phi), float(afr), float(or_pct)
    except (TypeError, ValueError):
        raise CommandError(f"command values must be numbers: phi_deg={phi!r}, afr={afr!r}, "
                           f"or_pct={or_pct!r}") from None
    if not math.isfinite(phi) or not -90.0 <= phi <= 90.0:
        raise CommandError(f"phi_deg {phi} outside -90..90")
    lv = cfg.louver
    if lv is not None:
        grid = np.asarray(lv.angles_deg())
        if np.min(np.abs(grid - phi)) > _GRID_TOL_DEG:
            raise CommandError(f"phi_deg {phi} is not on the {lv.step_deg:g} deg louver grid "
                               f"({', '.join(f'{a:g}' for a in grid)})")
    if not math.isfinite(afr_f) or afr_f != round(afr_f) or not 1 <= afr_f <= 10:
        raise CommandError(f"afr {afr} is not an airflow regime 1..10")
    afr_i = int(afr_f)
    available = cfg.openings.available_regimes()
    if afr_i not in available:
        raise CommandError(f"regime {afr_i} needs dampers this panel does not have "
                           f"(available: {available})")
    if not math.isfinite(or_pct) or not 0.0 <= or_pct <= 100.0:
        raise CommandError(f"or_pct {or_pct} outside 0..100")
    if or_quantum_pct is None:
        return Command(phi_deg=phi, afr=afr_i, or_pct=or_pct)
    or_q = min(100.0, round(or_pct / or_quantum_pct) * or_quantum_pct)
    return Command(phi_deg=phi, afr=afr_i, or_pct=or_q)


@dataclass
class Actuators:
    """Actuator positions as analytic functions of time (louver ramp, damper lag).

    Attributes
    ----------
    ideal : bool
        Follow commands instantly.
    rate_degs : float, [deg/s]
        Louver speed.
    tau_s : float, [s]
        Damper time constant.
    """

    ideal: bool
    rate_degs: float
    tau_s: float
    phi_from: float = 0.0
    phi_to: float = 0.0
    t_phi: float = 0.0
    y_from: np.ndarray | None = None
    y_to: np.ndarray | None = None
    t_y: float = 0.0

    @classmethod
    def for_options(cls, *, ideal: bool, rate_degs: float, rise_time_s: float) -> Actuators:
        return cls(ideal=ideal, rate_degs=rate_degs, tau_s=rise_time_s / math.log(9.0))

    def reset(self, phi_deg: float, openings: np.ndarray, t: float) -> None:
        """Place the actuators at rest at ``phi_deg`` and ``openings`` (4,) [-]."""
        self.phi_from = self.phi_to = float(phi_deg)
        self.y_from = np.array(openings, float)
        self.y_to = self.y_from.copy()
        self.t_phi = self.t_y = float(t)

    def command(self, t: float, phi_deg: float, openings: np.ndarray) -> None:
        """New targets at time ``t``; motion starts from the current positions."""
        if self.ideal:
            self.reset(phi_deg, openings, t)
            return
        self.phi_from, self.t_phi = self.phi_at(t), float(t)
        self.phi_to = float(phi_deg)
        self.y_from, self.t_y = self.dampers_at(t), float(t)
        self.y_to = np.array(openings, float)

    def phi_at(self, t: float) -> float:
        """Louver angle at time ``t`` [deg]."""
        delta = self.phi_to - self.phi_from
        travel = self.rate_degs * max(0.0, t - self.t_phi)
        if travel >= abs(delta):
            return self.phi_to
        return self.phi_from + math.copysign(travel, delta)

    def louver_arrival_s(self) -> float:
        """Time at which the louver reaches its target [s]."""
        return self.t_phi + abs(self.phi_to - self.phi_from) / self.rate_degs

    def louver_moving(self, t: float) -> bool:
        return t < self.louver_arrival_s() and self.phi_to != self.phi_from

    def dampers_at(self, t: float) -> np.ndarray:
        """Blade positions (EB, ET, IB, IT) at time ``t`` [-]."""
        decay = math.exp(-max(0.0, t - self.t_y) / self.tau_s)
        return self.y_to + (self.y_from - self.y_to) * decay

    def dampers_settled(self, t: float, tol: float = DAMPER_SHUT) -> bool:
        """True once every damper is within ``tol`` of its target."""
        return bool(np.max(np.abs(self.dampers_at(t) - self.y_to)) <= tol)

    def settle(self, t: float) -> None:
        """Snap dampers that are within :data:`DAMPER_SHUT` of their targets."""
        if self.dampers_settled(t):
            self.y_from = self.y_to.copy()
            self.t_y = t
