"""Assignments 04-06 (issue 13): practice twins, distinguishable mistakes, near-threshold cases.

The wrong-answer suite (tests/test_wrong_answers.py) grades whole submissions; these tests pin
the properties of the checks that make those grades possible, cheaply and with clear messages.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from course import nis
from course.grading.authoring.checks import load_checks
from course.grading.compare import compare

ROOT = Path(__file__).resolve().parents[1]
NAMES = ["04_ekf_residuals", "05_nis_wishart", "06_mismatched_filters"]


@pytest.fixture(scope="module", params=NAMES)
def checks(request):
    return load_checks(ROOT / "solutions" / request.param)


def test_every_personal_question_has_a_public_practice_twin(checks):
    personal = [q for q in checks.questions.values() if q.kind == "value" and q.data is not None]
    assert personal, "each of 04-06 has a question on personal data"
    for q in personal:
        twin = checks.questions.get(f"{q.id}_practice")
        assert twin is not None, f"{q.id} has no practice twin"
        if twin.kind == "function":
            # issue 26: a twin graded on hidden cases, self-checked on the public record
            assert twin.public_cases and twin.hidden_cases, twin.id
        else:
            assert twin.kind == "value" and twin.public and twin.data is None
            assert twin.target == f"{q.target}_practice"
        assert list(checks.questions).index(twin.id) < list(checks.questions).index(q.id)


def test_declared_mistakes_differ_from_the_right_answer(checks):
    """A value question's mistake never equals its right answer (it would name a right answer a
    mistake); a function question's mistake differs on some public case, so the self-check can
    name it before grading (on other cases it may coincide: the right answer wins there)."""
    n = 0
    for q in checks.questions.values():
        if not getattr(q, "mistakes", ()) or q.data is not None:
            continue
        cases = q.cases if q.kind == "function" else [None]
        for m in q.mistakes:
            differs = []
            for case in cases:
                args, kwargs = (case.args, case.kwargs) if case is not None else ((), {})
                right = q.reference(*args, **kwargs)
                wrong = m.reference(*args, **kwargs)
                differs.append(not compare(right, wrong, q.rtol, q.atol).ok)
            if q.kind == "value":
                assert all(differs), (q.id, m.message)
            else:
                assert any(d for d, c in zip(differs, cases) if not c.hidden), (q.id, m.message)
            n += 1
    assert n > 0


def test_personal_alarm_mistakes_change_the_answer_for_many_students():
    """04 q5 grades the threshold as well as the first alarm, so an L - 1 dof threshold or the
    window's first sample loses points for every student (not only near the threshold)."""
    checks = load_checks(ROOT / "solutions" / "04_ekf_residuals")
    q = checks.questions["q5"]
    for sid in ("a1", "b2", "c3"):
        d = checks.data_for("record", sid)
        right = q.expected(data=d)
        for m in q.mistakes:
            assert not compare(right, m.reference(d), q.rtol, q.atol).ok, (sid, m.message)


def test_matrix_test_has_cases_between_the_one_sided_and_two_sided_thresholds():
    """05 q5: a test at alpha instead of alpha/2 flips the decision in a public case and in
    hidden cases (issue 13: it used to keep full marks)."""
    checks = load_checks(ROOT / "solutions" / "05_nis_wishart")
    q = checks.questions["q5"]
    flips = {"public": 0, "hidden": 0}
    for case in q.cases:
        eps, S, alpha = case.args
        K, m = np.shape(eps)
        lmin, lmax, reject = q.reference(eps, S, alpha)
        lo, hi = nis.nis_matrix_critical_values(m, K, 2 * alpha)
        if bool(lmin < lo or lmax > hi) != reject:
            flips["hidden" if case.hidden else "public"] += 1
    assert flips["public"] >= 1 and flips["hidden"] >= 2, flips


def test_small_k_false_alarm_case_excludes_the_nominal_alpha():
    """05 q7: returning alpha without simulating falls outside the band of a public case."""
    checks = load_checks(ROOT / "solutions" / "05_nis_wishart")
    q = checks.questions["q7"]
    outside = [c for c in q.cases if not compare(q.reference(*c.args), float(c.args[2])).ok]
    assert any(not c.hidden for c in outside) and any(c.hidden for c in outside)


def _matrix_test_with(rule):
    """A student's q5 of assignment 05 whose decision is ``rule(lmin below, lmax above)``."""

    def matrix_test(eps, S, alpha):
        K, m = np.shape(eps)
        values = np.linalg.eigvalsh(nis.nis_matrix(eps, S))
        lower, upper = nis.nis_matrix_critical_values(m, K, alpha)
        return (
            float(values[0]),
            float(values[-1]),
            bool(rule(values[0] < lower, values[-1] > upper)),
        )

    return matrix_test


