"""The JSON a panel publishes: per-cycle state, daily KPIs, Home Assistant discovery configs.

Pure functions over rows the daemon stored (no I/O): :mod:`dsfd.integrations.mqtt.outbox`
reads the rows, :mod:`dsfd.integrations.mqtt.publisher` sends the results.

Topics under the panel's base topic ``<base>`` (default ``dsfd/<panel id>``):

=====================  ========  ======  =====================================================
topic                  retained  QoS     payload
=====================  ========  ======  =====================================================
``<base>/state``       yes       1       one JSON object per cycle (:func:`state_message`)
``<base>/availability`` yes      1       ``online`` / ``offline`` (also the last will)
``<base>/kpi``         yes       1       the last completed local day (:func:`daily_kpis`)
``<base>/cmd/...``     —         —       commands in (:mod:`~.commands`)
``<base>/error``       no        0       answers to refused commands (:mod:`~.receiver`)
``<base>/finding/K``   yes       1       open findings of kind K (:func:`finding_messages`)
=====================  ========  ======  =====================================================

Home Assistant discovery follows the documented schema (home-assistant.io/integrations/mqtt,
"MQTT Discovery", and the pages of the MQTT sensor, binary sensor, select, number and button
platforms):

* config topic ``<discovery_prefix>/<component>/<object_id>/config``, retained; the object ID
  uses only ``[a-zA-Z0-9_-]`` and equals the entity's ``unique_id`` (the documented best
  practice, without a node ID);
* every config carries ``unique_id``, a ``device`` block (``identifiers`` list, ``name``,
  ``manufacturer``, ``model``, ``sw_version``) that groups the entities as one device per
  panel, an ``origin`` block (``name``, ``sw_version``) and ``availability_topic`` (default
  payloads ``online``/``offline``);
* sensors read ``state_topic`` with a ``value_template`` over ``value_json``; a value the
  panel does not have renders as ``None``, which the MQTT platforms take as *unknown*;
  ``device_class`` and ``unit_of_measurement`` are pairs Home Assistant accepts
  (``homeassistant/components/sensor/const.py``, ``DEVICE_CLASS_UNITS``): temperature °C,
  speed m/s, power W, irradiance W/m², duration ms/s; ``state_class: measurement``;
* the faults ``binary_sensor`` has ``device_class: problem`` and compares the rendered
  template with ``payload_on``/``payload_off``; the occupancy ``binary_sensor`` likewise, with
  ``device_class: occupancy`` (the occupancy the comfort limits follow, issue 36);
* one ``binary_sensor`` with ``device_class: problem`` per finding kind of the diagnostics
  (:data:`~dsfd.estimation.lifecycle.FINDING_KINDS`, issue 38) reads ``<base>/finding/<kind>``:
  ``value_template`` renders ``ON`` while a finding of the kind is open, else ``OFF`` (the
  platform's default ``payload_on``/``payload_off``), and ``json_attributes_topic`` with
  ``json_attributes_template`` gives the open findings with their evidence as attributes;
* the day's comfort figures are sensors on the retained ``<base>/kpi`` topic
  (``value_json.comfort.*``): durations in min, the DGPs percentile without a unit, the
  share above the glare limit in %;
* the regime and control-objective ``select`` entities need ``command_topic`` and
  ``options``; the louver and damper ``number`` entities have ``command_topic``, ``min``,
  ``max``, ``step`` and ``mode``; the resume ``button`` has ``command_topic`` and
  ``payload_press``. What they publish is handled as :mod:`~dsfd.integrations.mqtt.commands`
  describes.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from datetime import UTC, date, datetime, timedelta
from typing import Any

import numpy as np

from dsfd.config import PanelConfig
from dsfd.config.panel import REGIME_NAMES
from dsfd.daemon.commands import OBJECTIVE_MODES
from dsfd.estimation.lifecycle import FINDING_KINDS
from dsfd.report.comfort_kpis import comfort_kpis
from dsfd.report.kpis import local_dates
from dsfd.signals import SENSOR_NAMES
from dsfd.storage.schema import HEAT_TERMS

__all__ = [
    "HEAT_TERMS",
    "daily_kpis",
    "discovery_configs",
    "dumps",
    "finding_messages",
    "local_day",
    "object_id",
    "regime_option",
    "state_message",
]

GOOD = "good"


def dumps(message: Mapping[str, Any]) -> str:
    """Compact JSON with NaN/inf as null (JSON has neither)."""
    return json.dumps(_finite(message), separators=(",", ":"), ensure_ascii=False)


def _finite(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def regime_option(afr: int) -> str:
    """The regime as a select option: ``"3: outdoor air curtain up"``."""
    return f"{afr}: {REGIME_NAMES.get(afr, 'unknown')}"


# --------------------------------------------------------------------------- state
def state_message(panel_id: str, row: Mapping[str, Any],
                  samples: Mapping[str, tuple[float | None, str]], *,
                  calibrated_s: float | None) -> dict[str, Any]:
    """The state of one stored cycle.

    Parameters
    ----------
    panel_id : str
    row : mapping
        The cycle's ``decisions`` row with the run's ``mode`` (docs/storage-schema.md).
    samples : mapping
        Signal → (value as delivered, quality) of the cycle's ``samples`` rows.
    calibrated_s : float or None
        Time of the newest on-line calibration update at or before the cycle [s, UTC].
    """
    method = str(row["method"])
    trace = _json_list(row.get("trace"))
    wind_set = any(t.get("stage") == "wind" and t.get("set") for t in trace)
    flagged = {n: q for n, (_, q) in sorted(samples.items()) if q != GOOD}
    faults = [f"{name}: {quality}" for name, quality in flagged.items()]
    if method == "safe":
        faults.append(f"safe state: {row.get('fallback_reason') or 'fault signal not GOOD'}")
    if row.get("write_status") == "failed":
        faults.append("write failed")
    afr = int(row["afr"])
    heating = row.get("heating")
    timings = _json_dict(row.get("timings_ms"))
    time_s = float(row["time_s"])
    return {
        "panel": panel_id, "run": int(row["run_id"]), "cycle": int(row["cycle"]),
        "slot": int(row["slot"]), "time_utc": row["time_utc"], "time_s": time_s,
        "mode": row.get("mode"),
        "objective": None if heating is None else ("heating" if heating else "cooling"),
        "set_by": "wind" if wind_set and method != "safe" else method,
        "method": method,
        "command": {"louver_deg": float(row["phi_deg"]), "regime": afr,
                    "regime_name": REGIME_NAMES.get(afr), "regime_option": regime_option(afr),
                    "damper_pct": float(row["or_pct"])},
        "write": row.get("write_status"),
        **_hold_fields(row),
        "objective_mode": row.get("objective_mode"),
        "objective_set_by": _objective_by(row),
        "occupancy": _occupancy_fields(row),
        "comfort": {k: _float(row.get(k)) for k in _COMFORT_QUANTITIES}
        | {"violations": _json_strings(row.get("violations"))},
        "measured": {n: (v if q == GOOD and v is not None else None)
                     for n, (v, q) in samples.items() if n in _SENSOR_SET},
        "flagged": flagged,
        "fault": bool(faults), "faults": faults,
        "estimate": {f"x{i}_c": _float(row.get(f"est_x{i}_c")) for i in range(1, 7)},
        "heat_w": {q: _float(row.get(f"{q}_w")) for q in HEAT_TERMS},
        "decision_ms": timings.get("decide"),
        "cycle_ms": _float(row.get("cycle_ms")),
        "calibration_age_s": None if calibrated_s is None else max(time_s - calibrated_s, 0.0),
        "fallback": row.get("fallback_reason") or None,
    }


_SENSOR_SET = frozenset(SENSOR_NAMES)


def _hold_fields(row: Mapping[str, Any]) -> dict[str, Any]:
    """The manual hold of a cycle (``decisions.hold_*``, issue 20) and who gave an operator
    hold (its ``commands`` row)."""
    source = row.get("hold_source")
    expires = row.get("hold_expires_s")
    by = None
    if row.get("hold_by_source"):
        by = f"{row['hold_by_source']} {row.get('hold_by_requester') or ''}".strip()
    return {"hold": source is not None, "hold_source": source,
            "hold_until_utc": None if expires is None else utc_iso(float(expires)),
            "hold_by": by, "hold_command_id": row.get("hold_command_id")}


#: The comfort quantities of a cycle in the state message (table ``comfort``, issue 36).
_COMFORT_QUANTITIES = ("direct_sun_wm2", "dgp", "supply_air_c", "asymmetry_k")


def _occupancy_fields(row: Mapping[str, Any]) -> dict[str, Any]:
    """The occupancy of a cycle, where it came from, and an operator's override in force."""
    occupied = row.get("occupied")
    until = row.get("occupancy_until_s")
    return {"occupied": None if occupied is None else bool(occupied),
            "source": row.get("occupancy_source"),
            "override": row.get("occupancy_override"),
            "override_until_utc": None if until is None else utc_iso(float(until)),
            "override_command_id": row.get("occupancy_command_id")}


