"""The commissioning record: one JSON document and one self-contained HTML page (inline CSS,
no script, no network) per ``dsfd commission`` run, in ``<state dir>/commissioning/``."""

from __future__ import annotations

import json
import statistics
from collections import defaultdict
from collections.abc import Mapping, Sequence
from html import escape
from pathlib import Path
from typing import Any

from dsfd.storage.atomic import write_text_atomic

__all__ = ["RECORD_DIR", "latest_record", "render_record", "write_record"]

#: Sub-directory of the state directory that holds the records.
RECORD_DIR = "commissioning"
_PREFIX = "commission-"

CSS = """
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; margin: 1.5em auto;
       max-width: 1180px; color: #222; line-height: 1.35; padding: 0 1em; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; }
h2 { font-size: 1.2em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 1.5em; }
table { border-collapse: collapse; margin: 0.4em 0 1em; font-size: 0.88em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; }
th { background: #f0f0f0; }
td.l, th.l { text-align: left; }
tr.bad td { background: #fde8e6; }
.verdict { font-size: 1.15em; padding: 0.5em 0.8em; border-radius: 4px; }
.good { background: #e3f4e1; color: #1d5e1a; }
.findings { background: #fde8e6; color: #8a1c10; }
ul.f li { margin-bottom: 0.5em; }
.likely { color: #8a4b00; }
.meta { color: #555; font-size: 0.9em; }
"""


def _f(value: Any, digits: int = 2) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return escape(str(value))


def _table(head: Sequence[str], rows: Sequence[tuple[Sequence[str], bool]],
           left: int | set[int]) -> str:
    """A table; columns in ``left`` (or the first ``left``) are text, the others numbers;
    rows marked True are highlighted."""
    lefts = set(range(left)) if isinstance(left, int) else left
    th = "".join(f'<th class="l">{escape(h)}</th>' if i in lefts else f"<th>{escape(h)}</th>"
                 for i, h in enumerate(head))
    body = "".join(
        f'<tr{" class=bad" if bad else ""}>'
        + "".join(f'<td class="l">{c}</td>' if i in lefts else f"<td>{c}</td>"
                  for i, c in enumerate(cells)) + "</tr>" for cells, bad in rows)
    return f"<table><tr>{th}</tr>{body}</table>"


def _position(cmd: Mapping[str, Any] | None) -> str:
    if cmd is None:
        return "unknown"
    return f"louver {cmd['phi_deg']:g}°, regime {cmd['afr']:g}, dampers {cmd['or_pct']:g} %"


def _signals(doc: Mapping[str, Any]) -> str:
    sig = doc.get("signals")
    if not sig:
        return ""
    flagged = {s for f in doc["findings"] for s in f["signals"]}
    rows = [([escape(r["signal"]), escape(r["source"]), _f(r["raw"], 1), _f(r["value"]),
              escape(r["unit"]), f'{escape(r["quality"])} ({r["good_reads"]}/{r["reads"]})',
              _f(r["latency_ms"], 1)], r["quality"] != "good" or r["signal"] in flagged)
            for r in sig["rows"]]
    acts = [([escape(a["signal"]), escape(a["source"]), _f(a["set_point"]),
              escape(a["feedback_source"]) or "none", _f(a["feedback"]), escape(a["unit"])],
             a["signal"] in flagged) for a in sig["actuators"]]
    return (f'<h2>Signals</h2><p class="meta">{sig["reads"]} reads, {sig["interval_s"]:g} s '
            "apart; value: median of the good reads; latency: median time of one read of "
            "the signal's device.</p>"
            + _table(["signal", "source", "raw", "value", "unit", "quality", "latency ms"],
                     rows, 2)
            + "<h3>Actuators (set-point and position feedback)</h3>"
            + _table(["actuator", "set-point register", "set-point", "feedback register",
                      "feedback", "unit"], acts, {0, 1, 3}))


def _stroke(doc: Mapping[str, Any]) -> str:
    st = doc.get("stroke")
    if not st:
        return ""
    times: dict[str, list[float]] = defaultdict(list)
    for m in st["moves"]:
        times[m["actuator"]].append(m["time_s"])
    summary = [([escape(a), str(len(t)), _f(statistics.median(t), 3), _f(max(t), 3)], False)
               for a, t in times.items()]
    moves = [([str(i), escape(m["stage"]), escape(m["actuator"]),
               " / ".join(_f(v, 0) for v in m["target"].values()),
               " / ".join(_f(v, 0) for v in m["feedback"].values()) or "–",
               "yes" if m["verified"] else "NO", "yes" if m["reached"] else "NO",
               _f(m["time_s"], 3), escape(m["detail"])], not m["reached"])
             for i, m in enumerate(st["moves"], 1)]
    back = "yes" if st["returned"] else "NO"
    stopped = f' <b>Stopped: {escape(st["stopped"])}</b>.' if st["stopped"] else ""
    return (f'<h2>Stroke</h2><p class="meta">Start: {escape(_position(st["start"]))}; end: '
            f'{escape(_position(st["end"]))}; back at the start: {back}.{stopped} Time: from the '
            "write to the feedback within tolerance (without feedback: to the verified "
            "read-back).</p>"
            + _table(["actuator", "moves", "median s", "max s"], summary, 1)
            + _table(["#", "stage", "exercises", "target φ / AFR / OR", "feedback",
                      "read-back ok", "reached", "time s", "detail"], moves, 3))


def render_record(doc: Mapping[str, Any]) -> str:
    """The HTML page of record ``doc``."""
    findings = doc["findings"]
    title = f"dsfd commissioning — panel {escape(doc['panel'])}"
    if findings:
        verdict = (f'<p class="verdict findings">{len(findings)} finding(s): look at each '
                   "before the controller is switched on.</p>")
        items = "".join(f'<li><b>{escape(f["check"])}</b> — {escape(f["message"])}'
                        f'<br><span class="likely">Likely: {escape(f["likely"])}</span></li>'
                        for f in findings)
        verdict += f'<h2>Findings</h2><ul class="f">{items}</ul>'
    else:
        verdict = '<p class="verdict good">Every signal and move checked out.</p>'
    night = "night" if doc["night"] else "day"
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title><style>{CSS}</style></head>
<body><h1>{title}</h1>
<p class="meta">Checked at {escape(doc["time_utc"])} UTC (sun {doc["sun_elevation_deg"]:.1f}°
above the horizon: {night}); configuration <code>{escape(doc["config"])}</code>; record made
{escape(doc["made_utc"])} by dsfd {escape(doc["dsfd"])}.</p>
{verdict}{_signals(doc)}{_stroke(doc)}
</body></html>
"""


def write_record(doc: Mapping[str, Any], out_dir: Path) -> tuple[Path, Path]:
    """Write ``commission-<UTC stamp>.json`` and ``.html`` into ``out_dir``; their paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    stamp = doc["made_utc"].replace("-", "").replace(":", "")
    base = out_dir / f"{_PREFIX}{stamp}"
    json_path, html_path = base.with_suffix(".json"), base.with_suffix(".html")
    write_text_atomic(json_path, json.dumps(doc, indent=1) + "\n")
    write_text_atomic(html_path, render_record(doc))
    return json_path, html_path


def latest_record(state_dir: Path) -> Path | None:
    """The newest commissioning page in ``state_dir`` (names sort by time), or None."""
    pages = sorted((state_dir / RECORD_DIR).glob(f"{_PREFIX}*.html"))
    return pages[-1] if pages else None
