"""Tests of course.lsq: the chapter's worked numbers, dense references, errors, Monte Carlo."""

import warnings

import numpy as np
import pytest
from numpy.linalg import LinAlgError
from scipy import stats

from course import chi2, lsq

TOL = 1e-10
T4 = np.arange(1.0, 5.0)
A_LINE = np.column_stack([np.ones(4), T4])  # t0 = 0
DAY1 = np.array([14.0, 20.0, 20.0, 24.0])
DAY2 = np.array([28.0, 20.0, 16.0, 36.0])


def dense_reference(A, y, Q):
    """Textbook formulas with explicit inverses: an independent check of the library."""
    Qi = np.linalg.inv(Q)
    Qxx = np.linalg.inv(A.T @ Qi @ A)
    x = Qxx @ A.T @ Qi @ y
    y_hat = A @ x
    e = y - y_hat
    Qyy_hat = A @ Qxx @ A.T
    Qee = Q - Qyy_hat
    N = Qi @ Qee @ Qi
    return {
        "x_hat": x,
        "y_hat": y_hat,
        "e_hat": e,
        "Qxx": Qxx,
        "Qyy_hat": Qyy_hat,
        "Qee": Qee,
        "redundancy_numbers": np.diag(Qee @ Qi),
        "T": e @ Qi @ e,
        "w": (Qi @ e) / np.sqrt(np.diag(N)),
        "N": N,
    }


def random_spd(rng, m, cond=30.0):
    Q, _ = np.linalg.qr(rng.standard_normal((m, m)))
    eig = np.geomspace(1.0, cond, m)
    return (Q * eig) @ Q.T


def correlated_problem(seed=3, m=9, n=3):
    rng = np.random.default_rng(seed)
    t = np.linspace(-1, 2, m)
    A = np.column_stack([t**k for k in range(n)])
    Qyy = random_spd(rng, m)
    y = A @ rng.normal(size=n) + np.linalg.cholesky(Qyy) @ rng.standard_normal(m)
    return A, y, Qyy


# ---------------------------------------------------------------------------
# chapter 10 worked numbers
# ---------------------------------------------------------------------------
def test_line_fit_day1_and_day2_numbers():
    f1, f2 = lsq.fit(A_LINE, DAY1), lsq.fit(A_LINE, DAY2)
    np.testing.assert_allclose(f1.x_hat, [12, 3], atol=TOL)
    np.testing.assert_allclose(f2.x_hat, [20, 2], atol=TOL)
    np.testing.assert_allclose(f1.e_hat, [-1, 2, -1, 0], atol=TOL)
    np.testing.assert_allclose(f2.e_hat, [6, -4, -10, 8], atol=TOL)
    np.testing.assert_allclose(f1.y_hat[1], 18.0, atol=TOL)  # ŷ2 = 18 while y2 = 20
    assert f1.redundancy == f2.redundancy == 2
    r1, r2 = lsq.overall_model_test(f1, 0.01), lsq.overall_model_test(f2, 0.01)
    assert r1.statistic == pytest.approx(6.0, abs=TOL)
    assert r2.statistic == pytest.approx(216.0, abs=TOL)
    assert round(r1.critical_value, 4) == 9.2103
    assert r1.critical_value == pytest.approx(stats.chi2.isf(0.01, 2), rel=1e-14)
    assert not r1.reject and r2.reject
    assert r1.dof == 2 and r1.pvalue == pytest.approx(stats.chi2.sf(6.0, 2), rel=1e-12)
    assert r1.null.dist.name == "chi2" and r1.null.args == (2,)
    assert r1.details["variance factor T/(m-n)"] == pytest.approx(3.0)


def test_quadratic_model_day2():
    A = np.column_stack([np.ones(4), T4, T4**2 / 2])
    f = lsq.fit(A, DAY2)
    assert (f.m, f.n, f.redundancy) == (4, 3, 1)
    np.testing.assert_allclose(f.x_hat, [55, -33, 14], atol=1e-9)
    np.testing.assert_allclose(f.e_hat, [-1, 3, -3, 1], atol=1e-9)
    r = lsq.overall_model_test(f, 0.01)
    # Much better than the line (216) but, with sigma = 1, still rejected at 1 %.
    assert r.statistic == pytest.approx(20.0, abs=1e-9)
    assert round(r.critical_value, 4) == 6.6349 and r.reject


def test_cubic_model_is_void():
    A = np.column_stack([T4**k for k in range(4)])
    f = lsq.fit(A, DAY2)
    assert f.redundancy == 0
    np.testing.assert_allclose(f.e_hat, 0, atol=1e-9)
    with pytest.raises(
        ValueError, match=r"overall model test is void: there is no redundancy \(m - n = 0"
    ):
        lsq.overall_model_test(f, 0.01)
    with pytest.raises(ValueError, match="w-test is void"):
        lsq.w_tests(f, 0.01)
    with pytest.raises(ValueError, match="no redundancy"):
        lsq.mdb(f)


def test_precision_of_fitted_value_and_confidence_interval_day1():
    f = lsq.fit(A_LINE, DAY1)
    assert f.sigma_y_hat[1] == pytest.approx(np.sqrt(0.3), rel=1e-12)
    assert round(float(f.sigma_y_hat[1]), 2) == 0.55
    y_new, half = lsq.confidence_band(f, A_LINE, level=0.95)
    np.testing.assert_allclose(y_new, [15, 18, 21, 24], atol=TOL)
    assert round(float(half[1]), 2) == 1.07
    assert half[1] == pytest.approx(stats.norm.isf(0.025) * np.sqrt(0.3), rel=1e-12)
    assert round(stats.norm.isf(0.025), 2) == 1.96  # the error-bar factor r_alpha


def test_sum_of_squares_minimum_is_6_at_12_3():
    from course.plotting.lsq import sum_of_squares_grid

    x1 = np.linspace(6, 18, 121)
    x2 = np.linspace(0, 6, 61)
    S = sum_of_squares_grid(A_LINE, DAY1, x1, x2)
    j, i = np.unravel_index(np.argmin(S), S.shape)
    assert (x1[i], x2[j]) == pytest.approx((12.0, 3.0))
    assert S.min() == pytest.approx(6.0, abs=TOL)


def test_threshold_m5_n2_alpha5():
    assert round(stats.chi2.isf(0.05, 5 - 2), 4) == 7.8147
    A = np.column_stack([np.ones(5), np.arange(-2.0, 3.0)])
    r = lsq.overall_model_test(lsq.fit(A, [25, 24, 27, 26, 28]), 0.05)
    assert round(r.critical_value, 4) == 7.8147 and r.dof == 3


