"""Settings of the controller daemon (``dsfd run``): where it keeps state, its cycle and budgets.

YAML shape (the ``daemon:`` section of a panel file; every key is optional)::

    daemon:
      state_directory: null          # null: --state-dir, else $STATE_DIRECTORY (systemd)
      cycle_period_s: 60
      calibrate_budget_s: 10
      store_budget_s: 5
      store_buffer_cycles: 720       # cycles kept in memory while the database cannot be written
      room_temperature_source: auto  # auto | sensor | config
      metrics_file: null             # e.g. /var/lib/node_exporter/textfile_collector/x.prom
      quality:
        stuck_window: 15
        max_rate_k_per_min: 10.0

Stage budgets of one cycle (each enforced with a hard time-out by the loop)::

    read        devices.read_budget_s        (the drivers' worst-case I/O, already checked)
    calibrate   daemon.calibrate_budget_s
    optimise    control.time_budget_s        (late or failed → rule-based baseline)
    write       devices.write_budget_s
    store       daemon.store_budget_s

``dsfd run`` checks that they fit into ``cycle_period_s`` (:func:`dsfd.daemon.runtime_problems`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from dsfd.config.loader import Problem, setting
from dsfd.signals import SENSORS

__all__ = ["DaemonSettings", "QualitySettings"]

#: Temperatures checked for stuck values by default: the façade's thermocouples and the
#: outdoor air, not the room air (a conditioned room may read the same 0.1 K for an hour).
STUCK_SIGNALS: tuple[str, ...] = ("x1_c", "x2_c", "x3_c", "x4_c", "x5_c", "t_out_c")
#: Temperatures checked for their rate of change by default: not the louver slat (x4, a thin
#: slat in sun can heat by ~15 K in a minute) nor the cavity air (x5, time constant ~10 s:
#: it follows the airflow within a minute when dampers open).
RATE_SIGNALS: tuple[str, ...] = ("x1_c", "x2_c", "x3_c", "t_room_c", "t_out_c")


@dataclass(frozen=True, kw_only=True)
class QualitySettings:
    """Sensor quality checks beyond the drivers' own flags (range checks use dsfd.signals)."""

    stuck_window: int = setting(
        15, doc="A signal whose last this many GOOD readings are identical is STUCK "
        "(thermocouple noise makes exact repeats unlikely for a live sensor; raise it for "
        "devices with a coarse resolution)", ge=3, le=1440)
    stuck_signals: tuple[str, ...] = setting(
        STUCK_SIGNALS, doc="Signals checked for stuck values (not irradiance or wind, which "
        "sit at 0 for hours at night or in calm, nor a steady room)", choices=tuple(SENSORS))
    max_rate_k_per_min: float = setting(
        10.0, doc="Largest plausible change of a temperature between two readings, per "
        "minute; a faster jump is flagged RATE (a loose connector, a spike)", unit="K/min",
        gt=0, le=200)
    rate_signals: tuple[str, ...] = setting(
        RATE_SIGNALS, doc="Signals checked for their rate of change (default: the panes, room "
        "and outdoor air; not the fast louver slat and cavity air)", choices=tuple(SENSORS))
    max_sample_age_s: float = setting(
        30.0, doc="A sample older than this when the decision is taken is STALE (a read that "
        "hung); measured in real seconds, also under an accelerated clock", unit="s", gt=0,
        le=3600)

    def check(self) -> list[Problem]:
        out = []
        for key in ("stuck_signals", "rate_signals"):
            for i, name in enumerate(getattr(self, key)):
                if name not in SENSORS:
                    out.append(Problem(f"{key}[{i}]", name,
                                       f"not a sensor signal; known: {', '.join(SENSORS)}"))
        return out


@dataclass(frozen=True, kw_only=True)
class DaemonSettings:
    """The controller daemon of one panel (``dsfd run``; systemd unit ``dsfd@PANEL``)."""

    state_directory: str | None = setting(
        None, doc="Directory for the time-series database and the calibration state; null: "
        "the --state-dir option, else $STATE_DIRECTORY (set by systemd's StateDirectory=)")
    cycle_period_s: float = setting(
        60.0, doc="Control cycle on the monotonic clock; must equal model.step_s (the observer "
        "and the calibrator predict one model step per cycle)", unit="s", ge=1, le=3600)
    calibrate_budget_s: float = setting(
        10.0, doc="Time allowed for the calibration update; a late update is abandoned and "
        "the previous parameters are kept", unit="s", gt=0, le=600)
    store_budget_s: float = setting(
        5.0, doc="Time allowed for writing the cycle to the database", unit="s", gt=0, le=600)
    store_buffer_cycles: int = setting(
        720, doc="Cycles kept in memory while the database cannot be written (full disk, I/O "
        "error) and written once it can; older ones are dropped and counted in an event",
        ge=1, le=100000)
    room_temperature_source: Literal["auto", "sensor", "config"] = setting(
        "auto", doc="Room air temperature: the t_room_c sensor (sensor), room.t_in_c (config), "
        "or the sensor while it reads GOOD and room.t_in_c otherwise (auto)")
    max_predicted_cycles: int = setting(
        10, doc="A state x1..x5 whose sensor is bad may be carried by the model's one-step "
        "prediction for at most this many cycles; then the optimiser lacks it", ge=0, le=1440)
    quality: QualitySettings = setting(default_factory=QualitySettings,
                                       doc="Sensor quality checks")
    metrics_file: str | None = setting(
        None, doc="Prometheus metrics of the panel, rewritten atomically after every cycle in "
        "the text exposition format for node_exporter's textfile collector (e.g. "
        "/var/lib/node_exporter/textfile_collector/dsfd-suwon-south.prom); null: off. Needs "
        "prometheus_client: pip install 'dsfd[metrics]'")

    def check(self) -> list[Problem]:
        if self.metrics_file is not None and not self.metrics_file.endswith(".prom"):
            return [Problem("metrics_file", self.metrics_file,
                            "must end in .prom (node_exporter's textfile collector reads only "
                            "*.prom files)")]
        return []
