"""Tests of module 7's library: q-dimensional alternatives, estimated variance, the B-method,
reliability and DIA (course.lsq).

References are independent of the library's whitened algebra: refits of the extended model
[A C] (the alternative hypothesis fitted directly), the textbook formulas with explicit
inverses, scipy's laws and Monte Carlo rates inside binomial bands.
"""

import numpy as np
import pytest
from conftest import assert_rate
from numpy.linalg import LinAlgError
from scipy import stats

from course import chi2, lsq

T10 = np.arange(10.0)
A_LINE = np.column_stack([np.ones(10), T10])
Y_OUTLIER = np.array([2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53])


def random_spd(rng, m, cond=20.0):
    Q, _ = np.linalg.qr(rng.standard_normal((m, m)))
    return (Q * np.geomspace(1.0, cond, m)) @ Q.T


def problem(seed, m=9, n=3, correlated=True):
    rng = np.random.default_rng(seed)
    t = np.linspace(-1, 2, m)
    A = np.column_stack([t**k for k in range(n)])
    Qyy = random_spd(rng, m) if correlated else rng.uniform(0.5, 2.0, m)
    cov = Qyy if np.ndim(Qyy) == 2 else np.diag(Qyy)
    y = A @ rng.normal(size=n) + np.linalg.cholesky(cov) @ rng.standard_normal(m)
    return A, y, Qyy, cov, rng


def textbook_T_q(A, y, cov, C):
    """T_q by the printed formula, with explicit inverses (an independent reference)."""
    Qi = np.linalg.inv(cov)
    Qxx = np.linalg.inv(A.T @ Qi @ A)
    e = y - A @ (Qxx @ A.T @ Qi @ y)
    Qee = cov - A @ Qxx @ A.T
    middle = np.linalg.inv(C.T @ Qi @ Qee @ Qi @ C)
    v = C.T @ Qi @ e
    return float(v @ middle @ v)


