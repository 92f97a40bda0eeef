"""Failure paths of the commands added with issues 20-22: each exits with its documented
status, names what the user must fix (the option, the file, the key) and changes nothing."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from dsfd.cli import main
from dsfd.integrations.mqtt.broker import free_port
from dsfd.storage.timeseries import Store
from tests.daemon.harness import ROOT, query, write_panel


def _state_with_a_run(state: Path, *, config_path: str | None) -> Path:
    store = Store.open(state)
    store.begin_run(panel="suwon-south", mode="hardware", version="test",
                    config_path=config_path)
    store.close()
    return state / "timeseries.sqlite"


# --------------------------------------------------------------------------- dsfd fleet
@pytest.mark.parametrize("args, named", [
    (["--wait", "-1"], "--wait -1.0: must be zero or more seconds"),
    (["--password-file", "pw"], "--password-file needs --username"),
])
def test_fleet_refuses_bad_options_before_connecting(args, named, capsys):
    assert main(["fleet", "--broker", f"127.0.0.1:{free_port()}", *args]) == 2
    assert named in capsys.readouterr().err


def test_fleet_names_a_password_file_it_cannot_read(tmp_path, capsys):
    empty = tmp_path / "pw"
    empty.write_text("")
    for path, why in ((empty, "the file is empty"), (tmp_path / "missing", "No such file")):
        assert main(["fleet", "--broker", "127.0.0.1", "--username", "ops",
                     "--password-file", str(path)]) == 2
        err = capsys.readouterr().err
        assert f"--password-file {path}" in err and why in err


def test_fleet_without_a_broker_listening_exits_1_naming_the_address(capsys):
    address = f"127.0.0.1:{free_port()}"  # nothing listens there
    assert main(["fleet", "--broker", address, "--wait", "0"]) == 1
    err = capsys.readouterr().err
    assert f"cannot connect to the MQTT broker {address}" in err


# --------------------------------------------------------------------------- dsfd bench
@pytest.mark.parametrize("option", ["--cycles", "--backlog", "--days"])
def test_bench_counts_must_be_positive(option, capsys):
    assert main(["bench", "mqtt", option, "0"]) == 2
    assert f"dsfd bench: {option} 0" in capsys.readouterr().err


# --------------------------------------------------------------------------- report, export
def test_report_and_export_name_the_option_or_file_they_cannot_use(tmp_path, capsys):
    state = tmp_path / "state"
    _state_with_a_run(state, config_path=None)
    out = tmp_path / "r.html"
    assert main(["report", "--state-dir", str(state), "--out", str(out), "--dpi", "10"]) == 2
    assert "--dpi 10: choose 30..400" in capsys.readouterr().err
    for command in ("report", "export"):
        assert main([command, "--state-dir", str(state), "--out", str(out),
                     "--since", "yesterday"]) == 2
        assert f"dsfd {command}: --since/--until" in capsys.readouterr().err
        assert main([command, "--config", str(tmp_path / "missing.yaml"),
                     "--out", str(out)]) == 2
        assert "missing.yaml" in capsys.readouterr().err
    assert not out.exists()


# --------------------------------------------------------------------------- operator
def test_an_operator_command_names_the_panel_file_it_cannot_read(tmp_path, capsys):
    missing = tmp_path / "missing.yaml"
    assert main(["resume", "--config", str(missing)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dsfd resume: ") and str(missing) in err and "No such file" in err


def test_without_config_the_daemon_s_own_panel_file_must_be_readable(tmp_path, capsys):
    unknown = tmp_path / "unknown"
    _state_with_a_run(unknown, config_path=None)
    assert main(["resume", "--state-dir", str(unknown)]) == 2
    assert "the panel is not known: give --config PANEL" in capsys.readouterr().err
    gone = tmp_path / "gone"
    _state_with_a_run(gone, config_path=str(tmp_path / "moved.yaml"))
    assert main(["resume", "--state-dir", str(gone)]) == 2
    err = capsys.readouterr().err
    assert f"the daemon's panel file {tmp_path / 'moved.yaml'} cannot be read" in err
    assert "give --config PANEL" in err
    for state in (unknown, gone):
        assert query(state / "timeseries.sqlite", "SELECT COUNT(*) FROM commands") == [(0,)]


def test_a_command_no_cycle_answers_stays_pending_and_exits_1(tmp_path):
    panel = write_panel(tmp_path / "panel.yaml", devices=False)
    state = tmp_path / "state"
    db = _state_with_a_run(state, config_path=str(panel))
    # A process that holds the lock like a daemon but never cycles (a hung daemon).
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time\nfrom pathlib import Path\n"
         "from dsfd.storage.lock import StateLock\nStateLock.acquire(Path(sys.argv[1]))\n"
         "print('locked', flush=True)\ntime.sleep(120)\n", str(state)],
        cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "locked"
        done = subprocess.run([sys.executable, "-m", "dsfd", "resume", "--config", str(panel),
                               "--state-dir", str(state), "--wait", "0.5"], cwd=ROOT,
                              capture_output=True, text=True, timeout=60, check=False)
    finally:
        holder.kill()
        holder.wait()
    assert done.returncode == 1, done.stderr
    assert "still pending after 0.5 s: is the daemon cycling? (dsfd status)" in done.stderr
    assert query(db, "SELECT kind, status FROM commands") == [("resume", "pending")]
