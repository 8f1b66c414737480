"""Tests of course.mismatched: the corrected appendix recursion, the section
statistics, their laws and the tests (Baram 1980).

Every Monte Carlo check is seeded and uses a tolerance band with a miss
probability of about 1e-4 (Bonferroni over the entries checked), so it is
meaningful and not flaky.
"""

import numpy as np
import pytest
from conftest import binomial_band
from scipy import linalg as sla
from scipy import stats

from course.filters import LinearModel, kalman_filter, riccati
from course.mismatched import (
    APPENDIX_MISPRINTS,
    ResidualMoments,
    correlation_matrix,
    correlation_statistic,
    correlation_test,
    covariance_matrix,
    covariance_statistic,
    covariance_test,
    mean_matrix,
    mean_statistic,
    mean_test,
    moment_zscores,
    pair_moments,
    power,
    principal_directions,
    residual_moments,
    residual_moments_as_printed,
    section_moments,
    simulate_records,
    statistic_law,
)
from course.quadform import QuadraticForm
from course.results import TestResult


# ---------------------------------------------------------------------------
# models
# ---------------------------------------------------------------------------
def two_state_system(drift_pole=0.98):
    """M0: a signal driven by a slow drift; the data-generating model."""
    return LinearModel(
        F=[[0.9, 1.0], [0.0, drift_pole]],
        H=[[1.0, 0.0]],
        Q=np.diag([0.5, 0.02]),
        R=[[1.0]],
        x0_mean=[0.0, 1.0],
        x0_cov=np.diag([1.0, 0.2]),
        w_mean=[0.1, 0.0],
        v_mean=[0.3],
    )


def reduced_filter():
    """M1: one state, no drift, inflated process noise."""
    return LinearModel(
        F=[[0.95]],
        H=[[1.0]],
        Q=[[1.0]],
        R=[[1.2]],
        x0_mean=[0.5],
        x0_cov=[[2.0]],
        v_mean=[0.1],
        w_mean=[0.05],
    )


def same_order_pair():
    """Two-state true model and a different two-state filter: every printed
    formula of the appendix is conformable, so each misprint can be measured."""
    m0 = LinearModel(
        F=[[0.9, 0.5], [0.0, 0.8]],
        H=[[1.0, 0.0]],
        Q=np.diag([0.5, 0.3]),
        R=[[1.0]],
        x0_mean=[1.0, -1.0],
        x0_cov=np.diag([1.0, 0.5]),
        w_mean=[0.1, 0.0],
        v_mean=[0.4],
    )
    m1 = LinearModel(
        F=[[0.7, 0.0], [0.0, 0.5]],
        H=[[1.0, 1.0]],
        Q=np.diag([2.0, 1.0]),
        R=[[0.3]],
        x0_mean=[0.0, 0.5],
        x0_cov=np.diag([3.0, 2.0]),
        v_mean=[-0.2],
        w_mean=[0.05, 0.1],
    )
    return m0, m1


def two_output_pair(scale_r=1.0):
    """Three states, two outputs; the filter keeps two states."""
    m0 = LinearModel(
        F=[[0.8, 0.3, 0.0], [0.0, 0.7, 0.2], [0.0, 0.0, 0.9]],
        H=[[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]],
        Q=np.diag([0.4, 0.3, 0.1]),
        R=scale_r * np.array([[1.0, 0.3], [0.3, 0.8]]),
        x0_mean=[0.5, 0.0, -0.5],
        x0_cov=np.eye(3),
        v_mean=[0.1, -0.1],
    )
    m1 = LinearModel(
        F=[[0.8, 0.2], [0.0, 0.85]],
        H=[[1.0, 0.0], [0.0, 1.0]],
        Q=np.diag([0.5, 0.5]),
        R=[[1.0, 0.2], [0.2, 1.0]],
        x0_cov=2 * np.eye(2),
    )
    return m0, m1


def bonferroni(n_entries, miss=1e-4):
    return stats.norm.isf(miss / (2 * n_entries))


