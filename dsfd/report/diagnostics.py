"""The report's Diagnostics section: the findings of the reported period and their evidence.

Every finding the daemon stored (table ``findings``, docs/model.md#findings) whose evidence
overlaps the period is listed: open, acknowledged or ended, with its evidence. The first
:data:`MAX_FIGURES` (open ones first, then the most recently detected) get a figure of that
evidence (:mod:`dsfd.report.finding_figures`); the rest are listed, so a long log with many
findings stays readable. With none, the section says so in one line, with the history each
detector needs before it judges.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from html import escape
from typing import Any

from dsfd.estimation.crosschecks import FlowCheckSettings
from dsfd.estimation.daylight_split import told_by_daylight
from dsfd.measured import iso_utc
from dsfd.report.plotting import ReportFigure, figure_html, png
from dsfd.storage.evidence import NIGHT_MIN_S, NIGHT_OFFSET_MIN_S, RESIDUAL_MIN_S
from dsfd.storage.findings import findings_between, first_signal
from dsfd.storage.history import History
from dsfd.storage.parameter_series import PARAMETER_MIN_DAYS
from dsfd.storage.queries import open_read_only

__all__ = ["MAX_FIGURES", "Diagnostics", "build_diagnostics", "render_section"]

#: Findings drawn at most; the others are listed without a figure.
MAX_FIGURES = 6
_STATE_ORDER = {"open": 0, "acknowledged": 1, "ended": 2}
#: Kinds whose statistic is a CUSUM in standardised units (the others: the signal's unit).
_CUSUM_KINDS = frozenset({"residual_shift", "parameter_shift", "pane_offset_shift",
                          "night_offset_shift", "solar_gain_shift"})


@dataclass(frozen=True)
class Diagnostics:
    """The findings of the period (rows of :func:`dsfd.storage.findings.findings_between`),
    the figures drawn (by finding id) and why a finding has none."""

    findings: list[dict[str, Any]]
    figures: dict[int, ReportFigure] = field(default_factory=dict)
    no_figure: dict[int, str] = field(default_factory=dict)
    #: The one line shown when there is no finding.
    empty: str = ""


def _span(seconds: float) -> str:
    return f"{seconds / 86400:.1f} days" if seconds >= 2 * 86400 else f"{seconds / 3600:.1f} h"


def _none_line(history: History) -> str:
    span = float(history.time_s[-1] - history.time_s[0]) if len(history) else 0.0
    if history.schema_version < 7:
        return (f"No findings: this database (schema {history.schema_version}) predates the "
                "daemon's diagnostics (schema 7).")
    if history.runs and all(r.mode.startswith("closed-loop simulation") for r in history.runs):
        return ("No findings: a closed-loop simulation (dsfd simulate) does not run the "
                "daemon's detectors; dsfd run does, also as a dry run.")
    return (f"No findings in this period. The cavity cross-check judges a damper set once it "
            f"has {FlowCheckSettings().min_samples} readings in the last day; the prediction-"
            f"error CUSUM needs {RESIDUAL_MIN_S / 86400:g} days of stored history, the night "
            f"pane check {NIGHT_MIN_S / 86400:g} days, the night offsets "
            f"{NIGHT_OFFSET_MIN_S / 86400:g} days, the parameter detector "
            f"{PARAMETER_MIN_DAYS} days of on-line estimates (this log spans {_span(span)}).")


def _priority(row: Mapping[str, Any]) -> tuple[int, float]:
    return _STATE_ORDER.get(str(row["state"]), 3), -float(row.get("detected_s") or 0.0)


def build_diagnostics(history: History, config: Mapping[str, Any] | None, *, offset_h: float,
                      dpi: int) -> Diagnostics:
    """Read the findings of ``history``'s period and draw the first :data:`MAX_FIGURES`."""
    from dsfd.report.finding_figures import evidence_figure

    if not len(history):
        return Diagnostics([], empty=_none_line(history))
    conn = open_read_only(history.path)
    try:
        rows = findings_between(conn, float(history.time_s[0]), float(history.time_s[-1]))
        if not rows:
            return Diagnostics([], empty=_none_line(history))
        figures: dict[int, ReportFigure] = {}
        no_figure: dict[int, str] = {}
        for row in sorted(rows, key=_priority):
            fid = int(row["finding_id"])
            if len(figures) >= MAX_FIGURES:
                no_figure[fid] = f"not drawn: the report draws at most {MAX_FIGURES}"
                continue
            fig = evidence_figure(conn, row, offset_h=offset_h, config=config,
                                  state_dir=history.path.parent)
            if isinstance(fig, str):
                no_figure[fid] = fig
                continue
            figures[fid] = ReportFigure(f"finding-{fid}", _title(row), _caption(row),
                                        png(fig, dpi))
    finally:
        conn.close()
    return Diagnostics(rows, figures, no_figure)


