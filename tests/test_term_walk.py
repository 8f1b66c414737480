"""The term of ``docs/instructors/term.md`` walked in one go, as an instructor runs it (issue 27).

Class secret, a Canvas roster export, the student edition, submissions named as Canvas names its
downloads (a typo'd notebook ID attached by the Canvas user number, a ``_LATE_`` file with a
time in the timestamps file, a resubmission on a second run marked ``_LATE_`` without a time),
a due date and a late policy, two short answers marked and re-imported, a two-assignment
gradebook; then every file the instructor uploads is checked for its columns and the
penalised totals.

The shared graded classes (``graded_class``) are graded without a secret or a roster, so this
walk grades its own small class: four students, two assignments, four ``course grade`` runs
of which the last only merges marks (no sandbox).
"""

from __future__ import annotations

import csv
import shutil
import zipfile
from pathlib import Path

import nbformat
import pytest

from course.cli import main as course_main
from course.grading.authoring.checks import load_checks
from course.grading.authoring.export import export
from course.grading.authoring.personal import PersonalData
from course.grading.authoring.secret import load_secret
from course.grading.batch.roster import read_roster
from course.grading.student.submit import make_submission

ROOT = Path(__file__).resolve().parents[1]
A1, A3 = "01_least_squares", "03_estimation_and_likelihood"
DUE = "2026-10-20T23:59+02:00"
ROSTER = (
    "Student,ID,SIS User ID,SIS Login ID,Section\n"
    "    Points Possible,,,,\n"
    '"Doe, Jane",101,s001,jdoe,A\n'
    '"Roe, Ann",102,s002,aroe,A\n'
    '"Poe, Ed",103,s003,epoe,A\n'
    '"Kay, Kim",104,s004,kkay,A\n'
    '"Student, Test",999,,,A\n'
)


def _saved(tmp: Path, assignment: str, sid: str, stub: bool = False) -> Path:
    """The notebook a student saves: the solution (or the untouched release) with their ID."""
    source = ROOT / ("exercises" if stub else "solutions") / assignment / f"{assignment}.ipynb"
    nb = nbformat.read(source, as_version=4)
    for cell in nb.cells:
        if cell.get("id") == "setup":
            for placeholder in ('"demo"', '"replace-with-your-student-id"'):
                cell.source = cell.source.replace(
                    f"STUDENT_ID = {placeholder}", f'STUDENT_ID = "{sid}"'
                )
    path = tmp / "students" / sid / f"{assignment}.ipynb"
    path.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, path)
    return path


def _upload(path: Path, subs: Path, canvas_name: str) -> Path:
    """Canvas's download name: ``lastfirst[_LATE]_<user number>_<submission number>_<file>``."""
    subs.mkdir(parents=True, exist_ok=True)
    target = subs / f"{canvas_name}_{path.name}"
    shutil.copyfile(path, target)
    return target


def _table(path: Path) -> list[list[str]]:
    return list(csv.reader(path.open(encoding="utf-8")))


def _grade(capsys, *args: str) -> str:
    code = course_main(["grade", *args, "--no-progress", "--jobs", "2"])
    out, err = capsys.readouterr()
    assert code == 0, err
    return out


