"""Self-calibration of the lumped model (Eq. 3 of the paper), state update, off-line baseline.

Pure core (no files, sockets, clocks or logging configuration):

* :mod:`~dsfd.estimation.stepdata` — measured rows → model steps (:func:`step_data`);
* :mod:`~dsfd.estimation.observer` — state update from the measurements, x6 observer;
* :mod:`~dsfd.estimation.params` — the fit vector ϑ = (θ, heat-flux offsets), coordinates,
  bounds, priors, what a panel/window can excite;
* :mod:`~dsfd.estimation.objective` — the Eq. 3 residual over a moving window
  (multi-step predictions from observed states);
* :mod:`~dsfd.estimation.fit` — one bounded, robust, prior-regularised least-squares fit;
* :mod:`~dsfd.estimation.calibration` — :class:`OnlineCalibrator` and :func:`offline_fit`;
* :mod:`~dsfd.estimation.state` — :class:`CalibrationState` and its JSON mapping;
* :mod:`~dsfd.estimation.validation` — replay scores in the layout of Tables 1 and 2;
* :mod:`~dsfd.estimation.diagnostics` — change detectors on prediction errors and the
  parameter history, and the :class:`~dsfd.estimation.diagnostics.Finding` they return;
* :mod:`~dsfd.estimation.crosschecks` — physical cross-checks (cavity speed against the
  commanded dampers, panes against the outdoor air at night).

Files: :mod:`dsfd.storage.calibration_file`. Settings: ``calibration:`` of the panel
(:class:`dsfd.config.calibration.Calibration`). A consumer of the calibrated model uses
θ (:attr:`OnlineCalibrator.model_theta`) as the model parameters and adds the offsets q
(:attr:`OnlineCalibrator.heat_offsets_wm2`) to the absorbed short-wave of its inputs
(:func:`~dsfd.estimation.params.with_offsets`); components by name:
:class:`dsfd.config.parameters.Param`.
"""

from dsfd.estimation.calibration import OnlineCalibrator, UpdateReport, offline_fit, window_start
from dsfd.estimation.observer import ObserverTrack, fill_state, initial_state, observe
from dsfd.estimation.params import (
    FIT_NAMES,
    OFFSET_NAMES,
    ParameterSpace,
    full_vector,
    with_offsets,
)
from dsfd.estimation.state import CalibrationState, CalibrationStateError, state_from_dict
from dsfd.estimation.stepdata import StepData, model_config, step_data
from dsfd.estimation.validation import ReplayScores, replay_scores

__all__ = [
    "FIT_NAMES",
    "OFFSET_NAMES",
    "CalibrationState",
    "CalibrationStateError",
    "ObserverTrack",
    "OnlineCalibrator",
    "ParameterSpace",
    "ReplayScores",
    "StepData",
    "UpdateReport",
    "fill_state",
    "full_vector",
    "initial_state",
    "model_config",
    "observe",
    "offline_fit",
    "replay_scores",
    "state_from_dict",
    "step_data",
    "window_start",
    "with_offsets",
]