def test_sea_level_exercise():
    A = np.column_stack([np.ones(5), np.arange(-2.0, 3.0)])
    f = lsq.fit(A, [25, 24, 27, 26, 28], np.eye(5))
    np.testing.assert_allclose(f.x_hat, [26, 0.8], atol=TOL)
    np.testing.assert_allclose(f.y_hat, [24.4, 25.2, 26.0, 26.8, 27.6], atol=TOL)
    np.testing.assert_allclose(f.e_hat, [0.6, -1.2, 1.0, -0.8, 0.4], atol=TOL)
    np.testing.assert_allclose(A.T @ A, [[5, 0], [0, 10]])
    r = lsq.overall_model_test(f, 0.1)
    assert r.statistic == pytest.approx(3.6, abs=TOL)
    assert round(r.critical_value, 4) == 6.2514 and not r.reject


def test_bridge_deck():
    l = np.array([-2.0, -1.0, 1.0, 2.0])
    d = np.array([1.0, 4.0, 3.0, 2.0])
    A_full = np.column_stack([l**2, l, np.ones(4)])
    np.testing.assert_array_equal(A_full, [[4, -2, 1], [1, -1, 1], [1, 1, 1], [4, 2, 1]])
    A = A_full[:, [0, 2]]  # maximum at l = 0, so x2 = 0
    np.testing.assert_array_equal(A.T @ A, [[34, 10], [10, 4]])
    f = lsq.fit(A, d)
    np.testing.assert_allclose(f.x_hat, [-2 / 3, 25 / 6], atol=TOL)
    np.testing.assert_allclose(f.Qxx, np.array([[4, -10], [-10, 34]]) / 36, atol=TOL)
    # Row form of the estimator: x̂ = (1/6) [[1, -1, -1, 1], [-1, 4, 4, -1]] d.
    np.testing.assert_allclose(
        f.Qxx @ A.T, np.array([[1, -1, -1, 1], [-1, 4, 4, -1]]) / 6, atol=TOL
    )


def test_repeated_measurements_T_over_m_minus_1_is_variance_ratio():
    rng = np.random.default_rng(10)
    sigma, m = 0.7, 12
    y = 5.0 + sigma * rng.standard_normal(m)
    f = lsq.fit(np.ones((m, 1)), y, sigma**2 * np.eye(m))
    assert f.x_hat[0] == pytest.approx(y.mean(), rel=1e-13)
    T = lsq.overall_model_test(f, 0.05).statistic
    assert T / (m - 1) == pytest.approx(np.var(y, ddof=1) / sigma**2, rel=1e-12)


def test_diagonal_qyy_T_is_sum_of_squared_standardised_residuals():
    rng = np.random.default_rng(11)
    m = 8
    A = np.column_stack([np.ones(m), np.arange(m)])
    sig = rng.uniform(0.5, 3.0, m)
    y = A @ [1.0, 2.0] + sig * rng.standard_normal(m)
    f = lsq.fit(A, y, np.diag(sig**2))
    assert f.squared_norm == pytest.approx(np.sum((f.e_hat / sig) ** 2), rel=1e-12)


