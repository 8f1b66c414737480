"""The instructor's term (issue 27): resubmissions and single students, the gradebook across
assignments, the class report.

The whole-class cases reuse the shared graded class of 01_least_squares (``graded_class``):
this module adds a full solution and an untouched release to it, and every rerun here works
on a copy of that class's submissions and output, so only the students a test changes are
graded again.
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import nbformat
import pytest
from conftest import class_submissions

from course.cli import main as course_main
from course.grading.authoring.checks import load_checks
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
    # a named mistake of checks.py (q1: the order) and a kind of wrong (q2: another order)
    nb = nbformat.read(SOLUTION / f"{NAME}.ipynb", as_version=4)
    for cell in nb.cells:
        course = cell.get("metadata", {}).get("course", {})
        if course.get("role") == "answer" and course.get("question") in WRONG:
            cell.source = WRONG[course["question"]]
    nbformat.write(nb, subs / "term-wrong.ipynb")
    return None


WRONG = {
    "q1": "def line_estimate(t, y):\n    return np.polyfit(t, y, 1)",
    "q2": "def line_residuals(t, y):\n"
    "    A = np.column_stack([np.ones(len(t)), t])\n"
    "    return np.sort(y - A @ np.linalg.lstsq(A, y, rcond=None)[0])",
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
    after = (out / "results.jsonl").read_text()  # an export of the record, one row each
    changed = set(before.splitlines()) ^ set(after.splitlines())
    assert {json.loads(line)["student"] for line in changed} <= {"term-full"}
    assert after.count("\n") == before.count("\n")
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
    # q1 of term-wrong matched checks.py's named mistake; q2's residuals come sorted
    assert "<td>q1</td><td>named mistake</td><td>the order looks like (velocity, position)" in text
    assert "<td>q2</td><td>kind of wrong</td><td>another order</td>" in text
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

    def case(label, ok, message="", kind=None):
        return CaseResult(label, ok, message, kind=kind)

    rows = [
        row("a", [case("small", True), case("hidden case 1", True)]),
        row("b", [case("small", True),
                  case("hidden case 1", False, "T: got NaN at [0]", "NaN or inf")]),
        row("c", [case("small", False, "timeout"), case("hidden case 1", False, "not run")],
            status="timeout", seconds=30.0),
        row("d", [case("small", False, "T: too large by a factor ≈ 2.0", "a constant factor"),
                  case("hidden case 1", False, "T: too large by a factor ≈ 2.0",
                       "a constant factor")]),
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


# -- item 2: late work ---------------------------------------------------------------------------
def test_late_policy_deducts_per_started_day_with_a_cap_and_a_cutoff():
    from course.grading.batch.late import Lateness, parse_due, parse_policy

    policy = parse_policy("percent-per-day:10,cap:25,zero-after:2026-10-27T23:59+02:00")
    due = parse_due("2026-10-20T23:59+02:00")

    def record(when: str | None, marked: bool = False) -> tuple:
        r = Lateness(parse_due(when) if when else None, due, "test", marked).record(policy)
        return r["days"], r["percent"]

    assert record("2026-10-20T23:59+02:00") == (0, 0)  # on the minute: on time
    assert record("2026-10-21T00:00+02:00") == (1, 10)  # a minute late is a started day
    assert record("2026-10-20T22:30Z") == (1, 10)  # 00:30 in the due date's zone
    assert record("2026-10-22T23:59+02:00") == (2, 20)
    assert record("2026-10-23T00:00+02:00") == (3, 25)  # capped
    assert record("2026-10-28T00:00+02:00") == (8, 100)  # after the cutoff: nothing
    # Canvas's _LATE_ without a time: one day, and never the cutoff
    assert record(None, marked=True) == (None, 10)
    assert parse_policy(None).describe() == "no deduction"
    assert "at most 25 %" in policy.describe()


def test_a_utc_z_time_is_read_on_every_supported_python(tmp_path):
    """The docs write times as ``...Z``; Python 3.10's fromisoformat does not read it."""
    from course.grading.batch.late import parse_due, read_timestamps

    assert parse_due("2026-10-20T21:59Z") == parse_due("2026-10-20T23:59+02:00")
    assert parse_due("2026-10-20T21:59z").utcoffset().total_seconds() == 0
    stamps = tmp_path / "times.csv"
    stamps.write_text("id,submitted_at,due\ns001,2026-10-21T08:00Z,2026-10-22T21:59Z\n")
    handed_in, own_due = read_timestamps(stamps, None)["s001"]
    assert handed_in == parse_due("2026-10-21T10:00+02:00")
    assert own_due == parse_due("2026-10-22T23:59+02:00")