def brute_force_moments(m0, m1, N):
    """Stacked mean and covariance of (r_0, ..., r_{N-1}) from the filter itself.

    Residuals are affine in xi = (x_0, w_0..w_{N-1}, v_0..v_{N-1}); running
    course.filters.kalman_filter on the outputs of each unit impulse gives the
    affine map r = r(0) + T xi, hence E r = r(E xi) and Cov r = T Cov(xi) T^T.
    Independent of the augmented-system recursion under test.
    """
    n0, q0, p = m0.n_states, m0.n_noise, m0.n_outputs
    dim = n0 + N * q0 + N * p
    mean_xi = np.concatenate([m0.x0_mean, np.tile(m0.w_mean, N), np.tile(m0.v_mean, N)])
    cov_xi = sla.block_diag(m0.x0_cov, *[m0.Q] * N, *[m0.R] * N)

    def outputs(xi):
        x = xi[:n0]
        W = xi[n0 : n0 + N * q0].reshape(N, q0)
        V = xi[n0 + N * q0 :].reshape(N, p)
        ys = []
        for t in range(N):
            ys.append(m0.H @ x + V[t])
            x = m0.F @ x + m0.G @ W[t]
        return np.array(ys)

    Y = np.array([outputs(np.zeros(dim))] + [outputs(e) for e in np.eye(dim)])
    R = kalman_filter(m1, Y).eps.reshape(dim + 1, -1)
    T = (R[1:] - R[0]).T
    return R[0] + T @ mean_xi, T @ cov_xi @ T.T


# ---------------------------------------------------------------------------
# the moment recursion
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("pair", ["reduced", "same_order", "two_output"])
def test_recursion_matches_brute_force_stacked_covariance(pair):
    if pair == "reduced":
        m0, m1 = two_state_system(), reduced_filter()
    elif pair == "same_order":
        m0, m1 = same_order_pair()
    else:
        m0, m1 = two_output_pair()
    N = 7
    moments = residual_moments(m0, m1, N)
    mean, cov = brute_force_moments(m0, m1, N)
    assert np.max(np.abs(moments.mean.ravel() - mean)) < 1e-10
    assert np.max(np.abs(moments.stacked_cov() - cov)) < 1e-10
    # C(j, k) = C(k, j)^T and C(j, j) = P_j
    assert np.allclose(moments.cross_cov, moments.cross_cov.transpose(1, 0, 3, 2))
    assert np.allclose(moments.C(3, 3), moments.cov[3])


def test_matched_filter_residuals_are_white_with_riccati_covariance():
    # the filter's own model generates the data: innovations are zero mean,
    # white, with covariance S_t from the Riccati recursion
    model = reduced_filter()
    N = 12
    moments = residual_moments(model, model, N)
    assert np.max(np.abs(moments.mean)) < 1e-12
    assert np.allclose(moments.cov, riccati(model, N).S, atol=1e-12)
    off = moments.cross_cov.copy()
    for t in range(N):
        off[t, t] = 0.0
    assert np.max(np.abs(off)) < 1e-12


def test_mismatched_residuals_are_coloured_biased_and_non_stationary():
    moments = residual_moments(two_state_system(), reduced_filter(), 30)
    assert abs(moments.mean[0, 0]) > 0.1  # non-zero mean
    assert abs(moments.mean[0, 0] - moments.mean[-1, 0]) > 0.05  # non-stationary
    assert abs(moments.C(10, 11)[0, 0]) > 0.05  # correlated


def test_corrected_moments_agree_with_monte_carlo_and_misprints_do_not():
    m0, m1 = same_order_pair()
    N, M = 6, 40_000
    residuals = simulate_records(m0, m1, M, N, np.random.default_rng(3))
    z_mean, z_cov = moment_zscores(residuals, residual_moments(m0, m1, N))
    limit = bonferroni(z_mean.size + z_cov.size)
    assert np.max(np.abs(z_mean)) < limit
    assert np.max(np.abs(z_cov)) < limit
    for name in APPENDIX_MISPRINTS:
        zm, zc = moment_zscores(residuals, residual_moments_as_printed(m0, m1, N, name))
        worst = max(np.max(np.abs(zm)), np.max(np.abs(zc)))
        assert worst > 3 * limit, f"the printed form of {name} was not detected ({worst:.1f})"


def test_reduced_order_moments_agree_with_monte_carlo():
    m0, m1 = two_state_system(), reduced_filter()
    N, M = 8, 40_000
    residuals = simulate_records(m0, m1, M, N, np.random.default_rng(4))
    z_mean, z_cov = moment_zscores(residuals, residual_moments(m0, m1, N))
    limit = bonferroni(z_mean.size + z_cov.size)
    assert np.max(np.abs(z_mean)) < limit and np.max(np.abs(z_cov)) < limit


