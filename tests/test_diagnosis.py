"""Tests of course.diagnosis: decision structures, prediction-error,
parameter-estimate and likelihood test quantities, thresholds and power.

Closed forms are checked against brute-force optimisation or independent
dense computations; thresholds against seeded Monte Carlo with binomial
bands at a 1e-4 miss level, so the tests are meaningful and not flaky.
"""

import itertools

import numpy as np
import pytest
from conftest import assert_rate, binomial_band
from numpy.linalg import LinAlgError
from scipy import optimize, stats

from course import chi2
from course import diagnosis as dg
from course.results import TestResult

LECTURE_TABLE = """
       NF F1 F2 F3
    T1  0  0  X  X
    T2  0  X  0  X
    T3  0  X  X  0
"""
MODES = {"NF": (), "F1": (0,), "F2": (1,), "F3": (2,)}
TESTS = [(0,), (1,), (2,)]
NOMINAL = np.ones(3)


@pytest.fixture
def structure():
    return dg.DecisionStructure.from_text(LECTURE_TABLE)


@pytest.fixture
def signals():
    rng = np.random.default_rng(20240501)
    N = 30
    t = np.arange(N)
    U = np.column_stack([np.sin(0.3 * t) + 1.5, np.cos(0.17 * t), rng.standard_normal(N)])
    return U


# ---------------------------------------------------------------------------
# decision structures and diagnoses
# ---------------------------------------------------------------------------
def test_structure_parses_and_prints(structure):
    assert structure.tests == ("T1", "T2", "T3")
    assert structure.modes == ("NF", "F1", "F2", "F3")
    expected = np.array([[0, 0, 1, 1], [0, 1, 0, 1], [0, 1, 1, 0]], dtype=bool)
    np.testing.assert_array_equal(structure.sensitivity, expected)
    assert str(structure) == (
        "    NF  F1  F2  F3\nT1   0   0   X   X\nT2   0   X   0   X\nT3   0   X   X   0"
    )
    assert repr(structure).startswith("DecisionStructure(\n")
    html = structure._repr_html_()
    assert html.count("<tr>") == 4 and "<th style='text-align:center'>F3</th>" in html
    assert structure == dg.DecisionStructure(
        expected.astype(int)
    )  # default names NF, F1.. and T1..
    with pytest.raises(ValueError):
        structure.sensitivity[0, 0] = True  # read-only


def test_structure_hypotheses(structure):
    h = structure.hypotheses("T1")
    assert h.null == ("NF", "F1") and h.alternative == ("F2", "F3")
    assert str(h) == "T1: H0: Fp in {NF, F1}  vs  H1: Fp in {F2, F3}"
    assert structure.row("T3") == {"NF": "0", "F1": "X", "F2": "X", "F3": "0"}


def test_structure_rejects_bad_input():
    with pytest.raises(ValueError, match="entry"):
        dg.DecisionStructure([["0", "Y"]])
    with pytest.raises(ValueError, match="row 1"):
        dg.DecisionStructure([[0, 1], [1]])
    with pytest.raises(ValueError, match="unique"):
        dg.DecisionStructure([[0, 1]], modes=["F1", "F1"])
    with pytest.raises(ValueError, match="entries"):
        dg.DecisionStructure.from_text("NF F1\nT1 0")
    with pytest.raises(ValueError, match="unknown test"):
        dg.DecisionStructure([[0, 1]]).hypotheses("T9")
    with pytest.raises(ValueError, match="2-D table"):
        dg.DecisionStructure([0, 1])
    assert dg.DecisionStructure([[0, 1], [1, 0]]).row_index("T2") == 1


def test_isolability_of_lecture_structure(structure):
    iso = structure.isolability()
    # every fault isolable from every other fault and from NF; NF from nothing.
    expected = np.array([[0, 0, 0, 0], [1, 0, 1, 1], [1, 1, 0, 1], [1, 1, 1, 0]], dtype=bool)
    np.testing.assert_array_equal(iso, expected)


@pytest.mark.parametrize(
    "alarms, expected",
    [
        ((0, 0, 0), ("NF", "F1", "F2", "F3")),
        ((1, 0, 0), ("F2", "F3")),
        ((0, 1, 0), ("F1", "F3")),
        ((0, 0, 1), ("F1", "F2")),
        ((0, 1, 1), ("F1",)),
        ((1, 0, 1), ("F2",)),
        ((1, 1, 0), ("F3",)),
        ((1, 1, 1), ()),
    ],
)
def test_diagnoses_single_fault(structure, alarms, expected):
    assert dg.diagnoses(structure, [bool(a) for a in alarms]) == expected
    names = [t for t, a in zip(structure.tests, alarms) if a]
    assert dg.diagnoses(structure, names) == expected
    assert dg.diagnoses(structure, dict(zip(structure.tests, alarms))) == expected


def test_diagnoses_accepts_test_results_and_exoneration(structure):
    def result(reject):
        # a consistent result (TestResult refuses a decision its statistic contradicts)
        return TestResult.from_null("t", 9.0 if reject else 1.0, stats.chi2(1), 0.05)

    assert dg.diagnoses(structure, [result(True), result(False), result(False)]) == ("F2", "F3")
    # With exoneration silent tests clear their X-modes: a lone T1 alarm fits no mode
    # (F2 would also trip T3, F3 would also trip T2), while T2 + T3 still give F1.
    assert dg.diagnoses(structure, [True, False, False], exoneration=True) == ()
    assert dg.diagnoses(structure, [False, True, True], exoneration=True) == ("F1",)
    assert dg.diagnoses(structure, [False, False, False], exoneration=True) == ("NF",)
    with pytest.raises(ValueError, match="3 tests"):
        dg.diagnoses(structure, [True, False])