# ---------------------------------------------------------------------------
# dense references: weighted and correlated
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["identity", "weighted", "correlated"])
def test_fit_matches_dense_reference(kind):
    A, y, Qyy = correlated_problem(seed=5)
    m = A.shape[0]
    if kind == "identity":
        Qyy = np.eye(m)
    elif kind == "weighted":
        Qyy = np.diag(np.linspace(0.2, 4.0, m))
    f = lsq.fit(A, y, None if kind == "identity" else Qyy)
    ref = dense_reference(A, y, Qyy)
    for name in ("x_hat", "y_hat", "e_hat", "Qxx", "Qyy_hat", "Qee", "redundancy_numbers"):
        np.testing.assert_allclose(getattr(f, name), ref[name], rtol=1e-9, atol=1e-11, err_msg=name)
    assert f.squared_norm == pytest.approx(ref["T"], rel=1e-10)
    assert np.sum(f.redundancy_numbers) == pytest.approx(f.redundancy, rel=1e-12)
    wt = lsq.w_tests(f, 0.05)
    np.testing.assert_allclose(wt.statistic, ref["w"], rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(wt.pvalue, 2 * stats.norm.sf(np.abs(ref["w"])), rtol=1e-9)
    assert wt.largest == int(np.argmax(np.abs(ref["w"])))
    np.testing.assert_array_equal(wt.reject, np.abs(ref["w"]) > stats.norm.isf(0.025))
    # mdb: sqrt(lambda0 / c_i^T Qyy^-1 Qee Qyy^-1 c_i)
    lam0 = chi2.noncentrality(0.001, 0.8)
    np.testing.assert_allclose(lsq.mdb(f), np.sqrt(lam0 / np.diag(ref["N"])), rtol=1e-9)


def test_w_equals_residual_over_its_std_for_diagonal_qyy():
    rng = np.random.default_rng(12)
    m = 10
    A = np.column_stack([np.ones(m), np.linspace(0, 1, m), np.linspace(0, 1, m) ** 2])
    sig = rng.uniform(0.5, 2.0, m)
    y = A @ [1, -1, 2] + sig * rng.standard_normal(m)
    f = lsq.fit(A, y, np.diag(sig**2))
    wt = lsq.w_tests(f, 0.01)
    np.testing.assert_allclose(wt.statistic, f.e_hat / f.sigma_e_hat, rtol=1e-10)
    assert wt.critical_value == pytest.approx(stats.norm.isf(0.005), rel=1e-14)
    assert wt.null.dist.name == "norm" and wt.alpha == 0.01
    # ...and then mdb = sigma_i sqrt(lambda0 / r_i)
    lam0 = chi2.noncentrality(0.001, 0.8)
    np.testing.assert_allclose(lsq.mdb(f), sig * np.sqrt(lam0 / f.redundancy_numbers), rtol=1e-10)


def test_w_test_per_observation_test_results():
    wt = lsq.w_tests(lsq.fit(A_LINE, DAY2), 0.01)
    tests = wt.tests()
    assert len(tests) == 4
    crit = stats.norm.isf(0.005)
    for i, t in enumerate(tests):
        assert t.alternative == "two-sided"
        assert t.critical_value == pytest.approx((-crit, crit))
        assert t.statistic == pytest.approx(wt.statistic[i]) and t.reject == wt.reject[i]
    # the largest |ê| (-10, obs 2) is not the largest |w|: the end point has less redundancy
    assert wt.rejected == [0, 1, 2, 3] and wt.largest == 3
    with pytest.raises(ValueError, match="observation index"):
        wt.test(4)


def test_untestable_observation_gets_nan_w_and_infinite_mdb():
    # The last observation alone determines the last parameter: no redundancy there.
    A = np.array([[1, 0], [1, 0], [1, 0], [0, 1]], dtype=float)
    f = lsq.fit(A, [1.0, 2.0, 4.0, 3.0])
    assert f.redundancy_numbers[3] == pytest.approx(0.0, abs=1e-12)
    wt = lsq.w_tests(f, 0.05)
    assert np.isnan(wt.statistic[3]) and not wt.testable[3] and not wt.reject[3]
    assert np.all(np.isfinite(wt.statistic[:3]))
    assert np.isinf(lsq.mdb(f)[3])
    with pytest.raises(ValueError, match="cannot be tested"):
        wt.test(3)
    assert len(wt.tests()) == 3


def test_confidence_band_matches_dense_formula():
    A, y, Qyy = correlated_problem(seed=8)
    f = lsq.fit(A, y, Qyy)
    t = np.linspace(-2, 3, 7)
    A_new = np.column_stack([t**k for k in range(3)])
    y_new, half = lsq.confidence_band(f, A_new, level=0.9)
    Qxx = np.linalg.inv(A.T @ np.linalg.inv(Qyy) @ A)
    np.testing.assert_allclose(y_new, A_new @ f.x_hat, rtol=1e-12)
    np.testing.assert_allclose(
        half, stats.norm.isf(0.05) * np.sqrt(np.diag(A_new @ Qxx @ A_new.T)), rtol=1e-9
    )
    with pytest.raises(ValueError, match=r"A_new must have shape \(k, n\) with n = 3"):
        lsq.confidence_band(f, A_new[:, :2])
    with pytest.raises(ValueError, match="level must lie strictly between 0 and 1"):
        lsq.confidence_band(f, A_new, level=95)
    # rows ~1e160: the half-width ~1e160 is representable, its square is not (it was inf)
    for c in (1e160, 1e-160):
        big = lsq.confidence_band(f, A_new * c, level=0.9)
        np.testing.assert_allclose(big.y_new_hat / c, y_new, rtol=1e-12)
        np.testing.assert_allclose(big.half_width / c, half, rtol=1e-12)


# ---------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------
def test_rank_deficient_A_names_the_column():
    A = np.column_stack([np.ones(4), T4, np.zeros(4)])
    with pytest.raises(LinAlgError, match=r"full column rank: column\(s\) \[2\]"):
        lsq.fit(A, DAY1)
    A = np.column_stack([np.ones(4), T4, 2 * T4 + 1])
    with pytest.raises(LinAlgError, match=r"column\(s\) \[[0-2]\] are linear combinations"):
        lsq.fit(A, DAY1)


@pytest.mark.parametrize(
    "A, y, Qyy, error, match",
    [
        (
            A_LINE,
            [1.0, 2.0, 3.0],
            None,
            ValueError,
            "shape mismatch: y has 3 observations but A has 4 rows",
        ),
        (A_LINE, [[1.0, 2.0, 3.0, 4.0]], None, ValueError, "y must be a 1-D vector"),
        (A_LINE[:, 0], DAY1, None, ValueError, "A must be 2-dimensional"),
        (
            A_LINE[:1],
            [1.0],
            None,
            ValueError,
            r"fewer rows than columns \(m = 1 observations, n = 2",
        ),
        (A_LINE, [14, np.nan, 20, 24], None, ValueError, "y contains NaN or inf"),
        (np.where(A_LINE == 3, np.inf, A_LINE), DAY1, None, ValueError, "A contains NaN or inf"),
        (A_LINE, DAY1, np.eye(3), ValueError, r"Qyy must have shape \(4, 4\)"),
        (
            A_LINE,
            DAY1,
            np.ones(3),
            ValueError,
            r"Qyy given as a 1-D array holds the variances of the m = 4 observations, got 3",
        ),
        (A_LINE, DAY1, [1.0, 0.0, 1.0, 1.0], ValueError, r"variances, .* Qyy\[1\] = 0.0"),
        (A_LINE, DAY1, np.triu(np.ones((4, 4))), ValueError, "Qyy is not symmetric"),
        (A_LINE, DAY1, np.diag([1.0, 1.0, -1.0, 1.0]), LinAlgError, "Qyy is not positive definite"),
        (A_LINE, DAY1, np.ones((4, 4)), LinAlgError, "Qyy is not positive definite"),
        (A_LINE, DAY1, np.diag([1.0, np.nan, 1.0, 1.0]), ValueError, "Qyy contains NaN or inf"),
        (
            A_LINE,
            DAY1,
            2.0,
            ValueError,
            r"got a scalar; for equal variances s2 pass s2 \* np.eye\(4\)",
        ),
        (A_LINE, None, None, ValueError, "y is None"),
        (A_LINE + 1j, DAY1, None, ValueError, "A is complex; pass real numbers"),
        (A_LINE, DAY1 + 0j, None, ValueError, "y is complex"),
    ],
)
def test_bad_input_errors(A, y, Qyy, error, match):
    with pytest.raises(error, match=match):
        lsq.fit(A, y, Qyy)


def test_alpha_and_type_validation():
    f = lsq.fit(A_LINE, DAY1)
    for bad in (0, 1, -0.1, 1.5, "x"):
        with pytest.raises(ValueError, match="alpha must"):
            lsq.overall_model_test(f, bad)
        with pytest.raises(ValueError, match="alpha must"):
            lsq.w_tests(f, bad)
    with pytest.raises(TypeError, match="fit must be a LeastSquaresFit"):
        lsq.overall_model_test((A_LINE, DAY1), 0.05)


def test_input_not_mutated_and_fit_read_only():
    A, y, Qyy = correlated_problem(seed=2)
    copies = [A.copy(), y.copy(), Qyy.copy()]
    f = lsq.fit(A, y, Qyy)
    for original, copy in zip((A, y, Qyy), copies):
        np.testing.assert_array_equal(original, copy)
    assert f.A is not A
    with pytest.raises(ValueError, match="read-only"):
        f.x_hat[0] = 1.0
    with pytest.raises(AttributeError):
        f.x_hat = np.zeros(3)


# ---------------------------------------------------------------------------
# data snooping
# ---------------------------------------------------------------------------
def test_data_snooping_finds_planted_outlier_with_original_numbering():
    rng = np.random.default_rng(20)
    m = 15
    t = np.arange(m, dtype=float)
    A = np.column_stack([np.ones(m), t])
    sigma = 0.5
    y = A @ [3.0, 0.4] + sigma * rng.standard_normal(m)
    y[9] += 12 * sigma
    res = lsq.data_snooping(lsq.fit(A, y, sigma**2 * np.eye(m)), alpha=0.001)
    assert res.removed == (9,)
    assert res.kept == tuple(i for i in range(m) if i != 9)
    assert res.stop_reason == "no observation rejected"
    assert len(res.rounds) == 2 and res.rounds[0].largest == 9 and res.rounds[0].reject[9]
    assert not res.rounds[-1].any_reject
    keep = np.array(res.kept)
    ref = lsq.fit(A[keep], y[keep], sigma**2 * np.eye(m - 1))
    np.testing.assert_allclose(res.fit.x_hat, ref.x_hat, rtol=1e-12)
    assert res.round_indices[1] == res.kept


def test_data_snooping_two_outliers_correlated_original_indices():
    A, _, Qyy = correlated_problem(seed=4, m=14, n=2)
    rng = np.random.default_rng(21)
    y = A @ [1.0, 2.0] + np.linalg.cholesky(Qyy) @ rng.standard_normal(14)
    y = y.copy()
    y[3] += 40.0
    y[11] -= 60.0
    res = lsq.data_snooping(lsq.fit(A, y, Qyy), alpha=0.001)
    assert sorted(res.removed) == [3, 11]
    assert res.removed[0] == res.round_indices[0][res.rounds[0].largest]
    # the second round's positions are shifted; its largest maps back to the original index
    second = res.rounds[1]
    assert res.round_indices[1][second.largest] == res.removed[1]
    assert len(res.round_indices[1]) == 13 and res.removed[0] not in res.round_indices[1]


def test_data_snooping_stops_when_no_redundancy_left_and_at_max_removals():
    A = np.column_stack([np.ones(3), np.arange(3.0)])
    res = lsq.data_snooping(lsq.fit(A, [0.0, 0.0, 100.0]), alpha=0.05)
    assert res.stop_reason == "no redundancy left"
    assert len(res.removed) == 1 and res.fit.redundancy == 0
    m = 10
    A = np.column_stack([np.ones(m), np.arange(m, dtype=float)])
    y = np.zeros(m)
    y[[2, 7]] = [50.0, -80.0]
    res = lsq.data_snooping(lsq.fit(A, y), alpha=0.01, max_removals=1)
    assert res.removed == (7,) and res.stop_reason == "max_removals reached"
    assert "removed [7]" in res.summary() and "np." not in repr(res) + res._repr_html_()
    for bad in (-1, 1.5, "a", True):
        with pytest.raises(
            ValueError, match=r"max_removals must be (a non-negative integer|an integer)"
        ):
            lsq.data_snooping(lsq.fit(A, y), max_removals=bad)


def test_sea_level_data_cases():
    t, y0 = lsq.load_sea_level(0)
    assert t.shape == y0.shape == (20,) and t[0] == 1 and t[-1] == 20
    assert y0[0] == pytest.approx(0.35408)
    A = np.column_stack([np.ones(20), t])
    Q = 4.0 * np.eye(20)  # stated standard deviation 2
    assert not lsq.overall_model_test(lsq.fit(A, y0, Q), 0.05).reject
    _, y1 = lsq.load_sea_level(1)
    assert lsq.overall_model_test(lsq.fit(A, y1, Q), 0.05).reject
    assert lsq.data_snooping(lsq.fit(A, y1, Q), alpha=0.05).removed == (4,)
    _, y2 = lsq.load_sea_level(2)
    assert lsq.overall_model_test(lsq.fit(A, y2, Q), 0.05).reject
    A2 = np.column_stack([A, t**2])
    assert not lsq.overall_model_test(lsq.fit(A2, y2, Q), 0.05).reject
    _, y3 = lsq.load_sea_level(3)
    assert lsq.overall_model_test(lsq.fit(A, y3, Q), 0.05).reject
    assert not lsq.overall_model_test(lsq.fit(A, y3, 2 * Q), 0.05).reject
    for bad in (4, 1.5, "1", True):
        with pytest.raises(ValueError, match="case must be 0, 1, 2 or 3"):
            lsq.load_sea_level(bad)
    np.testing.assert_array_equal(lsq.load_sea_level(np.int64(1))[1], y1)
    # the course's one integer rule: a whole float is an integer
    np.testing.assert_array_equal(lsq.load_sea_level(1.0)[1], y1)


# ---------------------------------------------------------------------------
# reliability: noncentrality and mdb
# ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "alpha, power, dof", [(0.001, 0.8, 1), (0.05, 0.5, 1), (0.2, 0.3, 1), (0.01, 0.9, 3)]
)
def test_noncentrality_achieves_power(alpha, power, dof):
    lam0 = chi2.noncentrality(alpha, power, dof)
    k = stats.chi2.isf(alpha, dof)
    assert stats.ncx2.sf(k, dof, lam0) == pytest.approx(power, abs=1e-10)
    if dof == 1:
        # two-sided w-test with mean shift sqrt(lambda0)
        z = stats.norm.isf(alpha / 2)
        exact = stats.norm.sf(z - np.sqrt(lam0)) + stats.norm.cdf(-z - np.sqrt(lam0))
        assert exact == pytest.approx(power, abs=1e-10)
        # the one-tail approximation (z_{alpha/2} + z_{1-power})^2 ignores the far tail,
        # so it overstates lambda0, by little when alpha is small
        approx = (z + stats.norm.ppf(power)) ** 2
        assert lam0 < approx
        if alpha <= 0.01:
            assert lam0 == pytest.approx(approx, rel=1e-6)


