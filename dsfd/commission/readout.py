"""``dsfd commission --signals``: read every configured signal several times, one row per
signal, then the plausibility checks of :mod:`dsfd.commission.checks`."""

from __future__ import annotations

import asyncio
import math
import statistics
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from dsfd.commission.checks import (
    Conditions,
    Finding,
    check_duplicates,
    check_feedback,
    check_louver_range,
    check_night,
    check_order,
    check_scales,
    order_constraints,
)
from dsfd.commission.rig import Rig, describe_point
from dsfd.config.devices import STATION_SIGNALS
from dsfd.drivers.station import SENTENCE
from dsfd.signals import SIGNALS

if TYPE_CHECKING:
    from dsfd.config.panel import PanelConfig

__all__ = ["ActuatorRow", "Readout", "SignalRow", "read_signals"]


@dataclass(frozen=True)
class SignalRow:
    """One signal over the reads: where it comes from, its median raw and scaled value, its
    quality (``good`` only if every read was GOOD) and the median read latency of its device."""

    signal: str
    source: str
    unit: str
    raw: float | None
    value: float | None
    quality: str
    good_reads: int
    reads: int
    latency_ms: float
    values: tuple[float, ...]
    detail: str = ""

    @property
    def ok(self) -> bool:
        return self.quality == "good"

    def as_dict(self) -> dict[str, object]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in self.__dict__.items() if k != "values"} | {
            "values": [v if math.isfinite(v) else None for v in self.values]}


@dataclass(frozen=True)
class ActuatorRow:
    """An actuator's set-point register and, if configured, its position feedback."""

    signal: str
    source: str
    unit: str
    set_point: float | None
    feedback: float | None
    feedback_source: str

    def as_dict(self) -> dict[str, object]:
        return dict(self.__dict__)


@dataclass
class Readout:
    rows: list[SignalRow]
    actuators: list[ActuatorRow]
    conditions: Conditions
    findings: list[Finding] = field(default_factory=list)


def _linear(panel: PanelConfig) -> tuple[dict[str, tuple[str, float, float]], dict[str, str]]:
    """Per Modbus sensor: (source, scale, offset); per station field: source."""
    points: dict[str, tuple[str, float, float]] = {}
    station: dict[str, str] = {}
    assert panel.devices is not None
    for cfg in panel.devices.entries:
        if cfg.is_modbus:
            for p in cfg.sensor_points():
                points[p.name] = (describe_point(cfg.name, p), p.scale, p.offset)
        else:
            for i, name in enumerate(STATION_SIGNALS):
                station[name] = f"{cfg.name} ${SENTENCE} field {i + 2}"
    return points, station


async def read_signals(panel: PanelConfig, rig: Rig, conditions: Conditions, *, reads: int,
                       interval_s: float) -> Readout:
    """``reads`` reads ``interval_s`` apart after one warm-up read (it opens the ports; the
    station flushes what it buffered before), then rows and findings."""
    await rig.read_timed()
    values: dict[str, list[float]] = defaultdict(list)
    qualities: dict[str, Counter[str]] = defaultdict(Counter)
    details: dict[str, str] = {}
    latency: dict[str, list[float]] = defaultdict(list)
    for _ in range(reads):
        await asyncio.sleep(interval_s)
        for timed in await rig.read_timed():
            for name, r in timed.sample.readings.items():
                values[name].append(r.value)
                qualities[name][r.quality.value] += 1
                latency[name].append(timed.latency_s)
                if not r.ok:
                    details[name] = r.detail
    points, station = _linear(panel)
    rows = []
    for name in (n for n in SIGNALS if n in values):
        good = [v for v in values[name] if math.isfinite(v)]
        value = statistics.median(good) if good else None
        source, scale, offset = points.get(name, (station.get(name, "?"), 1.0, 0.0))
        raw = None if value is None else (value - offset) / scale
        bad = {q: n for q, n in qualities[name].items() if q != "good"}
        quality = "good" if not bad else max(bad, key=lambda q: bad[q])
        rows.append(SignalRow(name, source, SIGNALS[name].unit, raw, value, quality,
                              qualities[name]["good"], reads,
                              1000.0 * statistics.median(latency[name]),
                              tuple(values[name]), details.get(name, "")))
    actuators = await _actuator_rows(rig)
    readout = Readout(rows, actuators, conditions)
    readout.findings = findings(readout, panel)
    return readout


async def _actuator_rows(rig: Rig) -> list[ActuatorRow]:
    set_points = await rig.composite.read_actuators()
    feedback = await rig.read_feedback()
    where = rig.set_point_where()
    return [ActuatorRow(name, where[name], SIGNALS[name].unit, set_points.get(name),
                        feedback.get(name),
                        rig.feedback_where(name) if name in rig.feedback else "")
            for name in (n for n in SIGNALS if n in where)]


def findings(readout: Readout, panel: PanelConfig) -> list[Finding]:
    """Every finding of the read-out: bad quality first, then the checks."""
    out = _quality_findings(readout)
    values = {r.signal: r.value for r in readout.rows if r.value is not None}
    points, _ = _linear(panel)
    scale_findings, mis_scaled = check_scales(values, {k: v[1] for k, v in points.items()})
    out += scale_findings
    physical = {k: v for k, v in values.items() if k not in mis_scaled}
    out += check_night(physical, readout.conditions)
    where = {k: v[0] for k, v in points.items()}
    out += check_order(physical, order_constraints(physical, readout.conditions), where)
    out += check_duplicates({r.signal: r.values for r in readout.rows if r.ok}, where)
    unread = [a for a in readout.actuators if a.set_point is None]
    if unread:
        out.append(Finding("quality", tuple(a.signal for a in unread), "set-point registers "
                           "could not be read: " + ", ".join(f"{a.signal} ({a.source})"
                                                              for a in unread),
                           "wiring, address or device id"))
    safety = panel.safety
    for a in readout.actuators:
        if a.set_point is None:
            continue
        if a.signal == "phi_deg":
            for value, where in ((a.set_point, a.source), (a.feedback, a.feedback_source)):
                found = None if value is None else check_louver_range(
                    value, safety.phi_min_deg, safety.phi_max_deg, where)
                if found is not None:
                    out.append(found)
        if a.feedback_source and a.feedback is None:
            out.append(Finding("quality", (a.signal,), f"{a.signal}: feedback "
                               f"{a.feedback_source} could not be read", "address or table"))
        elif a.feedback is not None:
            found = check_feedback(a.signal, a.set_point, a.feedback, a.feedback_source)
            if found is not None:
                out.append(found)
    return out


def _quality_findings(readout: Readout) -> list[Finding]:
    """One finding per device and flag (a dead device is one finding, not one per signal)."""
    groups: dict[tuple[str, str], list[SignalRow]] = defaultdict(list)
    for r in readout.rows:
        if not r.ok:
            groups[(r.source.split()[0], r.quality)].append(r)
    out = []
    for (device, quality), rows in groups.items():
        counts = ", ".join(f"{r.signal} {r.good_reads}/{r.reads}" for r in rows)
        detail = next((r.detail for r in rows if r.detail), "")
        out.append(Finding("quality", tuple(r.signal for r in rows),
                           f"{device}: {quality} (good reads: {counts})"
                           + (f"; {detail}" if detail else ""),
                           "see the detail: wiring, address, device id or port"))
    return out