def test_diagnosis_matrix_matches_loop(structure):
    rng = np.random.default_rng(1)
    random = dg.DecisionStructure(rng.random((5, 6)) < 0.5)
    for s in (structure, random):
        patterns = np.array(list(itertools.product([False, True], repeat=len(s.tests))))
        D = dg.diagnosis_matrix(s, patterns)
        for row, pattern in zip(D, patterns):
            # direct definition: mode j survives when every alarmed test has an X for j
            direct = [
                all(s.sensitivity[k, j] for k in np.flatnonzero(pattern))
                for j in range(len(s.modes))
            ]
            assert list(row) == direct
            assert tuple(np.array(s.modes)[row]) == dg.diagnoses(s, pattern)


def test_multiple_fault_diagnoses_are_minimal_hitting_sets(structure):
    assert dg.multiple_fault_diagnoses(structure, []) == [()]
    assert dg.multiple_fault_diagnoses(structure, ["T2", "T3"]) == [("F1",), ("F2", "F3")]
    assert dg.multiple_fault_diagnoses(structure, ["T1", "T2", "T3"]) == [
        ("F1", "F2"),
        ("F1", "F3"),
        ("F2", "F3"),
    ]
    # brute force on a random structure: all consistent sets, then the minimal ones
    rng = np.random.default_rng(7)
    s = dg.DecisionStructure(rng.random((4, 5)) < 0.5, modes=["A", "B", "C", "D", "E"])
    for pattern in itertools.product([False, True], repeat=4):
        conflicts = [set(np.flatnonzero(s.sensitivity[k])) for k in np.flatnonzero(pattern)]
        consistent = [
            set(c)
            for r in range(6)
            for c in itertools.combinations(range(5), r)
            if all(set(c) & conf for conf in conflicts)
        ]
        minimal = [c for c in consistent if not any(o < c for o in consistent)]
        expected = sorted(tuple(s.modes[j] for j in sorted(c)) for c in minimal)
        got = dg.multiple_fault_diagnoses(s, list(pattern), no_fault=None)
        assert sorted(got) == expected


def test_linear_decision_structure_sees_parallel_signals(signals, structure):
    assert (
        dg.linear_decision_structure(signals, MODES, dict(zip(structure.tests, TESTS))) == structure
    )
    U = signals.copy()
    U[:, 1] = 2.0 * U[:, 0]  # U2 parallel to U1: T1 cannot see F2
    s = dg.linear_decision_structure(U, MODES, {"T1": (0,), "T2": (1,), "T3": (2,)})
    assert s.row("T1") == {"NF": "0", "F1": "0", "F2": "0", "F3": "X"}
    assert s.row("T2") == {"NF": "0", "F1": "0", "F2": "0", "F3": "X"}


# ---------------------------------------------------------------------------
# prediction errors
# ---------------------------------------------------------------------------
def brute_force_min(V, p, start=None):
    start = np.zeros(p) if start is None else start
    sol = optimize.minimize(
        V, start, method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-14, "maxiter": 40000}
    )
    return sol.fun, sol.x


def test_lecture_closed_form_for_theta1(signals):
    rng = np.random.default_rng(3)
    u1, u2, u3 = signals.T
    y = 1.7 * u1 + 1.3 * u2 + u3 + 0.1 * rng.standard_normal(u1.size)
    # the lecture's ratio of sums
    theta1 = np.sum((y - u2 - u3) * u1) / np.sum(u1**2)
    T_closed = np.sum((y - theta1 * u1 - u2 - u3) ** 2)
    fit = dg.prediction_error(y, signals, NOMINAL, free=[0])
    assert fit.theta[0] == pytest.approx(theta1, rel=1e-12)
    assert fit.statistic == pytest.approx(T_closed, rel=1e-12)
    T_brute, x = brute_force_min(lambda th: np.sum((y - th[0] * u1 - u2 - u3) ** 2), 1)
    assert fit.statistic == pytest.approx(T_brute, rel=1e-9)
    assert fit.theta[0] == pytest.approx(x[0], abs=1e-6)
    np.testing.assert_array_equal(fit.theta[1:], [1.0, 1.0])


def test_u1_identically_zero_every_theta1_gives_same_T(signals):
    rng = np.random.default_rng(4)
    U = signals.copy()
    U[:, 0] = 0.0
    y = U @ [5.0, 1.0, 1.0] + 0.2 * rng.standard_normal(U.shape[0])
    fit = dg.prediction_error(y, U, NOMINAL, free=[0])
    assert fit.rank == 0 and fit.dof == U.shape[0] and not fit.unique
    expected = np.sum((y - U[:, 1] - U[:, 2]) ** 2)
    for theta1 in (-3.0, 0.0, 1.0, 7.5):
        assert np.sum((y - theta1 * U[:, 0] - U[:, 1] - U[:, 2]) ** 2) == pytest.approx(expected)
    assert fit.statistic == pytest.approx(expected, rel=1e-12)
    assert fit.theta[0] == 0.0  # minimum-norm choice


