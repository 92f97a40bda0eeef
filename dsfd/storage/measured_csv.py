"""Reading and writing the measured-data CSV (schema: :mod:`dsfd.measured`,
``docs/measured-data-csv.md``)."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from dsfd.measured import (
    EXTRA_PREFIX,
    KNOWN_COLUMNS,
    MeasuredData,
    MeasuredDataError,
    iso_utc,
    parse_iso_utc,
)
from dsfd.storage.atomic import write_text_atomic

__all__ = ["read_measured", "write_measured"]


def _validate_header(header: list[str], source: str) -> None:
    if not header or header[0] != "time_utc":
        raise MeasuredDataError(f"{source}: first column must be 'time_utc', got "
                                f"{header[0] if header else 'nothing'!r}")
    seen = set()
    for name in header[1:]:
        if name in seen:
            raise MeasuredDataError(f"{source}: column {name!r} appears twice")
        seen.add(name)
        if name not in KNOWN_COLUMNS and not name.startswith(EXTRA_PREFIX):
            raise MeasuredDataError(
                f"{source}: unknown column {name!r}; known columns: {', '.join(KNOWN_COLUMNS)}"
                f" (and {EXTRA_PREFIX}* extras)")


def read_measured(path: str | Path) -> MeasuredData:
    """Read a measured-data CSV (``#`` lines before the header are notes)."""
    path = Path(path)
    source = str(path)
    notes: list[str] = []
    with path.open(newline="", encoding="utf-8") as fh:
        lines = fh.read().splitlines()
    body_start = 0
    while body_start < len(lines) and lines[body_start].startswith("#"):
        notes.append(lines[body_start][1:].strip())
        body_start += 1
    reader = csv.reader(lines[body_start:])
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise MeasuredDataError(f"{source}: no header row") from None
    _validate_header(header, source)
    times: list[float] = []
    data: list[list[float]] = [[] for _ in header[1:]]
    for row_no, row in enumerate(reader, start=body_start + 2):
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise MeasuredDataError(f"{source}: row {row_no} has {len(row)} fields, header has "
                                    f"{len(header)}")
        try:
            times.append(parse_iso_utc(row[0]))
        except ValueError as exc:
            raise MeasuredDataError(f"{source}: row {row_no}, column 'time_utc': {row[0]!r}: "
                                    f"{exc}") from None
        for j, cell in enumerate(row[1:]):
            text = cell.strip()
            if not text:
                data[j].append(math.nan)
                continue
            try:
                data[j].append(float(text))
            except ValueError:
                raise MeasuredDataError(f"{source}: row {row_no}, column {header[j + 1]!r}: "
                                        f"{text!r} is not a number") from None
    columns = {name: np.asarray(vals, float) for name, vals in zip(header[1:], data,
                                                                   strict=True)}
    return MeasuredData(np.asarray(times, float), columns, source, tuple(notes))


def write_measured(data: MeasuredData, path: str | Path, *, precision: int = 4) -> None:
    """Write ``data`` atomically (temporary file + rename) with notes as ``#`` lines."""
    path = Path(path)
    names = [n for n in KNOWN_COLUMNS if n in data.columns]
    names += sorted(n for n in data.columns if n.startswith(EXTRA_PREFIX))
    buf = io.StringIO()
    for note in data.notes:
        buf.write(f"# {note}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time_utc", *names])
    cols = [data.columns[n] for n in names]
    for i, t in enumerate(data.time_s):
        row = [iso_utc(float(t))]
        for name, col in zip(names, cols, strict=True):
            v = col[i]
            if not math.isfinite(v):
                row.append("")
            elif name == "afr" or name.endswith("_label"):
                row.append(str(int(v)))
            else:
                row.append(f"{v:.{precision}f}".rstrip("0").rstrip(".") if v else "0")
        w.writerow(row)
    write_text_atomic(path, buf.getvalue(), newline="")


