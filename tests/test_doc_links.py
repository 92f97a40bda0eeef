"""Relative links in the README and docs/*.md lead somewhere: the file exists, and a
``#fragment`` names a heading of it (GitHub's anchor rule: lower case, punctuation other than
``-`` and ``_`` dropped, spaces to ``-``; or an explicit ``<a id="...">``)."""

from __future__ import annotations

import re

from tests.conftest import ROOT

LINK = re.compile(r"\]\(([^)\s]+)\)")
HEADING = re.compile(r"^#{1,6} (.+?)\s*$", re.MULTILINE)


def anchor(heading: str) -> str:
    text = heading.strip().lower().replace("`", "")
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: str) -> set[str]:
    explicit = set(re.findall(r'<a id="([^"]+)"></a>', page))  # docs/model.md's anchors
    return {anchor(h) for h in HEADING.findall(page)} | explicit


def test_every_relative_link_and_anchor_resolves():
    broken = []
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = path.read_text(encoding="utf-8")
        text = re.sub(r"```.*?```", "", text, flags=re.S)  # links in code are not links
        for target in LINK.findall(text):
            if re.match(r"[a-z]+:", target):
                continue  # http(s), mailto
            file, _, fragment = target.partition("#")
            dest = (path.parent / file).resolve() if file else path
            if not dest.exists():
                broken.append(f"{path.name}: {target}: no such file")
            elif fragment and dest.suffix == ".md" and fragment not in anchors(
                    dest.read_text(encoding="utf-8")):
                broken.append(f"{path.name}: {target}: no such heading")
    assert broken == []


def test_the_anchor_rule_matches_githubs_on_known_headings():
    # GitHub's ids for these headings, as its renderer writes them
    assert anchor("The first command: a dry run") == "the-first-command-a-dry-run"
    assert anchor("Commands over MQTT") == "commands-over-mqtt"
    assert anchor("`calibration.min_window_h`") == "calibrationmin_window_h"