def test_noise_free_T_is_zero_under_H0_and_geometric_under_F2(signals):
    u1, u2, _ = signals.T
    for theta1 in (-2.0, 0.5, 3.0):  # any theta in Theta_0 = {theta1 free, theta2 = theta3 = 1}
        y = signals @ [theta1, 1.0, 1.0]
        assert dg.prediction_error(y, signals, NOMINAL, [0]).statistic == pytest.approx(
            0.0, abs=1e-20
        )
    f = 1 - 1.8  # F2 with theta2 = 1.8
    y = signals @ [1.0, 1.8, 1.0]
    # distance from (1 - theta2) U2 to span(U1): Pythagoras
    geometric = f**2 * (u2 @ u2 - (u1 @ u2) ** 2 / (u1 @ u1))
    assert dg.prediction_error(y, signals, NOMINAL, [0]).statistic == pytest.approx(
        geometric, rel=1e-12
    )
    U = signals.copy()
    U[:, 1] = -0.5 * U[:, 0]
    y = U @ [1.0, 1.8, 1.0]
    assert dg.prediction_error(y, U, NOMINAL, [0]).statistic == pytest.approx(0.0, abs=1e-20)


def test_gain_and_bias_example_decouples_the_bias():
    rng = np.random.default_rng(5)
    N = 50
    u = np.linspace(-1, 2, N)
    U = np.column_stack([np.ones(N), u])  # theta = (b, g)
    y = 1.0 * u + 0.0 + 0.3 * rng.standard_normal(N)
    b_hat = np.mean(y - u)
    T_lecture = np.mean((y - u - b_hat) ** 2)  # the slide's 1/N form
    fit = dg.prediction_error(y, U, [0.0, 1.0], free=[0])
    assert fit.statistic / N == pytest.approx(T_lecture, rel=1e-12)
    assert fit.theta[0] == pytest.approx(b_hat, rel=1e-12)
    # a bias fault does not change T; a gain fault does
    assert dg.prediction_error(y + 4.0, U, [0.0, 1.0], [0]).statistic == pytest.approx(
        fit.statistic, rel=1e-10
    )
    assert dg.prediction_error(y + 0.5 * u, U, [0.0, 1.0], [0]).statistic > 2 * fit.statistic


def test_least_squares_residual_matches_brute_force_and_lstsq():
    rng = np.random.default_rng(6)
    Phi = rng.standard_normal((12, 3))
    y = rng.standard_normal(12)
    fit = dg.least_squares_residual(Phi, y)
    T_brute, x = brute_force_min(lambda th: np.sum((y - Phi @ th) ** 2), 3)
    assert fit.statistic == pytest.approx(T_brute, rel=1e-8)
    np.testing.assert_allclose(fit.theta, x, atol=1e-5)
    ref = np.linalg.lstsq(Phi, y, rcond=None)
    np.testing.assert_allclose(fit.theta, ref[0], rtol=1e-12)
    assert fit.statistic == pytest.approx(float(ref[1][0]), rel=1e-12)
    assert fit.rank == 3 and fit.dof == 9 and fit.unique
    # many records at once = one at a time
    Y = rng.standard_normal((4, 12))  # four records, as rows
    many = dg.least_squares_residual(Phi, Y)
    assert many.residual.shape == (4, 12) and many.theta.shape == (4, 3)
    for m in range(4):
        single = dg.least_squares_residual(Phi, Y[m])
        assert many.statistic[m] == pytest.approx(single.statistic, rel=1e-12)
        np.testing.assert_allclose(many.theta[m], single.theta, rtol=1e-12)


def test_rank_deficient_regressors_give_unique_residual():
    rng = np.random.default_rng(8)
    N = 15
    a, b = rng.standard_normal(N), rng.standard_normal(N)
    Phi = np.column_stack([a, b, a - 2 * b])  # third column dependent: rank 2
    y = rng.standard_normal(N)
    fit = dg.least_squares_residual(Phi, y)
    reduced = dg.least_squares_residual(Phi[:, :2], y)
    assert fit.rank == 2 and fit.dof == N - 2 and not fit.unique
    np.testing.assert_allclose(fit.residual, reduced.residual, atol=1e-12)
    # every minimiser (minimum-norm solution + a null-space vector) gives the same residual
    null = np.array([1.0, -2.0, -1.0])
    for c in (-3.0, 0.7, 10.0):
        np.testing.assert_allclose(y - Phi @ (fit.theta + c * null), fit.residual, atol=1e-10)
    # the minimum-norm solution is orthogonal to the null space
    assert abs(fit.theta @ null) < 1e-10
    # brute force agrees on T; the normal equations are singular
    T_brute, _ = brute_force_min(lambda th: np.sum((y - Phi @ th) ** 2), 3)
    assert fit.statistic == pytest.approx(T_brute, rel=1e-7)
    assert np.linalg.matrix_rank(Phi.T @ Phi) == 2


def test_rank_deficient_threshold_uses_N_minus_rank():
    """Calibration of the chi2(N - rank) law when the regressors lack excitation."""
    rng = np.random.default_rng(9)
    N, M, alpha, sigma = 10, 20000, 0.05, 0.5
    a = rng.standard_normal(N)
    U = np.column_stack([a, 3 * a, rng.standard_normal(N)])  # theta1, theta2 not separable
    Y = dg.simulate_regression_records(U, [1.0, 1.0, 1.0], sigma=sigma, n_records=M, rng=rng)
    fit = dg.prediction_error(Y, U, NOMINAL, free=[0, 1])
    assert fit.dof == N - 1
    J = chi2.residual_threshold(fit.dof, alpha, sigma=sigma)
    assert_rate(np.mean(fit.statistic > J), M, alpha)
    # the wrong dof (N - number of free parameters) would give a visibly wrong rate
    wrong = chi2.residual_threshold(N - 2, alpha, sigma=sigma)
    assert np.mean(fit.statistic > wrong) > binomial_band(M, alpha)[1]


