"""One student's session (course.grading.batch.session): which question a forbidden call is
charged on, and which definition of an answer function is graded (issue 37 items 3 and 5).

A forbidden call is charged once, on the question whose code made it: a question whose
function calls another question's function, which makes the call, is graded on its own values
with a note; a call from a cell the student added is named as coming from that cell. The
function graded is the one its answer cell defined (as the self-check right after it sees
it); a later definition is reported, not graded. The whole-grading tests use the
01_least_squares solution (q3 and q4 both forbid ``course.lsq.fit``)."""

from __future__ import annotations

import copy
import json
import types

import pytest
from test_grading_hostile import SOLUTION_DIR, _cell, _expect, _solution, _with_answer

from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions
from course.grading.batch.session import StudentSession
from course.grading.tripwire import Call

FIT = Call("course.lsq.fit", ("course.lsq.fit",), "")


def _session(forbid: dict, by_value=()) -> StudentSession:
    questions = {
        qid: types.SimpleNamespace(id=qid, target=f"f_{qid}", kind="function") for qid in forbid
    }
    grader = types.SimpleNamespace(
        forbid={qid: frozenset(names) for qid, names in forbid.items()},
        forbid_by_value=list(by_value),
        checks=types.SimpleNamespace(questions=questions),
    )
    session = StudentSession.__new__(StudentSession)
    session.g = grader
    session.hits, session.via = {}, {}
    return session


def test_a_call_made_by_another_answer_is_charged_there_once():
    """07: q2 and q3 call q1's function, which calls lsq.fit; all three forbid it. Charged on
    q1 (where its code made it), with a note on q2 and q3, not three times."""
    s = _session({"q1": {FIT.called}, "q2": {FIT.called}, "q3": {FIT.called}})
    for question in ("q1", "q2", "q3"):
        s._charge(question, FIT._replace(where="q1"), False, "your answer")
    assert set(s.hits) == {"q1"}
    assert (
        s._forbidden_message("q1")
        == "your answer calls course.lsq.fit, which this question forbids"
    )
    assert list(s.via["q2"]) == [
        "your f_q2 calls f_q1 (your answer to q1), which calls course.lsq.fit: charged on q1"
    ]


def test_a_label_cannot_move_a_charge_to_a_question_that_allows_the_call():
    """The label comes from the child: a call labelled with a question that does not forbid
    the function (or with nothing known) stays on the question that ran it."""
    s = _session({"q1": set(), "q2": {FIT.called}})
    s._charge("q2", FIT._replace(where="q1"), False, "your answer")
    s._charge("q2", FIT._replace(where="nonsense"), False, "your answer")
    assert set(s.hits) == {"q2"} and not s.via


def test_a_call_from_an_added_cell_names_that_cell():
    """06 q6 read "the answer calls ..." for a call in an added cell before it."""
    s = _session({"q6": {FIT.called}, "q5": {FIT.called}}, by_value=["q6"])
    s._charge(None, FIT, True, "your added cell at position 12")
    assert s._forbidden_message("q6") == (
        "your added cell at position 12 calls course.lsq.fit, which this question forbids"
    )
    assert "q5" not in s.hits  # a function question: graded on hidden inputs


def test_a_private_helper_is_named_as_called():
    core = Call(
        "course.filters._steps._update_core",
        ("course.filters.kf_update", "course.filters.steady_state", "course.filters.riccati"),
        "",
    )
    s = _session({"q8": {"course.filters.riccati", "course.filters.steady_state"}})
    s._charge("q8", core, False, "your answer")
    assert s._forbidden_message("q8") == (
        "your answer calls course.filters._steps._update_core (a private helper of "
        "course.filters.steady_state), which this question forbids"
    )


# -- whole grading --------------------------------------------------------------------------
_Q3_FORBIDDEN = """def overall_model_test_stat(A, y, Qyy, alpha, *, peek=False):
    r = lsq.overall_model_test(lsq.fit(A, y, Qyy), alpha)
    return r.statistic, r.critical_value, r.reject
"""
# q3 is honest on its own cases; it calls lsq.fit only when q4's function asks it to
_Q3_ON_REQUEST = """def _honest(A, y, Qyy, alpha):
{honest}

def overall_model_test_stat(A, y, Qyy, alpha, *, peek=False):
    if peek:
        lsq.fit(A, y, Qyy)
    return _honest(A, y, Qyy, alpha)
"""


def _q4_calling_q3(peek: bool) -> str:
    honest = _cell(_solution(), "q4-answer")["source"]
    return honest.replace(
        "    return numerator / denominator",
        f"    overall_model_test_stat(A, y, Qyy, 0.05, peek={peek})\n"
        "    return numerator / denominator",
    )


def _added_at_end(nb: dict, source: str) -> dict:
    nb = copy.deepcopy(nb)
    nb["cells"].append(
        {
            "cell_type": "code",
            "metadata": {},
            "outputs": [],
            "source": source,
            "execution_count": None,
            "id": "added-at-end",
        }
    )
    return nb


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("session")
    subs = tmp / "subs"
    subs.mkdir()
    q3_source = _cell(_solution(), "q3-answer")["source"]
    honest_q3 = "\n".join(
        "    " + line if line else line for line in q3_source.split("\n", 1)[1].splitlines()
    )
    files = {
        "through_q3": _with_answer("q4", _q4_calling_q3(False), _with_answer("q3", _Q3_FORBIDDEN)),
        "late_charge": _with_answer(
            "q4", _q4_calling_q3(True), _with_answer("q3", _Q3_ON_REQUEST.format(honest=honest_q3))
        ),
        "redefined_wrong": _added_at_end(
            _solution(), "def line_estimate(t, y):\n    return np.zeros(2)\n"
        ),
        "redefined_right": _added_at_end(
            _with_answer("q2", "def line_residuals(t, y):\n    return np.zeros(len(t))\n"),
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return y - A @ np.linalg.lstsq(A, y, rcond=None)[0]\n",
        ),
    }
    for sid, nb in files.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    options = GradeOptions(jobs=2, timeout=20, memory_mb=1024, progress=False)
    summary = grade(SOLUTION_DIR, subs, tmp / "out", options)
    return {r.student: r.to_json() for r in summary.rows}


def test_a_question_calling_another_answer_s_forbidden_call_keeps_its_points(rows):
    row = rows["through_q3"]
    _expect(row, {"q3": "forbidden"})
    message = row["questions"]["q4"]["message"]
    assert "your w_statistics calls overall_model_test_stat (your answer to q3)" in message
    assert "charged on q3" in message


def test_a_charge_found_after_its_question_was_graded_still_counts_there(rows):
    """q3's own cases never make the call; q4's run of q3's function does: q3 is charged
    (late), q4 keeps its points, and the call is not lost between the two."""
    row = rows["late_charge"]
    _expect(row, {"q3": "forbidden"})
    assert "charged on q3" in row["questions"]["q4"]["message"]


def test_the_answer_cell_s_function_is_graded_and_a_later_definition_reported(rows):
    row = rows["redefined_wrong"]
    _expect(row, {})
    assert "defined again after its answer cell" in row["questions"]["q1"]["message"]
    row = rows["redefined_right"]
    _expect(row, {"q2": "fail"})
    assert "defined again after its answer cell" in row["questions"]["q2"]["message"]
