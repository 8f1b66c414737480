"""The class report's item analysis, its tables as CSV files, and the similarity hints (issue 35
items 4 and 5)."""

from __future__ import annotations

import ast
import csv
import importlib
import io
import math
from collections.abc import Mapping
from pathlib import Path

import nbformat
import pytest
from conftest import class_submissions

from course.grading.authoring.checks import load_checks
from course.grading.authoring.release import load_assignment
from course.grading.batch.classreport import report_html, report_tables, write_report
from course.grading.batch.itemanalysis import item_analysis
from course.grading.batch.results import CaseResult, QuestionResult, StudentResult
from course.grading.batch.similarity import MAX_SOURCE_CHARS, fingerprint, similar_groups

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION = ROOT / "solutions" / NAME


def _case(ok: bool, kind: str | None = None) -> CaseResult:
    case = CaseResult("hidden case 1", ok, "" if ok else "wrong")
    if kind is not None:  # the results' per-case kind (issue 35 item 4's vocabulary)
        case.kind = kind  # type: ignore[attr-defined]
    return case


def _row(sid: str, scores: Mapping[str, tuple[float, float]], kinds=None) -> StudentResult:
    """A graded row: question -> (points, max); ``kinds``: question -> kind of its failed case."""
    kinds = kinds or {}
    row = StudentResult(sid, NAME, "c" * 64, "v", "public", sum(m for _, m in scores.values()))
    for qid, (points, maximum) in scores.items():
        ok = points >= maximum
        kind = kinds.get(qid)
        row.questions[qid] = QuestionResult(
            points, maximum, "pass" if ok else "fail", cases=[_case(ok, None if ok else kind)]
        )
    row.add_total()
    return row


# q1 (2 points), q2 (1 point), q3 (4 points) for five students
SMALL = {
    "s1": {"q1": (2, 2), "q2": (1, 1), "q3": (4, 4)},
    "s2": {"q1": (2, 2), "q2": (0, 1), "q3": (3, 4)},
    "s3": {"q1": (1, 2), "q2": (1, 1), "q3": (2, 4)},
    "s4": {"q1": (0, 2), "q2": (0, 1), "q3": (1, 4)},
    "s5": {"q1": (0, 2), "q2": (0, 1), "q3": (0, 4)},
}
KINDS = {"s3": {"q1": "factor"}, "s4": {"q1": "factor", "q2": "sign"}, "s5": {"q1": "shape"}}


def test_item_analysis_matches_a_hand_computation():
    """By hand, q1: shares 1, 1, 0.5, 0, 0 -> difficulty 2.5/5 = 0.5; rest scores (q2 + q3)
    5, 3, 3, 1, 0 (mean 2.4). Deviations x: .5 .5 0 -.5 -.5, y: 2.6 .6 .6 -1.4 -2.4;
    sum xy = 1.3 + .3 + 0 + .7 + 1.2 = 3.5, sum x² = 1, sum y² = 6.76 + .36 + .36 + 1.96
    + 5.76 = 15.2, so r = 3.5 / sqrt(15.2) = 0.89773. q2: difficulty 2/5 = 0.4, rest 6, 5, 3,
    1, 0 (mean 3): x .6 -.4 .6 -.4 -.4, y 3 2 0 -2 -3, sum xy = 3, sum x² = 1.2, sum y² = 26,
    r = 3 / sqrt(31.2) = 0.53709. Kinds of q1: factor (s3, s4) 2/5, shape 1/5;
    q2: sign (s4) 1/5, and the failed cases of s2 and s5 carry no kind: unknown 2/5."""
    rows = [_row(sid, q, KINDS.get(sid)) for sid, q in SMALL.items()]
    stats = {s.question: s for s in item_analysis(rows, ["q1", "q2", "q3"])}
    assert stats["q1"].difficulty == pytest.approx(0.5)
    assert stats["q1"].discrimination == pytest.approx(3.5 / math.sqrt(15.2))
    assert stats["q1"].discrimination == pytest.approx(0.89773, abs=1e-5)
    assert stats["q2"].difficulty == pytest.approx(0.4)
    assert stats["q2"].discrimination == pytest.approx(0.53709, abs=1e-5)
    assert stats["q3"].difficulty == pytest.approx(10 / 20)
    assert stats["q1"].kinds == {"factor": 0.4, "shape": 0.2}
    assert stats["q2"].kinds == {"sign": 0.2, "unknown": 0.4}
    assert not any(s.flagged for s in stats.values())
    tables = report_tables(rows, load_checks(SOLUTION), ["q1", "q2", "q3"])
    head, body = tables["items"]
    assert head == ["question", "students", "difficulty", "discrimination", "check"]
    assert body[0] == ["q1", "5", "0.50", "0.90", ""]
    assert ["q1", "factor", "0.40"] in tables["kinds"][1]


