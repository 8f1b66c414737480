"""The library's shape: one public name per object and no reaching into another package's privates."""

from __future__ import annotations

import ast
import importlib
import json
import pkgutil
import re
import types
from collections import defaultdict
from pathlib import Path

import course

ROOT = Path(__file__).resolve().parents[1]


#: Public modules of ``course`` that are tools around the library, not part of its API, so
#: they stay out of ``course.__all__``: the command line, the website builder, the workspace
#: helpers and the notebooks' optional sliders (they need ipywidgets).
TOOLS = frozenset({"cli", "docsite", "workspace", "interactive"})


def discovered_modules() -> list[str]:
    """Every public module of the package as it is on disk, registered or not.

    The guards start from here, not from ``course.__all__``: a module someone forgot to
    register would otherwise escape every one of them.
    """
    return sorted(
        info.name for info in pkgutil.iter_modules(course.__path__) if not info.name.startswith("_")
    )


def public_namespaces() -> list[str]:
    """``course.X`` for every public module of the library (tools aside), and the plotting modules."""
    names = [f"course.{name}" for name in discovered_modules() if name not in TOOLS]
    plotting = importlib.import_module("course.plotting")
    names += [
        f"course.plotting.{info.name}"
        for info in pkgutil.iter_modules(plotting.__path__)
        if not info.name.startswith("_")
    ]
    return names


def _named(obj) -> bool:
    """An object whose identity means something (not a small int or an interned string)."""
    return not isinstance(obj, (types.ModuleType, bool, int, str, type(None)))


def test_every_public_object_has_one_public_name():
    names: dict[int, list[str]] = defaultdict(list)
    for module_name in public_namespaces():
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", []):
            obj = getattr(module, name)
            if _named(obj):
                names[id(obj)].append(f"{module_name}.{name}")
    aliases = sorted(v for v in names.values() if len(v) > 1)
    assert not aliases, f"objects with two or more public names (keep one home): {aliases}"


def test_the_public_names_come_from_the_course():
    # A name of numpy or scipy re-exported by a course module would be a second name too.
    for module_name in public_namespaces():
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", []):
            obj = getattr(module, name)
            home = getattr(obj, "__module__", None)
            if isinstance(obj, (type, types.FunctionType)) and home is not None:
                assert home.startswith("course"), f"{module_name}.{name} is {home}.{name}"


def _shared_internal(target: str, imported: list[str]) -> bool:
    """``course._x`` (a top-level private module) is a shared internal module: the seam."""
    parts = target.split(".")
    if len(parts) == 2 and parts[1].startswith("_"):
        return True
    return target == "course" and all(n.startswith("_") for n in imported)