def test_a_file_stamped_at_the_zero_after_instant_keeps_its_points():
    """Moodle stamps to the minute, so a hand-in at exactly the cutoff is common: "0 points
    *after*" the instant means the instant itself is still charged per day."""
    from course.grading.batch.late import Lateness, parse_due, parse_policy

    policy = parse_policy("percent-per-day:10,cap:25,zero-after:2026-10-27T23:59+02:00")
    due = parse_due("2026-10-20T23:59+02:00")
    at_cutoff = Lateness(parse_due("2026-10-27T21:59Z"), due, "test", False).record(policy)
    assert (at_cutoff["days"], at_cutoff["percent"]) == (7, 25)
    assert policy.percent(7, parse_due("2026-10-27T23:59+02:00")) == 25
    assert policy.percent(7, parse_due("2026-10-28T00:00+02:00")) == 100


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("percent-per-day:ten", "percentage between 0 and 100"),
        ("percent-per-day:150", "percentage between 0 and 100"),
        ("percent-per-week:10", "unknown rule 'percent-per-week:10'"),
        ("zero-after:2026-10-27", "has no time zone"),
        ("zero-after:next friday", "not an ISO 8601 date-time"),
    ],
)
def test_late_policy_refuses_what_it_cannot_read(text, message):
    from course.grading.batch.late import LateError, parse_policy

    with pytest.raises(LateError, match=message):
        parse_policy(text)


def test_a_late_row_totals_after_the_deduction_everywhere(tmp_path):
    from course.grading.batch.reports import feedback_markdown, read_results, write_csv
    from course.grading.batch.results import QuestionResult
    from course.grading.batch.roster import read_roster, write_canvas_csv, write_moodle_csv

    def row(sid, points, late):
        r = StudentResult(sid, NAME, "c" * 64, "v", "public", 14.0)
        r.questions = {"q1": QuestionResult(points, 14.0, "pass" if points == 14 else "fail")}
        r.add_total()
        r.set_late(late)
        return r

    two_days = {"submitted_at": "2026-10-22T09:00+02:00", "due": "2026-10-20T23:59+02:00",
                "source": "timestamps file", "days": 2, "percent": 20.0, "policy": "10 % ..."}  # fmt: skip
    unknown = {**two_days, "submitted_at": None, "days": None, "percent": 10.0}
    rows = [
        row("s001", 12.5, two_days),  # 12.5 - 20 % of 14 = 9.7
        row("s002", 14.0, None),  # nothing known: no late columns of its own
        row("s003", 1.0, unknown),  # the deduction never takes more than the points
        row("s004", 14.0, {**two_days, "days": 0, "percent": 0.0}),  # on time
    ]
    assert [r.total for r in rows] == [9.7, 14.0, 0.0, 14.0]
    assert rows[0].penalty == 2.8 and rows[2].penalty == 1.0
    for r in rows:
        append_result(r, tmp_path / "results.jsonl")
    assert read_results(tmp_path / "results.jsonl")["s001"].late == two_days  # kept on disk
    write_csv(rows, ["q1"], tmp_path / "grades.csv")
    table = list(csv.DictReader((tmp_path / "grades.csv").open(encoding="utf-8")))
    assert [(r["total"], r["late"], r["penalty"]) for r in table] == [
        ("9.7", "2", "2.8"), ("14", "", ""), ("0", "unknown", "1"), ("14", "0", "0"),
    ]  # fmt: skip
    checks = load_checks(SOLUTION)
    text = feedback_markdown(rows[0], checks)
    assert "**Total: 9.7 / 14**" in text
    assert "2 days after the due date 2026-10-20T23:59+02:00" in text
    assert "-2.8 points, 9.7 instead of 12.5" in text
    assert "charged as 1 day late" in feedback_markdown(rows[2], checks)
    assert "Late" not in feedback_markdown(rows[3], checks)
    from course.grading.batch.classreport import report_html

    page = report_html(rows, checks, ["q1"])
    assert "<h2>Late submissions</h2>" in page and "2 late" in page
    assert "<td>s003</td><td>unknown</td><td>unknown (charged 1)</td><td>1</td>" in page
    assert "lowest 0, highest 14" in page  # the totals after the deduction
    roster_file = tmp_path / "roster.csv"
    roster_file.write_text(CANVAS_ROSTER, encoding="utf-8")
    roster = read_roster(roster_file)
    by_id = {r.student: r for r in rows}
    write_canvas_csv(by_id, roster, "A1", 14, tmp_path / "canvas.csv")
    canvas = list(csv.reader((tmp_path / "canvas.csv").open(encoding="utf-8")))
    assert [r[5] for r in canvas[2:]] == ["9.7", "14", "0"]
    write_moodle_csv(by_id, roster, "A1", tmp_path / "moodle.csv")
    moodle = list(csv.reader((tmp_path / "moodle.csv").open(encoding="utf-8")))
    assert moodle[1][4] == "9.7" and "late deduction 20 %" in moodle[1][5]


