"""Units of the exercise system: plain-data codec, comparisons and their messages, per-student
seeds, the student's self-check output, the sandbox layers (seccomp, spawn mode)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import hypothesis.extra.numpy as hnp
import hypothesis.strategies as st
import numpy as np
import pytest
from hypothesis import given, settings
from scipy.stats import chi2

from course.grading.authoring.checks import load_checks, student_rng
from course.grading.codec import Band, EncodingError, decode, encode, loads
from course.grading.compare import binomial_band, check_signature, compare, signature
from course.grading.student.selfcheck import Assignment

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
EXERCISE_DIR = ROOT / "exercises" / NAME


# -- codec --------------------------------------------------------------------------------
def test_codec_round_trip_without_pickle():
    value = {
        "a": np.arange(6.0).reshape(2, 3),
        "b": (1, 2.5, True, None, "s"),
        "c": [np.int64(3), np.float32(1.5)],
        "d": float("nan"),
        "e": np.array([True, False]),
        "f": 1 + 2j,
        "g": Band(0.1, 0.2),
    }
    back = loads(json.dumps(encode(value), allow_nan=False))
    assert np.array_equal(back["a"], value["a"]) and back["a"].flags.writeable
    assert back["b"] == (1, 2.5, True, None, "s")
    assert back["c"] == [3, 1.5] and type(back["c"][0]) is int
    assert np.isnan(back["d"]) and back["e"].dtype == bool and back["f"] == 1 + 2j
    assert back["g"] == Band(0.1, 0.2)
    text = json.dumps(encode(value))
    assert "pickle" not in text and "__reduce__" not in text


def test_codec_refuses_objects_and_student_bands():
    for bad in (np.array([object()]), {1: 2}, object(), {"__x": 1}):
        with pytest.raises(EncodingError):
            encode(bad)
    with pytest.raises(EncodingError):
        decode({"__pickle__": "x"})
    with pytest.raises(EncodingError):
        decode({"__band__": [0, 1]}, allow_band=False)


# -- comparisons ----------------------------------------------------------------------------
def test_compare_reports_shape_where_and_tolerance_never_the_expected_value():
    exp = np.array([1.0, 2.0, 3.0])
    assert compare(exp, exp + 1e-12).ok
    v = compare(exp, np.array([1.0, 2.0]))
    assert not v.ok and "expected shape (3,), got shape (2,)" in v.message
    assert "one element too few" in v.message
    v = compare(exp, np.array([1.0, 2.5, 3.1]), rtol=1e-6, atol=1e-8)
    assert "2 of 3 elements wrong, the worst at [1]" in v.message and "tolerance" in v.message
    assert "rtol 1e-06" in v.message and "atol 1e-08" in v.message
    assert "expected 2" not in v.message and "2.5" not in v.message
    # the instructor's detail has both, with the digits that tell them apart
    assert "expected 2, got 2.5" in v.detail and "largest error 0.5" in v.detail
    hidden = compare(exp, np.array([1.0, 2.5, 3.1]), reveal=False)
    assert "expected 2" not in hidden.detail
    assert "got NaN at [0]" in compare(exp, np.array([np.nan, 2, 3])).message
    # `expected 3, got 3`: a near miss is named as such, and the detail shows enough digits
    v = compare(3.0, 3.0000001, rtol=1e-10, atol=0.0)
    assert "close: it agrees to about 7 significant digits" in v.message
    assert "expected 3, got 3.0000001" in v.detail


@pytest.mark.parametrize(
    ("expected", "got", "words"),
    [
        (0.75, 1.5, "too large by a factor ≈ 2.0"),
        (1.5, 2.0, "too large by a factor ≈ 1.33 (= 4/3)"),
        (np.array([1.0, 2.0, 4.0]), np.array([0.5, 1.0, 2.0]), "too small by a factor ≈ 2.0"),
        (np.array([1.0, 2.0, 4.0]), np.array([1.37, 2.74, 5.48]), "too large by a factor ≈ 1.37"),
        (np.array([1.0, -2.0, 4.0]), np.array([-1.0, 2.0, -4.0]), "the sign is flipped"),
        (-0.5, 1.0, "the sign is flipped and too large by a factor ≈ 2.0"),
        (np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[1.0, 3.0], [2.0, 4.0]]), "transposed"),
        (np.array([[1.0, 2.0, 3.0]]), np.array([[1.0], [2.0], [3.0]]), "transposed"),
        (np.array([1.0, 2.0, 3.0]), np.array([2.0, 3.0, 1.0]), "another order"),
        (np.array([1.0, 2.0, 3.0]), np.array([3.0, 2.0, 1.0]), "reverse order"),
        (np.array([1.0, 2.0]), np.array([1.0, np.nan]), "got NaN at [1]"),
        (2.0, 4.0, "tolerance |got - expected| <= atol"),
        (["NF", "F1"], ["F1", "NF"], "the right items in another order"),
        (np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 3.0, 4.0]), "one element too many"),
        (np.array([1.0, 2.0]), np.array([[1.0, 2.0]]), "the right number of elements"),
        ("F1", "f1", "only in upper/lower case"),
        (2.0, "2.0", "expected a float, got a string"),
        (np.array([True, False]), np.array([False, True]), "every decision is the opposite"),
        (np.array([2.0, 3.0]), np.array([4.0, 9.0]), "the square"),
        (np.array([12.0, 3.0]), np.array([0.0, 0.0]), "all zeros"),
        (12.0, 0.0, "all zeros"),
        (np.array([12.0, 0.0]), np.array([5.0, 1.0]), "not within the tolerance"),
    ],
)
def test_compare_names_the_kind_of_wrong(expected, got, words):
    v = compare(expected, got, rtol=1e-8, atol=1e-10)
    assert not v.ok and words in v.message, v.message


def test_compare_names_a_declared_mistake_only_when_the_answer_is_wrong():
    mistakes = [("looks one-sided: z_alpha instead of z_alpha/2", 1.6448536269514722)]
    v = compare(1.959963984540054, 1.6448536269514724, mistakes=mistakes)
    assert not v.ok and v.message == "value: looks one-sided: z_alpha instead of z_alpha/2"
    assert compare(1.959963984540054, 1.959963984540054, mistakes=mistakes).ok
    assert "one-sided" not in compare(1.959963984540054, 3.0, mistakes=mistakes).message


def test_field_names_instead_of_item_numbers():
    from collections import namedtuple

    Result = namedtuple("Result", "statistic critical_value reject")
    expected = decode(encode(Result(6.0, 9.21, False)))  # the name survives the codec
    assert expected._fields == ("statistic", "critical_value", "reject")
    v = compare(expected, (6.0, 10.21, False))
    assert v.message.startswith("critical_value: ") and "item [1]" not in v.message
    v = compare((6.0, 9.21, False), Result(6.0, 9.21, True))  # the student's names count too
    assert v.message.startswith("reject: ")
    assert compare({"w": 1.0, "k": 2}, {"w": 1.0, "k": 3}).message.startswith("k: ")
    assert check_signature(signature(expected), (6.0, "x", False)).message.startswith(
        "critical_value: "
    )


def test_compare_exact_kinds_and_containers():
    assert compare(True, np.bool_(True)).ok and not compare(True, 1.0).ok
    assert compare(3, 3.0).ok and not compare(3, 4).ok
    assert compare("a", "a").ok and not compare("a", "b").ok
    assert compare((1.0, True), [1.0, True]).ok
    v = compare((1.0, 2.0, False), (1.0, 2.1, False))
    assert not v.ok and v.message.startswith("item [1]")  # no names to use
    assert not compare({"x": 1.0}, {"y": 1.0}).ok
    assert "expected a float, got a string" in compare(1.0, "1.0").message


def test_binomial_band_has_the_promised_coverage():
    band = binomial_band(20000, 0.05, miss=1e-4)
    assert band.lo < 0.05 < band.hi
    from scipy.stats import binom

    inside = binom.cdf(band.hi * 20000, 20000, 0.05) - binom.cdf(band.lo * 20000 - 1, 20000, 0.05)
    assert inside >= 1 - 1e-4
    # the typical mistake of q8 (chi2 with m instead of m - n degrees of freedom) lands far outside
    from scipy.stats import chi2

    wrong_rate = chi2.sf(chi2.isf(0.05, 4), 2)
    assert not compare(band, wrong_rate).ok
    assert "outside the accepted" in compare(band, 0.2).message


def test_signature_checks_type_and_shape_only():
    sig = signature((np.zeros(3), 1.5, True))
    assert check_signature(sig, (np.ones(3), -2.0, False)).ok
    assert not check_signature(sig, (np.ones(2), -2.0, False)).ok
    assert not check_signature(signature(1.0), np.nan).ok


# -- per-student data ---------------------------------------------------------------------
def test_student_rng_is_a_stable_hash_of_the_id():
    a = student_rng(NAME, "survey", "s123").standard_normal(3)
    assert np.array_equal(a, student_rng(NAME, "survey", " s123 ").standard_normal(3))
    assert not np.array_equal(a, student_rng(NAME, "survey", "s124").standard_normal(3))
    code = "from course.grading.authoring.checks import student_rng; print(student_rng('a', 'b', 'c').integers(1 << 62))"
    outs = {
        subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True,
            text=True,
            env={"PYTHONHASHSEED": seed, "PATH": "/usr/bin:/bin"},
            cwd=ROOT,
        ).stdout
        for seed in ("1", "2")
    }
    assert len(outs) == 1 and outs.pop().strip().isdigit()


def test_per_student_values_are_not_shipped():
    checks = load_checks(ROOT / "solutions" / NAME)
    spec = (EXERCISE_DIR / "checks.json").read_text()
    demo = checks.questions["q6"].expected(data=checks.data_for("survey", "demo"))
    assert repr(demo)[:8] not in spec
    q6 = next(q for q in json.loads(spec)["questions"] if q["id"] == "q6")
    assert q6["signature"] == {"kind": "float", "shape": []}


# -- the student's self-check ---------------------------------------------------------------
@pytest.fixture()
def check(monkeypatch):
    monkeypatch.chdir(EXERCISE_DIR)
    return Assignment.load(NAME, student_id="s123")


def test_self_check_pass_fail_hint_first(check, capsys):
    check("q1", lambda t, y: np.polyfit(t, y, 1)[::-1])
    assert "PASS" in capsys.readouterr().out
    check("q2", lambda t, y: np.array([6.0, -4.0, -10.0, 9.0]))  # day 2's last residual is 8
    out = capsys.readouterr().out
    assert "FAIL" in out and out.index("Hint") < out.index("the worst at [3]")
    assert "tolerance" in out and "8.0" not in out and "expected 8" not in out


def test_self_check_function_and_stub(check, capsys):
    def overall_model_test_stat(A, y, Qyy, alpha):
        raise NotImplementedError

    check("q3", overall_model_test_stat)
    assert "not answered yet" in capsys.readouterr().out
    from course import lsq

    def good(A, y, Qyy, alpha):
        r = lsq.overall_model_test(lsq.fit(A, y, Qyy), alpha)
        return r.statistic, r.critical_value, r.reject

    check("q3", good)
    out = capsys.readouterr().out
    # a forbidden library call is a FAIL (it scores 0 at grading), not PASS plus a warning
    assert "FAIL: your answer calls course.lsq.fit, course.lsq.overall_model_test" in out
    assert "PASS" not in out and "0 of 3 public cases count" in out

    def mine(A, y, Qyy, alpha):  # the fit is weighted too (a public case has Qyy != I)
        L = np.linalg.cholesky(Qyy)
        A_w, y_w = np.linalg.solve(L, A), np.linalg.solve(L, y)
        e = y_w - A_w @ np.linalg.lstsq(A_w, y_w, rcond=None)[0]
        statistic = float(e @ e)
        critical = float(chi2.isf(alpha, A.shape[0] - A.shape[1]))
        return statistic, critical, statistic > critical

    check("q3", mine)
    out = capsys.readouterr().out
    assert "3 of 3 public cases pass; 4 hidden cases run at grading." in out

    def wrong_dof(A, y, Qyy, alpha):
        T, c, _ = mine(A, y, Qyy, alpha)
        return T, c + 1.0, False

    check("q3", wrong_dof)
    out = capsys.readouterr().out
    # q3's reference is a named tuple: the feedback names the part (it said "item [1]")
    assert "FAIL" in out and "critical_value:" in out and "def " not in out
    assert "item [" not in out


def test_staged_hints_count_failures_in_the_kernel(tmp_path, capsys):
    from course.grading.authoring.seal import seal
    from course.grading.vocabulary import PublicCase, PublicQuestion, PublicSpec

    spec = PublicSpec(
        "demo_hints",
        "t",
        2.0,
        [
            PublicQuestion(
                "q1",
                "value",
                "x",
                1.0,
                hint=["a nudge", "the idea", "the formula"],
                cases=[PublicCase("x", seal(0.75, 1e-7, 1e-9, "salt 1"))],
            ),
            PublicQuestion(
                "q2",
                "value",
                "y",
                1.0,
                hint="one stage",
                cases=[PublicCase("y", seal(1.0, 1e-7, 1e-9, "salt 2"))],
            ),
        ],
    )
    spec = PublicSpec.loads(spec.text())  # as shipped in checks.json
    check = Assignment(spec, tmp_path, "s1")
    stages = []
    for _ in range(4):
        check("q1", 1.5)
        stages.append(capsys.readouterr().out)
    assert "Hint 1 of 3 (another failed check shows the next one): a nudge" in stages[0]
    assert "Hint 2 of 3" in stages[1] and "the idea" in stages[1]
    assert "Hint 3 of 3: the formula" in stages[2] and "Hint 3 of 3: the formula" in stages[3]
    assert all("0.75" not in out for out in stages)
    check("q1", 0.75)  # a pass shows no hint and does not count
    assert "PASS" in capsys.readouterr().out
    check("q2", 2.0)
    assert "Hint: one stage" in capsys.readouterr().out
    fresh = Assignment(spec, tmp_path, "s1")  # a new kernel starts over
    fresh("q1", 1.5)
    assert "Hint 1 of 3" in capsys.readouterr().out


def test_self_check_finds_answers_in_the_caller_namespace(check, capsys):
    line_estimate = ...  # noqa: F841  (a stub)
    check("q1")
    assert "not answered yet" in capsys.readouterr().out


def test_self_check_per_student_question(check, capsys):
    mine = check.data("survey")
    assert mine["A"].shape == (12, 2)
    check("q6", 12.5)
    out = capsys.readouterr().out
    assert "PASS: type and shape" in out and "checked at grading" in out and "'s123'" in out
    check("q6", -1.0)
    out = capsys.readouterr().out
    assert "FAIL: T is a non-negative number" in out and "Hint:" in out
    unset = Assignment.load(NAME, student_id="replace-with-your-student-id", path=EXERCISE_DIR)
    with pytest.raises(ValueError, match="Set STUDENT_ID"):
        unset.data("survey")


def test_self_check_matches_grader_data():
    checks = load_checks(ROOT / "solutions" / NAME)
    student = Assignment.load(NAME, student_id="s9", path=EXERCISE_DIR).data("survey")
    grader = checks.data_for("survey", "s9")
    for key in grader:
        assert np.array_equal(np.asarray(student[key]), np.asarray(grader[key]))


# -- sandbox layers -------------------------------------------------------------------------
def test_seccomp_blocks_fork_but_not_threads():
    from course.grading.sandbox.isolation import seccomp

    if not seccomp.available():
        pytest.skip("seccomp filter not available on this platform")
    code = textwrap.dedent("""
        import os, threading
        from course.grading.sandbox.isolation import seccomp
        assert seccomp.install()
        t = threading.Thread(target=lambda: None); t.start(); t.join()
        import _posixsubprocess  # the audit hook does not see this path; the kernel does
        try:
            os.fork()
            print("forked")
        except OSError as exc:
            print("blocked", exc.errno)
        try:
            os.kill(1, 0)
        except OSError:
            print("kill blocked")
    """)
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=60
    )
    assert out.stdout.split("\n")[:2] == ["blocked 1", "kill blocked"], out.stderr


def test_public_spec_round_trips_the_committed_checks_json():
    from course.grading.vocabulary import PublicSpec

    for folder in sorted((ROOT / "exercises").iterdir()):
        text = (folder / "checks.json").read_text("utf-8")
        spec = PublicSpec.loads(text)
        assert spec.assignment == folder.name and spec.questions
        assert spec.text() == text


# -- declared mistakes and forbidden calls (issue 13) ----------------------------------------
_MISTAKE_CHECKS = """
from scipy.stats import norm

