"""Graded exercises: one authoring source, student self-checks, and a sandboxed batch grader.

Students use :class:`Assignment` (``check = Assignment.load("01_least_squares",
student_id=STUDENT_ID)`` in the first cell, then ``check("q1")``). Instructors author
assignments in ``solutions/<name>/`` (see ``course/exercises/AUTHORING.md``), release them with
``course release`` and grade a class with ``course grade``.

Modules
-------
spec
    The authoring vocabulary of ``checks.py`` (:class:`~course.exercises.spec.Checks`).
authoring
    Helpers that build solution notebooks with the right cell metadata.
notebook
    Markers, the student release and the grading plan of a submitted notebook.
release
    ``course release``.
selfcheck
    The student's ``check(...)``.
grader, sandbox, runner
    ``course grade``: the trusted parent, process isolation, and the sandboxed child.
"""

from importlib import import_module

__all__ = ["Assignment", "Band", "Checks", "binomial_band", "student_rng"]

_LAZY = {
    "Assignment": "course.exercises.selfcheck",
    "Checks": "course.exercises.spec",
    "Band": "course.exercises.codec",
    "binomial_band": "course.exercises.compare",
    "student_rng": "course.exercises.spec",
}


def __getattr__(name):
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'course.exercises' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_LAZY))
