"""Graded exercises: one authoring source, student self-checks, and a sandboxed batch grader.

Students use :class:`Assignment` (``check = Assignment.load("01_least_squares",
student_id=STUDENT_ID)`` in the first cell, then ``check("q1")``). Instructors author
assignments in ``solutions/<name>/`` (see ``docs/instructors/authoring.md``), release them with
``course release`` and grade a class with ``course grade``.

The flow
--------
1. An instructor writes ``solutions/<name>/``: ``checks.py`` (:mod:`.authoring.checks`), the
   solution notebook (helpers: :mod:`.authoring.notebooks`) and ``data.py``.
2. ``course release`` (:mod:`.authoring.release`) builds the student notebook by the passes of
   :mod:`.authoring.passes` and ``checks.json``, whose expected values are sealed
   (:mod:`.authoring.seal`), into ``exercises/<name>/``; ``course export``
   (:mod:`.authoring.export`) packs the student edition, personal data included
   (:mod:`.authoring.personal`, drawn with :mod:`.authoring.secret`), after the leak scan of
   :mod:`.authoring.leaks`.
3. A student runs ``check("q1")`` (:mod:`.student.selfcheck`) against the sealed values and
   hands in with ``check.submit()`` (:mod:`.student.submit`).
4. ``course grade`` (:mod:`.batch.driver`, options in :mod:`.batch.options`) finds the
   submissions (:mod:`.batch.intake`: a folder or the LMS's zip) and whose each is
   (:mod:`.batch.lmsnames`, :mod:`.batch.identity`, :mod:`.batch.roster`), grades each
   student in a session (:mod:`.batch.session`) that matches the notebook against the release
   (:mod:`.batch.plan`) and runs it in a sandboxed child (:mod:`.sandbox.parent`,
   :mod:`.sandbox.forkserver`, :mod:`.sandbox.runner`, :mod:`.sandbox.isolation`; forbidden
   calls reported by :mod:`.tripwire`), compares in the trusted parent (:mod:`.compare`), and
   records a
   :class:`~.batch.results.StudentResult`, kept in the term's record (:mod:`.batch.record`,
   one SQLite database per class); the reports (:mod:`.batch.reports`, the class
   report ``report.html`` of :mod:`.batch.classreport`, with its item analysis,
   :mod:`.batch.itemanalysis`, and similarity hints, :mod:`.batch.similarity`), the short
   answers' marking file (:mod:`.batch.marks`) and the LMS files (:mod:`.batch.roster`) are
   exports of the record; :mod:`.batch.cluster` runs the sessions on Dask workers
   (their side: :mod:`.batch.clusterworker`), which never receive the class key.
   ``course gradebook`` (:mod:`.batch.gradebook`) combines several assignments' outputs into
   one gradebook, under the term's rules (:mod:`.batch.termrules`); ``course mark`` (:mod:`.batch.marking`) marks the short answers in Jupyter,
   alike answers in groups (:mod:`.batch.answergroups`).

Modules
-------
The words every room shares (a room imports them, never another room's module to get them):

vocabulary
    Cell roles, student IDs, protocol operations, statuses, ``checks.json``.
codec, compare
    Plain-data values across process boundaries, and comparing them with a tolerance.
items
    Choice and short-answer questions (what the release, the self-check and the grader share).
notebook
    Solution markers, the release's cells, reading a submission.
tripwire
    Forbidden library functions: a warning in the self-check, a report from a grading child.
cli
    ``course release | grade | gradebook | mark | export | secret | submit``: the entry points into
    the rooms.

``authoring/`` what the instructor writes and hands out
    checks (the vocabulary of ``checks.py``), notebooks (solution-notebook helpers), passes
    (the student release, pass by pass), release (``course release``), seal (sealed expected
    values), secret (the instructor's key), personal (personal data drawn from it), leaks (the
    scan that keeps solutions out), export (``course export``).
``student/`` what runs in the student's kernel
    selfcheck (``check(...)``), submit (``check.submit()``).
``batch/`` ``course grade`` in the trusted parent
    driver (the batch), options (:class:`~.batch.options.GradeOptions`), session (one
    student), plan (which of a submission's cells run, in which order), results (the typed
    results), record (the term's record: rows, marks, files, history), reports (feedback,
    grades, results log), marks (short answers), marking (the
    marking view of ``course mark``), answergroups (its groups of alike
    answers), intake (the files handed in: folders and LMS zips),
    lmsnames (each LMS's name grammar), identity (whose submission is whose), lmsfeedback
    (the feedback zips of ``course feedback``), roster (the class,
    LMS grade files), late (due dates and late penalties), cluster (Dask: the driver's side),
    clusterworker (a Dask worker's side), gradebook (several assignments in one file),
    termrules (the term's weights, letters, exemptions), classreport (``report.html``),
    itemanalysis (its per-question statistics), similarity (its similarity hints).
``sandbox/`` the sandboxed children
    parent (the grader's handle), forkserver (the warm process children fork from), runner
    (the child), isolation (the layers, one per module: namespaces, landlock, seccomp,
    privileges, limits, audit, paths).

Rooms import downward only, in the order shared words, authoring, student, sandbox, batch: the
self-check opens seals and reads personal data (authoring); a grading child runs the
self-check's grading stand-in (student); the batch loads the release (authoring), reads the
submission receipts (student) and starts children (sandbox). One crossing goes up: ``course
export`` reads the class roster (:mod:`.batch.roster`). No module imports one that imports it
back. ``tests/test_import_cycles.py`` checks both.
"""

from importlib import import_module

__all__ = ["Assignment", "Band", "Checks", "Mistake", "binomial_band", "student_rng"]

_LAZY = {
    "Assignment": "course.grading.student.selfcheck",
    "Checks": "course.grading.authoring.checks",
    "Mistake": "course.grading.authoring.checks",
    "Band": "course.grading.codec",
    "binomial_band": "course.grading.compare",
    "student_rng": "course.grading.authoring.checks",
}


def __getattr__(name):
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'course.grading' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_LAZY))
