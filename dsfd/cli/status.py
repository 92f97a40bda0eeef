"""``dsfd status``: what the daemon of a panel is doing now, from its state directory.

Read-only: it asks the kernel whether the state directory's lock is held (running or not,
and by which PID) and reads the database without ever writing it or taking the lock, so it
can run any time next to the service. What it shows: the run (mode, start), the last cycle
(time, decision time, method), the current command and who set it (optimiser, baseline, safe
state, a manual hold, the wind), the hold and its expiry, the signals flagged in the last
cycle, the calibration's age and the parameters sitting at a bound, the operator commands
(pending, last answer), the open findings of the diagnostics (issue 38; ``dsfd ack`` closes
one) and, with an ``mqtt:`` section, the publisher's delivery state per
broker (``mqtt_cursor``). ``--json`` prints the same as one JSON object.

Exit codes (as ``systemctl status``, LSB): 0 a daemon is running, 3 none is, 4 the state
cannot be read (permissions: docs/operating.md), 1 no database, 2 bad options.
"""

from __future__ import annotations

import argparse
import json
import sqlite3
import sys
import time
from pathlib import Path
from typing import Any

from dsfd.cli.operator import (
    EXIT_NO_ACCESS,
    EXIT_NOT_RUNNING,
    EXIT_OK,
    OperatorError,
    access_hint,
    add_target,
    load_target,
    open_database,
)
from dsfd.measured import iso_utc
from dsfd.storage.queries import first_row

_SET_BY = {"mpc": "optimiser (mpc)", "paper-sqp": "optimiser (paper-sqp)",
           "rule": "rule-based baseline", "safe": "safe state (faults)", "manual": "manual hold"}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("status", help="what the daemon of a panel is doing now",
                       description=__doc__.split("\n\n")[1].replace("\n", " "))
    add_target(p)
    p.add_argument("--json", action="store_true", help="one JSON object instead of text")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    try:
        state, cfg = load_target(args, need_config=False)
        info = gather(state, cfg)
    except OperatorError as exc:
        print(f"dsfd status: {exc}", file=sys.stderr)
        return exc.code
    if args.json:
        print(json.dumps(info, indent=1))
    else:
        print("\n".join(render(info)))
    return EXIT_OK if info["daemon"]["running"] else EXIT_NOT_RUNNING


def gather(state: Path, cfg: Any | None, *, now_s: float | None = None) -> dict[str, Any]:
    """Everything ``dsfd status`` shows, JSON-ready."""
    from dsfd.storage.lock import LOCK_NAME, lock_holder

    now = time.time() if now_s is None else now_s
    try:
        pid = lock_holder(state)
    except PermissionError as exc:
        raise OperatorError(f"{exc}: {access_hint()}", EXIT_NO_ACCESS) from None
    conn = open_database(state)
    try:
        return _gather(conn, state, cfg, now, pid, state / LOCK_NAME)
    except sqlite3.Error as exc:
        raise OperatorError(f"cannot read the database in {state}: {exc}",
                            EXIT_NO_ACCESS) from None
    finally:
        conn.close()


def _gather(conn: sqlite3.Connection, state: Path, cfg: Any | None, now: float,
            pid: int | None, lock: Path) -> dict[str, Any]:
    from dsfd.storage.queries import columns, last_decision

    tables = _tables(conn)
    run = first_row(conn, "SELECT run_id, panel, mode, started_utc, pid, version, "
                    "config_path, ended_utc, end_reason FROM runs ORDER BY run_id DESC LIMIT 1")
    last = last_decision(conn)
    info: dict[str, Any] = {
        "panel": (run or {}).get("panel") or (cfg.panel.id if cfg else None),
        "state_dir": str(state),
        "daemon": {"running": pid is not None, "pid": pid, "lock": str(lock)},
        "run": run,
        "last_cycle": None if last is None else _cycle(last, now),
        "hold": None if last is None else _hold(conn, last, now),
        "objective": None if last is None else _objective(conn, last),
        "occupancy": None if last is None else _occupancy(conn, last, now),
        "flagged": [] if last is None else _flagged(conn, last),
        "calibration": _calibration(conn, cfg, (run or {}).get("panel"), now),
        "commands": _commands(conn) if "commands" in tables else None,
        "findings": _findings(conn),
        "mqtt": _mqtt(conn, running=pid is not None) if "mqtt_cursor" in tables else [],
    }
    if last is not None and "hold_source" not in columns(conn, "decisions"):
        info["note"] = "database of an older dsfd (schema 1): no hold information"
    return info