def test_prediction_error_test_result_and_calibration(signals):
    rng = np.random.default_rng(10)
    sigma, alpha, M = 0.3, 0.05, 20000
    N = signals.shape[0]
    r = dg.prediction_error_test(
        signals @ NOMINAL + sigma * rng.standard_normal(N),
        signals,
        NOMINAL,
        [0],
        sigma=sigma,
        alpha=alpha,
        name="T1",
    )
    assert r.dof == N - 1 and r.alternative == "greater"
    assert r.critical_value == pytest.approx(sigma**2 * stats.chi2.isf(alpha, N - 1))
    assert r.pvalue == pytest.approx(stats.chi2.sf(r.statistic / sigma**2, N - 1))
    assert r.null.isf(alpha) == pytest.approx(r.critical_value)
    # false-alarm rate of all three tests under NF, and of T1 under F1 (decoupled)
    for mode, theta in (("NF", NOMINAL), ("F1", [2.5, 1, 1])):
        Y = dg.simulate_regression_records(signals, theta, sigma=sigma, n_records=M, rng=rng)
        stat = dg.linear_test_statistics(Y, signals, NOMINAL, TESTS)
        J = chi2.residual_threshold(N - 1, alpha, sigma=sigma)
        assert_rate(np.mean(stat[:, 0] > J), M, alpha)
        if mode == "NF":
            for k in (1, 2):
                assert_rate(np.mean(stat[:, k] > J), M, alpha)


def test_power_against_fault_size_matches_monte_carlo(signals):
    rng = np.random.default_rng(11)
    sigma, alpha, M = 0.5, 0.05, 20000
    N = signals.shape[0]
    for delta in (0.0, 0.15, 0.3):
        theta = np.array([1.0, 1.0 + delta, 1.0])  # F2
        p_theory = dg.prediction_error_power(signals, NOMINAL, [0], theta, sigma=sigma, alpha=alpha)
        Y = dg.simulate_regression_records(signals, theta, sigma=sigma, n_records=M, rng=rng)
        T = dg.prediction_error(Y, signals, NOMINAL, [0]).statistic
        assert_rate(np.mean(chi2.residual_threshold(N - 1, alpha, sigma=sigma) < T), M, p_theory)
    assert (
        dg.prediction_error_power(signals, NOMINAL, [0], [1, 1, 1], sigma=sigma, alpha=alpha)
        == alpha
    )
    # a fault in the decoupled parameter is invisible: power alpha at any size
    assert dg.prediction_error_power(
        signals, NOMINAL, [0], [9, 1, 1], sigma=sigma, alpha=alpha
    ) == pytest.approx(alpha)
    # vectorised over a curve and monotone in the fault size
    thetas = np.array([[1, 1 + d, 1] for d in np.linspace(0, 1, 6)])  # one per row
    curve = dg.prediction_error_power(signals, NOMINAL, [0], thetas, sigma=sigma, alpha=alpha)
    assert curve.shape == (6,) and np.all(np.diff(curve) > 0)


def test_fault_noncentrality_is_squared_distance():
    U = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    # residual of (0, 1, 1) * 2 off span{(1, 0, 1)}: (-1, 2, 1)... computed densely
    d = 2.0 * U[:, 1]
    P = np.outer(U[:, 0], U[:, 0]) / (U[:, 0] @ U[:, 0])
    expected = np.sum(((np.eye(3) - P) @ d) ** 2) / 0.25
    assert dg.fault_noncentrality(U, [1, 1], [0], [1, 3], sigma=0.5) == pytest.approx(expected)


def test_nonlinear_prediction_error_matches_linear_and_grid(signals):
    rng = np.random.default_rng(12)
    y = signals @ [1.4, 1.0, 1.0] + 0.1 * rng.standard_normal(signals.shape[0])
    lin = dg.prediction_error(y, signals, NOMINAL, [0])
    nl = dg.nonlinear_prediction_error(y, lambda th: signals @ th, NOMINAL, [0])
    assert nl.success and nl.statistic == pytest.approx(lin.statistic, rel=1e-9)
    assert nl.theta[0] == pytest.approx(lin.theta[0], rel=1e-7)
    # a nonlinear model: y = a exp(-b t), H0 leaves a free, b fixed at 0.5
    t = np.linspace(0, 4, 40)
    z = 2.0 * np.exp(-0.5 * t) + 0.05 * rng.standard_normal(t.size)
    fit = dg.nonlinear_prediction_error(
        z, lambda th: th[0] * np.exp(-th[1] * t), [1.0, 0.5], free=[0]
    )
    grid = np.linspace(1.5, 2.5, 200001)
    V = np.sum((z[None, :] - grid[:, None] * np.exp(-0.5 * t)[None, :]) ** 2, axis=1)
    assert fit.statistic == pytest.approx(V.min(), rel=1e-8)
    full = dg.nonlinear_prediction_error(
        z, lambda th: th[0] * np.exp(-th[1] * t), [1.0, 0.5], free=[0, 1]
    )
    T_brute, _ = brute_force_min(
        lambda th: np.sum((z - th[0] * np.exp(-th[1] * t)) ** 2), 2, np.array([1.0, 0.5])
    )
    assert full.statistic == pytest.approx(T_brute, rel=1e-7)
    # no free parameter: T = V(nominal)
    assert dg.nonlinear_prediction_error(
        z, lambda th: th[0] * np.exp(-th[1] * t), [2.0, 0.5]
    ).statistic == pytest.approx(np.sum((z - 2.0 * np.exp(-0.5 * t)) ** 2))

    # a prediction that is NaN where the fit starts: named, not scipy's "Residuals are not
    # finite" (free parameters) or a NaN statistic (none)
    def bad(th):
        return th[0] * np.exp(-th[1] * t) / (th[1] != 0.5)

    with np.errstate(divide="ignore", invalid="ignore"):
        for free in ([0], []):
            with pytest.raises(ValueError, match=r"predict returned NaN or inf at the \w+ theta"):
                dg.nonlinear_prediction_error(z, bad, [2.0, 0.5], free=free)
        # a non-finite trial point is scipy's to step back from: the fit still succeeds
        assert dg.nonlinear_prediction_error(z, bad, [2.0, 0.6], free=[0]).success


