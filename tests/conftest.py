"""Test-suite wide settings and the helpers the test modules share.

Small-matrix BLAS calls are many times slower with a threaded OpenBLAS on a
busy 2-core machine, so the suite (and the notebook kernels nbval starts,
which inherit this environment) runs single-threaded BLAS.

Helpers (import them with ``from conftest import ...``):

:func:`binomial_band`
    The interval that holds the share of successes in ``n`` Bernoulli(``p``)
    trials with probability ``1 - miss``: a Monte Carlo rate outside it is a
    real disagreement, not bad luck.
:func:`assert_rate`
    Assert that a Monte Carlo rate lies in that band, with a readable message.
:func:`class_submissions`
    Register a test module's submissions to an assignment's shared graded class.

Fixtures:

``graded_class``
    ``graded_class(name)``: the graded class of assignment ``name`` (a :class:`GradedClass`),
    graded ONCE per test session with the real grader. Every module that registered
    submissions with :func:`class_submissions` adds its notebooks to the same class, so the
    whole-class tests (release, wrong answers, feedback scan) share one grading run and one
    fork server per assignment instead of one each.

Markers: ``slow`` marks what ``python -m pytest -m "not slow"`` (the contributors' fast lane)
leaves out: the notebooks (nbval), the website, whole-class gradings and fresh installs.
"""

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest  # noqa: E402
from scipy import stats  # noqa: E402  (after the thread settings)

ROOT = Path(__file__).resolve().parents[1]


def binomial_band(n, p, miss=1e-4):
    """``(lo, hi)``: rates of ``n`` Bernoulli(``p``) trials fall outside with probability ``miss``.

    The argument order is scipy's ``binom(n, p)``.
    """
    lo, hi = stats.binom.interval(1 - miss, n, p)
    return lo / n, hi / n


def assert_rate(rate, n, p, miss=1e-4):
    """Assert that the Monte Carlo ``rate`` of ``n`` trials is consistent with probability ``p``."""
    rate = float(rate)
    lo, hi = binomial_band(n, p, miss)
    assert lo <= rate <= hi, (
        f"rate {rate:.4f} of {n} trials outside the binomial band [{lo:.4f}, {hi:.4f}] "
        f"around {p:.4f}"
    )


# -- the fast lane: python -m pytest -m "not slow" ----------------------------------------------
#: Module fixtures that grade a whole class or export a student edition (tens of seconds).
SLOW_FIXTURES = frozenset({"graded_class", "graded", "needles", "class_edition", "public_edition"})


def pytest_collection_modifyitems(config, items):
    """Mark ``slow`` what the fast lane leaves out without each test saying so: the notebook
    cells (nbval), the website (``browser``) and every test that needs a graded class or an
    exported edition (:data:`SLOW_FIXTURES`). Other slow tests carry ``@pytest.mark.slow``.

    Tests marked ``after_notebooks`` (the notebooks' time budget) move to the end of the run,
    after nbval has run every notebook of the session."""
    for item in items:
        if (
            item.path.suffix == ".ipynb"
            or item.get_closest_marker("browser") is not None
            or SLOW_FIXTURES & set(getattr(item, "fixturenames", ()))
        ):
            item.add_marker(pytest.mark.slow)
    last = [item for item in items if item.get_closest_marker("after_notebooks") is not None]
    if last:
        items[:] = [item for item in items if item not in last] + last


# -- the notebooks' time budget, measured in the suite's own run ---------------------------------
#: notebook path -> seconds nbval spent on it in this session (every cell, setup to teardown:
#: the kernel's start included, as a student's fresh kernel would pay it)
NOTEBOOK_SECONDS: dict[str, float] = {}


class _NotebookClock:
    """A global plugin: a conftest's own item hooks see only the items below its folder, and
    the notebooks live in notebooks/."""

    @staticmethod
    def pytest_runtest_logreport(report):
        path = report.nodeid.split("::", 1)[0]
        if path.endswith(".ipynb"):
            NOTEBOOK_SECONDS[path] = NOTEBOOK_SECONDS.get(path, 0.0) + report.duration


def pytest_configure(config):
    config.pluginmanager.register(_NotebookClock(), "course-notebook-clock")


# -- one graded class per assignment, shared by the whole-class tests ---------------------------
#: tag -> writer(assignment, folder): the notebooks a test module adds to that assignment's class
_CLASS_WRITERS: dict[str, Callable[[str, Path], object]] = {}


def class_submissions(tag: str):
    """Decorator: ``writer(assignment, folder)`` writes this module's submissions of
    ``assignment`` (``<student ID>.ipynb`` files, IDs unique across modules) into ``folder``
    and returns what its tests need to read their rows (``GradedClass.made[tag]``).

    Writers are registered when their module is imported, i.e. at collection, before the
    first class is graded; a writer with nothing for an assignment returns None.
    """

    def register(writer: Callable[[str, Path], object]):
        _CLASS_WRITERS[tag] = writer
        return writer

    return register


@dataclass
class GradedClass:
    """One assignment's class graded in one run: rows by student ID, and the output folder."""

    name: str
    out: Path
    rows: dict[str, dict]
    made: dict[str, object] = field(default_factory=dict)  # tag -> what its writer returned

    def feedback(self, student: str) -> str:
        """The feedback file ``student`` receives."""
        return (self.out / "feedback" / f"{student}.md").read_text("utf-8")


@pytest.fixture(scope="session")
def graded_class(tmp_path_factory) -> Callable[[str], GradedClass]:
    """``graded_class(name)``: the class of assignment ``name`` graded once per session (an
    assignment that fails to grade fails the tests that ask for it, and only those)."""
    cache: dict[str, GradedClass | Exception] = {}

    def get(name: str) -> GradedClass:
        if name not in cache:
            try:
                cache[name] = _grade_class(name, tmp_path_factory.mktemp(f"class-{name}"))
            except Exception as exc:  # reported by every test of this assignment
                cache[name] = exc
        result = cache[name]
        if isinstance(result, Exception):
            raise RuntimeError(f"grading the class of {name} failed") from result
        return result

    return get


def _grade_class(name: str, tmp: Path) -> GradedClass:
    import json

    from course.grading.batch.driver import grade
    from course.grading.batch.options import GradeOptions

    subs = tmp / "subs"
    subs.mkdir()
    made = {}
    for index, (tag, writer) in enumerate(sorted(_CLASS_WRITERS.items())):
        own = tmp / f"module-{index}"  # each module writes apart: a shared ID is an error
        own.mkdir()
        made[tag] = writer(name, own)
        for path in sorted(own.iterdir()):
            if (subs / path.name).exists():
                raise ValueError(f"{tag}: another module already submitted {path.name}")
            path.rename(subs / path.name)
    out = tmp / "out"
    grade(ROOT / "solutions" / name, subs, out, GradeOptions(jobs=2, progress=False))
    lines = (out / "results.jsonl").read_text().splitlines()
    rows = {row["student"]: row for row in map(json.loads, lines)}
    return GradedClass(name, out, rows, made)
