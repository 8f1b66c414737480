"""Issue 13, assignments 01-03: the holes the wrong-answer suite cannot see from one student.

02 q8 passes for a fault-free student; the personal data make the methods taught matter
(the largest |e| is not the blunder, the maximised likelihood is not the marginal one) for
essentially every student ID, not only for the suite's; every personal value question has a
public practice twin; the Monte Carlo questions repeat the student's seeded simulation.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from course import lsq
from course.grading.authoring.checks import load_checks
from course.grading.compare import compare
from course.grading.student.selfcheck import Assignment

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = ROOT / "solutions"
EXERCISES = ROOT / "exercises"
IDS = [f"s{i:03d}" for i in range(120)]


@pytest.fixture(scope="module")
def checks():
    return {
        name: load_checks(SOLUTIONS / name)
        for name in ("01_least_squares", "02_test_quantities", "03_estimation_and_likelihood")
    }


# -- 02 q8: a right answer never fails a public check ------------------------------------
@pytest.mark.parametrize("sid", ["s011", "s013"])  # fault-free records: nothing alarms
def test_02_q8_passes_for_a_fault_free_student(checks, capsys, sid, monkeypatch):
    """Old code: the public type check came from the demo student's ['F2'] and said
    'expected a sequence of length 1' to the right ['NF', 'F1', 'F2', 'F3']."""
    c = checks["02_test_quantities"]
    right = c.questions["q8"].expected(data=c.data_for("record", sid))
    assert right == ["NF", "F1", "F2", "F3"]  # the ID really is fault-free
    monkeypatch.chdir(EXERCISES / "02_test_quantities")
    check = Assignment.load("02_test_quantities", student_id=sid)
    check("q8", right)
    out = capsys.readouterr().out
    assert "FAIL" not in out and "PASS: type and shape" in out, out
    check("q8", "F1")  # not a list of names: still caught
    assert "FAIL: type and shape" in capsys.readouterr().out


# -- personal data where the wrong method gives another answer --------------------------
def _share(pairs) -> float:
    pairs = list(pairs)
    return sum(pairs) / len(pairs)


def test_01_survey_largest_residual_is_not_the_blunder(checks):
    c = checks["01_least_squares"]
    same_e, same_unweighted = [], []
    for sid in IDS:
        d = c.data_for("survey", sid)
        truth = c.questions["q7"].expected(data=d)
        fit = lsq.fit(d["A"], d["y"], d["Qyy"])
        same_e.append(int(np.argmax(np.abs(fit.e_hat))) == truth)
        unweighted = lsq.data_snooping(
            lsq.fit(d["A"], d["y"], np.eye(len(d["y"]))), alpha=d["alpha"]
        )
        same_unweighted.append(int(unweighted.removed[0]) == truth)
    assert _share(same_e) <= 0.02 and _share(same_unweighted) <= 0.03


def test_01_q6b_verdict_depends_on_the_data_and_the_method(checks):
    """Old code: the blunder made T several times its critical value, so "rejected" was right
    for every student and the point was free. Now about half of the class is on each side, and
    each plausible wrong method flips the verdict on one side of it: a threshold with m or
    m - 1 degrees of freedom or at alpha/2 for every rejected survey, ignoring Qyy for every
    accepted one."""
    from scipy import stats

    c = checks["01_least_squares"]
    q = c.questions["q6b"]
    rejected, flipped = [], {"dof m": [], "dof m - 1": [], "alpha / 2": [], "Qyy ignored": []}
    for sid in IDS:
        d = c.data_for("survey", sid)
        m, n = d["A"].shape
        right = q.reference(d) == "rejected"
        rejected.append(right)
        T = lsq.fit(d["A"], d["y"], d["Qyy"]).squared_norm
        T_unweighted = lsq.fit(d["A"], d["y"]).squared_norm
        for name, stat, dof, level in (
            ("dof m", T, m, d["alpha"]),
            ("dof m - 1", T, m - 1, d["alpha"]),
            ("alpha / 2", T, m - n, d["alpha"] / 2),
            ("Qyy ignored", T_unweighted, m - n, d["alpha"]),
        ):
            flipped[name].append((stat > stats.chi2.isf(level, dof)) != right)
    assert 0.35 <= _share(rejected) <= 0.65
    for name, flips in flipped.items():
        assert _share(flips) >= 0.35, name


def test_03_maximised_likelihood_never_passes_q9(checks):
    c = checks["03_estimation_and_likelihood"]
    q = c.questions["q9"]
    mod = sys.modules[q.reference.__module__]
    for sid in IDS[:60]:
        d = c.data_for("modes", sid)
        wrong = mod._maximised(d["y"], d["U"], d["sigma"], d["priors"])
        assert not compare(q.expected(data=d), wrong, q.rtol, q.atol).ok, sid


def test_02_threshold_is_personal(checks):
    """chi2(N) and alpha/2 lose q8a for every student (not only near a threshold)."""
    c = checks["02_test_quantities"]
    q = c.questions["q8a"]
    values = set()
    for sid in IDS[:30]:
        d = c.data_for("record", sid)
        J = q.expected(data=d)
        values.add(round(J, 12))
        for message, wrong in q.mistaken(data=d):
            assert not compare(J, wrong, q.rtol, q.atol).ok, (sid, message)
    assert len(values) >= 4  # sigma and alpha differ between students


# -- item 3: a public practice twin for every personal value question --------------------
TWINS = {
    "01_least_squares": {"q6": "q6_practice", "q7": "q7_practice"},
    "02_test_quantities": {"q7": "q7_practice", "q8a": "q8_practice", "q8": "q8_practice"},
    "03_estimation_and_likelihood": {"q9": "q9_practice"},
}


@pytest.mark.parametrize("name", sorted(TWINS))
def test_every_personal_value_question_has_a_public_twin(checks, name):
    """A twin is self-checked on public data: a public value, or (issue 26: no grade on a
    public value alone) a function of the data whose public case is the practice data and
    whose hidden cases decide the grade."""
    c = checks[name]
    personal = {q.id for q in c.questions.values() if q.data is not None and q.kind == "value"}
    assert personal == set(TWINS[name])
    for twin in TWINS[name].values():
        q = c.questions[twin]
        if q.kind == "function":
            assert q.public_cases and q.hidden_cases, twin
        else:
            assert q.kind == "value" and q.public and q.data is None


def test_01_unweighted_largest_standardised_residual_is_not_the_blunder(checks):
    """Old code: the largest |e_i / sigma_i| of a fit without the weights (no w-test) found
    the blunder on ~80 % of the surveys and on every public case, so q7 and q7_practice gave it
    full marks. Now it misses on every personal survey, a public case and the hidden ones."""
    c = checks["01_least_squares"]
    mod = sys.modules[c.questions["q7"].reference.__module__]
    for sid in IDS:
        d = c.data_for("survey", sid)
        assert mod._unweighted_suspect(d) != c.questions["q7"].expected(data=d), sid
    q = c.questions["q7_practice"]
    missed = [mod._unweighted_suspect(*case.args) != q.expected(case) for case in q.cases]
    assert any(m for m, case in zip(missed, q.cases) if not case.hidden)
    assert sum(m for m, case in zip(missed, q.cases) if case.hidden) >= 2


# -- Monte Carlo: the seeded simulation itself, not its law ------------------------------
@pytest.mark.parametrize(
    "name, qid",
    [
        ("01_least_squares", "q8"),
        ("02_test_quantities", "q9"),
        ("03_estimation_and_likelihood", "q8"),
    ],
)
def test_monte_carlo_answers_repeat_the_seeded_simulation(checks, name, qid):
    """The theoretical value (declared as a mistake) and a simulation with another seed both
    fail every case; the reference itself is a fraction of the runs."""
    q = checks[name].questions[qid]
    for case in q.cases:
        expected = q.expected(case)
        n_runs = case.args[-2] if name != "01_least_squares" else case.args[3]
        assert float(expected) * n_runs == pytest.approx(round(float(expected) * n_runs))
        for message, wrong in q.mistaken(case):
            assert not compare(expected, wrong, q.rtol, q.atol).ok, (case.label, message)
        args = list(case.args)
        seed_at = -1 if name == "02_test_quantities" else (4 if name == "01_least_squares" else 3)
        args[seed_at] = int(args[seed_at]) + 1
        other = q.reference(*args)
        assert not compare(expected, other, q.rtol, q.atol).ok, case.label


# -- issue 26: cases that exercise what the question asks ---------------------------------
def test_02_q9_hidden_cases_vary_the_record_length(checks):
    """A detection_rate written with the notebook's N (not U.shape[0]) scored 2/2."""
    q = checks["02_test_quantities"].questions["q9"]
    public_n = {np.shape(c.args[0])[0] for c in q.public_cases}
    assert {np.shape(c.args[0])[0] for c in q.hidden_cases} - public_n