def _json_strings(text: Any) -> list[str]:
    try:
        value = json.loads(text) if isinstance(text, str) else text
    except ValueError:
        return []
    return [str(v) for v in value] if isinstance(value, list) else []


def _objective_by(row: Mapping[str, Any]) -> str | None:
    if row.get("objective_mode") is None:
        return None
    cid = row.get("mode_command_id")
    return "panel file" if cid is None else f"operator command #{cid}"


def _json_list(text: Any) -> list[dict[str, Any]]:
    try:
        value = json.loads(text) if isinstance(text, str) else text
    except ValueError:
        return []
    return [v for v in value if isinstance(v, dict)] if isinstance(value, list) else []


def _json_dict(text: Any) -> dict[str, Any]:
    try:
        value = json.loads(text) if isinstance(text, str) else text
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def _float(value: Any) -> float | None:
    return None if value is None else float(value)


# --------------------------------------------------------------------------- KPIs
def local_day(time_s: float, utc_offset_h: float) -> date:
    """The panel's local (standard time) calendar day of a UTC time [s] (as ``dsfd report``
    counts days: :func:`dsfd.report.kpis.local_dates`)."""
    return local_dates(time_s, utc_offset_h).item()


def day_bounds_s(day: date, utc_offset_h: float) -> tuple[float, float]:
    """UTC start and end [s] of a local day."""
    start = datetime(day.year, day.month, day.day, tzinfo=UTC).timestamp() \
        - utc_offset_h * 3600.0
    return start, start + 86400.0


