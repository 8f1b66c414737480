"""Feedback that follows the mistake (issue 26, item 4): answers computed in float32 are told
so, the same way at self-check and at grading; a named mistake chooses its own hint; a mistake
made in one field of a tuple is named; ``from data import ...`` works at grading as at
self-check.

The grading tests grade a few notebooks in each assignment's shared class
(``graded_class`` in ``tests/conftest.py``).
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import nbformat
import numpy as np
import pytest
from conftest import class_submissions
from scipy import stats

from course import diagnosis as dg
from course.grading.authoring.checks import load_checks
from course.grading.authoring.seal import make_salt, seal, sealed_compare
from course.grading.batch.classreport import diagnosis
from course.grading.batch.results import CaseResult
from course.grading.compare import (
    SINGLE_PRECISION,
    Verdict,
    chosen_hint,
    compare,
    single_precision,
)
from course.grading.notebook import _STUDENT_ID_LINE
from course.grading.student.selfcheck import Assignment
from course.grading.vocabulary import MistakeKind

ROOT = Path(__file__).resolve().parents[1]
F04 = "04_ekf_residuals"
PHI = (1 + np.sqrt(5)) / 2  # 04 q1: P(t|t-1) with q = r = 1; K = 1/PHI; P(t|t) = 1/PHI too

# -- right answers computed in float32 --------------------------------------------------------
F32 = {
    "04_ekf_residuals": {
        "q1": """def steady_state(q, r):
    q, r = np.float32(q), np.float32(r)
    P = (q + np.sqrt(q * q + np.float32(4) * q * r)) / np.float32(2)
    return (P, P / (P + r))
""",
        "q2": """def normalized_innovations(y, a, q, r, m0, p0):
    y = np.asarray(y, dtype=np.float32)
    a, q, r = np.float32(a), np.float32(q), np.float32(r)
    x, P = np.float32(m0), np.float32(p0)
    z = np.empty(y.shape, dtype=np.float32)
    for t, y_t in enumerate(y):
        S = P + r
        K = P / S
        eps = y_t - x
        z[t] = eps / np.sqrt(S)
        x = x + K * eps
        P = (1 - K) * P
        x, P = a * x, a**2 * P + q
    return z
""",
        "q3": """def windowed_statistic(z, L):
    z = np.asarray(z, dtype=np.float32)
    return np.convolve(z**2, np.ones(L, dtype=np.float32), mode="valid")
""",
    },
    "03_estimation_and_likelihood": {
        "q4": """def likelihood(theta, z, sigma):
    theta = np.asarray(theta, dtype=np.float32)
    z = np.asarray(z, dtype=np.float32)
    pdf = stats.norm.pdf(z, theta[..., None], np.float32(sigma)).astype(np.float32)
    return np.prod(pdf, axis=-1)
""",
    },
}

# 04 q2 divided by S instead of sqrt(S): the diagnosed mistake chooses the hint
Q2_BY_S = (
    F32["04_ekf_residuals"]["q2"]
    .replace("np.float32", "float")
    .replace("eps / np.sqrt(S)", "eps / S")
)
# 04 q1 with the filtered variance for P and K right: a mistake in one field of the pair
Q1_FILTERED_P = """def steady_state(q, r):
    P = (q + np.sqrt(q * q + 4 * q * r)) / 2
    K = P / (P + r)
    return ((1 - K) * P, K)
