"""Tests of the shared pieces: course.results, course.linalg, course.distributions, import hygiene."""

import subprocess
import sys
from dataclasses import FrozenInstanceError

import numpy as np
import pytest
from numpy.linalg import LinAlgError
from scipy import stats

from course import linalg as cl
from course import validation
from course.distributions import FrozenDistribution
from course.results import TestResult, as_plain, describe_distribution, format_number


# ---------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------
def make_result(**overrides):
    kwargs = dict(
        name="overall model test",
        statistic=np.float64(6.0),
        alpha=np.float64(0.01),
        critical_value=np.float64(stats.chi2.isf(0.01, 2)),
        pvalue=np.float64(stats.chi2.sf(6.0, 2)),
        reject=np.bool_(False),
        null=stats.chi2(2),
        dof=np.int64(2),
    )
    kwargs.update(overrides)
    return TestResult(**kwargs)


def test_result_repr_is_short_and_deterministic():
    r = make_result()
    expected = (
        "TestResult('overall model test', statistic=6, dof=2, alpha=0.01, critical_value=9.2103, "
        "pvalue=0.04979, reject=False, null=chi2(2))"
    )
    assert repr(r) == expected
    assert repr(make_result()) == expected  # a second, independent build prints the same
    assert r.summary() == (
        "overall model test: statistic = 6, critical region > 9.2103 (alpha = 0.01), "
        "p = 0.04979: accept H0"
    )


def test_result_fields_are_plain_python_and_printing_shows_no_numpy_scalars():
    r = make_result(details={"variance factor": np.float64(3.0)})
    assert type(r.statistic) is float and type(r.alpha) is float and type(r.pvalue) is float
    assert type(r.reject) is bool and type(r.dof) is int and type(r.critical_value) is float
    for text in (repr(r), r.summary(), r._repr_html_()):
        assert "np." not in text and "float64" not in text and "0x" not in text
    assert "<table>" in r._repr_html_() and "variance factor" in r._repr_html_()


# np.float64 subclasses float: a naive isinstance(float) check would let it through.
def test_as_plain_converts_numpy_floats():
    assert type(as_plain(np.float64(2.5))) is float


def test_result_details_are_plain():
    r = make_result(details={"variance factor": np.float64(3.0)})
    assert "np." not in str(r.details)


def test_two_sided_result_with_tuple_critical_values():
    crit = stats.norm.isf(0.025)
    r = make_result(
        name="w-test",
        statistic=np.float64(-2.5),
        alpha=0.05,
        critical_value=(np.float64(-crit), np.float64(crit)),
        pvalue=2 * stats.norm.sf(2.5),
        reject=True,
        null=stats.norm(),
        dof=None,
        alternative="two-sided",
    )
    assert r.critical_value == (-crit, crit)
    assert all(type(v) is float for v in r.critical_value)
    assert "outside [-1.96, 1.96]" in r.summary() and r.summary().endswith("reject H0")
    assert "critical_value=(-1.96, 1.96)" in repr(r) and "null=norm()" in repr(r)
    assert "dof" not in repr(r)
    assert "np." not in repr(r) + r.summary() + r._repr_html_()


def test_less_alternative_summary():
    # statistic 6 < 9.2103 rejects; a consistent result has p < alpha too
    r = make_result(alternative="less", reject=True, pvalue=0.005)
    assert "critical region < 9.2103" in r.summary()


@pytest.mark.parametrize("alpha", [0, 1, -0.1, 1.5])
def test_result_alpha_validation(alpha):
    with pytest.raises(ValueError, match="alpha must lie strictly between 0 and 1"):
        make_result(alpha=alpha)


def test_result_alternative_validation_and_frozen():
    with pytest.raises(ValueError, match="alternative must be one of"):
        make_result(alternative="both")
    r = make_result()
    with pytest.raises(FrozenInstanceError):
        r.reject = True