def _title(row: Mapping[str, Any]) -> str:
    subject = f" ({row['subject']})" if row.get("subject") else ""
    return f"Finding #{row['finding_id']}: {row['kind']}{subject}, {row['state']}"


def _caption(row: Mapping[str, Any]) -> str:
    kind = str(row["kind"])
    if kind == "residual_shift":
        what = ("The stored readings minus the model's one-step predictions, averaged in "
                "10-min blocks, against the detector's reference (the median at the same time "
                "of day on the 5 previous days); below, Page's CUSUM of the standardised "
                "blocks, recomputed from the stored rows, against its threshold.")
    elif kind in ("pane_out_of_bounds", "pane_offset_shift"):
        what = ("The pane minus the outdoor air in the nights the latest check judged (the sun "
                "6° below the horizon and below it 2 h before) and their nightly medians, "
                + ("with the bounds a pane between the sky and the room keeps to."
                   if kind == "pane_out_of_bounds" else
                   "with the median of the nights before the start it is judged against."))
    elif kind == "night_offset_shift":
        what = ("The node's heat-flux offset as the calibration estimated it at night (the "
                "sun 6° below the horizon and below it 2 h before), in hourly block means "
                "against the detector's reference (the median at the same time of night on the "
                "5 previous days); below, Page's CUSUM of the standardised blocks, recomputed "
                "from the stored rows, against its threshold. At night no sun moves the "
                "offset: a sensor that reads off does.")
    elif told_by_daylight(kind, first_signal(row)):
        what = ("The calibrated coefficient's on-line estimates and daily values ± posterior "
                "sd, apart for the calibration windows that were all night and those that "
                "saw the sun, each with its level before the start. A property of air and "
                "glass moves by night as by day; a change in the sunlit windows alone is "
                "the sun the façade takes (dirt on the glass, or slats at another angle than "
                "their read-back).")
    elif kind == "solar_gain_shift":
        what = ("Per day, the least-squares share of the sun the model computes from the "
                "clean façade's optics that the calibration's heat-flux offsets remove "
                "(Σ q·S / Σ S² over the steps with the slats in the sun; negative: the façade "
                "takes less sun than computed) ± its standard error, recomputed from the "
                "stored weather, commands and offsets, and the same share for the exterior "
                "pane and the slats alone. Dirt on the glass lowers both; slats at another "
                "angle than their read-back lower or raise the slats' alone.")
    elif kind == "parameter_shift":
        what = ("Each on-line estimate of the parameter and the daily values the detector "
                "judges (the precision-weighted mean of the day's estimates) ± the posterior "
                "sd stored with them (a heat-flux offset q_x: the fixed sd it is given), "
                "against the level of the days before the start; the detector's spread adds "
                "the day-to-day wander of those days. An energy at stake in the evidence is "
                "the model's J over the last week with the parameter before and now (not "
                "for an offset, which names a sensor first).")
    else:
        what = ("Each reading of the cavity speed with the dampers the command in force "
                "during that step opened (the day the latest check judged), and the commanded "
                "regime and opening; an open path must move more air than the threshold, "
                "judged on its latest 15 readings. A cross-check's start is the first of the "
                "readings of a dead path it judged, which can precede the fault.")
    return f"{what} Marked: the finding's start and detection as stored."


