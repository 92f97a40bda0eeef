"""``daemon.metrics_file``: the panel's metrics for Prometheus, via node_exporter's textfile
collector — no network listener in the daemon.

After every cycle the whole file is written with ``prometheus_client.write_to_textfile``
(a temporary file next to it, then ``rename(2)``), so a scrape never sees it half-written.
Every series carries the label ``panel``; those about one sensor also ``signal``.

=====================================  =======  ==============================================
metric                                 type     meaning
=====================================  =======  ==============================================
dsfd_cycle_duration_seconds            gauge    wall time of the last cycle, all stages
dsfd_decision_duration_seconds         gauge    the last cycle's decide stage
dsfd_last_cycle_timestamp_seconds      gauge    cycle time of the last completed cycle (UTC)
dsfd_cycles_total{method}              counter  cycles by who decided (mpc, rule, safe, …)
dsfd_flagged_samples_total{signal,     counter  readings not used, by signal and quality flag
quality}
dsfd_write_failures_total              counter  commands not verified by read-back
dsfd_calibration_updates_total         counter  successful on-line calibration updates
dsfd_calibration_age_seconds           gauge    since the newest data of the last update
                                                (NaN before the first)
dsfd_parameter{parameter}              gauge    the calibrated θ̂ and heat-flux offsets
dsfd_louver_angle_degrees              gauge    position in effect (command, or read back)
dsfd_airflow_regime                    gauge    1..10
dsfd_damper_opening_ratio              gauge    0..1
dsfd_hold_active                       gauge    1 while a manual hold decides (method manual)
dsfd_room_heat_watts{term}             gauge    the model's room-side heat of the last step
dsfd_occupied{source}                  gauge    1 while the room counts as occupied; source:
                                                override, signal or schedule (issue 36)
dsfd_occupancy_override_active         gauge    1 while an operator's occupancy override holds
dsfd_direct_sun_watts_per_square_meter gauge    unscattered beam into the room, last cycle
dsfd_daylight_glare_probability        gauge    simplified DGPs at the occupant's eye
dsfd_supply_air_celsius                gauge    air blown into the room (NaN: none)
dsfd_radiant_asymmetry_kelvin          gauge    the inner pane's radiant asymmetry, + warm
dsfd_occupied_seconds_total            counter  occupied time (one cycle period per cycle)
dsfd_comfort_exceeded_seconds_total    counter  occupied time beyond a comfort limit; limit:
{limit}                                         direct_sun, glare, draught, asymmetry
dsfd_finding_open{kind}                gauge    open findings of the diagnostics by kind
                                                (docs/model.md#findings; issue 38)
=====================================  =======  ==============================================

The comfort series follow the day figures of the MQTT ``kpi`` topic
(:func:`dsfd.report.comfort_kpis.comfort_kpis`, each cycle counted as one cycle period):
Prometheus gets the running totals, ``increase(...[1d])`` the day's minutes. The gauges
are NaN while the comfort quantities cannot be computed (no forecast, no state estimate).

With an ``mqtt:`` section, the broker's state as the publisher last saw it:

=====================================  =======  ==============================================
dsfd_mqtt_connected                    gauge    1 while connected to the broker
dsfd_mqtt_error{reason}                gauge    1 while not connected after an error (``reason``
                                                the last one: refused, not authorised, …)
dsfd_mqtt_backlog_cycles               gauge    stored cycles whose state is not yet delivered
dsfd_mqtt_delivered_cycle{run}         gauge    the last cycle the broker acknowledged
dsfd_mqtt_delivered_timestamp_seconds  gauge    its cycle time, UTC (NaN: none yet)
dsfd_mqtt_delivered_total              counter  state messages acknowledged
dsfd_mqtt_commands_total{result}       counter  command messages: ``queued`` (into the commands
                                                table), ``refused`` (malformed, out of range),
                                                ``rejected`` (by the loop), ``dropped``
=====================================  =======  ==============================================

Counters count since the daemon started (Prometheus handles the restart); the counters'
``*_created`` series are left out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from dsfd.estimation.lifecycle import FINDING_KINDS
from dsfd.storage.schema import HEAT_TERMS

if TYPE_CHECKING:
    from dsfd.config.comfort import Comfort
    from dsfd.daemon.calibration import CalibrationStage
    from dsfd.daemon.loop import CycleOutcome

__all__ = ["INSTALL_HINT", "MetricsFile", "metrics_problem"]

INSTALL_HINT = "pip install 'dsfd[metrics]'"


def metrics_problem(path: str | None) -> str | None:
    """Why ``daemon.metrics_file`` cannot be written, or None (checked at start and reload)."""
    if path is None:
        return None
    try:
        import prometheus_client  # noqa: F401
    except ImportError:
        return f"needs prometheus_client, which is not installed: {INSTALL_HINT}"
    parent = Path(path).parent
    if not parent.is_dir():
        return f"directory {parent} does not exist"
    return None


class MetricsFile:
    """The metrics of one panel and the file they are written to."""

    def __init__(self, path: str | Path, panel: str) -> None:
        from prometheus_client import CollectorRegistry, Counter, Gauge, disable_created_metrics

        # Counters' ``*_created`` series (wall time of the counter's creation) only repeat the
        # daemon's start time for a textfile; the process is the daemon, so this is global.
        disable_created_metrics()
        self.path = str(path)
        self.panel = panel
        r = self.registry = CollectorRegistry()
        p = ["panel"]

        def gauge(name: str, doc: str, labels: list[str] = p) -> Gauge:
            return Gauge(name, doc, labels, registry=r)

        def counter(name: str, doc: str, labels: list[str] = p) -> Counter:
            return Counter(name, doc, labels, registry=r)

        self.cycle_s = gauge("dsfd_cycle_duration_seconds", "Wall time of the last cycle")
        self.decide_s = gauge("dsfd_decision_duration_seconds",
                              "Wall time of the last cycle's decision stage")
        self.last_cycle = gauge("dsfd_last_cycle_timestamp_seconds",
                                "Cycle time of the last completed cycle, UTC unix seconds")
        self.cycles = counter("dsfd_cycles", "Cycles by who decided", [*p, "method"])
        self.flagged = counter("dsfd_flagged_samples", "Readings flagged and not used",
                               [*p, "signal", "quality"])
        self.write_failures = counter("dsfd_write_failures",
                                      "Commands not verified by read-back")
        self.updates = counter("dsfd_calibration_updates",
                               "Successful on-line calibration updates")
        self.calibration_age = gauge(
            "dsfd_calibration_age_seconds",
            "Seconds since the newest data of the last calibration update (NaN: none yet)")
        self.parameter = gauge("dsfd_parameter", "Calibrated model parameter",
                               [*p, "parameter"])
        self.louver = gauge("dsfd_louver_angle_degrees", "Louver angle in effect")
        self.regime = gauge("dsfd_airflow_regime", "Airflow regime in effect (1..10)")
        self.damper = gauge("dsfd_damper_opening_ratio", "Damper opening in effect (0..1)")
        self.hold = gauge("dsfd_hold_active", "1 while a manual hold decides the position")
        self.heat = gauge("dsfd_room_heat_watts",
                          "Model estimate of the heat into the room over the last step",
                          [*p, "term"])
        for term in HEAT_TERMS:
            self.heat.labels(panel, term).set(math.nan)
        self._comfort = _ComfortMetrics(r, panel)
        self.findings = gauge("dsfd_finding_open", "Open findings of the diagnostics by kind",
                              [*p, "kind"])
        self.update_findings({})
        self.calibration_age.labels(panel).set(math.nan)
        self.write_failures.labels(panel)
        self.updates.labels(panel)
        self._mqtt: _MqttMetrics | None = None

    def update(self, out: CycleOutcome, calibration: CalibrationStage) -> None:
        """Take the figures of a completed cycle."""
        panel = self.panel
        t = out.timings_ms
        self.cycle_s.labels(panel).set(t.get("total", math.nan) / 1e3)
        self.decide_s.labels(panel).set(t.get("decide", math.nan) / 1e3)
        self.last_cycle.labels(panel).set(out.time_s)
        self.cycles.labels(panel, out.method).inc()
        readings = out.quality.sample.readings
        for name in out.quality.flags:
            self.flagged.labels(panel, name, readings[name].quality.value).inc()
        if out.write_status == "failed":
            self.write_failures.labels(panel).inc()
        if out.calibration is not None and out.calibration.updated:
            self.updates.labels(panel).inc()
        last = calibration.state.last_update_s
        self.calibration_age.labels(panel).set(math.nan if last is None else out.time_s - last)
        for name, value in calibration.theta_by_name().items():
            self.parameter.labels(panel, name).set(value)
        pos = out.applied or out.command
        self.louver.labels(panel).set(pos.phi_deg)
        self.regime.labels(panel).set(pos.afr)
        self.damper.labels(panel).set(pos.or_pct / 100.0)
        self.hold.labels(panel).set(1.0 if out.method == "manual" else 0.0)
        pred = out.estimate.prediction if out.estimate is not None else None
        for term in HEAT_TERMS:
            self.heat.labels(panel, term).set(math.nan if pred is None else pred.heat_w[term])
        cfg = calibration.cfg
        self._comfort.update(out, cfg.comfort, period_s=cfg.daemon.cycle_period_s)

    def update_findings(self, open_by_kind: Mapping[str, int]) -> None:
        """Open findings by kind (every known kind, 0 when none is open)."""
        for kind in (*FINDING_KINDS, *open_by_kind):
            self.findings.labels(self.panel, kind).set(float(open_by_kind.get(kind, 0)))

    def update_mqtt(self, health: Mapping[str, Any]) -> None:
        """Take the MQTT publisher's state (``MqttPublisher.health``)."""
        if self._mqtt is None:
            self._mqtt = _MqttMetrics(self.registry)
        self._mqtt.update(self.panel, health)

    def write(self) -> None:
        """Replace the file atomically (raises OSError if it cannot)."""
        from prometheus_client import write_to_textfile

        write_to_textfile(self.path, self.registry)


