"""The diagnosis of a wrong answer as data (issue 35 item 4, issue 37 items 6 and 7).

A failed case carries its kind (:class:`~course.grading.vocabulary.MistakeKind`), set where
the comparison makes the diagnosis and written with the case to ``results.jsonl``; the class
report counts kinds, never the words of a message. A hidden case's message names no factor
that tells its input, and a wrong answer that is another data's right answer is told so.
"""

from __future__ import annotations

import numpy as np
import pytest

from course.grading.authoring.seal import make_salt, seal, sealed_compare
from course.grading.batch.classreport import _Class, report_html
from course.grading.batch.results import CaseResult, QuestionResult, StudentResult
from course.grading.codec import Band
from course.grading.compare import OTHER_DATA, Verdict, check_signature, compare, signature
from course.grading.items import choice_verdict
from course.grading.vocabulary import SPECIFIC_KINDS, MistakeKind

RIGHT = np.array([[2.0, 0.5, 0.1], [0.3, 1.0, 0.2], [0.7, 0.4, 3.0]])

#: (expected, a wrong answer): one of each kind of wrong the comparison recognises
WRONG = [
    (RIGHT, RIGHT.T),
    (RIGHT, -RIGHT),
    (RIGHT, 2 * RIGHT),
    (np.array([1.0, 4.0, 9.0]), np.array([1.0, 2.0, 3.0])),
    (np.array([1.0, 2.0, 3.0]), np.array([3.0, 2.0, 1.0])),
    (np.array([1.0, 2.0, 3.0, 4.0]), np.array([1.0, 2.0, 3.0])),
    (np.array([1.0, 2.0, 3.0]), np.zeros(3)),
    (np.array([1.0, 2.0, 3.0]), np.array([1.0, np.nan, 3.0])),
    (np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0000001, 3.0])),
    (np.array([0.1, 1.7, np.pi]), np.array([0.1, 1.7, np.pi], dtype=np.float32)),
    (RIGHT, np.ones((2, 2))),
    (np.array([True, False]), np.array([False, True])),
    (np.array([True, False, True]), np.array([True, True, True])),
    (3, 4),
    (1.0, "one"),
    ("reject", "Reject "),
    ("reject", "accept"),
    ((1.0, 2.0), (2.0, 1.0)),
    ((1.0, 2.0), (1.0, 2.0, 3.0)),
    (Band(0.04, 0.06), 0.2),
    (1.5, 2.7),
]


def test_every_kind_a_diagnosis_returns_is_in_the_enum():
    seen = set()
    for expected, got in WRONG:
        clear = compare(expected, got, 1e-9, 1e-12)
        assert not clear.ok and isinstance(clear.kind, MistakeKind), (expected, got, clear)
        seen.add(clear.kind)
        if not isinstance(expected, Band):
            sealed = sealed_compare(seal(expected, 1e-9, 1e-12, make_salt("kinds")), got)
            assert not sealed.ok and isinstance(sealed.kind, MistakeKind), (expected, got)
            seen.add(sealed.kind)
        shape = check_signature(signature(expected), got)
        assert shape.ok or isinstance(shape.kind, MistakeKind)
    for answer in ("reject", "maybe"):
        verdict = choice_verdict("q", ["accept", "reject"], "accept", answer)
        assert isinstance(verdict.kind, MistakeKind)
        seen.add(verdict.kind)
    named = compare(1.0, 2.0, mistakes=[("doubled", 2.0)])
    assert (named.kind, named.mistake) == (MistakeKind.NAMED, "doubled")
    assert compare(1.0, 1.0).kind is None
    # the battery reaches every kind the comparisons can say (the session adds the rest)
    said_elsewhere = {MistakeKind.NAMED, MistakeKind.RAISED, MistakeKind.NOT_PLAIN_DATA,
                      MistakeKind.OTHER_DATA}  # fmt: skip
    assert seen | said_elsewhere == set(MistakeKind), set(MistakeKind) - seen - said_elsewhere
    # a kind outside the one list is refused where the verdict is made
    with pytest.raises(ValueError):
        Verdict(False, "x", kind="a factor")


