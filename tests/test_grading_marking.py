"""Issue 27 item 5: marking short answers in Jupyter, and no unmarked answer exported as 0
without a warning.

The marking view (:mod:`course.grading.batch.marking`) is tested here without a browser, through
its widgets' values and buttons as the front end sets them; ``tests/test_lab_marking.py`` drives
it in a real JupyterLab.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from test_grading_items import NAME, RIGHT, _course, _student

from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions
from course.grading.batch.roster import read_roster


def _moodle(out: Path) -> dict[str, list[str]]:
    return {r[0]: r for r in csv.reader((out / "moodle.csv").open(encoding="utf-8"))}


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    """Four students answered the short question q3 (2 points), one did not."""
    root = tmp_path_factory.mktemp("marking")
    _course(root)
    subs = root / "subs"
    subs.mkdir()
    answers = {
        "s1": "Because T exceeds the critical value.",
        "s2": "<img src=x onerror=alert(1)> the p-value is small",
        "s3": "Because T exceeds the critical value.",  # the same text as s1
        "s4": "I do not know.",
    }
    for sid, text in answers.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(_student(root, {**RIGHT, "q3": text})))
    (subs / "s5.ipynb").write_text(json.dumps(_student(root, {**RIGHT, "q3": ""})))
    roster = root / "roster.csv"
    roster.write_text(
        "id,name,email\n" + "".join(f"s{i},Student {i},s{i}@example.org\n" for i in range(1, 6))
    )
    return root


def _grade(course: Path, out: Path, **options):
    opts = GradeOptions(jobs=1, progress=False, roster=read_roster(course / "roster.csv"))
    for key, value in options.items():
        setattr(opts, key, value)
    return grade(course / "solutions" / NAME, course / "subs", out, opts)


@pytest.fixture(scope="module")
def graded(course, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    return _grade(course, out), out


# -- unmarked answers are never exported as 0 without a warning ----------------------------
def test_unmarked_answers_are_counted_per_question_in_the_console(graded):
    """Old code: "4 to mark in …" and nothing said that grades and LMS files count them 0."""
    summary, out = graded
    text = summary.text()
    assert (
        "WARNING: 4 short answer(s) NOT marked yet count as 0 (q3: 4 of 4 answers) in "
        "grades.csv, report.html and the LMS files"
    ) in text
    assert f"course mark {out}" in text


def test_unmarked_answers_are_a_warning_in_the_report(graded):
    _, out = graded
    page = (out / "report.html").read_text()
    warning = page.split('<div class="warning">')[1].split("</div>")[0]
    assert "4 short answer(s) NOT marked yet count as 0" in warning
    assert "<td>q3</td><td>4</td><td>4</td>" in warning
    # before the first figure: the totals below it count the unmarked answers as 0
    assert page.index('<div class="warning">') < page.index("<h2>Pass rate per question</h2>")


def test_lms_files_carry_the_unmarked_zero_visibly(graded):
    _, out = graded
    moodle = _moodle(out)
    assert "q3 0/2 not marked yet" in moodle["s1"][-1]
    assert "not marked" not in moodle["s5"][-1]  # no answer given: a real 0


def test_no_warning_once_everything_is_marked(course, tmp_path):
    out = tmp_path / "out"
    _grade(course, out)
    rows = list(csv.DictReader((out / "short_answers.csv").open(encoding="utf-8")))
    for r in rows:
        r["points"] = "1"
    with open(tmp_path / "all.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    summary = _grade(course, out, short_answers=tmp_path / "all.csv")
    assert "NOT marked" not in summary.text() and "all marked" in summary.text()
    assert '<div class="warning">' not in (out / "report.html").read_text()
    assert "not marked" not in _moodle(out)["s1"][-1]
