"""The instructor's term (issue 27): resubmissions and single students, the gradebook across
assignments, the class report.

The whole-class cases reuse the shared graded class of 01_least_squares (``graded_class``):
this module adds a full solution and an untouched release to it, and every rerun here works
on a copy of that class's submissions and output, so only the students a test changes are
graded again.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from conftest import class_submissions

from course.cli import main as course_main
from course.grading.batch.driver import SelectionError, grade
from course.grading.batch.options import GradeOptions

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION = ROOT / "solutions" / NAME
EXERCISE = ROOT / "exercises" / NAME


@class_submissions("term")
def _term_submissions(name: str, subs: Path) -> None:
    """A full solution and an untouched release of assignment 01."""
    if name != NAME:
        return None
    (subs / "term-full.ipynb").write_bytes((SOLUTION / f"{NAME}.ipynb").read_bytes())
    (subs / "term-stub.ipynb").write_bytes((EXERCISE / f"{NAME}.ipynb").read_bytes())
    return None


@pytest.fixture
def class_copy(graded_class, tmp_path):
    """(submissions, out) copied from the shared graded class: reruns change only the copy."""
    graded = graded_class(NAME)
    subs, out = tmp_path / "subs", tmp_path / "out"
    shutil.copytree(graded.out.parent / "subs", subs)
    shutil.copytree(graded.out, out)
    return graded, subs, out


def _options(**kw) -> GradeOptions:
    return GradeOptions(jobs=1, progress=False, **kw)


# -- item 1: resubmissions and single students ---------------------------------------------------
def test_a_resubmission_is_graded_again(class_copy):
    graded, subs, out = class_copy
    # the student hands in the full solution in place of the untouched stub
    (subs / "term-stub.ipynb").write_bytes((subs / "term-full.ipynb").read_bytes())
    summary = grade(SOLUTION, subs, out, _options())
    assert summary.graded == 1 and summary.resumed == len(graded.rows) - 1
    assert summary.regraded == {"file changed": 1}
    assert "Graded 1 submission(s) (1 regraded: file changed)" in summary.text()
    row = next(r for r in summary.rows if r.student == "term-stub")
    assert row.total == graded.rows["term-full"]["total"] > graded.rows["term-stub"]["total"]
    assert row.file is not None
    assert row.file["sha256"] == graded.rows["term-full"]["file"]["sha256"]
    assert "term-stub" in (out / "grades.csv").read_text()
    # the next run keeps the new grade
    again = grade(SOLUTION, subs, out, _options())
    assert again.graded == 0 and again.regraded == {}


def test_student_grades_only_the_chosen_students(class_copy, capsys):
    _, subs, out = class_copy
    (subs / "term-stub.ipynb").write_bytes((subs / "term-full.ipynb").read_bytes())
    # without --regrade a chosen student graded from an unchanged file is kept
    summary = grade(SOLUTION, subs, out, _options(students=frozenset({"term-full"})))
    assert summary.graded == 0 and summary.stale == ["term-stub"]
    assert "1 changed since graded but not chosen by --student (term-stub)" in summary.text()
    # --regrade with --student: only that student, the rest of results.jsonl stays
    before = (out / "results.jsonl").read_text()
    code = course_main(
        ["grade", str(SOLUTION), str(subs), "--out", str(out), "--student", "term-full",
         "--regrade", "--no-progress", "--jobs", "1"]
    )  # fmt: skip
    assert code == 0
    assert "Graded 1 submission(s) (1 regraded: --regrade)" in capsys.readouterr().out
    after = (out / "results.jsonl").read_text()
    assert after.startswith(before) and after.count("\n") == before.count("\n") + 1
    # an ID without a submission is refused before anything is graded
    with pytest.raises(SelectionError, match="nobody"):
        grade(SOLUTION, subs, out, _options(students=frozenset({"nobody"})))
