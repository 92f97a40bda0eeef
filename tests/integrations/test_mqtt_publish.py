"""What a panel publishes, as a third-party subscriber (``mosquitto_sub``) receives it.

The real ``dsfd run`` (simulated plant) publishes to a real Mosquitto with a password file.
The discovery configs are checked against Home Assistant's documented MQTT discovery schema,
written out here from its documentation (home-assistant.io/integrations/mqtt, "MQTT
Discovery", and the sensor, binary_sensor, select, number and button MQTT platform pages; the
device-class units from homeassistant/components/sensor/const.py), not from dsfd's code. Each
``value_template`` is rendered against the state messages that arrived, as Home Assistant
would (the templates are of the form ``{{ value_json.a.b }}``, rendered here by walking the
path; ``None`` is what Jinja prints for a JSON null, which the MQTT platforms take as
*unknown*). What the messages say is compared with the daemon's database.
"""

from __future__ import annotations

import json
import re
import subprocess
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from dsfd.estimation.lifecycle import FINDING_KINDS
from dsfd.integrations.mqtt.broker import LocalBroker
from dsfd.report.kpis import compute_kpis
from dsfd.storage.history import read_history
from tests.daemon.harness import ROOT, dsfd_command, query
from tests.integrations.mqtt_harness import Message, Subscriber, mqtt_panel, run_args

#: Local midnight (UTC+9) falls between cycles 5 and 6: the day's KPIs go out during the run.
START = "2022-01-01T14:55:00Z"
CYCLES = 9
PANEL = "suwon-south"
BASE = f"dsfd/{PANEL}"

#: Discovery topic: <discovery_prefix>/<component>/[<node_id>/]<object_id>/config, IDs from
#: the character class [a-zA-Z0-9_-].
TOPIC = re.compile(r"^homeassistant/(?P<component>[a-z_]+)/(?:[A-Za-z0-9_-]+/)?"
                   r"(?P<object_id>[A-Za-z0-9_-]+)/config$")
#: Keys each platform requires (the platform pages: "Required").
REQUIRED = {"sensor": {"state_topic"}, "binary_sensor": {"state_topic"},
            "select": {"command_topic", "options"}, "number": {"command_topic"},
            "button": {"command_topic"}}
#: Units Home Assistant accepts per sensor device class (DEVICE_CLASS_UNITS).
UNITS = {"temperature": {"°C", "°F", "K"}, "speed": {"m/s", "km/h", "mph", "kn", "ft/s"},
         "power": {"W", "kW", "MW"}, "irradiance": {"W/m²", "BTU/(h⋅ft²)"},
         "duration": {"ms", "s", "min", "h", "d"}}
STATE_CLASSES = {"measurement", "total", "total_increasing"}
TEMPLATE = re.compile(r"^\{\{ value_json((?:\.[A-Za-z0-9_]+)+) \}\}$")


def render(template: str, state: dict[str, Any]) -> str:
    """``{{ value_json.a.b }}`` against a JSON state, as Jinja prints it."""
    m = TEMPLATE.match(template)
    assert m, f"not a plain value_json path: {template}"
    value: Any = state
    for key in m.group(1).split(".")[1:]:
        value = value[key]
    return str(value)  # Jinja prints Python values: None, True, 3.5


