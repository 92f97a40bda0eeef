"""The devices: section of a panel file: loading, derived bounds, errors that name key paths."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest
import yaml

from dsfd.config import ConfigError, load_panel
from dsfd.config.devices import STATION_SIGNALS, Devices
from dsfd.config.loader import build

PANEL = Path(__file__).resolve().parents[2] / "config" / "panels" / "suwon-south.yaml"

DEVICES_YAML = """
devices:
  read_budget_s: 15
  write_budget_s: 10
  entries:
    - name: facade-io              # thermocouple + actuator module on the LAN
      kind: modbus_tcp
      tcp: {host: 192.168.10.20, port: 502}
      device_id: 1
      timeout_s: 1.0
      retries: 1
      reconnect_backoff_min_s: 1
      reconnect_backoff_max_s: 60
      breaker_failures: 2
      breaker_cycles: 5
      sensors:
        - {signal: x1_c, address: 0, data_type: float32}
        - {signal: x2_c, address: 2, data_type: float32}
        - {signal: x3_c, address: 4, data_type: float32, word_order: little}
        - {signal: x4_c, address: 6, data_type: int16, scale: 0.1, nan_value: 0x7FFF}
        - {signal: x5_c, address: 7, data_type: int16, scale: 0.1, nan_value: 0x7FFF}
        - {signal: t_room_c, address: 8, data_type: int16, scale: 0.1}
      actuators:
        - {signal: phi_deg, address: 100, data_type: int16, scale: 0.1}
        - {signal: afr, address: 101, data_type: uint16}
        - {signal: or_pct, address: 102, data_type: uint16, scale: 0.1}
    - name: cavity-anemometer      # RS-485 slave 7
      kind: modbus_rtu
      serial: {port: /dev/ttyUSB0, baudrate: 9600, parity: E, stopbits: 1}
      device_id: 7
      timeout_s: 0.5
      retries: 1
      sensors:
        - {signal: v_cav_ms, address: 0, table: holding, data_type: uint16, scale: 0.01}
    - name: weather-station
      kind: serial_station
      serial: {port: /dev/ttyUSB1, baudrate: 9600}
      timeout_s: 1.5
