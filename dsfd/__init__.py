"""dsfd — on-line self-calibrating model-predictive control of double-skin façade panels.

The Python API (docs/development.md, "Python API", has a worked example)::

    import dsfd

    panel = dsfd.load_panel("config/panels/suwon-south.yaml")      # PanelConfig
    weather = dsfd.load_weather("rmis-golden-2022-01")               # WeatherSeries
    model = dsfd.LumpedModel(panel)                                  # the 6-state model
    decision = dsfd.MpcOptimiser(panel).decide(problem)              # ControlProblem → Decision

Panels and weather
    :func:`load_panel`, :class:`PanelConfig`, :class:`ConfigError`; :class:`Param`,
    :data:`PARAMETER_NAMES`, :data:`FIT_NAMES` (the calibrated parameters by name);
    :func:`load_weather` (bundled name or file), :func:`read_weather`, :class:`WeatherSeries`,
    :func:`at_site` (replayed at the panel's longitude), :func:`weather_inputs` (a series
    in model steps), :func:`model_weather` and :class:`WeatherInputs` (any measured or
    forecast weather → the model's weather, the defaults stated once), :func:`facade_forcing`
    (weather → the façade's boundary).
The model
    :class:`LumpedModel`, :class:`FacadeOptics`, :class:`Forcing`.
Control
    :class:`ControlProblem`, :class:`MpcOptimiser`, :class:`Decision`, :func:`rule_decision`.
Estimation
    :class:`MeasuredData`, :func:`read_measured`, :func:`step_data`, :class:`StepData`,
    :func:`observe` (the state observer over a record), :class:`OnlineCalibrator`,
    :func:`offline_fit`.
Simulation
    :class:`Plant` (the stratified truth plant), :class:`PlantOptions`,
    :class:`TrueParameters`, :func:`run_truth` (the paper's excitation protocol).

Names are imported on first use, so ``import dsfd`` stays light for the daemon and the
pure core (``dsfd.physics``, ``dsfd.estimation``, ``dsfd.control``) never pulls in the
edges (YAML, Modbus, serial, SQLite, logging set-up).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Public name → the module that defines it.
_API: dict[str, str] = {
    "ConfigError": "dsfd.config",
    "PanelConfig": "dsfd.config",
    "load_panel": "dsfd.config",
    "WeatherSeries": "dsfd.weather",
    "read_weather": "dsfd.weather",
    "load_weather": "dsfd.sim.replay",
    "at_site": "dsfd.sim.replay",
    "weather_inputs": "dsfd.sim.replay",
    "WeatherInputs": "dsfd.physics.boundary",
    "model_weather": "dsfd.physics.boundary",
    "Param": "dsfd.config.parameters",
    "FIT_NAMES": "dsfd.config.parameters",
    "PARAMETER_NAMES": "dsfd.config.parameters",
    "Forcing": "dsfd.physics.forcing",
    "FacadeOptics": "dsfd.physics.forcing",
    "facade_forcing": "dsfd.physics.forcing",
    "LumpedModel": "dsfd.physics.model",
    "ControlProblem": "dsfd.control.optimiser",
    "Decision": "dsfd.control.optimiser",
    "MpcOptimiser": "dsfd.control.optimiser",
    "rule_decision": "dsfd.control.baseline",
    "MeasuredData": "dsfd.measured",
    "read_measured": "dsfd.storage.measured_csv",
    "StepData": "dsfd.estimation",
    "step_data": "dsfd.estimation",
    "observe": "dsfd.estimation",
    "OnlineCalibrator": "dsfd.estimation",
    "offline_fit": "dsfd.estimation",
    "Plant": "dsfd.sim.plant.plant",
    "PlantOptions": "dsfd.sim.plant.config",
    "TrueParameters": "dsfd.sim.plant.config",
    "run_truth": "dsfd.sim.truth_run",
}

__all__ = [
    "FIT_NAMES",
    "PARAMETER_NAMES",
    "ConfigError",
    "ControlProblem",
    "Decision",
    "FacadeOptics",
    "Forcing",
    "LumpedModel",
    "MeasuredData",
    "MpcOptimiser",
    "OnlineCalibrator",
    "PanelConfig",
    "Param",
    "Plant",
    "PlantOptions",
    "StepData",
    "TrueParameters",
    "WeatherInputs",
    "WeatherSeries",
    "__version__",
    "at_site",
    "facade_forcing",
    "load_panel",
    "load_weather",
    "model_weather",
    "observe",
    "offline_fit",
    "read_measured",
    "read_weather",
    "rule_decision",
    "run_truth",
    "step_data",
    "weather_inputs",
]


def __getattr__(name: str) -> Any:
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'dsfd' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_API})


if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from dsfd.config import ConfigError, PanelConfig, load_panel
    from dsfd.config.parameters import FIT_NAMES, PARAMETER_NAMES, Param
    from dsfd.control.baseline import rule_decision
    from dsfd.control.optimiser import ControlProblem, Decision, MpcOptimiser
    from dsfd.estimation import OnlineCalibrator, StepData, observe, offline_fit, step_data
    from dsfd.measured import MeasuredData
    from dsfd.physics.boundary import WeatherInputs, model_weather
    from dsfd.physics.forcing import FacadeOptics, Forcing, facade_forcing
    from dsfd.physics.model import LumpedModel
    from dsfd.sim.plant.config import PlantOptions, TrueParameters
    from dsfd.sim.plant.plant import Plant
    from dsfd.sim.replay import at_site, load_weather, weather_inputs
    from dsfd.sim.truth_run import run_truth
    from dsfd.storage.measured_csv import read_measured
    from dsfd.weather import WeatherSeries, read_weather