# ---------------------------------------------------------------------------
# glr_test: the special cases and the printed formula
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("correlated", [True, False])
def test_glr_of_one_observation_is_the_w_test_squared(seed, correlated):
    A, y, Qyy, _, _ = problem(seed, correlated=correlated)
    f = lsq.fit(A, y, Qyy)
    w = lsq.w_tests(f).statistic
    for i in range(f.m):
        statistic = lsq.glr_test(f, np.eye(f.m)[:, i]).statistic
        assert statistic == pytest.approx(w[i] ** 2, rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_glr_with_q_equal_to_the_redundancy_is_the_overall_model_test(seed):
    A, y, Qyy, _, rng = problem(seed)
    f = lsq.fit(A, y, Qyy)
    C = rng.standard_normal((f.m, f.redundancy))  # [A C] of full rank almost surely
    glr = lsq.glr_test(f, C, alpha=0.05)
    omt = lsq.overall_model_test(f, alpha=0.05)
    assert glr.statistic == pytest.approx(omt.statistic, rel=1e-10)
    assert glr.critical_value == pytest.approx(omt.critical_value, rel=1e-12)
    assert glr.reject == omt.reject


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("q", [1, 2, 4])
def test_glr_agrees_with_the_printed_formula_and_the_refit(seed, q):
    A, y, Qyy, cov, rng = problem(seed)
    f = lsq.fit(A, y, Qyy)
    C = rng.standard_normal((f.m, q))
    result = lsq.glr_test(f, C)
    assert result.statistic == pytest.approx(textbook_T_q(A, y, cov, C), rel=1e-9)
    # T_q is the drop of the residual norm when the bias is estimated: fit [A C] directly
    extended = lsq.fit(np.column_stack([A, C]), y, Qyy)
    assert result.statistic == pytest.approx(f.squared_norm - extended.squared_norm, rel=1e-9)
    np.testing.assert_allclose(
        result.details["estimated bias"], extended.x_hat[A.shape[1] :], rtol=1e-8, atol=1e-10
    )
    assert result.dof == q and result.null.kwds == {} and result.null.args == (q,)


@pytest.mark.parametrize("seed", range(4))
def test_the_f_statistic_is_the_nested_models_f(seed):
    A, y, Qyy, _, rng = problem(seed, m=12)
    f = lsq.fit(A, y, Qyy)
    C = rng.standard_normal((f.m, 2))
    extended = lsq.fit(np.column_stack([A, C]), y, Qyy)
    dof2 = f.redundancy - 2
    F = ((f.squared_norm - extended.squared_norm) / 2) / (extended.squared_norm / dof2)
    result = lsq.glr_test(f, C, alpha=0.05, variance="estimated")
    assert result.statistic == pytest.approx(F, rel=1e-9)
    assert result.critical_value == pytest.approx(stats.f.isf(0.05, 2, dof2), rel=1e-12)
    assert result.pvalue == pytest.approx(stats.f.sf(F, 2, dof2), rel=1e-9)
    assert result.details["denominator dof"] == dof2


def test_the_f_test_does_not_depend_on_the_variance_factor():
    A, y, Qyy, _, rng = problem(1, m=12)
    C = rng.standard_normal((12, 2))
    a = lsq.glr_test(lsq.fit(A, y, Qyy), C, variance="estimated")
    b = lsq.glr_test(lsq.fit(A, y, 9.0 * Qyy), C, variance="estimated")
    assert a.statistic == pytest.approx(b.statistic, rel=1e-10)
    known = lsq.glr_test(lsq.fit(A, y, 9.0 * Qyy), C)
    assert known.statistic == pytest.approx(lsq.glr_test(lsq.fit(A, y, Qyy), C).statistic / 9)


def test_glr_refuses_a_bias_that_the_model_absorbs():
    f = lsq.fit(A_LINE, Y_OUTLIER, 0.01 * np.eye(10))
    with pytest.raises(LinAlgError, match="range of A"):
        lsq.glr_test(f, T10)  # a slope error is absorbed by the slope parameter
    with pytest.raises(LinAlgError, match="full column rank"):
        lsq.glr_test(f, np.column_stack([np.eye(10)[:, 3], 2 * np.eye(10)[:, 3]]))


@pytest.mark.parametrize(
    "C, variance, match",
    [
        (np.ones(9), "known", "one row per observation"),
        (np.eye(10)[:, :9], "known", "at most m - n"),
        (np.eye(10)[:, :8], "estimated", "q < m - n"),
        (np.eye(10)[:, 0], "unknown", "variance must be"),
        (np.full(10, np.nan), "known", "C"),
    ],
)
def test_glr_bad_input(C, variance, match):
    f = lsq.fit(A_LINE, Y_OUTLIER, 0.01 * np.eye(10))
    with pytest.raises(ValueError, match=match):
        lsq.glr_test(f, C, variance=variance)


# ---------------------------------------------------------------------------
# power: the alternative law against Monte Carlo
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("variance, scale", [("known", 1.0), ("estimated", 1.6)])
def test_power_from_the_alternative_law_matches_simulation(variance, scale):
    rng = np.random.default_rng(7)
    m = 10
    Qyy = 0.04 * np.eye(m)
    C = np.eye(m)[:, [4, 5]]
    bias = scale * np.array([0.3, 0.25])
    template = lsq.fit(A_LINE, np.zeros(m), Qyy)
    law = lsq.alternative_law(template, C, bias, variance=variance)
    reps = 2000
    rejections = 0
    for _ in range(reps):
        y = A_LINE @ [1.0, 0.2] + C @ bias + 0.2 * rng.standard_normal(m)
        result = lsq.glr_test(lsq.fit(A_LINE, y, Qyy), C, alpha=0.05, variance=variance)
        rejections += result.reject
    power = result.power(law)
    assert 0.3 < power < 0.95  # a case that can tell a wrong law from the right one
    assert_rate(rejections / reps, reps, power)


def test_alternative_law_at_zero_bias_is_the_null():
    f = lsq.fit(A_LINE, Y_OUTLIER, 0.01 * np.eye(10))
    C = np.eye(10)[:, [2, 3]]
    result = lsq.glr_test(f, C, alpha=0.01)
    assert result.power(lsq.alternative_law(f, C, [0.0, 0.0])) == pytest.approx(0.01)


# ---------------------------------------------------------------------------
# w-tests with an estimated variance: Student's t, Pope's tau
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(4))
def test_estimated_variance_w_is_the_t_statistic_of_the_outlier_parameter(seed):
    A, y, Qyy, _, _ = problem(seed, m=11)
    f = lsq.fit(A, y, Qyy)
    t = lsq.w_tests(f, variance="estimated")
    assert t.dof == f.redundancy - 1 and t.variance == "estimated"
    for i in range(f.m):
        extended = lsq.fit(np.column_stack([A, np.eye(f.m)[:, i]]), y, Qyy)
        sigma2 = extended.squared_norm / extended.redundancy
        expected = extended.x_hat[-1] / np.sqrt(sigma2 * extended.Qxx[-1, -1])
        assert t.statistic[i] == pytest.approx(expected, rel=1e-8)


