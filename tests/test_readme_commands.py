"""The command table of docs/operating.md (moved there from the README) lists every ``dsfd``
subcommand, each with what it does."""

from __future__ import annotations

import argparse
import re

from dsfd.cli import build_parser
from tests.conftest import ROOT

ROW = re.compile(r"^\| `dsfd ([a-z-]+)[^`]*` \| (.*) \|$")


def subcommands() -> set[str]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return set(sub.choices)


def table_rows() -> list[tuple[str, str]]:
    text = (ROOT / "docs" / "operating.md").read_text(encoding="utf-8")
    section = text[text.index("\n## Commands\n"):]
    section = section[:section.index("\n## ", 1)]
    return [(m.group(1), m.group(2)) for line in section.splitlines()
            if (m := ROW.match(line))]


def test_every_subcommand_has_a_row_saying_what_it_does():
    rows = table_rows()
    listed = {name for name, _ in rows}
    assert subcommands() - listed == set()  # every command of `dsfd --help` is there
    assert listed - subcommands() == set()  # and nothing that is not a command
    assert all(len(what.split()) >= 4 for _, what in rows), rows
