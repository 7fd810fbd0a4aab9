"""The import graph of src/: no circles, and the simulation's core imports no plugin package.

Every import counts, at module level or deferred inside a function, except those under
``if TYPE_CHECKING:`` (types only, never run).  Plugins (drives, sensors, cameras,
effecters) sit above the simulation's leaf modules and below the composition root, which
hands them to the simulation as a ``usarsim.sim.plugins.PluginSet``.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"
PLUGIN_PACKAGES = ("usarsim.robots", "usarsim.sensors", "usarsim.effecters")


def _modules() -> dict[str, Path]:
    mods = {}
    for p in SRC.rglob("*.py"):
        name = ".".join(p.relative_to(SRC).with_suffix("").parts)
        mods[name.removesuffix(".__init__")] = p
    return mods


def _imports(mod: str, path: Path, mods: dict[str, Path]) -> set[str]:
    """The project's modules ``mod`` imports (run-time imports only)."""
    package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
    found: set[str] = set()

    def known(name: str) -> str:
        while name not in mods and "." in name:
            name = name.rpartition(".")[0]
        return name

    class Visitor(ast.NodeVisitor):
        def visit_If(self, node: ast.If) -> None:
            if "TYPE_CHECKING" in ast.unparse(node.test):
                for stmt in node.orelse:
                    self.visit(stmt)
            else:
                self.generic_visit(node)

        def visit_Import(self, node: ast.Import) -> None:
            found.update(known(a.name) for a in node.names if a.name.startswith("usarsim"))

        def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
            if node.level:
                parts = package.split(".")
                target = ".".join(parts[: len(parts) - node.level + 1] + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("usarsim"):
                for a in node.names:
                    full = f"{target}.{a.name}"
                    found.add(full if full in mods else known(target))

    Visitor().visit(ast.parse(path.read_text()))
    found.discard(mod)
    return found


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    return {m: _imports(m, p, mods) for m, p in mods.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                strong(w)
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
            strong(v)
    return out


def test_the_graph_is_read() -> None:
    graph = _graph()
    assert "usarsim.sim.plugins" in graph["usarsim.sim.simulation"]
    assert "usarsim.sim.plugins" in graph["usarsim.plugins"]
    assert "usarsim.robots" in graph["usarsim.plugins"]  # a package's own name counts
    # a deferred import inside a function counts too
    assert "usarsim.config.catalog" in graph["usarsim.bench.command"]


def test_no_import_circles() -> None:
    assert _cycles(_graph()) == []


def test_a_circle_would_be_found() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_simulation_core_imports_no_plugin_package() -> None:
    graph = _graph()
    wrong = sorted(
        f"{m} -> {t}"
        for m, targets in graph.items()
        if m.startswith("usarsim.sim.") or m == "usarsim.sim"
        for t in targets
        if t.startswith(PLUGIN_PACKAGES)
    )
    assert wrong == []