@pytest.mark.parametrize(
    ("rule", "words"),
    [
        (lambda low, high: False, "never a rejection"),
        (lambda low, high: low and high, "BOTH extreme eigenvalues"),
        (lambda low, high: True, "both extreme eigenvalues lie between"),
    ],
    ids=["never rejects", "and instead of or", "always rejects"],
)
def test_05_q5_public_cases_see_the_decision(rule, words):
    """Issue 26: neither public case of 05 q5 rejected, so a test that never rejects passed the
    self-check and "and" instead of "or" scored full marks; always-reject was told "one-sided".
    Each now fails a public case, and its first failure (the message a student reads) names
    what is wrong in kind."""
    q = load_checks(ROOT / "solutions" / "05_nis_wishart").questions["q5"]
    student = _matrix_test_with(rule)
    messages = []
    for case in q.public_cases:
        mistakes = [(m.message, m.reference(*case.args)) for m in q.mistakes]
        verdict = compare(
            q.reference(*case.args), student(*case.args), q.rtol, q.atol, mistakes=mistakes
        )
        if not verdict.ok:
            messages.append(verdict.message)
    assert messages, "a public case must fail"
    assert words in messages[0], messages[0]
    assert "one-sided" not in messages[0]


@pytest.mark.parametrize("qid", ["q1", "q2"])
def test_05_q1_q2_public_cases_include_a_stack_of_S(qid):
    """The preamble allows S as a (K, m, m) stack: a solution for one S must fail the
    self-check, not only the hidden cases."""
    q = load_checks(ROOT / "solutions" / "05_nis_wishart").questions[qid]
    stacks = [c for c in q.public_cases if np.ndim(c.args[1]) == 3]
    assert stacks
    eps, S = stacks[0].args
    one_S = q.reference(eps, S[0])  # what a solution that handles one S only computes
    assert not compare(q.reference(eps, S), one_S, q.rtol, q.atol).ok


# -- issue 26, item 5: the commonest mistakes are named -----------------------------------
def _first_message(q, student):
    """The message a student reads: that of the first public case the answer fails."""
    for case in q.public_cases if q.kind == "function" else [None]:
        args = case.args if case is not None else ()
        mistakes = [(m.message, m.reference(*args)) for m in q.mistakes]
        got = student(*args)
        verdict = compare(q.reference(*args), got, q.rtol, q.atol, mistakes=mistakes)
        if not verdict.ok:
            return verdict.message
    return ""


def _whiten(eps, S, root):
    eps = np.asarray(eps, float)
    K, m = eps.shape
    S = np.broadcast_to(np.asarray(S, float), (K, m, m))
    return np.stack([np.linalg.solve(root(S[k]), eps[k]) for k in range(K)])


def _symmetric_root(S):
    w, V = np.linalg.eigh(S)
    return V @ np.diag(np.sqrt(w)) @ V.T


@pytest.mark.parametrize(
    ("student", "words"),
    [
        (lambda eps, S: (z := _whiten(eps, S, np.linalg.cholesky)).T @ z, "SUM of the outer"),
        (lambda eps, S: np.asarray(eps).T @ np.asarray(eps) / len(eps), "whiten first"),
        (
            lambda eps, S: (z := _whiten(eps, S, _symmetric_root)).T @ z / len(eps),
            "another square root of S",
        ),
    ],
    ids=["factor K (sum)", "not whitened", "symmetric square root"],
)
def test_05_q2_common_mistakes_are_named(student, words):
    q = load_checks(ROOT / "solutions" / "05_nis_wishart").questions["q2"]
    assert words in _first_message(q, student)


def test_05_q8_normal_approximation_is_named():
    q = load_checks(ROOT / "solutions" / "05_nis_wishart").questions["q8"]
    from scipy import stats

    def nees_interval(n, N, alpha):
        half = float(stats.norm.isf(alpha / 2)) * np.sqrt(2 * n / N)
        return (n - half, n + half)

    assert "normal approximation" in _first_message(q, nees_interval)


def test_04_q7_records_alarm_as_their_cause_says():
    """04 q7 and q7_why used one fixed record for the whole class; data.drift now gives each
    student a record whose false alarms have one of two causes, checked by a compact EKF in
    the generator. That EKF counts what the course's counts, and the cause q7_why expects is
    the one the counts show: only the constant-beta filter alarms ("model"), or both do."""
    import sys

    checks = load_checks(ROOT / "solutions" / "04_ekf_residuals")
    q7, why = checks.questions["q7"], checks.questions["q7_why"]
    data = sys.modules[q7.reference.__module__].data
    causes = set()
    for sid in [f"s{k:03d}" for k in range(40)]:
        d = checks.data_for("drift", sid)
        counts = tuple(q7.expected(data=d))
        compact = tuple(
            data._windowed_alarms(
                d["y"],
                d["u"],
                d["Ts"],
                q_beta,
                d["q_x"],
                d["r"],
                d["window"],
                d["alpha"],
                d["t_fault"],
            )
            for q_beta in (0.0, 1e-4)
        )
        assert compact == counts, sid
        cause = why.reference(d)
        causes.add(cause)
        if cause == "model":
            assert counts[0] >= 5 and counts[1] <= 1, (sid, counts)
        else:
            assert cause == "noise" and min(counts) >= 5, (sid, counts)
    assert causes == {"model", "noise"}
