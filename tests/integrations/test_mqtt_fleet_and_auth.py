"""A wrong password or a wrong certificate is reported and control goes on; TLS works;
``dsfd fleet`` sees several daemons.

Real ``dsfd run`` processes against a real Mosquitto with a password file.
"""

from __future__ import annotations

import asyncio
import json
import shutil
import signal
import subprocess
from pathlib import Path

import pytest
from prometheus_client.parser import text_string_to_metric_families

from dsfd.integrations.mqtt.broker import LocalBroker, make_test_ca
from tests.daemon.harness import ROOT, DaemonProcess, dsfd_command, query, run_dsfd
from tests.integrations.mqtt_harness import Subscriber, mosquitto_missing, mqtt_panel, run_args

MORNING = "2022-01-01T23:30:00Z"


def test_wrong_password_is_a_clear_error_and_control_goes_on(
        broker: LocalBroker, tmp_path: Path) -> None:
    prom = tmp_path / "dsfd-test.prom"
    panel = mqtt_panel(tmp_path / "panel.yaml", broker, password="not-the-password",
                       extra={"daemon": {"metrics_file": str(prom)}})
    state = tmp_path / "state"

    async def run() -> tuple[DaemonProcess, tuple[int, str, str]]:
        daemon = await DaemonProcess(run_args(panel, state, start=MORNING, cycles=400,
                                              speed=240.0)).start()
        await daemon.wait_cycle(6)
        status = await run_dsfd("status", "--state-dir", str(state))
        await daemon.wait_cycle(daemon.cycles_logged[-1] + 2)
        daemon.signal(signal.SIGTERM)
        assert await daemon.wait_exit() == 0, daemon.stderr
        return daemon, status

    daemon, (rc, status, err) = asyncio.run(run())
    n = len(daemon.cycles_logged)
    assert n >= 8 and daemon.cycles_logged == list(range(1, n + 1))  # control went on
    db = state / "timeseries.sqlite"
    assert query(db, "SELECT COUNT(*) FROM decisions")[0][0] == n
    errors = [r for r in daemon.records if r.get("level") == "error"]
    assert len(errors) == 1, errors  # once, not once per attempt
    message = errors[0]["event"]
    assert "refused" in message and "not authorised" in message
    assert "mqtt.password_file" in message and errors[0]["broker"] == broker.address
    (connected, last_error, cycle), = query(db, "SELECT connected, last_error, cycle "
                                                "FROM mqtt_cursor")
    assert connected == 0 and "not authorised" in last_error and cycle == 0
    assert "not authorised" in broker.log()  # the broker's own account of it
    # dsfd status (while running) and the metrics file (of the last cycle) say so too.
    assert rc == 0, err
    assert f"mqtt:        {broker.address} dsfd/suwon-south: not connected; " in status
    assert "none delivered yet" in status and "not authorised" in status.split("mqtt:")[1]
    fam = {f.name: f.samples for f in text_string_to_metric_families(prom.read_text())}
    assert fam["dsfd_mqtt_connected"][0].value == 0.0
    (error,) = fam["dsfd_mqtt_error"]
    assert error.value == 1.0 and "not authorised" in error.labels["reason"]
    assert fam["dsfd_mqtt_backlog_cycles"][0].value >= 1


