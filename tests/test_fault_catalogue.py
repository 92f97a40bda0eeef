"""docs/faults.md cannot rot: at least 25 fault kinds, each naming tests that exist."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CATALOGUE = ROOT / "docs" / "faults.md"
ROW = re.compile(r"^\| (\d+) \| ([^|]+) \|")
TEST_REF = re.compile(r"`(tests/[\w/]+\.py)::(test_\w+)`")
COLUMNS = ["#", "fault", "detection", "daemon action", "recovery", "test"]


def rows() -> list[tuple[int, str, list[tuple[str, str]], list[str]]]:
    out = []
    for line in CATALOGUE.read_text().splitlines():
        m = ROW.match(line)
        if m:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            out.append((int(m.group(1)), m.group(2).strip(), TEST_REF.findall(line), cells))
    return out


def defined_tests(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    return {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}


def test_the_catalogue_lists_at_least_25_fault_kinds_each_with_its_test() -> None:
    found = rows()
    assert len(found) >= 25
    assert [n for n, *_ in found] == list(range(1, len(found) + 1))
    assert len({name for _, name, *_ in found}) == len(found)  # one row per kind
    headers = [line for line in CATALOGUE.read_text().splitlines() if line.startswith("| # |")]
    assert headers and all([c.strip() for c in h.strip("|").split("|")] == COLUMNS
                           for h in headers)
    for number, name, refs, cells in found:
        assert len(cells) == len(COLUMNS), (number, name)
        assert all(cells), (number, name)  # detection, action, recovery, test: all said
        assert refs, f"fault {number} ({name}) names no test"


def test_every_named_test_exists() -> None:
    missing = []
    for number, name, refs, _ in rows():
        for path, func in refs:
            file = ROOT / path
            if not file.exists() or func not in defined_tests(file):
                missing.append(f"{number} {name}: {path}::{func}")
    assert not missing, missing
