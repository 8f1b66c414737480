"""Deprecated alias of :mod:`course.grading` (the package's name until version 0.1).

Notebooks handed out before the rename start with ``from course.exercises import Assignment``
and instructors' ``checks.py`` files with ``from course.exercises.spec import Checks``; both keep
working for one release, with a :class:`DeprecationWarning`. Old submodule names map to their
new homes (``spec`` -> ``checks``, ``grader`` -> ``driver``/``session``/``reports``,
``seccomp`` -> ``isolation.seccomp``). Write ``course.grading`` in new code.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types
import warnings

from course.grading import __all__ as _grading_all

__all__ = list(_grading_all)
__path__: list[str] = []  # a package, so that ``course.exercises.spec`` can be imported

warnings.warn(
    "course.exercises is now course.grading; the old name stops working in the next release",
    DeprecationWarning,
    stacklevel=2,
)

#: old submodule -> the module(s) that now hold its names (the first one is the module itself)
_RENAMED = {
    "spec": ("course.grading.authoring.checks",),
    "grader": (
        "course.grading.batch.driver",
        "course.grading.batch.session",
        "course.grading.batch.reports",
    ),
    "seccomp": ("course.grading.sandbox.isolation.seccomp",),
}
_OLD_NAMES = {"Grader": "AssignmentGrader", "_read_results": "read_results"}


def __getattr__(name: str):
    return getattr(importlib.import_module("course.grading"), name)


def __dir__():
    return sorted(__all__)


def _combined(old: str, targets: tuple[str, ...]) -> types.ModuleType:
    """A module whose attributes come from several new modules (``grader`` was split in three)."""
    modules = [importlib.import_module(t) for t in targets]
    module = types.ModuleType(old, f"Deprecated alias of {', '.join(targets)}.")

    def lookup(name: str):
        name = _OLD_NAMES.get(name, name)
        for m in modules:
            if hasattr(m, name):
                return getattr(m, name)
        raise AttributeError(f"module {old!r} has no attribute {name!r}")

    module.__getattr__ = lookup  # type: ignore[method-assign]
    return module


class _AliasLoader(importlib.abc.Loader):
    def __init__(self, targets: tuple[str, ...]):
        self.targets = targets

    def create_module(self, spec):
        if len(self.targets) == 1:
            return importlib.import_module(self.targets[0])
        return _combined(spec.name, self.targets)

    def exec_module(self, module) -> None:
        return None


class _AliasFinder(importlib.abc.MetaPathFinder):
    """Finds ``course.exercises.<name>`` as the module of the renamed package."""

    prefix = __name__ + "."

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith(self.prefix):
            return None
        old = fullname[len(self.prefix) :]
        targets = _RENAMED.get(old, (f"course.grading.{old}",))
        if importlib.util.find_spec(targets[0]) is None:
            return None
        return importlib.util.spec_from_loader(fullname, _AliasLoader(targets))


if not any(isinstance(f, _AliasFinder) for f in sys.meta_path):
    sys.meta_path.insert(0, _AliasFinder())