def test_noncentrality_known_value_and_monotonicity():
    assert round(chi2.noncentrality(0.001, 0.80), 2) == 17.07  # Baarda's B-method value
    assert chi2.noncentrality(0.001, 0.9) > chi2.noncentrality(0.001, 0.8)
    assert chi2.noncentrality(0.01, 0.8) < chi2.noncentrality(0.001, 0.8)
    assert chi2.noncentrality(0.001, 0.8, 2) > chi2.noncentrality(0.001, 0.8, 1)
    with pytest.raises(ValueError, match=r"power .* must exceed alpha"):
        chi2.noncentrality(0.1, 0.05)
    for bad in (0, 1.5, "a", True, np.inf):
        with pytest.raises(ValueError, match=r"dof must be (a positive integer|an integer), got"):
            chi2.noncentrality(0.05, 0.8, bad)
    assert chi2.noncentrality(0.05, 0.8, np.int64(2)) == chi2.noncentrality(0.05, 0.8, 2.0)
    with pytest.raises(ValueError, match="power must lie strictly between 0 and 1"):
        chi2.noncentrality(0.05, 1.0)


def test_bias_of_size_mdb_is_detected_with_the_stated_power():
    A, _, Qyy = correlated_problem(seed=6, m=8, n=2)
    f0 = lsq.fit(A, np.zeros(8), Qyy)
    alpha, power, i = 0.01, 0.8, 2
    bias = lsq.mdb(f0, alpha=alpha, power=power)[i]
    rng = np.random.default_rng(30)
    L = np.linalg.cholesky(Qyy)
    N = 500
    hits = 0
    for _ in range(N):
        y = A @ [1.0, -1.0] + L @ rng.standard_normal(8)
        y[i] += bias
        wt = lsq.w_tests(lsq.fit(A, y, Qyy), alpha)
        hits += bool(wt.reject[i])
    low, high = stats.binom.interval(1 - 1e-4, N, power)
    assert low <= hits <= high