def test_bad_input_is_refused(signals):
    y = signals @ NOMINAL
    with pytest.raises(ValueError, match="NaN"):
        dg.prediction_error(np.where(np.arange(y.size) == 3, np.nan, y), signals, NOMINAL)
    with pytest.raises(ValueError, match="shape mismatch"):
        dg.prediction_error(y[:-1], signals, NOMINAL)
    with pytest.raises(ValueError, match="out of range"):
        dg.prediction_error(y, signals, NOMINAL, free=[3])
    with pytest.raises(ValueError, match="sigma"):
        dg.prediction_error_test(y, signals, NOMINAL, sigma=0.0)
    with pytest.raises(ValueError, match="alpha"):
        dg.prediction_error_test(y, signals, NOMINAL, sigma=1.0, alpha=1.5)
    with pytest.raises(ValueError, match="no redundancy"):
        dg.prediction_error_test(y[:3], signals[:3], NOMINAL, [0, 1, 2], sigma=1.0)
    with pytest.raises(ValueError, match=r"dof .* must be a positive integer"):
        chi2.residual_threshold(0, 0.05)
    for bad in ("a", None, 2.5, np.inf):
        with pytest.raises(ValueError, match=r"dof .* must be an integer"):
            chi2.residual_threshold(bad, 0.05)
    with pytest.raises(ValueError, match=r"n_records .* must be an integer"):
        dg.simulate_regression_records(
            signals, NOMINAL, sigma=1.0, n_records=2.5, rng=np.random.default_rng(0)
        )


# ---------------------------------------------------------------------------
# parameter estimates
# ---------------------------------------------------------------------------
def test_estimate_matches_brute_force_and_covariance(signals):
    rng = np.random.default_rng(16)
    sigma = 0.2
    y = signals @ [1.3, 0.6, 1.0] + sigma * rng.standard_normal(signals.shape[0])
    est = dg.estimate_parameters(y, signals, NOMINAL, [0, 1], sigma=sigma)
    u1, u2, u3 = signals.T
    _, x = brute_force_min(lambda th: np.sum((y - th[0] * u1 - th[1] * u2 - u3) ** 2), 2)
    np.testing.assert_allclose(est.theta[:2], x, atol=1e-6)
    assert est.theta[2] == 1.0
    Phi = signals[:, :2]
    np.testing.assert_allclose(est.covariance, sigma**2 * np.linalg.inv(Phi.T @ Phi), rtol=1e-10)
    with pytest.raises(LinAlgError, match="full column rank"):
        U = signals.copy()
        U[:, 1] = U[:, 0]
        dg.estimate_parameters(y, U, NOMINAL, [0, 1], sigma=sigma)


def test_parameter_estimate_test_calibration_and_isolation(signals):
    """T1 = |theta2_hat - 1|: calibrated under NF and F1 when theta1 is estimated too."""
    rng = np.random.default_rng(17)
    sigma, alpha, M = 0.3, 0.05, 20000
    for theta, estimate in (([1, 1, 1], [0, 1]), ([2.0, 1, 1], [0, 1])):
        Y = dg.simulate_regression_records(signals, theta, sigma=sigma, n_records=M, rng=rng)
        est = dg.estimate_parameters(Y, signals, NOMINAL, estimate, sigma=sigma)
        s = est.std[1]
        T = np.abs(est.theta[:, 1] - 1.0)
        assert_rate(np.mean(s * stats.norm.isf(alpha / 2) < T), M, alpha)
    # estimating theta2 alone lets the F1 fault leak into it: the power formula predicts the rate
    # (u2 correlated with u1, as signals of one process often are)
    U = signals.copy()
    U[:, 1] = 0.6 * U[:, 0] + U[:, 1]
    theta = np.array([1.4, 1.0, 1.0])
    Y = dg.simulate_regression_records(U, theta, sigma=sigma, n_records=M, rng=rng)
    est = dg.estimate_parameters(Y, U, NOMINAL, [1], sigma=sigma)
    rate = np.mean(np.abs(est.theta[:, 1] - 1) > est.std[0] * stats.norm.isf(alpha / 2))
    p = dg.parameter_estimate_power(U, NOMINAL, [1], 1, theta, sigma=sigma, alpha=alpha)
    assert p > 0.5  # a real leak: the isolation problem
    assert_rate(rate, M, p)
    assert dg.parameter_estimate_power(
        U, NOMINAL, [0, 1], 1, theta, sigma=sigma, alpha=alpha
    ) == pytest.approx(alpha)
    # and a genuine F2 fault of the same size is seen by the decoupled test with the formula's power
    theta = np.array([1.0, 1.3, 1.0])
    Y = dg.simulate_regression_records(U, theta, sigma=sigma, n_records=M, rng=rng)
    est = dg.estimate_parameters(Y, U, NOMINAL, [0, 1], sigma=sigma)
    rate = np.mean(np.abs(est.theta[:, 1] - 1) > est.std[1] * stats.norm.isf(alpha / 2))
    assert_rate(
        rate, M, dg.parameter_estimate_power(U, NOMINAL, [0, 1], 1, theta, sigma=sigma, alpha=alpha)
    )


