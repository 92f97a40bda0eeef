"""Edge: the calibration-state JSON file and the fitted-parameters YAML file.

* Calibration state (``<state dir>/calibration.json``): what a restart needs to resume the
  self-calibration (:class:`dsfd.estimation.state.CalibrationState`). Written atomically —
  temporary file in the same directory, flush + fsync, ``os.replace``, fsync of the
  directory — so a crash at any instant leaves the old or the new file, never a torn one.
  :func:`resume_state` reads it if there is one (the daemon's calibration stage), and
  :func:`load_state_or_prior` falls back to the panel priors, with a message saying why,
  when the file is missing or unusable; the daemon moves an unusable file aside
  (:func:`move_aside`, ``calibration.json.corrupt.<time>``) before it writes a new one.
* Fitted parameters (``dsfd calibrate --out PARAMS.yaml``): the frozen off-line θ with its
  standard errors and the training period; read back by ``dsfd validate --params``.

Errors name the file and the key.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from dsfd.estimation.params import FIT_NAMES, OFFSET_NAMES, ParameterSpace
from dsfd.estimation.state import CalibrationState, CalibrationStateError, state_from_dict
from dsfd.storage.atomic import corrupt_name, write_text_atomic

PARAMS_SCHEMA = "dsfd.parameters"
PARAMS_SCHEMA_VERSION = 1


class CalibrationFileError(ValueError):
    """A state or parameters file that cannot be used; the message names file and key."""


# --------------------------------------------------------------------------- state file
def save_state(path: str | Path, state: CalibrationState, space: ParameterSpace) -> None:
    """Write the calibration state as JSON (with standard errors for readers)."""
    write_text_atomic(path, json.dumps(state.to_dict(space), indent=1) + "\n")


def load_state(path: str | Path, *, space: ParameterSpace, panel_id: str) -> CalibrationState:
    """Read and validate a calibration-state file.

    Raises
    ------
    CalibrationFileError
        Unreadable file, invalid JSON (with line and column) or a bad key (named).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise CalibrationFileError(f"{path}: cannot read: {exc.strerror or exc}") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CalibrationFileError(f"{path}: not valid JSON (line {exc.lineno}, column "
                                   f"{exc.colno}): {exc.msg}") from None
    try:
        return state_from_dict(doc, space=space, panel_id=panel_id)
    except CalibrationStateError as exc:
        raise CalibrationFileError(f"{path}: {exc}") from None


def resume_state(path: str | Path, *, space: ParameterSpace, panel_id: str
                 ) -> tuple[CalibrationState | None, str]:
    """The saved state and "resumed ...", or None and why there is none (no file).

    Raises
    ------
    CalibrationFileError
        The file exists but cannot be used (:func:`load_state`).
    """
    path = Path(path)
    if not path.exists():
        return None, f"no calibration state at {path}: starting from the panel priors"
    state = load_state(path, space=space, panel_id=panel_id)
    return state, f"resumed calibration state from {path} ({state.updates} updates)"


def load_state_or_prior(path: str | Path, *, space: ParameterSpace,
                        panel_id: str) -> tuple[CalibrationState, str]:
    """The saved state, or the panel priors with a message saying why.

    Returns
    -------
    state : CalibrationState
    message : str
        "resumed ..." or why the priors are used (missing or unusable file).
    """
    try:
        state, message = resume_state(path, space=space, panel_id=panel_id)
    except CalibrationFileError as exc:
        return (CalibrationState.initial(panel_id, space),
                f"calibration state unusable, starting from the panel priors: {exc}")
    return state or CalibrationState.initial(panel_id, space), message


def move_aside(path: str | Path) -> Path:
    """Rename an unusable state file to ``<name>.corrupt.<UTC time>``; the new name."""
    path = Path(path)
    target = corrupt_name(path)
    os.replace(path, target)
    return target


# --------------------------------------------------------------------------- params file
def write_params(path: str | Path, state: CalibrationState, space: ParameterSpace, *,
                 provenance: dict[str, Any]) -> None:
    """Write fitted parameters as YAML (θ, standard errors, free set, provenance)."""
    se = state.std_error(space)
    doc = {
        "schema": PARAMS_SCHEMA,
        "schema_version": PARAMS_SCHEMA_VERSION,
        "panel_id": state.panel_id,
        "parameters": {k: float(f"{v:.6g}") for k, v in zip(FIT_NAMES, state.theta,
                                                             strict=True)},
        "std_error": {k: float(f"{v:.3g}") for k, v in zip(FIT_NAMES, se, strict=True)},
        "fitted": list(state.free_last),
        "cost": None if not math.isfinite(state.cost_last) else float(f"{state.cost_last:.6g}"),
        "residuals": state.residuals_last,
        "provenance": provenance,
    }
    head = (f"# dsfd off-line calibration of panel {state.panel_id}: parameters frozen for "
            "'dsfd validate --params'\n# units: h_* W/(m2 K), f -, c m3/(s Pa^n), n -, "
            "q_x* (heat-flux offsets on nodes x1..x4) W/m2\n")
    write_text_atomic(path, head + yaml.safe_dump(doc, sort_keys=False))


def read_params(path: str | Path, *, space: ParameterSpace,
                panel_id: str | None = None) -> np.ndarray:
    """Fit vector ϑ (13,) from a parameters file, validated against the panel bounds.

    The nine parameters of ``dsfd.config.panel.PARAMETER_NAMES`` are required; the heat-flux offsets
    are optional (0).

    Raises
    ------
    CalibrationFileError
        Naming the file and the offending key.
    """
    path = Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise CalibrationFileError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise CalibrationFileError(f"{path}: invalid YAML: {exc}") from None
    if not isinstance(doc, dict):
        raise CalibrationFileError(f"{path}: expected a mapping at the top level")
    if doc.get("schema") != PARAMS_SCHEMA or doc.get("schema_version") != PARAMS_SCHEMA_VERSION:
        raise CalibrationFileError(
            f"{path}: key 'schema'/'schema_version': expected {PARAMS_SCHEMA!r} version "
            f"{PARAMS_SCHEMA_VERSION}, got {doc.get('schema')!r} {doc.get('schema_version')!r}")
    if panel_id is not None and doc.get("panel_id") != panel_id:
        raise CalibrationFileError(f"{path}: key 'panel_id': parameters are for panel "
                                   f"{doc.get('panel_id')!r}, not {panel_id!r}")
    params = doc.get("parameters")
    if not isinstance(params, dict):
        raise CalibrationFileError(f"{path}: key 'parameters': expected a mapping")
    unknown = sorted(set(params) - set(FIT_NAMES))
    if unknown:
        raise CalibrationFileError(f"{path}: key 'parameters.{unknown[0]}': unknown parameter")
    theta = space.default.copy()
    for i, name in enumerate(FIT_NAMES):
        if name in OFFSET_NAMES and name not in params:
            continue  # offsets are optional (0)
        value = params.get(name)
        if (isinstance(value, bool) or not isinstance(value, int | float)
                or not math.isfinite(value)):
            raise CalibrationFileError(f"{path}: key 'parameters.{name}': expected a finite "
                                       f"number, got {value!r}")
        if not space.lower[i] <= value <= space.upper[i]:
            raise CalibrationFileError(
                f"{path}: key 'parameters.{name}': {value:g} outside the panel bounds "
                f"[{space.lower[i]:g}, {space.upper[i]:g}]")
        theta[i] = float(value)
    return theta