# ---------------------------------------------------------------------------
# Monte Carlo: false-alarm rates under H0
# ---------------------------------------------------------------------------
def test_omt_and_w_test_reject_at_rate_alpha_under_h0():
    A, _, Qyy = correlated_problem(seed=7, m=7, n=2)
    L = np.linalg.cholesky(Qyy)
    rng = np.random.default_rng(40)
    alpha, N = 0.05, 1000
    omt_rejects = 0
    w_rejects = np.zeros(7, dtype=int)
    T = np.empty(N)
    for k in range(N):
        y = A @ [2.0, 0.5] + L @ rng.standard_normal(7)
        f = lsq.fit(A, y, Qyy)
        r = lsq.overall_model_test(f, alpha)
        omt_rejects += r.reject
        T[k] = r.statistic
        w_rejects += lsq.w_tests(f, alpha).reject
    low, high = stats.binom.interval(1 - 1e-4, N, alpha)
    assert low <= omt_rejects <= high
    for i in (0, 3, 6):
        assert low <= w_rejects[i] <= high
    # the whole distribution, not only one tail: T ~ chi2(m - n)
    assert stats.kstest(T, stats.chi2(5).cdf).pvalue > 1e-4
    # a wrong law is detected by the same check (so the check can fail)
    assert stats.kstest(T, stats.chi2(4).cdf).pvalue < 1e-4


# ---------------------------------------------------------------------------
# presentation
# ---------------------------------------------------------------------------
def test_reprs_are_short_deterministic_and_plain():
    f = lsq.fit(A_LINE, DAY1)
    assert repr(f) == "LeastSquaresFit(m=4, n=2, redundancy=2, x_hat=[12, 3], squared_norm=6)"
    wt = lsq.w_tests(f, 0.01)
    assert repr(wt) == (
        "WTestResult(m=4, alpha=0.01, critical_value=2.5758, largest=1, w_largest=2.3905, rejected=[])"
    )
    assert wt.summary().endswith("rejected: none")
    r = lsq.overall_model_test(f, 0.01)
    assert repr(r) == (
        "TestResult('overall model test', statistic=6, dof=2, alpha=0.01, critical_value=9.2103, "
        "pvalue=0.04979, reject=False, null=chi2(2))"
    )
    big = lsq.fit(
        np.column_stack(
            [np.ones(20), np.arange(20.0)] + [np.arange(20.0) ** k for k in range(2, 8)]
        ),
        np.arange(20.0) ** 0.5,
    )
    assert "(8 values)" in repr(big)
    for text in (
        repr(f),
        f._repr_html_(),
        repr(wt),
        wt._repr_html_(),
        wt.summary(),
        repr(r),
        r.summary(),
        r._repr_html_(),
        repr(wt.test(0)),
    ):
        assert "np." not in text and "0x" not in text


# ---------------------------------------------------------------------------
# plotting helpers
# ---------------------------------------------------------------------------
def test_plot_helpers_return_their_axes():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    from course.plotting import lsq as plots

    f1 = lsq.fit(A_LINE, DAY1)
    fig, ax = plt.subplots()
    try:
        assert plots.plot_line_fit(T4, DAY1, f1, ax=ax) is ax
        assert plots.plot_error_bars(T4, DAY1, 1.0, ax=ax) is ax
        assert plots.plot_confidence_band(T4, f1, ax=ax) is ax
        lower = ax.lines[-2].get_ydata()  # the dashed lower edge of the band
        assert np.all(lower < ax.lines[-3].get_ydata())
        assert (
            plots.plot_sum_of_squares(
                A_LINE,
                DAY1,
                np.linspace(6, 18, 13),
                np.linspace(0, 6, 7),
                log10=True,
                ax=ax,
                minimum=f1.x_hat,
            )
            is ax
        )
        assert (
            plots.plot_chi2_histogram(
                stats.chi2(2).rvs(200, random_state=np.random.default_rng(1)), 2, ax=ax, alpha=0.05
            )
            is ax
        )
        assert plots.plot_w_tests(lsq.w_tests(lsq.fit(A_LINE, DAY2), 0.01), ax=ax) is ax
        quad = lsq.fit(np.column_stack([A_LINE, T4**2 / 2]), DAY2)
        with pytest.raises(ValueError, match="pass design="):
            plots.plot_line_fit(T4, DAY2, quad, ax=ax)
        design = lambda tt: plots.line_design(tt, degree=2)  # noqa: E731
        np.testing.assert_array_equal(design(T4), quad.A)
        assert plots.plot_line_fit(T4, DAY2, quad, design=design, ax=ax) is ax
        new = plots.plot_w_tests(lsq.w_tests(f1, 0.01))
        assert new is not ax and new.figure is not fig
        plt.close(new.figure)
    finally:
        plt.close(fig)


# ---------------------------------------------------------------------------
# input forms for network sizes: 1-D variances and scipy.sparse
# ---------------------------------------------------------------------------
def _assert_same_fit(f, ref, rtol=1e-10, atol=1e-12):
    for name in ("x_hat", "e_hat", "Qxx", "redundancy_numbers", "sigma_e_hat", "sigma_y_hat"):
        np.testing.assert_allclose(
            getattr(f, name), getattr(ref, name), rtol=rtol, atol=atol, err_msg=name
        )
    assert f.squared_norm == pytest.approx(ref.squared_norm, rel=rtol)
    np.testing.assert_allclose(
        lsq.w_tests(f).statistic, lsq.w_tests(ref).statistic, rtol=rtol, atol=atol, err_msg="w"
    )
    np.testing.assert_allclose(lsq.mdb(f), lsq.mdb(ref), rtol=rtol, err_msg="mdb")