# --------------------------------------------------------------------------------- HTML
def _time(t: float | None) -> str:
    """UTC to the minute (the cycles are a minute or more apart)."""
    return "–" if t is None else iso_utc(round(float(t)))[:16].replace("T", " ")


def _num(v: float | None, unit: str = "") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    return f"{v:.3g}" + (f" {unit}" if unit else "")


def _head(head: Sequence[str], classes: Sequence[str]) -> str:
    return ("<thead><tr>" + "".join(f'<th class="{c}">{escape(h)}</th>'
                                    for h, c in zip(head, classes, strict=True))
            + "</tr></thead>")


def _row(values: Sequence[str], classes: Sequence[str]) -> str:
    return "<tr>" + "".join(f'<td class="{c}">{escape(v)}</td>'
                            for v, c in zip(values, classes, strict=True)) + "</tr>"


def _closed(r: Mapping[str, Any]) -> str:
    if r.get("ended_s") is None:
        return "–"
    return f"{_time(r['ended_s'])}: {r.get('end_reason') or r['state']}"


def _findings_table(d: Diagnostics) -> str:
    """One row per finding, and under it the suggested action across the table (long
    sentences in a narrow column make a tall, unreadable table)."""
    head = ["finding", "kind", "subject", "state", "confidence", "start (UTC)",
            "detected (UTC)", "closed (UTC), why"]
    # l: left-aligned, t: a time kept on one line
    classes = ["l", "l", "l", "l", "", "l t", "l t", "l"]
    out = ["<table>", _head(head, classes), "<tbody>"]
    for r in d.findings:
        out.append(_row([f"#{r['finding_id']}", str(r["kind"]), str(r.get("subject") or "–"),
                         str(r["state"]), _num(r.get("confidence")), _time(r.get("start_s")),
                         _time(r.get("detected_s")), _closed(r)], classes))
        out.append(f'<tr class="action"><td class="l" colspan="{len(head)}">suggested action: '
                   f'{escape(str(r.get("action") or "–"))}</td></tr>')
    out.append("</tbody></table>")
    return "".join(out)


def _evidence_table(d: Diagnostics) -> str:
    classes = ["l", "l", "", "", "l t", "", ""]
    rows = []
    for r in d.findings:
        for e in r.get("evidence") or []:
            unit = str(e.get("unit") or "")
            stat_unit = "sd" if r["kind"] in _CUSUM_KINDS else unit
            rows.append(_row([f"#{r['finding_id']}", str(e.get("signal", "")),
                              _num(e.get("shift"), unit), _num(e.get("shift_sd")),
                              _time(e.get("since_s")), _num(e.get("statistic"), stat_unit),
                              _num(e.get("threshold"), stat_unit)], classes))
    return ("<table>" + _head(["finding", "signal", "shift", "shift [sd]", "since (UTC)",
                               "statistic", "threshold"], classes)
            + f"<tbody>{''.join(rows)}</tbody></table>")


def render_section(d: Diagnostics) -> str:
    """The section's HTML (its heading included)."""
    head = '<h2 id="diagnostics">Diagnostics</h2>'
    if not d.findings:
        return f'{head}<p>{escape(d.empty)}</p>'
    n = len(d.findings)
    intro = (f"<p class=\"meta\">{n} finding{'s' if n != 1 else ''} of the daemon's detectors "
             "(docs/model.md#findings) whose evidence overlaps this period: open, "
             "acknowledged by an operator (<code>dsfd ack</code>) or ended when the evidence "
             "went away. Confidence is how far past its threshold the evidence is (0.5 at "
             "it), not a probability. Shift: the change in the signal's unit and in units of "
             "its reference spread; statistic against the threshold it crossed.</p>")
    listed = "".join(f"<li>#{fid}: {escape(why)}</li>" for fid, why in sorted(d.no_figure.items()))
    rest = f'<p class="meta">Without a figure:</p><ul class="meta">{listed}</ul>' \
        if listed else ""
    return (f"{head}{intro}{_findings_table(d)}<h3>Evidence</h3>{_evidence_table(d)}"
            + "".join(figure_html(f) for f in d.figures.values()) + rest)
