"""The typed results of a grading (course.grading.batch.results): the JSON they write, and the
status of a function question decided from what its cases did, not from their messages' text."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest

from course.grading.batch.results import CaseResult, QuestionResult, StudentResult
from course.grading.batch.session import _CaseRun
from course.grading.vocabulary import GradeStatus

ROW = {
    "assignment": "01_least_squares",
    "checks_sha256": "ab" * 32,
    "data_key": "public",
    "file": None,
    "max": 4.0,
    "notes": ["STUDENT_ID was not set in the notebook; graded as 's1'."],
    "questions": {
        "q1": {
            "cases": [{"label": "x", "ok": False, "message": "x: wrong sign", "detail": ""}],
            "max": 1.0,
            "message": "x: wrong sign",
            "points": 0.0,
            "status": "fail",
        },
        "q2": {
            "answer": "because",
            "cases": [],
            "max": 2,
            "message": "your instructor marks this answer",
            "points": 0.0,
            "status": "to mark",
        },
        "q3": {
            "cases": [
                {"label": "small", "ok": True, "message": ""},
                {"label": "hidden case 1", "ok": False, "message": "raised ValueError: no"},
            ],
            "max": 1.0,
            "message": "hidden case 1: raised ValueError: no",
            "points": 0.5,
            "status": "partial",
        },
    },
    "status": "ok",
    "student": "s1",
    "total": 0.5,
    "version": "0.2.0",
    "wall_seconds": 1.25,
}


def _dumps(row: dict) -> str:
    return json.dumps(row, sort_keys=True, ensure_ascii=False)


@pytest.mark.parametrize(
    "change",
    [
        {},
        {"deleted_answers": {"q1": "adopted"}},
        {"file": {"name": "s1.ipynb", "sha256": "00" * 32}},
        {"from_another_version": [1, 2]},  # kept as read: a resumed row is rewritten unchanged
    ],
)
def test_a_row_reads_and_writes_back_byte_for_byte(change):
    row = {**ROW, **change}
    assert _dumps(StudentResult.from_json(json.loads(_dumps(row))).to_json()) == _dumps(row)


def test_optional_keys_are_written_only_when_set():
    row = StudentResult("s1", "a", "d", "v", "public", 1.0)
    assert set(row.to_json()) == {
        "student", "assignment", "checks_sha256", "version", "data_key",
        "questions", "notes", "total", "max", "status",
    }  # fmt: skip
    row.record_file(None)  # the driver records "no file" as null
    assert row.to_json()["file"] is None
    assert "answer" not in QuestionResult(0.0, 1.0, "pass").to_json()
    assert "detail" not in CaseResult("x", True).to_json()
    assert CaseResult("x", False, detail="").to_json()["detail"] == ""
    assert "raised" not in CaseResult("x", False, raised=True).to_json()


@pytest.mark.parametrize("line", ["", "{", "[]", '{"student": "s1"}', '"s1"'])
def test_read_results_skips_what_is_not_a_row(tmp_path, line):
    from course.grading.batch.reports import read_results

    path = tmp_path / "results.jsonl"
    path.write_text(line + "\n" + _dumps(ROW) + "\n")
    assert list(read_results(path)) == ["s1"]


Q = SimpleNamespace(points=2.0, partial=True)


def _status(*cases: CaseResult, stop=None) -> tuple[str, float, str]:
    run = _CaseRun()
    for case in cases:
        (run.results.append if case.ok else run.fail)(case)
    if stop is not None:
        run.stop(*stop)
    r = run.result(Q)
    return str(r.status), r.points, r.message


def test_every_failed_case_raised_is_an_error():
    raised = CaseResult("a", False, "raised ValueError: no", raised=True)
    assert _status(raised, raised) == ("error", 0.0, "a: raised ValueError: no")


def test_a_wrong_value_whose_message_begins_with_raised_is_a_fail():
    # a declared mistake may well read "raised to the wrong power": it is a wrong value, not
    # an exception (the status used to be read from the message's first word)
    wrong = CaseResult("a", False, "raised to the wrong power")
    assert _status(wrong)[0] == "fail"


def test_partial_and_the_first_failure_message():
    ok = CaseResult("a", True)
    assert _status(ok, CaseResult("b", False, "too large"), CaseResult("c", False, "nan")) == (
        "partial",
        round(2.0 / 3, 4),
        "b: too large",
    )
    assert _status(ok, ok) == ("pass", 2.0, "")


def test_a_stopping_status_stays_and_its_message_replaces_the_first_failure():
    late = (GradeStatus.TIMEOUT, "f did not return within 1 s on b and was stopped")
    status, points, message = _status(
        CaseResult("a", True), CaseResult("b", False, "wrong"), stop=late
    )
    assert (status, points, message) == ("timeout", 1.0, late[1])
    skipped = (GradeStatus.SKIPPED, "the time budget for this submission ran out", True)
    assert _status(CaseResult("a", False, "wrong"), stop=skipped)[2] == "a: wrong"