def test_variances_as_vector_equal_the_diagonal_matrix():
    rng = np.random.default_rng(50)
    m = 12
    A = np.column_stack([np.ones(m), np.linspace(0, 1, m), np.linspace(0, 1, m) ** 2])
    variances = rng.uniform(0.2, 5.0, m)
    y = A @ [1.0, -2.0, 0.5] + np.sqrt(variances) * rng.standard_normal(m)
    f = lsq.fit(A, y, variances)
    ref = lsq.fit(A, y, np.diag(variances))
    _assert_same_fit(f, ref)
    np.testing.assert_array_equal(f.Qyy, np.diag(variances))
    np.testing.assert_allclose(f.Qee, ref.Qee, atol=1e-12)
    dense = dense_reference(A, y, np.diag(variances))
    np.testing.assert_allclose(f.squared_norm, np.sum(f.e_hat**2 / variances), rtol=1e-12)
    np.testing.assert_allclose(f.Qee, dense["Qee"], rtol=1e-9, atol=1e-12)
    # a list is accepted like an array, and the caller's vector is not changed
    kept = variances.copy()
    lsq.fit(A, y, list(variances))
    np.testing.assert_array_equal(variances, kept)


def _block_diagonal_covariance(rng, blocks, size=3):
    """A GNSS-like covariance: correlated size x size blocks, rows shuffled."""
    import scipy.sparse as sp

    parts = []
    for _ in range(blocks):
        B = rng.standard_normal((size, size))
        parts.append(B @ B.T + 0.5 * np.eye(size))
    Q = sp.block_diag(parts, format="csr")
    perm = rng.permutation(size * blocks)
    return Q[perm][:, perm]


def test_sparse_covariances_equal_their_dense_form():
    import scipy.sparse as sp

    rng = np.random.default_rng(51)
    m = 30
    t = np.linspace(0, 1, m)
    A = np.column_stack([np.ones(m), t, t**2])
    y = A @ [1.0, 2.0, -1.0] + rng.standard_normal(m)
    tridiagonal = sp.diags(
        [np.full(m - 1, 0.45), np.full(m, 1.0), np.full(m - 1, 0.45)], [-1, 0, 1], format="csc"
    )
    diagonal = sp.diags(rng.uniform(0.5, 2.0, m))
    full = sp.csr_array(random_spd(rng, m))  # no band to exploit: factored densely
    for Q in (_block_diagonal_covariance(rng, 10), tridiagonal, diagonal, full):
        f = lsq.fit(A, y, Q)
        dense = Q.toarray()
        _assert_same_fit(f, lsq.fit(A, y, dense))
        np.testing.assert_allclose(f.Qee, lsq.fit(A, y, dense).Qee, atol=1e-12)
        np.testing.assert_array_equal(f.Qyy, dense)
        ref = dense_reference(A, y, dense)
        np.testing.assert_allclose(lsq.w_tests(f).statistic, ref["w"], rtol=1e-9)
        snoop = lsq.data_snooping(lsq.fit(A, y + 30 * (np.arange(m) == 7), Q), alpha=0.001)
        assert snoop.removed[0] == 7


@pytest.mark.parametrize(
    "Q, error, match",
    [
        ("nonsymmetric", ValueError, "Qyy is not symmetric"),
        ("nan", ValueError, "Qyy contains NaN or inf"),
        ("indefinite", LinAlgError, "Qyy is not positive definite"),
        ("negative diagonal", LinAlgError, r"diagonal entry 2 is -1.0"),
        ("shape", ValueError, r"Qyy must have shape \(6, 6\), got \(5, 5\)"),
    ],
)
def test_sparse_covariance_bad_input(Q, error, match):
    import scipy.sparse as sp

    m = 6
    A = np.column_stack([np.ones(m), np.arange(m, dtype=float)])
    y = np.arange(m, dtype=float) ** 1.5
    matrix = {
        "nonsymmetric": sp.diags([np.ones(m), np.full(m - 1, 0.3)], [0, 1]),
        "nan": sp.diags([np.r_[1.0, np.nan, 1, 1, 1, 1]], [0]),
        "indefinite": sp.diags([np.ones(m), np.full(m - 1, 0.9), np.full(m - 1, 0.9)], [0, 1, -1]),
        "negative diagonal": sp.diags([np.r_[1.0, 1, -1, 1, 1, 1]], [0]),
        "shape": sp.eye(5),
    }[Q]
    with pytest.raises(error, match=match):
        lsq.fit(A, y, matrix)


def test_a_scalar_or_a_wrong_length_vector_is_refused_with_the_fix():
    with pytest.raises(ValueError, match=r"or the vector of variances np.full\(4, s2\)"):
        lsq.fit(A_LINE, DAY1, 4.0)
    with pytest.raises(ValueError, match="holds the variances of the m = 4 observations, got 5"):
        lsq.fit(A_LINE, DAY1, np.ones(5))
    with pytest.raises(ValueError, match=r"must be positive; Qyy\[3\] = -2.0"):
        lsq.fit(A_LINE, DAY1, [1.0, 1.0, 1.0, -2.0])
    with pytest.raises(ValueError, match="Qyy contains NaN or inf"):
        lsq.fit(A_LINE, DAY1, [1.0, np.inf, 1.0, 1.0])


# ---------------------------------------------------------------------------
# standard deviations passed where variances belong
# ---------------------------------------------------------------------------
def _line_data(rng, sigma, m=200):
    t = np.linspace(0, 10, m)
    A = np.column_stack([np.ones(m), t])
    return A, A @ [3.0, 0.5] + sigma * rng.standard_normal(m)


@pytest.mark.parametrize("sigma", [3.0, 0.3])
def test_standard_deviations_passed_as_variances_are_named(sigma):
    # Too large (sigma = 3: T ~ 3 (m-n)) or too small (sigma = 0.3: T ~ 0.3 (m-n)).
    rng = np.random.default_rng(52)
    A, y = _line_data(rng, sigma)
    f = lsq.fit(A, y, np.full(200, sigma))  # the slip: sigma instead of sigma**2
    with pytest.warns(
        UserWarning, match=r"if you passed standard deviations sigma, pass sigma\*\*2"
    ):
        result = lsq.overall_model_test(f, 0.05)
    assert result.statistic == pytest.approx(f.squared_norm)
    # heteroscedastic: the pattern of the residuals points to the slip as well
    sigmas = rng.uniform(0.5 * sigma, 2 * sigma, 200)
    y = A @ [3.0, 0.5] + sigmas * rng.standard_normal(200)
    with pytest.warns(UserWarning, match="Read as standard deviations"):
        lsq.overall_model_test(lsq.fit(A, y, sigmas), 0.05)