def test_02_q3_hidden_cases_include_u1_identically_zero(checks):
    """The question insists on the u1 = 0 guard: it must weigh on the hidden cases too."""
    q = checks["02_test_quantities"].questions["q3"]
    zero = [c for c in q.hidden_cases if not np.any(c.args[1])]
    assert len(zero) >= 2
    for case in zero:  # the answer is the whole sum of squares, neither 0 nor NaN
        y, _, u2, u3 = (np.asarray(a, dtype=float) for a in case.args)
        assert q.reference(*case.args) == pytest.approx(float(np.sum((y - u2 - u3) ** 2)))


def test_03_q7_public_case_with_sigma_not_one(checks):
    """With sigma = 1 only, dividing by sigma^2 passed the self-check; now a public case tells
    it, and names it."""
    q = checks["03_estimation_and_likelihood"].questions["q7"]
    cases = [c for c in q.public_cases if c.args[3] != 1.0]
    assert cases
    n, theta0, theta1, sigma, alpha = cases[0].args
    from scipy import stats

    wrong = float(
        stats.norm.sf(stats.norm.isf(alpha) - np.sqrt(n) * abs(theta1 - theta0) / sigma**2)
    )
    mistakes = [(m.message, m.reference(*cases[0].args)) for m in q.mistakes]
    verdict = compare(q.reference(*cases[0].args), wrong, q.rtol, q.atol, mistakes=mistakes)
    assert not verdict.ok and "sigma^2" in verdict.message


