"""The instructor's term (issue 27): resubmissions and single students, the gradebook across
assignments, the class report.

The whole-class cases reuse the shared graded class of 01_least_squares (``graded_class``):
this module adds a full solution and an untouched release to it, and every rerun here works
on a copy of that class's submissions and output, so only the students a test changes are
graded again.
"""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import nbformat
import pytest
from conftest import class_submissions

from course.cli import main as course_main
from course.grading.batch.driver import SelectionError, grade
from course.grading.batch.options import GradeOptions
from course.grading.batch.reports import append_result
from course.grading.batch.results import StudentResult

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION = ROOT / "solutions" / NAME
EXERCISE = ROOT / "exercises" / NAME


@class_submissions("term")
def _term_submissions(name: str, subs: Path) -> None:
    """A full solution, an untouched release and a solution with two wrong answers."""
    if name != NAME:
        return None
    (subs / "term-full.ipynb").write_bytes((SOLUTION / f"{NAME}.ipynb").read_bytes())
    (subs / "term-stub.ipynb").write_bytes((EXERCISE / f"{NAME}.ipynb").read_bytes())
    # a named mistake of checks.py (q1: day 2's data) and a kind of wrong (q2: the sign)
    nb = nbformat.read(SOLUTION / f"{NAME}.ipynb", as_version=4)
    for cell in nb.cells:
        course = cell.get("metadata", {}).get("course", {})
        if course.get("role") == "answer" and course.get("question") in WRONG:
            cell.source = WRONG[course["question"]]
    nbformat.write(nb, subs / "term-wrong.ipynb")
    return None


WRONG = {
    "q1": "x_hat_day1 = np.linalg.lstsq(A, y_day2, rcond=None)[0]",
    "q2": "x_hat_day2 = np.linalg.lstsq(A, y_day2, rcond=None)[0]\n"
    "e_hat_day2 = A @ x_hat_day2 - y_day2",
}


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
    assert "1 out of date but not chosen by --student (term-stub)" in summary.text()
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


# -- item 4: the gradebook across assignments ----------------------------------------------------
def _output(folder: Path, assignment: str, max_points: float, totals: dict, column=None) -> Path:
    """A grading output folder as `course grade` leaves it (results.jsonl; canvas.csv's header
    when the run had a roster and named its column)."""
    folder.mkdir()
    for sid, total in totals.items():
        row = StudentResult(sid, assignment, "c" * 64, "1.0", "public", max_points, total=total)
        append_result(row, folder / "results.jsonl")
    if column is not None:
        header = f"Student,ID,SIS User ID,SIS Login ID,Section,{column}\r\n"
        (folder / "canvas.csv").write_text(header, encoding="utf-8")
    return folder


CANVAS_ROSTER = (
    "Student,ID,SIS User ID,SIS Login ID,Section\n"
    "    Points Possible,,,,\n"
    '"Doe, Jane",101,s001,jdoe,A\n'
    '"Roe, Ann",102,s002,aroe,A\n'
    '"Poe, Ed",103,s003,epoe,B\n'
)