def test_no_standard_deviation_warning_when_it_is_not_the_likely_cause(recwarn):
    rng = np.random.default_rng(53)
    A, y = _line_data(rng, 3.0)
    lsq.overall_model_test(lsq.fit(A, y, np.full(200, 9.0)), 0.05)  # right: variances
    # a dense diagonal matrix is written as a covariance: no guessing there
    lsq.overall_model_test(lsq.fit(A, y, 3.0 * np.eye(200)), 0.05)
    # unequal variances given right, and a gross outlier: the test rejects, but the
    # residuals' pattern fits the values as variances, so the slip is not suggested
    sigmas = rng.uniform(0.3, 6.0, 200)
    y = A @ [3.0, 0.5] + sigmas * rng.standard_normal(200)
    y[17] += 80 * sigmas[17]
    result = lsq.overall_model_test(lsq.fit(A, y, sigmas**2), 0.05)
    assert result.reject
    assert not [w for w in recwarn if issubclass(w.category, UserWarning)]


def _warns_of_standard_deviations(f) -> bool:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lsq.overall_model_test(f, 0.05)
    return any("Read as standard deviations" in str(w.message) for w in caught)


def test_standard_deviation_warning_is_rare_in_correct_fits():
    # 2,000 correct fits (variances U(0.5, 2), m = 50): the old rule (T outside the central
    # range, T with squared values inside it, a loose pattern check) warned in ~3 % of them
    # and in more than half of the test's own false alarms. The likelihood-ratio rule
    # reaches its bound of 1000 in at most 0.1 % of correct fits (Markov's inequality).
    rng = np.random.default_rng(2028)
    m = 50
    A = np.column_stack([np.ones(m), np.linspace(0, 10, m)])
    warned = rejected = 0
    for _ in range(2000):
        v = rng.uniform(0.5, 2.0, m)
        f = lsq.fit(A, A @ [3.0, 0.5] + np.sqrt(v) * rng.standard_normal(m), v)
        warned += _warns_of_standard_deviations(f)
        rejected += lsq.overall_model_test(f, 0.05).reject
    assert 60 <= rejected <= 140  # the test's own false alarms do occur: the hint is not void
    assert warned < 0.001 * 2000


def test_standard_deviation_warning_fires_for_a_typical_slip():
    # Sensor standard deviations 0.1 to 0.5 passed as Qyy: the slip is named in nearly
    # every record (T small, the squared values give a chi2-like T).
    rng = np.random.default_rng(2029)
    m = 50
    A = np.column_stack([np.ones(m), np.linspace(0, 10, m)])
    fired = 0
    for _ in range(200):
        s = rng.uniform(0.1, 0.5, m)
        fired += _warns_of_standard_deviations(
            lsq.fit(A, A @ [3.0, 0.5] + s * rng.standard_normal(m), s)
        )
    assert fired >= 0.9 * 200


