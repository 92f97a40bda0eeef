"""The ``mqtt:`` section: defaults, key-path errors, files found where systemd puts them, and
``dsfd run`` refusing to start without paho-mqtt (exit 2, before any device is touched)."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest
import yaml

from dsfd.config import ConfigError, panel_from_mapping
from dsfd.integrations.mqtt.link import Backoff, parse_broker, resolve_link
from tests.conftest import PANELS
from tests.daemon.harness import ROOT, write_panel


def _panel(mqtt: object) -> dict:
    doc = yaml.safe_load((PANELS / "suwon-south.yaml").read_text())
    doc["mqtt"] = mqtt
    return doc


def _issues(mqtt: object) -> dict[str, str]:
    with pytest.raises(ConfigError) as exc:
        panel_from_mapping(_panel(mqtt), source="test.yaml")
    return {issue.path: str(issue) for issue in exc.value.issues}


def test_defaults_follow_the_panel_id():
    cfg = panel_from_mapping(_panel({"host": "broker.lan"}))
    mq = cfg.mqtt
    assert mq is not None and mq.broker_port() == 1883
    assert mq.client_id_for(cfg.panel.id) == "dsfd-suwon-south"
    assert mq.base_topic_for(cfg.panel.id) == "dsfd/suwon-south"
    assert mq.discovery_prefix == "homeassistant"
    tls = panel_from_mapping(_panel({"host": "b", "tls": {}, "discovery_prefix": None})).mqtt
    assert tls is not None and tls.broker_port() == 8883 and tls.discovery_prefix is None
    assert panel_from_mapping(_panel(None)).mqtt is None


def test_errors_name_the_key_path_and_never_echo_a_password():
    issues = _issues({"host": "b", "port": 70000, "password": "hunter2", "base_topic": "a/#",
                      "discovery_prefix": "$SYS/x", "client_id": "has space",
                      "tls": {"cert_file": "c.pem"}, "keepalive_s": 1, "qos": 2})
    assert "70000" in issues["mqtt.port"] and "<= 65535" in issues["mqtt.port"]
    assert "unknown key" in issues["mqtt.qos"]
    assert "mqtt.keepalive_s" in issues
    assert all("hunter2" not in text for text in issues.values())
    # Cross-field checks run once the types are right.
    issues = _issues({"host": "b", "password": "hunter2", "base_topic": "a/#",
                      "discovery_prefix": "$SYS/x", "client_id": "has space",
                      "password_file": "pw", "reconnect_min_s": 30, "reconnect_max_s": 10})
    assert "password_file" in issues["mqtt.password"]
    assert all("hunter2" not in text for text in issues.values())
    assert "wildcards" in issues["mqtt.base_topic"]
    assert "'$'" in issues["mqtt.discovery_prefix"]
    assert "mqtt.client_id" in issues
    assert "needs a username" in issues["mqtt.password_file"]
    assert "reconnect_max_s" in issues["mqtt.reconnect_min_s"]
    assert "key_file" in _issues({"host": "b", "tls": {"cert_file": "c.pem"}})["mqtt.tls.key_file"]
    assert "mqtt.host" in _issues({"port": 1883})


def test_password_file_is_found_in_the_credentials_directory(tmp_path, monkeypatch):
    creds = tmp_path / "creds"
    creds.mkdir()
    (creds / "mqtt-password").write_text("from-systemd\n")
    (tmp_path / "mqtt-password").write_text("next-to-the-panel\n")
    cfg = panel_from_mapping(_panel({"host": "b", "username": "u",
                                     "password_file": "mqtt-password"}))
    panel_file = tmp_path / "panel.yaml"
    monkeypatch.delenv("CREDENTIALS_DIRECTORY", raising=False)
    assert resolve_link(cfg, config_path=panel_file).password == "next-to-the-panel"
    monkeypatch.setenv("CREDENTIALS_DIRECTORY", str(creds))
    link = resolve_link(cfg, config_path=panel_file)
    assert link.password == "from-systemd" and "from-systemd" not in repr(link)
    (creds / "mqtt-password").unlink()
    with pytest.raises(ConfigError) as exc:
        resolve_link(cfg, config_path=panel_file)
    (issue,) = exc.value.issues
    assert issue.path == "mqtt.password_file" and str(creds) in issue.message


def test_run_without_paho_exits_2_naming_the_extra_before_any_device(tmp_path):
    # A listening socket stands in for the Modbus device: no connection may arrive.
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    listener.setblocking(False)
    panel = write_panel(tmp_path / "p.yaml", tcp_port=listener.getsockname()[1],
                        extra={"mqtt": {"host": "127.0.0.1"}})
    state = tmp_path / "state"
    code = ("import sys\nsys.modules['paho'] = None  # as if paho-mqtt were not installed\n"
            "from dsfd.cli import main\nraise SystemExit(main(sys.argv[1:]))\n")
    try:
        done = subprocess.run([sys.executable, "-c", code, "run", "--config", str(panel),
                               "--state-dir", str(state)], cwd=ROOT, capture_output=True,
                              text=True, timeout=60, check=False)
        with pytest.raises(BlockingIOError):
            listener.accept()
    finally:
        listener.close()
    assert done.returncode == 2
    assert "pip install 'dsfd[mqtt]'" in done.stderr
    assert not state.exists()


def test_backoff_doubles_with_jitter_up_to_the_cap():
    draws: list[tuple[float, float]] = []

    def lowest(lo: float, hi: float) -> float:
        draws.append((lo, hi))
        return lo

    b = Backoff(1.0, 10.0, uniform=lowest)
    delays = [b.next_delay() for _ in range(6)]
    assert [hi for _, hi in draws] == [1.0, 2.0, 4.0, 8.0, 10.0, 10.0]
    assert delays == [0.5, 1.0, 2.0, 4.0, 5.0, 5.0]  # the lower end of each jitter interval
    b.reset()
    assert b.next_delay() == 0.5
    real = Backoff(1.0, 10.0)
    delays = [real.next_delay() for _ in range(200)]
    assert all(0.5 <= d <= 1.0 for d in delays[:1]) and all(5.0 <= d <= 10.0 for d in delays[4:])
    assert len(set(delays[4:])) > 100  # jittered: panels do not reconnect in lockstep


def test_broker_addresses_parse():
    assert parse_broker("mqtt.lan") == ("mqtt.lan", 1883)
    assert parse_broker("10.0.0.2:8883") == ("10.0.0.2", 8883)
    assert parse_broker("[::1]:1884") == ("::1", 1884)
    for bad in ("host:http", ":1883", "host:0", "[::1"):
        with pytest.raises(ValueError):
            parse_broker(bad)


@pytest.mark.parametrize("topic, why", [
    ("", "must not be empty"), ("/dsfd/p", "must not start or end with '/'"),
    ("dsfd/p/", "must not start or end with '/'"), ("dsfd//p", "empty level"),
    ("d" * 1025, "too long"),
])
def test_topics_dsfd_cannot_publish_under_are_named_by_key(topic, why):
    issues = _issues({"host": "b", "base_topic": topic, "discovery_prefix": topic})
    assert why in issues["mqtt.base_topic"] and why in issues["mqtt.discovery_prefix"]


def test_a_blank_host_is_named():
    assert "must not be empty" in _issues({"host": "  "})["mqtt.host"]


def test_password_and_tls_files_that_cannot_be_used_are_named_by_key(tmp_path, monkeypatch):
    monkeypatch.delenv("CREDENTIALS_DIRECTORY", raising=False)
    (tmp_path / "pw").write_text("\n")  # a first line, but an empty one
    cfg = panel_from_mapping(_panel({"host": "b", "username": "u", "password_file": "pw",
                                     "tls": {"ca_file": "ca.pem"}}))
    with pytest.raises(ConfigError) as exc:
        resolve_link(cfg, config_path=tmp_path / "panel.yaml")
    issues = {issue.path: issue.message for issue in exc.value.issues}
    assert set(issues) == {"mqtt.password_file", "mqtt.tls.ca_file"}
    assert "the file is empty" in issues["mqtt.password_file"]
    assert f"{tmp_path / 'ca.pem'}: not found or not readable" in issues["mqtt.tls.ca_file"]
