"""``dsfd fleet``: one line per panel publishing to an MQTT broker.

Examples::

    dsfd fleet --broker mqtt.campus.example:1883 --username ops --password-file ~/.mqtt-pw
    dsfd fleet --broker 10.0.4.2 --base dsfd --json

Exit codes: 0 with at least one panel, 1 if the broker cannot be reached, refuses, or no
panel publishes under ``--base``, 2 for bad options or without paho-mqtt.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from dsfd.config.mqtt import topic_problem

EXIT_OK, EXIT_FAILURE, EXIT_USAGE = 0, 1, 2


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "fleet", help="list the panels publishing to an MQTT broker",
        description="Subscribe to <base>/+/state and <base>/+/availability (retained) and "
        "print one line per panel: panel, online, mode, regime, louver, damper, hold, "
        "faults, last seen, decision time.")
    p.add_argument("--broker", required=True, metavar="HOST[:PORT]",
                   help="the broker (port 1883, or 8883 with --tls/--cafile)")
    p.add_argument("--base", default="dsfd", help="topic prefix of the panels (default dsfd: "
                   "the panels' default base topic is dsfd/<panel id>)")
    p.add_argument("--json", action="store_true", help="print a JSON list instead of a table")
    p.add_argument("--username", default=None, help="user name at the broker")
    p.add_argument("--password-file", type=Path, default=None, metavar="FILE",
                   help="file holding the password (first line)")
    p.add_argument("--tls", action="store_true", help="TLS with the system's trusted CAs")
    p.add_argument("--cafile", type=Path, default=None, metavar="FILE",
                   help="TLS with this CA certificate (PEM)")
    p.add_argument("--wait", type=float, default=2.0, metavar="S",
                   help="seconds to listen after subscribing (default 2)")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from dsfd.integrations.mqtt.link import (
        BrokerLink,
        MissingExtraError,
        TlsFiles,
        parse_broker,
        read_password_file,
        require_paho,
    )

    tls = args.tls or args.cafile is not None
    try:
        require_paho()
        host, port = parse_broker(args.broker, default_port=8883 if tls else 1883)
        if (why := topic_problem(args.base)):
            raise ValueError(f"--base {args.base!r} {why}")
        if not args.wait >= 0:
            raise ValueError(f"--wait {args.wait}: must be zero or more seconds")
        if args.password_file is not None and args.username is None:
            raise ValueError("--password-file needs --username")
        password = None
        if args.password_file is not None:
            try:
                password = read_password_file(args.password_file.expanduser())
            except (OSError, ValueError, UnicodeDecodeError) as exc:
                raise ValueError(f"--password-file {args.password_file}: {exc}") from exc
    except (MissingExtraError, ValueError) as exc:
        print(f"dsfd fleet: {exc}", file=sys.stderr)
        return EXIT_USAGE
    from dsfd.integrations.mqtt.fleet import FleetError, collect, fleet_rows, format_table

    link = BrokerLink(host=host, port=port, client_id="", username=args.username,
                      password=password,
                      tls=TlsFiles(args.cafile, None, None) if tls else None)
    try:
        panels = collect(link, base=args.base, wait_s=args.wait)
    except FleetError as exc:
        print(f"dsfd fleet: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    rows = fleet_rows(panels)
    if args.json:
        print(json.dumps(rows, indent=1))
    elif rows:
        print(format_table(rows))
    if not rows:
        print(f"dsfd fleet: no panel publishes under {args.base}/ on {link.address}",
              file=sys.stderr)
        return EXIT_FAILURE
    return EXIT_OK