def test_parameter_estimate_test_result(signals):
    r = dg.parameter_estimate_test(1.5, 0.04, 1.0, alpha=0.05)
    assert r.statistic == pytest.approx(0.5)
    assert r.critical_value == pytest.approx(0.2 * 1.959963984540054)
    assert r.pvalue == pytest.approx(2 * stats.norm.sf(2.5))
    assert r.reject
    # vector: Wald statistic against a dense computation
    C = np.array([[0.04, 0.01], [0.01, 0.09]])
    d = np.array([0.3, -0.2])
    w = dg.parameter_estimate_test(1 + d, C, [1, 1])
    assert w.statistic == pytest.approx(d @ np.linalg.solve(C, d))
    assert w.dof == 2 and w.pvalue == pytest.approx(stats.chi2.sf(w.statistic, 2))
    # the regression wrapper gives the same number as estimate + test
    rng = np.random.default_rng(18)
    y = signals @ [1.1, 1.2, 1.0] + 0.2 * rng.standard_normal(signals.shape[0])
    r = dg.regression_parameter_test(y, signals, NOMINAL, [0, 1], 1, sigma=0.2)
    est = dg.estimate_parameters(y, signals, NOMINAL, [0, 1], sigma=0.2)
    assert r.statistic == pytest.approx(abs(est.theta[1] - 1))
    with pytest.raises(LinAlgError):
        dg.parameter_estimate_test([1, 1], [[1, 2], [2, 1]], [0, 0])
    with pytest.raises(ValueError, match="subset"):
        dg.regression_parameter_test(y, signals, NOMINAL, [0], 1, sigma=0.2)


# ---------------------------------------------------------------------------
# likelihood
# ---------------------------------------------------------------------------
def test_normal_likelihood_lecture_examples():
    grid = np.linspace(-2, 10, 1201)
    L1 = dg.normal_likelihood(grid, 2.0)
    np.testing.assert_allclose(L1, stats.norm.pdf(2.0, grid, 1.0), rtol=1e-12)
    assert grid[np.argmax(L1)] == pytest.approx(2.0)
    L2 = dg.normal_likelihood(grid, [3.0, 5.0])
    np.testing.assert_allclose(
        L2, stats.norm.pdf(3.0, grid) * stats.norm.pdf(5.0, grid), rtol=1e-12
    )
    assert grid[np.argmax(L2)] == pytest.approx(4.0)
    assert dg.normal_likelihood(4.0, [3.0, 5.0]) == pytest.approx(np.exp(-1) / (2 * np.pi))
    ml = dg.maximum_likelihood(lambda th: dg.normal_log_likelihood(th[0], [3.0, 5.0]), [0.0])
    assert ml.theta[0] == pytest.approx(4.0, abs=1e-6)
    assert ml.log_likelihood == pytest.approx(-1 - np.log(2 * np.pi))


def test_maximum_likelihood_against_closed_form():
    rng = np.random.default_rng(19)
    z = rng.normal(3.0, 2.0, 200)

    def loglik(th):  # (mean, log sigma)
        return float(np.sum(stats.norm.logpdf(z, th[0], np.exp(th[1]))))

    ml = dg.maximum_likelihood(loglik, [0.0, 0.0])
    assert ml.theta[0] == pytest.approx(z.mean(), abs=1e-5)
    assert np.exp(ml.theta[1]) == pytest.approx(z.std(), rel=1e-5)  # the ML variance divides by N
    fixed = dg.maximum_likelihood(loglik, [0.0, np.log(2.0)], free=[0])
    assert fixed.theta[1] == np.log(2.0) and fixed.theta[0] == pytest.approx(z.mean(), abs=1e-5)


def test_likelihood_test_equals_prediction_error_test(signals):
    rng = np.random.default_rng(20)
    sigma = 0.3
    for theta in ([1, 1, 1], [1, 1.25, 1], [1, 2, 1]):
        y = signals @ theta + sigma * rng.standard_normal(signals.shape[0])
        lt = dg.likelihood_test(y, signals, NOMINAL, [0], sigma=sigma)
        pe = dg.prediction_error_test(y, signals, NOMINAL, [0], sigma=sigma)
        assert lt.alternative == "less" and lt.reject == pe.reject
        assert lt.pvalue == pytest.approx(pe.pvalue, rel=1e-9)
        fit = dg.prediction_error(y, signals, NOMINAL, [0])
        direct = np.sum(stats.norm.logpdf(y, signals @ fit.theta, sigma))
        assert lt.statistic == pytest.approx(direct, rel=1e-12)
    law = lt.null
    q = np.array([0.01, 0.3, 0.9])
    np.testing.assert_allclose(law.cdf(law.ppf(q)), q, rtol=1e-10)
    np.testing.assert_allclose(law.sf(law.isf(q)), q, rtol=1e-10)
    draws = law.rvs(size=20000, rng=np.random.default_rng(1))
    assert_rate(np.mean(draws < law.ppf(0.05)), 20000, 0.05)