def test_discovery_configs_and_states_arrive_as_home_assistant_expects(
        broker: LocalBroker, tmp_path: Path) -> None:
    # Occupied until local midnight (Saturday, issue 36): the comfort KPIs count something.
    panel = mqtt_panel(tmp_path / "panel.yaml", broker,
                       extra={"occupancy": {"sat": ["20:00-24:00"]}})
    state_dir = tmp_path / "state"
    sub = Subscriber(broker, "homeassistant/#", "dsfd/#", out=tmp_path / "sub.txt").start()
    done = subprocess.run(dsfd_command(*run_args(panel, state_dir, start=START, cycles=CYCLES,
                                                 speed=240.0)),
                          cwd=ROOT, capture_output=True, text=True, timeout=150, check=False)
    assert done.returncode == 0, done.stderr
    got = sub.wait_for(lambda ms: any(m.topic == f"{BASE}/availability" and m.payload ==
                                      "offline" for m in ms))
    sub.stop()
    db = state_dir / "timeseries.sqlite"

    states = [m.json() for m in got if m.topic == f"{BASE}/state"]
    stored = query(db, "SELECT cycle, phi_deg, afr, or_pct, method FROM decisions "
                       "ORDER BY cycle")
    assert [s["cycle"] for s in states] == [c for c, *_ in stored] == list(range(1, CYCLES + 1))
    for s, (_, phi, afr, or_pct, method) in zip(states, stored, strict=True):
        assert s["command"]["louver_deg"] == phi and s["command"]["regime"] == afr
        assert s["command"]["damper_pct"] == or_pct and s["set_by"] == method
        assert s["hold"] is False and s["hold_source"] is None and s["hold_until_utc"] is None
        assert s["objective_mode"] == "auto" and s["objective_set_by"] == "panel file"
    x1 = dict(query(db, "SELECT cycle, value FROM samples WHERE signal = 'x1_c'"))
    assert all(s["measured"]["x1_c"] == x1[s["cycle"]] for s in states)
    # The model's view of each cycle (table model) is what the state says.
    model = {c: (x6, q) for c, x6, q in query(db, "SELECT cycle, est_x6_c, q_cv_rd_w "
                                                  "FROM model")}
    assert all((s["estimate"]["x6_c"], s["heat_w"]["q_cv_rd"]) == model[s["cycle"]]
               for s in states)
    assert all(isinstance(s["heat_w"]["q_cv_rd"], float) for s in states[1:])  # after cycle 1

    # The occupancy and the comfort quantities of each cycle are its comfort row.
    comfort = {r[0]: r[1:] for r in query(db, "SELECT cycle, occupied, occupancy_source, dgp "
                                              "FROM comfort")}
    for s in states:
        occupied, source, dgp = comfort[s["cycle"]]
        assert (s["occupancy"]["occupied"], s["occupancy"]["source"]) == (bool(occupied),
                                                                          source)
        assert s["comfort"]["dgp"] == dgp and s["occupancy"]["override"] is None

    (kpi,) = [m.json() for m in got if m.topic == f"{BASE}/kpi"]
    configs = {m.topic: m.json() for m in got if m.topic.startswith("homeassistant/")}
    check_discovery(configs, states, got, kpi)
    check_comfort_kpis(kpi, db)

    day_cycles = query(db, "SELECT COUNT(*) FROM decisions WHERE time_s < ?",
                       1641049200.0)[0][0]  # 2022-01-02 00:00 local (UTC+9)
    assert kpi["day"] == "2022-01-01" and kpi["cycles"] == day_cycles == 5
    # The day's heat as dsfd report reckons it (its own code, from the whole history).
    (config,), = query(db, "SELECT config_json FROM runs")
    (day,) = [d for d in compute_kpis(read_history(state_dir), json.loads(config)).days
              if d.day == "2022-01-01"]
    assert kpi["heat_kwh"] == pytest.approx(day.heat_model_kwh, rel=1e-9)
    assert kpi["heat_hours"] == pytest.approx(day.heat_model_hours)
    assert all(v is not None for v in kpi["heat_kwh"].values()) and kpi["heat_hours"] > 0
    availability = [m.payload for m in got if m.topic == f"{BASE}/availability"]
    assert availability == ["online", "offline"]

    # Retained for whoever subscribes later (Home Assistant after a restart, dsfd fleet).
    late = subprocess.run(
        ["mosquitto_sub", "-p", str(broker.port), "-u", broker.username, "-P",
         broker.password, "-t", f"{BASE}/#", "-t", "homeassistant/#", "--retained-only",
         "-W", "2", "-F", "%t"], capture_output=True, text=True, timeout=30, check=False)
    retained = set(late.stdout.split())
    assert {f"{BASE}/state", f"{BASE}/availability", f"{BASE}/kpi"} <= retained
    assert set(configs) <= retained


def check_comfort_kpis(kpi: dict[str, Any], db: Path) -> None:
    """The day's comfort figures against the stored rows, counted here in SQL: the five
    cycles of 2022-01-01 fall in the Saturday 20:00-24:00 schedule, each a 60 s step."""
    day_end = 1641049200.0  # 2022-01-02 00:00 local (UTC+9)
    (occupied, source), = query(db, "SELECT SUM(occupied), GROUP_CONCAT(DISTINCT "
                                    "occupancy_source) FROM comfort WHERE time_s < ?", day_end)
    assert (occupied, source) == (5, "schedule")
    c = kpi["comfort"]
    assert c["occupied_min"] == 5.0
    # at night no sun reaches the room, and the glare probability is its floor 0.184
    assert c["occupied_direct_sun_min"] == 0.0
    assert c["dgp_p95"] == pytest.approx(0.184, abs=1e-3) and c["dgp_above_limit_pct"] == 0.0
    (cold,), = query(db, "SELECT COUNT(*) FROM comfort WHERE time_s < ? AND occupied AND "
                         "supply_air_c < supply_air_min_c", day_end)
    (asym,), = query(db, "SELECT COUNT(*) FROM comfort WHERE time_s < ? AND occupied AND "
                         "ABS(asymmetry_k) > asymmetry_max_k", day_end)
    assert c["supply_air_below_limit_min"] == float(cold)
    assert c["asymmetry_beyond_limit_min"] == float(asym)
    assert c["comfort_unknown_min"] == float(query(
        db, "SELECT COUNT(*) FROM comfort WHERE time_s < ? AND dgp IS NULL", day_end)[0][0])