def daily_kpis(panel_id: str, day: date, rows: Sequence[Mapping[str, Any]], *,
               utc_offset_h: float, flagged_samples: int, calibration_updates: int,
               heat_kwh: Mapping[str, float | None] | None = None, heat_hours: float = 0.0,
               comfort_rows: Sequence[Mapping[str, Any]] = (), step_s: float = 60.0
               ) -> dict[str, Any]:
    """Key figures of one local day from its ``decisions`` rows in cycle order, with the
    model's heat into the room by term [kWh] over ``heat_hours`` of steps with figures, and
    the comfort figures of its ``comfort`` rows, each a cycle period ``step_s`` long
    (:func:`dsfd.report.comfort_kpis.comfort_kpis`)."""
    methods: dict[str, int] = {}
    for r in rows:
        methods[str(r["method"])] = methods.get(str(r["method"]), 0) + 1
    decide = np.array([v for r in rows if (v := _json_dict(r.get("timings_ms")).get("decide"))
                       is not None], float)
    return {
        "panel": panel_id, "day": day.isoformat(), "utc_offset_h": utc_offset_h,
        "cycles": len(rows), "cycles_by_method": dict(sorted(methods.items())),
        "louver_moves": _changes(r["phi_deg"] for r in rows),
        "regime_changes": _changes(r["afr"] for r in rows),
        "damper_moves": _changes(r["or_pct"] for r in rows),
        "write_failures": sum(r.get("write_status") == "failed" for r in rows),
        "skipped_slots": sum(int(r.get("skipped_slots") or 0) for r in rows),
        "flagged_samples": flagged_samples,
        "calibration_updates": calibration_updates,
        "decision_ms_p50": float(np.percentile(decide, 50)) if decide.size else None,
        "decision_ms_p99": float(np.percentile(decide, 99)) if decide.size else None,
        "heat_kwh": {q: (heat_kwh or {}).get(q) for q in HEAT_TERMS},
        "heat_hours": heat_hours,
        "comfort": comfort_kpis(comfort_rows, step_s=step_s),
    }


def _changes(values: Iterable[Any]) -> int:
    out, last = 0, None
    for v in values:
        if last is not None and v != last:
            out += 1
        last = v
    return out


# --------------------------------------------------------------------------- discovery
_OBJECT_ID = re.compile(r"[^A-Za-z0-9_-]")


def object_id(panel_id: str, key: str) -> str:
    """Discovery object ID and unique_id of one entity: ``dsfd_<panel>_<key>``."""
    return _OBJECT_ID.sub("_", f"dsfd_{panel_id}_{key}")