def test_printed_gain_is_not_conformable_for_a_reduced_filter():
    with pytest.raises(ValueError, match="cannot multiply"):
        residual_moments_as_printed(two_state_system(), reduced_filter(), 5, "gain_of_tested_model")
    with pytest.raises(ValueError, match="misprint must be one of"):
        residual_moments_as_printed(two_state_system(), reduced_filter(), 5, "A99")


def test_a15_is_not_a_misprint():
    """The paper prints (A15) as [H_j^0 - H_j^1]: in its block notation (blocks separated by
    spaces, as in (A14)) that is [H^0, -H^1], the correct matrix; a plus-sign "as printed"
    variant put a formula in the paper's mouth that it never printed."""
    assert "H_tilde_sign" not in APPENDIX_MISPRINTS
    assert not any(eq == "(A15)" for eq, _, _ in APPENDIX_MISPRINTS.values())
    with pytest.raises(ValueError, match="misprint must be one of"):
        residual_moments_as_printed(two_state_system(), reduced_filter(), 5, "H_tilde_sign")


def test_a26_is_not_a_misprint():
    """The paper's (A26) prints the zero block of the known initial estimate and is wrong only
    by a tilde; a "random initial estimate" variant was the reader's, not the paper's (issue 39,
    the same misquote as (A15))."""
    assert "initial_estimate_random" not in APPENDIX_MISPRINTS
    assert not any(eq == "(A26)" for eq, _, _ in APPENDIX_MISPRINTS.values())
    with pytest.raises(ValueError, match="misprint must be one of"):
        residual_moments_as_printed(
            two_state_system(), reduced_filter(), 5, "initial_estimate_random"
        )


# ---------------------------------------------------------------------------
# statistics, their quadratic-form matrices and laws
# ---------------------------------------------------------------------------
def test_statistics_equal_their_quadratic_forms():
    rng = np.random.default_rng(8)
    M, N, p = 5, 4, 2
    r = rng.normal(size=(M, N, p)) + 0.3
    j, k = 1, 3
    phi_j = r[:, j].ravel()
    phi_jk = np.concatenate([r[:, j].ravel(), r[:, k].ravel()])
    v = np.array([0.6, 0.8])
    u, w = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    assert mean_statistic(r, j) == pytest.approx(phi_j @ mean_matrix(M, p) @ phi_j)
    assert covariance_statistic(r, j) == pytest.approx(phi_j @ covariance_matrix(M, p) @ phi_j)
    assert covariance_statistic(r, j, v) == pytest.approx(
        phi_j @ covariance_matrix(M, p, v) @ phi_j
    )
    assert correlation_statistic(r, j, k) == pytest.approx(
        phi_jk @ correlation_matrix(M, p) @ phi_jk
    )
    assert correlation_statistic(r, j, k, (u, w)) == pytest.approx(
        phi_jk @ correlation_matrix(M, p, (u, w)) @ phi_jk
    )
    # (2.12)/(2.17): with one orthonormal basis on both sides the projected
    # statistics add up to the trace
    basis = np.linalg.qr(rng.normal(size=(p, p)))[0]
    assert sum(
        correlation_statistic(r, j, k, (basis[:, g], basis[:, g])) for g in range(p)
    ) == pytest.approx(correlation_statistic(r, j, k))
    assert sum(covariance_statistic(r, j, basis[:, g]) for g in range(p)) == pytest.approx(
        covariance_statistic(r, j)
    )


def test_reduced_laws_equal_the_papers_full_quadratic_forms():
    m0, m1 = two_output_pair()
    moments = residual_moments(m0, m1, 6)
    M = 4
    _s, U, W = principal_directions(moments, 1, 4)
    _lam, V = principal_directions(moments, 2)
    cases = [
        ("mean", 2, None, None),
        ("covariance", 2, None, None),
        ("covariance", 2, None, V[:, 1]),
        ("correlation", 1, 4, None),
        ("correlation", 1, 4, (U[:, 0], W[:, 0])),
    ]
    for kind, j, k, direction in cases:
        small = statistic_law(moments, kind, j, M, k=k, direction=direction)
        full = statistic_law(moments, kind, j, M, k=k, direction=direction, full=True)
        x = small.ppf([0.02, 0.3, 0.7, 0.98])
        assert np.max(np.abs(small.cdf(x) - full.cdf(x))) < 1e-9, kind
        assert full.mean() == pytest.approx(small.mean(), rel=1e-9, abs=1e-12)
    assert section_moments(moments, 2, M)[1].shape == (2 * M, 2 * M)
    assert pair_moments(moments, 1, 4, M)[1].shape == (4 * M, 4 * M)


