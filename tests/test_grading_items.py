"""Issue 13 items 4-6: choice and short-answer questions (with the marking file's round trip),
locked cells and answers found by cell id, points in one place."""

from __future__ import annotations

import contextlib
import copy
import csv
import io
import json
from pathlib import Path

import nbformat
import pytest

from course.grading.authoring.checks import Checks, load_checks
from course.grading.authoring.notebooks import (
    answer_cell,
    check_cell,
    md,
    new_assignment_notebook,
    setup_cell,
    short_answer_cell,
)
from course.grading.authoring.passes import make_release
from course.grading.authoring.release import find_solutions, release, release_files
from course.grading.batch.driver import grade
from course.grading.batch.marks import MarksError
from course.grading.batch.options import GradeOptions
from course.grading.batch.plan import build_plan
from course.grading.items import SHORT_ANSWER_STUB
from course.grading.notebook import MarkerError
from course.grading.student.selfcheck import Assignment

ROOT = Path(__file__).resolve().parents[1]
NAME = "00_items"
CHECKS_PY = """
from course.grading.authoring.checks import Checks
CHECKS = Checks("00_items", title="Items")


@CHECKS.value("q1", var="x", points=1)
def q1():
    return 2.0


@CHECKS.choice("q2", var="verdict", options=["accept", "reject"], points=2)
def q2():
    return "reject"


CHECKS.short_answer("q3", points=2, rubric="=the statistic exceeds its critical value")
"""


def _solution_cells(q1_header="## q1: a value", q2_header="## q2 (2 points): accept or reject?"):
    return [
        md("# Items"),
        setup_cell(NAME),
        md(q1_header),
        answer_cell("q1", "### BEGIN SOLUTION\nx = 2.0\n### END SOLUTION"),
        check_cell("q1"),
        md(q2_header),
        answer_cell(
            "q2", "### BEGIN SOLUTION\nverdict = 'reject'\n### STUB verdict = ...\n### END SOLUTION"
        ),
        check_cell("q2"),
        md("## q3: why?"),
        short_answer_cell("q3", "Because T = 9.1 exceeds the critical value 5.99."),
        check_cell("q3"),
    ]


def _course(root: Path, cells=None) -> Path:
    sol = root / "solutions" / NAME
    sol.mkdir(parents=True)
    (sol / "checks.py").write_text(CHECKS_PY)
    nbformat.write(new_assignment_notebook(NAME, cells or _solution_cells()), sol / f"{NAME}.ipynb")
    release(NAME, root / "solutions", root / "exercises")
    return sol


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    root = tmp_path_factory.mktemp("items")
    _course(root)
    return root


def _student(course: Path, answers: dict, delete=(), retype=(), move=()) -> dict:
    """The released notebook with answer cells replaced; ``delete`` removes answer cells,
    ``retype`` removes them and puts their text into a new cell at the same place."""
    nb = json.loads((course / "exercises" / NAME / f"{NAME}.ipynb").read_text())
    for cell in nb["cells"]:
        qid = cell["id"].removesuffix("-answer")
        if cell["id"].endswith("-answer") and qid in answers:
            cell["source"] = answers[qid]
    for qid in (*delete, *retype):
        i = next(i for i, c in enumerate(nb["cells"]) if c["id"] == f"{qid}-answer")
        old = nb["cells"].pop(i)
        if qid in retype:
            new = nbformat.v4.new_code_cell(old["source"])
            new["id"] = f"my-own-{qid}"
            nb["cells"].insert(i, new)
    for qid in move:  # to the very end of the notebook
        i = next(i for i, c in enumerate(nb["cells"]) if c["id"] == f"{qid}-answer")
        nb["cells"].append(nb["cells"].pop(i))
    return nb


RIGHT = {"q1": "x = 2.0", "q2": "verdict = ' Reject'", "q3": "=1+1 because T > k"}


@pytest.fixture(scope="module")
def graded(course):
    subs = course / "subs"
    subs.mkdir()
    students = {
        "right": _student(course, RIGHT),
        "wrong": _student(course, {**RIGHT, "q2": "verdict = 'accept'", "q3": SHORT_ANSWER_STUB}),
        "invalid": _student(course, {**RIGHT, "q2": "verdict = 'maybe'"}),
        "retyped": _student(course, RIGHT, retype=["q1"]),
        "deleted": _student(course, RIGHT, delete=["q1", "q3"]),
        "moved": _student(course, RIGHT, move=["q1", "q2"]),
    }
    for sid, nb in students.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    out = course / "out"
    summary = grade(course / "solutions" / NAME, subs, out, GradeOptions(jobs=2, progress=False))
    rows = {json.loads(line)["student"]: json.loads(line) for line in open(out / "results.jsonl")}
    return summary, rows, out


def _q(rows, sid, qid):
    return rows[sid]["questions"][qid]