from course.grading.authoring.checks import Checks, Mistake

CHECKS = Checks("mistakes_demo")


@CHECKS.value(
    "q1",
    var="z",
    points=1,
    hint=["Two-sided: alpha is split.", "z = norm.isf(alpha / 2)"],
    mistakes=[Mistake("looks one-sided: z_alpha instead of z_alpha/2", lambda: norm.isf(0.05))],
    forbid=["course.lsq.fit"],
)
def q1():
    return norm.isf(0.025)


q2 = CHECKS.function(
    "q2",
    func="crit",
    points=1,
    mistakes=[Mistake("looks one-sided", lambda alpha: norm.isf(alpha))],
    forbid=["course.lsq.fit"],
)(lambda alpha: norm.isf(alpha / 2))
q2.case(0.05)
q2.case(0.01, hidden=True)
"""


@pytest.fixture()
def mistakes_demo(tmp_path):
    from course.grading.authoring.release import public_spec
    from course.grading.vocabulary import PublicSpec

    folder = tmp_path / "mistakes_demo"
    folder.mkdir()
    (folder / "checks.py").write_text(_MISTAKE_CHECKS)
    checks = load_checks(folder)
    spec = PublicSpec.loads(public_spec(checks).text())
    return checks, spec, Assignment(spec, folder, "s1")


def test_declared_mistakes_ship_for_public_cases_and_are_named(mistakes_demo, capsys):
    from scipy.stats import norm

    checks, spec, check = mistakes_demo
    assert spec.question("q1").cases[0].mistakes[0][0].startswith("looks one-sided")
    assert spec.question("q1").hint == ["Two-sided: alpha is split.", "z = norm.isf(alpha / 2)"]
    assert len(spec.question("q2").cases) == 1  # the hidden case's mistake stays private
    check("q1", norm.isf(0.05))
    out = capsys.readouterr().out
    assert "z: looks one-sided: z_alpha instead of z_alpha/2" in out
    # the named mistake chooses the hint: it has none, so no staged hint (about another step
    # of the method) follows its message
    assert "Hint" not in out and "1.95996" not in out and "1.64485" not in out
    check("q1", 0.5)  # nothing diagnosed: the stages, in order
    assert "Hint 1 of 2" in capsys.readouterr().out
    check("q2", lambda alpha: float(norm.isf(alpha)))
    assert "value: looks one-sided" in capsys.readouterr().out
    check("q1", norm.isf(0.025))
    assert "PASS" in capsys.readouterr().out
    # the grader names the mistake of every case, hidden ones included
    wrong = checks.questions["q2"].mistaken(checks.questions["q2"].hidden_cases[0])
    assert wrong[0][0] == "looks one-sided" and wrong[0][1] == pytest.approx(norm.isf(0.01))


def test_mistake_and_hint_arguments_are_validated():
    from course.grading.authoring.checks import Checks, Mistake

    with pytest.raises(ValueError, match="message must be a non-empty string"):
        Mistake("", lambda: 1.0)
    with pytest.raises(ValueError, match="reference must be a function"):
        Mistake("m", 1.0)
    c = Checks("x")
    with pytest.raises(ValueError, match="mistakes=\\[Mistake"):
        c.value("q1", var="v", points=1, mistakes=["not a Mistake"])(lambda: 1.0)
    with pytest.raises(ValueError, match="hint stages must be non-empty strings"):
        c.value("q2", var="w", points=1, hint=["nudge", ""])(lambda: 1.0)
    from course.grading import Mistake as exported

    assert exported is Mistake


def test_a_forbidden_call_fails_the_self_check(mistakes_demo, capsys):
    from course import lsq

    _, _, check = mistakes_demo

    def crit(alpha):  # right values, through a forbidden library function
        lsq.fit(np.ones((2, 1)), np.ones(2))
        from scipy.stats import norm

        return float(norm.isf(alpha / 2))

    check("q2", crit)
    out = capsys.readouterr().out
    assert "FAIL: your answer calls course.lsq.fit" in out and "scores 0 at grading" in out
    assert "PASS" not in out and "Warning" not in out


def _run_cell(check, cell_id: str, source: str, ns: dict) -> None:
    """Run ``source`` as the notebook cell ``cell_id`` (as JupyterLab tells the kernel)."""
    check._cells._cell = cell_id
    exec(compile(textwrap.dedent(source), f"<{cell_id}>", "exec"), ns)


_FORBIDDEN_CALLS = {  # every path to course.lsq.fit, in the answer cell of q1 (a value question)
    "plain": "from course import lsq\nlsq.fit(np.ones((2, 1)), np.ones(2))",
    "alias": "from course.lsq import fit as f\nf(np.ones((2, 1)), np.ones(2))",
    "module alias": "import course.lsq as cl\ncl.fit(np.ones((2, 1)), np.ones(2))",
    "getattr": "import course.lsq\ngetattr(course.lsq, 'f' + 'it')(np.ones((2, 1)), np.ones(2))",
    "__import__": "__import__('course.lsq', fromlist=['x']).fit(np.ones((2, 1)), np.ones(2))",
    "partial": "import functools, course.lsq\nfunctools.partial(course.lsq.fit, np.ones((2, 1)))(np.ones(2))",
    "private twin": "from course.lsq import _fit\n_fit._rcond_upper(np.ones((2, 1)))",
}


@pytest.mark.parametrize("how", sorted(_FORBIDDEN_CALLS))
def test_a_forbidden_call_by_any_path_fails_a_value_question(mistakes_demo, capsys, how):
    """The self-check uses the grader's tripwires (the function objects report, not a scan of
    names): an alias, getattr, __import__, partial or a private helper of the function trip
    them, in the answer cell or in a cell the student added (a scratch cell)."""
    from scipy.stats import norm

    _, _, check = mistakes_demo
    for cell in ("q1-answer", "a-scratch-cell"):
        check.calls.clear()
        ns = {"np": np, "z": norm.isf(0.025)}
        _run_cell(check, cell, _FORBIDDEN_CALLS[how], ns)
        check._check("q1", ns, None, False)
        out = capsys.readouterr().out
        assert "FAIL: your answer cell or a cell you added" in out, (cell, out)
        if how == "private twin":  # named as called (issue 37 item 3)
            assert "calls course.lsq._fit._rcond_upper (a private helper of course.lsq.fit)" in out
        else:
            assert "calls course.lsq.fit" in out
        assert "PASS" not in out


def test_a_forbidden_import_or_another_answers_call_costs_nothing(mistakes_demo, capsys):
    """An import is not a call; a call in another question's answer cell (where that question
    allows it) or while another question's check runs is not this question's."""
    from scipy.stats import norm

    _, _, check = mistakes_demo
    ns = {"np": np, "z": norm.isf(0.025)}
    _run_cell(check, "q1-answer", "from course.lsq import fit\nimport course.lsq as cl", ns)
    _run_cell(check, "q2-answer", "fit(np.ones((2, 1)), np.ones(2))", ns)
    _run_cell(check, "q2-check", "fit(np.ones((2, 1)), np.ones(2))", ns)
    check._check("q1", ns, None, False)
    out = capsys.readouterr().out
    assert "PASS" in out and "FAIL" not in out, out

    check.calls.clear()  # (q2 forbids fit too: its answer cell's call counted against q2)
    # a scratch cell's call counts against the value question q1, not the function question q2
    _run_cell(check, "a-scratch-cell", "fit(np.ones((2, 1)), np.ones(2))", ns)
    assert check._forbidden_calls(check._questions["q1"]) == {"course.lsq.fit"}
    assert check._forbidden_calls(check._questions["q2"]) == set()
    # running the cell again without the call withdraws it (IPython's pre_run_cell)
    check._forget_cell(type("Info", (), {"cell_id": "a-scratch-cell"})())
    assert check._forbidden_calls(check._questions["q1"]) == set()

    def crit(alpha):  # imports the forbidden function and never calls it
        from course.lsq import fit  # noqa: F401

        return float(norm.isf(alpha / 2))

    check("q2", crit)
    out = capsys.readouterr().out
    assert "1 of 1 public case passes" in out and "FAIL" not in out, out


def test_a_forbidden_call_in_a_protected_cell_costs_nothing_as_at_grading(tmp_path):
    """A protected cell of the released notebook (setup or context, e.g. ``check.submit()``)
    is not a cell the student added: its forbidden call counts against no question, as at
    grading (docs/instructors/authoring.md). It counted against every value question that
    forbids the function, so running ``check.submit()`` or the class's grader in the kernel
    after it failed them (issue 36, the self-check and grading disagreed)."""
    import json

    from course.grading.authoring.release import public_spec
    from course.grading.vocabulary import PublicSpec

    folder = tmp_path / "mistakes_demo"
    folder.mkdir()
    (folder / "checks.py").write_text(_MISTAKE_CHECKS)
    spec = PublicSpec.loads(public_spec(load_checks(folder)).text())

    def cell(cid, role=None):
        meta = {"course": {"role": role}} if role else {}
        return {"cell_type": "code", "id": cid, "metadata": meta, "source": "", "outputs": []}

    nb = {"cells": [cell("setup", "setup"), cell("code-02", "context"), cell("mine")]}
    (folder / "mistakes_demo.ipynb").write_text(json.dumps(nb))
    check = Assignment(spec, folder, "s1")
    q1, q2 = check._questions["q1"], check._questions["q2"]
    ns = {"np": np}
    for protected in ("setup", "code-02"):
        _run_cell(
            check, protected, "import course.lsq\ncourse.lsq.fit(np.ones((2, 1)), np.ones(2))", ns
        )
    assert check._forbidden_calls(q1) == set() and check._forbidden_calls(q2) == set()
    _run_cell(check, "mine", "course.lsq.fit(np.ones((2, 1)), np.ones(2))", ns)  # added by me
    assert check._forbidden_calls(q1) == {"course.lsq.fit"}
    assert check._forbidden_calls(q2) == set()


def test_the_self_check_catches_private_twins_and_aliases_of_assignment_04(capsys):
    """04 q8 (kf_update) and q2 (kalman_filter): the private implementation and aliased
    imports failed at grading but passed the self-check (issue 26)."""
    from course.grading.vocabulary import PublicSpec

    folder = ROOT / "exercises" / "04_ekf_residuals"
    check = Assignment(PublicSpec.read(folder), folder, "s1")
    from course.filters._steps import _kf_update

    def twin(theta, P, phi, y, r):  # right values, through the private implementation
        args = (np.atleast_1d(y), np.asarray(phi, float)[None, :], np.array([[r]]))
        out = _kf_update(np.asarray(theta, float), np.asarray(P, float), *args)
        return out[0], out[1]

    from course.filters import kf_update as f

    def aliased(theta, P, phi, y, r):
        args = (np.atleast_1d(y), np.asarray(phi, float)[None, :], np.array([[r]]))
        out = f(np.asarray(theta, float), np.asarray(P, float), *args)
        return out[0], out[1]

    for func in (twin, aliased):
        check("q8", func)
        out = capsys.readouterr().out
        assert "FAIL: your answer calls " in out and "course.filters.kf_update" in out, out
        assert "PASS" not in out and "(1 of 1 give the right values)" in out, out
    del check


def test_a_forbidden_function_called_through_its_private_module_fails_the_self_check(
    mistakes_demo, capsys
):
    """The grader forbids the code, not the public name: ``course.lsq._fit.fit`` is
    ``course.lsq.fit`` and scores 0 at grading, so the self-check must say so as well (it
    wrapped only the public attribute, and a call made in a helper from another cell showed
    PASS)."""
    from course.lsq import _fit

    _, _, check = mistakes_demo

    def helper():  # another cell's function: the scan of the answer's source does not see it
        return _fit.fit(np.ones((2, 1)), np.ones(2))

    def crit(alpha):
        helper()
        from scipy.stats import norm

        return float(norm.isf(alpha / 2))

    check("q2", crit)
    out = capsys.readouterr().out
    assert "FAIL: your answer calls course.lsq.fit" in out and "PASS" not in out
    assert _fit.fit.__module__ == "course.lsq._fit"


@settings(max_examples=150, deadline=None, derandomize=True, database=None)
@given(
    expected=hnp.arrays(
        np.float64,
        hnp.array_shapes(min_dims=0, max_dims=2, max_side=4),
        elements=st.floats(-1e6, 1e6, allow_nan=False).filter(lambda x: abs(x) > 1e-3),
    ),
    how=st.sampled_from(["double", "negate", "shift", "reverse", "transpose", "noise", "zero"]),
    seed=st.integers(0, 2**32 - 1),
)
def test_compare_never_shows_an_expected_number(expected, how, seed):
    """Whatever the wrong answer, the student's message carries no expected element (at 6
    significant digits or as repr), and a diagnosis never breaks the verdict."""
    rng = np.random.default_rng(seed)
    got = {
        "double": lambda e: 2.0 * e,
        "negate": lambda e: -e,
        "shift": lambda e: e + 1.0,
        "reverse": lambda e: e[::-1] if e.ndim else e,
        "transpose": lambda e: e.T,
        "noise": lambda e: e * (1 + rng.uniform(1e-6, 1e-2, e.shape)),
        "zero": np.zeros_like,
    }[how](expected)
    v = compare(expected, got, rtol=1e-9, atol=1e-12)
    if v.ok:
        return
    for x in np.atleast_1d(expected).ravel():
        digits = f"{abs(x):.6e}".split("e")[0].replace(".", "").rstrip("0")
        if len(digits) >= 4:  # a number with some digits: its printed forms must not show
            for text in (f"{x:.6g}", repr(float(x))):
                assert text not in v.message, (text, v.message)


def test_the_short_answer_self_check_says_whether_the_saved_cell_is_answered(tmp_path, capsys):
    """Issue 37 item 7: the self-check of a short answer told a student who had answered to
    "replace its placeholder line"; it reads the saved cell and says which it is."""
    from course.grading.items import SHORT_ANSWER_STUB
    from course.grading.student.submit import saved_short_answer

    name = "05_nis_wishart"
    folder = ROOT / "exercises" / name
    check = Assignment.load(name, student_id="s123", path=folder)
    nb = json.loads((folder / f"{name}.ipynb").read_text(encoding="utf-8"))
    (cell,) = [
        c
        for c in nb["cells"]
        if c.get("metadata", {}).get("course", {}).get("question") == "q6_why"
    ]
    assert "".join(cell["source"]).strip() == SHORT_ANSWER_STUB
    path = tmp_path / f"{name}.ipynb"
    ns = {"__session__": str(path)}
    for text, words, absent in (
        (SHORT_ANSWER_STUB, "not answered yet", "Answered"),
        ("The matrix test sees the cross-correlation.", "Answered", "placeholder"),
    ):
        cell["source"] = [text]
        path.write_text(json.dumps(nb), encoding="utf-8")
        assert saved_short_answer(ns, name, "q6_why") == text
        exec("check('q6_why')", {**ns, "check": check})
        out = capsys.readouterr().out
        assert words in out and absent not in out and "replacing" not in out, out
    assert (
        saved_short_answer({"__session__": str(tmp_path / "gone.ipynb")}, "nowhere", "q6_why")
        is None
    )


def test_a_float32_line_estimate_fails_at_the_self_check_as_at_grading(check, capsys):
    """Issue 37 item 7: 01 q1's only public case had a round answer, exact in float32, so a
    float32 answer passed the self-check and lost its point at grading; a non-round public
    case tells it at the self-check."""

    def in_float32(t, y):
        A = np.column_stack([np.ones(len(t)), t]).astype(np.float32)
        return np.linalg.lstsq(A, np.asarray(y, dtype=np.float32), rcond=None)[0]

    check("q1", in_float32)
    out = capsys.readouterr().out
    assert "FAIL" in out and "single precision (float32)" in out, out
    check("q1", lambda t, y: np.polyfit(t, y, 1)[::-1])
    assert "FAIL" not in capsys.readouterr().out


def test_a_call_through_another_answer_is_charged_there_as_at_grading(capsys):
    """Issue 37 item 3, the self-check's side: q4's function calls the student's q3
    function, which calls lsq.fit (both questions forbid it). q3 fails for the call; q4 is
    checked on its own values with a note that the call is charged on q3, as grading does
    (tests/test_grading_session.py)."""
    import scipy.linalg
    import scipy.stats

    import course.lsq
    from course.grading.vocabulary import PublicSpec

    folder = ROOT / "exercises" / "01_least_squares"
    check = Assignment(PublicSpec.read(folder), folder, "s1")
    solution = json.loads(
        (ROOT / "solutions" / "01_least_squares" / "01_least_squares.ipynb").read_text()
    )
    q4 = next("".join(c["source"]) for c in solution["cells"] if c.get("id") == "q4-answer")
    ns = {"np": np, "lsq": course.lsq, "linalg": scipy.linalg, "stats": scipy.stats}
    exec(
        "def overall_model_test_stat(A, y, Qyy, alpha):\n"
        "    r = lsq.overall_model_test(lsq.fit(A, y, Qyy), alpha)\n"
        "    return r.statistic, r.critical_value, r.reject\n",
        ns,
    )
    exec(
        q4.replace(
            "    return numerator / denominator",
            "    overall_model_test_stat(A, y, Qyy, 0.05)\n    return numerator / denominator",
        ),
        ns,
    )
    check._check("q3", ns, None, False)
    out = capsys.readouterr().out
    assert "FAIL: your answer calls course.lsq.fit, course.lsq.overall_model_test" in out, out
    check._check("q4", ns, None, False)
    out = capsys.readouterr().out
    assert (
        "note: your w_statistics calls overall_model_test_stat (your answer to q3), which "
        "calls course.lsq.fit: charged on q3, not here"
    ) in out, out
    assert "FAIL" not in out and "PASS" in out, out