def test_format_number_and_helpers():
    assert format_number(np.float64(6.0)) == "6"
    assert format_number(9.21034037) == "9.2103"
    assert format_number(1.2345678e-47, 4) == "1.235e-47"
    assert format_number((np.float64(-1.959964), 1.959964), 4) == "(-1.96, 1.96)"
    assert format_number(np.int64(3)) == "3" and format_number(True) == "True"
    assert format_number(float("nan")) == "nan"
    assert as_plain(np.float64(2.5)) == 2.5 and type(as_plain(np.float32(2.5))) is float
    assert as_plain((np.int64(1), np.float64(2))) == (1, 2.0)
    arr = np.arange(3)
    assert as_plain(arr) is arr
    assert describe_distribution(stats.chi2(3)) == "chi2(3)"
    assert describe_distribution(stats.norm(loc=1.5)) == "norm(loc=1.5)"
    assert describe_distribution(None) == "None"


# ---------------------------------------------------------------------------
# linalg
# ---------------------------------------------------------------------------
def test_as_float_array_errors_and_copy():
    with pytest.raises(
        ValueError, match=r"y contains NaN or inf \(1 entries, first at index \(2,\)\)"
    ):
        validation.as_float_array([1, 2, np.nan], "y")
    with pytest.raises(ValueError, match="y must be numeric"):
        validation.as_float_array(["a", "b"], "y")
    with pytest.raises(
        ValueError, match=r"A must be 2-dimensional, got shape \(3,\) \(pass a column"
    ):
        validation.as_float_array([1, 2, 3], "A", ndim=2)
    with pytest.raises(ValueError, match="y is None"):
        validation.as_float_array(None, "y")
    with pytest.raises(ValueError, match="y is complex; pass real numbers"):
        validation.as_float_array(
            np.array([1.0, 2.0 + 1e-20j]), "y"
        )  # never drops imaginary parts silently
    with pytest.raises(ValueError, match="y must be numeric"):
        validation.as_float_array([[1.0, 2.0], [3.0]], "y")
    src = np.arange(3.0)
    out = validation.as_float_array(src, "y")
    out[0] = 99
    assert src[0] == 0.0  # the caller's array is never modified


def test_as_vector_and_as_matrix_messages():
    with pytest.raises(
        ValueError, match=r"y must be a 1-D vector, got shape \(3, 1\); pass it flattened"
    ):
        validation.as_vector(np.ones((3, 1)), "y")
    with pytest.raises(ValueError, match="y must have length 4, got 3"):
        validation.as_vector([1, 2, 3], "y", size=4)
    with pytest.raises(ValueError, match=r"H must have shape \(2, any\), got \(3, 2\)"):
        validation.as_matrix(np.ones((3, 2)), "H", shape=(2, None))
    assert validation.as_matrix(np.ones((2, 5)), "H", shape=(2, None)).shape == (2, 5)


def test_as_covariance_checks():
    with pytest.raises(ValueError, match=r"R must have shape \(2, 2\)"):
        validation.as_covariance(np.eye(3), "R", 2)
    with pytest.raises(ValueError, match="R is not symmetric"):
        validation.as_covariance([[1.0, 0.5], [0.0, 1.0]], "R", 2)
    with pytest.raises(LinAlgError, match=r"R is not positive definite \(smallest eigenvalue -1"):
        validation.as_covariance([[1.0, 2.0], [2.0, 1.0]], "R", 2)
    with pytest.raises(LinAlgError, match="R is not positive definite"):
        validation.as_covariance([[1.0, 1.0], [1.0, 1.0]], "R", 2)
    singular = np.array([[1.0, 1.0], [1.0, 1.0]])
    np.testing.assert_array_equal(
        validation.as_covariance(singular, "R", 2, allow_singular=True), singular
    )
    with pytest.raises(LinAlgError, match="not positive semi-definite"):
        validation.as_covariance([[1.0, 2.0], [2.0, 1.0]], "R", 2, allow_singular=True)


def test_as_probability():
    assert validation.as_probability(np.float64(0.05)) == 0.05
    for bad in (0, 1, 2, -1):
        with pytest.raises(ValueError, match="alpha must lie strictly between 0 and 1"):
            validation.as_probability(bad)
    with pytest.raises(ValueError, match="power must be a number in"):
        validation.as_probability("high", "power")