def test_a_question_with_a_wrong_expected_value_is_flagged():
    """q5's expected value is wrong: the students who compute it right (the strong ones, who do
    well on q1..q4) fail it, and those who make the mistake the wrong value encodes pass. Its
    discrimination is negative and the report flags it; the sound questions are not."""
    rows = []
    for ability in range(10):  # sound questions q1..q4: harder and harder, 1 point each
        scores = {f"q{k}": (float(ability >= 2 * k - 1), 1.0) for k in range(1, 5)}
        # q5's expected value is the answer of a mistake weak students make: they pass
        scores["q5"] = (float(ability < 5), 1.0)
        rows.append(_row(f"s{ability}", scores))
    qids = ["q1", "q2", "q3", "q4", "q5"]
    stats = {s.question: s for s in item_analysis(rows, qids)}
    assert (stats["q5"].discrimination or 0) < 0 and stats["q5"].flagged
    assert all((stats[q].discrimination or 0) > 0.3 and not stats[q].flagged for q in qids[:4])
    page = report_html(rows, load_checks(SOLUTION), qids)
    assert "<td>q5</td><td>10</td><td>0.50</td><td>-0." in page
    assert page.count("flagged: discrimination near zero or negative") == 1


def test_a_question_everyone_gets_right_has_no_discrimination_and_no_flag():
    rows = [_row(f"s{i}", {"q1": (1, 1), "q2": (i % 2, 1)}) for i in range(6)]
    q1 = item_analysis(rows, ["q1", "q2"])[0]
    assert (q1.difficulty, q1.discrimination, q1.flagged) == (1.0, None, False)
    rows[0].questions["q2"].status = "to mark"  # not marked yet: no score, left out
    assert item_analysis(rows, ["q1", "q2"])[1].students == 5


def test_every_table_of_the_report_is_a_csv_beside_it_with_student_text_as_data(tmp_path):
    """RFC 4180 (comma, double quotes, CRLF): an ID with a comma, a quote, a newline and a
    leading = comes back exactly as it was, and a table the page no longer has loses its file."""
    odd = '=HYPERLINK("x"),\n"me"'
    rows = [_row(sid, q, KINDS.get(sid)) for sid, q in SMALL.items()]
    rows.append(_row(odd, {"q1": (0, 2), "q2": (0, 1), "q3": (0, 4)}))
    for r in rows:
        r.wall_seconds = 1.0
    checks = load_checks(SOLUTION)
    (tmp_path / "report-late.csv").write_text("stale")
    write_report(rows, checks, ["q1", "q2", "q3"], tmp_path)
    written = sorted(p.name for p in tmp_path.glob("report-*.csv"))
    assert written == ["report-items.csv", "report-kinds.csv", "report-questions.csv",
                       "report-slowest.csv", "report-wrong.csv"]  # fmt: skip
    raw = (tmp_path / "report-slowest.csv").read_bytes()
    assert raw.startswith(b"student,seconds,status\r\n")
    slowest = list(csv.reader(io.StringIO(raw.decode("utf-8"), newline="")))
    assert [odd, "1.00", "ok"] in slowest
    items = list(csv.reader((tmp_path / "report-items.csv").open(encoding="utf-8", newline="")))
    assert items[0][:4] == ["question", "students", "difficulty", "discrimination"]
    assert [r[0] for r in items[1:]] == ["q1", "q2", "q3"]


def test_the_similarity_hint_finds_two_students_who_renamed_every_variable():
    """The same right answer of q2 with every name changed, literals respelled, comments and
    spacing rewritten: one group; a third student's different right answer stays out."""
    _, release = load_assignment(SOLUTION)
    skeleton = next(c.source for c in release.cells if c.question == "q2" and c.role == "answer")
    answers = importlib.import_module("wrong_answers.answers_01").RIGHT["q2"]
    first, other = answers[1][1], answers[0][1]  # the projector, and lsq.fit
    renamed = _renamed(first)
    assert not (_names(first) - KEEP) & _names(renamed)  # every variable renamed
    fps = {
        "ann": fingerprint(first, skeleton),
        "bob": fingerprint(renamed, skeleton),
        "cat": fingerprint(other, skeleton),
    }
    assert fps["ann"] is not None and fps["cat"] is not None
    groups = similar_groups(("q2", sid, fp) for sid, fp in fps.items())
    assert groups == [("q2", ["ann", "bob"])]
    rows = []
    for sid, fp in fps.items():
        row = _row(sid, {"q2": (1, 1)})
        row.questions["q2"].fingerprint = fp
        rows.append(row)
    tables = report_tables(rows, load_checks(SOLUTION), ["q2"])
    assert tables["similar"][1] == [["q2", "2", "ann, bob"]]
    from course.grading.batch.reports import feedback_markdown

    for row in rows:  # never in a student's feedback
        text = feedback_markdown(row, load_checks(SOLUTION))
        assert "ann" not in text.replace(row.student, "") and fps["ann"] not in text