# -- item 4: choice ------------------------------------------------------------------------
def test_choice_is_graded_at_grading_only(graded):
    _, rows, _ = graded
    assert (_q(rows, "right", "q2")["status"], _q(rows, "right", "q2")["points"]) == ("pass", 2)
    wrong = _q(rows, "wrong", "q2")
    assert (wrong["status"], wrong["points"]) == ("fail", 0)
    assert "reject" not in wrong["message"]  # never names the right option
    assert "not one of the options" in _q(rows, "invalid", "q2")["message"]


def _selfcheck_output(course, **values) -> str:
    check = Assignment.load(NAME, student_id="s1", path=course / "exercises" / NAME)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        check.all(dict(values))
    return buf.getvalue()


def test_choice_selfcheck_never_says_right_or_wrong(course):
    right = _selfcheck_output(course, x=2.0, verdict="reject")
    wrong = _selfcheck_output(course, x=2.0, verdict="accept")

    def q2(out, answer):
        return out.split("q2 (")[1].split("q3 (")[0].replace(f"{answer!r} is one", "<A> is one")

    assert q2(right, "reject") == q2(wrong, "accept")  # the same words for right and wrong
    assert "<A> is one of the options" in q2(right, "reject") and "PASS" not in q2(right, "reject")
    invalid = _selfcheck_output(course, x=2.0, verdict="maybe")
    assert "FAIL: 'maybe' is not one of the options" in invalid


def test_check_all_ends_with_the_points_summary(course):
    out = _selfcheck_output(course, x=2.0, verdict="reject").strip().splitlines()[-1]
    assert out == (
        "1 of 1 points from public checks; 1 hidden case at grading; 4 more points "
        "(choices, short answers) are decided only at grading (5 points in total)."
    )
    assert _selfcheck_output(course, x=3.0).strip().splitlines()[-1].startswith("0 of 1 points")


def test_choice_authoring_mistakes_are_refused():
    checks = Checks("00_x")
    with pytest.raises(ValueError, match="at least 2 options"):
        checks.choice("q1", var="v", options=["yes"], points=1)
    with pytest.raises(ValueError, match="must differ"):
        checks.choice("q1", var="v", options=["Yes", " yes"], points=1)


def test_choice_reference_must_return_an_option(tmp_path):
    sol = _course(tmp_path)
    (sol / "checks.py").write_text(CHECKS_PY.replace('return "reject"', 'return "rejected"'))
    with pytest.raises(ValueError, match="'rejected', which is not an option"):
        release_files(sol)


# -- item 4: short answers and the marking file -------------------------------------------
def _marking_rows(out: Path) -> list[dict]:
    return list(csv.DictReader(open(out / "short_answers.csv", encoding="utf-8")))


def test_short_answers_wait_for_the_instructor(graded):
    summary, rows, out = graded
    assert _q(rows, "right", "q3")["status"] == "to mark" and _q(rows, "right", "q3")["points"] == 0
    assert _q(rows, "wrong", "q3")["status"] == "not answered"  # the placeholder is no answer
    marking = _marking_rows(out)
    assert list(marking[0]) == [
        "student",
        "question",
        "answer",
        "points_possible",
        "points",
        "rubric",
        "comment",
        "answer_id",
    ]
    by_student = {r["student"]: r for r in marking}
    assert set(by_student) == {"right", "invalid", "retyped", "moved"}
    assert by_student["right"]["answer"] == "'=1+1 because T > k"  # no formula for a spreadsheet
    assert by_student["right"]["rubric"].startswith("'=")
    assert by_student["right"]["points"] == "" and by_student["right"]["points_possible"] == "2"
    assert "4 to mark" in summary.text()


