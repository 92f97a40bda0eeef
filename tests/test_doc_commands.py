"""Every shell block of the README and docs/*.md runs as written, or says why it cannot.

A fenced block tagged ``sh``, ``bash`` or ``shell`` is run with ``bash -euo pipefail`` in a
fresh directory that holds the repository's ``config/`` and ``systemd/`` (the blocks name
``config/panels/...`` as a reader in the checkout would), with the environment's ``dsfd``
on PATH; it must exit 0 and leave every file it names after ``--out``, ``--json`` or
``--report``. What the test changes is fixed and written down here:

* ``.venv/bin/X`` is the ``X`` of the test's environment, and the installation steps
  (``python3 -m venv .venv && .venv/bin/pip install -q ... &&`` and a ``.venv/bin/pip
  install`` line) are left out: the environment is installed already.
* A Markdown comment on the line before a block changes what happens to it:

  ``<!-- doc-test: skip: REASON -->``
      not run; REASON must be one of :data:`SKIP_REASONS` (hardware, root, systemd, a
      broker elsewhere, or the test suite itself);
  ``<!-- doc-test: replace "OLD" "NEW"; ... -->``
      run with each OLD replaced by NEW (a shorter run: fewer cycles or hours; every
      replacement must match);
  ``<!-- doc-test: after a dry run -->``
      run where a 5-cycle dry run of suwon-south left its database (the state directory is
      the block's directory), for the ``sqlite3`` examples.

  The README's first two blocks carry no comment, so that they stay the first lines a
  reader sees: :data:`README_TOP` gives their treatment.

The test fails on a shell block that is neither run nor marked, and on a marker that is
unknown or that no block follows.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.conftest import ROOT

SHELLS = {"sh", "bash", "shell"}
#: Why a block may not run in CI (nothing else is an acceptable reason).
SKIP_REASONS = {
    "needs root and systemd",
    "needs root and a running service",
    "needs the site's MQTT broker",
    "needs three panels on a broker",
    "the test suite itself",
    "needs the panel's devices",
    "takes hours of CPU (the plant oracle)",
    "takes hours of CPU (six cases, four runs each)",
}
#: The README's first two blocks (no marker line above them; see the module docstring).
README_TOP = ('replace "--cycles 540" "--cycles 20"', "skip: the test suite itself")
MARKER = re.compile(r"^<!-- doc-test: (.*) -->$")
FENCE = re.compile(r"^```(\S*)\s*$")
BIN = Path(sys.executable).parent


@dataclass(frozen=True)
class Block:
    page: str
    line: int  # of the opening fence, 1-based
    text: str
    marker: str | None

    @property
    def name(self) -> str:
        return f"{self.page}:{self.line}"


def _pages() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def shell_blocks(path: Path) -> tuple[list[Block], list[str]]:
    """The shell blocks of one page, and the problems of its markers."""
    lines = path.read_text(encoding="utf-8").splitlines()
    page = str(path.relative_to(ROOT))
    blocks: list[Block] = []
    problems: list[str] = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            if MARKER.match(lines[i]) and not (i + 1 < len(lines) and FENCE.match(lines[i + 1])
                                               and FENCE.match(lines[i + 1]).group(1)):
                problems.append(f"{page}:{i + 1}: a doc-test marker without a block after it")
            i += 1
            continue
        end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith("```"))
        if m.group(1) in SHELLS:
            above = MARKER.match(lines[i - 1]) if i else None
            blocks.append(Block(page, i + 1, "\n".join(lines[i + 1:end]) + "\n",
                                above.group(1) if above else None))
        i = end + 1
    if page == "README.md":
        blocks[:2] = [Block(b.page, b.line, b.text, README_TOP[k]) for k, b in
                      enumerate(blocks[:2])]
    return blocks, problems


ALL = [b for p in _pages() for b in shell_blocks(p)[0]]
#: The blocks to run, a block repeated word for word on another page once (the first).
_FIRST: dict[tuple[str, str | None], Block] = {}
for _b in ALL:
    if not (_b.marker or "").startswith("skip:"):
        _FIRST.setdefault((_b.text, _b.marker), _b)
TO_RUN = list(_FIRST.values())
_INSTALL = re.compile(r"python3 -m venv \.venv && \.venv/bin/pip install -q \S+ && ")


def _prepared(block: Block) -> str:
    """The block as the test runs it (see the module docstring)."""
    text = _INSTALL.sub("", block.text)
    text = "\n".join(ln for ln in text.splitlines()
                     if not ln.startswith(".venv/bin/pip install")) + "\n"
    for old, new in re.findall(r'replace "([^"]*)" "([^"]*)"', block.marker or ""):
        assert old in text, f"{block.name}: replace {old!r}: not in the block"
        text = text.replace(old, new)
    return text.replace(".venv/bin/", f"{BIN}/")


def test_every_shell_block_is_run_or_marked_with_a_known_reason():
    problems = [p for page in _pages() for p in shell_blocks(page)[1]]
    for b in ALL:
        marker = b.marker or ""
        if marker.startswith("skip:"):
            if marker[len("skip:"):].strip() not in SKIP_REASONS:
                problems.append(f"{b.name}: unknown reason to skip: {marker!r}")
        elif marker and not re.fullmatch(r'(replace "[^"]*" "[^"]*"(; )?|after a dry run(; )?)+',
                                         marker):
            problems.append(f"{b.name}: unknown doc-test marker {marker!r}")
    assert problems == []
    assert {b.page for b in TO_RUN} >= {"README.md", "docs/operating.md", "docs/benchmarks.md",
                                        "docs/configuration.md", "docs/storage-schema.md"}


def _dry_run_into(directory: Path) -> None:
    subprocess.run([sys.executable, "-m", "dsfd", "run", "--config",
                    "config/panels/suwon-south.yaml", "--dry-run", "--plant", "sim",
                    "--plant-fidelity", "lumped", "--start", "2022-01-01T23:00:00Z",
                    "--cycles", "5", "--state-dir", "."], cwd=directory, check=True,
                   capture_output=True, timeout=300)


def _named_outputs(script: str) -> list[str]:
    words = shlex.split(script.replace("\\\n", " "), comments=True)
    return [words[i + 1] for i, w in enumerate(words[:-1])
            if w in ("--out", "--json", "--report") and "$" not in words[i + 1]]


@pytest.mark.parametrize("block", TO_RUN, ids=lambda b: b.name)
def test_the_shell_block_runs(block, tmp_path):
    for name in ("config", "systemd"):
        (tmp_path / name).symlink_to(ROOT / name)
    if "after a dry run" in (block.marker or ""):
        _dry_run_into(tmp_path)
    script = _prepared(block)
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    done = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=900)  # hang guard
    assert done.returncode == 0, f"{block.name}\n{script}\n{done.stdout[-3000:]}\n{done.stderr}"
    missing = [p for p in _named_outputs(script) if not (tmp_path / p).exists()]
    assert missing == [], block.name