def _findings(conn: sqlite3.Connection) -> list[dict[str, Any]]:
    """The open findings (none in a database older than schema 7), evidence parsed."""
    from dsfd.storage.findings import open_findings

    return open_findings(conn)


def _finding_lines(found: list[dict[str, Any]]) -> list[str]:
    if not found:
        return ["  findings:    none open"]
    out = [f"  findings:    {len(found)} open (dsfd ack FINDING_ID closes one)"]
    for f in found:
        subject = f" {f['subject']}" if f["subject"] else ""
        since = iso_utc(round(f["start_s"]))
        out.append(f"    #{f['finding_id']} {f['kind']}{subject} since {since}, confidence "
                   f"{f['confidence']:.2f}: {f['action']}")
    return out


def _requester(conn: sqlite3.Connection, command_id: int) -> dict[str, Any] | None:
    """Source and requester of an operator command (its ``commands`` row)."""
    return first_row(conn, "SELECT source, requester FROM commands WHERE command_id = ?",
                     command_id)


def _tables(conn: sqlite3.Connection) -> set[str]:
    return {t for (t,) in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}


def _age(t: float | None, now: float) -> float | None:
    """Seconds since ``t`` if that is a plausible age on this host's clock (a simulated
    run's clock is elsewhere), else None."""
    if t is None:
        return None
    age = now - t
    return round(age, 1) if 0.0 <= age < 7 * 86400.0 else None


def _cycle(d: dict[str, Any], now: float) -> dict[str, Any]:
    timings = json.loads(d.get("timings_ms") or "{}")
    trace = json.loads(d.get("trace") or "[]")
    wind = any(t.get("stage") == "wind" and t.get("set") for t in trace)
    method = d["method"]
    set_by = _SET_BY.get(method, method)
    if wind:
        set_by += ", changed by the wind protection"
    return {"run_id": d["run_id"], "cycle": d["cycle"], "time_utc": d["time_utc"],
            "age_s": _age(d["time_s"], now), "method": method, "set_by": set_by,
            "wind_override": wind,
            "command": {"phi_deg": d["phi_deg"], "afr": d["afr"], "or_pct": d["or_pct"]},
            "write_status": d["write_status"], "fallback": d.get("fallback_reason") or "",
            "decide_ms": timings.get("decide"), "cycle_ms": d.get("cycle_ms")}


def _hold(conn: sqlite3.Connection, d: dict[str, Any], now: float) -> dict[str, Any] | None:
    from dsfd.measured import iso_utc

    source = d.get("hold_source")
    if not source:
        return None
    expires = d.get("hold_expires_s")
    out: dict[str, Any] = {
        "source": source,
        "expires_utc": None if expires is None else iso_utc(round(expires)),
        "remaining_s": None, "command_id": d.get("hold_command_id"), "requester": None}
    if expires is not None and _age(d["time_s"], now) is not None:
        out["remaining_s"] = round(expires - now, 1)
    if out["command_id"] is not None:
        cmd = _requester(conn, out["command_id"])
        if cmd:
            out["requester"] = f"{cmd['source']} {cmd['requester']}"
    return out


def _objective(conn: sqlite3.Connection, d: dict[str, Any]) -> dict[str, Any] | None:
    """The control objective of the last cycle and who chose it (None before schema 5)."""
    if d.get("objective_mode") is None:
        return None
    heating = d.get("heating")
    out: dict[str, Any] = {
        "mode": d["objective_mode"], "command_id": d.get("mode_command_id"),
        "now": None if heating is None else ("heating" if heating else "cooling"),
        "set_by": "panel file (control.mode)"}
    if out["command_id"] is not None:
        cmd = _requester(conn, out["command_id"])
        who = f" by {cmd['source']} {cmd['requester']}" if cmd else ""
        out["set_by"] = f"operator command #{out['command_id']}{who}"
    return out