def _id_notebook(path: Path, sid: str) -> Path:
    """A notebook that declares ``sid`` (setup cell and submission metadata)."""
    import json

    nb = {
        "nbformat": 4,
        "nbformat_minor": 5,
        "metadata": {"course": {"submission": {"student_id": sid}}},
        "cells": [
            {
                "cell_type": "code",
                "id": "setup",
                "metadata": {"course": {"role": "setup"}},
                "source": f'STUDENT_ID = "{sid}"',
                "outputs": [],
                "execution_count": None,
            }
        ],
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(nb))
    return path


def _resolved(subs: Path, roster_text: str, tmp_path: Path):
    from course.grading.batch.identity import resolve_identities
    from course.grading.batch.intake import find_submissions
    from course.grading.batch.roster import read_roster

    (tmp_path / "roster.csv").write_text(roster_text, encoding="utf-8")
    roster = read_roster(tmp_path / "roster.csv")
    return resolve_identities(find_submissions(subs, NAME), NAME, roster.students), roster


def test_submission_times_from_a_timestamps_file_a_moodle_worksheet_and_canvas(tmp_path):
    from course.grading.batch.late import LateError, late_records, parse_due, parse_policy

    subs = tmp_path / "subs"
    _id_notebook(subs / f"doejane_101_501_{NAME}.ipynb", "s001")
    _id_notebook(subs / f"roeann_LATE_102_502_{NAME}.ipynb", "s002")  # no time: unknown
    _id_notebook(subs / f"poeed_LATE_103_503_{NAME}.ipynb", "s003")
    identity, roster = _resolved(subs, CANVAS_ROSTER, tmp_path)
    due, policy = parse_due("2026-10-20T23:59+02:00"), parse_policy("percent-per-day:10")
    stamps = tmp_path / "times.csv"
    # s001 by student ID with an extension; s003 by its Canvas user number (103)
    stamps.write_text(
        "id,submitted_at,due\n"
        "s001,2026-10-22T10:00+02:00,2026-10-23T23:59+02:00\n"
        "103,2026-10-21T08:00:00+02:00,\n"
    )
    records, notes = late_records(identity.entries, subs, due, policy, stamps, roster)
    assert {sid: (r["days"], r["percent"]) for sid, r in records.items()} == {
        "s001": (0, 0), "s002": (None, 10), "s003": (1, 10),
    }  # fmt: skip
    assert records["s003"]["source"] == "timestamps file"
    assert "charged as 1 day late" in notes[0] and "s002" in notes[0]
    assert len(notes) == 1  # s002 is named once, as late by an unknown time
    # Moodle's grading worksheet: "Participant N" is the number in the folder's name, and its
    # times (without a zone) are in the due date's zone
    moodle = tmp_path / "moodle"
    _id_notebook(moodle / "Jane Doe_11_assignsubmission_file_" / f"{NAME}.ipynb", "s001")
    _id_notebook(moodle / "Ann Roe_12_assignsubmission_file_" / f"{NAME}.ipynb", "s002")
    sheet = tmp_path / "worksheet.csv"
    sheet.write_text(
        "Identifier,Full name,Email address,Status,Grade,Last modified (submission)\n"
        'Participant 11,Jane Doe,,Submitted,,"Tuesday, 20 October 2026, 11:59 PM"\n'
        'Participant 12,Ann Roe,,Submitted,,"Thursday, 22 October 2026, 9:15 AM"\n'
    )
    identity, roster = _resolved(moodle, CANVAS_ROSTER, tmp_path)
    records, notes = late_records(identity.entries, moodle, due, policy, sheet, roster)
    assert records["s001"]["days"] == 0 and records["s002"]["days"] == 2 and not notes
    assert records["s002"]["submitted_at"] == "2026-10-22T09:15+02:00"
    # no due date: only Canvas's marker makes a record
    records, _ = late_records(identity.entries, moodle, None, policy)
    assert records == {}
    # a timestamps file of the late students only: the others are counted, never named
    stamps.write_text("id,submitted_at\n103,2026-10-21T08:00:00+02:00\n")
    identity, roster = _resolved(subs, CANVAS_ROSTER, tmp_path)
    _, notes = late_records(identity.entries, subs, due, policy, stamps, roster)
    assert notes[-1].startswith("1 submission(s) not in") and "s001" not in notes[-1]
    assert "taken as handed in on time" in notes[-1]
    sheet.write_text("Identifier,Last modified (submission)\nParticipant 11,yesterday\n")
    with pytest.raises(LateError, match="line 2: 'yesterday' is not a time"):
        late_records(identity.entries, moodle, due, policy, sheet, roster)