def test_glr_general_equals_exact_linear_and_is_calibrated(signals):
    rng = np.random.default_rng(21)
    sigma, alpha, M = 0.3, 0.05, 20000
    y = signals @ [1.2, 1.1, 1.0] + sigma * rng.standard_normal(signals.shape[0])
    exact = dg.linear_glr_test(y, signals, NOMINAL, [0], sigma=sigma, alpha=alpha)
    general = dg.glr_test(
        lambda th: float(np.sum(stats.norm.logpdf(y, signals @ th, sigma))),
        NOMINAL,
        [0],
        alpha=alpha,
    )
    assert exact.dof == general.dof == 2
    assert general.statistic == pytest.approx(exact.statistic, rel=1e-6, abs=1e-8)
    # exact chi2(2) calibration of (T0 - T1)/sigma^2 under H0 (here F1: theta1 free)
    Y = dg.simulate_regression_records(signals, [3.0, 1, 1], sigma=sigma, n_records=M, rng=rng)
    T0 = dg.prediction_error(Y, signals, NOMINAL, [0]).statistic
    T1 = dg.prediction_error(Y, signals, NOMINAL, [0, 1, 2]).statistic
    assert_rate(np.mean((T0 - T1) / sigma**2 > exact.critical_value), M, alpha)


def test_glr_wilks_for_exponential_rate():
    """A non-Gaussian model: closed form vs optimiser, and Wilks' chi2(1) in a large sample."""
    rng = np.random.default_rng(22)
    z = rng.exponential(1.0, 100)

    def loglik(th):  # rate exp(th) keeps it positive
        lam = np.exp(th[0])
        return float(z.size * np.log(lam) - lam * z.sum())

    r = dg.glr_test(loglik, [0.0], [], alpha=0.05)
    zbar = z.mean()
    assert r.statistic == pytest.approx(2 * z.size * (zbar - 1 - np.log(zbar)), rel=1e-6, abs=1e-9)
    assert r.dof == 1 and r.details["calibration"] == "Wilks (asymptotic)"
    M, N = 10000, 200
    zbar = rng.exponential(1.0, (M, N)).mean(axis=1)
    glr = 2 * N * (zbar - 1 - np.log(zbar))
    assert_rate(np.mean(glr > r.critical_value), M, 0.05)


def test_neyman_pearson_threshold_and_power():
    rng = np.random.default_rng(23)
    z = np.array([3.0, 5.0])
    r = dg.neyman_pearson_test(z, 0.0, 1.0)
    direct = np.sum(stats.norm.logpdf(z, 1.0)) - np.sum(stats.norm.logpdf(z, 0.0))
    assert r.statistic == pytest.approx(direct)
    d = np.sqrt(2.0)
    assert r.details["power"] == pytest.approx(stats.norm.sf(stats.norm.isf(0.05) - d))
    M, N, alpha = 20000, 4, 0.05
    for theta, p in ((0.0, alpha), (0.8, None)):
        Z = rng.normal(theta, 1.0, (M, N))
        res = [dg.neyman_pearson_test(Z[m], 0.0, 0.8, alpha=alpha) for m in range(200)]
        crit = res[0].critical_value
        logl = (np.sum(Z**2, axis=1) - np.sum((Z - 0.8) ** 2, axis=1)) / 2
        np.testing.assert_allclose([x.statistic for x in res], logl[:200], rtol=1e-12)
        assert_rate(np.mean(logl > crit), M, alpha if p is not None else res[0].details["power"])
    with pytest.raises(ValueError, match="cannot be told apart"):
        dg.neyman_pearson_test(z, 1.0, 1.0)


