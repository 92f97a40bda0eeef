"""The calibration stage of the loop: the daemon's record of recent cycles and the on-line
calibrator (:class:`dsfd.estimation.calibration.OnlineCalibrator`) behind it.

Every cycle adds one row in the measured-data convention of :mod:`dsfd.measured` — sensor
readings at the row time (flagged readings as NaN, so they never enter the fit), the
commanded actuator position applied from that row until the next one (filled in once the
write stage knows it). When the calibrator says an update is due, the last
``calibration.window_h`` hours are cut into model steps (:func:`~dsfd.estimation.stepdata.
step_data`), the observer runs over them (:func:`~dsfd.estimation.observer.observe`) and
θ̂ is refitted. The fit runs on a *copy* of the calibrator in a worker thread: an update that
misses its budget is abandoned and its result never applied, so θ̂ only changes between
cycles. Every successful update is saved atomically (``calibration.json`` in the state
directory, :mod:`dsfd.storage.calibration_file`); a restart resumes from it.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.drivers.base import Command, Sample
from dsfd.estimation.calibration import OnlineCalibrator, UpdateReport, window_start
from dsfd.estimation.observer import observe
from dsfd.estimation.params import FIT_NAMES, N_PARAMS, ParameterSpace, full_vector
from dsfd.estimation.state import CalibrationState, CalibrationStateError, state_from_dict
from dsfd.estimation.stepdata import step_data
from dsfd.measured import CONTROL_COLUMNS, KNOWN_COLUMNS, MeasuredData, MeasuredDataError
from dsfd.physics.model import LumpedModel
from dsfd.storage.calibration_file import load_state_or_prior, save_state

__all__ = ["STATE_FILE", "CalibrationStage", "UpdateOutcome"]

STATE_FILE = "calibration.json"
_SENSOR_COLUMNS = tuple(c for c in KNOWN_COLUMNS if c not in CONTROL_COLUMNS)


@dataclass(frozen=True)
class UpdateOutcome:
    """What an update attempt did: ``updated`` True if θ̂ changed, else ``skipped`` says why."""

    updated: bool
    skipped: str
    theta: np.ndarray
    cost: float
    n_residuals: int


class CalibrationStage:
    """Row record, calibrator and state file of one panel."""

    def __init__(self, cfg: PanelConfig, model: LumpedModel, *, state_dir: Path) -> None:
        self.path = state_dir / STATE_FILE
        self.cfg = cfg
        self.model = model
        self.space = ParameterSpace.from_panel(cfg)
        state, self.resume_message = load_state_or_prior(self.path, space=self.space,
                                                         panel_id=cfg.panel.id)
        self.resumed = self.resume_message.startswith("resumed")
        self.calibrator = OnlineCalibrator(model, cfg.calibration, state=state)
        self._rows: deque[tuple[float, dict[str, float]]] = deque()
        self._run_start_s: float | None = None
        self._retry_after_s = -math.inf  # an attempt that fitted nothing waits an interval

    @property
    def theta(self) -> np.ndarray:
        """The model parameters θ (9,) of the current estimate."""
        return full_vector(self.calibrator.state.theta)[:N_PARAMS].copy()

    @property
    def offsets(self) -> np.ndarray:
        """The calibrated heat-flux offsets q [W/m2] added to the absorbed short-wave of
        nodes 1-4 (zeros if the estimate has none)."""
        return full_vector(self.calibrator.state.theta)[N_PARAMS:].copy()

    @property
    def state(self) -> CalibrationState:
        return self.calibrator.state

    def theta_by_name(self) -> dict[str, float]:
        """Every component of the fit vector by name (θ, then the offsets)."""
        return {k: float(v) for k, v in zip(FIT_NAMES, full_vector(self.calibrator.state.theta),
                                            strict=True)}

    def reconfigure(self, cfg: PanelConfig, model: LumpedModel) -> str:
        """Use a reloaded configuration; keep θ̂ if it is valid under the new bounds."""
        space = ParameterSpace.from_panel(cfg)
        doc = self.calibrator.state.to_dict()
        try:
            state = state_from_dict(doc, space=space, panel_id=cfg.panel.id)
            note = "calibration state kept"
        except CalibrationStateError as exc:
            state = CalibrationState.initial(cfg.panel.id, space)
            note = f"calibration state reset to the priors: {exc}"
        self.cfg, self.model, self.space = cfg, model, space
        self.calibrator = OnlineCalibrator(model, cfg.calibration, state=state)
        return note

    # ------------------------------------------------------------------ the record
    def add_row(self, sample: Sample) -> None:
        """Append this cycle's GOOD readings (flagged ones are NaN: excluded from the fit)."""
        t = sample.time_s
        if self._rows and t <= self._rows[-1][0]:
            return  # the clock did not advance (should not happen on the cycle grid)
        row = {n: v for n in _SENSOR_COLUMNS if (v := sample.good(n)) is not None}
        self._rows.append((t, row))
        if self._run_start_s is None:
            self._run_start_s = t
        keep_s = self.cfg.calibration.window_h * 3600.0 + 2.0 * self.cfg.model.step_s
        while self._rows and self._rows[0][0] < t - keep_s:
            self._rows.popleft()

    def set_controls(self, cmd: Command | None) -> None:
        """The actuator position applied from the newest row on (None: unknown)."""
        if self._rows and cmd is not None:
            self._rows[-1][1].update(cmd.as_dict())

    def due(self, now_s: float) -> bool:
        """True if an update should run now."""
        if self._run_start_s is None or now_s < self._retry_after_s:
            return False
        return self.calibrator.due(now_s, self._run_start_s)

    # ------------------------------------------------------------------ the update
    def prepare_update(self) -> Callable[[], UpdateReport | str]:
        """Snapshot the record and the state; the returned job refits θ̂ (blocking, for a
        worker thread) on a calibrator *copy* and returns its report, or why nothing could
        be fitted. Nothing of the stage is touched until :meth:`accept`."""
        data = self._measured()
        cfg, model, state = self.cfg, self.model, self.calibrator.state

        def job() -> UpdateReport | str:
            if data is None:
                return "fewer than two rows with controls"
            try:
                steps = step_data(cfg, data)
            except MeasuredDataError as exc:
                return f"record unusable: {exc}"
            start = window_start(steps.time_s, steps.n_steps, cfg.calibration.window_h)
            window = steps.window(min(start, steps.n_steps - 1), steps.n_steps)
            work = OnlineCalibrator(model, cfg.calibration, state=state)
            track = observe(model, window, work.theta[None])
            return work.update(window, track.x_hat[0], track.x_pred[0])

        return job

    def accept(self, result: UpdateReport | str, *, now_s: float) -> UpdateOutcome:
        """Apply a finished update (in time) and save the state atomically if θ̂ changed."""
        if isinstance(result, str) or result.skipped:
            self._retry_after_s = now_s + self.cfg.calibration.update_interval_s
        if isinstance(result, str):
            return UpdateOutcome(False, result, self.theta, math.nan, 0)
        self.calibrator.state = result.state
        if result.skipped:
            return UpdateOutcome(False, result.skipped, self.theta, math.nan, 0)
        save_state(self.path, result.state, self.space)
        fit = result.fit
        return UpdateOutcome(True, "", self.theta, float(fit.cost) if fit else math.nan,
                             int(fit.n_residuals) if fit else 0)

    def _measured(self) -> MeasuredData | None:
        rows = [(t, r) for t, r in self._rows]
        if len(rows) < 2 or not any("afr" in r for _, r in rows):
            return None
        names = sorted({k for _, r in rows for k in r})
        columns: dict[str, np.ndarray] = {
            n: np.array([r.get(n, math.nan) for _, r in rows], float) for n in names}
        return MeasuredData(np.array([t for t, _ in rows], float), columns,
                            source=f"daemon record of panel {self.cfg.panel.id}")
