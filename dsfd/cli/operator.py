"""``dsfd override``, ``dsfd resume``, ``dsfd mode``, ``dsfd occupancy`` and ``dsfd ack``:
operator commands to the running daemon of a panel.

Examples::

    sudo dsfd override --config /etc/dsfd/suwon-south.yaml --hold 2h --louver-deg 36
    sudo dsfd override --config /etc/dsfd/suwon-south.yaml            # hold where it is
    sudo dsfd resume --config /etc/dsfd/suwon-south.yaml
    sudo dsfd mode --config /etc/dsfd/suwon-south.yaml cooling        # the control objective
    sudo dsfd occupancy --config /etc/dsfd/suwon-south.yaml occupied until 20:00
    sudo dsfd occupancy --config /etc/dsfd/suwon-south.yaml unoccupied until 2026-12-01T08:00
    sudo dsfd occupancy --config /etc/dsfd/suwon-south.yaml auto      # end the override
    sudo dsfd ack --config /etc/dsfd/suwon-south.yaml 3               # acknowledge finding #3

The request is validated against the panel (louver grid and limits, the regimes the dampers
allow, damper steps) before anything is queued; a bad one exits 2 naming the option and the
value and changes nothing. A good one goes into the daemon's ``commands`` table (source
``cli``, the requester ``user@host``); the daemon applies it at its next cycle and records
the result, which this command waits for and prints.

Exit codes: 0 applied (or queued with ``--no-wait``), 1 rejected by the daemon or not
answered in time, 2 bad request or options, 3 no daemon runs on the state directory (nothing
queued), 4 the state directory cannot be read or written (permissions:
docs/operating.md, "Permissions").
"""

from __future__ import annotations

import argparse
import sqlite3
import sys
import time
from pathlib import Path
from typing import Any

from dsfd.cli.state_dir import SYSTEMD_STATE_ROOT, state_dir_of

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_NOT_RUNNING, EXIT_NO_ACCESS = 0, 1, 2, 3, 4
#: Option names of the request fields (for error messages).
OPTION_OF = {"hold": "--hold", "louver_deg": "--louver-deg", "regime": "--regime",
             "or_pct": "--or-pct", "mode": "OBJECTIVE", "state": "STATE", "until": "until",
             "finding": "FINDING_ID"}


class OperatorError(Exception):
    """A problem an operator must fix; ``code`` is the exit status."""

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


def add_target(p: argparse.ArgumentParser) -> None:
    """``--config PANEL`` / ``--state-dir DIR``: which panel's daemon."""
    p.add_argument("--config", type=Path, metavar="PANEL",
                   help="the panel file the daemon runs (/etc/dsfd/NAME.yaml); its state "
                   "directory is daemon.state_directory, else $STATE_DIRECTORY, else "
                   f"{SYSTEMD_STATE_ROOT}/NAME (systemd's StateDirectory=dsfd/%%i)")
    p.add_argument("--state-dir", type=Path, metavar="DIR",
                   help="the daemon's state directory (overrides the one --config implies)")


def load_target(args: argparse.Namespace, *, need_config: bool) -> tuple[Path, Any]:
    """(state directory, panel config or None). Without --config, the config the daemon's
    last run used (``runs.config_path``) is tried; it must load when ``need_config``."""
    from dsfd.config import ConfigError, load_panel

    cfg = None
    if args.config is not None:
        try:
            cfg = load_panel(args.config)
        except ConfigError as exc:  # also a file that cannot be read, named
            raise OperatorError(str(exc), EXIT_USAGE) from None
    if args.state_dir is not None:
        state = args.state_dir
    elif cfg is not None:
        state = state_dir_of(args.config, cfg)
    else:
        raise OperatorError("give --config PANEL or --state-dir DIR", EXIT_USAGE)
    if cfg is None and need_config:
        cfg = _config_of_last_run(state)
    elif cfg is None:
        try:  # nice to have (parameter bounds), not needed; access errors come later
            cfg = _config_of_last_run(state)
        except (OperatorError, OSError):
            cfg = None
    return state, cfg