def check_discovery(configs: dict[str, dict[str, Any]], states: list[dict[str, Any]],
                    got: list[Message], kpi: dict[str, Any]) -> None:
    components: Counter[str] = Counter()
    devices = []
    # the retained open findings per kind (issue 38): a clean run has none, so all OFF
    findings = {m.topic: m.json() for m in got if m.topic.startswith(f"{BASE}/finding/")}
    assert {f["state"] for f in findings.values()} == {"OFF"}
    for topic, cfg in configs.items():
        m = TOPIC.match(topic)
        assert m, topic
        component = m.group("component")
        components[component] += 1
        assert REQUIRED[component] <= set(cfg), (topic, REQUIRED[component] - set(cfg))
        assert cfg["unique_id"] == m.group("object_id")  # documented best practice
        assert cfg["availability_topic"] == f"{BASE}/availability"
        device = cfg["device"]
        assert isinstance(device["identifiers"], list) and device["identifiers"]
        assert device["name"] and device["sw_version"] and cfg["origin"]["name"]
        devices.append((tuple(device["identifiers"]), device["name"]))
        if "command_topic" in cfg:
            assert cfg["command_topic"].startswith(f"{BASE}/cmd/")
        rendered: list[str] = []
        if "state_topic" in cfg:
            assert cfg["state_topic"] in (f"{BASE}/state", f"{BASE}/kpi", *findings)
            sources = (states if cfg["state_topic"] == f"{BASE}/state" else
                       [kpi] if cfg["state_topic"] == f"{BASE}/kpi" else
                       [findings[cfg["state_topic"]]])
            rendered = [render(cfg["value_template"], s) for s in sources]
        if component == "sensor" and "device_class" in cfg:
            assert cfg["unit_of_measurement"] in UNITS[cfg["device_class"]], topic
            assert cfg["state_class"] in STATE_CLASSES
            for text in rendered:
                assert text == "None" or float(text) == float(text)  # a number or unknown
        elif component == "sensor" and "unit_of_measurement" in cfg:  # no device class
            assert cfg["unit_of_measurement"] == "%" and cfg["state_class"] in STATE_CLASSES
            assert all(text == "None" or 0.0 <= float(text) <= 100.0 for text in rendered)
        elif component == "binary_sensor":
            assert cfg["device_class"] in {"problem", "occupancy"}
            assert set(rendered) <= {cfg["payload_on"], cfg["payload_off"]}
        elif component == "select":
            assert all(isinstance(o, str) for o in cfg["options"])
            assert set(rendered) <= set(cfg["options"])
        elif component == "number":
            lo, hi, step = cfg["min"], cfg["max"], cfg["step"]
            assert lo < hi and step > 0 and cfg["mode"] in {"auto", "box", "slider"}
            for text in rendered:
                v = float(text)
                assert lo <= v <= hi and abs((v - lo) / step - round((v - lo) / step)) < 1e-9
        elif component == "button":
            assert cfg["payload_press"]
    assert len(set(cfg["unique_id"] for cfg in configs.values())) == len(configs)
    assert len(set(devices)) == 1  # one device per panel
    assert components["binary_sensor"] == 2 + len(FINDING_KINDS) == 2 + len(findings)
    assert components["select"] == 2
    assert components["number"] == 2 and components["button"] == 1
    # x1..x5, the cavity speed and the heat terms have sensors with their device classes.
    classes = {cfg["value_template"]: cfg.get("device_class") for cfg in configs.values()
               if "value_template" in cfg}
    for n in range(1, 6):
        assert classes[f"{{{{ value_json.measured.x{n}_c }}}}"] == "temperature"
    assert classes["{{ value_json.measured.v_cav_ms }}"] == "speed"
    assert sum(1 for c in classes.values() if c == "power") == 4
    # the occupancy and the day's comfort figures (issue 36)
    assert classes["{{ value_json.occupancy.occupied }}"] == "occupancy"
    for key in ("occupied_min", "occupied_direct_sun_min", "supply_air_below_limit_min",
                "asymmetry_beyond_limit_min"):
        assert classes[f"{{{{ value_json.comfort.{key} }}}}"] == "duration"
    assert classes["{{ value_json.comfort.dgp_p95 }}"] is None
    # The numeric sensors of x1..x5 read numbers in every state (the simulated sensors work).
    assert all(isinstance(s["measured"][f"x{n}_c"], float) for s in states for n in range(1, 6))
