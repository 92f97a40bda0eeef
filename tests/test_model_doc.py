"""docs/model.md is the model's documentation, and the code cites it instead of outside notes.

* No file under ``dsfd/`` cites the former external design notes (``physics §…``,
  ``physics.md``, ``errata E…``, or their bare ``§N.N`` / ``E19.2`` items).
* Every ``docs/model.md#anchor`` cited under ``dsfd/`` is an anchor of docs/model.md.
* The document keeps its core sections, and two of its tables agree with the code: the
  regime → damper table with ``REGIME_OPENINGS`` and the parameter table with the Suwon
  panel file.
"""

# modeldoc-citations: skip (this file quotes the old citations it guards against)
from __future__ import annotations

import re
from pathlib import Path

import pytest

from dsfd.config.panel import PARAMETER_NAMES, REGIME_OPENINGS

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "model.md"
PACKAGE = ROOT / "dsfd"

#: Citations of the external notes, in any letter case.
OLD_CITATION = re.compile(r"errata E|physics(\.md)? ?§|physics\.md", re.IGNORECASE)
#: A bare errata item (E1 … E20, E19.2) standing alone as a word.
BARE_ERRATUM = re.compile(r"(?<![\w.#/-])E\d{1,2}(\.\d{1,2})?(?![\w])")
#: A bare section sign, and what may precede one that cites another document.
BARE_SECTION = re.compile(r"§\s?\d")
OTHER_DOCUMENT = re.compile(
    r"(ISO\s?\d+(?::\d{4})?|ecosystem notes|\d{4},|ed\.,)\s*$")
CITED_ANCHOR = re.compile(r"docs/model\.md#([A-Za-z0-9_-]+)")
#: Sections the document must keep (the issue's list: states, regimes, network, airflow,
#: optics, parameters, calibration and control objectives, departures from the paper).
CORE = ("states", "regimes", "network", "airflow", "optics", "parameters",
        "calibration-objective", "control-objective", "truth-plant", "departures")


def _doc() -> str:
    return DOC.read_text(encoding="utf-8")


def _anchors(text: str) -> list[str]:
    return re.findall(r'<a id="([^"]+)"></a>', text)


def _sources() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def test_the_package_is_there():
    # guards the scans below against passing vacuously on a moved package
    assert len(_sources()) > 50


def test_no_citation_of_the_external_notes():
    found = []
    for path in _sources():
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            where = f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
            if OLD_CITATION.search(line) or BARE_ERRATUM.search(line):
                found.append(where)
            for m in BARE_SECTION.finditer(line):
                if not OTHER_DOCUMENT.search(line[:m.start()]):
                    found.append(where)
    assert not found, "cite docs/model.md#<anchor> instead:\n" + "\n".join(found)


def test_the_scan_catches_old_citations():
    # the patterns above are what keeps the package clean: make sure they can fire
    for old in ("(physics §8.3 with errata E1)", "Physics §8.3", "physics.md §5.4",
                "see Errata E19.2"):
        assert OLD_CITATION.search(old), old
    assert BARE_ERRATUM.search("exact step average (E8)")
    assert BARE_SECTION.search("(§5.2)") and not OTHER_DOCUMENT.search("(")
    assert OTHER_DOCUMENT.search("ISO 15099:2003 ")
    for fine in ("docs/model.md#zoh", "1E10", "E+ ER", "ε_L E_4", "nE2"):
        assert not BARE_ERRATUM.search(fine), fine


def test_cited_anchors_exist():
    anchors = set(_anchors(_doc()))
    cited: dict[str, list[str]] = {}
    for path in _sources():
        for name in CITED_ANCHOR.findall(path.read_text(encoding="utf-8")):
            cited.setdefault(name, []).append(str(path.relative_to(ROOT)))
    assert cited, "no docs/model.md citations found under dsfd/"
    missing = {name: files for name, files in cited.items() if name not in anchors}
    assert not missing, f"anchors cited but not in docs/model.md: {missing}"


def test_anchors_are_unique_lowercase_and_head_a_section():
    text = _doc()
    anchors = _anchors(text)
    assert len(anchors) == len(set(anchors)), "duplicate anchors"
    for name in anchors:
        assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", name), name
        # an anchor sits on its own line right above a heading
        assert re.search(rf'<a id="{name}"></a>\n#{{2,4}} \S', text), name
    links = set(re.findall(r"\]\(#([^)]+)\)", text))
    assert links <= set(anchors), f"links to missing anchors: {links - set(anchors)}"


def _section(name: str) -> str:
    """The text of a section with its subsections (up to the next heading of its level)."""
    text = _doc()
    start = text.index(f'<a id="{name}"></a>')
    level = len(re.match(r'<a id="[^"]+"></a>\n(#+)', text[start:]).group(1))
    nxt = re.compile(rf'<a id="[^"]+"></a>\n#{{2,{level}}} ')
    m = nxt.search(text, start + 1)
    return text[start:m.start() if m else len(text)]


@pytest.mark.parametrize("name", CORE)
def test_core_section_is_present(name):
    assert name in _anchors(_doc())
    assert len(_section(name).split()) > 150, f"section {name} is nearly empty"


def test_regime_table_matches_the_damper_sets():
    short = {"exterior_bottom": "EB", "exterior_top": "ET", "interior_bottom": "IB",
             "interior_top": "IT"}
    rows = {}
    for m in re.finditer(r"^\| (\d+) \| ([^|]+) \|", _section("regimes"), re.M):
        cell = m.group(2).strip()
        rows[int(m.group(1))] = (set() if cell == "none" else
                                 {"EB", "ET", "IB", "IT"} if cell == "all four" else
                                 {d.strip() for d in cell.split("+")})
    assert set(rows) == set(range(1, 11))
    for regime, opening in REGIME_OPENINGS.items():
        assert rows[regime] == {short[o] for o in opening}, regime


def test_parameter_table_matches_the_suwon_panel():
    yaml = pytest.importorskip("yaml")
    panel = yaml.safe_load((ROOT / "config" / "panels" / "suwon-south.yaml").read_text())
    table = {}
    for line in _section("parameters").splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) >= 5 and cells[0] in PARAMETER_NAMES:
            table[cells[0]] = tuple(float(c.replace(" ", "")) for c in cells[2:5])
    assert set(table) == set(PARAMETER_NAMES)
    for name in PARAMETER_NAMES:
        p = panel["parameters"][name]
        assert table[name] == (p["default"], p["lower"], p["upper"]), name