@pytest.mark.slow
def test_a_term_from_the_secret_to_the_gradebook(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("COURSE_SECRET_FILE", raising=False)
    # 1. the class's secret; 2. the roster (Canvas's gradebook export as it comes)
    key = tmp_path / "class.key"
    assert course_main(["secret", "new", str(key)]) == 0
    capsys.readouterr()
    secret = load_secret(str(key))
    roster_file = tmp_path / "roster.csv"
    roster_file.write_text(ROSTER, encoding="utf-8")
    roster = read_roster(roster_file)
    # 3. the student edition: every roster student's data drawn with the key
    edition = export(tmp_path / "handout", secret=secret, roster=roster, check_leaks=False)
    assert edition.data_key == secret.key_id and edition.students == 4
    exercises = edition.folder / "course" / "materials" / "exercises"
    issued = {name: PersonalData.read(exercises / name) for name in (A1, A3)}

    def submit(assignment: str, sid: str, stub: bool = False) -> Path:
        path, _, _ = make_submission(
            _saved(tmp_path, assignment, sid, stub), None, assignment, None, issued[assignment]
        )
        return path

    # 5. collect assignment 01 as Canvas names the downloads
    subs1 = tmp_path / "submissions" / "01"
    _upload(submit(A1, "s001"), subs1, "doejane_101_5001")
    _upload(submit(A1, "s002", stub=True), subs1, "roeann_102_5002")  # untouched release
    # Ed typed s0O3: no submit() (it refuses an ID without issued data), the raw notebook
    _upload(_saved(tmp_path, A1, "s0O3"), subs1, "poeed_103_5003")
    _upload(submit(A1, "s004"), subs1, "kaykim_LATE_104_5004")
    times = tmp_path / "submitted.csv"  # the LMS's times: s004 by its ID, Ed by his user number
    times.write_text(
        "id,submitted_at\ns001,2026-10-20T21:00+02:00\n103,2026-10-20T23:00+02:00\n"
        "s004,2026-10-22T09:30+02:00\n"
    )
    grades1 = tmp_path / "grades" / "01"
    late = [
        "--due",
        DUE,
        "--late-policy",
        "percent-per-day:10,cap:50",
        "--submitted-at",
        str(times),
    ]
    cls = ["--roster", str(roster_file), "--secret", str(key)]
    a1 = str(ROOT / "solutions" / A1)
    text = _grade(capsys, a1, str(subs1), "--out", str(grades1), *cls, *late)
    max1 = load_checks(ROOT / "solutions" / A1).max_points
    # the typo'd ID is graded for the student Canvas names, and said so (console, csv, feedback)
    assert "'s0O3', which is not on the roster; graded as 's003'" in text
    conflicts = _table(grades1 / "identity_conflicts.csv")
    assert conflicts[0][-1] == "decision" and conflicts[1][:3] == [
        f"poeed_103_5003_{A1}.ipynb", "s003", "s0O3"
    ] and conflicts[1][-1] == "graded as s003"  # fmt: skip
    assert "not on the class list" in (grades1 / "feedback" / "s003.md").read_text("utf-8")
    assert "Late: 1 submission(s): s004 (2 days, -" in text
    assert f"; due {DUE}; 10 % of the points possible per started day late, at most 50 %" in text
    grades = {r["student"]: r for r in csv.DictReader((grades1 / "grades.csv").open())}
    assert sorted(grades) == ["s001", "s002", "s003", "s004"]
    assert (grades["s001"]["total"], grades["s001"]["late"], grades["s001"]["penalty"]) == (
        f"{max1:g}",
        "0",
        "0",
    )
    assert grades["s004"]["late"] == "2" and float(grades["s004"]["total"]) == pytest.approx(
        0.8 * max1
    )
    stub_total = float(grades["s002"]["total"])
    assert stub_total < max1

    # a resubmission: Ann uploads the whole solution after the due date; Canvas marks it
    # _LATE_, the timestamps file has no row for it: late by an unknown time, charged 1 day
    _upload(submit(A1, "s002"), subs1, "roeann_LATE_102_5010")
    text = _grade(capsys, a1, str(subs1), "--out", str(grades1), *cls, *late)
    assert "Graded 1 submission(s) (1 regraded: file changed), 3 already graded" in text
    assert "(the last in the LMS's order: the highest Canvas submission number" in text
    assert "charged as 1 day late" in text and "s002" in text
    grades = {r["student"]: r for r in csv.DictReader((grades1 / "grades.csv").open())}
    assert grades["s002"]["late"] == "unknown"
    assert float(grades["s002"]["total"]) == pytest.approx(0.9 * max1)
    assert float(grades["s002"]["penalty"]) == pytest.approx(0.1 * max1)
    feedback = (grades1 / "feedback" / "s004.md").read_text("utf-8")
    assert "**Late:** Handed in 2026-10-22T09:30+02:00, 2 days after the due date" in feedback
    report = (grades1 / "report.html").read_text("utf-8")
    assert (
        "<h2>Late submissions</h2>" in report
        and "<td>s004</td><td>2026-10-22T09:30+02:00" in report
    )
    # 7. the files the instructor uploads for 01: penalised totals, Canvas's and Moodle's columns
    title1 = load_checks(ROOT / "solutions" / A1).title
    canvas = _table(grades1 / "canvas.csv")
    assert canvas[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", title1]
    assert canvas[1][0].strip() == "Points Possible" and canvas[1][5] == f"{max1:g}"
    by_sis = {r[2]: r for r in canvas[2:]}
    assert sorted(by_sis) == ["s001", "s002", "s003", "s004"]  # no test student
    assert by_sis["s004"][:2] == ["Kay, Kim", "104"]
    for sid in by_sis:
        assert by_sis[sid][5] == grades[sid]["total"]
    moodle = _table(grades1 / "moodle.csv")
    assert moodle[0] == [
        "ID number",
        "Email address",
        "First name",
        "Last name",
        title1,
        "Feedback",
    ]
    m4 = next(r for r in moodle if r[0] == "s004")
    assert m4[4] == grades["s004"]["total"] and "late deduction 20 %" in m4[5]

    # assignment 03, no due date: two short answers to mark
    subs3 = tmp_path / "submissions" / "03"
    _upload(submit(A3, "s001"), subs3, "doejane_101_6001")
    _upload(submit(A3, "s004"), subs3, "kaykim_104_6004")
    grades3 = tmp_path / "grades" / "03"
    a3 = str(ROOT / "solutions" / A3)
    text = _grade(capsys, a3, str(subs3), "--out", str(grades3), *cls)
    assert "2 to mark" in text
    marking = grades3 / "short_answers.csv"
    rows = list(csv.DictReader(marking.open(encoding="utf-8")))
    assert [(r["student"], r["question"]) for r in rows] == [("s001", "q3b"), ("s004", "q3b")]
    rows[0]["points"], rows[1]["points"], rows[1]["comment"] = "1", "0,5", "Why more powerful?"
    with marking.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    text = _grade(
        capsys, a3, str(subs3), "--out", str(grades3), *cls, "--short-answers", str(marking)
    )
    assert "2 mark(s) imported" in text and "Graded 0 submission(s)" in text
    max3 = load_checks(ROOT / "solutions" / A3).max_points
    grades = {r["student"]: r for r in csv.DictReader((grades3 / "grades.csv").open())}
    assert float(grades["s001"]["total"]) == max3
    assert float(grades["s004"]["total"]) == max3 - 0.5
    assert "Why more powerful?" in (grades3 / "feedback" / "s004.md").read_text("utf-8")
    assert "late" not in grades["s001"]  # no due date, nothing marked late: no late columns

    # 9. the gradebook of the term
    book = tmp_path / "gradebook"
    assert (
        course_main(
            [
                "gradebook",
                str(grades1),
                str(grades3),
                "--out",
                str(book),
                "--roster",
                str(roster_file),
            ]
        )
        == 0
    )
    capsys.readouterr()
    title3 = load_checks(ROOT / "solutions" / A3).title
    rows = {r[0]: r for r in _table(book / "gradebook.csv")}
    assert rows["student"] == ["student", title1, title3, "total", "max"]
    s01 = {r["student"]: r for r in csv.DictReader((grades1 / "grades.csv").open())}
    assert rows["s004"][1:] == [
        s01["s004"]["total"], f"{max3 - 0.5:g}",
        f"{float(s01['s004']['total']) + max3 - 0.5:g}", f"{max1 + max3:g}",
    ]  # fmt: skip
    assert rows["s002"][1:3] == [s01["s002"]["total"], ""]  # penalised, and no 03 submission
    canvas = _table(book / "canvas.csv")
    assert canvas[0][5:] == [title1, title3] and canvas[1][5:] == [f"{max1:g}", f"{max3:g}"]
    assert next(r for r in canvas if r[2] == "s002")[5:] == [s01["s002"]["total"], ""]
    moodle = _table(book / "moodle.csv")
    assert moodle[0][4:] == [title1, title3, "Total"]
    assert next(r for r in moodle if r[0] == "s004")[4:] == rows["s004"][1:4]


# -- issue 34: graded straight from the LMS's own downloads ---------------------------------------
CANVAS_CLASS = ROSTER.replace(
    '"Student, Test",999,,,A\n',
    '"Lee, Lou",105,s005,llee,A\n"Lory, Mal",106,s006,mlory,A\n"Student, Test",999,,,A\n',
)


def _canvas_zip(tmp_path: Path) -> Path:
    """Canvas's "Download Submissions" of a class of six, as it comes."""
    a1, a3 = load_checks(ROOT / "solutions" / A1), ROOT / "solutions" / A3

    def saved(sid, stub=False, assignment=A1):
        return _saved(tmp_path, assignment, sid, stub).read_bytes()

    assert a1.max_points > 0 and a3.is_dir()
    entries = {
        f"doejane_101_5001_{A1}.ipynb": saved("s001"),
        f"roeann_102_5002_{A1}.ipynb": saved("s002", stub=True),
        f"roeann_LATE_102_5010_{A1}-1.ipynb": saved("s002"),  # the resubmission, after the due
        f"poeed_103_5003_{A1}.ipynb": saved("s0O3"),  # a typo'd ID
        "kaykim_104_5004_report.html": b"<p>my answers, as a web page</p>",
        f"leelou_105_5005_{A3}.ipynb": saved("s005", assignment=A3),  # another assignment's
        # Mal uploads her untouched notebook as "s001.ipynb", declaring her classmate's ID
        "lorymal_106_5006_s001.ipynb": saved("s001", stub=True),
    }
    archive = tmp_path / "downloads" / "submissions.zip"
    archive.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in entries.items():
            zf.writestr(name, data)
    return archive


def _moodle_zip(tmp_path: Path) -> tuple[Path, Path]:
    """Moodle's "Download all submissions" (in folders) and its grading worksheet."""
    archive = tmp_path / "downloads" / "moodle.zip"
    archive.parent.mkdir(parents=True, exist_ok=True)
    mallory = "Zed_11_assignsubmission_file__13_assignsubmission_file_"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(
            f"Jane Doe_11_assignsubmission_file_/{A1}.ipynb",
            _saved(tmp_path, A1, "s001").read_bytes(),
        )
        zf.writestr(
            f"Ann Roe_12_assignsubmission_file_/work/final/{A1}.ipynb",
            _saved(tmp_path, A1, "s002").read_bytes(),
        )
        zf.writestr("Ann Roe_12_assignsubmission_file_/notes.pdf", b"%PDF-1.4")
        zf.writestr(f"{mallory}/{A1}.ipynb", _saved(tmp_path, A1, "s001", stub=True).read_bytes())
    sheet = tmp_path / "downloads" / "worksheet.csv"
    sheet.write_text(
        "Identifier,Full name,ID number,Email address,Status,Grade,Maximum Grade,"
        "Last modified (submission),Feedback comments\n"
        'Participant 11,Jane Doe,s001,jd@x,Submitted,,14,"Tuesday, 20 October 2026, 11:00 PM",\n'
        'Participant 12,Ann Roe,s002,ar@x,Submitted,,14,"Thursday, 22 October 2026, 9:15 AM",\n'
        "Participant 13,Zed_11_assignsubmission_file_,s003,z@x,Submitted,,14,"
        '"Tuesday, 20 October 2026, 10:00 PM",\n',
        encoding="utf-8",
    )
    return archive, sheet


@pytest.mark.slow
def test_a_class_graded_straight_from_the_lms_downloads(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("COURSE_SECRET_FILE", raising=False)
    roster = tmp_path / "canvas_roster.csv"
    roster.write_text(CANVAS_CLASS, encoding="utf-8")
    a1 = str(ROOT / "solutions" / A1)
    max1 = load_checks(ROOT / "solutions" / A1).max_points
    title1 = load_checks(ROOT / "solutions" / A1).title
    late = ["--due", DUE, "--late-policy", "percent-per-day:10"]
    out = tmp_path / "grades" / "canvas"
    text = _grade(capsys, a1, str(_canvas_zip(tmp_path)), "--out", str(out), "--roster",
                  str(roster), "--no-secret", *late)  # fmt: skip
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    assert sorted(grades) == ["s001", "s002", "s003", "s004", "s005", "s006"]
    # Jane keeps her own full marks; Mal's upload named after her is Mal's, and said so
    assert float(grades["s001"]["total"]) == max1
    assert float(grades["s006"]["total"]) < max1
    assert "lorymal_106_5006_s001.ipynb: the notebook declares STUDENT_ID 's001'" in text
    assert "graded as 's006''s" in (out / "feedback" / "s006.md").read_text("utf-8")
    # the resubmission is graded, late by a time Canvas does not say (charged one day)
    assert grades["s002"]["late"] == "unknown"
    assert float(grades["s002"]["total"]) == pytest.approx(0.9 * max1)
    assert "'s0O3', which is not on the roster; graded as 's003'" in text
    assert float(grades["s003"]["total"]) == max1
    # what is not a gradable notebook is said against its student, never dropped
    assert (
        "kaykim_104_5004_report.html (s004): handed in kaykim_104_5004_report.html, not a" in text
    )
    assert f"leelou_105_5005_{A3}.ipynb (s005): this is assignment 03's notebook" in text
    assert float(grades["s004"]["total"]) == 0 and float(grades["s005"]["total"]) == 0
    assert "not a notebook" in (out / "feedback" / "s004.md").read_text("utf-8")
    assert "Roster: 0 missing" in text or "missing" not in text.split("Roster:")[-1][:12]
    canvas = _table(out / "canvas.csv")
    assert canvas[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", title1]
    assert canvas[1][0].strip() == "Points Possible" and canvas[1][5] == f"{max1:g}"
    assert (out / "canvas.csv").read_bytes().count(b"\r\n") == 2 + 6  # Canvas's CRLF rows
    by_sis = {r[2]: r for r in canvas[2:]}
    assert sorted(by_sis) == ["s001", "s002", "s003", "s004", "s005", "s006"]
    assert by_sis["s006"][:2] == ["Lory, Mal", "106"]
    for sid in ("s001", "s002", "s003", "s006"):
        assert by_sis[sid][5] == grades[sid]["total"]
    # the feedback back through Canvas's Re-Upload Submissions (issue 35 item 1)
    downloads = zipfile.ZipFile(tmp_path / "downloads" / "submissions.zip").namelist()
    assert course_main(["feedback", str(out), "--lms", "canvas"]) == 0
    printed = capsys.readouterr().out
    assert "Not in it (2): s004: not graded (invalid notebook); s005: not graded (refused)" in (
        printed
    )
    names = zipfile.ZipFile(out / "canvas_feedback.zip").namelist()
    graded = {
        f"doejane_101_5001_{A1}", f"roeann_LATE_102_5010_{A1}-1", f"poeed_103_5003_{A1}",
        "lorymal_106_5006_s001",
    }  # fmt: skip
    assert sorted(names) == sorted(f"{stem}.html" for stem in graded)
    assert all(f"{n[: -len('.html')]}.ipynb" in downloads for n in names)

    # Moodle: the zip and its grading worksheet (roster, participant numbers and times at once)
    archive, sheet = _moodle_zip(tmp_path)
    out = tmp_path / "grades" / "moodle"
    text = _grade(capsys, a1, str(archive), "--out", str(out), "--roster", str(sheet),
                  "--no-secret", *late, "--submitted-at", str(sheet))  # fmt: skip
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    assert sorted(grades) == ["s001", "s002", "s003"]
    assert float(grades["s001"]["total"]) == max1  # participant 13 never borrows 11's place
    assert float(grades["s003"]["total"]) < max1 and grades["s003"]["late"] == "0"
    assert grades["s002"]["late"] == "2"  # Thursday 9:15 against Tuesday 23:59
    assert float(grades["s002"]["total"]) == pytest.approx(0.8 * max1)
    assert "Ann Roe_12_assignsubmission_file_ (s002): handed in notes.pdf, not a" in text
    moodle = _table(out / "moodle.csv")
    assert moodle[0] == ["ID number", "Email address", "First name", "Last name", title1,
                         "Feedback"]  # fmt: skip
    m2 = next(r for r in moodle if r[0] == "s002")
    assert m2[1:4] == ["ar@x", "Ann", "Roe"] and m2[4] == grades["s002"]["total"]
    assert "late deduction 20 %" in m2[5]
    # the feedback back through Moodle's "Upload multiple feedback files in a zip"
    assert course_main(["feedback", str(out), "--lms", "moodle"]) == 0
    folders = {n.split("/")[0] for n in zipfile.ZipFile(archive).namelist()}
    names = zipfile.ZipFile(out / "moodle_feedback.zip").namelist()
    assert len(names) == 3 and all(n.endswith("/feedback.html") for n in names)
    assert {n.split("/")[0] for n in names} == folders
    page = zipfile.ZipFile(out / "moodle_feedback.zip").read(
        "Ann Roe_12_assignsubmission_file_/feedback.html"
    )
    assert b"<h1>" in page and b"late" in page.lower()
