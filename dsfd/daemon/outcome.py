"""What one cycle did: the record the loop hands to the log line, the store, the run summary,
the benches and the tests."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from dsfd.control.comfort import ComfortCheck
from dsfd.control.occupancy import EffectiveOccupancy, OccupancyOverride
from dsfd.control.optimiser import Decision
from dsfd.daemon.calibration import UpdateOutcome
from dsfd.daemon.hold import Hold
from dsfd.daemon.observer import StateEstimate
from dsfd.daemon.quality import QualityReport
from dsfd.daemon.safety import SafetyResult
from dsfd.drivers.base import Command, WriteResult

__all__ = ["CycleOutcome"]


@dataclass
class CycleOutcome:
    """What one cycle did (for the log line, the summary, the bench and the tests)."""

    cycle: int
    slot: int
    skipped_slots: int
    time_s: float
    method: str
    command: Command
    proposed: Decision | None
    fallback: str
    heating: bool | None
    safety: SafetyResult
    write_status: str
    write: WriteResult | None
    quality: QualityReport
    calibration: UpdateOutcome | None
    timings_ms: dict[str, float] = field(default_factory=dict)
    manual_override: bool = False
    store_ok: bool = True
    #: The state estimate of this cycle (with the observer's one-step prediction).
    estimate: StateEstimate | None = None
    #: The actuator position in effect from this cycle on: the command unless a dry run
    #: or a hold left the actuators where they were read.
    applied: Command | None = None
    #: x1..x6 predicted at ``time_s + horizon_s`` with ``applied`` held [K].
    horizon_x_k: np.ndarray | None = None
    horizon_s: float = math.nan
    #: A simulated plant's own heat into the room since its start, by term [J].
    plant_heat_j: Mapping[str, float] | None = None
    #: The manual hold in force this cycle (None: the controller decided).
    hold: Hold | None = None
    #: The control objective in force (heating, cooling, auto) and the operator ``mode``
    #: command that set it (None: the panel file's ``control.mode``).
    objective_mode: str | None = None
    mode_command_id: int | None = None
    #: Seconds since the run's first cycle on the monotonic cycle grid.
    run_elapsed_s: float = 0.0
    #: Events of this cycle beyond the sensor faults: (level, kind, message).
    events: list[tuple[str, str, str]] = field(default_factory=list)
    #: Operator commands handled this cycle: (command_id, status, reason).
    command_results: list[tuple[int, str, str]] = field(default_factory=list)
    #: The command's comfort now, the limits it would break and what bound its choice
    #: (docs/model.md#comfort-trace). None without a forecast or a usable estimate.
    comfort: ComfortCheck | None = None
    #: The occupancy in force this cycle and where it came from (issue 36), and the
    #: operator's occupancy override in force (None: none).
    occupancy: EffectiveOccupancy | None = None
    occupancy_override: OccupancyOverride | None = None

    @property
    def cycle_ms(self) -> float:
        return self.timings_ms.get("total", math.nan)
