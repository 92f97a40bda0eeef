"""Simulated sensors of the plant: thermocouples, cavity anemometer, weather station.

Readings carry the canonical names of :mod:`dsfd.signals` (``x1_c`` … ``wind_dir_deg``).
Error model (docs/model.md#plant-sensors), all seeded:

* thermocouples (x1..x5, room air, outdoor air): fixed bias uniform in ±0.3 K per sensor
  plus white noise σ = 0.2 K;
* cavity anemometer (unsigned speed): σ = 0.02 m/s below 0.1 m/s, σ = 0.02 m/s + 5 % of
  the reading above; readings clipped at 0;
* pyranometer: fixed gain error uniform in ±2 %, noise σ = 0.5 % of the reading;
* wind: speed σ = 0.1 m/s (clipped at 0), direction σ = 3°;
* barometer (station pressure): noise σ = 0.1 hPa; hygrometer: σ = 1 % RH, clipped to 0–100 %.

Faults (for fault-handling tests), per sensor from a start time: ``dropout`` (NaN),
``stuck`` (the reading at the fault start, or a given value) and ``spikes`` (with a given
probability per reading, ± a magnitude); and the slow ones of the diagnostics
(docs/faults.md#simulated-faults): ``offset`` (the reading + a value), ``drift`` (+ a value
per day since the start) and ``gain`` (the reading × a value). Faults apply with ideal
sensors too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

SENSOR_NAMES = ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c", "t_room_c", "v_cav_ms", "t_out_c",
                "ghi_wm2", "wind_speed_ms", "wind_dir_deg", "pressure_hpa", "rh_pct")
THERMOCOUPLES = ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c", "t_room_c", "t_out_c")
_SLOW = ("offset", "drift", "gain")
_SECONDS_PER_DAY = 86400.0


@dataclass(frozen=True, kw_only=True)
class SensorFault:
    """A configured sensor failure.

    Attributes
    ----------
    sensor : str
        Canonical sensor name (one of :data:`SENSOR_NAMES`).
    kind : {"dropout", "stuck", "spikes", "offset", "drift", "gain"}
    start_s : float, [s]
        UTC unix time the fault begins.
    end_s : float, [s]
        When it ends (default never).
    value : float, optional
        Stuck value (default the reading at the first faulty sample); the offset [unit],
        drift [unit per day] or gain [-] of those kinds (required there).
    magnitude : float
        Spike size in the sensor's unit.
    probability : float
        Spike probability per reading.
    """

    sensor: str
    kind: Literal["dropout", "stuck", "spikes", "offset", "drift", "gain"]
    start_s: float
    end_s: float = math.inf
    value: float | None = None
    magnitude: float = 5.0
    probability: float = 0.05

    def __post_init__(self) -> None:
        if self.sensor not in SENSOR_NAMES:
            raise ValueError(f"unknown sensor {self.sensor!r}; choose one of {SENSOR_NAMES}")
        if self.kind not in ("dropout", "stuck", "spikes", *_SLOW):
            raise ValueError(f"unknown fault kind {self.kind!r}")
        if self.kind in _SLOW and self.value is None:
            raise ValueError(f"a {self.kind} fault needs a value")

    def active(self, t: float) -> bool:
        return self.start_s <= t < self.end_s


@dataclass(frozen=True, kw_only=True)
class SensorConfig:
    """Placement and error model of the simulated sensors.

    Attributes
    ----------
    heights_m : tuple of 5 (float or None), [m]
        Height of the x1..x5 thermocouples above the bottom of the glazed section;
        None = mid-height (the default, a deliberate mismatch with the lumped states).
    x5_location : {"mean", "outer", "inner"}
        Which sub-cavity the air thermocouple sits in (split cavity only).
    anemometer_height_m : float, [m]
        Height of the hot-sphere probe (paper: about 1 m above the bottom).
    """

    heights_m: tuple[float | None, ...] = (None, None, None, None, None)
    x5_location: Literal["mean", "outer", "inner"] = "mean"
    anemometer_height_m: float = 1.0
    thermocouple_sigma_k: float = 0.2
    thermocouple_bias_k: float = 0.3
    anemometer_sigma_ms: float = 0.02
    anemometer_relative: float = 0.05
    anemometer_threshold_ms: float = 0.1
    pyranometer_gain: float = 0.02
    pyranometer_sigma_rel: float = 0.005
    wind_sigma_ms: float = 0.1
    wind_dir_sigma_deg: float = 3.0
    barometer_sigma_hpa: float = 0.1
    hygrometer_sigma_pct: float = 1.0
    faults: tuple[SensorFault, ...] = field(default_factory=tuple)


class SensorBank:
    """Turns true values into readings (noise, bias, faults); one instance per plant.

    Parameters
    ----------
    config : SensorConfig
    rng : numpy Generator
        Draws the fixed biases at construction and the noise at every reading.
    ideal : bool
        No bias and no noise (docs/model.md#plant-switches); configured faults still apply.
    """

    def __init__(self, config: SensorConfig, rng: np.random.Generator, *, ideal: bool) -> None:
        self.config = config
        self.rng = rng
        self.ideal = ideal
        c = config
        self.bias = {name: float(rng.uniform(-c.thermocouple_bias_k, c.thermocouple_bias_k))
                     for name in THERMOCOUPLES}
        self.gain = 1.0 + float(rng.uniform(-c.pyranometer_gain, c.pyranometer_gain))
        self._stuck: dict[int, float] = {}

    def reset(self) -> None:
        """Forget stuck values (a new run); the biases stay."""
        self._stuck.clear()

    def _noisy(self, true: dict[str, float]) -> dict[str, float]:
        c, rng = self.config, self.rng
        out = {}
        for name in THERMOCOUPLES:
            if name in true:
                out[name] = (true[name] + self.bias[name]
                             + c.thermocouple_sigma_k * float(rng.standard_normal()))
        v = abs(true["v_cav_ms"])
        sigma = (c.anemometer_sigma_ms if v < c.anemometer_threshold_ms
                 else c.anemometer_sigma_ms + c.anemometer_relative * v)
        out["v_cav_ms"] = max(0.0, v + sigma * float(rng.standard_normal()))
        ghi = true["ghi_wm2"] * self.gain
        out["ghi_wm2"] = max(0.0, ghi * (1.0 + c.pyranometer_sigma_rel
                                         * float(rng.standard_normal())))
        out["wind_speed_ms"] = max(0.0, true["wind_speed_ms"]
                                   + c.wind_sigma_ms * float(rng.standard_normal()))
        out["wind_dir_deg"] = (true["wind_dir_deg"]
                               + c.wind_dir_sigma_deg * float(rng.standard_normal())) % 360.0
        if "pressure_hpa" in true:
            out["pressure_hpa"] = (true["pressure_hpa"]
                                   + c.barometer_sigma_hpa * float(rng.standard_normal()))
        if "rh_pct" in true:
            out["rh_pct"] = min(100.0, max(0.0, true["rh_pct"] + c.hygrometer_sigma_pct
                                           * float(rng.standard_normal())))
        return out

    def read(self, true: dict[str, float], t: float) -> dict[str, float]:
        """Readings at time ``t`` [s] from the true values (same names and units)."""
        out = dict(true) if self.ideal else self._noisy(true)
        out["v_cav_ms"] = abs(out["v_cav_ms"])
        for i, fault in enumerate(self.config.faults):
            if not fault.active(t):
                self._stuck.pop(i, None)
                continue
            name = fault.sensor
            if fault.kind in _SLOW:
                if name in out:  # a station channel the panel lacks stays absent
                    out[name] = _slow(fault, out[name], t)
            elif fault.kind == "dropout":
                out[name] = math.nan
            elif fault.kind == "stuck":
                if i not in self._stuck:
                    self._stuck[i] = out[name] if fault.value is None else float(fault.value)
                out[name] = self._stuck[i]
            elif self.rng.uniform() < fault.probability:
                out[name] += fault.magnitude * (1.0 if self.rng.uniform() < 0.5 else -1.0)
        return {name: float(out[name]) for name in SENSOR_NAMES if name in out}


def _slow(fault: SensorFault, value: float, t: float) -> float:
    """A reading under an offset, drift or gain fault (docs/faults.md#simulated-faults)."""
    size = float(fault.value or 0.0)
    if fault.kind == "offset":
        return value + size
    if fault.kind == "drift":
        return value + size * (t - fault.start_s) / _SECONDS_PER_DAY
    return value * size