#: (key, name, template path, device_class, unit) of the numeric sensors.
_SENSORS: tuple[tuple[str, str, str, str | None, str], ...] = (
    ("x1", "Exterior pane (x1)", "measured.x1_c", "temperature", "°C"),
    ("x2", "Interior DGU outer pane (x2)", "measured.x2_c", "temperature", "°C"),
    ("x3", "Interior DGU inner pane (x3)", "measured.x3_c", "temperature", "°C"),
    ("x4", "Louver slat (x4)", "measured.x4_c", "temperature", "°C"),
    ("x5", "Cavity air (x5)", "measured.x5_c", "temperature", "°C"),
    ("v_cav", "Cavity air speed", "measured.v_cav_ms", "speed", "m/s"),
    ("t_out", "Outdoor air", "measured.t_out_c", "temperature", "°C"),
    ("ghi", "Global horizontal irradiance", "measured.ghi_wm2", "irradiance", "W/m²"),
    ("x6_est", "DGU gas gap (x6, estimated)", "estimate.x6_c", "temperature", "°C"),
    ("q_sol_trans", "Solar heat transmitted", "heat_w.q_sol_trans", "power", "W"),
    ("q_cv_rd", "Convective and long-wave heat", "heat_w.q_cv_rd", "power", "W"),
    ("q_air", "Ventilation air heat", "heat_w.q_air", "power", "W"),
    ("q_da", "Daylight credit", "heat_w.q_da", "power", "W"),
    ("decision_time", "Decision time", "decision_ms", "duration", "ms"),
    ("calibration_age", "Calibration age", "calibration_age_s", "duration", "s"),
)


#: (key, name, KPI key, device_class, unit, icon) of the day's comfort figures, read from the
#: retained ``<base>/kpi`` (the last completed local day; issue 36).
_COMFORT_SENSORS: tuple[tuple[str, str, str, str | None, str | None, str], ...] = (
    ("occupied_time", "Occupied time (last day)", "occupied_min", "duration", "min",
     "mdi:account-clock"),
    ("direct_sun_time", "Occupied time with direct sun (last day)",
     "occupied_direct_sun_min", "duration", "min", "mdi:white-balance-sunny"),
    ("dgp_p95", "Glare DGPs 95th percentile (last day)", "dgp_p95", None, None,
     "mdi:sun-wireless"),
    ("dgp_above_limit", "Occupied time above the glare limit (last day)",
     "dgp_above_limit_pct", None, "%", "mdi:sun-wireless-outline"),
    ("draught_time", "Supply air below the draught limit (last day)",
     "supply_air_below_limit_min", "duration", "min", "mdi:weather-windy"),
    ("asymmetry_time", "Radiant asymmetry beyond the limit (last day)",
     "asymmetry_beyond_limit_min", "duration", "min", "mdi:thermometer-lines"),
)