def test_late_without_a_due_date_never_contradicts_itself(tmp_path):
    """Old code: "late by an unknown time, -0 points" in the summary and, on the next line,
    "charged as 1 day late"."""
    from course.grading.batch.late import late_records, parse_policy
    from course.grading.batch.reports import Summary
    from course.grading.batch.results import QuestionResult

    subs = tmp_path / "subs"
    _id_notebook(subs / f"roeann_LATE_102_502_{NAME}.ipynb", "s002")
    identity, _ = _resolved(subs, CANVAS_ROSTER, tmp_path)
    records, notes = late_records(identity.entries, subs, None, parse_policy(None))
    assert records["s002"]["days"] is None and records["s002"]["percent"] == 0
    assert "charged" not in notes[0] and "no deduction (no due date)" in notes[0]
    row = StudentResult("s002", NAME, "c" * 64, "v", "public", 14.0)
    row.questions = {"q1": QuestionResult(14.0, 14.0, "pass")}
    row.set_late(records["s002"])
    summary = Summary([row], ["q1"], {"q1": 14.0}, 1, 0, 1.0, tmp_path)
    summary.late_notes = notes
    text = summary.class_text()
    assert "(late by an unknown time, no deduction)" in text and "-0 points" not in text
    assert "charged" not in text


def test_grade_without_a_due_date_refuses_a_timestamps_file(tmp_path, capsys):
    subs = tmp_path / "subs"
    subs.mkdir()
    args = ["grade", str(SOLUTION), str(subs), "--out", str(tmp_path / "out"), "--no-progress"]
    assert course_main([*args, "--due", "2026-10-20 23:59"]) == 2
    assert "has no time zone" in capsys.readouterr().err
    assert course_main([*args, "--submitted-at", str(tmp_path / "t.csv")]) == 2
    assert "--submitted-at needs a due date" in capsys.readouterr().err


# -- item 6: Canvas and Moodle IDs ---------------------------------------------------------------
def test_a_canvas_user_number_attaches_a_file_whose_notebook_id_is_a_typo(tmp_path):
    subs = tmp_path / "subs"
    _id_notebook(subs / f"poeed_103_503_{NAME}.ipynb", "s0O3")  # a typo: on no roster
    _id_notebook(subs / f"roeann_102_502_{NAME}.ipynb", "s001")  # another roster student's
    identity, _ = _resolved(subs, CANVAS_ROSTER, tmp_path)
    s003 = next(e for e in identity.entries if e.student == "s003")
    assert s003.path is not None and s003.path.name.startswith("poeed_103_")
    assert "'s0O3' is not on the class list" in s003.note  # the student is told
    assert sorted(a[:3] for a in identity.attached) == [
        (f"poeed_103_503_{NAME}.ipynb", "s003", "s0O3"),
        (f"roeann_102_502_{NAME}.ipynb", "s002", "s001"),
    ]
    flags = "\n".join(identity.flags)
    assert "'s0O3', which is not on the roster; graded as 's003'" in flags
    # an ID that is another roster student's: graded for its uploader, and said so (issue 34)
    s002 = next(e for e in identity.entries if e.student == "s002")
    assert s002.path is not None and s002.path.name.startswith("roeann_102_")
    assert "graded as 's002'" in s002.note and not identity.conflicts
    s001 = [e for e in identity.entries if e.student == "s001"]
    assert s001 == []  # Jane handed nothing in: Ann's file never becomes hers