def open_database(state: Path) -> sqlite3.Connection:
    """The state directory's database, read-only (:mod:`dsfd.storage.queries`)."""
    from dsfd.storage.queries import open_read_only
    from dsfd.storage.timeseries import DB_NAME

    try:
        return open_read_only(state / DB_NAME)
    except FileNotFoundError:
        raise OperatorError(f"no database in {state}: no daemon has run with this state "
                            "directory (wrong --config or --state-dir?)", EXIT_FAILURE) from None
    except (PermissionError, sqlite3.Error) as exc:
        raise OperatorError(f"cannot read {state / DB_NAME}: {exc}: {access_hint()}",
                            EXIT_NO_ACCESS) from None


def access_hint() -> str:
    return ("run it with sudo, or give your group access to the state directory "
            "(docs/operating.md, 'Permissions')")


def _config_of_last_run(state: Path) -> Any:
    from dsfd.config import ConfigError, load_panel

    conn = open_database(state)
    try:
        row = conn.execute("SELECT config_path FROM runs ORDER BY run_id DESC LIMIT 1"
                           ).fetchone()
    finally:
        conn.close()
    if row is None or not row[0]:
        raise OperatorError("the panel is not known: give --config PANEL", EXIT_USAGE)
    try:
        return load_panel(row[0])
    except ConfigError as exc:
        raise OperatorError(f"the daemon's panel file {row[0]} cannot be read ({exc}): give "
                            "--config PANEL", EXIT_USAGE) from None


# --------------------------------------------------------------------------- commands
def register(sub: argparse._SubParsersAction) -> None:
    o = sub.add_parser(
        "override", help="hold the panel (optionally at given positions) for a while",
        description="Tell the running daemon to hold the panel: it then writes nothing "
        "(except the positions given here, once, and wind protection) until the hold ends "
        "(--hold, default safety.manual_hold_min), or dsfd resume. Takes effect at the next "
        "cycle.")
    add_target(o)
    o.add_argument("--hold", metavar="DURATION",
                   help="how long, e.g. 2h, 90min, 1h30m (default safety.manual_hold_min, "
                   "ending at safety.manual_reset_local at the latest)")
    o.add_argument("--louver-deg", type=float, metavar="X",
                   help="louver angle [deg] on the motor's grid")
    o.add_argument("--regime", type=int, metavar="N", help="airflow regime 1..10")
    o.add_argument("--or-pct", type=float, metavar="Y", help="damper opening [%%]")
    _wait_options(o)
    o.set_defaults(handler=override)
    r = sub.add_parser("resume", help="end a manual hold: the daemon controls again",
                       description="End the panel's manual hold (detected or operator); the "
                       "daemon decides again from the next cycle. An override input that is "
                       "set keeps holding.")
    add_target(r)
    _wait_options(r)
    r.set_defaults(handler=resume)
    m = sub.add_parser("mode", help="set the control objective: heating, cooling or auto",
                       description="Tell the running daemon which objective to control for "
                       "(heating: Eq. 4, cooling: Eq. 5, auto: by the outdoor air), in place of "
                       "the panel file's control.mode, until the next mode command or a "
                       "change of control.mode in the file. It moves nothing by itself and is "
                       "no hold. Takes effect at the next cycle.")
    add_target(m)
    m.add_argument("objective", metavar="OBJECTIVE", help="heating, cooling or auto")
    _wait_options(m)
    m.set_defaults(handler=mode)
    c = sub.add_parser(
        "occupancy", help="override the occupancy: occupied|unoccupied until TIME, or auto",
        description="Tell the running daemon that the room is occupied or unoccupied until a "
        "time, whatever the occupied signal and the schedule say (the comfort limits apply "
        "while occupied). TIME is HH:MM panel local time (the next such time) or an ISO 8601 "
        "date-time (2026-12-01T08:00 is panel local time; add Z or +09:00 for a zone). 'auto' "
        "ends the override. It moves nothing by itself and is no hold. Takes effect at the "
        "next cycle.")
    add_target(c)
    c.add_argument("state", metavar="STATE", help="occupied, unoccupied or auto")
    c.add_argument("until", nargs="*", metavar="until TIME",
                   help="when the override ends: 'until 18:00', 'until 2026-12-01T08:00'")
    _wait_options(c)
    c.set_defaults(handler=occupancy)
    a = sub.add_parser(
        "ack", help="acknowledge an open finding of the diagnostics (dsfd status lists them)",
        description="Tell the running daemon that a person has seen an open finding (a "
        "damper that does not follow its motor, a residual that shifted, ...): it closes, and "
        "stays closed until new evidence (a later start) opens a new one. It moves nothing. "
        "Takes effect at the next cycle.")
    add_target(a)
    a.add_argument("finding", metavar="FINDING_ID", help="the finding's id (dsfd status)")
    _wait_options(a)
    a.set_defaults(handler=ack)