"""


def _namespace(source: str) -> dict:
    ns = {"np": np, "stats": stats}
    exec(compile(source, "<answer>", "exec"), ns)
    return ns


def _self_check(assignment: str, qid: str, source: str) -> str:
    """What check(qid, answer) prints in a fresh kernel, against the released checks.json."""
    check = Assignment.load(assignment, student_id="s001", path=ROOT / "exercises" / assignment)
    target = check.spec.question(qid).target
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        check(qid, _namespace(source)[target])
    return out.getvalue()


# -- the rule itself --------------------------------------------------------------------------
def test_single_precision_is_recognised_by_dtype_or_by_its_numbers():
    x = np.array([0.1, 1.7, np.pi])
    assert single_precision(x.astype(np.float32)) and single_precision(x.astype(np.float16))
    # a float32 scalar reaches the grader as a Python float holding a float32 number
    assert single_precision(np.array([float(np.float32(np.pi))]))
    assert not single_precision(x)  # float64 numbers
    assert not single_precision(np.array([0.5, 1.25, 3.0, 1e6]))  # exact in any precision
    assert not single_precision(np.array([1, 2, 3]))


def test_a_float32_answer_is_told_so_at_grading_and_at_self_check_alike():
    theta = np.linspace(-2.0, 6.0, 9)
    e = np.asarray(dg.normal_likelihood(theta, np.array([2.0]), sigma=1.0))  # symmetric
    sealed = seal(e, 1e-8, 1e-14, make_salt("test", "float32"))
    for got in (e.astype(np.float32), e.astype(np.float32).astype(float)):
        clear, by_seal = compare(e, got, 1e-8, 1e-14), sealed_compare(sealed, got)
        for v in (clear, by_seal):
            assert not v.ok and SINGLE_PRECISION in v.message, v.message
            assert "reverse order" not in v.message
    # a float64 near miss keeps its own diagnosis
    assert "close: it agrees" in compare(e, e * (1 + 3e-8), 1e-8, 1e-14).message
    # and the class report counts float32 answers as such, by the verdict's kind
    assert clear.kind == by_seal.kind == MistakeKind.SINGLE_PRECISION
    assert diagnosis(CaseResult.of("c", clear)) == ("kind", "computed in float32")


def test_a_symmetric_answer_off_by_round_off_is_not_in_reverse_order():
    """03 q4's public likelihood is symmetric: reversing a near miss changes nothing, so
    "the right values in reverse order" was a guess from round-off."""
    e = np.array([1.0, 2.0, 3.0, 2.0, 1.0])
    got = e * (1 + np.array([3e-8, -2e-8, 4e-8, 1e-8, -3e-8]))
    assert "reverse" not in compare(e, got, 1e-8, 0.0).message
    sealed = seal(e, 1e-8, 0.0, make_salt("test", "palindrome"))
    assert "reverse" not in sealed_compare(sealed, got).message
    # a real reversal is still named
    ramp = np.array([1.0, 2.0, 3.0, 4.0])
    assert "reverse order" in compare(ramp, ramp[::-1], 1e-8, 0.0).message


def test_a_mistake_in_one_field_is_named_at_grading_and_at_self_check():
    right = (PHI, 1 / PHI)
    wrong = (1 / PHI, (1 / PHI) / (1 / PHI + 1))  # P(t|t), and K computed from it
    mistakes = [("the FILTERED variance", wrong)]
    salt = make_salt("test", "fieldwise")
    sealed = seal(right, 1e-8, 1e-10, salt)
    sealed_mistakes = [("the FILTERED variance", seal(wrong, 1e-8, 1e-10, salt + "m"))]
    for got in [(1 / PHI, 1 / PHI), wrong, [1 / PHI, 1 / PHI]]:
        assert "FILTERED" in compare(right, got, 1e-8, 1e-10, mistakes=mistakes).message
        assert "FILTERED" in sealed_compare(sealed, got, mistakes=sealed_mistakes).message
    # a field that matches neither the answer nor the mistake: not this mistake
    for got in [(1 / PHI, 0.5), (2.0, 1 / PHI)]:
        assert "FILTERED" not in compare(right, got, 1e-8, 1e-10, mistakes=mistakes).message
        assert "FILTERED" not in sealed_compare(sealed, got, mistakes=sealed_mistakes).message


def test_the_hint_follows_the_diagnosis():
    hints = {"looks divided by S": "the square root of S"}
    named = Verdict(False, "value: looks divided by S", kind=MistakeKind.NAMED,
                    mistake="looks divided by S")  # fmt: skip
    float32 = Verdict(False, f"value: {SINGLE_PRECISION}", kind=MistakeKind.SINGLE_PRECISION)
    assert chosen_hint([named], hints) == "the square root of S"
    assert chosen_hint([float32], hints) == ""
    assert chosen_hint([Verdict(False, "value: not within the tolerance")], hints) is None
    # a named mistake without its own hint: no staged hint, which could contradict it
    other = Verdict(False, "value: dof m", kind=MistakeKind.NAMED, mistake="dof m")
    assert chosen_hint([other, None], hints) == ""
    # the words of a message choose nothing: only the diagnosis does
    assert chosen_hint([Verdict(False, "value: looks divided by S")], hints) is None
    q2 = load_checks(ROOT / "solutions" / "04_ekf_residuals").questions["q2"]
    assert set(q2.mistake_hints) == {m.message for m in q2.mistakes}
    by_s = next(h for m, h in q2.mistake_hints.items() if "divided by S_t" in m)
    assert by_s in q2.hints[1:]  # a later stage, shown first for this mistake


# -- the self-check ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("assignment", "qid"),
    # 04 q3's public case (z = 0..5) is exact in float32 and passes: its hidden cases fail
    [(a, q) for a, questions in F32.items() for q in questions if (a, q) != (F04, "q3")],
)
def test_self_check_tells_a_float32_answer_to_use_float64(assignment, qid):
    out = _self_check(assignment, qid, F32[assignment][qid])
    assert "FAIL" in out and SINGLE_PRECISION in out, out
    assert "Hint" not in out and "reverse order" not in out, out


def test_self_check_shows_the_hint_of_the_diagnosed_mistake():
    out = _self_check("04_ekf_residuals", "q2", Q2_BY_S)
    assert "looks divided by S_t" in out and "Hint (for this mistake)" in out, out
    assert "square root of its own variance" in out and "BEFORE" not in out, out
    out = _self_check("04_ekf_residuals", "q1", Q1_FILTERED_P)
    assert "FILTERED variance" in out and "before the measurement update" in out.lower(), out


# -- grading ----------------------------------------------------------------------------------
DATA_IMPORT = "from data import survey_T_properties  # the data.py beside the notebook\n"
SUBMISSIONS = {
    "04_ekf_residuals": {"fp-f32": F32["04_ekf_residuals"], "fp-hint": {"q2": Q2_BY_S}},
    "03_estimation_and_likelihood": {"fp-f32": F32["03_estimation_and_likelihood"]},
    "01_least_squares": {"fp-data": {"q4": None}},  # None: the solution with DATA_IMPORT first
}


@class_submissions("diagnosis")
def _write(name: str, folder: Path):
    if name not in SUBMISSIONS:
        return None
    solution = nbformat.read(ROOT / "solutions" / name / f"{name}.ipynb", as_version=4)
    for sid, answers in SUBMISSIONS[name].items():
        nb = nbformat.from_dict(json.loads(json.dumps(solution)))
        for cell in nb.cells:
            meta = cell.get("metadata", {}).get("course", {})
            if meta.get("role") == "setup":
                cell.source = _STUDENT_ID_LINE.sub(f'STUDENT_ID = "{sid}"', cell.source, 1)
            if meta.get("role") == "answer" and meta.get("question") in answers:
                new = answers[meta["question"]]
                cell.source = DATA_IMPORT + cell.source if new is None else new
        nbformat.write(nb, folder / f"{sid}.ipynb")
    return sorted(SUBMISSIONS[name])


@pytest.mark.parametrize("name", ["04_ekf_residuals", "03_estimation_and_likelihood"])
def test_grading_tells_a_float32_answer_to_use_float64(graded_class, name):
    graded = graded_class(name)
    row = graded.rows["fp-f32"]["questions"]
    feedback = graded.feedback("fp-f32")
    for qid in F32[name]:
        r = row[qid]
        assert r["points"] < r["max"], (qid, r)  # told, not accepted (docs: the tolerance rule)
        failed = [c["message"] for c in r.get("cases", []) if not c["ok"]] or [r["message"]]
        assert all(SINGLE_PRECISION in m for m in failed), (qid, failed)
        assert "reverse order" not in json.dumps(r)
    # no hint about the method: the method may be right
    section = feedback.split("## q2:")[1].split("## ")[0] if name.startswith("04") else ""
    assert "Hint" not in section


def test_grading_feedback_shows_the_hint_of_the_diagnosed_mistake(graded_class):
    graded = graded_class("04_ekf_residuals")
    section = graded.feedback("fp-hint").split("## q2:")[1].split("\n## ")[0]
    assert "looks divided by S" in section, section
    assert "square root of its own variance" in section and "BEFORE" not in section, section


def test_data_py_beside_the_notebook_is_importable_at_grading(graded_class):
    row = graded_class("01_least_squares").rows["fp-data"]
    r = row["questions"]["q4"]
    assert r["points"] == r["max"] and r["status"] == "pass", r
    assert "ModuleNotFoundError" not in json.dumps(row)
