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
directory, :mod:`dsfd.storage.calibration_file`); a restart resumes from it. A save that
fails (full disk) keeps θ̂ in memory and is reported as an event; the next update saves again.

An unusable ``calibration.json`` is moved aside (``calibration.json.corrupt.<time>``) and
the stage resumes from the newest consistent row of the database's parameter history (a row
with calibrated values, every parameter finite and inside the panel's current bounds), or
from the priors if there is none; :attr:`CalibrationStage.origin` and an event say which.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from dsfd.config.panel import PanelConfig
from dsfd.drivers.base import Command, Sample
from dsfd.estimation.calibration import OnlineCalibrator, UpdateReport, window_start
from dsfd.estimation.observer import observe
from dsfd.estimation.params import (
    FIT_NAMES,
    N_PARAMS,
    PARAMETER_NAMES,
    ParameterSpace,
    full_vector,
)
from dsfd.estimation.state import CalibrationState, CalibrationStateError, state_from_dict
from dsfd.estimation.stepdata import step_data
from dsfd.measured import CONTROL_COLUMNS, KNOWN_COLUMNS, MeasuredData, MeasuredDataError
from dsfd.physics.model import LumpedModel
from dsfd.storage.calibration_file import (
    CalibrationFileError,
    move_aside,
    resume_state,
    save_state,
)

__all__ = ["STATE_FILE", "CalibrationStage", "HistoryRow", "UpdateOutcome",
           "state_from_history"]

#: A row of the database's parameter history: (run_id, cycle, time_s, source, value by name).
HistoryRow = tuple[int, int, float, str, Mapping[str, float]]

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

    def __init__(self, cfg: PanelConfig, model: LumpedModel, *, state_dir: Path,
                 history: Callable[[], Sequence[HistoryRow]] | None = None) -> None:
        self.path = state_dir / STATE_FILE
        self.cfg = cfg
        self.model = model
        self.space = ParameterSpace.from_panel(cfg)
        #: Events for the first cycle's record (level, kind, message), drained by the loop.
        self.events: list[tuple[str, str, str]] = []
        #: Where θ̂ came from: "prior", "resumed" (calibration.json) or "database".
        self.origin = "prior"
        state = self._initial_state(history)
        self.calibrator = OnlineCalibrator(model, cfg.calibration, state=state)
        self._rows: deque[tuple[float, dict[str, float]]] = deque()
        self._run_start_s: float | None = None
        self._retry_after_s = -math.inf  # an attempt that fitted nothing waits an interval

    @property
    def resumed(self) -> bool:
        """True if θ̂ did not start from the priors."""
        return self.origin != "prior"

    def _initial_state(self, history: Callable[[], Sequence[HistoryRow]] | None
                       ) -> CalibrationState:
        """The state file, else (moved aside if unusable) the database history, else priors;
        sets :attr:`resume_message` and :attr:`origin`."""
        panel = self.cfg.panel.id
        try:
            saved, self.resume_message = resume_state(self.path, space=self.space,
                                                      panel_id=panel)
        except CalibrationFileError as exc:
            why = str(exc)
        else:
            if saved is None:  # no file: the priors
                return CalibrationState.initial(panel, self.space)
            self.origin = "resumed"
            return saved
        try:
            kept = f"moved aside to {move_aside(self.path).name}"
        except OSError as err:
            kept = f"could not be moved aside ({err.strerror or err})"
        try:
            rows = list(history()) if history is not None else []
        except Exception as err:  # a database problem must not keep the daemon from starting
            rows, why = [], f"{why}; the parameter history could not be read ({err})"
        found = state_from_history(rows, space=self.space, panel_id=panel)
        if found is None:
            state, self.origin = CalibrationState.initial(panel, self.space), "prior"
            then = "no consistent parameter history in the database: starting from the priors"
        else:
            state, where = found
            self.origin = "database"
            then = f"resumed from the database's parameter history ({where})"
        self.resume_message = f"calibration state unusable ({why}); {kept}; {then}"
        self.events.append(("warning", "calibration_recovered", self.resume_message))
        return state

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

    def posterior_sd_by_name(self) -> dict[str, float]:
        """The posterior sd of each θ parameter in the fitting coordinates (of log θ for the
        positive ones, a relative sd; of n itself): the square root of the diagonal of the
        state's covariance, as the ``parameters`` table stores it (``sd_<name>``)."""
        sd = np.sqrt(np.clip(np.diag(self.calibrator.state.cov_z), 0.0, None))
        return {k: float(v) for k, v in zip(PARAMETER_NAMES, sd[:N_PARAMS], strict=True)}

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

    def restart_record(self) -> None:
        """Forget the rows (after a wall-clock step: two time lines do not make model
        steps); the next update waits for ``calibration.min_window_h`` of new rows."""
        self._rows.clear()
        self._run_start_s = None

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
        try:
            save_state(self.path, result.state, self.space)
        except OSError as exc:  # full disk: θ̂ is kept in memory, the next update saves again
            self.events.append(("error", "calibration_not_saved",
                                f"{self.path}: {exc.strerror or exc}; the updated parameters "
                                "are used but a restart would start from the previous file"))
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


def state_from_history(rows: Sequence[HistoryRow], *, space: ParameterSpace, panel_id: str
                       ) -> tuple[CalibrationState, str] | None:
    """The newest row whose θ is complete, finite and inside the bounds of ``space``, as a
    state (covariance: the first prior, since the history keeps none), and where it came
    from; None if no row qualifies. Offsets missing from a row are 0."""
    for run, cycle, time_s, source, values in rows:
        theta = np.array([values.get(name, 0.0 if i >= N_PARAMS else math.nan)
                          for i, name in enumerate(FIT_NAMES)], float)
        if np.all(np.isfinite(theta)) and np.all(theta >= space.lower) and \
                np.all(theta <= space.upper):
            state = replace(CalibrationState.initial(panel_id, space), theta=theta,
                            last_update_s=time_s)
            return state, f"run {run}, cycle {cycle}, {source}"
    return None