def test_sample_covariance_expectation_has_the_m_minus_one_factor():
    # E c_j = (M - 1)/M tr P_j: with M = 3 forgetting the factor is a 33 % error
    m0, m1 = two_state_system(), reduced_filter()
    N, M, reps = 5, 3, 30_000
    moments = residual_moments(m0, m1, N)
    r = simulate_records(m0, m1, M * reps, N, np.random.default_rng(12)).reshape(reps, M, N, 1)
    values = np.array([covariance_statistic(x, 2) for x in r])
    law = statistic_law(moments, "covariance", 2, M)
    assert law.mean() == pytest.approx((M - 1) / M * np.trace(moments.cov[2]))
    se = values.std() / np.sqrt(reps)
    assert abs(values.mean() - law.mean()) < 4.5 * se
    assert abs(values.mean() - np.trace(moments.cov[2])) > 20 * se


def test_projected_statistics_need_squares_and_an_svd():
    m0, m1 = two_output_pair()
    N, M, reps = 6, 8, 6_000
    moments = residual_moments(m0, m1, N)
    r = simulate_records(m0, m1, M * reps, N, np.random.default_rng(21)).reshape(reps, M, N, 2)
    j, k = 0, 1
    # (2.14) as printed averages the projections themselves: always zero
    lam, V = principal_directions(moments, j)
    dev = r[0, :, j] - r[0, :, j].mean(axis=0)
    assert abs(np.mean(dev @ V[:, 0])) < 1e-12
    # corrected: squared projections, E c_j^(g) = (M-1)/M lambda_g
    values = np.array([covariance_statistic(x, j, V[:, 0]) for x in r])
    assert abs(values.mean() - (M - 1) / M * lam[0]) < 4.5 * values.std() / np.sqrt(reps)
    # (2.7): left/right singular vectors give E c^(g) = (M-1)/M s_g ...
    s, U, W = principal_directions(moments, j, k)
    svd = np.array([correlation_statistic(x, j, k, (U[:, 0], W[:, 0])) for x in r])
    assert abs(svd.mean() - (M - 1) / M * s[0]) < 4.5 * svd.std() / np.sqrt(reps)
    # ... while one set of directions on both sides does not reach s_g
    same = np.array([correlation_statistic(x, j, k, (U[:, 0], U[:, 0])) for x in r])
    assert abs(same.mean() - (M - 1) / M * s[0]) > 10 * same.std() / np.sqrt(reps)
    # (2.13) as printed projects with V_j, i.e. on the ROWS of V_j: for a
    # non-symmetric V_j (here a rotation) that is not a principal direction
    assert np.max(np.abs(V - V.T)) > 0.5
    rows = np.array([covariance_statistic(x, j, V[0]) for x in r])
    assert abs(rows.mean() - (M - 1) / M * lam[0]) > 10 * rows.std() / np.sqrt(reps)
    assert abs(
        rows.mean() - (M - 1) / M * V[0] @ moments.cov[j] @ V[0]
    ) < 4.5 * rows.std() / np.sqrt(reps)


def test_the_mean_law_is_the_quadratic_form_of_the_squared_norm():
    # statistic_law reduces ||rbar||^2 by one eigendecomposition of a non-singular
    # covariance; it is QuadraticForm(I, mean, cov) to rounding, and a singular
    # covariance takes QuadraticForm itself
    from course.mismatched._quadratic_forms import _mean_law

    rng = np.random.default_rng(3)
    for p in (1, 2, 4):
        X = rng.normal(size=(p, p))
        cov, mean = X @ X.T + 0.1 * np.eye(p), rng.normal(size=p)
        fast, general = _mean_law(mean, cov), QuadraticForm(np.eye(p), mean, cov)
        points = np.linspace(0.05, 3.0, 5) * general.mean()
        assert np.allclose(fast.cdf(points), general.cdf(points), rtol=1e-13, atol=1e-15)
    singular = np.array([[1.0, 1.0], [1.0, 1.0]])
    assert isinstance(_mean_law(np.array([1.0, -1.0]), singular), QuadraticForm)