def test_the_name_check_lists_only_real_problems(tmp_path):
    """Canvas names hold no student ID; a roster with names (no Canvas numbers) still ties
    them to their students, so only the real problems are listed."""
    subs = tmp_path / "subs"
    _id_notebook(subs / f"doejane_1234_5678_{NAME}.ipynb", "s001")
    _id_notebook(subs / f"roeann_1235_5679_{NAME}.ipynb", "s002")
    _id_notebook(subs / f"poeed_1236_5680_{NAME}.ipynb", "s0O3")  # a typo
    _id_notebook(subs / f"kaykim_1237_5681_{NAME}.ipynb", "replace-with-your-student-id")
    _id_notebook(subs / f"kaykim_1237_5690_{NAME}-1.ipynb", "s004")  # a second upload
    _id_notebook(subs / f"zedzed_1238_5700_{NAME}.ipynb", "s001")  # who is this?
    roster = 'id,name,email\ns001,Jane Doe,\ns002,"Roe, Ann",\ns003,Ed Poe,\ns004,Kim Kay,\n'
    identity, _ = _resolved(subs, roster, tmp_path)
    assert {e.student: e.path.name[:7] for e in identity.entries if e.path} == {
        "s001": "doejane", "s002": "roeann_", "s003": "poeed_1", "s004": "kaykim_",
    }  # fmt: skip
    flags = identity.flags
    assert len(flags) == 3, flags
    assert "'s0O3', which is not on the roster; graded as 's003'" in flags[0] + flags[1]
    assert any("QUARANTINED zedzed" in f for f in flags)
    assert any(f.startswith("2 submissions claim the ID 's004'") for f in flags)
    # a roster of bare IDs gives nothing to compare a Canvas name with: no line for a file
    # whose notebook's ID is on the roster (zedzed's claim on s001 would quarantine both)
    (subs / f"zedzed_1238_5700_{NAME}.ipynb").unlink()
    identity, _ = _resolved(subs, "id\ns001\ns002\ns003\ns004\n", tmp_path)
    assert not any("doejane" in f or "roeann" in f for f in identity.flags), identity.flags


def test_the_duplicate_line_names_the_rule_it_applied(tmp_path):
    subs = tmp_path / "subs"
    _id_notebook(subs / f"doejane_101_900_{NAME}.ipynb", "s001")
    _id_notebook(subs / f"doejane_101_700_{NAME}-1.ipynb", "s001")
    _id_notebook(subs / "s002.ipynb", "s002")
    _id_notebook(subs / "s002_resubmitted.ipynb", "s002")
    identity, _ = _resolved(subs, CANVAS_ROSTER, tmp_path)
    flags = "\n".join(identity.flags)
    assert (
        f"graded doejane_101_900_{NAME}.ipynb (the last in the LMS's order: the highest Canvas "
        "submission number, its latest upload)" in flags
    )
    assert "graded s002_resubmitted.ipynb (the last in the LMS's order: by file name)" in flags


def test_a_canvas_user_number_never_takes_the_time_of_the_student_with_that_id(tmp_path):
    """Numeric IDs: Ann's Canvas user number 101 is Jane's student ID; the row "101" of the
    timestamps file is Jane's time, not Ann's."""
    from course.grading.batch.intake import Submission
    from course.grading.batch.late import late_records, parse_due, parse_policy

    subs = tmp_path / "subs"
    jane = _id_notebook(subs / f"doejane_7_1_{NAME}.ipynb", "101")
    ann = _id_notebook(subs / f"roeann_101_2_{NAME}.ipynb", "102")
    stamps = tmp_path / "times.csv"
    stamps.write_text("id,submitted_at\n101,2026-10-25T12:00+02:00\n")
    entries = [Submission("101", jane), Submission("102", ann)]
    due = parse_due("2026-10-20T23:59+02:00")
    records, notes = late_records(entries, subs, due, parse_policy(None), stamps)
    assert records["101"]["days"] == 5 and records["102"]["days"] == 0
    assert notes == [f"1 submission(s) not in {stamps}: taken as handed in on time"]


def test_the_due_date_and_policy_of_checks_py_and_the_command_line_wins(tmp_path):
    from types import SimpleNamespace

    from course.grading.batch.driver import _late_work
    from course.grading.batch.intake import Submission
    from course.grading.batch.late import LateError, parse_due, parse_policy

    subs = tmp_path / "subs"
    path = _id_notebook(subs / f"doejane_LATE_101_501_{NAME}.ipynb", "s001")
    entries = [Submission("s001", path)]
    checks = SimpleNamespace(due="2026-10-20T23:59Z", late_policy="percent-per-day:5")
    records, _ = _late_work(checks, entries, subs, _options())
    assert records["s001"]["due"] == "2026-10-20T23:59+00:00"
    assert records["s001"]["percent"] == 5  # _LATE_ without a time: one day
    options = _options(due=parse_due(DUE_CLI), late_policy=parse_policy("percent-per-day:20"))
    records, _ = _late_work(checks, entries, subs, options)
    assert records["s001"]["due"] == DUE_CLI and records["s001"]["percent"] == 20
    with pytest.raises(LateError, match=r"due= in checks\.py 'friday'"):
        _late_work(SimpleNamespace(due="friday", late_policy=None), entries, subs, _options())


DUE_CLI = "2026-10-21T12:00+02:00"
