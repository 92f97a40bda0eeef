"""The ``bacnet:`` section: off by default, key-path errors, a bind address that is not this
host's or a port in use named before anything starts, and ``dsfd run`` refusing to start
without bacpypes3 (exit 2, naming the extra, before any device is touched)."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest
import yaml

from dsfd.config import ConfigError, panel_from_mapping
from tests.conftest import PANELS
from tests.daemon.harness import ROOT, write_panel


def _panel(bacnet: object) -> dict:
    doc = yaml.safe_load((PANELS / "suwon-south.yaml").read_text())
    doc["bacnet"] = bacnet
    return doc


def _issues(bacnet: object) -> dict[str, str]:
    with pytest.raises(ConfigError) as exc:
        panel_from_mapping(_panel(bacnet), source="test.yaml")
    return {issue.path: str(issue) for issue in exc.value.issues}


def test_off_by_default_and_read_only_when_on():
    doc = yaml.safe_load((PANELS / "suwon-south.yaml").read_text())
    assert "bacnet" not in doc and panel_from_mapping(doc).bacnet is None
    bn = panel_from_mapping(_panel({"device_instance": 7, "address": "192.0.2.10/24"})).bacnet
    assert bn is not None and bn.writable is False and bn.hold_until_relinquished is False
    assert bn.port == 47808 and bn.foreign_device is None
    assert bn.bind_address() == "192.0.2.10/24:47808"
    assert bn.device_name_for("suwon-south") == "dsfd-suwon-south"


def test_errors_name_the_key_path():
    issues = _issues({"device_instance": 4194303, "address": "192.0.2.10", "port": 0,
                      "writeable": True, "foreign_device": {"bbmd": "x"}})
    assert "4194303" in issues["bacnet.device_instance"]
    assert "bacnet.port" in issues
    assert "unknown key" in issues["bacnet.writeable"]  # a misspelt writable
    # Cross-field checks of the section run once its keys are right.
    assert "not-an-ip/99" in _issues({"device_instance": 1,
                                      "address": "not-an-ip/99"})["bacnet.address"]
    assert "one address of this host" in _issues({"device_instance": 1,
                                                  "address": "0.0.0.0"})["bacnet.address"]
    for bbmd, why in (("198.51.100.7", "UDP port"), ("198.51.100.7:99999", "99999"),
                      ("bbmd.lan:47808", "not an IPv4 address")):
        issues = _issues({"device_instance": 1, "address": "127.0.0.1",
                          "foreign_device": {"bbmd": bbmd}})
        assert why in issues["bacnet.foreign_device.bbmd"], issues
    assert "bacnet.device_instance" in _issues({"address": "127.0.0.1"})  # required


def _run(tmp_path, bacnet: dict, code: str | None = None) -> subprocess.CompletedProcess:
    panel = write_panel(tmp_path / "p.yaml", devices=False, extra={"bacnet": bacnet})
    argv = ["run", "--config", str(panel), "--dry-run", "--plant", "sim", "--cycles", "1",
            "--state-dir", str(tmp_path / "state")]
    cmd = [sys.executable, "-m", "dsfd"] if code is None else [sys.executable, "-c", code]
    return subprocess.run([*cmd, *argv], cwd=ROOT, capture_output=True, text=True,
                          timeout=120, check=False)


def test_run_without_bacpypes3_exits_2_naming_the_extra(tmp_path):
    code = ("import sys\nsys.modules['bacpypes3'] = None  # as if bacpypes3 were not "
            "installed\nfrom dsfd.cli import main\nraise SystemExit(main(sys.argv[1:]))\n")
    done = _run(tmp_path, {"device_instance": 1, "address": "127.0.0.1", "port": 47999},
                code)
    assert done.returncode == 2, done.stderr
    assert "pip install 'dsfd[bacnet]'" in done.stderr
    assert not (tmp_path / "state").exists()


def test_an_address_of_another_host_or_a_busy_port_is_named_before_anything_starts(tmp_path):
    pytest.importorskip("bacpypes3")
    done = _run(tmp_path, {"device_instance": 1, "address": "192.0.2.10/24"})  # TEST-NET-1
    assert done.returncode == 2
    assert "bacnet.address: '192.0.2.10/24': cannot bind UDP 192.0.2.10:47808" in done.stderr
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as busy:
        busy.bind(("127.0.0.1", 0))
        port = busy.getsockname()[1]
        done = _run(tmp_path, {"device_instance": 1, "address": "127.0.0.1", "port": port})
    assert done.returncode == 2
    assert f"bacnet.port: {port}: cannot bind UDP 127.0.0.1:{port}" in done.stderr
    assert not (tmp_path / "state").exists()