def test_the_t_test_and_popes_tau_test_are_one_test():
    A, y, Qyy, _, _ = problem(2, m=11)
    f = lsq.fit(A, y, Qyy)
    r = f.redundancy
    w = lsq.w_tests(f).statistic
    tau = w / np.sqrt(f.squared_norm / r)
    # Pope's tau: tau² / r ~ Beta(1/2, (r - 1)/2) under H0, a symmetric law on [-sqrt(r), sqrt(r)]
    p_tau = stats.beta.sf(tau**2 / r, 0.5, (r - 1) / 2)
    t = lsq.w_tests(f, alpha=0.05, variance="estimated")
    np.testing.assert_allclose(t.pvalue, p_tau, rtol=1e-9)
    np.testing.assert_allclose(t.statistic**2, (r - 1) * tau**2 / (r - tau**2), rtol=1e-9)


def test_estimated_variance_w_tests_need_two_redundant_observations():
    f = lsq.fit(A_LINE[:3], Y_OUTLIER[:3])
    with pytest.raises(ValueError, match="m - n >= 2"):
        lsq.w_tests(f, variance="estimated")
    with pytest.raises(ValueError, match="variance must be"):
        lsq.w_tests(lsq.fit(A_LINE, Y_OUTLIER), variance="sigma")


# ---------------------------------------------------------------------------
# the B-method
# ---------------------------------------------------------------------------
def test_b_method_reference_values():
    b = lsq.b_method(0.001, 0.80, q=[1, 2, 3, 10])
    assert b.lambda0 == pytest.approx(17.0746, abs=5e-4)  # Baarda's lambda0 for (0.001, 80 %)
    assert b.alpha_q[0] == pytest.approx(0.001, rel=1e-8)  # q = 1 is the w-test itself
    assert b.critical_value_1 == pytest.approx(3.2905, abs=1e-4)
    # every q-dimensional test at its alpha_q has power 0.80 at lambda0 (scipy's laws)
    np.testing.assert_allclose(
        stats.ncx2.sf(stats.chi2.isf(b.alpha_q, [1, 2, 3, 10]), [1, 2, 3, 10], b.lambda0),
        0.80,
        rtol=1e-8,
    )
    assert np.all(np.diff(b.alpha_q) > 0)  # higher dimension, larger level


def test_b_method_tests_detect_the_reference_bias_equally_often():
    rng = np.random.default_rng(3)
    b = lsq.b_method(0.001, 0.80, q=3)
    reps = 4000
    # T_3 under a bias of non-centrality lambda0: a normal vector shifted by sqrt(lambda0)
    z = rng.standard_normal((reps, 3))
    z[:, 0] += np.sqrt(b.lambda0)
    assert_rate(np.mean(np.sum(z**2, axis=1) > b.critical_value_q), reps, 0.80)
    w = rng.standard_normal(reps) + np.sqrt(b.lambda0)
    assert_rate(np.mean(np.abs(w) > b.critical_value_1), reps, 0.80)


def test_b_method_bad_input():
    with pytest.raises(ValueError, match="power must exceed"):
        lsq.b_method(0.5, 0.2)
    with pytest.raises(ValueError, match="q"):
        lsq.b_method(0.001, 0.8, q=1.5)