def test_cholesky_whiten_and_solve_spd():
    rng = np.random.default_rng(0)
    B = rng.standard_normal((5, 5))
    S = B @ B.T + 5 * np.eye(5)
    L = cl.cholesky_lower(S, "S")
    np.testing.assert_allclose(L @ L.T, S, rtol=1e-12)
    assert np.allclose(L, np.tril(L))
    v = rng.standard_normal(5)
    np.testing.assert_allclose(L @ cl.whiten(L, v), v, rtol=1e-12)
    np.testing.assert_allclose(S @ cl.solve_spd(S, v), v, rtol=1e-10)
    with pytest.raises(LinAlgError, match="P is not positive definite"):
        cl.cholesky_lower(-np.eye(2), "P")


def test_column_rank_deficiency_and_message():
    t = np.arange(5.0)
    assert cl.column_rank_deficiency(np.column_stack([np.ones(5), t])) == []
    assert cl.column_rank_deficiency(np.column_stack([np.ones(5), t, np.zeros(5)])) == [2]
    dependent = cl.column_rank_deficiency(np.column_stack([np.ones(5), t, t + 1]))
    assert len(dependent) == 1
    with pytest.raises(LinAlgError, match=r"H does not have full column rank: column\(s\) \[1\]"):
        cl.check_full_column_rank(np.column_stack([np.ones(5), np.zeros(5)]), "H")
    cl.check_full_column_rank(np.eye(3))  # full rank: no error


def test_symmetrize_and_psd_sqrt():
    P = np.array([[2.0, 1.0], [0.0, 3.0]])
    np.testing.assert_array_equal(cl.symmetrize(P), [[2.0, 0.5], [0.5, 3.0]])
    stack = np.stack([P, P.T])
    np.testing.assert_array_equal(cl.symmetrize(stack)[1], [[2.0, 0.5], [0.5, 3.0]])
    C = np.array([[4.0, 2.0], [2.0, 1.0]])  # rank one
    S = cl.psd_sqrt(C)
    np.testing.assert_allclose(S @ S, C, atol=1e-12)
    np.testing.assert_allclose(S, S.T)


# ---------------------------------------------------------------------------
# distributions
# ---------------------------------------------------------------------------
class Chi2Wrapper(FrozenDistribution):
    """Minimal subclass: only _cdf, _sf, _rvs (pdf, quantiles, moments from the base)."""

    def __init__(self, dof):
        self.dof = dof

    def _cdf(self, x):
        return stats.chi2.cdf(x, self.dof)

    def _sf(self, x):
        return stats.chi2.sf(x, self.dof)

    def _rvs(self, size, rng):
        return rng.chisquare(self.dof, size=size)


@pytest.mark.parametrize("dof", [1, 3, 10])
def test_frozen_distribution_subclass_matches_scipy(dof):
    ours, ref = Chi2Wrapper(dof), stats.chi2(dof)
    x = np.array([0.05, 0.5, 1.0, 3.0, 9.0, 25.0])
    np.testing.assert_allclose(ours.cdf(x), ref.cdf(x), rtol=1e-12)
    np.testing.assert_allclose(ours.sf(x), ref.sf(x), rtol=1e-12)
    np.testing.assert_allclose(ours.pdf(x), ref.pdf(x), rtol=1e-6)
    q = np.array([1e-6, 0.01, 0.5, 0.95, 0.999])
    np.testing.assert_allclose(ours.ppf(q), ref.ppf(q), rtol=1e-9)
    np.testing.assert_allclose(ours.isf(q), ref.isf(q), rtol=1e-9)
    assert ours.isf(1e-12) == pytest.approx(ref.isf(1e-12), rel=1e-9)  # deep upper tail via sf
    assert ours.mean() == pytest.approx(ref.mean(), rel=1e-7)
    assert ours.var() == pytest.approx(ref.var(), rel=1e-6)
    assert ours.std() == pytest.approx(ref.std(), rel=1e-6)
    lo, hi = ours.interval(0.9)
    assert (lo, hi) == pytest.approx(ref.interval(0.9), rel=1e-9)
    assert ours.cdf(-1.0) == 0.0 and ours.sf(-1.0) == 1.0 and ours.pdf(-1.0) == 0.0
    assert ours.ppf(0.0) == 0.0 and ours.isf(0.0) == np.inf
    assert np.ndim(ours.cdf(2.0)) == 0


