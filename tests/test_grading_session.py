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


# -- the scratch-cell rule, through a session's cells (fast: a fake child, no sandbox) --------
_SCRATCH_CHECKS = """
from course.grading.authoring.checks import Checks

CHECKS = Checks("scratch")


@CHECKS.value("q1", var="z", points=1, forbid=["course.lsq.fit"])
def q1():
    return 1.0


@CHECKS.value("q2", var="w", points=1, forbid=["course.lsq.w_tests"])
def q2():
    return 2.0


q3 = CHECKS.function("q3", func="crit", points=1, forbid=["course.lsq.fit"])(lambda a: a)
q3.case(0.05)
"""


@pytest.fixture(scope="module")
def scratch_grader(tmp_path_factory):
    """A real grader of a three-question assignment: value questions q1 (forbids lsq.fit) and
    q2 (forbids lsq.w_tests), function question q3 (forbids lsq.fit). Its sandbox never
    starts: the tests hand its sessions a fake child."""
    import nbformat

    from course.grading.batch.session import AssignmentGrader

    folder = tmp_path_factory.mktemp("scratch") / "scratch"
    folder.mkdir()
    (folder / "checks.py").write_text(_SCRATCH_CHECKS)

    def code(source, **meta):
        return nbformat.v4.new_code_cell(source, metadata={"course": meta})

    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_markdown_cell("# Scratch"),
        code(
            'STUDENT_ID = "demo"   # <- your student ID, exactly as registered\n'
            "from course.grading import Assignment\n"
            'check = Assignment.load("scratch", student_id=STUDENT_ID)',
            role="setup",
        ),
    ]
    for qid, answer in (("q1", "z = 1.0"), ("q2", "w = 2.0"), ("q3", "def crit(a):\n    return a")):
        nb.cells += [
            nbformat.v4.new_markdown_cell(f"## {qid}: an answer"),
            code(f"### BEGIN SOLUTION\n{answer}\n### END SOLUTION", role="answer", question=qid),
        ]
    nbformat.write(nb, folder / "scratch.ipynb")
    return AssignmentGrader(folder)


class _FakeChild:
    """Runs nothing: each cell "makes" the forbidden calls its source names (one per line,
    ``call <dotted>``), reported as the real child's tripwires report them."""

    tmpdir = "/nonexistent"

    def __init__(self):
        self.events: list = []

    def request(self, op, timeout, **fields):
        for line in fields.get("source", "").splitlines():
            if line.startswith("call "):
                name = line.split()[1]
                self.events.append(Call(name, (name,), ""))
        return {"status": "ok"}

    def take_events(self):
        events, self.events = self.events, []
        return events


def _run(grader, cells, deleted=None):
    from course.grading.batch.plan import Plan, PlanCell

    plan = Plan(cells=[PlanCell(*c) for c in cells], deleted=dict(deleted or {}))
    session = StudentSession(grader, types.SimpleNamespace(notes=[]), "s1", plan)
    session.child = _FakeChild()
    assert session._run_cells()
    return session


def test_a_scratch_cell_s_call_counts_against_every_value_question_that_forbids_it(
    scratch_grader,
):
    """Issue 40 item 5 (was pinned only by the slow wrong-answer suite): a forbidden call in a
    cell the student added counts against every value question that forbids the function,
    named as that cell, and against no function question, whatever question's slot the cell
    stands in; in a protected cell against nothing; in an added cell adopted as a deleted
    answer cell, against that answer's question only."""
    from course.grading.vocabulary import CellOrigin

    s = _run(
        scratch_grader,
        [
            ("", None, CellOrigin.SETUP, "setup cell"),
            ("call course.lsq.fit", None, CellOrigin.CONTEXT, "protected cell 'code-02'"),
            ("z = 1.0", "q1", CellOrigin.ANSWER, "answer cell of q1"),
            ("w = 2.0", "q2", CellOrigin.ANSWER, "answer cell of q2"),
            ("def crit(a): ...", "q3", CellOrigin.ANSWER, "answer cell of q3"),
            ("call course.lsq.fit", None, CellOrigin.EXTRA, "your added cell at position 9"),
        ],
    )
    assert set(s.hits) == {"q1"}  # not q2 (allows fit), not q3 (a function question)
    assert s._forbidden_message("q1") == (
        "your added cell at position 9 calls course.lsq.fit, which this question forbids"
    )
    s = _run(
        scratch_grader, [("call course.lsq.w_tests", "q3", CellOrigin.EXTRA, "your added cell")]
    )
    assert set(s.hits) == {"q2"}  # in q3's slot, still a scratch cell
    adopted = [("call course.lsq.fit", "q3", CellOrigin.EXTRA, "your added cell at position 4")]
    s = _run(scratch_grader, adopted, deleted={"q3": "adopted"})
    assert set(s.hits) == {"q3"}  # graded as q3's answer cell: its call is q3's, not q1's


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