def _private_imports(path: Path) -> list[str]:
    """``from course.a._b import c`` / ``from course.a import _c`` reaching outside its package.

    Shared helpers live in top-level private modules (``course._unchecked``, ``course._stacked``,
    ...) that any module may import; a package's own private modules are its business.
    """
    module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
    package = (
        module.rsplit(".", 1)[0] if path.name != "__init__.py" else module[: -len(".__init__")]
    )
    # a topic package and its private modules are one unit; course/*.py modules are their own
    unit = ".".join(package.split(".")[:2]) if package.count(".") >= 1 else module
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [(a.name, []) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: from .x import y, from . import y
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            targets = [(base, [a.name for a in node.names])]
        else:
            continue
        for target, imported in targets:
            if not target.startswith("course") or ".".join(target.split(".")[:2]) == unit:
                continue
            if _shared_internal(target, imported):
                continue
            private_module = any(part.startswith("_") for part in target.split(".")[1:])
            private_names = [n for n in imported if n.startswith("_") and not n.startswith("__")]
            if private_module or private_names:
                found.append(f"{module}: {target} {', '.join(private_names)}".rstrip())
    return found


def test_no_module_reaches_into_another_packages_private_names():
    found = []
    for path in sorted((ROOT / "course").rglob("*.py")):
        found += _private_imports(path)
    assert not found, "cross-package private imports:\n" + "\n".join(found)


# ---------------------------------------------------------------------------
# a topic module is wired into every place ARCHITECTURE.md's checklist names
# ---------------------------------------------------------------------------
#: The layers below the topics and the two packages beside them; every other public module
#: of ``course`` is a topic module (found, not listed: a new one is checked by default).
NOT_TOPICS = {"results", "validation", "linalg", "distributions", "chi2", "quadform"}
NOT_TOPICS |= {"plotting", "grading"}


def topic_modules() -> list[str]:
    return [name for name in discovered_modules() if name not in NOT_TOPICS | TOOLS]


def _uses(text: str, topic: str) -> bool:
    """``from course import ..., topic``, ``import course.topic``, ``course.topic.x``, ..."""
    return bool(
        re.search(rf"from course import [^\n]*\b{topic}\b", text)
        or re.search(rf"\bcourse\.{topic}\b", text)
    )


def _code_of(path: Path) -> str:
    if path.suffix == ".ipynb":
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    return path.read_text(encoding="utf-8")


def _bad_input_tables() -> set[str]:
    """The modules whose public callables a tests/test_bad_input_*.py table covers."""
    covered: set[str] = set()
    for path in sorted((ROOT / "tests").glob("test_bad_input_*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (
                isinstance(node, ast.Call)
                and getattr(node.func, "id", None) == "module_tests"
                and node.args
            ):
                value = ast.literal_eval(node.args[0])
                covered |= {value} if isinstance(value, str) else set(value)
    return covered


def test_the_topic_modules_are_found():
    assert {"lsq", "diagnosis", "filters", "nis", "mismatched"} <= set(topic_modules())


def test_every_public_module_is_registered_or_a_tool():
    registered = set(course._SUBMODULES)
    unknown = [f"course.{n}" for n in discovered_modules() if n not in registered | TOOLS]
    assert not unknown, (
        f"public modules neither in course/__init__.py's _SUBMODULES nor named a tool in "
        f"tests/test_architecture.py's TOOLS: {unknown}; register a library module (and follow "
        f"ARCHITECTURE.md's checklist), or make it private (_name)"
    )
    gone = sorted((registered | TOOLS) - set(discovered_modules()))
    assert not gone, f"registered or listed as tools but not on disk: {gone}"


def _readme_rows() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return "\n".join(line for line in text.splitlines() if line.startswith("| "))


def _missing_pieces(topic: str) -> list[str]:
    """What ARCHITECTURE.md's checklist asks of a topic module and ``topic`` lacks."""
    module = importlib.import_module(f"course.{topic}")
    checks = {
        "its name in course/__init__.py's _SUBMODULES": topic in course._SUBMODULES,
        "its name among the topics of course/__init__.py's docstring": f"\n{topic}\n"
        in (course.__doc__ or ""),
        "its place in a layer of ARCHITECTURE.md": f"`course.{topic}`"
        in (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8"),
        f"a unit-test file tests/test_{topic}.py": (ROOT / "tests" / f"test_{topic}.py").exists(),
        "a bad-input table in tests/test_bad_input_*.py": f"course.{topic}" in _bad_input_tables(),
        f"a plotting module course/plotting/{topic}.py": (
            ROOT / "course" / "plotting" / f"{topic}.py"
        ).exists(),
        "a notebook that uses it": any(
            _uses(_code_of(p), topic) for p in sorted((ROOT / "notebooks").glob("*.ipynb"))
        ),
        "an assignment that uses it": any(
            _uses(_code_of(p), topic) for p in sorted((ROOT / "solutions").glob("*/*.py"))
        ),
        "a row in the README's learning path": f"`course.{topic}`" in _readme_rows(),
        "a link to the bibliography in its docstring": ":doc:`/docs/bibliography`"
        in (module.__doc__ or ""),
    }
    return [piece for piece, present in checks.items() if not present]


def test_every_topic_module_follows_the_checklist():
    """One message per module with every missing piece: what a newcomer needs to read."""
    missing = {t: pieces for t in topic_modules() if (pieces := _missing_pieces(t))}
    assert not missing, "topic modules short of ARCHITECTURE.md's checklist:\n" + "\n".join(
        f"course.{t} lacks: {'; '.join(pieces)}" for t, pieces in missing.items()
    )


def test_the_package_docstring_lists_the_topics_the_map_lists():
    doc = course.__doc__ or ""
    topics_part = doc.split("Topics", 1)[1].split("Shared pieces", 1)[0]
    listed = set(re.findall(r"^(\w+)\n", topics_part, flags=re.MULTILINE))
    assert listed == set(topic_modules()), (
        f"course/__init__.py's docstring lists as topics {sorted(listed)}; the topic modules "
        f"are {sorted(topic_modules())} (the laws and the bottom go under 'Shared pieces')"
    )


def _checklist() -> list[str]:
    """The numbered lines of ARCHITECTURE.md's "Adding a topic module", one string each."""
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    part = text.split("## Adding a topic module", 1)[1].split("\n## ", 1)[0]
    return [m.group(0) for m in re.finditer(r"(?ms)^\d+\. .*?(?=^\d+\. |\Z)", part)]


def test_every_checklist_line_names_the_guard_that_checks_it():
    # test_architecture_map_names_only_what_exists checks that every named guard exists.
    lines = _checklist()
    assert len(lines) >= 9, "ARCHITECTURE.md's checklist is found"
    unguarded = [line.split("\n")[0] for line in lines if not re.search(r"`test_\w+`", line)]
    assert not unguarded, f"checklist lines that name no guard (`test_...`): {unguarded}"


#: Public names of the library from before the changelog recorded each one (0.2.0 is the first
#: release). Every name added since needs its CHANGELOG.md entry.
_NAMES_BEFORE_THE_CHANGELOG = ROOT / "tests" / "public_names_before_changelog.json"


def test_every_new_public_name_has_a_changelog_entry():
    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    older = set(json.loads(_NAMES_BEFORE_THE_CHANGELOG.read_text(encoding="utf-8"))["names"])
    missing = []
    for namespace in public_namespaces():
        for name in getattr(importlib.import_module(namespace), "__all__", []):
            full = f"{namespace}.{name}"
            if full not in older and not re.search(rf"\b{re.escape(name)}\b", changelog):
                missing.append(full)
    assert not missing, f"public names without a CHANGELOG.md entry: {missing}"


def test_every_public_module_has_a_bad_input_table():
    modules = {n for n in public_namespaces() if n.count(".") == 1} - {
        "course.plotting",
        "course.grading",
    }
    missing = sorted(modules - _bad_input_tables())
    assert not missing, f"modules without a table in tests/test_bad_input_*.py: {missing}"


def test_every_topic_module_has_a_plotting_module():
    missing = [
        t for t in topic_modules() if not (ROOT / "course" / "plotting" / f"{t}.py").exists()
    ]
    assert not missing, f"topic modules without course/plotting/<module>.py: {missing}"


def test_every_topic_module_is_taught_in_a_notebook_and_an_assignment():
    notebooks = [_code_of(p) for p in sorted((ROOT / "notebooks").glob("*.ipynb"))]
    assignments = [
        "\n".join(_code_of(p) for p in sorted(folder.iterdir()) if p.suffix in (".py", ".ipynb"))
        for folder in sorted((ROOT / "solutions").iterdir())
        if folder.is_dir()
    ]
    for topic in topic_modules():
        assert any(_uses(text, topic) for text in notebooks), f"no notebook uses course.{topic}"
        assert any(_uses(text, topic) for text in assignments), f"no assignment uses course.{topic}"


def test_every_assignment_has_a_wrong_answer_suite():
    suites = {}
    for path in sorted((ROOT / "tests" / "wrong_answers").glob("answers_*.py")):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "ASSIGNMENT":
                suites[ast.literal_eval(node.value)] = path.name
    assignments = {p.name for p in (ROOT / "solutions").iterdir() if (p / "checks.py").exists()}
    missing = sorted(assignments - set(suites))
    assert not missing, f"assignments without tests/wrong_answers/answers_NN.py: {missing}"


# ---------------------------------------------------------------------------
# ARCHITECTURE.md names only what exists
# ---------------------------------------------------------------------------
_PATH = re.compile(r"^(course|tests|docs|notebooks|solutions|exercises|\.ci)/[\w./*-]*$")
_DOTTED = re.compile(r"^course(\.\w+)+$")


def _resolves(dotted: str) -> bool:
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_architecture_map_names_only_what_exists():
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    names = set(re.findall(r"`([^`\n]+)`", text))
    checked, missing = 0, []
    for name in sorted(names):
        if "<" in name:  # a pattern such as course/plotting/<topic>.py
            continue
        if _DOTTED.match(name):
            checked += 1
            if not _resolves(name):
                missing.append(name)
        elif re.fullmatch(r"test_\w+", name):  # a guard the checklist relies on
            checked += 1
            sources = "".join(f.read_text(encoding="utf-8") for f in (ROOT / "tests").glob("*.py"))
            if f"def {name}(" not in sources:
                missing.append(name)
        elif _PATH.match(name):
            checked += 1
            if not (any(ROOT.glob(name)) if "*" in name else (ROOT / name).exists()):
                missing.append(name)
    assert checked >= 20, "the map names modules and paths in backticks"
    assert not missing, f"ARCHITECTURE.md names what does not exist: {missing}"


def test_architecture_map_names_every_public_module():
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    missing = [n for n in public_namespaces() if n.count(".") == 1 and n not in text]
    assert not missing, f"public modules ARCHITECTURE.md does not place in a layer: {missing}"


def test_every_library_name_an_assignment_names_resolves():
    # Forbidden functions are dotted names: one that no longer resolves (a removed alias)
    # would silently forbid nothing.
    missing = []
    for path in sorted(ROOT.glob("solutions/*/checks.py")) + sorted(
        ROOT.glob("exercises/*/checks.json")
    ):
        for name in set(re.findall(r"[\"'](course(?:\.\w+)+)[\"']", path.read_text("utf-8"))):
            if not name.startswith("course.grading") and not _resolves(name):
                missing.append(f"{path.relative_to(ROOT)}: {name}")
    assert not missing, f"names that do not resolve: {missing}"


# ---------------------------------------------------------------------------
# the import graph (the layers test; tests/test_import_cycles.py finds cycles)
# ---------------------------------------------------------------------------
def _import_graph() -> dict[str, set[str]]:
    modules: dict[str, Path] = {}
    for path in (ROOT / "course").rglob("*.py"):
        name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        modules[name.removesuffix(".__init__")] = path

    def owner(dotted: str) -> str:
        while dotted and dotted not in modules:
            dotted = dotted.rpartition(".")[0]
        return dotted

    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):  # functions too
            if isinstance(node, ast.Import):
                targets |= {owner(a.name) for a in node.names if a.name.startswith("course")}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join(anchor + ([base] if base else []))
                if base.startswith("course"):
                    for a in node.names:
                        full = f"{base}.{a.name}"
                        targets.add(full if full in modules else owner(base))
        graph[name] = {t for t in targets if t and t != name}
    return graph


#: The layers of ARCHITECTURE.md, bottom (0) to top; a module not named here is a topic (2).
LAYERS = {
    0: {"results", "validation", "linalg"},  # and every shared internal module course._x
    1: {"chi2", "quadform", "distributions"},
    3: {"plotting", "interactive"},
    4: {"cli", "docsite", "workspace", "grading", "__main__"},
}


def _layer(module: str) -> int:
    parts = module.split(".")
    if len(parts) == 1:
        return 0  # the package itself: its version (it imports its modules lazily, by name)
    first = parts[1]
    if first.startswith("_") and first != "__main__":
        return 0
    return next((level for level, names in LAYERS.items() if first in names), 2)


def test_layers_import_only_downward():
    upward = [
        f"{a} -> {b}"
        for a, targets in sorted(_import_graph().items())
        for b in sorted(targets)
        if _layer(b) > _layer(a)
    ]
    assert not upward, f"imports that go up a layer (see ARCHITECTURE.md): {upward}"


#: The size past which a file is split into single-concept modules (ARCHITECTURE.md, item 1).
MAX_LINES = 1100


def test_no_source_file_is_over_the_size_limit():
    long = {
        str(p.relative_to(ROOT)): n
        for p in sorted((ROOT / "course").rglob("*.py"))
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not long, f"files over {MAX_LINES} lines (split them by concept): {long}"