def test_frozen_distribution_input_checks_and_rvs():
    d = Chi2Wrapper(2)
    with pytest.raises(ValueError, match="probabilities must lie in"):
        d.ppf(1.5)
    with pytest.raises(ValueError, match="x contains NaN"):
        d.cdf(np.nan)
    a = d.rvs(size=5, rng=np.random.default_rng(3))
    b = d.rvs(size=5, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    g = np.random.default_rng(1)
    assert validation.as_generator(g) is g
    assert isinstance(validation.as_generator(7), np.random.Generator)
    with pytest.raises(TypeError, match="not a legacy RandomState"):
        validation.as_generator(np.random.RandomState(0))
    # the default repr is deterministic (no memory address), so results print the same every run
    assert repr(Chi2Wrapper(np.int64(3))) == "Chi2Wrapper(dof=3)"
    assert describe_distribution(Chi2Wrapper(2.5)) == "Chi2Wrapper(dof=2.5)"


# ---------------------------------------------------------------------------
# import hygiene
# ---------------------------------------------------------------------------
def run_python(code):
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_import_course_loads_no_scipy_matplotlib_and_prints_nothing():
    code = (
        "import sys, course\n"
        "heavy = sorted(m for m in ('scipy', 'matplotlib') if m in sys.modules)\n"
        "print('HEAVY', heavy)\n"
    )
    assert run_python(code) == "HEAVY []"


def test_library_modules_do_not_import_matplotlib():
    code = (
        "import sys, course\n"
        "course.lsq, course.results, course.linalg, course.distributions, course.plotting\n"
        "import course.plotting.lsq\n"
        "print('matplotlib' in sys.modules)\n"
    )
    assert run_python(code) == "False"


# ---------------------------------------------------------------------------
# the course command
# ---------------------------------------------------------------------------
def test_python_m_course_is_the_course_command():
    out = subprocess.run(
        [sys.executable, "-m", "course", "--help"], capture_output=True, text=True, timeout=120
    )
    assert (
        out.returncode == 0
        and "open" in out.stdout
        and "release" in out.stdout
        and "grade" in out.stdout
    )
    out = subprocess.run(
        [sys.executable, "-m", "course", "open", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0 and "JupyterLab" in out.stdout and "--no-browser" in out.stdout
    out = subprocess.run(
        [sys.executable, "-m", "course", "release", "x", "--bogus"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 2 and "unrecognized arguments: --bogus" in out.stderr


def test_course_open_uses_this_interpreters_jupyter(monkeypatch, tmp_path, capsys):
    from course import cli

    calls = []
    monkeypatch.setattr(
        cli.subprocess, "call", lambda command, cwd: calls.append((command, cwd)) or 0
    )
    monkeypatch.setenv("PATH", "/nonexistent")  # no `jupyter` on PATH: found through sys.executable
    assert cli.main(["open", "--no-browser", "--port=8890"]) == 0
    ((command, cwd),) = calls
    assert command[:3] == [sys.executable, "-m", "jupyterlab"] and command[3:] == [
        "--no-browser",
        "--port=8890",
    ]
    assert cwd.name == "notebooks" and (cwd / "01_least_squares_validation.ipynb").is_file()
    notebook = tmp_path / "x.ipynb"
    notebook.write_text("{}")
    assert cli.main(["open", str(notebook), "--app", "notebook"]) == 0
    assert calls[-1] == ([sys.executable, "-m", "notebook", "x.ipynb"], tmp_path)
    assert cli.main(["open", str(tmp_path / "missing")]) == 2
    assert "does not exist" in capsys.readouterr().err
    monkeypatch.setattr(cli, "_jupyter_command", lambda app: None)
    assert cli.main(["open"]) == 2
    assert "is not installed" in capsys.readouterr().err


@pytest.mark.parametrize(
    "words, jupyter",
    [
        (["--port", "8899"], ["--port", "8899"]),  # issue 39: 8899 was taken for the folder
        (["--port=8899"], ["--port=8899"]),
        (["--ip", "0.0.0.0", "--port", "8899"], ["--ip", "0.0.0.0", "--port", "8899"]),
        (["--ip=0.0.0.0"], ["--ip=0.0.0.0"]),
        (["--allow-root"], ["--allow-root"]),
        (["--ServerApp.token", ""], ["--ServerApp.token", ""]),
    ],
)
@pytest.mark.parametrize("folder", ["none", "before", "after"])
def test_course_open_passes_jupyters_options_on_in_both_forms(
    monkeypatch, tmp_path, words, jupyter, folder
):
    from course import cli

    calls = []

    def call(command, cwd):
        calls.append((command, cwd))
        return 0

    monkeypatch.setattr(cli.subprocess, "call", call)
    notebook = tmp_path / "x.ipynb"
    notebook.write_text("{}")
    # a Jupyter switch (no value) just before the folder leaves the folder to course
    args = {
        "none": words,
        "before": [str(notebook), *words],
        "after": [*words, "--allow-root", str(notebook)],
    }[folder]
    assert cli.main(["open", "--no-browser", *args, "--app", "notebook"]) == 0
    ((command, cwd),) = calls
    opened = {"none": [], "before": ["x.ipynb"], "after": ["--allow-root", "x.ipynb"]}[folder]
    assert command == [sys.executable, "-m", "notebook", "--no-browser", *jupyter, *opened]
    assert cwd.name == "notebooks" if folder == "none" else cwd == tmp_path


def test_only_open_and_mark_pass_unknown_options_on():
    from course import cli

    with pytest.raises(SystemExit):
        cli.main(["docs", "out", "--port", "8899"])


# ---------------------------------------------------------------------------
# the decision path, laws and the linear-algebra home (release 0.2)
# ---------------------------------------------------------------------------
def test_decide_for_every_alternative_and_for_arrays():
    from course.results import CriticalValues, decide

    law = stats.chi2(3)
    d = decide(law, 10.0, 0.05, "greater")
    assert d.critical_value == pytest.approx(law.isf(0.05)) and d.reject
    assert d.pvalue == pytest.approx(law.sf(10.0))
    d = decide(law, 0.1, 0.05, "less")
    assert d.critical_value == pytest.approx(law.ppf(0.05)) and d.reject
    d = decide(law, np.array([0.01, 3.0, 20.0]), 0.05, "two-sided")
    assert isinstance(d.critical_value, CriticalValues)
    np.testing.assert_array_equal(d.reject, [True, False, True])
    np.testing.assert_allclose(d.pvalue[1], 2 * min(law.cdf(3.0), law.sf(3.0)))
    with pytest.raises(ValueError, match="alternative"):
        decide(law, 1.0, 0.05, "both")


def test_tail_pair_judges_each_tail_on_its_own_statistic():
    from course.distributions import TailPair
    from course.results import Law, TestResult

    pair = TailPair(stats.norm(-1), stats.norm(1))
    assert isinstance(pair, Law)
    r = TestResult.from_null("pair", (-1.5, 3.5), pair, 0.05, "two-sided")
    assert r.reject and r.critical_value == pytest.approx((-1 - 1.959964, 1 + 1.959964), rel=1e-6)
    assert r.pvalue == pytest.approx(2 * stats.norm(1).sf(3.5))
    assert r.power(pair) == pytest.approx(0.05)
    with pytest.raises(NotImplementedError, match="joint sampler"):
        pair.rvs(3)


def test_frozen_distribution_scipy_methods():
    law = stats.chi2(4)

    class Chi2(FrozenDistribution):
        def _cdf(self, x):
            return law.cdf(x)

        def _sf(self, x):
            return law.sf(x)

        def _rvs(self, size, rng):
            return law.rvs(size, random_state=rng)

    mine = Chi2()
    assert mine.support() == (0.0, np.inf)
    assert mine.median() == pytest.approx(law.median(), rel=1e-10)
    assert mine.logsf(30.0) == pytest.approx(law.logsf(30.0), rel=1e-8)
    assert mine.logcdf(1.0) == pytest.approx(law.logcdf(1.0), rel=1e-8)
    assert mine.expect(lambda x: x**2) == pytest.approx(law.expect(lambda x: x**2), rel=1e-5)
    assert mine.expect(lb=2.0, ub=6.0, conditional=True) == pytest.approx(
        law.expect(lb=2.0, ub=6.0, conditional=True), rel=1e-5
    )
    # quantiles are remembered: the same object, no second root search
    assert mine.isf(0.05) == mine.isf(0.05) == pytest.approx(law.isf(0.05), rel=1e-10)


def test_linalg_home_of_least_squares_and_rank():
    rng = np.random.default_rng(3)
    A = rng.standard_normal((20, 3))
    b = rng.standard_normal((20, 2))
    sol = cl.qr_solve(A, b)
    np.testing.assert_allclose(sol.x, np.linalg.lstsq(A, b, rcond=None)[0], rtol=1e-12)
    np.testing.assert_allclose(sol.R_inv @ sol.R_inv.T, np.linalg.inv(A.T @ A), rtol=1e-10)
    assert cl.qr_solve(A, b[:, 0], full=True).Q.shape == (20, 20)
    deficient = np.column_stack([A, A[:, 0] + A[:, 1]])
    assert cl.matrix_rank(deficient) == 3 == np.linalg.matrix_rank(deficient)
    mn = cl.lstsq_min_norm(deficient, b[:, 0])
    np.testing.assert_allclose(mn.x, np.linalg.pinv(deficient) @ b[:, 0], atol=1e-12)
    assert mn.rank == 3 and cl.column_rank_deficiency(deficient) in ([0], [1], [3])


def test_stacked_cholesky_and_whitening():
    rng = np.random.default_rng(4)
    B = rng.standard_normal((5, 3, 3))
    S = B @ np.swapaxes(B, -1, -2) + np.eye(3)
    v = rng.standard_normal((5, 3))
    L = cl.cholesky_factor(S)
    expected = np.einsum("ki,kij,kj->k", v, np.linalg.inv(S), v)
    np.testing.assert_allclose(cl.whitened_squared_norms(L, v), expected, rtol=1e-10)
    shared = np.broadcast_to(S[0], (7, 3, 3))  # a broadcast view is factored once
    assert cl.cholesky_factor(shared).shape == (1, 3, 3)
    with pytest.raises(LinAlgError, match="S is not positive definite"):
        cl.cholesky_factor(-S)
    with pytest.raises(ValueError, match="not symmetric"):
        cl.cholesky_factor(S + np.triu(np.ones(3), 1))
    m = cl.readonly(np.zeros(3))
    with pytest.raises(ValueError):
        m[0] = 1.0


def test_version_is_written_once_and_shown_by_the_command(capsys):
    import importlib.metadata

    import course
    from course import cli

    assert importlib.metadata.version("residual-validation-course") == course.__version__
    with pytest.raises(SystemExit) as stop:
        cli.main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"course {course.__version__}"


def test_package_data_comes_from_importlib_resources():
    from importlib import resources

    from course import lsq

    text = resources.files("course").joinpath("data", "sea_level_mude", "Dataset_0.txt").read_text()
    t, y = lsq.load_sea_level(0)
    assert y.size == len(text.split()) == t.size == 20


def test_named_results_unpack_as_tuples():
    from course import filters, mismatched, nis

    eps = np.random.default_rng(0).standard_normal((30, 2))
    law_min, law_max = nis.nis_matrix_test(eps, np.eye(2)).null  # a pair of laws
    assert law_min.which == "min" and law_max.which == "max"
    lo, hi = nis.nis_critical_values(2, 30)
    assert (lo, hi) == tuple(nis.nis_critical_values(2, 30))
    x, P = filters.kf_predict([1.0], [[1.0]], [[2.0]], [[0.5]])
    assert x[0] == 2.0 and P[0, 0] == 4.5
    m0 = filters.LinearModel([[0.5]], [[1.0]], [[1.0]], [[1.0]])
    moments = mismatched.residual_moments(m0, m0, 3)
    lam, V = mismatched.principal_directions(moments, 0)
    s, left, right = mismatched.principal_directions(moments, 0, 1)
    assert lam.shape == s.shape == (1,) and V.shape == left.shape == right.shape == (1, 1)
