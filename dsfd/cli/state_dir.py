"""Options shared by the commands that read a state directory (``report``, ``export``).

``--state-dir DIR`` names it; ``--config PANEL`` finds it as ``dsfd run`` would: the panel's
``daemon.state_directory``, else ``$STATE_DIRECTORY``, else systemd's
``/var/lib/dsfd/<file name>`` of the ``dsfd@<file name>`` unit. Nothing here writes.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from dsfd.config import ConfigError, load_panel
from dsfd.measured import parse_iso_utc

if TYPE_CHECKING:
    from dsfd.config.panel import PanelConfig
    from dsfd.storage.history import History

#: Where systemd's ``StateDirectory=dsfd/%i`` puts the state of unit ``dsfd@NAME``.
SYSTEMD_STATE_ROOT = Path("/var/lib/dsfd")


def add_state_arguments(p: argparse.ArgumentParser) -> None:
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--state-dir", type=Path, metavar="DIR",
                       help="the daemon's state directory (holds timeseries.sqlite)")
    where.add_argument("--config", type=Path, metavar="PANEL",
                       help="panel YAML: its daemon.state_directory, else $STATE_DIRECTORY, "
                       "else /var/lib/dsfd/<file name> (the systemd unit's)")
    p.add_argument("--since", default=None, metavar="ISO",
                   help="first cycle to include (ISO-8601 UTC, e.g. 2022-01-02T00:00:00Z)")
    p.add_argument("--until", default=None, metavar="ISO", help="last cycle to include")
    p.add_argument("--run", type=int, default=None, metavar="N",
                   help="only run N (runs.run_id; default: every run in the window)")


def state_dir_of(config_path: Path, cfg: PanelConfig) -> Path:
    """The state directory ``dsfd run --config config_path`` uses (see module docstring)."""
    from dsfd.daemon.startup import configured_state_dir

    return configured_state_dir(cfg) or SYSTEMD_STATE_ROOT / config_path.stem


def history_from_args(args: argparse.Namespace, command: str
                      ) -> tuple[History | None, PanelConfig | None, int]:
    """(history, panel or None, 0), or (None, None, exit status) after printing why."""
    from dsfd.storage.history import HistoryError, read_history

    def fail(message: str, code: int = 2) -> tuple[None, None, int]:
        print(f"dsfd {command}: {message}", file=sys.stderr)
        return None, None, code

    cfg = None
    try:
        since = parse_iso_utc(args.since) if args.since else None
        until = parse_iso_utc(args.until) if args.until else None
    except ValueError as exc:
        return fail(f"--since/--until: {exc}")
    if args.config is not None:
        try:
            cfg = load_panel(args.config)
        except ConfigError as exc:  # also a file that cannot be read, named
            print(exc, file=sys.stderr)
            return None, None, 2
        state_dir = state_dir_of(args.config, cfg)
    else:
        state_dir = args.state_dir
    try:
        history = read_history(state_dir, since_s=since, until_s=until, run_id=args.run)
    except HistoryError as exc:
        return fail(str(exc), 1)
    if cfg is not None and history.panel and history.panel != cfg.panel.id:
        return fail(f"{state_dir} holds panel {history.panel!r}, not {cfg.panel.id!r}")
    return history, cfg, 0