def test_mean_statistic_is_the_squared_norm():
    # (2.6) calls ||rbar_j|| a norm but means rbar_j^T rbar_j: only the
    # square has the quadratic-form law of statistic_law
    m0, m1 = two_state_system(), reduced_filter()
    N, M, reps, j = 6, 10, 3_000, 4
    moments = residual_moments(m0, m1, N)
    r = simulate_records(m0, m1, M * reps, N, np.random.default_rng(41)).reshape(reps, M, N, 1)
    squared = np.array([mean_statistic(x, j) for x in r])
    law = statistic_law(moments, "mean", j, M)
    assert stats.kstest(squared, law.cdf).pvalue > 1e-4
    assert stats.kstest(np.sqrt(squared), law.cdf).pvalue < 1e-12


# ---------------------------------------------------------------------------
# tests: size and power
# ---------------------------------------------------------------------------
def test_false_alarm_rates_and_power_match_the_laws():
    m0, m1 = two_output_pair()
    m2, _ = two_output_pair(scale_r=1.6)  # alternative: noisier sensors
    N, M, reps, alpha = 5, 10, 2_000, 0.1
    null = residual_moments(m0, m1, N)
    alt = residual_moments(m2, m1, N)
    r0 = simulate_records(m0, m1, M * reps, N, np.random.default_rng(31)).reshape(reps, M, N, 2)
    r2 = simulate_records(m2, m1, M * reps, N, np.random.default_rng(32)).reshape(reps, M, N, 2)
    setups = [
        (mean_test, dict(j=2), lambda x: mean_statistic(x, 2)),
        (covariance_test, dict(j=2), lambda x: covariance_statistic(x, 2)),
        (covariance_test, dict(j=2, gamma=0), lambda x: covariance_statistic(x, 2, V[:, 0])),
        (correlation_test, dict(j=1, k=3), lambda x: correlation_statistic(x, 1, 3)),
        (
            correlation_test,
            dict(j=1, k=3, gamma=0),
            lambda x: correlation_statistic(x, 1, 3, (U[:, 0], W[:, 0])),
        ),
    ]
    _, V = principal_directions(null, 2)
    _, U, W = principal_directions(null, 1, 3)
    miss = 1e-4 / (2 * len(setups))

    def rejects(result, values):
        crit = result.critical_value
        if isinstance(crit, tuple):
            return (values < crit[0]) | (values > crit[1])
        return values > crit

    for test, kwargs, statistic in setups:
        # one call gives the critical region and the power from the laws; the
        # replicated decisions then only need the statistic
        first = test(r0[0], null=null, alpha=alpha, power_against=alt, **kwargs)
        assert isinstance(first, TestResult) and 0.0 <= first.pvalue <= 1.0
        assert first.statistic == pytest.approx(statistic(r0[0]))
        size = np.mean(rejects(first, np.array([statistic(x) for x in r0])))
        lo, hi = binomial_band(reps, alpha, miss)
        assert lo <= size <= hi, (test.__name__, kwargs, size)
        rate = np.mean(rejects(first, np.array([statistic(x) for x in r2])))
        lo, hi = binomial_band(reps, first.details["power"], miss)
        assert lo <= rate <= hi, (test.__name__, kwargs, rate, first.details["power"])


def test_power_grows_with_the_number_of_records():
    m0, m1 = two_state_system(), reduced_filter()
    m2 = LinearModel(
        F=m0.F,
        H=m0.H,
        Q=m0.Q,
        R=m0.R,
        x0_mean=m0.x0_mean,
        x0_cov=m0.x0_cov,
        w_mean=m0.w_mean,
        v_mean=[0.8],
    )  # a larger sensor bias
    N = 10
    null, alt = residual_moments(m0, m1, N), residual_moments(m2, m1, N)
    values = [power(null, alt, "mean", 8, M) for M in (5, 20, 80)]
    assert values[0] < values[1] < values[2]
    assert power(null, null, "covariance", 8, 20) == pytest.approx(0.05, abs=1e-8)
    assert power(null, null, "correlation", 3, 20, k=6, alpha=0.1) == pytest.approx(0.1, abs=1e-8)


