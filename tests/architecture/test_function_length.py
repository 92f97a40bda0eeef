"""No function in dsfd/ longer than 80 lines unless a ``# long:`` comment just above it says
why (issue 23: "no function over ~80 lines without a reason")."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "dsfd"
LIMIT = 80


def long_functions_without_reason(root: Path, limit: int = LIMIT) -> list[str]:
    """``path:line name (n lines)`` of every function over ``limit`` lines (decorators and
    docstring included) whose definition is not preceded, within the three lines above its
    first decorator, by a comment starting ``# long:``."""
    found = []
    for path in sorted(root.rglob("*.py")):
        lines = path.read_text(encoding="utf-8").splitlines()
        for node in ast.walk(ast.parse("\n".join(lines), filename=str(path))):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
            length = node.end_lineno - first + 1
            above = lines[max(0, first - 4):first - 1]
            if length > limit and not any(s.strip().startswith("# long:") for s in above):
                found.append(f"{path.relative_to(root.parent)}:{first} {node.name} "
                             f"({length} lines)")
    return found


def test_no_function_over_80_lines_without_a_reason():
    assert long_functions_without_reason(PACKAGE) == []


def test_the_length_check_finds_a_long_function(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(LIMIT))
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "a.py").write_text(f"def too_long():\n{body}\n")
    (tmp_path / "pkg" / "b.py").write_text(f"# long: a table of constants\ndef fine():\n{body}\n")
    assert long_functions_without_reason(tmp_path / "pkg") == ["pkg/a.py:1 too_long (81 lines)"]
