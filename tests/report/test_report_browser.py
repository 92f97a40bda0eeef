"""The report of a short dry run, rendered by a real browser (headless Chromium)."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest

from dsfd.report.figures import FIGURES

CHROMIUM = next((p for p in map(shutil.which, ("chromium", "chromium-browser",
                                               "google-chrome")) if p), None)


def chromium(profile, *args: str) -> str:
    """Headless Chromium with the flags this machine's closed network needs; its stdout."""
    return subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
         "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", f"--user-data-dir={profile}", *args],
        check=True, capture_output=True, text=True, timeout=180).stdout


def screenshot(html_uri: str, out, profile, *, height: int) -> None:
    chromium(profile, f"--screenshot={out}", f"--window-size=1400,{height}", html_uri)


#: Appended to a copy of the report (the report itself has no script): after the page's load
#: event, the ids of the figures whose image the browser decoded, with its pixel width.
DECODED_PROBE = ("<script>addEventListener('load', () => { document.body.dataset.decoded = "
                 "[...document.images].filter(i => i.complete && i.naturalWidth > 0)"
                 ".map(i => i.closest('figure').id + ':' + i.naturalWidth).join(' '); })"
                 "</script>")


def test_the_report_is_one_self_contained_file_with_every_figure(faulted_run):
    html = faulted_run.html.read_text()
    for fig_id, *_ in FIGURES:
        assert html.count(f'<figure id="{fig_id}">') == 1, fig_id
    assert html.count("<img ") == len(FIGURES) == 7
    # Nothing to fetch: every src is inline data, every link an anchor in the page.
    assert re.findall(r'(?:src|href)="(?!data:image/png;base64,|#)', html) == []
    assert "<script" not in html and "http://" not in html and "https://" not in html
    for heading in ("Operation per day", "Heat into the room [kWh]", "Prediction error",
                    "Flagged samples by signal and quality", "Calibration"):
        assert heading in html


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium installed (Debian package "
                    "'chromium'; .ci/run installs it)")
def test_the_report_renders_in_headless_chromium(faulted_run, tmp_path):
    from PIL import Image

    shot, profile = tmp_path / "report.png", tmp_path / "profile"
    profile.mkdir()
    screenshot(faulted_run.html.as_uri(), shot, profile, height=7200)
    rgb = np.asarray(Image.open(shot).convert("RGB"), float)
    assert rgb.shape == (7200, 1400, 3)
    ink = rgb.min(axis=2) < 200  # anything darker than a light grey
    assert ink.mean() > 0.02, "the page is (nearly) blank"
    # The page's own colour is a few lines of blue links; the rest is the figures' lines and
    # bars: well over a thousand coloured rows mean the embedded PNGs were decoded and drawn
    # (a broken image is a small grey icon).
    saturation = rgb.max(axis=2) - rgb.min(axis=2)
    coloured_rows = (saturation > 80).sum(axis=1) > 3
    assert coloured_rows.sum() > 1200, "figures not drawn"
    # ... in every part of the figure section, not only at the top.
    first = int(np.argmax(coloured_rows))
    bands = np.array_split(coloured_rows[first:], 5)
    assert all(b.any() for b in bands)


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium installed (Debian package "
                    "'chromium'; .ci/run installs it)")
def test_chromium_decodes_every_figure_of_the_report(faulted_run, tmp_path):
    """Every figure's embedded PNG is decoded by the browser (a broken image has no natural
    width), read from the DOM Chromium serialises after the page's load event."""
    html = faulted_run.html.read_text()
    probed = tmp_path / "probed.html"
    probed.write_text(html.replace("</body>", DECODED_PROBE + "</body>"))
    profile = tmp_path / "profile"
    profile.mkdir()
    dom = chromium(profile, "--dump-dom", probed.as_uri())
    (decoded,) = re.findall(r'<body[^>]*data-decoded="([^"]*)"', dom)
    widths = dict(item.split(":") for item in decoded.split())
    assert sorted(widths) == sorted(fig_id for fig_id, *_ in FIGURES)
    assert all(int(w) >= 300 for w in widths.values()), widths
