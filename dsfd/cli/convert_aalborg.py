"""``dsfd convert-aalborg``: the Aalborg "Cube" DSF tables → measured-data CSV."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("convert-aalborg", help="convert the Aalborg 'Cube' DSF data to CSV",
                       description="Read the 10-minute DSFModelica tables of the Aalborg "
                       "'Cube' (BoundaryConditions10min.txt, DSFValidation10min.txt) and "
                       "write a measured-data CSV (x1..x3 glass temperatures, weather, room "
                       "air; regime 3 throughout). Assumptions are written as # notes.")
    p.add_argument("src_dir", type=Path, help="folder with the DSFModelica tables")
    p.add_argument("--out", required=True, type=Path, help="measured-data CSV to write")
    p.add_argument("--year", type=int, default=2006, help="year of the record (not in the "
                   "source; default 2006)")
    p.add_argument("--irradiance", choices=("horizontal", "facade"), default="horizontal",
                   help="read Ghtot/Ghdiff as global/diffuse horizontal (default; see "
                   "dsfd.convert.aalborg) or as façade-plane total/diffuse")
    p.add_argument("--hourly", choices=("interpolate", "hold"), default="interpolate",
                   help="hourly irradiance: interpolate between hour midpoints (default) or "
                   "hold over the hour")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from dsfd.convert.aalborg import convert_aalborg
    from dsfd.measured import iso_utc
    from dsfd.storage.measured_csv import write_measured

    if not 1990 <= args.year <= 2100:
        print(f"dsfd convert-aalborg: --year {args.year}: expected 1990..2100", file=sys.stderr)
        return 2
    try:
        data = convert_aalborg(args.src_dir, year=args.year, irradiance=args.irradiance,
                               hourly=args.hourly)
        write_measured(data, args.out)
    except (OSError, ValueError) as exc:
        print(f"dsfd convert-aalborg: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}: {len(data)} rows, {iso_utc(data.time_s[0])} to "
          f"{iso_utc(data.time_s[-1])}, step {data.step_s:g} s")
    for note in data.notes:
        print(f"  note: {note}")
    return 0