class _ComfortMetrics:
    """The occupancy and the comfort quantities of the last cycle, and their running totals
    (issue 36)."""

    #: Counter label of each day figure of :func:`~dsfd.report.comfort_kpis.comfort_kpis`
    #: (glare: from the share above the limit).
    LIMITS: ClassVar[dict[str, str | None]] = {
        "direct_sun": "occupied_direct_sun_min", "glare": None,
        "draught": "supply_air_below_limit_min", "asymmetry": "asymmetry_beyond_limit_min"}

    def __init__(self, registry: Any, panel: str) -> None:
        from prometheus_client import Counter, Gauge

        p, r = ["panel"], registry
        self.panel = panel
        self.occupied = Gauge("dsfd_occupied", "1 while the room counts as occupied; source: "
                              "override, signal or schedule", [*p, "source"], registry=r)
        self.override = Gauge("dsfd_occupancy_override_active", "1 while an operator's "
                              "occupancy override holds", p, registry=r)
        self.quantities = {
            "direct_sun_wm2": Gauge("dsfd_direct_sun_watts_per_square_meter", "Solar beam "
                                    "passing the louver unscattered into the room", p,
                                    registry=r),
            "dgp": Gauge("dsfd_daylight_glare_probability", "Simplified daylight glare "
                         "probability DGPs at the occupant's eye", p, registry=r),
            "supply_air_c": Gauge("dsfd_supply_air_celsius", "Air blown into the room "
                                  "(NaN: none)", p, registry=r),
            "asymmetry_k": Gauge("dsfd_radiant_asymmetry_kelvin", "Radiant asymmetry of the "
                                 "inner pane, + warm", p, registry=r)}
        self.occupied_s = Counter("dsfd_occupied_seconds", "Occupied time", p, registry=r)
        self.exceeded_s = Counter("dsfd_comfort_exceeded_seconds", "Occupied time beyond a "
                                  "comfort limit", [*p, "limit"], registry=r)
        self.override.labels(panel).set(0.0)
        self.occupied_s.labels(panel)
        for limit in self.LIMITS:
            self.exceeded_s.labels(panel, limit)
        for gauge in self.quantities.values():
            gauge.labels(panel).set(math.nan)

    def update(self, out: CycleOutcome, limits: Comfort, *, period_s: float) -> None:
        from dsfd.daemon.record import comfort_row
        from dsfd.report.comfort_kpis import comfort_kpis

        panel = self.panel
        row = comfort_row(out, limits)
        self.override.labels(panel).set(0.0 if out.occupancy_override is None else 1.0)
        if row is None:
            return
        self.occupied.clear()  # one series: the source of now
        self.occupied.labels(panel, row["occupancy_source"]).set(float(row["occupied"]))
        for key, gauge in self.quantities.items():
            value = row.get(key)
            gauge.labels(panel).set(math.nan if value is None else float(value))
        day = comfort_kpis([row], step_s=period_s)
        self.occupied_s.labels(panel).inc(day["occupied_min"] * 60.0)
        glare = (day["dgp_above_limit_pct"] or 0.0) / 100.0 * day["occupied_min"]
        for limit, key in self.LIMITS.items():
            minutes = glare if key is None else day[key]
            self.exceeded_s.labels(panel, limit).inc(minutes * 60.0)