# ---------------------------------------------------------------------------
# reliability
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(3))
def test_one_dimensional_mdb_is_the_observations_mdb(seed):
    A, y, Qyy, _, _ = problem(seed)
    f = lsq.fit(A, y, Qyy)
    expected = lsq.mdb(f, alpha=0.001, power=0.8)
    for i in range(f.m):
        got = lsq.minimal_detectable_bias(f, np.eye(f.m)[:, i], alpha=0.001, power=0.8)
        assert got.lengths[0] == pytest.approx(expected[i], rel=1e-10)


def test_mdb_along_a_direction_has_the_required_power():
    A, y, Qyy, _, rng = problem(4, m=12)
    f = lsq.fit(A, y, Qyy)
    C = rng.standard_normal((12, 3))
    region = lsq.minimal_detectable_bias(f, C, alpha=0.01, power=0.9)
    result = lsq.glr_test(f, C, alpha=0.01)
    for direction in [[1, 0, 0], [0.3, -1, 2], region.axes[:, 0], region.axes[:, -1]]:
        bias = region.along(direction)
        assert result.power(lsq.alternative_law(f, C, bias)) == pytest.approx(0.9, abs=1e-6)
    # the semi-axes are the shortest and the longest MDB over all directions
    sizes = [np.linalg.norm(region.along(d)) for d in rng.standard_normal((200, 3))]
    assert region.lengths[0] <= min(sizes) + 1e-12 and max(sizes) <= region.lengths[-1] + 1e-12
    # and the covariance of the estimated bias is the textbook inverse
    Qi = np.linalg.inv(Qyy)
    Qee = Qyy - A @ f.Qxx @ A.T
    np.testing.assert_allclose(region.covariance, np.linalg.inv(C.T @ Qi @ Qee @ Qi @ C), rtol=1e-8)


