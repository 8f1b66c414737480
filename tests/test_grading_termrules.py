"""The term's rules in the gradebook (issue 35 item 3): weights, drop-lowest, letters and pass
marks, exemptions and extensions, read by ``course gradebook --rules`` and by late work
(``course grade --extensions``)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from course.cli import main as course_main
from course.grading.batch.reports import append_result
from course.grading.batch.results import QuestionResult, StudentResult

ROSTER = (
    "id,name,email\n"
    "s1,Ada One,s1@uni.example\n"
    "s2,Bo Two,s2@uni.example\n"
    "s3,Cy Three,s3@uni.example\n"
    "s4,Di Four,s4@uni.example\n"
    "s5,Ed Five,s5@uni.example\n"
)
#: s4 handed A4 in a day late (20 % deducted: 20 -> 16); the extension moves the due date past it
LATE = {
    "submitted_at": "2026-11-02T10:00+01:00",
    "due": "2026-11-01T23:59+01:00",
    "source": "timestamps file",
    "days": 1,
    "percent": 20.0,
    "policy": "20 % of the points possible per started day late",
}
SCORES = {  # assignment -> (points possible, {student: points}); absent: no submission
    "A1": (10, {"s1": 10, "s2": 5, "s3": 4, "s4": 7, "s5": 9}),
    "A2": (10, {"s1": 8, "s3": 0, "s4": 7, "s5": 6}),  # s2 did not submit; s3 is exempt
    "A3": (10, {"s1": 6, "s2": 9, "s3": 8, "s4": 7, "s5": 8}),
    "A4": (20, {"s1": 18, "s2": 15, "s3": 10, "s4": 20}),  # s5 is exempt from the exam
}
RULES: dict = {
    "categories": [
        {"name": "homework", "weight": 40, "assignments": ["A1", "A2", "A3"], "drop_lowest": 1},
        {"name": "exam", "weight": 60, "assignments": ["A4"]},
    ],
    "letters": {"A": 90, "B": 80, "C": 70, "D": 60, "F": 0},
    "pass": 65,
    "exemptions": [{"id": "s3", "assignment": "A2"}, {"id": "s5", "assignment": "A4"}],
    "extensions": "extensions.csv",
}


def _term(tmp_path: Path, extension_due: str = "2026-11-03T23:59+01:00") -> list[Path]:
    outs = []
    for name, (maximum, points) in SCORES.items():
        out = tmp_path / name
        out.mkdir()
        for sid, p in points.items():
            row = StudentResult(sid, name, "c" * 64, "1.0", "public", maximum)
            row.questions = {"q1": QuestionResult(p, maximum, "pass" if p == maximum else "fail")}
            row.add_total()
            if (sid, name) == ("s4", "A4"):
                row.set_late(LATE)
                assert row.total == 16
            append_result(row, out / "results.jsonl")
        outs.append(out)
    (tmp_path / "term.json").write_text(json.dumps(RULES), encoding="utf-8")
    (tmp_path / "extensions.csv").write_text(f"id,assignment,due\ns4,A4,{extension_due}\n")
    (tmp_path / "roster.csv").write_text(ROSTER, encoding="utf-8")
    return outs


def _gradebook(tmp_path: Path, outs: list[Path], *extra: str) -> int:
    return course_main(
        [
            "gradebook",
            *map(str, outs),
            "--out",
            str(tmp_path / "book"),
            "--rules",
            str(tmp_path / "term.json"),
            *extra,
        ]
    )


def test_weights_drop_lowest_an_exemption_and_an_extension_give_the_hand_computed_grades(
    tmp_path, capsys
):
    """By hand (homework 40 %, its lowest share dropped; exam 60 %):

    s1: hw (10 + 8) / 20 = 90 (A3 dropped), exam 18/20 = 90 -> 90, A;
    s2: A2 missing counts 0 and is dropped: hw (5 + 9) / 20 = 70, exam 75 -> 28 + 45 = 73, C;
    s3: exempt from A2, A1 (0.4) dropped: hw 8/10 = 80, exam 50 -> 32 + 30 = 62, D, fail
        (with A2 a 0 it would be 54, F);
    s4: the three 7s tie, the first (A1) dropped: hw 70; the extension waives the exam's
        late deduction: 20/20 = 100 -> 28 + 60 = 88, B (without it 76, C);
    s5: exempt from the exam, which gives its weight to homework: A2 dropped, hw 17/20 = 85
        -> 85, B (its blank as a 0 would give 34, F).
    """
    outs = _term(tmp_path)
    assert _gradebook(tmp_path, outs, "--roster", str(tmp_path / "roster.csv")) == 0, (
        capsys.readouterr().err
    )
    book = list(csv.reader((tmp_path / "book" / "gradebook.csv").open(encoding="utf-8")))
    assert book == [
        ["student", "A1", "A2", "A3", "A4", "homework %", "exam %", "dropped", "percent",
         "letter", "pass"],
        ["s1", "10", "8", "6", "18", "90", "90", "A3", "90", "A", "pass"],
        ["s2", "5", "", "9", "15", "70", "75", "A2", "73", "C", "pass"],
        ["s3", "4", "EX", "8", "10", "80", "50", "A1", "62", "D", "fail"],
        ["s4", "7", "7", "7", "20", "70", "100", "A1", "88", "B", "pass"],
        ["s5", "9", "6", "8", "EX", "85", "", "A2", "85", "B", "pass"],
    ]  # fmt: skip
    canvas = list(csv.reader((tmp_path / "book" / "canvas.csv").open(encoding="utf-8")))
    assert canvas[0][5:] == ["A1", "A2", "A3", "A4"]  # Canvas computes its own total
    assert canvas[1][5:] == ["10", "10", "10", "20"]
    by_id = {r[2]: r[5:] for r in canvas[2:]}
    assert by_id["s3"] == ["4", "EX", "8", "10"] and by_id["s5"][3] == "EX"  # Canvas: excused
    moodle = list(csv.reader((tmp_path / "book" / "moodle.csv").open(encoding="utf-8")))
    assert moodle[0][4:] == ["A1", "A2", "A3", "A4", "Final %", "Letter"]
    assert moodle[3][4:] == ["4", "", "8", "10", "62", "D"]  # an exemption is no grade
    assert moodle[5][4:] == ["9", "6", "8", "", "85", "B"]


def test_missing_as_zero_never_zeroes_an_exemption(tmp_path):
    outs = _term(tmp_path)
    assert _gradebook(tmp_path, outs, "--missing-as-zero") == 0
    book = list(csv.DictReader((tmp_path / "book" / "gradebook.csv").open(encoding="utf-8")))
    s2, s3 = book[1], book[2]
    assert (s2["A2"], s3["A2"], s3["percent"]) == ("0", "EX", "62")


def test_an_extension_that_still_leaves_the_file_late_asks_for_a_regrade(tmp_path, capsys):
    outs = _term(tmp_path, extension_due="2026-11-02T09:00+01:00")
    assert _gradebook(tmp_path, outs) == 2
    err = capsys.readouterr().err
    assert "s4, A4" in err and "--extensions FILE" in err


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"categories": []}, "at least one category"),
        ({"weights": {}}, "unknown key"),
        ({"letters": {"A": 90, "B": 80}}, "lowest letter at 0"),
        ({"exemptions": [{"id": "s1"}]}, "exemptions"),
        (
            {
                "categories": [
                    {"name": "hw", "weight": 1, "assignments": ["A1", "A2"], "drop_lowest": 2}
                ]
            },
            "drops 2 of its 2",
        ),
        (
            {"categories": [{"name": "hw", "weight": 1, "assignments": ["A1", "A2", "A3"]}]},
            "A4 in no category",
        ),
        (
            {
                "categories": RULES["categories"]
                + [{"name": "x", "weight": 1, "assignments": ["A9"]}]
            },
            "'A9' is no assignment",
        ),
    ],
)
def test_rules_that_cannot_be_used_are_refused_with_the_fix(tmp_path, capsys, change, message):
    outs = _term(tmp_path)
    (tmp_path / "term.json").write_text(json.dumps({**RULES, **change}), encoding="utf-8")
    assert _gradebook(tmp_path, outs) == 2
    assert message in capsys.readouterr().err


def test_grade_extensions_move_one_students_due_date(tmp_path):
    """``course grade --extensions``: s2's own due date makes the same hand-in time on time."""
    from course.grading.batch.intake import Submission
    from course.grading.batch.late import (
        extensions_for,
        late_records,
        parse_due,
        parse_policy,
        read_extensions,
    )

    subs = tmp_path / "subs"
    subs.mkdir()
    entries = []
    for sid in ("s1", "s2"):
        (subs / f"{sid}.ipynb").write_text("{}")
        entries.append(Submission(sid, subs / f"{sid}.ipynb"))
    stamps = tmp_path / "times.csv"
    stamps.write_text("id,submitted_at\ns1,2026-10-22T09:00+02:00\ns2,2026-10-22T09:00+02:00\n")
    ext = tmp_path / "extensions.csv"
    # a quoted cell with a semicolon and a tab: one fixed dialect, never a guessed delimiter
    ext.write_text(
        'id,assignment,due\ns2,01_least_squares,2026-10-23T23:59+02:00\n"s;3\t",other,'
        "2026-10-23T23:59+02:00\n"
    )
    table = read_extensions(ext)
    assert set(table) == {("s2", "01_least_squares"), ("s;3", "other")}  # cells stripped
    mine = extensions_for(table, "01_least_squares", "Least squares")
    due = parse_due("2026-10-20T23:59+02:00")
    records, _ = late_records(
        entries, subs, due, parse_policy("percent-per-day:10"), stamps, extensions=mine
    )
    assert (records["s1"]["days"], records["s1"]["percent"]) == (2, 20)
    assert (records["s2"]["days"], records["s2"]["due"]) == (0, "2026-10-23T23:59+02:00")