def test_mode_log_likelihoods_and_bayes_ranking(signals):
    rng = np.random.default_rng(24)
    sigma = 0.3
    y = signals @ [1, 1.3, 1] + sigma * rng.standard_normal(signals.shape[0])
    ll = dg.mode_log_likelihoods(y, signals, NOMINAL, MODES, sigma=sigma)
    for mode, free in MODES.items():
        fit = dg.prediction_error(y, signals, NOMINAL, free)
        assert ll[mode] == pytest.approx(np.sum(stats.norm.logpdf(y, signals @ fit.theta, sigma)))
        assert ll[mode] >= ll["NF"] - 1e-9  # the maximised likelihood never prefers NF
    priors = {"NF": 0.97, "F1": 0.01, "F2": 0.01, "F3": 0.01}
    ranking = dg.bayes_ranking(ll, priors)
    w = {m: np.exp(ll[m]) * priors[m] for m in MODES}
    total = sum(w.values())
    for mode, post in ranking.as_dict().items():
        assert post == pytest.approx(w[mode] / total, rel=1e-9)
    assert ranking.modes[0] == "F2" and list(ranking.posterior) == sorted(
        ranking.posterior, reverse=True
    )
    assert "posterior" in ranking.to_text() and "<table>" in ranking._repr_html_()
    # marginal likelihood against a dense multivariate normal
    tau = 0.5
    ml = dg.mode_log_likelihoods(y, signals, NOMINAL, MODES, sigma=sigma, prior_std=tau)
    u2 = signals[:, 1]
    cov = sigma**2 * np.eye(y.size) + tau**2 * np.outer(u2, u2)
    assert ml["F2"] == pytest.approx(
        stats.multivariate_normal(signals @ NOMINAL, cov).logpdf(y), rel=1e-10
    )
    assert ml["NF"] == pytest.approx(ll["NF"])
    # no fault: the marginal likelihood favours NF, the maximised one cannot
    y0 = signals @ NOMINAL + sigma * rng.standard_normal(signals.shape[0])
    flat = dict.fromkeys(MODES, 0.25)
    marg = dg.bayes_ranking(
        dg.mode_log_likelihoods(y0, signals, NOMINAL, MODES, sigma=sigma, prior_std=1.0), flat
    )
    assert marg.modes[0] == "NF"
    with pytest.raises(ValueError, match="sum to 1"):
        dg.bayes_ranking(ll, {"NF": 0.5, "F1": 0.1, "F2": 0.1, "F3": 0.1})
    with pytest.raises(ValueError, match="same modes"):
        dg.bayes_ranking(ll, {"NF": 1.0})
    with pytest.raises(ValueError, match="likelihood 0"):
        dg.bayes_ranking({"NF": -np.inf, "F1": -np.inf}, {"NF": 0.5, "F1": 0.5})
    # one impossible mode is fine: it gets posterior 0
    assert dg.bayes_ranking({"NF": -np.inf, "F1": -3.0}, {"NF": 0.5, "F1": 0.5}).as_dict() == {
        "F1": 1.0,
        "NF": 0.0,
    }


# ---------------------------------------------------------------------------
# Monte Carlo isolation
# ---------------------------------------------------------------------------
def test_isolation_monte_carlo(structure, signals):
    rng = np.random.default_rng(25)
    sigma, alpha, M = 0.3, 0.01, 4000
    N = signals.shape[0]
    size = 0.25
    thetas = {"NF": NOMINAL, "F1": [1 + size, 1, 1], "F2": [1, 1 + size, 1], "F3": [1, 1, 1 + size]}

    def simulate(mode, n, g):
        return dg.simulate_regression_records(
            signals, thetas[mode], sigma=sigma, n_records=n, rng=g
        )

    J = np.full(3, chi2.residual_threshold(N - 1, alpha, sigma=sigma))
    res = dg.isolation_monte_carlo(
        structure,
        simulate,
        lambda Y: dg.linear_test_statistics(Y, signals, NOMINAL, TESTS),
        J,
        n_records=M,
        rng=rng,
    )
    assert res.alarm_rate.shape == (4, 3) and res.membership.shape == (4, 4)
    for k in range(3):
        assert_rate(res.alarm_rate[0, k], M, alpha)
    for i, mode in enumerate(structure.modes):
        for k in range(3):
            p = dg.prediction_error_power(
                signals, NOMINAL, TESTS[k], thetas[mode], sigma=sigma, alpha=alpha
            )
            assert_rate(res.alarm_rate[i, k], M, p)
        # the true mode is never ruled out except through false alarms of the tests with a 0 for it
        assert res.membership[i, i] >= 1 - 3 * binomial_band(M, alpha)[1]
    assert "exact" in repr(res) and "<table>" in res._repr_html_()
    # the same seed gives the same table
    again = dg.isolation_monte_carlo(
        structure,
        simulate,
        lambda Y: dg.linear_test_statistics(Y, signals, NOMINAL, TESTS),
        J,
        n_records=M,
        rng=np.random.default_rng(25),
    )
    np.testing.assert_array_equal(again.membership, res.membership)


def test_plots_return_axes(structure, signals):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from course.plotting import diagnosis as pd

    fig, axes = plt.subplots(3, 3)
    ax = axes.ravel()
    assert pd.plot_residual_geometry(signals[:, 0], signals[:, 1], -0.8, ax=ax[0]) is ax[0]
    assert pd.plot_residual_geometry(signals[:, 0], 2 * signals[:, 0], -0.8, ax=ax[1]) is ax[1]
    assert pd.plot_density(0.0, 1.0, 2.0, ax=ax[2]) is ax[2]
    assert pd.plot_likelihood([3.0, 5.0], ax=ax[3]) is ax[3]
    assert (
        pd.plot_criterion(np.linspace(0, 2), np.linspace(0, 2) ** 2, ax=ax[4], minimiser=0.0)
        is ax[4]
    )
    assert (
        pd.plot_null_histogram(
            stats.chi2(3).rvs(500, random_state=np.random.default_rng(0)),
            stats.chi2(3),
            7.81,
            ax=ax[5],
        )
        is ax[5]
    )
    assert (
        pd.plot_power_curves(
            [0, 1], {"T1": [0.05, 0.9]}, {"T1": [0.06, 0.88]}, alpha=0.05, ax=ax[6]
        )
        is ax[6]
    )
    res = dg.IsolationResult(
        structure, structure.modes, np.zeros((4, 3)), np.eye(4), np.ones(4), 10
    )
    assert pd.plot_isolation(res, ax=ax[7]) is ax[7]
    assert pd.plot_windowed_statistic(np.arange(5), np.arange(5.0), 2.5, ax=ax[8]) is ax[8]
    plt.close(fig)
