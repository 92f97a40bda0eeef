"""``dsfd export``: the daemon's log as a measured-data CSV for ``dsfd calibrate``/``validate``.

One row per cycle: the readings whose quality was ``good`` (a flagged sample is an empty
cell, never its bad value), the weather the station measured and the actuator position in
effect from the row on (docs/measured-data-csv.md).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dsfd.cli.state_dir import add_state_arguments, history_from_args

#: Decimals written: far below any sensor's resolution, so the export loses nothing a
#: score could see (1 µK, 1 µm/s, 1 µW/m2).
PRECISION = 6


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="the daemon's log as a measured-data CSV",
                       description="Write the cycles of a state directory as the measured-data "
                       "CSV of 'dsfd calibrate' and 'dsfd validate': good readings, weather, "
                       "and the actuator position in effect from each row on. A flagged "
                       "sample is an empty cell.")
    add_state_arguments(p)
    p.add_argument("--out", required=True, type=Path, help="CSV to write")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from dsfd.measured import iso_utc
    from dsfd.storage.history import measured_from_history
    from dsfd.storage.measured_csv import write_measured

    history, _cfg, code = history_from_args(args, "export")
    if history is None:
        return code
    data = measured_from_history(history)
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        write_measured(data, args.out, precision=PRECISION)
    except OSError as exc:
        print(f"dsfd export: {exc}", file=sys.stderr)
        return 1
    for note in history.notes:
        print(f"note: {note}")
    print(f"wrote {args.out}: {len(data)} rows, {iso_utc(data.time_s[0])} to "
          f"{iso_utc(data.time_s[-1])}; flagged samples are empty cells")
    return 0