def test_the_kind_is_written_to_results_and_read_back():
    case = CaseResult.of("c", compare(1.0, 2.0, mistakes=[("doubled", 2.0)]))
    row = case.to_json()
    assert row["kind"] == "named mistake" and row["mistake"] == "doubled"
    back = CaseResult.from_json(row)
    assert (back.kind, back.mistake) == (MistakeKind.NAMED, "doubled")
    plain = CaseResult.of("c", compare(1.0, 2.7)).to_json()
    assert plain["kind"] == "another wrong value" and "mistake" not in plain
    assert "kind" not in CaseResult.of("c", compare(1.0, 1.0)).to_json()


def _rows(cases_by_student: dict[str, list[CaseResult]]) -> list[StudentResult]:
    rows = []
    for sid, cases in cases_by_student.items():
        q = QuestionResult(0.0, 1.0, "fail", cases=cases)
        rows.append(StudentResult(sid, "a", "c", "v", "k", 1.0, {"q1": q}))
    return rows


class _Checks:
    title = "t"

    def __init__(self):
        self.questions: dict = {}


def _counts(rows):
    data = _Class(rows, _Checks(), ["q1"])
    return dict(data.named["q1"]), dict(data.kinds["q1"])


def test_the_report_counts_kinds_not_words():
    verdicts = {
        "a": [compare(RIGHT, RIGHT.T), compare(RIGHT, 2 * RIGHT)],
        "b": [compare(1.0, 2.0, mistakes=[("doubled", 2.0)])],
        "c": [compare(1.0, 2.7), compare(1.0, 1.0)],
        "d": [compare(RIGHT, -RIGHT)],
    }
    rows = _rows(
        {s: [CaseResult.of(f"c{k}", v) for k, v in enumerate(vs)] for s, vs in verdicts.items()}
    )
    named, kinds = _counts(rows)
    assert named == {"doubled": 1}
    assert kinds == {
        "transposed": 1,
        "a constant factor": 1,
        "another wrong value": 1,
        "the sign": 1,
    }
    # every message reworded, words of other kinds included: the counts do not move
    for row in rows:
        for case in row.questions["q1"].cases:
            case.message = "reworded: transposed, a factor, raised , expected a, opposite"
    assert _counts(rows) == (named, kinds)


def test_a_students_text_saying_factor_is_not_a_factor_error():
    """The old report matched "factor" in the message, which quotes a choice answer."""
    verdict = choice_verdict("q", ["accept", "reject"], "accept", "factor")
    rows = _rows({"s": [CaseResult.of("verdict", verdict)]})
    assert "factor" in rows[0].questions["q1"].cases[0].message
    assert _counts(rows) == ({}, {"not an option": 1})
    page = report_html(rows, _Checks(), ["q1"])
    assert "a constant factor" not in page and "<td>not an option</td><td>1</td>" in page


def test_a_hidden_case_message_names_no_factor():
    """06 q4: "(= 3/2)" on hidden case 2 told that its M is 3 (issue 37 item 7)."""
    expected, got = np.array([1.0, 2.0]), np.array([1.5, 3.0])
    public = compare(expected, got, 1e-9, 1e-12)
    hidden = compare(expected, got, 1e-9, 1e-12, hidden=True)
    assert "3/2" in public.message and public.kind == hidden.kind == MistakeKind.FACTOR
    assert "3/2" not in hidden.message and "1.5" not in hidden.message
    assert "too large by a constant factor" in hidden.message


def test_another_datas_answer_is_named():
    demo, mine = np.array([1.0, 2.5]), np.array([1.2, 2.1])
    verdict = compare(mine, demo, others=[np.array([7.0, 7.0]), demo])
    assert verdict.kind == MistakeKind.OTHER_DATA and OTHER_DATA in verdict.message
    # a named mistake wins; integers are never told (an index equals another case's by chance)
    assert compare(mine, demo, mistakes=[("m", demo)], others=[demo]).kind == MistakeKind.NAMED
    assert compare(3, 4, others=[4]).kind == MistakeKind.WRONG_VALUE
    # a specific kind is kept
    assert compare(mine, -mine, others=[-mine]).kind == MistakeKind.SIGN
    assert MistakeKind.OTHER_DATA in SPECIFIC_KINDS and MistakeKind.FACTOR not in SPECIFIC_KINDS
