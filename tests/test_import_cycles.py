"""No import cycles among ogcp's modules, package ``__init__`` files included.

``lint-imports`` (pyproject's contracts) forbids cycles between the sibling modules and
subpackages of every package, following every import. It does not see a module that imports its
own package's ``__init__`` while that ``__init__`` re-exports from it, the cycle that makes
``import ogcp.planner.x`` fail on a partially initialised module. This test builds the graph of the
imports that run when a module is imported (module level, class bodies, ``try``/``if`` blocks)
and requires it to be acyclic. Imports inside functions are deliberately lazy (heavy or optional
dependencies, the CLI's matplotlib): they run once every module is initialised, so they cannot
fail that way, and cycles through them across packages are still caught by ``lint-imports``.
``if TYPE_CHECKING:`` blocks never run.
"""

from __future__ import annotations

import ast
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("ogcp",)


def _modules(root: Path, packages: tuple[str, ...]) -> dict[str, Path]:
    found = {}
    for package in packages:
        # ogcp/ links to the top-level folders: walk through the links, as the import system does.
        for folder, _, files in os.walk(root / package, followlinks=True):
            for path in (Path(folder) / name for name in files if name.endswith(".py")):
                parts = path.relative_to(root).with_suffix("").parts
                found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


def _executed_statements(body: list[ast.stmt]) -> list[ast.stmt]:
    """Statements that run on import: descends into blocks and class bodies, not functions."""
    executed: list[ast.stmt] = []
    for statement in body:
        if isinstance(statement, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        if isinstance(statement, ast.If) and "TYPE_CHECKING" in ast.unparse(statement.test):
            executed += _executed_statements(statement.orelse)
            continue
        executed.append(statement)
        for block in ("body", "orelse", "finalbody"):
            executed += _executed_statements(getattr(statement, block, []))
        for handler in getattr(statement, "handlers", []):
            executed += _executed_statements(handler.body)
    return executed


def import_graph(root: Path = ROOT, packages: tuple[str, ...] = PACKAGES) -> dict[str, set[str]]:
    """Module -> the project modules its import-time statements import (``from p import m`` names p.m)."""
    modules = _modules(root, packages)
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets: set[str] = set()
        for statement in _executed_statements(ast.parse(path.read_text(encoding="utf-8")).body):
            if isinstance(statement, ast.Import):
                targets |= {alias.name for alias in statement.names}
            elif isinstance(statement, ast.ImportFrom):
                base = statement.module or ""
                if statement.level:
                    anchor = package.split(".")[: len(package.split(".")) - statement.level + 1]
                    base = ".".join([*anchor, *([base] if base else [])])
                for alias in statement.names:
                    submodule = f"{base}.{alias.name}"
                    targets.add(submodule if submodule in modules else base)
        graph[name] = {target for target in targets if target in modules and target != name}
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as ``[a, b, ..., a]``, or None if it is acyclic."""
    state: dict[str, str] = {}  # "open" while on the DFS stack, then "done"
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = "open"
        stack.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == "open":
                return [*stack[stack.index(target) :], target]
            if target not in state and (cycle := visit(target)):
                return cycle
        state[node] = "done"
        stack.pop()
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_ogcp_has_no_import_time_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_graph_sees_package_re_exports_and_submodule_imports():
    graph = import_graph()
    assert "ogcp.planner.infra.errors" in graph["ogcp.planner.infra"]  # __init__ re-export
    assert (
        "ogcp.planner.objects.fetchable" in graph["ogcp.planner.objects.fetch"]
    )  # from ogcp.planner.objects import fetchable
    assert "matplotlib" not in str(graph["ogcp.benchmarks.cli.plot"])  # external imports are not nodes


def test_a_re_export_cycle_through_init_is_found(tmp_path):
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("from pkg.a import A\n")
    (package / "a.py").write_text("from pkg import helper\nA = 1\n")
    (package / "b.py").write_text("def later():\n    from pkg import a\n")
    (package / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from . import a\n")
    graph = import_graph(tmp_path, ("pkg",))
    assert graph["pkg.b"] == set() and graph["pkg.c"] == set()  # lazy and type-only imports do not count
    assert find_cycle(graph) == ["pkg", "pkg.a", "pkg"]


def test_relative_imports_resolve(tmp_path):
    package = tmp_path / "pkg" / "sub"
    package.mkdir(parents=True)
    (package.parent / "__init__.py").write_text("")
    (package / "__init__.py").write_text("from .x import X\nfrom .. import y\n")
    (package / "x.py").write_text("from ..y import Y\nX = 1\n")
    (package.parent / "y.py").write_text("try:\n    from pkg.sub import x\nexcept ImportError:\n    pass\n")
    graph = import_graph(tmp_path, ("pkg",))
    assert graph["pkg.sub"] == {"pkg.sub.x", "pkg.y"}
    assert graph["pkg.sub.x"] == {"pkg.y"}
    assert find_cycle(graph) == ["pkg.sub.x", "pkg.y", "pkg.sub.x"]
