"""Where the operator commands look for a panel's state, and how status reads as text."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from dsfd.cli.operator import OperatorError, load_target
from dsfd.cli.status import render


def test_the_state_directory_follows_systemd_unless_told_otherwise(
        suwon, monkeypatch: pytest.MonkeyPatch) -> None:
    # The unit runs dsfd@NAME with --config /etc/dsfd/NAME.yaml and StateDirectory=dsfd/%i.
    monkeypatch.delenv("STATE_DIRECTORY", raising=False)
    target = argparse.Namespace(config=None, state_dir=None)
    with pytest.raises(OperatorError, match="--config PANEL or --state-dir DIR"):
        load_target(target, need_config=False)
    panel = Path("/etc/dsfd/suwon-south.yaml")
    monkeypatch.setattr("dsfd.config.load_panel", lambda path: suwon)
    state, cfg = load_target(argparse.Namespace(config=panel, state_dir=None),
                             need_config=True)
    assert (state, cfg) == (Path("/var/lib/dsfd/suwon-south"), suwon)
    monkeypatch.setenv("STATE_DIRECTORY", "/srv/a:/srv/b")
    assert load_target(argparse.Namespace(config=panel, state_dir=None),
                       need_config=True)[0] == Path("/srv/a")
    assert load_target(argparse.Namespace(config=panel, state_dir=Path("/x")),
                       need_config=True)[0] == Path("/x")


def test_status_text_says_who_holds_the_panel_and_until_when() -> None:
    info = {
        "panel": "p", "state_dir": "/var/lib/dsfd/p",
        "daemon": {"running": True, "pid": 42, "lock": "/var/lib/dsfd/p/dsfd.lock"},
        "run": {"run_id": 3, "mode": "hardware", "started_utc": "2025-01-02T06:00:00Z",
                "ended_utc": None, "end_reason": None},
        "last_cycle": {"cycle": 7, "time_utc": "2025-01-02T08:31:00Z", "age_s": 14.0,
                       "decide_ms": None, "method": "manual", "set_by": "manual hold, "
                       "changed by the wind protection", "wind_override": True,
                       "command": {"phi_deg": 90.0, "afr": 10, "or_pct": 0.0},
                       "write_status": "verified", "fallback": ""},
        "hold": {"source": "input", "expires_utc": None, "remaining_s": None,
                 "command_id": None, "requester": None},
        "flagged": [{"signal": "x3_c", "quality": "stuck", "detail": ""}],
        "calibration": {"updates_this_run": 2, "last_update_utc": "2025-01-02T08:21:00Z",
                        "age_s": 614.0, "source": "online", "at_bound": ["h_ca4"]},
        "commands": {"pending": 1, "last": None},
        "mqtt": [{"destination": "10.0.4.2:1883 dsfd/p", "connected": False, "backlog": 12,
                  "delivered": 340, "last_error": "not authorised",
                  "last_error_utc": "2025-01-02T08:20:00Z",
                  "last_delivered": {"run_id": 3, "cycle": 140,
                                     "time_utc": "2025-01-02T08:19:00Z"},
                  "updated_utc": "2025-01-02T08:30:58Z"}],
        "objective": {"mode": "auto", "command_id": 5, "now": "heating",
                      "set_by": "operator command #5 by mqtt 10.0.4.2:1883 dsfd/p/cmd/mode"},
    }
    text = "\n".join(render(info))
    assert "daemon running (PID 42)" in text
    assert "louver +90 deg, regime 10, dampers 0 % (verified); set by manual hold, changed "\
        "by the wind protection" in text
    assert "hold:        input, while the override input is set" in text
    assert "flagged:     x3_c (stuck)" in text
    assert "(10 min ago), online; 2 updates this run; at a bound: h_ca4" in text
    assert "commands:    1 pending" in text
    assert "objective:   auto (heating now); set by operator command #5 by mqtt " \
        "10.0.4.2:1883 dsfd/p/cmd/mode" in text
    assert "mqtt:        10.0.4.2:1883 dsfd/p: not connected; 12 waiting, delivered up to " \
        "cycle 140 of run 3 (2025-01-02T08:19:00Z), 340 in all" in text
    assert "last error 2025-01-02T08:20:00Z: not authorised" in text


def test_dsfd_run_finds_the_same_state_directory_and_names_the_key_without_one(
        suwon, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import dataclasses
    import shutil

    from dsfd.config import ConfigError
    from dsfd.daemon.runner import RunOptions
    from dsfd.daemon.startup import resolve_state_dir

    monkeypatch.delenv("STATE_DIRECTORY", raising=False)
    hardware = RunOptions(config_path=Path("/etc/dsfd/suwon-south.yaml"))
    with pytest.raises(ConfigError, match=r"daemon\.state_directory") as err:
        resolve_state_dir(hardware, suwon)  # nothing says where: refused before anything
    assert "StateDirectory=" in str(err.value) and "--state-dir" in str(err.value)
    sim = dataclasses.replace(hardware, plant="sim")
    temporary, is_temporary = resolve_state_dir(sim, suwon)
    try:
        assert is_temporary and temporary.is_dir() and "suwon-south" in temporary.name
    finally:
        shutil.rmtree(temporary)
    monkeypatch.setenv("STATE_DIRECTORY", "/srv/a:/srv/b")
    assert resolve_state_dir(hardware, suwon) == (Path("/srv/a"), False)
    configured = dataclasses.replace(
        suwon, daemon=dataclasses.replace(suwon.daemon, state_directory=str(tmp_path)))
    assert resolve_state_dir(hardware, configured) == (tmp_path, False)
    told = dataclasses.replace(hardware, state_dir=Path("/x"))
    assert resolve_state_dir(told, configured) == (Path("/x"), False)