class _MqttMetrics:
    """The broker's state (series only with an ``mqtt:`` section)."""

    def __init__(self, registry: Any) -> None:
        from prometheus_client import Counter, Gauge

        p = ["panel"]
        r = registry
        self.connected = Gauge("dsfd_mqtt_connected", "1 while connected to the MQTT broker",
                               p, registry=r)
        self.error = Gauge("dsfd_mqtt_error", "1 while not connected to the broker after an "
                           "error; reason: the last error", [*p, "reason"], registry=r)
        self.backlog = Gauge("dsfd_mqtt_backlog_cycles", "Stored cycles whose state message "
                             "is not yet acknowledged by the broker", p, registry=r)
        self.cycle = Gauge("dsfd_mqtt_delivered_cycle", "The last cycle whose state the "
                           "broker acknowledged (with all before it)", [*p, "run"], registry=r)
        self.time = Gauge("dsfd_mqtt_delivered_timestamp_seconds", "Cycle time of the last "
                          "acknowledged state, UTC unix seconds (NaN: none yet)", p, registry=r)
        self.delivered = Counter("dsfd_mqtt_delivered", "State messages acknowledged by the "
                                 "broker", p, registry=r)
        self.commands = Counter("dsfd_mqtt_commands", "Command messages by what became of "
                                "them", [*p, "result"], registry=r)
        # The publisher's command counts start with this process; its delivered count spans
        # earlier runs (kept in the database), so its first value is the baseline.
        self._seen: dict[str, float] = dict.fromkeys(("queued", "refused", "rejected",
                                                      "dropped"), 0.0)

    def update(self, panel: str, h: Mapping[str, Any]) -> None:
        self.connected.labels(panel).set(1.0 if h["connected"] else 0.0)
        self.error.clear()  # one series: the reason of now
        failed = not h["connected"] and bool(h["last_error"])
        self.error.labels(panel, h["last_error"] if failed else "").set(1.0 if failed else 0.0)
        self.backlog.labels(panel).set(h["backlog"])
        self.cycle.clear()
        self.cycle.labels(panel, str(h["delivered_run"])).set(h["delivered_cycle"])
        t = h["delivered_time_s"]
        self.time.labels(panel).set(math.nan if t is None else t)
        self._count(self.delivered.labels(panel), "delivered", h["delivered"])
        for result, n in h["commands"].items():
            self._count(self.commands.labels(panel, result), result, n)

    def _count(self, counter: Any, key: str, total: float) -> None:
        """Counters move by what the publisher counted since the last cycle."""
        last = self._seen.get(key)
        self._seen[key] = total
        if last is not None and total > last:
            counter.inc(total - last)