@pytest.mark.parametrize("seed", range(3))
def test_external_reliability_is_the_shift_of_the_estimate(seed):
    A, y, Qyy, _, rng = problem(seed)
    f = lsq.fit(A, y, Qyy)
    C = rng.standard_normal((f.m, 2))
    bias = np.array([0.7, -0.4])
    er = lsq.external_reliability(f, C, bias)
    shifted = lsq.fit(A, y + C @ bias, Qyy)
    np.testing.assert_allclose(er.effect, shifted.x_hat - f.x_hat, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(er.bias_to_noise, er.effect / f.sigma_x_hat)
    overall = np.sqrt(er.effect @ np.linalg.solve(f.Qxx, er.effect))
    assert er.overall == pytest.approx(overall, rel=1e-8)


# ---------------------------------------------------------------------------
# DIA
# ---------------------------------------------------------------------------
def test_dia_adapts_to_the_identified_outlier_like_a_refit_without_it():
    f = lsq.fit(A_LINE, Y_OUTLIER, 0.01 * np.eye(10))
    result = lsq.dia(f, alpha=0.01)
    assert result.identified == 6 and result.decision == "adapted: observation 6"
    keep = np.delete(np.arange(10), 6)
    refit = lsq.fit(A_LINE[keep], Y_OUTLIER[keep], 0.01 * np.eye(9))
    np.testing.assert_allclose(result.x_hat, refit.x_hat, rtol=1e-10)
    np.testing.assert_allclose(result.statistics, lsq.w_tests(f).statistic ** 2, rtol=1e-10)


def test_dia_accepts_h0_and_keeps_the_estimate_when_nothing_is_detected():
    y = A_LINE @ [2.0, 0.5] + 0.1 * np.random.default_rng(0).standard_normal(10)
    f = lsq.fit(A_LINE, y, 0.01 * np.eye(10))
    result = lsq.dia(f, alpha=0.01)
    assert not result.detection.reject and result.identified is None
    np.testing.assert_array_equal(result.x_hat, f.x_hat)


def test_dia_with_candidates_of_different_dimension_adapts_to_the_extended_fit():
    f = lsq.fit(A_LINE, Y_OUTLIER, 0.01 * np.eye(10))
    jump = np.r_[np.zeros(6), np.ones(4)]
    pair = np.eye(10)[:, [6, 7]]
    result = lsq.dia(f, candidates=[jump, pair], alpha=0.01)
    k = result.identified
    C = [jump[:, None], pair][k]
    extended = lsq.fit(np.column_stack([A_LINE, C]), Y_OUTLIER, 0.01 * np.eye(10))
    np.testing.assert_allclose(result.x_hat, extended.x_hat[:2], rtol=1e-9)


def test_dia_monte_carlo_rates_and_the_mixture():
    f = lsq.fit(A_LINE, np.zeros(10), 0.01 * np.eye(10))
    size = 20_000
    null = lsq.dia_monte_carlo(f, alpha=0.05, size=size, rng=np.random.default_rng(5))
    assert_rate(null.detection_rate, size, 0.05)
    # the plain estimator is N(0, Qxx)
    np.testing.assert_allclose(np.cov(null.errors_null.T), f.Qxx, rtol=0.05, atol=1e-6)
    # under a bias of one MDB in observation 3 the w-test's power is the w-tests' 80 %, and
    # detection + identification is rarer than detection alone
    bias_size = lsq.mdb(f, alpha=0.001, power=0.8)[3]
    b = bias_size * np.eye(10)[3]
    alt = lsq.dia_monte_carlo(f, alpha=0.05, bias=b, size=size, rng=np.random.default_rng(6))
    correct = alt.identification_rate(3)
    assert 0.5 < correct < alt.detection_rate
    # the DIA estimator is a mixture: unbiased plain errors are shifted by the undetected
    # bias in some runs and adapted in others, so its slope error is not normal
    slope = alt.errors[:, 1]
    assert stats.normaltest(slope).pvalue < 1e-6
    # the runs adapted to the right candidate are unbiased (the refit without observation 3;
    # run by run: test_dia_monte_carlo_agrees_run_by_run_with_dia_...), the accepted runs
    # carry the undetected bias
    runs = alt.identified == 3
    shift = lsq.external_reliability(f, np.eye(10)[:, 3], bias_size).effect[1]
    se = alt.errors[runs, 1].std() / np.sqrt(runs.sum())
    assert abs(alt.errors[runs, 1].mean()) < abs(shift) / 2 and shift < -5 * se
    assert alt.errors[alt.identified < 0, 1].mean() < shift / 2


def test_dia_monte_carlo_needs_a_generator():
    f = lsq.fit(A_LINE, Y_OUTLIER, 0.01 * np.eye(10))
    with pytest.raises(ValueError, match="rng is required"):
        lsq.dia_monte_carlo(f, size=10)
    with pytest.raises(ValueError, match="candidates"):
        lsq.dia(f, candidates=[])


def test_noncentrality_agrees_with_the_b_method():
    assert lsq.b_method(0.01, 0.9).lambda0 == pytest.approx(chi2.noncentrality(0.01, 0.9, 1))


def test_dia_identification_with_mixed_dimensions_survives_underflowing_pvalues():
    """Two candidates of dimension 1 and 2 whose statistics are both so large that their
    chi-square p-values underflow to 0: the pair that explains the data must be identified
    whatever the order of the candidates (the old rule took the first of the zeros)."""
    y = A_LINE @ [2.0, 0.5]
    y[6] += 20.0
    y[7] -= 20.0
    f = lsq.fit(A_LINE, y, 0.01 * np.eye(10))
    single, pair = np.eye(10)[:, 6], np.eye(10)[:, [6, 7]]
    assert np.all(stats.chi2.sf(lsq.dia(f, [single, pair]).statistics, [1, 2]) == 0.0)
    assert lsq.dia(f, [single, pair], alpha=0.01).identified == 1
    assert lsq.dia(f, [pair, single], alpha=0.01).identified == 0
    bias = np.zeros(10)
    bias[[6, 7]] = [20.0, -20.0]
    mc = lsq.dia_monte_carlo(
        f, [single, pair], alpha=0.01, bias=bias, size=50, rng=np.random.default_rng(3)
    )
    assert mc.identification_rate(1) == 1.0


def test_dia_identification_with_mixed_dimensions_ranks_by_the_pvalue():
    """Where the p-values are representable, the smallest p-value wins, not the largest T."""
    from course.lsq._dia import _identify

    statistics = np.array([[10.0, 11.0], [12.0, 11.0], [3.0e3, 3.1e3], [3.1e3, 3.0e3]])
    dims = np.array([1, 2])
    expected = np.argmin(
        [
            [stats.chi2.logsf(10.0, 1), stats.chi2.logsf(11.0, 2)],
            [stats.chi2.logsf(12.0, 1), stats.chi2.logsf(11.0, 2)],
        ],
        axis=1,
    )
    got = _identify(statistics, dims)
    np.testing.assert_array_equal(got[:2], expected)
    # far in the tail the log p-value is about -T/2 + (q/2 - 1) log(T/2) - log Gamma(q/2)
    np.testing.assert_array_equal(got[2:], [1, 0])


def test_dia_monte_carlo_agrees_run_by_run_with_dia_for_candidates_of_several_dimensions():
    """The vectorised adaptation of dia_monte_carlo equals dia (and so the extended refit)
    on the same draws, for candidates of dimension 1, 2 and 3 (sigma = 0.1, so the draws
    are y = 0.1 * (standard normal + b / 0.1) in the simulation's order)."""
    f = lsq.fit(A_LINE, np.zeros(10), 0.01 * np.eye(10))
    candidates = [np.eye(10)[:, 2], np.eye(10)[:, [6, 7]], np.eye(10)[:, [0, 4, 9]]]
    bias = np.zeros(10)
    bias[[6, 7]] = [0.4, 0.3]
    size = 200
    mc = lsq.dia_monte_carlo(
        f, candidates, alpha=0.05, bias=bias, size=size, rng=np.random.default_rng(11)
    )
    draws = np.random.default_rng(11).standard_normal((size, 10)) * 0.1 + bias
    for run, y in enumerate(draws):
        result = lsq.dia(lsq.fit(A_LINE, y, 0.01 * np.eye(10)), candidates, alpha=0.05)
        k = -1 if result.identified is None else result.identified
        assert mc.identified[run] == k
        np.testing.assert_allclose(mc.errors[run], result.x_hat, rtol=1e-8, atol=1e-10)
    assert {1, 2} <= set(mc.identified.tolist())


def test_chi2_log_sf_continued_fraction_matches_scipy_where_scipy_is_finite(monkeypatch):
    """The far-tail branch of the log p-value, forced on statistics where scipy's logsf is
    still finite, reproduces it (the branch is otherwise reached only beyond x = 1500)."""
    import types

    from course.lsq import _dia

    x = np.array([40.0, 200.0, 600.0, 1400.0, 1400.0])
    dof = np.array([1, 2, 5, 30, 200])
    expected = stats.chi2.logsf(x, dof)
    never_finite = types.SimpleNamespace(
        logsf=lambda v, d: np.full(np.broadcast(v, d).shape, -np.inf)
    )
    monkeypatch.setattr(_dia, "stats", types.SimpleNamespace(chi2=never_finite))
    np.testing.assert_allclose(_dia._chi2_log_sf(x, dof), expected, rtol=1e-12)


@pytest.mark.parametrize("scale", [1.0, 1e-6, 1e8])
def test_estimated_variance_refuses_data_that_fit_exactly(scale):
    """Points exactly on the line leave residuals of round-off size: sigma² estimated from
    them is 0 and the t-tests judged the rounding errors (observation 5 of this line was
    'rejected' at 5 %). A clear ValueError instead; the known-variance tests still run."""
    A = np.column_stack([np.ones(6), np.arange(6.0)])
    f = lsq.fit(A, scale * (1.0 + 2.0 * np.arange(6.0)))
    with pytest.raises(ValueError, match="fit the model exactly"):
        lsq.w_tests(f, variance="estimated")
    with pytest.raises(ValueError, match="fit the model exactly"):
        lsq.glr_test(f, np.eye(6)[:, [2]], variance="estimated")
    assert not lsq.glr_test(f, np.eye(6)[:, [2]]).reject
    # one bias on otherwise exact data: the alternative explains everything, F is infinite
    y = 1.0 + 2.0 * np.arange(6.0)
    y[2] += 1.0
    g = lsq.glr_test(lsq.fit(A, scale * y), np.eye(6)[:, 2], variance="estimated")
    assert g.reject and g.pvalue < 1e-6
    # small but real noise is not round-off
    noisy = scale * (1.0 + 2.0 * np.arange(6.0) + 1e-9 * np.array([1, -2, 1, 3, -1, 0.5]))
    assert np.all(np.isfinite(lsq.w_tests(lsq.fit(A, noisy), variance="estimated").statistic))


# ---------------------------------------------------------------------------
# issue 38: a law of another test refused; the B-method near power 1
# ---------------------------------------------------------------------------
def test_power_refuses_a_law_of_another_dimension_or_family():
    """The mistakes assignment 7 declares: a q = 2 law for a q = 1 test (0.975 before), an
    F law for the chi-square test (0.792 before); the message names both laws."""
    y = A_LINE @ [1.0, 0.5] + 0.1 * np.random.default_rng(3).standard_normal(10)
    f = lsq.fit(A_LINE, y, 0.01 * np.eye(10))
    e4, pair = np.eye(10)[:, 4], np.eye(10)[:, [4, 5]]
    single = lsq.glr_test(f, e4, alpha=0.05)
    with pytest.raises(ValueError, match=r"ncx2\(2, .*chi2\(1\)"):
        single.power(lsq.alternative_law(f, pair, [0.3, 0.3]))
    with pytest.raises(ValueError, match=r"family .*ncf\(1, 7|ncf\(1, 7.*family"):
        single.power(lsq.alternative_law(f, e4, 0.3, variance="estimated"))
    with pytest.raises(ValueError, match="degrees of freedom"):
        lsq.glr_test(f, e4, variance="estimated").power(stats.ncf(1, 6, 3.0))
    # the test's own laws, and location-scale changes, are taken
    assert single.power(lsq.alternative_law(f, e4, 0.0)) == pytest.approx(0.05)
    assert 0.05 < single.power(stats.ncx2(1, 4.0, scale=1.2)) < 1.0


def _lambda0_w_test(alpha, power):
    """λ0 of the two-sided w-test from its closed-form miss probability, with mpmath."""
    import mpmath as mp

    mp.mp.dps = 40
    z = mp.sqrt(2) * mp.erfinv(1 - mp.mpf(alpha))
    miss = 1 - mp.mpf(power)
    start = z + mp.sqrt(2) * mp.erfinv(2 * mp.mpf(power) - 1)
    root = mp.findroot(lambda s: mp.ncdf(z - s) - mp.ncdf(-z - s) - miss, start)
    return float(root**2)


@pytest.mark.parametrize("power", [0.8, 1 - 1e-9, 1 - 1e-12, 1 - 1e-14, 1 - 1e-15])
def test_b_method_stays_accurate_up_to_power_one_minus_1e15(power):
    """λ0 to 1e-12 relative and alpha_q(q = 1) = alpha_1 (0.000999925 at 1 - 1e-12 and λ0
    3 % off at 1 - 1e-16 before); beyond 1 - 1e-15 refused."""
    b = lsq.b_method(0.001, power, q=[1, 3])
    assert b.lambda0 == pytest.approx(_lambda0_w_test(0.001, power), rel=1e-12)
    assert b.alpha_q[0] == pytest.approx(0.001, rel=1e-12)
    # the q = 3 test at alpha_q misses ncx2(3, λ0) with probability 1 - power
    miss = stats.ncx2.cdf(b.critical_value_q[1], 3, b.lambda0)
    assert miss == pytest.approx(1 - power, rel=1e-6)


def test_b_method_refuses_power_nearer_one_than_1e15():
    with pytest.raises(ValueError, match="1 - 1e-15"):
        lsq.b_method(0.001, 1 - 1e-16)


def test_w_tests_docstring_names_the_t_law_for_an_estimated_variance():
    """The Returns section said ``null`` (``norm()``) and ``norm.isf`` whatever the variance."""
    returns = lsq.w_tests.__doc__.split("Returns")[1].split("Raises")[0]
    assert "t(m - n - 1)" in returns and "(``norm()``)" not in returns
    attributes = lsq.WTestResult.__doc__
    assert "2 norm.sf" not in attributes and "t(m - n - 1).isf" in attributes
