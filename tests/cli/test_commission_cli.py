"""``dsfd commission`` failure paths: each exits 2, names what to fix, opens no device and
writes no record."""

from __future__ import annotations

import json

import yaml

from dsfd.cli import main
from tests.daemon.harness import UntouchedDevice, write_panel


def test_bad_options_and_configuration_exit_2_naming_the_fix(tmp_path, capsys) -> None:
    device = UntouchedDevice()
    panel = write_panel(tmp_path / "panel.yaml", tcp_port=device.port)
    state = tmp_path / "state"
    base = ["commission", "--config", str(panel), "--state-dir", str(state)]
    assert main([*base, "--stroke"]) == 2
    assert "--yes-move-actuators" in capsys.readouterr().err
    assert main([*base, "--reads", "0"]) == 2
    assert "--reads must be >= 1" in capsys.readouterr().err
    assert main([*base, "--at", "yesterday"]) == 2
    assert "--at 'yesterday'" in capsys.readouterr().err
    doc = yaml.safe_load(panel.read_text())
    doc["devices"]["entries"][0]["actuators"][0]["feedback"] = {"address": 3}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(doc))
    assert main(["commission", "--config", str(bad), "--state-dir", str(state)]) == 2
    assert "devices.entries[0].actuators[0].feedback.address: 3" in capsys.readouterr().err
    none = write_panel(tmp_path / "none.yaml", devices=False)
    assert main(["commission", "--config", str(none), "--state-dir", str(state)]) == 2
    assert "no devices: section" in capsys.readouterr().err
    assert not device.contacted()
    assert not state.exists()


def test_dead_devices_are_findings_and_the_record_goes_to_out(tmp_path, capsys) -> None:
    from dsfd.integrations.mqtt.broker import free_port

    panel = write_panel(tmp_path / "panel.yaml", tcp_port=free_port(),  # nothing listens
                        station_port=str(tmp_path / "no-such-tty"))
    out, state = tmp_path / "out", tmp_path / "state"
    assert main(["commission", "--config", str(panel), "--state-dir", str(state), "--out",
                 str(out), "--reads", "1", "--interval", "0"]) == 1
    printed = capsys.readouterr().out
    assert "facade-io: disconnected" in printed and "weather: disconnected" in printed
    (record,) = out.glob("commission-*.json")
    doc = json.loads(record.read_text())
    assert doc["verdict"] == "findings"
    assert {f["check"] for f in doc["findings"]} == {"quality"}
    assert {r["quality"] for r in doc["signals"]["rows"]} == {"disconnected"}
    assert len(list(out.glob("commission-*.html"))) == 1 and not state.exists()
