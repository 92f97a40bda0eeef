"""The daemon's log for a person at a terminal: one aligned line per cycle, events marked.

The journal's JSON lines are for machines; in a terminal the same events are rendered here:
a header, then per cycle its number, the cycle's time (UTC), who decided (mpc, rule, safe,
manual, ...), louver angle, airflow regime with its name, damper opening, what the
calibration did and the decision time, followed by marks: ``⚑`` the flagged signals, ``✋``
the manual hold, ``WIND``, a failed write, a fallback, skipped slots, a store backlog.
docs/operating.md shows a captured example.

A cycle line is the ``cycle`` event the daemon logs (dsfd.daemon.runner); every other event
is one line under the cycle number it happened in, with a marker and a colour by what it is:
``★`` a calibration update, ``✋`` a manual hold starting, ending or detected, ``▲`` a
warning (a flagged sensor, a late stage), ``✖`` an error. Colours only when the stream is a
terminal (ANSI SGR codes, ECMA-48). The renderer is a structlog processor that returns the
line (it replaces the JSON renderer, it does not sit beside it).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, MutableMapping
from typing import Any

from dsfd.config.panel import REGIME_NAMES

__all__ = ["CONSOLE_ONLY", "CycleConsoleRenderer"]

#: Keys the daemon adds to an event for the console only; the JSON renderer drops them, so
#: the journal's lines stay as they were.
CONSOLE_ONLY = ("flagged_signals",)

_RESET, _BOLD, _DIM = "\x1b[0m", "\x1b[1m", "\x1b[2m"
_RED, _YELLOW, _GREEN, _MAGENTA, _CYAN = (f"\x1b[{n}m" for n in (31, 33, 32, 35, 36))
#: Keys every line carries that the console does not repeat.
_CONTEXT = {"event", "level", "logger", "timestamp", "panel", "cycle", "exception"}
_ISO = re.compile(r"\b\d{4}-\d\d-\d\dT(\d\d:\d\d):\d\d(?:\.\d+)?Z\b")
_HOLD_KINDS = {"hold_started", "hold_ended", "manual_override"}
_HEADER = (f"{'cycle':>6}  {'time (UTC)':16}  {'by':6}  {'louver':>6}  {'regime':28}  "
           f"{'dampers':>7}  {'calibration':15}  {'decide':>8}")


class CycleConsoleRenderer:
    """structlog renderer: ``cycle`` events as aligned columns, other events as marked lines.

    Parameters
    ----------
    colors : bool
        Emit ANSI colours (only for a terminal).
    header_every : int
        Repeat the column header after this many cycle lines (0: only before the first).
    """

    def __init__(self, *, colors: bool, header_every: int = 40) -> None:
        self.colors = colors
        self.header_every = header_every
        self._cycle_lines = 0

    def _paint(self, text: str, *codes: str) -> str:
        return f"{''.join(codes)}{text}{_RESET}" if self.colors and codes else text

    def __call__(self, _logger: Any, _name: str, event_dict: MutableMapping[str, Any]) -> str:
        if event_dict.get("event") == "cycle" and "method" in event_dict:
            return self._cycle(event_dict)
        return self._event(event_dict)

    # ------------------------------------------------------------ cycle lines

    def _cycle(self, ev: Mapping[str, Any]) -> str:
        head = ""
        if self._cycle_lines == 0 or (self.header_every
                                      and self._cycle_lines % self.header_every == 0):
            head = self._paint(_HEADER, _DIM) + "\n"
        self._cycle_lines += 1
        when = str(ev.get("time_utc") or "")[:16].replace("T", " ")
        afr = ev.get("afr")
        regime = f"{afr:>2} {REGIME_NAMES.get(afr, '?')}" if isinstance(afr, int) else "?"
        phi, or_pct, decide = ev.get("phi_deg"), ev.get("or_pct"), ev.get("decide_ms")
        louver = f"{phi:+.0f}°" if isinstance(phi, int | float) else "-"
        dampers = f"{or_pct:.0f} %" if isinstance(or_pct, int | float) else "-"
        ms = f"{decide:.1f} ms" if isinstance(decide, int | float) else "-"
        method = str(ev.get("method", "?"))
        calib = f"{_cut(str(ev.get('calibration') or '-'), 15):15}"
        if calib.startswith("updated"):
            calib = self._paint(calib, _CYAN, _BOLD)
        line = (f"{ev.get('cycle', ''):>6}  {when:16}  "
                f"{self._paint(f'{method:6}', *_METHOD_COLOUR.get(method, ()))}  "
                f"{louver:>6}  {_cut(regime, 28):28}  {dampers:>7}  {calib}  {ms:>8}")
        return head + line + self._marks(ev)

    def _marks(self, ev: Mapping[str, Any]) -> str:
        marks: list[str] = []
        flagged = ev.get("flagged_signals") or ()
        if flagged:
            marks.append(self._paint("⚑ " + ",".join(flagged), _YELLOW))
        elif ev.get("flagged"):
            marks.append(self._paint(f"⚑ {ev['flagged']} flagged", _YELLOW))
        if ev.get("hold"):
            marks.append(self._paint(f"✋ {_clock(str(ev['hold']))}", _MAGENTA, _BOLD))
        if ev.get("wind_override"):
            marks.append(self._paint("WIND safe position", _RED, _BOLD))
        write = ev.get("write")
        if write == "failed":  # verified, held (a hold writes nothing) and dry-run are normal
            marks.append(self._paint(f"write {write}", _RED, _BOLD))
        if ev.get("fallback"):
            marks.append(self._paint(f"fallback: {ev['fallback']}", _YELLOW))
        if ev.get("skipped"):
            marks.append(self._paint(f"{ev['skipped']} slot(s) skipped", _YELLOW))
        if ev.get("stored"):
            marks.append(self._paint(f"store {ev['stored']}", _RED))
        return ("  " + "  ".join(marks)) if marks else ""

    # ------------------------------------------------------------ other events

    def _event(self, ev: Mapping[str, Any]) -> str:
        level = str(ev.get("level", "info"))
        text = str(ev.get("event", ""))
        extra = {k: v for k, v in ev.items() if k not in _CONTEXT and k not in CONSOLE_ONLY}
        if text == "calibration updated":
            marker, codes = "★", (_CYAN, _BOLD)
            extra.pop("residuals", None)
            detail, extra = _parameters(extra), {}
        elif ev.get("event_kind") in _HOLD_KINDS:
            marker, codes, detail = "✋", (_MAGENTA, _BOLD), ""
            extra.pop("event_kind", None)
        elif level in ("error", "critical", "exception"):
            marker, codes, detail = "✖", (_RED, _BOLD), ""
        elif level == "warning":
            marker, codes, detail = "▲", (_YELLOW,), ""
        else:
            marker, codes, detail = "·", (_DIM,), ""
        if extra:
            detail = _cut("  ".join(f"{k}={_short(v)}" for k, v in extra.items()), 110)
        line = f"{ev.get('cycle', ''):>6}  " + self._paint(f"{marker} {text}", *codes)
        if detail:
            line += "  " + (self._paint(detail, _DIM) if marker == "·" else detail)
        if ev.get("exception"):
            line += "\n" + self._paint(str(ev["exception"]).rstrip(), _RED)
        return line


_METHOD_COLOUR: dict[str, tuple[str, ...]] = {
    "mpc": (_GREEN,), "rule": (_YELLOW,), "safe": (_RED, _BOLD), "manual": (_MAGENTA, _BOLD),
    "wind": (_RED, _BOLD),
}


def _parameters(theta: Mapping[str, Any]) -> str:
    """``h_out 8.41  h_ca1 2.1 ... n 1  q_x1..x4 -10.8/20.3/17.9/-9.8 W/m²``."""
    plain = [f"{k} {v:.3g}" for k, v in theta.items()
             if not k.startswith("q_") and isinstance(v, int | float)]
    offsets = [f"{v:.3g}" for k, v in theta.items()
               if k.startswith("q_") and isinstance(v, int | float)]
    if offsets:
        plain.append(f"q_x1..x{len(offsets)} {'/'.join(offsets)} W/m²")
    return "  ".join(plain)


def _clock(text: str) -> str:
    """ISO times in a line shortened to the minute (``2022-01-01T23:55:02Z`` → ``23:55Z``);
    the cycle's date stands in the same line."""
    return _ISO.sub(r"\1Z", text)


def _cut(text: str, width: int) -> str:
    return text if len(text) <= width else text[:width - 1] + "…"


def _short(value: Any) -> str:
    return repr(value) if isinstance(value, str) and " " in value else str(value)