def discovery_configs(cfg: PanelConfig, *, base_topic: str, discovery_prefix: str,
                      version: str) -> list[tuple[str, dict[str, Any]]]:
    """(config topic, payload) of every entity of the panel's Home Assistant device."""
    pid = cfg.panel.id
    state = f"{base_topic}/state"
    common: dict[str, Any] = {
        "availability_topic": f"{base_topic}/availability",
        "payload_available": "online", "payload_not_available": "offline",
        "device": {"identifiers": [object_id(pid, "panel")],
                   "name": f"DSF panel {pid}", "manufacturer": "dsfd",
                   "model": "double-skin façade panel (MPC)", "sw_version": version},
        "origin": {"name": "dsfd", "sw_version": version},
    }
    out: list[tuple[str, dict[str, Any]]] = []

    def add(component: str, key: str, name: str, **fields: Any) -> None:
        uid = object_id(pid, key)
        out.append((f"{discovery_prefix}/{component}/{uid}/config",
                    {"name": name, "unique_id": uid, **fields, **common}))

    for key, name, path, device_class, unit in _SENSORS:
        add("sensor", key, name, state_topic=state, value_template=f"{{{{ value_json.{path} }}}}",
            device_class=device_class, unit_of_measurement=unit, state_class="measurement")
    add("sensor", "set_by", "Command set by", state_topic=state,
        value_template="{{ value_json.set_by }}", icon="mdi:account-cog")
    add("sensor", "hold", "Manual hold", state_topic=state,
        value_template="{{ value_json.hold_source }}", icon="mdi:hand-back-right",
        json_attributes_topic=state, json_attributes_template="{{ {'until': "
        "value_json.hold_until_utc, 'by': value_json.hold_by} | tojson }}")
    add("binary_sensor", "fault", "Fault", state_topic=state, device_class="problem",
        value_template="{{ value_json.fault }}", payload_on="True", payload_off="False",
        json_attributes_topic=state,
        json_attributes_template="{{ {'faults': value_json.faults} | tojson }}")
    add("binary_sensor", "occupancy", "Occupancy", state_topic=state,
        device_class="occupancy", value_template="{{ value_json.occupancy.occupied }}",
        payload_on="True", payload_off="False", json_attributes_topic=state,
        json_attributes_template="{{ {'source': value_json.occupancy.source, 'override': "
        "value_json.occupancy.override, 'until': value_json.occupancy.override_until_utc} "
        "| tojson }}")
    for key, name, kpi, device_class, unit, icon in _COMFORT_SENSORS:
        fields = {"device_class": device_class, "unit_of_measurement": unit}
        add("sensor", key, name, state_topic=f"{base_topic}/kpi",
            value_template=f"{{{{ value_json.comfort.{kpi} }}}}", state_class="measurement",
            icon=icon, **{k: v for k, v in fields.items() if v is not None})
    for kind in FINDING_KINDS:
        topic = f"{base_topic}/finding/{kind}"
        add("binary_sensor", f"finding_{kind}", f"Finding: {kind.replace('_', ' ')}",
            state_topic=topic, device_class="problem", value_template="{{ value_json.state }}",
            payload_on="ON", payload_off="OFF", json_attributes_topic=topic,
            json_attributes_template="{{ {'findings': value_json.findings} | tojson }}")
    cmd = f"{base_topic}/cmd"
    add("select", "regime", "Airflow regime", state_topic=state,
        value_template="{{ value_json.command.regime_option }}", command_topic=f"{cmd}/regime",
        options=[regime_option(r) for r in cfg.openings.available_regimes()], qos=1,
        retain=False)
    add("select", "objective", "Control objective", state_topic=state,
        value_template="{{ value_json.objective_mode }}", command_topic=f"{cmd}/mode",
        options=list(OBJECTIVE_MODES), qos=1, retain=False, icon="mdi:sun-snowflake-variant")
    s = cfg.safety
    if cfg.louver is not None:
        angles = [a for a in cfg.louver.angles_deg()
                  if s.phi_min_deg - 1e-9 <= a <= s.phi_max_deg + 1e-9]
        add("number", "louver", "Louver angle", state_topic=state,
            value_template="{{ value_json.command.louver_deg }}",
            command_topic=f"{cmd}/louver_deg", min=min(angles), max=max(angles),
            step=cfg.louver.step_deg, mode="box", unit_of_measurement="°", qos=1, retain=False)
    add("number", "damper", "Damper opening", state_topic=state,
        value_template="{{ value_json.command.damper_pct }}", command_topic=f"{cmd}/damper_pct",
        min=0.0, max=s.or_max_pct, step=s.or_step_pct, mode="box", unit_of_measurement="%",
        qos=1, retain=False)
    add("button", "resume", "Resume automatic control", command_topic=f"{cmd}/resume",
        payload_press="resume", qos=1, retain=False)
    return out


def utc_iso(time_s: float) -> str:
    return (datetime(1970, 1, 1, tzinfo=UTC) + timedelta(seconds=time_s)).strftime(
        "%Y-%m-%dT%H:%M:%SZ")


def finding_messages(base_topic: str, rows: Sequence[Mapping[str, Any]]
                     ) -> list[tuple[str, str]]:
    """(topic, payload) per finding kind: ``{"state": "ON"|"OFF", "findings": [...]}`` with
    the open findings of that kind (``rows``: :func:`dsfd.storage.findings.open_findings`),
    each with its id (for an ``ack``), subject, confidence, start, action and evidence."""
    by_kind: dict[str, list[dict[str, Any]]] = {k: [] for k in FINDING_KINDS}
    for r in rows:
        by_kind.setdefault(str(r["kind"]), []).append({
            "id": r["finding_id"], "subject": r["subject"],
            "confidence": _finite(r["confidence"]), "start_utc": utc_iso(r["start_s"]),
            "detected_utc": utc_iso(r["detected_s"]), "action": r["action"],
            "evidence": r["evidence"]})
    return [(f"{base_topic}/finding/{kind}",
             dumps({"state": "ON" if found else "OFF", "findings": found}))
            for kind, found in by_kind.items()]