def _write(path: Path, rows: list[dict], delimiter=",") -> Path:
    with open(path, "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]), delimiter=delimiter)
        writer.writeheader()
        writer.writerows(rows)
    return path


def test_marking_file_round_trip(graded, course):
    _, _, out = graded
    rows = _marking_rows(out)
    by_student = {r["student"]: r for r in rows}
    by_student["right"].update(points="1,5", comment="=good; name the dof")  # decimal comma
    by_student["moved"].update(points="2")
    filled = _write(course / "filled.csv", rows)
    opts = GradeOptions(jobs=1, progress=False, short_answers=filled)
    summary = grade(course / "solutions" / NAME, course / "subs", out, opts)
    assert "2 mark(s) imported; 2 to mark" in summary.text()
    grades = {r["student"]: r for r in csv.DictReader(open(out / "grades.csv"))}
    assert (grades["right"]["q3"], grades["right"]["total"]) == ("1.5", "4.5")
    assert grades["moved"]["q3"] == "2"
    feedback = (out / "feedback" / "right.md").read_text()
    assert "## q3: 1.5 / 2 (marked)" in feedback and "=good; name the dof" in feedback
    last = [json.loads(line) for line in open(out / "results.jsonl")]
    assert [r for r in last if r["student"] == "right"][-1]["total"] == 4.5
    # a regrade keeps the marks (the answers did not change)
    summary = grade(
        course / "solutions" / NAME,
        course / "subs",
        out,
        GradeOptions(jobs=1, progress=False, regrade=True),
    )
    assert {r.student: r.total for r in summary.rows}["right"] == 4.5
    assert {r["student"]: r["points"] for r in _marking_rows(out)}["right"] == "1.5"


def test_a_marking_file_is_read_with_one_dialect_never_guessed(graded, course):
    """A semicolon file (a spreadsheet's locale) is refused as a whole, with what to do:
    guessing the dialect from the file is how a student's quote and comma forged marks."""
    _, _, out = graded
    rows = _marking_rows(out)
    bad = _write(course / "semicolons.csv", rows, delimiter=";")
    with pytest.raises(MarksError, match="comma-separated"):
        grade(
            course / "solutions" / NAME,
            course / "subs",
            out,
            GradeOptions(jobs=1, progress=False, short_answers=bad),
        )


@pytest.mark.parametrize(
    "change, message",
    [
        ({"student": "s999", "points": "1"}, "unknown student 's999'"),
        ({"question": "q9", "points": "1"}, "'q9' is not a question"),
        ({"question": "q1", "points": "1"}, "'q1' is not a short-answer question"),
        ({"points": "3"}, "3 points for invalid q3: give between 0 and 2"),
        ({"points": "-1"}, "give between 0 and 2"),
        ({"points": "lots"}, "is not a number"),
        ({"comment": "see me"}, "a comment but no points for invalid q3"),
        ({"answer_id": "0123456789ab", "points": "1"}, "changed since this file was written"),
        ({"answer_id": "", "points": "1"}, "no answer_id for invalid q3"),
        ({"answer": "another text", "points": "1"}, "is not the answer its answer_id names"),
    ],
)
def test_a_bad_row_is_refused_with_its_line_and_the_others_imported(
    graded, course, change, message
):
    """Old code: one bad row refused the whole file (nothing imported)."""
    _, _, out = graded
    rows = _marking_rows(out)
    line = next(i for i, r in enumerate(rows, start=2) if r["student"] == "invalid")
    rows[line - 2].update(change)
    good = next(r for r in rows if r["student"] == "retyped")
    good.update(points="0.5")
    bad = _write(course / "bad.csv", rows)
    summary = grade(
        course / "solutions" / NAME,
        course / "subs",
        out,
        GradeOptions(jobs=1, progress=False, short_answers=bad),
    )
    text = summary.text()
    assert "1 row(s) of the marking file refused" in text
    assert any(x.strip().startswith(f"line {line}: ") and message in x for x in text.splitlines())
    marks = {r.student: r.questions["q3"] for r in summary.rows}
    assert marks["retyped"].points == 0.5 and marks["invalid"].status == "to mark"


def test_marking_file_twice_the_same_row(graded, course):
    _, _, out = graded
    rows = _marking_rows(out)
    rows[0]["points"] = "1"
    bad = _write(course / "twice.csv", [*rows, dict(rows[0])])
    summary = grade(
        course / "solutions" / NAME,
        course / "subs",
        out,
        GradeOptions(jobs=1, progress=False, short_answers=bad),
    )
    assert f"line {len(rows) + 2}: {rows[0]['student']} q3 is marked twice (also line 2)" in (
        summary.text()
    )


def test_release_locks_cells_and_names_answer_cells(course):
    nb = nbformat.read(course / "exercises" / NAME / f"{NAME}.ipynb", as_version=4)
    for cell in nb.cells:
        role = cell.metadata["course"]["role"]
        assert cell.metadata["deletable"] is False, cell.id
        assert cell.metadata["editable"] is (role in ("answer", "setup")), cell.id
        if role == "answer":
            assert cell.id == f"{cell.metadata['course']['question']}-answer"
    short = next(c for c in nb.cells if c.id == "q3-answer")
    assert short.cell_type == "markdown" and short.source == SHORT_ANSWER_STUB


def test_answer_retyped_in_a_new_cell_is_graded_and_flagged(graded):
    """Old code: the answer scored 0 silently ("not answered")."""
    summary, rows, _ = graded
    r = _q(rows, "retyped", "q1")
    assert (r["status"], r["points"]) == ("pass", 1)
    assert "answer cell of q1 was deleted" in r["message"]
    assert rows["retyped"]["deleted_answers"] == {"q1": "adopted"}
    assert "retyped (q1: graded from an added cell)" in summary.text()


def test_deleted_answer_cell_is_said_clearly(graded):
    summary, rows, out = graded
    assert _q(rows, "deleted", "q1")["status"] == "not answered"
    assert "answer cell of q1 (id 'q1-answer') is missing" in _q(rows, "deleted", "q1")["message"]
    assert _q(rows, "deleted", "q3")["status"] == "not answered"
    assert "deleted (q1: not answered, q3: not answered)" in summary.text()
    assert "q3-answer" in (out / "feedback" / "deleted.md").read_text()


def test_moved_answer_cells_are_found_by_id(graded):
    _, rows, _ = graded
    assert rows["moved"]["total"] == rows["right"]["total"] == 3
    assert "deleted_answers" not in rows["moved"]


def test_plan_grades_an_added_cell_only_when_it_defines_the_answer(course):
    from course.grading.authoring.release import load_assignment

    _, rel = load_assignment(course / "solutions" / NAME)
    nb = _student(course, RIGHT, delete=["q1"])
    extra = nbformat.v4.new_code_cell("print(x)")
    nb["cells"].insert(3, extra)
    plan = build_plan(rel, copy.deepcopy(nb), "s1", {"q1": "x", "q2": "verdict", "q3": ""})
    assert plan.deleted == {"q1": "missing"} and "q1" not in plan.answered


# -- item 6: points in one place -----------------------------------------------------------
def test_release_writes_points_into_headers_and_the_total(course):
    nb = nbformat.read(course / "exercises" / NAME / f"{NAME}.ipynb", as_version=4)
    text = [c.source for c in nb.cells if c.cell_type == "markdown"]
    assert "## q1 (1 point): a value" in text and "## q3 (2 points): why?" in text
    assert "## q2 (2 points): accept or reject?" in text
    assert nb.cells[1].id == "points-total"
    assert nb.cells[1].source.startswith("**Points.** 3 questions, 5 points in total")
    assert "marked by your instructor" in nb.cells[1].source


def test_release_fails_when_header_and_checks_disagree(tmp_path):
    """Old code: the header said 3 points, checks.py 2, and nobody noticed."""
    with pytest.raises(MarkerError, match=r"header of q2 states 3 point.*checks\.py gives 2"):
        _course(tmp_path, _solution_cells(q2_header="## q2 (3 points): accept or reject?"))


def test_release_needs_a_header_per_question(tmp_path):
    with pytest.raises(MarkerError, match="q1 has no header"):
        _course(tmp_path, _solution_cells(q1_header="A value, please."))


def test_release_refuses_a_second_header_for_one_question():
    checks = Checks(NAME)
    checks.value("q1", var="x", points=1)(lambda: 1.0)
    cells = [
        md("## q1: a"),
        setup_cell(NAME),
        answer_cell("q1", "### BEGIN SOLUTION\nx = 1\n### END SOLUTION"),
        md("## q1 again"),
    ]
    with pytest.raises(MarkerError, match="second header names q1"):
        make_release(new_assignment_notebook(NAME, cells), NAME, checks.questions)


@pytest.mark.parametrize("name", find_solutions(ROOT / "solutions"))
def test_course_assignments_state_points_and_lock_cells(name):
    checks = load_checks(ROOT / "solutions" / name)
    nb = nbformat.read(ROOT / "exercises" / name / f"{name}.ipynb", as_version=4)
    text = "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")
    for q in checks.questions.values():
        assert f"{q.id} ({q.points:g} point" in text, q.id
    assert f"{checks.max_points:g} points in total" in text
    assert all(c.metadata.get("deletable") is False for c in nb.cells)


