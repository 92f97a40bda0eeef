"""Progress of a long command on stderr, fit for where stderr goes.

On a terminal a bar is redrawn in place (``\\r``). Anywhere else — a file, a pipe, journald,
a CI log — redrawing leaves hundreds of fragments behind, so a plain line is printed every
``every_pct`` per cent instead (and at the end).
"""

from __future__ import annotations

import sys
from typing import TextIO

__all__ = ["Progress"]


class Progress:
    """``progress(done, total, detail="")`` reports; :meth:`close` ends the bar's line."""

    def __init__(self, label: str, *, stream: TextIO | None = None, width: int = 30,
                 every_pct: int = 10) -> None:
        self.label, self.width, self.every_pct = label, width, every_pct
        self.stream = stream if stream is not None else sys.stderr
        isatty = getattr(self.stream, "isatty", None)
        self.terminal = bool(isatty and isatty())
        self._last_pct = -1
        self._open = False  # a bar is on the current line

    def __call__(self, done: int, total: int, detail: str = "") -> None:
        pct = min(100, int(100 * done / max(total, 1)))
        tail = f" ({detail})" if detail else ""
        if self.terminal:
            if pct == self._last_pct and done < total:
                return
            bar = "#" * (pct * self.width // 100)
            self.stream.write(f"\r{self.label} [{bar:<{self.width}}] {pct:3d}% "
                              f"{done}/{total}{tail}   ")
            self._open = True
        else:
            pct = 100 if done >= total else pct // self.every_pct * self.every_pct
            if pct <= self._last_pct:
                return
            self.stream.write(f"{self.label}: {pct:3d}% ({done}/{total}){tail}\n")
        self._last_pct = pct
        self.stream.flush()
        if done >= total:
            self.close()

    def close(self) -> None:
        """End the bar's line (a no-op when nothing is drawn)."""
        if self._open:
            self.stream.write("\n")
            self.stream.flush()
            self._open = False
