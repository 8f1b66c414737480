"""Issue 34: the term's record (``record.sqlite``), faults that are retried and never graded,
and blank meaning blank in the LMS files.

The record's API is tested directly; the faults through real grading runs of a small assignment
(``test_grading_items``'s), with the run folder deleted mid-run as another process would.
"""

from __future__ import annotations

import csv
import json
import shutil
import sqlite3
import threading
from pathlib import Path

import pytest
from test_grading_items import NAME, RIGHT, _course, _student

from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions
from course.grading.batch.record import RECORD_FILE, Record
from course.grading.batch.results import QuestionResult, StudentResult
from course.grading.batch.roster import read_roster
from course.grading.batch.session import AssignmentGrader

STUDENTS = ("s1", "s2", "s3", "s4")


def _row(sid: str, points: float, status: str = "ok") -> StudentResult:
    row = StudentResult(sid, NAME, "c" * 64, "1.0", "public", 3.0, status=status)
    row.questions = {
        "q2": QuestionResult(points, 2.0, "ok"),
        "q1": QuestionResult(1.0, 1.0, "ok"),
    }
    row.add_total()
    return row


# -- the record's API -----------------------------------------------------------------------
def test_the_record_keeps_every_change_of_a_grade_with_who_and_when(tmp_path):
    with Record(tmp_path, who="ann") as record:
        record.put_result(_row("s1", 1.0))
        record.put_result(_row("s1", 1.0))  # the same grade: no new event
        record.put_result(_row("s1", 2.0), who="bob")
        assert record.results()["s1"].total == 3.0
        history = record.history("s1")
    assert [(who, kind) for _, who, kind, _, _ in history] == [("ann", "grade"), ("bob", "grade")]
    assert history[0][4].startswith("2/3 ok") and history[1][4].startswith("3/3 ok")
    assert all(at.endswith("Z") for at, *_ in history)
    con = sqlite3.connect(tmp_path / RECORD_FILE)
    assert con.execute("PRAGMA journal_mode").fetchone() == ("wal",)