def _names(source: str) -> set[str]:
    tree = ast.parse(source)
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} | {
        a.arg for a in ast.walk(tree) if isinstance(a, ast.arg)
    }


KEEP = {"np", "len", "range", "sum", "abs", "float", "list", "tuple", "lsq", "print"}


def _renamed(source: str) -> str:
    """``source`` with every variable and argument renamed (the library's names kept),
    numbers respelled (1 -> 1.0e0 keeps a float a float) and a comment and spacing added."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id not in KEEP:
            node.id = f"zz_{node.id}_renamed"
        elif isinstance(node, ast.arg):
            node.arg = f"zz_{node.arg}_renamed"
    text = ast.unparse(tree).replace("    ", "        ")
    return "# my own work\n" + text.replace(" = ", "   =   ") + "\n\n"


@pytest.mark.parametrize("assignment", [f"0{n}" for n in range(1, 8)])
def test_independent_right_answers_written_differently_are_never_grouped(assignment):
    """The course's own right-but-different answers (tests/wrong_answers' RIGHT tables): no
    two answers of the same question share a fingerprint."""
    module = importlib.import_module(f"wrong_answers.answers_{assignment}")
    solution = next((ROOT / "solutions").glob(f"{assignment}_*"))
    _, release = load_assignment(solution)
    skeletons = {c.question: c.source for c in release.cells if c.role == "answer"}
    triples = [
        (qid, f"{qid}:{label}", fingerprint(source, skeletons.get(qid, "")))
        for qid, answers in module.RIGHT.items()
        for label, source in answers
    ]
    assert sum(fp is not None for *_, fp in triples) >= len(triples) // 2  # most are compared
    assert similar_groups(triples) == []


@pytest.mark.parametrize(
    "source",
    [
        "x = 1\n" * (MAX_SOURCE_CHARS // 6 + 1),  # over the cap: not parsed at all
        "def f(:\n    pass",  # a syntax error
        "y = " + "-" * 5000 + "1",  # a tree deeper than any recursion limit
        "x = " + "(" * 300 + "1" + ")" * 300,  # deeper than the parser allows
        "s = '\\d' + 'x'\n" * 3,  # a warning Python would print
        "a\x00b",  # a null byte
    ],
)
def test_a_fingerprint_of_hostile_source_is_bounded_and_never_raises(source, recwarn):
    fp = fingerprint(source)
    assert fp is None or len(fp) == 32
    assert not recwarn.list


def test_the_handed_out_skeleton_and_short_answers_are_not_compared():
    skeleton = '# YOUR CODE HERE\nraise NotImplementedError("q6: not answered yet")'
    assert fingerprint(skeleton, skeleton) is None
    assert fingerprint("T = e @ e", "") is None  # too short to mean anything
    longer = "T = float(e @ np.linalg.solve(Q, e))\nok = T <= threshold * 2 + 1"
    assert fingerprint(longer + "\n" + skeleton, skeleton) == fingerprint(longer, "")


# -- the grader records the fingerprints ---------------------------------------------------------
COPIED = "def line_residuals(t, y):\n    A = np.column_stack([np.ones(len(t)), t])\n" \
    "    x_hat = np.linalg.solve(A.T @ A, A.T @ y)\n    return y - A @ x_hat"  # fmt: skip


@class_submissions("similar")
def _similar_submissions(name: str, subs: Path) -> None:
    """Two students with the same q2 (one renamed), each graded in the shared class."""
    if name != NAME:
        return None
    for sid, source in (("sim-one", COPIED), ("sim-two", _renamed(COPIED))):
        nb = nbformat.read(SOLUTION / f"{NAME}.ipynb", as_version=4)
        for cell in nb.cells:
            course = cell.get("metadata", {}).get("course", {})
            if course.get("role") == "answer" and course.get("question") == "q2":
                cell.source = source
        nbformat.write(nb, subs / f"{sid}.ipynb")
    return None


def test_the_grader_records_fingerprints_and_the_report_lists_the_pair(graded_class):
    graded = graded_class(NAME)
    one, two = graded.rows["sim-one"], graded.rows["sim-two"]
    assert one["questions"]["q2"]["points"] == one["questions"]["q2"]["max"]
    assert one["questions"]["q2"]["fingerprint"] == two["questions"]["q2"]["fingerprint"]
    similar = list(csv.reader((graded.out / "report-similar.csv").open(encoding="utf-8")))
    assert any(r[0] == "q2" and "sim-one" in r[2] and "sim-two" in r[2] for r in similar[1:])
    assert "sim-two" not in graded.feedback("sim-one")