def _wait_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--no-wait", action="store_true",
                   help="return once the command is queued")
    p.add_argument("--wait", type=float, default=None, metavar="S",
                   help="give up waiting for the daemon's answer after S seconds (default: "
                   "two cycle periods and 10 s)")


def override(args: argparse.Namespace) -> int:
    request: dict[str, Any] = {"command": "override"}
    for key, value in (("hold", args.hold), ("louver_deg", args.louver_deg),
                       ("regime", args.regime), ("or_pct", args.or_pct)):
        if value is not None:
            request[key] = value
    return _send("override", request, args)


def resume(args: argparse.Namespace) -> int:
    return _send("resume", {"command": "resume"}, args)


def mode(args: argparse.Namespace) -> int:
    return _send("mode", {"command": "mode", "mode": args.objective}, args)


def occupancy(args: argparse.Namespace) -> int:
    from dsfd.daemon.commands import CommandError, occupancy_request

    try:
        request = occupancy_request(" ".join([args.state, *args.until]))
    except CommandError as exc:
        print(f"dsfd occupancy: {exc}; nothing was sent", file=sys.stderr)
        return EXIT_USAGE
    return _send("occupancy", request, args)


def ack(args: argparse.Namespace) -> int:
    text = args.finding.strip()
    return _send("ack", {"command": "ack", "finding": int(text) if text.isdigit() else text},
                 args)


def _send(name: str, request: dict[str, Any], args: argparse.Namespace) -> int:
    from dsfd.daemon.commands import CommandError, validate_command

    try:
        state, cfg = load_target(args, need_config=True)
        try:
            validated = validate_command(cfg, request)
        except CommandError as exc:
            option = OPTION_OF.get(exc.field, exc.field)
            raise OperatorError(f"{option} {exc.value}: {exc.message}; nothing was sent",
                                EXIT_USAGE) from None
        command_id = _queue(state, request)
    except OperatorError as exc:
        print(f"dsfd {name}: {exc}", file=sys.stderr)
        return exc.code
    print(f"command #{command_id} ({validated.describe()}) queued for panel {cfg.panel.id}")
    if args.no_wait:
        return EXIT_OK
    limit = args.wait if args.wait is not None else 2 * cfg.daemon.cycle_period_s + 10.0
    return _await_answer(name, state, command_id, limit)


def _queue(state: Path, request: dict[str, Any]) -> int:
    from dsfd.storage.commands import requester, submit
    from dsfd.storage.lock import lock_holder
    from dsfd.storage.timeseries import DB_NAME

    try:
        pid = lock_holder(state)
    except PermissionError as exc:
        raise OperatorError(f"{exc}: {access_hint()}", EXIT_NO_ACCESS) from None
    if pid is None:
        raise OperatorError(f"no daemon is running on {state}; nothing was queued",
                            EXIT_NOT_RUNNING)
    args = {k: v for k, v in request.items() if k != "command"}
    try:
        return submit(state / DB_NAME, kind=request["command"], args=args, source="cli",
                      requester=requester())
    except sqlite3.OperationalError as exc:
        raise OperatorError(f"cannot write {state / DB_NAME}: {exc}: {access_hint()}",
                            EXIT_NO_ACCESS) from None


def _await_answer(name: str, state: Path, command_id: int, limit_s: float) -> int:
    from dsfd.storage.commands import outcome

    deadline = time.monotonic() + limit_s
    while True:
        conn = open_database(state)
        try:
            got = outcome(conn, command_id)
        finally:
            conn.close()
        if got is not None and got.status != "pending":
            print(f"{got.status} at cycle {got.cycle} ({got.handled_utc}): {got.reason}")
            return EXIT_OK if got.status == "applied" else EXIT_FAILURE
        if time.monotonic() > deadline:
            print(f"dsfd {name}: command #{command_id} still pending after {limit_s:g} s: is "
                  "the daemon cycling? (dsfd status)", file=sys.stderr)
            return EXIT_FAILURE
        time.sleep(0.2)