# ---------------------------------------------------------------------------
# lazy m x m matrices and memory
# ---------------------------------------------------------------------------
def test_m_by_m_matrices_are_built_only_when_asked_for():
    A, y, Qyy = correlated_problem(seed=9)
    f = lsq.fit(A, y, Qyy)
    lsq.overall_model_test(f)
    lsq.w_tests(f)
    lsq.mdb(f)
    _ = (f.sigma_e_hat, f.sigma_y_hat, f.redundancy_numbers)
    assert not {"Qee", "Qyy_hat"} & set(vars(f))
    ref = dense_reference(A, y, Qyy)
    np.testing.assert_allclose(f.Qee, ref["Qee"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(f.Qyy_hat, ref["Qyy_hat"], rtol=1e-9, atol=1e-12)
    assert {"Qee", "Qyy_hat"} <= set(vars(f))
    assert f.Qee is f.Qee  # computed once
    with pytest.raises(ValueError, match="read-only"):
        f.Qee[0, 0] = 1.0
    np.testing.assert_allclose(f.sigma_e_hat**2, np.diag(f.Qee), rtol=1e-10, atol=1e-13)


@pytest.mark.parametrize("form", ["variances", "sparse blocks"])
def test_fit_and_tests_at_m_3000_use_no_m_by_m_memory(form):
    import tracemalloc

    rng = np.random.default_rng(54)
    m, n = 3000, 3
    A = np.column_stack([np.ones(m), rng.standard_normal((m, n - 1))])
    if form == "variances":
        Q = rng.uniform(0.5, 2.0, m)
        noise = np.sqrt(Q) * rng.standard_normal(m)
    else:
        Q = _block_diagonal_covariance(rng, m // 3)
        noise = rng.standard_normal(m)  # the law of y does not matter here
    y = A @ [1.0, 2.0, 3.0] + noise
    tracemalloc.start()
    try:
        f = lsq.fit(A, y, Q)
        lsq.overall_model_test(f)
        lsq.w_tests(f)
        lsq.data_snooping(lsq.fit(A, y, Q), alpha=0.001, max_removals=2)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 0.05 * 8 * m * m  # one m x m matrix would be 72 MB


# ---------------------------------------------------------------------------
# data snooping by downdating
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["identity", "variances", "correlated", "sparse"])
def test_snooping_downdate_equals_a_fresh_fit_every_round(kind):
    rng = np.random.default_rng(60)
    m = 24
    t = np.linspace(-1, 1, m)
    A = np.column_stack([np.ones(m), t, t**2])
    Q = {
        "identity": None,
        "variances": rng.uniform(0.3, 3.0, m),
        "correlated": random_spd(rng, m, cond=20.0),
        "sparse": _block_diagonal_covariance(rng, m // 3),
    }[kind]
    dense = (
        np.eye(m)
        if Q is None
        else np.diag(Q)
        if np.ndim(Q) == 1
        else np.asarray(Q.todense() if kind == "sparse" else Q)
    )
    y = A @ [1.0, -1.0, 2.0] + np.linalg.cholesky(dense) @ rng.standard_normal(m)
    y[[4, 11, 19]] += [25.0, -30.0, 40.0]
    res = lsq.data_snooping(lsq.fit(A, y, Q), alpha=0.001)
    assert {4, 11, 19} <= set(res.removed)
    fresh_fits = []
    for wt, idx in zip(res.rounds, res.round_indices):
        idx = np.array(idx)
        fresh = lsq.fit(A[idx], y[idx], dense[np.ix_(idx, idx)])
        ref = lsq.w_tests(fresh, 0.001)
        np.testing.assert_allclose(wt.statistic, ref.statistic, rtol=1e-10, atol=1e-12)
        np.testing.assert_array_equal(wt.reject, ref.reject)
        np.testing.assert_array_equal(wt.testable, ref.testable)
        assert wt.largest == ref.largest
        fresh_fits.append(fresh)
    # removing observation i lowers T by exactly w_i² of the round that removed it
    for k in range(1, len(res.rounds)):
        w_removed = res.rounds[k - 1].statistic[res.rounds[k - 1].largest]
        drop = fresh_fits[k - 1].squared_norm - fresh_fits[k].squared_norm
        assert drop == pytest.approx(w_removed**2, rel=1e-9)
    keep = np.array(res.kept)
    _assert_same_fit(res.fit, lsq.fit(A[keep], y[keep], dense[np.ix_(keep, keep)]))


def test_snooping_with_redundancy_one_removes_the_first_of_equal_w():
    # All |w_i| are equal when m - n = 1; which one goes must not depend on round-off.
    A = np.column_stack([np.ones(4), T4, T4**2 / 2])
    wt = lsq.w_tests(lsq.fit(A, DAY2), 0.01)
    np.testing.assert_allclose(np.abs(wt.statistic), np.abs(wt.statistic[0]), rtol=1e-12)
    assert wt.largest == 0
    assert lsq.data_snooping(lsq.fit(A, DAY2), alpha=0.01).removed == (0,)


def test_snooping_keeps_untestable_observations_untested():
    # observation 3 alone determines x2; observation 5 becomes untestable once 4 is removed
    A = np.array([[1, 0, 0], [1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1]], float)
    y = np.array([1.0, 1.1, 0.9, 7.0, 2.0, 40.0])
    res = lsq.data_snooping(lsq.fit(A, y), alpha=0.01)
    assert not res.rounds[0].testable[3]
    for wt, idx in zip(res.rounds, res.round_indices):
        idx = np.array(idx)
        ref = lsq.w_tests(lsq.fit(A[idx], y[idx]), 0.01)
        np.testing.assert_array_equal(wt.testable, ref.testable)
        np.testing.assert_allclose(wt.statistic, ref.statistic, rtol=1e-10)


# ---------------------------------------------------------------------------
# property-based tests of the fit
# ---------------------------------------------------------------------------
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import assume, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402

# Subnormal numbers carry fewer significant digits, so relative tolerances cannot hold there.
_finite = st.floats(-10.0, 10.0, allow_subnormal=False)
# The same examples on every run (CI must not flake) and no example database on disk.
_PROPERTY_SETTINGS = settings(max_examples=60, deadline=None, derandomize=True, database=None)


@st.composite
def weighted_problems(draw):
    n = draw(st.integers(1, 4))
    m = draw(st.integers(n + 1, 25))
    A = draw(hnp.arrays(float, (m, n), elements=_finite))
    y = draw(hnp.arrays(float, m, elements=st.floats(-100.0, 100.0, allow_subnormal=False)))
    log_variances = draw(hnp.arrays(float, m, elements=st.floats(-3.0, 3.0)))
    correlated = draw(st.booleans())
    if correlated:
        B = draw(hnp.arrays(float, (m, m), elements=st.floats(-1.0, 1.0)))
        Q = B @ B.T / m + np.diag(10.0**log_variances)
    else:
        Q = 10.0**log_variances
    singular_values = np.linalg.svd(A, compute_uv=False)
    assume(singular_values[-1] > 1e-6 * singular_values[0] and singular_values[-1] > 1e-3)
    return A, y, Q


def _as_dense(Q):
    return np.diag(Q) if np.ndim(Q) == 1 else Q


@_PROPERTY_SETTINGS
@given(weighted_problems())
def test_property_residuals_are_orthogonal_to_range_of_A_in_the_Qyy_inverse_metric(problem):
    A, y, Q = problem
    f = lsq.fit(A, y, Q)
    L = np.linalg.cholesky(_as_dense(Q))
    A_w = np.linalg.solve(L, A)
    e_w = np.linalg.solve(L, f.e_hat)
    y_w = np.linalg.solve(L, y)
    # A^T Qyy^{-1} ê = (L^{-1}A)^T (L^{-1}ê) = 0, relative to the sizes involved (1-norms:
    # they bound the 2-norms and do not underflow for tiny y)
    gap = np.abs(A_w.T @ e_w)
    assert np.all(gap <= 1e-9 * np.sum(np.abs(A_w), axis=0) * np.sum(np.abs(y_w)))


@_PROPERTY_SETTINGS
@given(weighted_problems(), hnp.arrays(float, 4, elements=st.floats(-6.0, 6.0)))
def test_property_T_is_invariant_under_scaling_the_columns_of_A(problem, log_scales):
    A, y, Q = problem
    D = 10.0 ** log_scales[: A.shape[1]]
    f, g = lsq.fit(A, y, Q), lsq.fit(A * D, y, Q)
    # T = |y_w|² - |Q1^T y_w|² is exact up to rounding relative to |y_w|², y_w = L^{-1} y
    y_w = np.linalg.solve(np.linalg.cholesky(_as_dense(Q)), y)
    size = np.max(np.abs(y_w))
    y_w_norm = size * np.linalg.norm(y_w / size) if size > 0 else 0.0  # no underflow
    assert g.squared_norm == pytest.approx(f.squared_norm, rel=1e-8, abs=1e-10 * y_w_norm**2)
    # x̂ scales inversely, to rounding in units of its own standard deviation times |y_w|
    np.testing.assert_allclose(
        g.x_hat * D, f.x_hat, rtol=1e-6, atol=1e-8 * y_w_norm * np.max(f.sigma_x_hat)
    )
    np.testing.assert_allclose(g.y_hat, f.y_hat, rtol=1e-7, atol=1e-9 * np.max(np.abs(y)))


@_PROPERTY_SETTINGS
@given(weighted_problems())
def test_property_T_is_the_sum_of_squared_whitened_residuals(problem):
    A, y, Q = problem
    f = lsq.fit(A, y, Q)
    dense = _as_dense(Q)
    L = np.linalg.cholesky(dense)
    whitened = np.linalg.solve(L, f.e_hat)
    scale = np.sum(np.linalg.solve(L, y) ** 2)
    assert f.squared_norm == pytest.approx(np.sum(whitened**2), rel=1e-8, abs=1e-10 * scale)
    assert np.sum(f.redundancy_numbers) == pytest.approx(f.redundancy, rel=1e-8)
    if np.ndim(Q) == 1:
        assert f.squared_norm == pytest.approx(np.sum(f.e_hat**2 / Q), rel=1e-8, abs=1e-10 * scale)
        assert np.all(f.redundancy_numbers > -1e-10) and np.all(f.redundancy_numbers < 1 + 1e-10)
