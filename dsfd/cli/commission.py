"""``dsfd commission --config PANEL [--signals] [--stroke] [--out DIR]``: check the wiring.

Exit codes: 0 every signal and move checked out; 1 findings (or the record could not be
written); 2 bad options or configuration, or ``--stroke`` without ``--yes-move-actuators``;
3 a daemon holds the state directory (as ``dsfd run``): it owns the actuators and the
serial lines.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dsfd.config import ConfigError, load_panel
from dsfd.measured import parse_iso_utc

if TYPE_CHECKING:
    from dsfd.commission.readout import Readout
    from dsfd.commission.stroke import Move, StrokeResult
    from dsfd.config.panel import PanelConfig

EXIT_OK, EXIT_FINDINGS, EXIT_USAGE, EXIT_BUSY = 0, 1, 2, 3
CONFIRM = "--yes-move-actuators"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "commission", help="check the panel's wiring: read every signal, stroke the actuators",
        description="Talk to the configured devices without running the controller. "
        "--signals (the default) reads every signal several times and checks plausibility "
        "(scale, swapped thermocouples, night irradiance, copied registers, louver sign); "
        f"--stroke moves every actuator through its range and back (needs {CONFIRM}). Both "
        "are refused while a daemon holds the state directory. Writes a JSON and an HTML "
        "record into <state dir>/commissioning/ (or --out). docs/commissioning.md.")
    p.add_argument("--config", required=True, type=Path, metavar="PANEL", help="panel YAML")
    p.add_argument("--signals", action="store_true", help="read and check every signal")
    p.add_argument("--stroke", action="store_true",
                   help="move every actuator through its range and back")
    p.add_argument(CONFIRM, dest="confirmed", action="store_true",
                   help="confirm that --stroke may move the louver and the dampers")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="where to write the record (default: <state dir>/commissioning)")
    p.add_argument("--state-dir", type=Path, default=None, metavar="DIR",
                   help="the daemon's state directory (default: as dsfd run finds it)")
    p.add_argument("--reads", type=int, default=5, help="reads per signal (default 5)")
    p.add_argument("--interval", type=float, default=2.0, metavar="S",
                   help="seconds between reads (default 2; the station pushes a line every "
                   "few seconds)")
    p.add_argument("--at", default=None, metavar="ISO",
                   help="judge day and night as at this UTC time (default: now)")
    p.add_argument("--damper-step-pct", type=float, default=25.0,
                   help="damper opening step of the stroke (default 25)")
    p.add_argument("--move-timeout-s", type=float, default=120.0,
                   help="longest wait for one move's feedback (default 120)")
    p.add_argument("--settle-s", type=float, default=3.0,
                   help="a feedback unchanged this long has stopped moving (default 3)")
    p.add_argument("--poll-s", type=float, default=0.1,
                   help="feedback poll period, the resolution of the move times (default 0.1)")
    p.set_defaults(handler=run)


def _fail(message: str, code: int = EXIT_USAGE) -> int:
    print(f"dsfd commission: {message}", file=sys.stderr)
    return code


def run(args: argparse.Namespace) -> int:
    if not args.signals and not args.stroke:
        args.signals = True
    if (args.reads < 1 or args.interval < 0 or args.damper_step_pct <= 0
            or args.settle_s <= 0 or args.poll_s <= 0):
        return _fail("--reads must be >= 1, --interval >= 0, --damper-step-pct, --settle-s "
                     "and --poll-s > 0")
    if args.stroke and not args.confirmed:
        return _fail(f"--stroke moves the louver and the dampers through their whole range: "
                     f"make sure nobody is at the panel and add {CONFIRM}")
    try:
        at_s = parse_iso_utc(args.at) if args.at else time.time()
    except ValueError as exc:
        return _fail(f"--at {args.at!r}: {exc}")
    try:
        cfg = load_panel(args.config)
    except ConfigError as exc:
        print(exc, file=sys.stderr)
        return EXIT_USAGE
    if cfg.devices is None:
        return _fail(f"{args.config}: no devices: section, nothing to commission")
    from dsfd.cli.state_dir import state_dir_of

    state_dir = args.state_dir or state_dir_of(args.config, cfg)
    from dsfd.storage.lock import StateDirBusyError, StateLock, lock_holder

    lock = None
    try:
        if args.stroke:  # held for the whole session: no daemon starts while things move
            lock = StateLock.acquire(state_dir)
        elif (pid := lock_holder(state_dir)) is not None:
            # A running daemon owns the serial lines: reading them would take its lines.
            return _fail(f"a daemon (PID {pid}) controls this panel through {state_dir}: "
                         "stop it first; nothing was opened", EXIT_BUSY)
    except StateDirBusyError as exc:
        return _fail(f"refusing to move the actuators: {exc}; nothing was opened", EXIT_BUSY)
    except OSError as exc:
        return _fail(f"state directory {state_dir}: {exc}")
    try:
        doc = asyncio.run(_session(args, cfg, at_s))
    finally:
        if lock is not None:
            lock.release()
    return _write(doc, args.out or state_dir / "commissioning")


async def _session(args: argparse.Namespace, cfg: PanelConfig, at_s: float) -> dict[str, Any]:
    from dsfd.commission.checks import Conditions
    from dsfd.commission.readout import read_signals
    from dsfd.commission.rig import Rig
    from dsfd.commission.stroke import StrokeOptions, run_stroke
    from dsfd.physics.solar.position import solar_position

    elevation = float(solar_position(at_s, cfg.site.latitude_deg,
                                     cfg.site.longitude_deg).elevation_deg)
    conditions = Conditions(elevation, cfg.room.t_in_c)
    assert cfg.devices is not None
    rig = Rig(cfg.devices)
    readout = stroke = None
    try:
        await rig.start()
        if args.signals:
            readout = await read_signals(cfg, rig, conditions, reads=args.reads,
                                         interval_s=args.interval)
            _print_readout(readout)
        if args.stroke:
            opts = StrokeOptions(damper_step_pct=args.damper_step_pct,
                                 move_timeout_s=args.move_timeout_s, settle_s=args.settle_s,
                                 poll_s=args.poll_s)
            print("stroke: move, target (phi_deg / afr / or_pct), feedback, time")
            stroke = await run_stroke(cfg, rig, opts, log=_print_move)
            _print_findings(stroke.findings, "stroke")
    finally:
        await rig.close()
    return _document(args, cfg, conditions, at_s, readout, stroke)


def _document(args: argparse.Namespace, cfg: PanelConfig, conditions: Any, at_s: float,
              readout: Readout | None, stroke: StrokeResult | None) -> dict[str, Any]:
    from dsfd import __version__
    from dsfd.measured import iso_utc

    findings = [*(readout.findings if readout else ()), *(stroke.findings if stroke else ())]
    doc: dict[str, Any] = {
        "kind": "dsfd-commissioning", "panel": cfg.panel.id, "config": str(args.config),
        "made_utc": datetime.now(UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z"),
        "dsfd": __version__, "time_utc": iso_utc(round(at_s)),
        "sun_elevation_deg": round(conditions.sun_elevation_deg, 2),
        "night": conditions.night, "signals": None, "stroke": None,
        "findings": [f.as_dict() for f in findings],
        "verdict": "findings" if findings else "good",
    }
    if readout is not None:
        doc["signals"] = {"reads": args.reads, "interval_s": args.interval,
                          "rows": [r.as_dict() for r in readout.rows],
                          "actuators": [a.as_dict() for a in readout.actuators]}
    if stroke is not None:
        doc["stroke"] = {"start": stroke.start and stroke.start.as_dict(),
                         "end": stroke.end and stroke.end.as_dict(),
                         "returned": stroke.returned, "stopped": stroke.stopped,
                         "moves": [m.as_dict() for m in stroke.moves]}
    return doc


def _write(doc: dict[str, Any], out_dir: Path) -> int:
    from dsfd.commission.record import write_record

    try:
        json_path, html_path = write_record(doc, out_dir)
    except OSError as exc:
        return _fail(f"cannot write the record into {out_dir}: {exc}", EXIT_FINDINGS)
    n = len(doc["findings"])
    print(f"record: {html_path} ({json_path.name})")
    print("verdict: every signal and move checked out" if not n else f"verdict: {n} finding(s)")
    return EXIT_FINDINGS if n else EXIT_OK


def _cell(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def _print_readout(r: Readout) -> None:
    head = ("signal", "source", "raw", "value", "unit", "quality", "latency_ms")
    rows = [(x.signal, x.source, _cell(x.raw, 1), _cell(x.value), x.unit,
             x.quality if x.ok else f"{x.quality} {x.good_reads}/{x.reads}",
             _cell(x.latency_ms, 1)) for x in r.rows]
    rows += [(a.signal, a.source, "", _cell(a.set_point), a.unit, "set-point", "")
             for a in r.actuators]
    rows += [(a.signal, a.feedback_source, "", _cell(a.feedback), a.unit, "feedback", "")
             for a in r.actuators if a.feedback_source]
    widths = [max(len(row[i]) for row in (head, *rows)) for i in range(len(head))]
    for row in (head, *rows):
        print("  ".join(c.ljust(w) if i < 2 or i in (4, 5) else c.rjust(w)
                        for i, (c, w) in enumerate(zip(row, widths, strict=True))).rstrip())
    night = "night" if r.conditions.night else "day"
    print(f"sun {r.conditions.sun_elevation_deg:.1f} deg above the horizon ({night})")
    _print_findings(r.findings, "signals")


def _print_findings(findings: list[Any], what: str) -> None:
    if not findings:
        print(f"{what}: no findings")
        return
    print(f"{what}: {len(findings)} finding(s)")
    for f in findings:
        print(f"  [{f.check}] {f.message}\n      likely: {f.likely}")


def _print_move(m: Move) -> None:
    target = " / ".join(f"{v:g}" for v in m.target.as_dict().values())
    fb = " / ".join(f"{v:g}" for v in m.feedback.values()) or "-"
    state = "ok" if m.reached else "FAILED"
    print(f"  {m.stage:9} {m.actuator:7} {target:>16}  fb {fb:>16}  {m.time_s:7.3f} s  {state}"
          + (f"  {m.detail}" if m.detail else ""))
