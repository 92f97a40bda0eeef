"""The paper's excitation protocol: random louver angle and airflow regime every 30–90 min.

Yoon et al. (2009), Fig. 7(a): during the airflow experiment "the louver angles and the
airflow regimes were randomly changed". The hold time of each setting is drawn uniformly
from [30, 90] min [ENG reading of Fig. 7a], the louver angle uniformly from the motor grid
and the regime uniformly from the regimes the panel's dampers can realise (by default those
of the paper's Table 1: 1, 3, 5, 6). The opening ratio stays at 100 % unless configured.
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.sim.plant.actuators import Command, validate_command

#: Regimes of the paper's Table 1 (mean cavity velocities 2.8–14.1 cm/s).
PAPER_REGIMES = (1, 3, 5, 6)


@dataclass(frozen=True)
class Schedule:
    """Piecewise-constant commands: ``commands[i]`` holds from ``times_s[i]`` on."""

    times_s: tuple[float, ...]
    commands: tuple[Command, ...]

    def at(self, t_s: float) -> Command:
        """The command in force at ``t_s`` (the first one before the schedule starts)."""
        i = bisect.bisect_right(self.times_s, t_s) - 1
        return self.commands[max(i, 0)]

    def __len__(self) -> int:
        return len(self.times_s)


def paper_protocol(cfg: PanelConfig, *, seed: int, start_s: float, duration_s: float,
                   or_pct: float = 100.0, regimes: Sequence[int] | None = None,
                   hold_min_s: float = 1800.0, hold_max_s: float = 5400.0) -> Schedule:
    """Random (φ, AFR) every 30–90 min over ``duration_s`` from ``start_s`` (seeded).

    Parameters
    ----------
    cfg : PanelConfig
    seed : int
    start_s, duration_s : float, [s]
    or_pct : float, [%]
        Damper opening of every command.
    regimes : sequence of int, optional
        Candidate regimes; default :data:`PAPER_REGIMES`. Only those the panel's dampers
        can realise are used; if none of the defaults is available, all available ones.
    hold_min_s, hold_max_s : float, [s]
        Range of the uniformly drawn hold time (rounded to whole minutes).

    Returns
    -------
    Schedule
        Commands on the louver grid (φ = 0 for a panel without louver), validated.
    """
    if not 0 < hold_min_s <= hold_max_s:
        raise ValueError(f"need 0 < hold_min_s <= hold_max_s, got {hold_min_s}, {hold_max_s}")
    available = cfg.openings.available_regimes()
    wanted = PAPER_REGIMES if regimes is None else tuple(regimes)
    pool = [r for r in wanted if r in available]
    if not pool:
        if regimes is not None:
            raise ValueError(f"none of the regimes {tuple(regimes)} is available on this panel "
                             f"(available: {available})")
        pool = [r for r in available if r != 10] or list(available)
    angles = cfg.louver.angles_deg() if cfg.louver is not None else (0.0,)
    rng = np.random.default_rng(seed)
    times: list[float] = []
    commands: list[Command] = []
    t = float(start_s)
    end = float(start_s) + float(duration_s)
    while t < end:
        cmd = Command(phi_deg=float(angles[rng.integers(len(angles))]),
                      afr=int(pool[rng.integers(len(pool))]), or_pct=float(or_pct))
        times.append(t)
        commands.append(validate_command(cfg, cmd))
        t += 60.0 * max(1, round(float(rng.uniform(hold_min_s, hold_max_s)) / 60.0))
    return Schedule(tuple(times), tuple(commands))