def test_fleet_lists_three_daemons_with_their_regimes(broker: LocalBroker,
                                                      tmp_path: Path) -> None:
    starts = {"fleet-east": MORNING, "fleet-south": "2022-01-02T04:00:00Z",
              "fleet-west": "2022-01-01T14:00:00Z"}  # morning, early afternoon, night
    panels = {pid: mqtt_panel(tmp_path / f"{pid}.yaml", broker, panel_id=pid)
              for pid in starts}
    secret = tmp_path / "ops-password"
    secret.write_text(broker.password + "\n")
    fleet = dsfd_command("fleet", "--broker", broker.address, "--username", broker.username,
                         "--password-file", str(secret), "--wait", "0.5")

    async def run() -> list[dict]:
        daemons = [await DaemonProcess(run_args(panels[pid], tmp_path / pid, start=start,
                                                cycles=400, speed=240.0)).start()
                   for pid, start in starts.items()]
        for d in daemons:
            await d.wait_cycle(3)
        listed = await asyncio.to_thread(subprocess.run, [*fleet, "--json"], cwd=ROOT,
                                         capture_output=True, text=True, timeout=60)
        # Two stop cleanly; fleet-west dies (SIGKILL): the broker publishes its last will.
        for d, sig in zip(daemons, (signal.SIGTERM, signal.SIGTERM, signal.SIGKILL),
                          strict=True):
            d.signal(sig)
        for d, rc in zip(daemons, (0, 0, -signal.SIGKILL), strict=True):
            assert await d.wait_exit() == rc, d.stderr
        assert listed.returncode == 0, listed.stderr
        return json.loads(listed.stdout)

    def check_against_the_databases(rows: list[dict]) -> None:
        assert [r["panel"] for r in rows] == sorted(starts)
        for r in rows:
            assert r["hold"] is None
            # Regime, positions and flagged sensors are those the daemon stored for the
            # cycle it reported.
            db = tmp_path / r["panel"] / "timeseries.sqlite"
            (afr, phi, or_pct, time_utc, method), = query(
                db, "SELECT afr, phi_deg, or_pct, time_utc, method FROM decisions "
                "WHERE run_id = ? AND cycle = ?", r["run"], r["cycle"])
            assert (r["regime"], r["louver_deg"], r["damper_pct"]) == (afr, phi, or_pct)
            flagged = query(db, "SELECT signal, quality FROM samples WHERE run_id = ? AND "
                            "cycle = ? AND quality != 'good' ORDER BY signal", r["run"],
                            r["cycle"])
            assert [f for f in r["faults"] if not f.startswith("safe state")] == [
                f"{s}: {q}" for s, q in flagged]
            assert r["set_by"] in (method, "wind")
            assert r["last_seen_utc"] == time_utc and r["decision_ms"] > 0

    running = asyncio.run(run())
    check_against_the_databases(running)
    assert [r["online"] for r in running] == [True, True, True]

    # Stopped: each panel's last state stays on the broker (retained) and it shows offline
    # (fleet-west by its last will); a clean stop sent the last stored cycle first.
    listed = subprocess.run([*fleet, "--json"], cwd=ROOT, capture_output=True, text=True,
                            timeout=60, check=False)
    table = subprocess.run(fleet, cwd=ROOT, capture_output=True, text=True, timeout=60,
                           check=False)
    assert listed.returncode == 0 and table.returncode == 0, listed.stderr + table.stderr
    stopped = json.loads(listed.stdout)
    check_against_the_databases(stopped)
    for r in stopped:
        last = query(tmp_path / r["panel"] / "timeseries.sqlite",
                     "SELECT MAX(cycle) FROM decisions")[0][0]
        assert r["online"] is False
        assert r["cycle"] == last if r["panel"] != "fleet-west" else r["cycle"] <= last
    print(table.stdout)
    lines = table.stdout.splitlines()
    assert lines[0].split()[:3] == ["panel", "online", "mode"] and len(lines) == 4
    for line, r in zip(lines[1:], stopped, strict=True):
        assert line.startswith(f"{r['panel']}  ") and " no " in line
        assert f"{r['regime']} {r['regime_name']}" in line


def test_fleet_reports_a_broker_it_cannot_use(broker: LocalBroker, tmp_path: Path) -> None:
    wrong = tmp_path / "wrong"
    wrong.write_text("nope\n")
    refused = subprocess.run(dsfd_command("fleet", "--broker", broker.address, "--username",
                                          broker.username, "--password-file", str(wrong)),
                             cwd=ROOT, capture_output=True, text=True, timeout=60,
                             check=False)
    assert refused.returncode == 1 and "not authorised" in refused.stderr
    empty = subprocess.run(dsfd_command("fleet", "--broker", broker.address, "--username",
                                        broker.username, "--password-file", str(wrong),
                                        "--base", "a/+"), cwd=ROOT, capture_output=True,
                           text=True, timeout=60, check=False)
    assert empty.returncode == 2 and "--base 'a/+'" in empty.stderr


def test_fleet_with_no_panel_under_its_base_exits_1_saying_so(broker: LocalBroker,
                                                              tmp_path: Path) -> None:
    password = tmp_path / "pw"
    password.write_text(broker.password + "\n")
    done = subprocess.run(dsfd_command("fleet", "--broker", broker.address, "--username",
                                       broker.username, "--password-file", str(password),
                                       "--base", "nobody-here", "--wait", "0"),
                          cwd=ROOT, capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 1 and done.stdout == ""
    assert f"no panel publishes under nobody-here/ on {broker.address}" in done.stderr


def test_tls_to_a_broker_whose_certificate_chains_to_the_configured_ca(tmp_path: Path) -> None:
    if why := mosquitto_missing() or ("" if shutil.which("openssl") else "openssl missing"):
        pytest.skip(why)
    with LocalBroker(tmp_path / "broker", tls=True) as broker:
        sub = Subscriber(broker, "dsfd/#", out=tmp_path / "sub.txt").start()
        stranger, _, _ = make_test_ca(tmp_path / "other-ca")
        runs = {}
        for name, ca in (("good", broker.ca_file), ("stranger", stranger)):
            panel = mqtt_panel(tmp_path / f"{name}.yaml", broker, mqtt={
                "port": broker.tls_port, "tls": {"ca_file": str(ca)}})
            done = subprocess.run(dsfd_command(*run_args(
                panel, tmp_path / name, start=MORNING, cycles=3, speed=240.0)), cwd=ROOT,
                capture_output=True, text=True, timeout=150, check=False)
            assert done.returncode == 0, done.stderr
            runs[name] = done.stdout
        got = sub.wait_for(lambda ms: any(m.payload == "offline" for m in ms))
        sub.stop()
    assert [m.json()["cycle"] for m in got if m.topic.endswith("/state")] == [1, 2, 3]
    assert "certificate verify failed" not in runs["good"]
    # A broker whose certificate does not chain to the configured CA is refused, loudly,
    # and control goes on.
    assert "certificate verify failed" in runs["stranger"]
    assert query(tmp_path / "stranger" / "timeseries.sqlite",
                 "SELECT COUNT(*) FROM decisions")[0][0] == 3