def test_test_result_fields():
    m0, m1 = two_state_system(), reduced_filter()
    null = residual_moments(m0, m1, 6)
    r = simulate_records(m0, m1, 20, 6, np.random.default_rng(1))
    result = covariance_test(r, 3, null)
    assert isinstance(result.critical_value, tuple) and result.alternative == "two-sided"
    assert result.details["M"] == 20
    assert "covariance test (j=3, M=20)" in result.summary()
    assert repr(result).startswith("TestResult('covariance test")


# ---------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------
def test_errors_for_bad_input():
    m0, m1 = two_state_system(), reduced_filter()
    null = residual_moments(m0, m1, 5)
    r = simulate_records(m0, m1, 4, 5, np.random.default_rng(0))
    p2, _ = two_output_pair()
    with pytest.raises(ValueError, match="same number of outputs"):
        residual_moments(p2, m1, 5)
    with pytest.raises(TypeError, match="LinearModel"):
        residual_moments("model", m1, 5)
    with pytest.raises(ValueError, match="input"):
        residual_moments(LinearModel(F=[[0.5]], H=[[1.0]], Q=[[1.0]], R=[[1.0]], B=[[1.0]]), m1, 5)
    with pytest.raises(ValueError, match="positive integer"):
        residual_moments(m0, m1, 0)
    with pytest.raises(ValueError, match="time index"):
        mean_test(r, 5, null)
    with pytest.raises(ValueError, match="two records"):
        mean_statistic(r[:1], 0)
    with pytest.raises(ValueError, match="shape"):
        mean_statistic(np.zeros(5), 0)
    with pytest.raises(ValueError, match="unit vector"):
        covariance_statistic(r, 0, [2.0])
    with pytest.raises(ValueError, match="null moments"):
        mean_test(r[:, :4], 0, null)
    with pytest.raises(ValueError, match="at least 2"):
        mean_matrix(1, 1)
    with pytest.raises(ValueError, match="second section"):
        statistic_law(null, "correlation", 1, 5)
    with pytest.raises(ValueError, match="kind"):
        statistic_law(null, "variance", 1, 5)
    with pytest.raises(ValueError, match="alternative"):
        covariance_test(r, 1, null, alternative="bigger")
    with pytest.raises(ValueError, match="gamma"):
        covariance_test(r, 1, null, gamma=1)
    with pytest.raises(TypeError, match="ResidualMoments"):
        mean_test(r, 1, null=np.zeros(3))
    assert isinstance(null, ResidualMoments)
    with pytest.raises(ValueError, match=r"cov must have shape \(N, p, p\)"):
        ResidualMoments(null.mean, null.cov[:3], null.cross_cov)
    with pytest.raises(ValueError, match=r"cross_cov must have shape"):
        ResidualMoments(null.mean, null.cov, null.cross_cov[0])
    with pytest.raises(ValueError, match=r"mean must have shape \(N, p\)"):
        ResidualMoments(null.mean.ravel(), null.cov, null.cross_cov)


def test_statistics_at_extreme_scales():
    # residuals ~1e154: the sums of products overflowed (inf, then NaN from inf - inf)
    # where the statistics (~1e307) do not; beyond double precision they are inf, not NaN
    r = np.random.default_rng(0).standard_normal((5, 4, 2))
    uw = ([1.0, 0.0], [0.0, 1.0])
    for c in (1e154, 2.0**-500):
        assert mean_statistic(r * c, 1) / c / c == pytest.approx(mean_statistic(r, 1), rel=1e-14)
        assert covariance_statistic(r * c, 1) / c / c == pytest.approx(
            covariance_statistic(r, 1), rel=1e-14
        )
        assert correlation_statistic(r * c, 1, 2) / c / c == pytest.approx(
            correlation_statistic(r, 1, 2), rel=1e-14
        )
        assert correlation_statistic(r * c, 1, 2, uw) / c / c == pytest.approx(
            correlation_statistic(r, 1, 2, uw), rel=1e-14
        )
    assert correlation_statistic(r * 1e300, 1, 2) == np.inf  # true value ~4e599
    assert covariance_statistic(r * 1e300, 1) == np.inf
