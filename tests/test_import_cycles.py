"""No import cycle between the package's modules (issue 23, item 2): the AST of src/quickrelease walked, every
import counted (module level and inside functions; those under ``if TYPE_CHECKING:`` alone are left out, they
never run), and the graph searched for a cycle. ``lint-imports`` (the contract in pyproject.toml) checks the
layers; this test checks what a layers contract cannot see: a cycle inside one layer."""

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "quickrelease"

#: Lazy imports the layers contract names as still crossing upward (pyproject.toml, ignore_imports) close these
#: cycles at run time: a result's convenience method calling the presentation layer that draws that result.
ACCEPTED = {
    ("quickrelease.device.response", "quickrelease.report.plots"),
    ("quickrelease.device.identify", "quickrelease.io.frames"),
    ("quickrelease.building.isolation_fit", "quickrelease.io.frames"),
}


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for inner in node.body:
                lines.update(range(inner.lineno, inner.end_lineno + 1))
    return lines


def import_graph(root: Path = SRC) -> dict[str, set[str]]:
    """module -> the package's modules it imports (a ``from pkg import name`` counts ``pkg.name`` when that
    is a module, else ``pkg``)."""
    modules = {_module_name(p, root): p for p in root.rglob("*.py")}
    top = root.name
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skip = _type_checking_lines(tree)
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        deps = set()
        for node in ast.walk(tree):
            if getattr(node, "lineno", None) in skip:
                continue
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module.split(".") if node.module else []
                if node.level:
                    base = package[: len(package) - node.level + 1] + base
                base_name = ".".join(base)
                targets = [f"{base_name}.{a.name}" if f"{base_name}.{a.name}" in modules else base_name
                           for a in node.names]
            else:
                continue
            deps.update(t for t in targets if t.split(".")[0] == top and t in modules and t != name)
        graph[name] = deps
    return graph


def find_cycle(graph: dict[str, set[str]], accepted=frozenset()) -> list[str] | None:
    """One import cycle (the modules in order, the first repeated at the end), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for dep in sorted(graph.get(node, ())):
            if (node, dep) in accepted:
                continue
            if state.get(dep) == 1:
                return stack[stack.index(dep):] + [dep]
            if dep not in state and (found := visit(dep)):
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_no_import_cycle_between_modules():
    cycle = find_cycle(import_graph(), ACCEPTED)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_the_walk_finds_a_planted_cycle(tmp_path):
    """A two-module cycle through a function-level import, and one through ``from . import``, are found."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from .sub import b\n")
    (pkg / "sub" / "b.py").write_text("def f():\n    from .. import a\n")
    graph = import_graph(pkg)
    assert graph["pkg.a"] == {"pkg.sub.b"} and graph["pkg.sub.b"] == {"pkg.a"}
    assert find_cycle(graph) == ["pkg.a", "pkg.sub.b", "pkg.a"]
    (pkg / "sub" / "b.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .. import a\n")
    assert find_cycle(import_graph(pkg)) is None
