"""Atomic file replacement, and the name an unusable file is moved aside to (no dsfd
imports, so any edge module can use it)."""

from __future__ import annotations

import os
import tempfile
from datetime import UTC, datetime
from pathlib import Path

__all__ = ["corrupt_name", "write_text_atomic"]


def write_text_atomic(path: str | Path, text: str, *, newline: str = "\n") -> None:
    """Replace ``path`` with ``text`` atomically (temp file, fsync, rename, directory fsync).

    ``newline`` is passed to :func:`open` (``""`` keeps the text's own line ends, as the
    csv module wants).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline=newline) as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    dir_fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)


def corrupt_name(path: Path) -> Path:
    """Where an unusable ``path`` is moved aside: ``<name>.corrupt.<UTC time>`` beside it
    (microseconds, so two in one second do not collide)."""
    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%S.%fZ")
    return path.with_name(f"{path.name}.corrupt.{stamp}")
