"""The report as one self-contained HTML page: inline CSS, figures as base64 PNG, no script,
no network — it opens from a USB stick and prints."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from html import escape
from typing import TYPE_CHECKING

from dsfd.measured import iso_utc
from dsfd.report.diagnostics import render_section
from dsfd.report.kpis import HEAT_TERMS, STATES, DayKpis, zone_name
from dsfd.report.plotting import figure_html

if TYPE_CHECKING:
    from dsfd.report import Report

__all__ = ["render_html"]

CSS = """
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; margin: 1.5em auto;
       max-width: 1180px; color: #222; line-height: 1.35; padding: 0 1em; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; }
h2 { font-size: 1.25em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em;
     margin-top: 1.6em; }
h3 { font-size: 1.05em; margin-bottom: 0.3em; }
table { border-collapse: collapse; margin: 0.4em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.55em; text-align: right; }
th { background: #f0f0f0; }
td.l, th.l { text-align: left; }
td.t { white-space: nowrap; }
tr.action td { white-space: normal; color: #444; background: #fafafa; }
td:first-child { white-space: nowrap; }
tr.total td { font-weight: bold; background: #fafafa; }
figure { margin: 1em 0 2em; }
figure img { width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; margin-top: 0.3em; }
.note { color: #8a4b00; }
.meta { color: #555; font-size: 0.9em; }
nav ul { columns: 2; font-size: 0.95em; }
"""


def _f(value: float | None, digits: int = 2) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return f"{value:.{digits}f}"


def _table(head: Sequence[str], rows: Iterable[Sequence[str]], *, left: int = 1,
           total_last: bool = False) -> str:
    rows = list(rows)
    out = ["<table><thead><tr>"]
    out += [f'<th class="{"l" if i < left else ""}">{escape(h)}</th>' for i, h in
            enumerate(head)]
    out.append("</tr></thead><tbody>")
    for k, row in enumerate(rows):
        cls = ' class="total"' if total_last and k == len(rows) - 1 else ""
        out.append(f"<tr{cls}>" + "".join(
            f'<td class="{"l" if i < left else ""}">{escape(c)}</td>' for i, c in
            enumerate(row)) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _methods(d: DayKpis) -> str:
    return ", ".join(f"{m} {n}" for m, n in d.methods.most_common()) or "–"


def _operation(report: Report) -> str:
    k = report.kpis
    head = ["day (local)", "hours logged", "cycles by method", "louver moves", "damper moves",
            "flagged samples", "write failures", "decision time p50 [ms]",
            "decision time p99 [ms]", "calibration updates"]
    rows = [[d.day, _f(d.hours, 1), _methods(d), str(d.louver_moves), str(d.damper_moves),
             str(d.flagged), str(d.write_failures), _f(d.decide_ms_p50, 1),
             _f(d.decide_ms_p99, 1), str(d.calibration_updates)]
            for d in [*k.days, k.total]]
    return _table(head, rows, left=1, total_last=True)


def _heat(report: Report) -> str:
    k = report.kpis
    plant = k.total.heat_plant_kwh is not None
    head = ["day (local)", "model: hours covered"]
    head += [f"model: {label}" for _, label in HEAT_TERMS] + ["model: sum"]
    if plant:
        head += [f"plant: {label.split(' ')[0]}" for _, label in HEAT_TERMS] + ["plant: sum"]
    rows = []
    for d in [*k.days, k.total]:
        row = [d.day, _f(d.heat_model_hours, 1)]
        row += [_f(d.heat_model_kwh.get(t), 3) for t, _ in HEAT_TERMS]
        row.append(_f(sum(d.heat_model_kwh.values()), 3))
        if plant:
            p = d.heat_plant_kwh or {}
            row += [_f(p.get(t), 3) for t, _ in HEAT_TERMS] + [_f(sum(p.values()), 3)]
        rows.append(row)
    return _table(head, rows, left=1, total_last=True)


def _errors(report: Report) -> str:
    k = report.kpis
    h = k.horizon_steps
    head = ["output", "unit", "cycles (1 step)", "model, 1 step", "persistence, 1 step",
            f"cycles ({h} steps)", f"model, {h} steps", f"persistence, {h} steps"]
    rows = []
    for key in (*STATES, "v"):
        e = k.errors.get(key, {})
        scale, unit = (100.0, "cm/s") if key == "v" else (1.0, "K")
        label = "cavity air speed |v|" if key == "v" else key

        def cell(name: str, e=e, scale=scale) -> str:
            v = e.get(name)
            return _f(None if v is None else v * scale, 3)

        rows.append([label, unit, str(int(e.get("h1_cycles", 0))), cell("h1_model_mae"),
                     cell("h1_persistence_mae"),
                     str(int(e["horizon_cycles"])) if "horizon_cycles" in e else "–",
                     cell("horizon_model_mae"), cell("horizon_persistence_mae")])
    return _table(head, rows, left=2)


def _errors_by_regime(report: Report) -> str:
    rows_in = report.kpis.errors_by_regime
    if not rows_in:
        return "<p>No scored cycle.</p>"
    keys = [k for k in (*STATES, "v") if any(k in r["outputs"] for r in rows_in)]
    head = ["regime", "cycles", *(("|v| [cm/s]" if k == "v" else f"{k} [K]") for k in keys)]
    rows = []
    for r in rows_in:
        outs = r["outputs"]
        cycles = max(o["cycles"] for o in outs.values())
        cells = []
        for k in keys:
            o = outs.get(k)
            scale = 100.0 if k == "v" else 1.0
            bias = o["model_mean_error"] * scale if o is not None else math.nan
            cells.append("–" if o is None else
                         f"{_f(o['model_mae'] * scale, 3)} / {_f(o['persistence_mae'] * scale, 3)}"
                         + (f" ({bias:+.2f})" if math.isfinite(bias) else ""))
        label = r["regime"] if isinstance(r["regime"], str) else f"{r['regime']} {r['name']}"
        rows.append([label, str(cycles), *cells])
    return _table(head, rows, left=1)


def _flagged(report: Report) -> str:
    flagged = report.kpis.flagged
    if not flagged:
        return "<p>No sample was flagged.</p>"
    rows = [[s, q, str(n)] for (s, q), n in sorted(flagged.items())]
    return _table(["signal", "quality", "samples"], rows, left=2)


def _bounds(report: Report) -> str:
    k = report.kpis
    p = report.history.parameters
    updates = int((p.source == "online").sum()) if len(p) else 0
    text = (f"<p>{updates} on-line calibration update{'s' if updates != 1 else ''} in this "
            "period.</p>")
    if report.config is None:
        return text + '<p class="note">Bounds unknown: the run stored no configuration and ' \
            "none was given (--config).</p>"
    if not k.at_bound:
        return text + "<p>No parameter sat at a bound.</p>"
    rows = [[b["parameter"], b["bound"], f"{b['value']:g}", _f(b["hours"], 2),
             iso_utc(round(b["first_utc_s"]))] for b in k.at_bound]
    return text + _table(["parameter", "bound", "value", "hours at it", "first (UTC)"], rows,
                         left=2)


def _events(report: Report, limit: int = 40) -> str:
    ev = report.history.events
    if not ev:
        return "<p>No events.</p>"
    rows = [[iso_utc(round(t)), str(run), level, kind, msg] for t, run, level, kind, msg in
            ev[:limit]]
    more = (f"<p class='meta'>… and {len(ev) - limit} more (table <code>events</code>).</p>"
            if len(ev) > limit else "")
    return _table(["time (UTC)", "run", "level", "kind", "message"], rows, left=5) + more


def _runs(report: Report) -> str:
    h = report.history
    rows = []
    for r in h.runs:
        sel = h.run_id == r.run_id
        t = h.time_s[sel]
        rows.append([str(r.run_id), r.mode, r.started_utc, r.ended_utc or "did not end cleanly",
                     r.version, str(int(sel.sum())), iso_utc(round(t[0])),
                     iso_utc(round(t[-1]))])
    return _table(["run", "mode", "started (UTC, wall clock)", "ended (UTC, wall clock)", "dsfd",
                   "cycles shown", "first cycle (UTC)", "last cycle (UTC)"], rows, left=5)


def _commissioning(report: Report) -> str:
    """A link to the newest commissioning record (``dsfd commission``), if there is one."""
    page = report.commissioning
    if page is None:
        return ""
    return (f'<p class="meta">Latest commissioning record: <a href="{page.resolve().as_uri()}">'
            f"{escape(page.name)}</a></p>")


def render_html(report: Report) -> str:
    """The whole page."""
    h, k = report.history, report.kpis
    title = f"dsfd report — panel {escape(h.panel)}"
    first, last = iso_utc(round(h.time_s[0])), iso_utc(round(h.time_s[-1]))
    notes = "".join(f'<p class="note">Note: {escape(n)}</p>' for n in report.notes)
    nav = "".join(f'<li><a href="#{f.fig_id}">{escape(f.title)}</a></li>'
                  for f in report.figures)
    figures = "".join(figure_html(f) for f in report.figures)
    diagnostics = "" if report.diagnostics is None else render_section(report.diagnostics)
    found = None if report.diagnostics is None else len(report.diagnostics.findings)
    diag_nav = "" if found is None else (
        f'<li><a href="#diagnostics">Diagnostics ({found or "no"} finding'
        f'{"" if found == 1 else "s"})</a></li>')
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title><style>{CSS}</style></head>
<body>
<h1>{title}</h1>
<p class="meta">{len(h)} cycles of {k.step_s:g} s from {first} to {last} (UTC; tables and
figures in local standard time {zone_name(k.utc_offset_h)}). State directory
<code>{escape(str(h.path.parent))}</code>; report made {escape(report.made_utc)} by dsfd
{escape(report.version)}.</p>
{notes}{_commissioning(report)}
<nav><ul><li><a href="#kpis">Key figures</a></li>{diag_nav}{nav}</ul></nav>
<h2 id="kpis">Key figures</h2>
<h3>Operation per day</h3>{_operation(report)}
<h3>Heat into the room [kWh]</h3>
<p class="meta">Model: the self-calibrating model's room-side heat for the position applied,
step by step. {"Plant: the simulated truth plant's own integrals." if k.total.heat_plant_kwh
is not None else ""} Positive: into the room. Q_DA is the lighting energy daylight saves.</p>
{_heat(report)}
<h3>Prediction error (mean absolute difference from the reading)</h3>
<p class="meta">One step: the model's prediction from the previous cycle; persistence holds
the last good reading; both on the same cycles. {k.horizon_steps} steps: the horizon-end
prediction with the applied command held on the forecast weather, against the reading then.
</p>
{_errors(report)}
<h4>One step ahead by airflow regime</h4>
<p class="meta">Each cell: model / persistence mean absolute error, and in brackets the
model's mean error (prediction − reading; + the model runs warm or fast). A step counts for the
regime applied over it when the step before had the same; the steps right after a regime
change are a row of their own. A model that loses to persistence in one regime points to what
its lumped form misses there.</p>
{_errors_by_regime(report)}
<h3>Flagged samples by signal and quality</h3>{_flagged(report)}
<h3>Calibration</h3>{_bounds(report)}
{diagnostics}
<h2>Figures</h2>
{figures}
<h2>Runs</h2>{_runs(report)}
<h2>Events</h2>{_events(report)}
</body></html>
"""

