"""The structure of ``course/``: no import cycle anywhere, counting the imports written inside
functions; the grader's rooms import downward only; the grader's docstring names every module.

An import inside a function hides a cycle from Python at import time but not from a reader:
the two modules still cannot be understood, moved or tested apart. The graph is built from the
source (every ``import`` and ``from ... import`` node of every module, at any depth, including
``if TYPE_CHECKING:`` blocks), so a cycle fails here before it confuses anyone.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "course"


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _resolve(target: str, modules: set[str]) -> str | None:
    """The course module that ``target`` names: itself, or its longest module prefix (a name
    imported from a module is an edge to that module)."""
    while target:
        if target in modules:
            return target
        target = target.rpartition(".")[0]
    return None


def import_graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the course modules it imports anywhere in its source (parent packages not
    counted: importing ``a.b.c`` runs ``a/__init__`` and ``a/b/__init__`` but does not make
    ``c`` depend on them in the sense a cycle means)."""
    files = {_module_name(p, package.parent): p for p in package.rglob("*.py")}
    modules = set(files)
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        is_package = path.name == "__init__.py"
        deps: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = name.split(".")
                    base = base[: len(base) - node.level + (1 if is_package else 0)]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                targets = [f"{module}.{a.name}" for a in node.names]
            for target in targets:
                dep = _resolve(target, modules)
                if dep is not None and dep != name:
                    deps.add(dep)
        graph[name] = deps
    return graph


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One cycle per strongly connected component with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                components.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return components


def test_no_import_cycle_in_course():
    cycles = find_cycles(import_graph())
    assert not cycles, "import cycles (imports inside functions count):\n" + "\n".join(
        " <-> ".join(c) for c in cycles
    )


#: The grader's rooms, lowest first: a module imports from its own room or a lower one.
ROOMS = ("", "authoring", "student", "sandbox", "batch", "cli")  # "": the shared words; cli: the
# entry points, above every room
#: Imports that go up, each with its reason (see course/grading/__init__.py).
UPWARD = {
    ("course.grading.authoring.export", "course.grading.batch.roster"),  # export reads the class
}


def _room(module: str) -> str | None:
    parts = module.split(".")
    if parts[:2] != ["course", "grading"]:
        return None
    if module == "course.grading.cli":
        return "cli"
    return parts[2] if len(parts) > 3 and parts[2] in ROOMS else ""


def test_the_graders_rooms_import_downward():
    graph = import_graph()
    upward = {
        (a, b)
        for a, deps in graph.items()
        for b in deps
        if _room(a) is not None
        and _room(b) is not None
        and ROOMS.index(_room(b) or "") > ROOMS.index(_room(a) or "")
    }
    assert upward == UPWARD, (
        f"imports up the rooms {' < '.join(r or 'shared' for r in ROOMS)}: "
        f"{sorted(upward - UPWARD)}; no longer there: {sorted(UPWARD - upward)}"
    )


def test_the_graders_docstring_names_every_module():
    import course.grading

    doc = course.grading.__doc__ or ""
    grading = PACKAGE / "grading"
    names = {
        p.stem if p.name != "__init__.py" else p.parent.name
        for p in grading.rglob("*.py")
        if p.parent != grading or p.name != "__init__.py"
    }
    missing = sorted(n for n in names if not re.search(rf"\b{re.escape(n)}\b", doc))
    assert not missing, f"course/grading/__init__.py's docstring does not name {missing}"


@pytest.mark.parametrize(
    "sources, cyclic",
    [
        ({"a": "from pkg import b", "b": "def f():\n    from pkg.a import x\n"}, True),
        ({"a": "from pkg import b", "b": "import pkg.c", "c": "from . import a"}, True),
        ({"a": "from pkg import b", "b": "import math", "c": "from .a import x"}, False),
        (
            {
                "a": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.b import B",
                "b": "from pkg.a import A",
            },
            True,
        ),
    ],
)
def test_the_cycle_finder_sees_cycles_at_any_depth(tmp_path, sources, cyclic):
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    for name, text in sources.items():
        (package / f"{name}.py").write_text(text)
    assert bool(find_cycles(import_graph(package))) is cyclic