def test_gradebook_combines_assignments(tmp_path, capsys):
    first = _output(tmp_path / "g01", "01_least_squares", 14, {"s001": 12.5, "s002": 14, "zz9": 3})
    third = _output(
        tmp_path / "g03", "03_kalman", 10, {"s001": 7, "s003": 9.25}, column="Kalman (4711)"
    )
    roster = tmp_path / "roster.csv"
    roster.write_text(CANVAS_ROSTER, encoding="utf-8")
    dest = tmp_path / "book"
    code = course_main(
        ["gradebook", str(first), str(third), "--out", str(dest), "--roster", str(roster)]
    )
    assert code == 0, capsys.readouterr().err
    assert "01_least_squares (14), Kalman (4711) (10)" in capsys.readouterr().out
    book = list(csv.reader((dest / "gradebook.csv").open(encoding="utf-8")))
    assert book == [
        ["student", "01_least_squares", "Kalman (4711)", "total", "max"],
        ["s001", "12.5", "7", "19.5", "24"],
        ["s002", "14", "", "14", "24"],
        ["s003", "", "9.25", "9.25", "24"],
    ]
    canvas = list(csv.reader((dest / "canvas.csv").open(encoding="utf-8")))
    assert canvas[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section"] + [
        "01_least_squares",
        "Kalman (4711)",
    ]  # no total: Canvas computes its own and would import one as a new assignment
    assert canvas[1][0].strip() == "Points Possible" and canvas[1][5:] == ["14", "10"]
    assert canvas[2] == ["Doe, Jane", "101", "s001", "jdoe", "A", "12.5", "7"]
    assert (dest / "canvas.csv").read_bytes().count(b"\r\n") == 5  # Canvas's CRLF rows
    moodle = list(csv.reader((dest / "moodle.csv").open(encoding="utf-8")))
    assert moodle[0][4:] == ["01_least_squares", "Kalman (4711)", "Total"]
    assert moodle[2] == ["s002", "", "Ann", "Roe", "14", "", "14"]
    # without a roster: every graded student (zz9 too), no LMS files; missing as zero
    course_main(["gradebook", str(first), str(third), "--out", str(tmp_path / "b2"),
                 "--missing-as-zero"])  # fmt: skip
    rows = list(csv.reader((tmp_path / "b2" / "gradebook.csv").open(encoding="utf-8")))
    assert (
        rows[-1] == ["zz9", "3", "0", "3", "24"] and not (tmp_path / "b2" / "canvas.csv").exists()
    )


