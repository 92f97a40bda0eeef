"""The daemon's state estimate x̂ = (x1..x6) for the optimiser, one cycle at a time.

Each cycle the lumped model predicts the state from the previous estimate over the step
that just ended (the actuator position that was applied, that step's weather, the current
θ̂); then :func:`dsfd.estimation.observer.fill_state` replaces the prediction by the GOOD
measurements of x1..x5 and sets x6 = (x2 + x3)/2 (docs/model.md#initial-state). A state whose sensor
is flagged is carried by the prediction — for at most ``daemon.max_predicted_cycles`` cycles,
after which the estimate is not *usable*: the optimiser then does not run and the baseline
(or the safe state) decides.

No previous estimate (first cycle, a skipped slot, missing weather) means no prediction:
only measured states are known then, and the estimate is usable only if all of x1..x5 are
measured (a panel without a louver has x4 tied to x5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dsfd.drivers.base import Command
from dsfd.estimation.observer import fill_state, probe_to_state
from dsfd.estimation.params import with_offsets
from dsfd.estimation.reading_offsets import (
    initial_reading_offsets,
    reading_offset,
    track_reading_offsets,
)
from dsfd.physics.constants import T_ZERO
from dsfd.physics.coupling import StepInputs
from dsfd.physics.forcing import FacadeOptics, Forcing, step_inputs
from dsfd.physics.model import LumpedModel

__all__ = ["STATE_SIGNALS", "StateEstimate", "StateObserver", "StatePrediction", "horizon_end"]

#: Sensors of x1..x5, in state order.
STATE_SIGNALS: tuple[str, ...] = ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c")
_NEVER = 10**9  # age of a state never measured


@dataclass(frozen=True)
class StatePrediction:
    """The model's one-step prediction of the step that just ended (from the previous
    estimate, with the actuator position applied during the step and its measured weather):
    what the reading of this cycle scores, and the room-side heat of that step.

    Attributes
    ----------
    x_k : ndarray (6,), [K]
        Predicted readings of x1..x5 at this cycle (the cavity-air probe's for x5,
        docs/model.md#cavity-probe; with the regime's reading offsets,
        docs/model.md#reading-offsets) and x6.
    v_cav_ms : float, [m/s]
        Predicted mean cavity speed over the step, unsigned (the anemometer reads |v|).
    heat_w : dict
        Step-average heat into the room by term: ``q_cv_rd``, ``q_sol_trans``, ``q_air``,
        ``q_da`` [W] (docs/model.md#room-heat).
    """

    x_k: np.ndarray
    v_cav_ms: float
    heat_w: dict[str, float]


@dataclass(frozen=True)
class StateEstimate:
    """The estimate after this cycle's measurement update.

    Attributes
    ----------
    x_k : ndarray (6,), [K]
        x1..x6; NaN where nothing is known.
    age_cycles : tuple of int
        Per x1..x5: cycles since the sensor was last GOOD (0 = measured now).
    usable : bool
        Every x1..x5 measured or predicted within the allowed age: the optimiser may run.
    why : str
        Why not usable ("" if usable).
    prediction : StatePrediction or None
        The one-step prediction this estimate corrected (None: no previous estimate).
    """

    x_k: np.ndarray
    age_cycles: tuple[int, ...]
    usable: bool
    why: str = ""
    prediction: StatePrediction | None = None

    def celsius(self, i: int) -> float | None:
        """State ``x{i+1}`` in degC, None if unknown."""
        v = float(self.x_k[i])
        return None if not np.isfinite(v) else v - T_ZERO


class StateObserver:
    """Predict–correct state estimate for one panel (model and θ̂ supplied per cycle)."""

    def __init__(self, model: LumpedModel, *, max_predicted_cycles: int) -> None:
        self.model = model
        self.max_predicted_cycles = max_predicted_cycles
        self.has_louver = model.cfg.louver is not None
        self._x: np.ndarray | None = None
        self._age = np.full(5, _NEVER)
        self._offsets = initial_reading_offsets()

    def reset(self) -> None:
        """Forget the previous estimate and the reading offsets (after a gap in the cycles)."""
        self._x = None
        self._offsets = initial_reading_offsets()

    def reading_offset_k(self, regime: int) -> np.ndarray:
        """The reading offsets of x1..x5 [K] under commanded ``regime``
        (docs/model.md#reading-offsets): what a prediction of the readings adds."""
        return reading_offset(self._offsets, regime)

    def update(self, y_c: dict[str, float], *, step: StepInputs | None,
               applied: Command | None, theta: np.ndarray,
               offsets: np.ndarray | None = None) -> StateEstimate:
        """Measurement update with GOOD readings ``y_c`` [degC] of x1..x5.

        Parameters
        ----------
        y_c : mapping
            GOOD sensor values by signal name; absent ones are unknown.
        step : StepInputs or None
            Inputs of the step that just ended (None: no prediction possible).
        applied : Command or None
            Actuator position during that step.
        theta : ndarray (9,)
            Current parameter estimate.
        offsets : ndarray (4,), optional, [W/m2]
            Calibrated heat-flux offsets of nodes 1-4 (the calibrator's disturbance model).
        """
        y = np.array([y_c.get(n, np.nan) for n in STATE_SIGNALS], float) + T_ZERO
        measured = np.isfinite(y)
        x_pred = np.full(6, np.nan)
        prediction = None
        if self._x is not None and step is not None and applied is not None:
            if offsets is not None:
                step = with_offsets(step, offsets)
            res = self.model.step(self._x[None], [applied.afr], applied.or_pct / 100.0, step,
                                  theta)
            if np.all(np.isfinite(res.x_next)):
                x_pred = res.x_next[0]
                readings = x_pred.copy()
                readings[4] = res.x5_probe_k[0]
                offset = self.reading_offset_k(applied.afr)
                readings[:5] += offset
                self._track_offsets(applied.afr, y - readings[:5])
                y = probe_to_state((y - offset)[None], res.x_next[:, 4], res.x5_probe_k)[0]
                prediction = StatePrediction(
                    readings, abs(float(res.v_cav_ms[0])),
                    {"q_cv_rd": float(res.q_cv_rd_w[0]), "q_sol_trans": float(res.q_sol_w[0]),
                     "q_air": float(res.q_air_w[0]),
                     "q_da": float(np.broadcast_to(res.q_da_w, (1,))[0])})
        x = fill_state(y, x_pred, has_louver=self.has_louver,
                       gain=self.model.cfg.calibration.measurement_gain)
        predicted = np.isfinite(x[:5]) & ~measured
        self._age = np.where(measured, 0, np.where(predicted, self._age + 1, _NEVER))
        if not self.has_louver and measured[4]:
            self._age[3] = 0  # the louver node is tied to the measured cavity air
        too_old = [STATE_SIGNALS[i] for i in range(5)
                   if self._age[i] > self.max_predicted_cycles]
        unknown = [STATE_SIGNALS[i] for i in range(5) if not np.isfinite(x[i])]
        if unknown:
            why = f"no estimate of {', '.join(unknown)}"
        elif too_old:
            why = (f"{', '.join(too_old)} not measured for more than "
                   f"{self.max_predicted_cycles} cycles")
        elif not np.isfinite(x[5]):
            why = "no estimate of x6"
        else:
            why = ""
        self._x = x if np.all(np.isfinite(x)) else None
        return StateEstimate(x, tuple(int(min(a, _NEVER)) for a in self._age), not why, why,
                             prediction)

    def _track_offsets(self, regime: int, innovation_k: np.ndarray) -> None:
        cal = self.model.cfg.calibration
        self._offsets = track_reading_offsets(
            self._offsets, regime=regime, innovation_k=innovation_k,
            step_s=self.model.cfg.model.step_s,
            tracking_s=np.asarray(cal.reading_offset_tracking_s, float),
            memory_s=cal.reading_offset_memory_s, clip_k=cal.spike_threshold_k)


def horizon_end(model: LumpedModel, optics: FacadeOptics, forecast: Forcing, x_k: np.ndarray,
                applied: Command, theta: np.ndarray, offsets: np.ndarray, *,
                coupling_tol_k: float | None = None) -> np.ndarray | None:
    """x1..x6 at the end of the horizon [K] (the probe's reading for x5) with ``applied``
    held from ``x_k`` on the ``forecast``, as the optimiser predicts it (same model, θ̂ and
    heat-flux offsets [W/m2]); None if the rollout is not finite. One candidate,
    ``len(forecast)`` steps.

    ``coupling_tol_k`` [K] loosens the thermal–airflow fixed point (the daemon passes the
    optimiser's screening tolerance, 0.1 K: half the coupling evaluations, end states within
    0.02 K of the strict rollout on the Suwon panel — far below the prediction errors this
    is scored for)."""
    loads = optics.loads(forecast, np.radians(applied.phi_deg))
    inp = with_offsets(step_inputs(forecast, loads), offsets)
    steps = forecast.time_s.shape[0]
    traj = model.rollout(x_k, np.full((1, steps), applied.afr),
                         np.full((1, steps), applied.or_pct / 100.0), inp, theta,
                         coupling_tol_k=coupling_tol_k)
    x_end = np.array(traj.x[0, -1])
    x_end[4] = traj.x5_probe[0, -1]  # what the probe will read (docs/model.md#cavity-probe)
    return x_end if np.all(np.isfinite(x_end)) else None