def _first_message(q, student):
    """The message a student reads: that of the first public case the answer fails."""
    for case in q.public_cases if q.kind == "function" else [None]:
        args = case.args if case is not None else ()
        mistakes = [(m.message, m.reference(*args)) for m in q.mistakes]
        verdict = compare(q.reference(*args), student(*args), q.rtol, q.atol, mistakes=mistakes)
        if not verdict.ok:
            return verdict.message
    return ""


def test_02_q4_dof_from_columns_is_told_to_use_the_rank(checks):
    """It was told "off by one ... a 1-based index" (and at grading "a factor ≈ 1.5")."""
    q = checks["02_test_quantities"].questions["q4"]

    def regression_residual(Phi, Y):
        T = q.reference(Phi, Y).T
        return (T, np.shape(Phi)[0] - np.shape(Phi)[1])

    message = _first_message(q, regression_residual)
    assert "use its rank" in message and "off by one" not in message


@pytest.mark.parametrize(
    ("qid", "wrong"),
    [
        ("q3", lambda q: lambda *args: q.reference(*args) / 0.2**2),
        ("q6", lambda q: lambda *a: (q.reference(*a).J / a[1] ** 2, q.reference(*a).power)),
        ("q7_practice", lambda q: lambda *a: q.reference(*a) / 0.2**2),
    ],
)
def test_02_one_over_sigma_squared_is_named(checks, qid, wrong):
    q = checks["02_test_quantities"].questions[qid]
    assert "sigma^2" in _first_message(q, wrong(q))


def test_02_q5_sum_for_mean_is_named(checks):
    q = checks["02_test_quantities"].questions["q5"]
    assert "sum of the squared residuals" in _first_message(
        q, lambda y, u: q.reference(y, u) * len(y)
    )


def test_02_q9_another_draw_order_is_named(checks):
    """A right statistic on noise drawn (N, n_runs) read like a wrong statistic."""
    q = checks["02_test_quantities"].questions["q9"]

    def detection_rate(U, theta, sigma, alpha, n_runs, seed):
        from scipy import stats

        U = np.asarray(U, dtype=float)
        n = U.shape[0]
        rng = np.random.default_rng(seed)
        Y = (U @ np.asarray(theta))[:, None] + sigma * rng.standard_normal((n, n_runs))
        target = Y.T - U[:, 1] - U[:, 2]
        u = U[:, 0]
        R = target - np.outer(target @ u, u) / (u @ u)
        return float(np.mean(np.sum(R**2, axis=1) > sigma**2 * stats.chi2.isf(alpha, n - 1)))

    assert "another order" in _first_message(q, detection_rate)
