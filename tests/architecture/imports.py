"""The package import graph of dsfd, read from the source with :mod:`ast` (no imports run).

A *package* is the first component under ``dsfd`` (``dsfd.physics.model`` → ``physics``;
a top-level module such as ``dsfd/signals.py`` is its own package). Imports under
``if TYPE_CHECKING:`` are left out: they never run.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2] / "dsfd"


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def package_of(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "dsfd"


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                skip.update(id(n) for n in ast.walk(child))
    return skip


def imported_modules(path: Path) -> set[str]:
    """Every ``dsfd…`` module that ``path`` imports at run time (any depth in the file)."""
    tree = ast.parse(path.read_text(), str(path))
    skip = _type_checking_nodes(tree)
    me = module_name(path)
    out: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("dsfd"))
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against this module's package
                base = me.split(".")
                base = base[: len(base) - node.level + (path.name == "__init__.py")]
                mod = ".".join([*base, node.module] if node.module else base)
            else:
                mod = node.module or ""
            if mod.startswith("dsfd"):
                out.add(mod)
                out.update(f"{mod}.{a.name}" for a in node.names)
    return out


def module_graph() -> dict[str, set[str]]:
    """Module → the dsfd modules it imports (only names that are modules of the tree)."""
    files = {module_name(p): p for p in ROOT.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for mod, path in files.items():
        graph[mod] = {m for m in imported_modules(path) if m in files and m != mod}
    return graph


def package_graph() -> dict[str, set[str]]:
    """Package → the packages it imports (self-edges dropped)."""
    edges: dict[str, set[str]] = defaultdict(set)
    for mod, deps in module_graph().items():
        a = package_of(mod)
        edges[a].update(b for b in map(package_of, deps) if b != a and b != "dsfd")
    return dict(edges)


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


if __name__ == "__main__":
    g = package_graph()
    for a in sorted(g):
        print(f"{a:12s} -> {', '.join(sorted(g[a]))}")
    print("cycles:", cycles(g))