def test_two_writers_at_once_lose_no_mark(tmp_path):
    """Two connections (two markers' views) give marks in parallel threads: all land."""
    answers = [
        {
            "student": f"s{i}",
            "question": "q3",
            "answer_id": f"{i:012d}",
            "text": f"answer {i}",
            "points_possible": 2.0,
            "rubric": "",
        }
        for i in range(40)
    ]
    with Record(tmp_path) as record:
        record.set_answers(answers)

    def mark(who: str, part: list) -> None:
        with Record(tmp_path, who=who) as mine:
            for a in part:
                mine.set_mark(a["student"], "q3", a["answer_id"], 1.0, f"by {who}")

    threads = [
        threading.Thread(target=mark, args=(who, answers[k::2]))
        for k, who in enumerate(("ann", "bob"))
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    with Record(tmp_path) as record:
        marks = record.marks()
    assert len(marks) == 40
    assert {m["q3"]["who"] for m in marks.values()} == {"ann", "bob"}


def test_a_mark_for_an_answer_no_longer_current_is_refused(tmp_path):
    with Record(tmp_path) as record:
        record.set_answers(
            [
                {
                    "student": "s1",
                    "question": "q3",
                    "answer_id": "aaaaaaaaaaaa",
                    "text": "x",
                    "points_possible": 2,
                    "rubric": "",
                }
            ]
        )
        with pytest.raises(ValueError, match="no longer"):
            record.set_mark("s1", "q3", "bbbbbbbbbbbb", 1.0)
        assert record.marks() == {}


def test_an_older_folder_is_imported_once_with_a_message(tmp_path):
    rows = [_row("s1", 1.0), _row("s2", 2.0)]
    (tmp_path / "results.jsonl").write_text(
        "".join(json.dumps(r.to_json()) + "\n" for r in rows) + "{cut short\n"
    )
    (tmp_path / "short_answer_marks.json").write_text(
        json.dumps({"s1": {"q3": {"points": 1.5, "comment": "ok", "answer_id": "abc"}}})
    )
    with Record(tmp_path) as record:
        message = record.import_old(
            tmp_path / "results.jsonl", tmp_path / "short_answer_marks.json"
        )
        assert "Imported 2 row(s) of results.jsonl and 1 mark(s)" in message
        assert set(record.results()) == {"s1", "s2"}
        assert record.marks()["s1"]["q3"]["points"] == 1.5
    with Record(tmp_path) as record:  # once: the record is the truth from now on
        assert record.import_old(tmp_path / "results.jsonl") == ""


def test_rows_read_back_list_questions_in_the_notebooks_order(tmp_path):
    """Old code: results.jsonl was written with sorted keys, so a resumed row listed its
    questions sorted (q10 before q2) and its feedback differed from a fresh run's."""
    row = _row("s1", 1.0)
    assert list(row.questions) == ["q2", "q1"]
    back = StudentResult.from_json(json.loads(json.dumps(row.to_json(), sort_keys=True)))
    back.order_questions(["q2", "q1"])
    assert list(back.questions) == ["q2", "q1"]


# -- faults are retried, never graded ---------------------------------------------------------
@pytest.fixture(scope="module")
def course(tmp_path_factory):
    root = tmp_path_factory.mktemp("record")
    _course(root)
    subs = root / "subs"
    subs.mkdir()
    for sid in STUDENTS:
        (subs / f"{sid}.ipynb").write_text(json.dumps(_student(root, RIGHT)))
    (root / "roster.csv").write_text(
        "id,name,email\n" + "".join(f"{s},N {s},{s}@x.org\n" for s in (*STUDENTS, "s9"))
    )
    return root


def _options(root: Path, **kw) -> GradeOptions:
    return GradeOptions(jobs=1, progress=False, roster=read_roster(root / "roster.csv"), **kw)


def _canvas(out: Path) -> dict:
    return {r[2]: r[5] for r in csv.reader((out / "canvas.csv").open(encoding="utf-8"))}


def test_the_run_folder_deleted_mid_run_costs_no_grade(course, tmp_path, monkeypatch):
    """Old code: once another process removed the run folder, every later student got
    0 `grader error`, and the next plain run resumed those zeros as grades."""
    real = AssignmentGrader.grade_one
    done: list[str] = []

    def grade_one(self, sid, *args, **kwargs):
        row = real(self, sid, *args, **kwargs)
        if not done:  # after the first student: a cleaner of /tmp removes the run folder
            shutil.rmtree(self.sandbox._rundir)
        done.append(sid)
        return row

    monkeypatch.setattr(AssignmentGrader, "grade_one", grade_one)
    out = tmp_path / "out"
    summary = grade(course / "solutions" / NAME, course / "subs", out, _options(course))
    assert sorted(done) == list(STUDENTS)
    assert {r.student: r.status for r in summary.rows} == dict.fromkeys(STUDENTS, "ok")
    assert all(r.questions["q1"].points == 1 for r in summary.rows)
    assert not summary.not_graded


def test_a_fault_that_persists_is_not_graded_blank_and_regraded_next_run(
    course, tmp_path, monkeypatch, capsys
):
    from course.cli import main
    from course.grading.sandbox.parent import Sandbox

    real = Sandbox.start
    calls = {"s3": 0}

    def start(self, init, *args, **kwargs):  # s3's grading always loses its sandbox
        if init.get("student_id") == "s3":
            calls["s3"] += 1
            raise OSError("the run folder is gone")
        return real(self, init, *args, **kwargs)

    monkeypatch.setattr(Sandbox, "start", start)
    out = tmp_path / "out"
    argv = [
        "grade",
        str(course / "solutions" / NAME),
        str(course / "subs"),
        "--out",
        str(out),
        "--roster",
        str(course / "roster.csv"),
        "--jobs",
        "1",
        "--no-progress",
        "--no-secret",
    ]
    assert main(argv) == 1  # a fault of the grader is no finished run
    text = capsys.readouterr().out
    assert calls["s3"] == 3  # graded once, retried twice
    assert "NOT GRADED: 1 submission(s)" in text and ": s3; grade them again with" in text
    assert f"course grade {NAME} " in text
    assert _canvas(out)["s3"] == "" and _canvas(out)["s1"] != ""
    moodle = {r[0]: r for r in csv.reader((out / "moodle.csv").open(encoding="utf-8"))}
    assert moodle["s3"][4] == "" and moodle["s3"][-1].startswith("Not graded")
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    assert grades["s3"]["total"] == "" and grades["s3"]["status"] == "not graded"
    with Record(out) as record:
        assert record.not_graded() == ["s3"] and "s3" not in record.results()
    page = (out / "report.html").read_text()
    assert "No grade: 1 student(s)" in page and "<td>s3</td><td>not graded</td>" in page
    assert "3 student(s); total out of" in page  # s3 is not a 0 in the numbers
    # the next plain run grades s3 (and only s3)
    monkeypatch.setattr(Sandbox, "start", real)
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "Graded 1 submission(s) (1 regraded: not graded last time" in text
    assert _canvas(out)["s3"] == _canvas(out)["s1"] != ""
    assert main(["history", str(out), "s3"]) == 0
    history = capsys.readouterr().out
    assert history.index("NOT GRADED") < history.index("grade      3/5")


def test_quarantined_and_refused_students_are_blank_not_zero(course, tmp_path):
    """Old code: a refused (or quarantined) submission was 0 in canvas.csv and moodle.csv."""
    subs = tmp_path / "subs"
    shutil.copytree(course / "subs", subs)
    (subs / "s4.ipynb").unlink()
    (subs / "s4.ipynb").symlink_to(subs / "s1.ipynb")  # refused: a symbolic link
    out = tmp_path / "out"
    summary = grade(course / "solutions" / NAME, subs, out, _options(course))
    assert {r.student: r.status for r in summary.rows}["s4"] == "refused"
    assert _canvas(out)["s4"] == "" and _canvas(out)["s9"] == ""  # refused, missing
    moodle = {r[0]: r for r in csv.reader((out / "moodle.csv").open(encoding="utf-8"))}
    assert moodle["s4"][4] == "" and "symbolic link" in moodle["s4"][-1]
    # a corrected file is graded and replaces the blank
    (subs / "s4.ipynb").unlink()
    shutil.copy(course / "subs" / "s1.ipynb", subs / "s4.ipynb")
    grade(course / "solutions" / NAME, subs, out, _options(course))
    assert _canvas(out)["s4"] == _canvas(out)["s1"] != ""


def test_the_grading_parent_limits_its_own_blas_threads(tmp_path):
    """`course grade` sets one BLAS thread before numpy is imported (the parent's own linear
    algebra is tiny; an OpenBLAS pool only spins around it)."""
    import subprocess
    import sys

    code = (
        "import os, sys\n"
        "from course.cli import main\n"
        "os.environ.pop('OPENBLAS_NUM_THREADS', None)\n"
        f"main(['grade', 'no-such-assignment', {str(tmp_path)!r}, '--out', 'o'])\n"
        "print(os.environ.get('OPENBLAS_NUM_THREADS'), os.environ.get('OMP_NUM_THREADS'))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert done.stdout.split()[-2:] == ["1", "1"], done.stderr
