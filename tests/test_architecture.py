"""The library's shape: one public name per object and no reaching into another package's privates."""

from __future__ import annotations

import ast
import importlib
import pkgutil
import types
from collections import defaultdict
from pathlib import Path

import course

ROOT = Path(__file__).resolve().parents[1]


def public_namespaces() -> list[str]:
    """``course.X`` for every X of ``course.__all__``, and the plotting modules."""
    names = [f"course.{name}" for name in course.__all__ if not name.startswith("_")]
    names = [n for n in names if isinstance(importlib.import_module(n), types.ModuleType)]
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
        if "grading" in path.relative_to(ROOT).parts:
            continue  # the grader's own rooms are restructured separately
        found += _private_imports(path)
    assert not found, "cross-package private imports:\n" + "\n".join(found)