def test_selfcheck_notes_an_answer_set_outside_its_answer_cell():
    """The kernel hears each cell's id from JupyterLab: an answer retyped in a new cell is
    noted by the self-check (old code: PASS, and 0 points at grading)."""
    from types import SimpleNamespace

    from course.grading.items import AnswerCells

    watcher = AnswerCells({"x": "q1"})
    watcher._shell = SimpleNamespace(user_ns={})

    def run(cell_id, **assign):
        watcher._pre(SimpleNamespace(cell_id=cell_id))
        watcher._shell.user_ns.update(assign)
        watcher._post(None)

    run("q1-answer", x=[2.0])
    assert watcher.note("q1", "x") is None
    run("q1-check")  # reading x does not move it
    assert watcher.note("q1", "x") is None
    run("3f9c2e", x=[2.0])
    assert "x was last set in a cell that is not the answer cell of q1 (id 'q1-answer')" in (
        watcher.note("q1", "x") or ""
    )
    run(None, x=[3.0])  # a front end that sends no cell ids: no guess
    assert watcher.set_in["x"] == "3f9c2e"


def test_submit_lists_an_unanswered_short_answer(course):
    from course.grading.student.submit import unanswered_questions

    assert unanswered_questions(_student(course, {"q1": "x = 2.0"})) == ["q2", "q3"]
    assert unanswered_questions(_student(course, RIGHT)) == []