def _occupancy(conn: sqlite3.Connection, d: dict[str, Any], now: float
               ) -> dict[str, Any] | None:
    """The occupancy of the last cycle, where it came from, and an operator's override in
    force (None before schema 6)."""
    from dsfd.measured import iso_utc

    if "comfort" not in _tables(conn):
        return None
    row = first_row(conn, "SELECT occupied, occupancy_source FROM comfort WHERE run_id = ? "
                    "AND cycle = ?", d["run_id"], d["cycle"])
    out: dict[str, Any] = {
        "occupied": None if row is None else bool(row["occupied"]),
        "source": None if row is None else row["occupancy_source"], "override": None}
    state, until = d.get("occupancy_override"), d.get("occupancy_until_s")
    if state is not None and until is not None:
        o: dict[str, Any] = {"state": state, "until_utc": iso_utc(round(until)),
                             "remaining_s": None, "command_id": d.get("occupancy_command_id"),
                             "requester": None}
        if _age(d["time_s"], now) is not None:
            o["remaining_s"] = round(until - now, 1)
        if o["command_id"] is not None and (cmd := _requester(conn, o["command_id"])):
            o["requester"] = f"{cmd['source']} {cmd['requester']}"
        out["override"] = o
    return out


def _occupancy_line(occ: dict[str, Any]) -> str:
    now = "unknown" if occ["occupied"] is None else (
        f"{'occupied' if occ['occupied'] else 'unoccupied'} (by the {occ['source']})")
    o = occ["override"]
    if o is None:
        return f"{now}; no override"
    by = f" by {o['requester']}" if o["requester"] else ""
    left = "" if o["remaining_s"] is None else \
        f", {_duration(max(o['remaining_s'], 0.0))} left"
    return f"{now}; override {o['state']} until {o['until_utc']}{left}{by}"


def _flagged(conn: sqlite3.Connection, d: dict[str, Any]) -> list[dict[str, str]]:
    return [{"signal": s, "quality": q, "detail": t} for s, q, t in conn.execute(
        "SELECT signal, quality, detail FROM samples WHERE run_id = ? AND cycle = ? AND "
        "quality != 'good' ORDER BY signal", (d["run_id"], d["cycle"]))]


def _calibration(conn: sqlite3.Connection, cfg: Any | None, panel: str | None, now: float
                 ) -> dict[str, Any]:
    from dsfd.daemon.summary import at_bound
    from dsfd.estimation.params import ParameterSpace
    from dsfd.measured import iso_utc
    from dsfd.storage.queries import parameter_history

    rows = parameter_history(conn, panel or "", limit=1) if panel else []
    updates = conn.execute("SELECT COUNT(*) FROM parameters WHERE source = 'online' AND "
                           "run_id = (SELECT MAX(run_id) FROM runs)").fetchone()[0]
    out: dict[str, Any] = {"updates_this_run": updates, "last_update_utc": None,
                           "age_s": None, "source": None, "at_bound": None}
    if rows:
        _, _, t, source, values = rows[0]
        out.update(last_update_utc=iso_utc(round(t)), age_s=_age(t, now), source=source)
        if cfg is not None:
            out["at_bound"] = list(at_bound(values, ParameterSpace.from_panel(cfg)))
    return out


def _commands(conn: sqlite3.Connection) -> dict[str, Any]:
    pending = conn.execute("SELECT COUNT(*) FROM commands WHERE status = 'pending'"
                           ).fetchone()[0]
    last = first_row(conn, "SELECT command_id, kind, args, source, requester, status, "
                     "reason, cycle, handled_utc FROM commands ORDER BY command_id DESC LIMIT 1")
    return {"pending": pending, "last": last}


def _mqtt(conn: sqlite3.Connection, *, running: bool) -> list[dict[str, Any]]:
    """The MQTT publisher's delivery state per destination (``mqtt_cursor``): connected (as
    last saved by a running daemon: a killed one cannot clear it), the last error, the
    backlog, the state messages delivered and the last one acknowledged (run, cycle, time)."""
    from dsfd.measured import iso_utc

    cur = conn.execute("SELECT destination, connected, backlog, delivered, expired, "
                       "last_error, last_error_utc, run_id, cycle, time_s, updated_utc "
                       "FROM mqtt_cursor ORDER BY destination")
    names = [d[0] for d in cur.description]
    out = []
    for row in cur:
        m = dict(zip(names, row, strict=True))
        m["connected"] = bool(m["connected"]) and running
        t = m.pop("time_s")
        m["last_delivered"] = None if not m["cycle"] else {
            "run_id": m["run_id"], "cycle": m["cycle"],
            "time_utc": None if t is None else iso_utc(round(t))}
        del m["run_id"], m["cycle"]
        out.append(m)
    return out


