"""``dsfd report``: what a controller did, from its own log, as one self-contained HTML page.

The report reads a state directory's database (:func:`dsfd.storage.history.read_history`,
read-only: the daemon may be running) and never sits on the control cycle's path.
:func:`build_report` computes the key figures (:mod:`dsfd.report.kpis`) and draws the
figures (:mod:`dsfd.report.figures`, matplotlib's Agg canvas); :func:`render_html` makes
the page; :mod:`dsfd.report.diagnostics` lists the daemon's findings of the period with a
figure of each one's evidence. matplotlib is the optional extra ``dsfd[report]``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dsfd.report.kpis import Kpis, compute_kpis, prediction_errors, report_step_s
from dsfd.storage.history import History
from dsfd.storage.schema import iso_now

if TYPE_CHECKING:
    from dsfd.config.panel import PanelConfig
    from dsfd.report.diagnostics import Diagnostics
    from dsfd.report.figures import ReportFigure

__all__ = ["INSTALL_HINT", "Report", "ReportUnavailableError", "build_report", "render_html",
           "write_report"]

INSTALL_HINT = "pip install 'dsfd[report]'"


class ReportUnavailableError(RuntimeError):
    """matplotlib is not installed (the message names the pip install)."""


@dataclass(frozen=True, eq=False)
class Report:
    """The key figures, the figures and what they were made from."""

    history: History
    config: Mapping[str, Any] | None
    kpis: Kpis
    figures: list[ReportFigure]
    notes: tuple[str, ...]
    made_utc: str
    version: str
    #: The newest ``dsfd commission`` page in the state directory, if any.
    commissioning: Path | None = None
    #: The findings of the period and their figures (None: not built).
    diagnostics: Diagnostics | None = None


def _config(history: History, panel: PanelConfig | None) -> tuple[Mapping[str, Any] | None,
                                                                   list[str]]:
    """The configuration to report against: the run's own, else the given panel file."""
    if history.config is not None:
        return history.config, []
    if panel is not None:
        return dataclasses.asdict(panel), ["the database stores no configuration of its runs "
                                           "(older dsfd): using the given panel file"]
    return None, ["no configuration stored with the runs and none given (--config): no "
                  "site (sky conditions, solar elevation) and no parameter bounds"]


def build_report(history: History, *, panel: PanelConfig | None = None, dpi: int = 90
                 ) -> Report:
    """Key figures and figures of ``history``.

    Raises
    ------
    ReportUnavailableError
        matplotlib is missing.
    """
    try:
        from dsfd.report.figures import draw_figures
    except ImportError as exc:
        raise ReportUnavailableError(
            f"dsfd report needs matplotlib ({exc}): {INSTALL_HINT}") from None
    from dsfd import __version__

    config, notes = _config(history, panel)
    errors = prediction_errors(history, report_step_s(history, config))
    kpis = compute_kpis(history, config, errors)
    figures = draw_figures(history, kpis, errors, config, dpi=dpi)
    from dsfd.commission.record import latest_record
    from dsfd.report.diagnostics import build_diagnostics

    diagnostics = build_diagnostics(history, config, offset_h=kpis.utc_offset_h, dpi=dpi)
    return Report(history, config, kpis, figures, (*history.notes, *notes), iso_now(),
                  __version__, latest_record(history.path.parent), diagnostics)


def render_html(report: Report) -> str:
    """The page (:mod:`dsfd.report.html`)."""
    from dsfd.report.html import render_html as render

    return render(report)


def write_report(report: Report, out: Path) -> None:
    """Write the page atomically."""
    from dsfd.storage.atomic import write_text_atomic

    write_text_atomic(Path(out), render_html(report))
