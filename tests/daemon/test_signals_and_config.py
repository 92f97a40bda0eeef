"""Configuration at start and on SIGHUP, and SIGTERM, against the real ``dsfd run`` process.

* a bad file makes ``dsfd run`` exit 2 naming the key path before any device is touched;
* SIGHUP with a bad file keeps the running configuration (the errors are logged with their
  key paths); SIGHUP with a good file applies it between cycles;
* SIGTERM stops after the current cycle; the run is marked ended in the database.
"""

from __future__ import annotations

import asyncio
import signal
import subprocess
from pathlib import Path

import yaml

from tests.daemon.harness import (
    ROOT,
    DaemonProcess,
    UntouchedDevice,
    dsfd_command,
    free_port,
    query,
    write_panel,
)


def test_bad_config_exits_before_touching_any_device(tmp_path: Path) -> None:
    device = UntouchedDevice()  # stands in for the Modbus device: nothing may connect
    panel = write_panel(tmp_path / "bad.yaml", tcp_port=device.port, extra={
        "safety": {"wind_limit_ms": -3.0}, "daemon": {"cycle_period_s": 60.0,
                                                      "store_budget_sec": 5}})
    state = tmp_path / "state"
    done = subprocess.run(dsfd_command("run", "--config", str(panel), "--state-dir",
                                       str(state)), cwd=ROOT, capture_output=True,
                          text=True, timeout=60, check=False)
    connected = device.contacted()
    assert done.returncode == 2
    assert "safety.wind_limit_ms: -3.0" in done.stderr
    assert "daemon.store_budget_sec" in done.stderr and "did you mean" in done.stderr
    assert not connected
    assert not state.exists()  # nothing was opened


def test_run_against_hardware_needs_a_devices_section(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "nodev.yaml", devices=False)
    done = subprocess.run(dsfd_command("run", "--config", str(panel), "--state-dir",
                                       str(tmp_path / "s")), cwd=ROOT, capture_output=True,
                          text=True, timeout=60, check=False)
    assert done.returncode == 2
    assert "devices: None: required to run against hardware" in done.stderr


def test_simulated_start_outside_the_weather_is_a_usage_error(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    done = subprocess.run(dsfd_command("run", "--config", str(panel), "--plant", "sim",
                                       "--start", "2030-01-01T00:00:00Z"), cwd=ROOT,
                          capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 2
    assert "--start 2030-01-01T00:00:00Z is outside the weather" in done.stderr


def _signalled_run(panel: Path, state: Path) -> list[str]:
    """A dry run on the simulated plant, 60 simulated seconds every 0.25 s: slow enough to
    signal between cycles."""
    return ["run", "--config", str(panel), "--dry-run", "--plant", "sim", "--plant-fidelity",
            "lumped", "--speed", "240", "--cycles", "400", "--state-dir", str(state)]


def test_sighup_keeps_the_old_config_when_the_new_one_is_bad(tmp_path: Path) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    good = yaml.safe_load(panel.read_text())
    state = tmp_path / "state"

    def rewrite(**changes: object) -> None:
        doc = yaml.safe_load(yaml.safe_dump(good))
        for dotted, value in changes.items():
            section, key = dotted.split("__")
            doc.setdefault(section, {})[key] = value
        panel.write_text(yaml.safe_dump(doc, sort_keys=False))

    async def scenario() -> DaemonProcess:
        daemon = await DaemonProcess(_signalled_run(panel, state)).start()
        await daemon.wait_cycle(2)
        # The same switch to the baseline, but with a typo and a bad value: rejected whole.
        rewrite(control__optimiser="rule", control__horizon_step=5,
                safety__min_louver_move_interval_s=-1)
        daemon.signal(signal.SIGHUP)
        await daemon.wait_for(lambda d: bool(d.events("reload rejected: keeping")))
        rejected_at = daemon.cycles_logged[-1]
        await daemon.wait_cycle(rejected_at + 3)
        rewrite(control__optimiser="rule")
        daemon.signal(signal.SIGHUP)
        await daemon.wait_for(lambda d: bool(d.events("configuration reloaded")))
        reloaded_at = daemon.cycles_logged[-1]
        await daemon.wait_cycle(reloaded_at + 3)
        daemon.signal(signal.SIGTERM)
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    daemon = asyncio.run(scenario())
    key_paths = {r.get("key_path") for r in daemon.events("reload rejected: ")}
    assert {"control.horizon_step", "safety.min_louver_move_interval_s"} <= key_paths
    db = state / "timeseries.sqlite"
    methods = dict(query(db, "SELECT cycle, method FROM decisions"))
    (rejected,) = [r["after_cycle"] for r in daemon.events("reload rejected: keeping")]
    (reloaded,) = [r["after_cycle"] for r in daemon.events("configuration reloaded")]
    # Until the good reload the optimiser ran (the bad file's "optimiser: rule" was not
    # applied); after it, the baseline decided.
    assert rejected + 3 <= reloaded
    assert all(methods[c] == "mpc" for c in methods if c <= reloaded)
    assert all(methods[c] == "rule" for c in methods if c > reloaded)
    kinds = [k for (k,) in query(db, "SELECT kind FROM events WHERE kind LIKE 'reload%' "
                                 "ORDER BY event_id")]
    assert kinds == ["reload_rejected", "reload"]
    # SIGTERM: the run ended cleanly after the current cycle, every logged cycle is stored.
    (reason, cycles), = query(db, "SELECT end_reason, cycles FROM runs")
    assert reason == "signal"
    assert sorted(methods) == daemon.cycles_logged == list(range(1, cycles + 1))


def test_sighup_keeps_the_state_directory_mqtt_and_bacnet_until_a_restart(tmp_path: Path
                                                                          ) -> None:
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    doc = yaml.safe_load(panel.read_text())
    state, elsewhere = tmp_path / "state", tmp_path / "elsewhere"

    async def scenario() -> DaemonProcess:
        daemon = await DaemonProcess(_signalled_run(panel, state)).start()
        await daemon.wait_cycle(2)
        # A broker nothing listens on, another state directory, and the baseline.
        doc["mqtt"] = {"host": "127.0.0.1", "port": free_port()}
        doc["bacnet"] = {"device_instance": 1, "address": "127.0.0.1", "port": free_port()}
        doc["daemon"]["state_directory"] = str(elsewhere)
        doc["control"]["optimiser"] = "rule"
        panel.write_text(yaml.safe_dump(doc, sort_keys=False))
        daemon.signal(signal.SIGHUP)
        await daemon.wait_for(lambda d: bool(d.events("configuration reloaded")))
        await daemon.wait_cycle(daemon.cycles_logged[-1] + 3)
        daemon.signal(signal.SIGTERM)
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon

    daemon = asyncio.run(scenario())
    (kept,) = daemon.events("reload: ")
    assert kept["event"] == ("reload: daemon.state_directory, mqtt, bacnet changed; restart "
                             "the service to apply")
    (reloaded,) = [r["after_cycle"] for r in daemon.events("configuration reloaded")]
    methods = dict(query(state / "timeseries.sqlite", "SELECT cycle, method FROM decisions"))
    assert all(methods[c] == "rule" for c in methods if c > reloaded)  # the rest applied
    assert not elsewhere.exists()
    assert not [r for r in daemon.records if ("mqtt" in r.get("event", "").lower()
                                              or "bacnet" in r.get("event", "").lower())
                and r is not kept]  # no publisher, no BACnet device started by the reload