def test_gradebook_refuses_what_it_cannot_combine(tmp_path, capsys):
    first = _output(tmp_path / "a", "01_least_squares", 14, {"s001": 1})
    again = _output(tmp_path / "b", "01_least_squares", 14, {"s002": 2})
    (tmp_path / "empty").mkdir()
    assert course_main(["gradebook", str(first), str(again), "--out", str(tmp_path / "o")]) == 2
    assert "both hold 01_least_squares" in capsys.readouterr().err
    assert course_main(["gradebook", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 2
    assert "holds no results.jsonl" in capsys.readouterr().err


# -- item 3: the class report --------------------------------------------------------------------
def _report(graded) -> str:
    return (graded.out / "report.html").read_text("utf-8")


def test_report_counts_mistakes_and_cases(graded_class):
    text = _report(graded_class(NAME))
    # q1 of term-wrong matched checks.py's named mistake; q2's residuals have the sign flipped
    assert "<td>q1</td><td>named mistake</td><td>this is the estimate of day 2&#x27;s data" in text
    assert "<td>q2</td><td>kind of wrong</td><td>the sign</td>" in text
    assert text.count("<svg") == 2 and text.count("<rect") > 10
    for forbidden in ("http://", "https://", "<script", "<link"):
        assert forbidden not in text  # self-contained: nothing fetched, nothing run


def test_report_of_rows_separates_public_and_hidden_cases():
    from course.grading.authoring.checks import load_checks
    from course.grading.batch.classreport import report_html
    from course.grading.batch.results import CaseResult, QuestionResult

    def row(sid, cases, status="fail", seconds=1.0):
        ok = all(c.ok for c in cases)
        q = QuestionResult(1.0 if ok else 0.0, 1.0, "pass" if ok else status, cases=cases)
        r = StudentResult(sid, NAME, "c", "v", "k", 1.0, {"q3": q}, wall_seconds=seconds)
        r.add_total()
        return r

    def case(label, ok, message=""):
        return CaseResult(label, ok, message)

    rows = [
        row("a", [case("small", True), case("hidden case 1", True)]),
        row("b", [case("small", True), case("hidden case 1", False, "T: got NaN at [0]")]),
        row("c", [case("small", False, "timeout"), case("hidden case 1", False, "not run")],
            status="timeout", seconds=30.0),
        row("d", [case("small", False, "T: too large by a factor ≈ 2.0"),
                  case("hidden case 1", False, "T: too large by a factor ≈ 2.0")]),
    ]  # fmt: skip
    text = report_html(rows, load_checks(SOLUTION), ["q3"])
    # full marks 1 of 4; public cases 2 of 4 passed; hidden 1 of 4
    assert "<td>q3</td><td>3</td><td>0.25</td><td>25 %</td><td>50 %</td><td>25 %</td>" in text
    assert "<td>a constant factor</td><td>1</td>" in text  # d counts once for two cases
    assert "<td>NaN or inf</td><td>1</td>" in text
    assert "<td>q3</td><td>timeout</td><td>1</td><td>c</td>" in text
    assert text.index("<td>c</td><td>30.00</td>") < text.index("<td>a</td><td>1.00</td>")


@pytest.mark.browser
def test_report_renders_in_chromium_with_its_figures(graded_class):
    from browser import CHROMIUM_ARGS, chromium_or_skip

    chromium = chromium_or_skip()
    sync_api = pytest.importorskip("playwright.sync_api")
    report = graded_class(NAME).out / "report.html"
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            requests, errors = [], []
            page.on("request", lambda r: requests.append(r.url))
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(report.as_uri(), wait_until="load")
            figures = page.evaluate(
                "() => Array.from(document.querySelectorAll('figure svg')).map(f => "
                "[f.getBoundingClientRect().width, f.getBoundingClientRect().height, "
                "f.querySelectorAll('rect').length, f.querySelector('title').textContent])"
            )
            headings = page.evaluate(
                "() => Array.from(document.querySelectorAll('h2')).map(h => h.textContent)"
            )
        finally:
            browser.close()
    assert [title for *_, title in figures] == [
        "pass rate per question: full marks, public and hidden cases",
        "distribution of the totals",
    ]
    assert all(w > 300 and h > 100 and bars >= 3 for w, h, bars, _ in figures), figures
    assert not errors
    assert all(url.startswith(("file:", "data:")) for url in requests), requests
    assert headings[:2] == ["Pass rate per question", "Distribution of the totals"]


# -- item 6: small traps -------------------------------------------------------------------------
def test_the_layers_line_stands_on_its_own_line(class_copy, capsys):
    """The sandbox layers are announced before the progress bar starts its line."""
    import sys

    _, subs, out = class_copy
    options = GradeOptions(
        jobs=1, progress=True, announce=lambda text: print(text, file=sys.stderr)
    )
    grade(SOLUTION, subs, out, options)
    err = capsys.readouterr().err
    first = GradeOptions().isolation().describe().splitlines()[0]
    at = err.index(first)
    assert at == 0 or err[at - 1] == "\n", repr(err[max(0, at - 80) : at + 20])


def test_roster_without_secret_is_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("COURSE_SECRET_FILE", raising=False)
    roster = tmp_path / "roster.csv"
    roster.write_text("id,name\ns1,A\n", encoding="utf-8")
    subs = tmp_path / "subs"
    subs.mkdir()
    args = ["grade", str(SOLUTION), str(subs), "--out", str(tmp_path / "out")]
    assert course_main([*args, "--roster", str(roster)]) == 2
    err = capsys.readouterr().err
    assert "--roster without the class's secret" in err and "--no-secret" in err
    assert not (tmp_path / "out").exists()
    code = course_main([*args, "--roster", str(roster), "--no-secret", "--no-progress"])
    assert code == 0 and "public generators (no secret)" in capsys.readouterr().err


def test_class_data_stays_out_of_the_clone():
    import subprocess

    names = ["roster.csv", "submissions/02/s1.ipynb", "grades/02/grades.csv", "handout/x.whl",
             "gradebook/canvas.csv", "class.key"]  # fmt: skip
    text = (ROOT / "docs" / "instructors" / "term.md").read_text("utf-8")
    assert "outside** the clone" in text
    ignored = subprocess.run(
        ["git", "check-ignore", "--no-index", *names], cwd=ROOT, capture_output=True, text=True
    ).stdout.split()
    assert sorted(ignored) == sorted(names)
