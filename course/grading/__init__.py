"""Graded exercises: one authoring source, student self-checks, and a sandboxed batch grader.

Students use :class:`Assignment` (``check = Assignment.load("01_least_squares",
student_id=STUDENT_ID)`` in the first cell, then ``check("q1")``). Instructors author
assignments in ``solutions/<name>/`` (see ``docs/instructors/authoring.md``), release them with
``course release`` and grade a class with ``course grade``.

Modules
-------
vocabulary
    The shared words: cell roles, student IDs, protocol operations, statuses, ``checks.json``.
checks
    The authoring vocabulary of ``checks.py`` (:class:`~course.grading.checks.Checks`).
items, marks
    Choice and short-answer questions; the short-answer marking file and its re-import.
authoring
    Helpers that build solution notebooks with the right cell metadata.
notebook
    Markers, the student release and the grading plan of a submitted notebook.
codec, compare
    Plain-data values across process boundaries, and comparing them with a tolerance.
release
    ``course release``.
selfcheck
    The student's ``check(...)``.
driver, session, reports
    ``course grade``: the batch, one student's session in the trusted parent, the outputs.
sandbox, forkserver, runner
    The parent's handle on sandboxed children, the warm fork server, the child itself.
isolation
    The isolation layers of a child, one per module.
tripwire
    Forbidden library functions.
secret, personal
    A graded class's instructor secret, and the personal data issued from it.
submit, identity, roster
    Handing in (``check.submit()``), whose submission is whose, the roster and LMS grade files.
export, leaks
    ``course export`` (the student edition) and the scan that keeps solutions out of it.
"""

from importlib import import_module

__all__ = ["Assignment", "Band", "Checks", "Mistake", "binomial_band", "student_rng"]

_LAZY = {
    "Assignment": "course.grading.selfcheck",
    "Checks": "course.grading.checks",
    "Mistake": "course.grading.checks",
    "Band": "course.grading.codec",
    "binomial_band": "course.grading.compare",
    "student_rng": "course.grading.checks",
}


def __getattr__(name):
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'course.grading' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_LAZY))