"""


def panel_data() -> dict[str, Any]:
    data = yaml.safe_load(PANEL.read_text(encoding="utf-8"))
    data.update(yaml.safe_load(DEVICES_YAML))
    return data


def devices_data() -> dict[str, Any]:
    return copy.deepcopy(yaml.safe_load(DEVICES_YAML)["devices"])


def issues_of(data: dict[str, Any]) -> dict[str, str]:
    with pytest.raises(ConfigError) as err:
        build(Devices, data, prefix="devices")
    return {i.path: i.message for i in err.value.issues}


def test_example_loads_through_the_panel_file(tmp_path: Path) -> None:
    path = tmp_path / "panel.yaml"
    path.write_text(yaml.safe_dump(panel_data()), encoding="utf-8")
    panel = load_panel(path)
    assert panel.devices is not None
    io, anemometer, station = panel.devices.entries
    assert io.tcp is not None and io.tcp.host == "192.168.10.20"
    assert io.sensors[3].nan_value == 0x7FFF
    assert anemometer.serial is not None and anemometer.serial.parity == "E"
    assert station.signal_names() == STATION_SIGNALS
    # 6 sensors in one contiguous block: T·(1 + (R+1)·1) = 1·(1 + 2) = 3 s
    assert io.worst_case_read_s() == pytest.approx(3.0)
    # one write block (3 contiguous registers) + one read-back block: 1·(1 + 2·2) = 5 s
    assert io.worst_case_write_s() == pytest.approx(5.0)
    assert anemometer.worst_case_read_s() == pytest.approx(0.5 * 3)
    assert station.worst_case_read_s() == pytest.approx(3.0)
    assert io.link_key() == "tcp://192.168.10.20:502"


def test_panels_without_devices_still_load() -> None:
    # The 400 mm variant has no devices: section (a simulation-only panel).
    other = PANEL.with_name("suwon-south-400-white.yaml")
    assert "devices:" not in other.read_text()
    assert load_panel(other).devices is None
    assert load_panel(PANEL).devices is not None


@pytest.mark.parametrize(("edit", "path", "message"), [
    (lambda d: d["entries"][0]["sensors"][3].update(adress=1),
     "devices.entries[0].sensors[3].adress", "did you mean 'address'"),
    (lambda d: d["entries"][0]["sensors"][3].update(address="six"),
     "devices.entries[0].sensors[3].address", "expected an integer"),
    (lambda d: d["entries"][0]["sensors"][3].update(address=70000),
     "devices.entries[0].sensors[3].address", "<= 65535"),
    (lambda d: d["entries"][0]["sensors"][0].update(address=65535),
     "devices.entries[0].sensors[0].address", "2 registers"),
    (lambda d: d["entries"][0]["sensors"][1].update(signal="x2_f"),
     "devices.entries[0].sensors[1].signal", "not a sensor signal"),
    (lambda d: d["entries"][0]["sensors"][1].update(signal="phi_deg"),
     "devices.entries[0].sensors[1].signal", "not a sensor signal"),
    (lambda d: d["entries"][0]["sensors"][1].update(data_type="float64"),
     "devices.entries[0].sensors[1].data_type", "must be one of"),
    (lambda d: d["entries"][0]["sensors"][1].update(scale=0),
     "devices.entries[0].sensors[1].scale", "zero"),
    (lambda d: d["entries"][0]["sensors"][3].update(nan_value=0x10000),
     "devices.entries[0].sensors[3].nan_value", "16 bits"),
    (lambda d: d["entries"][0]["actuators"][0].update(table="input"),
     "devices.entries[0].actuators[0].table", "must be one of 'holding'"),
    (lambda d: d["entries"][0]["actuators"][2].update(signal="afr"),
     "devices.entries[0].actuators[2].signal", "already mapped"),
    (lambda d: d["entries"][0]["sensors"][2].update(address=3),
     "devices.entries[0].sensors[2].address", "overlap"),
    (lambda d: d["entries"][0]["actuators"][1].update(address=100),
     "devices.entries[0].actuators[1].address", "overlap"),
    (lambda d: d["entries"][0].pop("tcp"), "devices.entries[0].tcp", "required"),
    (lambda d: d["entries"][0].update(kind="modbus_udp"), "devices.entries[0].kind",
     "must be one of"),
    (lambda d: d["entries"][1]["serial"].update(bytesize=9),
     "devices.entries[1].serial.bytesize", "must be one of"),
    (lambda d: d["entries"][1].update(reconnect_backoff_min_s=100),
     "devices.entries[1].reconnect_backoff_min_s", "above"),
    (lambda d: d["entries"][2].update(sensors=[{"signal": "t_out_c", "address": 0}]),
     "devices.entries[2].sensors", "fixed fields"),
    (lambda d: d["entries"][1].update(name="facade-io"), "devices.entries[1].name",
     "duplicate"),
    (lambda d: d["entries"][1]["sensors"].append({"signal": "t_out_c", "address": 1,
                                                  "table": "holding", "data_type": "int16"}),
     "devices.entries[2].kind", "already delivered by"),
    (lambda d: d["entries"][1].update(actuators=[{"signal": "phi_deg", "address": 9}]),
     "devices.entries[1].actuators[0].signal", "already delivered by"),
    (lambda d: d.update(read_budget_s=5), "devices.read_budget_s", "exceeds the budget"),
    (lambda d: d["entries"][0].update(retries=4), "devices.write_budget_s",
     "exceeds the budget"),
    (lambda d: d.update(entries=[]), "devices.entries", "at least one"),
    # issue 36: a coil or discrete input holds only a 0/1 signal (occupied)
    (lambda d: d["entries"][0]["sensors"][1].update(table="coil"),
     "devices.entries[0].sensors[1].table", "only a 0/1 signal (occupied)"),
    (lambda d: d["entries"][0]["sensors"].append({"signal": "occupied", "address": 3,
                                                  "table": "discrete_input",
                                                  "nan_value": 0}),
     "devices.entries[0].sensors[6].nan_value", "no 'no value' code"),
    (lambda d: d["entries"][0].update(override_input={"table": "coil", "address": 4}) or
     d["entries"][0]["sensors"].append({"signal": "occupied", "address": 4, "table": "coil"}),
     "devices.entries[0].override_input.address", "coil 4 is already sensors[6]"),
])
def test_errors_name_the_key_path(edit: Any, path: str, message: str) -> None:
    data = devices_data()
    edit(data)
    issues = issues_of(data)
    assert path in issues, issues
    assert message in issues[path]


def test_devices_sharing_a_serial_line_must_agree() -> None:
    data = devices_data()
    second = copy.deepcopy(data["entries"][1])
    second.update(name="second-slave", device_id=7, timeout_s=0.4)
    second["serial"]["baudrate"] = 19200
    second["sensors"] = [{"signal": "x5_c", "address": 0}]
    data["entries"][0]["sensors"].pop(4)
    data["entries"].append(second)
    issues = issues_of(data)
    assert "devices.entries[3].serial" in issues
    assert "devices.entries[3].timeout_s" in issues
    assert "same link and id" in issues["devices.entries[3].device_id"]
    second_is_station = devices_data()
    second_is_station["entries"][2]["serial"]["port"] = "/dev/ttyUSB0"
    assert "shares its port" in issues_of(second_is_station)["devices.entries[2].kind"]


def test_all_problems_are_reported_at_once() -> None:
    data = devices_data()
    data["entries"][0]["sensors"][0]["address"] = -1
    data["entries"][1]["timeout_s"] = 0
    data["entries"][2]["serial"]["parity"] = "X"
    assert set(issues_of(data)) == {"devices.entries[0].sensors[0].address",
                                    "devices.entries[1].timeout_s",
                                    "devices.entries[2].serial.parity"}