def test_course_grade_extensions_reach_late_work_by_folder_name_or_title(tmp_path):
    from types import SimpleNamespace

    from course.grading.batch.driver import _late_work
    from course.grading.batch.intake import Submission
    from course.grading.batch.options import GradeOptions

    subs = tmp_path / "subs"
    subs.mkdir()
    entries = []
    for sid in ("s1", "s2", "s3"):
        (subs / f"{sid}.ipynb").write_text("{}")
        entries.append(Submission(sid, subs / f"{sid}.ipynb"))
    stamps = tmp_path / "times.csv"
    stamps.write_text("id,submitted_at\n" + "".join(f"{s},2026-10-22T09:00+02:00\n" for s in
                                                    ("s1", "s2", "s3")))  # fmt: skip
    ext = tmp_path / "extensions.csv"
    ext.write_text(
        "id,assignment,due\n"
        "s2,01_least_squares,2026-10-23T23:59+02:00\n"  # by folder name
        "s3,Least squares,2026-10-24T23:59+02:00\n"  # by title
        "s1,02_other,2026-10-30T23:59+02:00\n"  # another assignment's: not this one's
    )
    checks = SimpleNamespace(
        name="01_least_squares",
        title="Least squares",
        due="2026-10-20T23:59+02:00",
        late_policy="percent-per-day:10",
    )
    options = GradeOptions(jobs=1, progress=False, submitted_at=stamps, extensions=ext)
    records, _ = _late_work(checks, entries, subs, options)
    assert [records[s]["percent"] for s in ("s1", "s2", "s3")] == [20, 0, 0]
    assert records["s3"]["due"] == "2026-10-24T23:59+02:00"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("student;assignment;due\ns1;A1;2026-10-23T23:59Z\n", "needs the header id,assignment,due"),
        ("id,assignment,due\ns1,A1,friday\n", "line 2: due 'friday'"),
        ("id,assignment,due\ns1,A1,2026-10-23T23:59\n", "no time zone"),
        (
            "id,assignment,due\ns1,A1,2026-10-23T23:59+00:00\ns1,A1,2026-10-24T23:59+00:00\n",
            "a second",
        ),
    ],
)
def test_an_extensions_file_that_cannot_be_read_is_refused(tmp_path, text, message):
    from course.grading.batch.late import LateError, read_extensions

    (tmp_path / "e.csv").write_text(text)
    with pytest.raises(LateError, match=message):
        read_extensions(tmp_path / "e.csv")