# --------------------------------------------------------------------------- text
def render(info: dict[str, Any]) -> list[str]:
    """The human-readable status."""
    d = info["daemon"]
    run = info["run"] or {}
    running = f"running (PID {d['pid']})" if d["running"] else "not running"
    out = [f"panel {info['panel']}: daemon {running}",
           f"  state:       {info['state_dir']}"]
    if run:
        ended = f", ended {run['ended_utc']} ({run['end_reason']})" if run["ended_utc"] else ""
        out.append(f"  run:         #{run['run_id']} {run['mode']}, started "
                   f"{run['started_utc']}{ended}")
    c = info["last_cycle"]
    if c is None:
        out.append("  last cycle:  none yet")
    else:
        cmd = c["command"]
        age = "" if c["age_s"] is None else f", {_duration(c['age_s'])} ago"
        decide = "" if c["decide_ms"] is None else f", decision {c['decide_ms']:.0f} ms"
        out += [f"  last cycle:  {c['cycle']} at {c['time_utc']}{age}{decide}",
                f"  command:     louver {cmd['phi_deg']:+.0f} deg, regime {cmd['afr']}, "
                f"dampers {cmd['or_pct']:g} % ({c['write_status']}); set by {c['set_by']}"]
        if c["fallback"]:
            out.append(f"  fallback:    {c['fallback']}")
    out.append(f"  hold:        {_hold_line(info['hold'])}")
    if obj := info.get("objective"):
        now = f" ({obj['now']} now)" if obj["mode"] == "auto" and obj["now"] else ""
        out.append(f"  objective:   {obj['mode']}{now}; set by {obj['set_by']}")
    if occ := info.get("occupancy"):
        out.append(f"  occupancy:   {_occupancy_line(occ)}")
    flagged = ", ".join(f"{f['signal']} ({f['quality']})" for f in info["flagged"])
    out.append(f"  flagged:     {flagged or 'none'}")
    out.append(f"  calibration: {_calibration_line(info['calibration'])}")
    cmds = info["commands"]
    if cmds is not None:
        last = cmds["last"]
        line = f"{cmds['pending']} pending"
        if last:
            line += (f"; last #{last['command_id']} {last['kind']} by {last['source']} "
                     f"{last['requester']}: {last['status']}"
                     + (f" ({last['reason']})" if last["reason"] else ""))
        out.append(f"  commands:    {line}")
    out += _finding_lines(info.get("findings") or [])
    for m in info.get("mqtt") or []:
        out += _mqtt_lines(m, running=d["running"])
    if info.get("note"):
        out.append(f"  note:        {info['note']}")
    return out


def _mqtt_lines(m: dict[str, Any], *, running: bool) -> list[str]:
    state = "connected" if m["connected"] else (
        "not connected" if running else "not connected (no daemon)")
    last = m.get("last_delivered")
    upto = "none delivered yet" if not last else (
        f"delivered up to cycle {last['cycle']} of run {last['run_id']}"
        + (f" ({last['time_utc']})" if last["time_utc"] else ""))
    lines = [f"  mqtt:        {m['destination']}: {state}; {m['backlog']} waiting, "
             f"{upto}, {m['delivered']} in all (as of {m['updated_utc']})"]
    if m["last_error"]:
        lines.append(f"               last error {m['last_error_utc']}: {m['last_error']}")
    return lines


def _hold_line(hold: dict[str, Any] | None) -> str:
    if hold is None:
        return "none"
    by = f" by {hold['requester']}" if hold["requester"] else ""
    if hold["expires_utc"] is None:
        return f"{hold['source']}{by}, while the override input is set"
    left = "" if hold["remaining_s"] is None else \
        f" ({_duration(max(hold['remaining_s'], 0.0))} left)"
    return f"{hold['source']}{by} until {hold['expires_utc']}{left}"


def _calibration_line(cal: dict[str, Any]) -> str:
    if cal["last_update_utc"] is None:
        return f"no calibrated parameters yet ({cal['updates_this_run']} updates this run)"
    age = "" if cal["age_s"] is None else f" ({_duration(cal['age_s'])} ago)"
    line = (f"parameters from {cal['last_update_utc']}{age}, {cal['source']}; "
            f"{cal['updates_this_run']} updates this run")
    if cal["at_bound"]:
        line += f"; at a bound: {', '.join(cal['at_bound'])}"
    return line


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
