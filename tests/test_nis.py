"""Tests of course.nis: the NIS, the NIS matrix and the exact Wishart extreme-eigenvalue laws.

Reference values come from an independent 80-digit mpmath implementation of
Chiani's Pfaffian in his own monomial basis (tests/nis_reference.py); Monte
Carlo checks use seeded generators and statistical bands (DKW, binomial,
Kolmogorov-Smirnov) at a 1e-4 miss level.
"""

import numpy as np
import pytest
from conftest import binomial_band
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.linalg import LinAlgError
from references import load as load_reference
from scipy import integrate, stats

from course import nis
from course.nis._pfaffians import _pfaffian
from course.results import TestResult

# (m, K, x, P(lmax <= x), P(lmax > x), P(lmin <= x), P(lmin > x)) and
# (m, K, lower, upper, P(all eigenvalues of Pi in [lower, upper])): 80-digit mpmath
# (tests/nis_reference.py), read with their provenance from tests/reference/
EXTREMES = [tuple(row) for row in load_reference("nis_extreme_eigenvalues")["values"]]
BAND = [tuple(row) for row in load_reference("nis_eigenvalue_bands")["values"]]

MISS = 1e-4  # probability that a seeded statistical check fails by chance


def dkw_halfwidth(n, miss=MISS):
    """Dvoretzky-Kiefer-Wolfowitz: P(sup|F_n - F| > eps) <= 2 exp(-2 n eps^2)."""
    return np.sqrt(np.log(2 / miss) / (2 * n))


def random_covariances(rng, count, m):
    A = rng.standard_normal((count, m, m))
    return A @ np.swapaxes(A, -1, -2) + 0.5 * np.eye(m)


def innovations_with(rng, runs, S_true):
    """Innovations N(0, S_true[k]) for every run: (runs, K, m)."""
    L = np.linalg.cholesky(S_true)
    w = rng.standard_normal((runs,) + S_true.shape[:-1])
    return np.einsum("...ij,...j->...i", L, w)


# ---------------------------------------------------------------------------
# exact laws against the high-precision reference
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("row", EXTREMES, ids=lambda r: f"m{r[0]}-K{r[1]}-x{r[2]}")
def test_extreme_laws_match_mpmath_reference(row):
    m, K, x, cdf_max, sf_max, cdf_min, sf_min = row
    law_max, law_min = nis.extreme_eigenvalue(m, K, "max"), nis.extreme_eigenvalue(m, K, "min")
    got = [law_max.cdf(x), law_max.sf(x), law_min.cdf(x), law_min.sf(x)]
    ref = [cdf_max, sf_max, cdf_min, sf_min]
    for value, expected in zip(got, ref):
        assert abs(float(value) - expected) < 1e-12
    # The tails the tests use (upper of lambda_max, lower of lambda_min) keep
    # their relative accuracy however small they are.
    for value, expected in ((got[1], sf_max), (got[2], cdf_min)):
        if expected > 0:
            assert float(value) == pytest.approx(expected, rel=1e-11)


# (m, K, x_max, P(lmax <= x_max), x_min, P(lmin <= x_min)) beyond m = 15 near K = m, where the
# standardised basis returned nonsense; reference: tests/nis_reference.checked_probabilities.
LARGE_M = [
    (16, 16, 3.639, 0.6999839256960453, 2.52e-06, 0.025000511297700978),
    (16, 20, 3.292, 0.6999427294248357, 0.00491, 0.024995477774563346),
    (20, 21, 3.613, 0.6995924047084371, 0.0001206, 0.025007987182601776),
    (24, 30, 3.2095, 0.4994474351944651, 0.005837, 0.025003645065697522),
    (30, 30, 3.778, 0.7000522166700396, 7.064e-07, 0.02499989654495527),
    (30, 45, 3.143, 0.6998165503620835, 0.02351, 0.024997005846662868),
    (30, 60, 2.791, 0.7003092375412757, 0.06841, 0.025002528691742798),
]


@pytest.mark.parametrize("row", LARGE_M, ids=lambda r: f"m{r[0]}-K{r[1]}")
def test_exact_laws_stay_exact_beyond_m_15_near_K_equal_m(row):
    m, K, x_max, cdf_max, x_min, cdf_min = row
    assert float(nis.extreme_eigenvalue(m, K, "max").cdf(x_max)) == pytest.approx(
        cdf_max, abs=1e-12
    )
    assert float(nis.extreme_eigenvalue(m, K, "min").cdf(x_min)) == pytest.approx(
        cdf_min, abs=1e-12
    )


def test_critical_values_beyond_m_15():
    # The 2.5 % point of lambda_min at m = 20, K = 21 (the reference puts P = 0.025 there to
    # 1e-16); the standardised basis gave 0.00306, a lower test alarming ~45 % of the time.
    lower, upper = nis.nis_matrix_critical_values(20, 21)
    assert lower == pytest.approx(1.2056099040138043e-4, rel=1e-8)
    assert float(nis.extreme_eigenvalue(20, 21, "max").sf(upper)) == pytest.approx(0.025, abs=1e-12)


@settings(max_examples=8, deadline=None, derandomize=True)
@given(
    m=st.integers(1, nis.EXACT_LAW_LIMITS["m"]),
    extra=st.floats(0.0, 1.0),
    which=st.sampled_from(["max", "min"]),
    q=st.floats(1e-3, 1 - 1e-3),
)
def test_exact_laws_match_high_precision_reference_over_the_validated_region(m, extra, which, q):
    # The fast grid of the sweep (the full grid is tests/benchmarks/bench_nis.py): any m <= 30,
    # K from m to 2m, any level; the CDF and the quantile against a 30-digit reference.
    pytest.importorskip("mpmath", reason="the reference needs mpmath (the tests extra)")
    import nis_reference as reference

    K = m + round(extra * m)
    law = nis.extreme_eigenvalue(m, K, which)
    x = float(law.ppf(q))
    interval = (0.0, x) if which == "max" else (x, float("inf"))
    inside = reference.checked_probabilities(m, K, [interval])[0]
    truth = inside if which == "max" else 1.0 - inside
    assert abs(float(law.cdf(x)) - truth) <= 1e-8
    assert abs(truth - q) <= 1e-8


def test_exact_laws_refuse_sizes_beyond_the_validated_region():
    largest_m, largest_K = nis.EXACT_LAW_LIMITS["m"], nis.EXACT_LAW_LIMITS["K"]
    for m, K in ((largest_m + 1, 2 * largest_m), (2, largest_K + 1)):
        with pytest.raises(ValueError, match="validated for m <= 30"):
            nis.extreme_eigenvalue(m, K)
        with pytest.raises(ValueError, match="tracy-widom"):
            nis.nis_matrix_critical_values(m, K)
    nis.extreme_eigenvalue(largest_m, largest_K, "min")  # the corner itself is served
    assert nis.extreme_eigenvalue(40, 80, method="tracy-widom").cdf(3.0) > 0


@pytest.mark.parametrize("m, K, lower, upper, expected", BAND)
def test_probability_all_eigenvalues_within_band(m, K, lower, upper, expected):
    assert nis.prob_eigenvalues_within(m, K, lower, upper) == pytest.approx(expected, abs=1e-12)


def test_band_reduces_to_the_extreme_laws():
    m, K = 3, 12
    assert nis.prob_eigenvalues_within(m, K, 0, 1.7) == pytest.approx(
        float(nis.extreme_eigenvalue(m, K, "max").cdf(1.7)), abs=1e-14
    )
    assert nis.prob_eigenvalues_within(m, K, 0.4, np.inf) == pytest.approx(
        float(nis.extreme_eigenvalue(m, K, "min").sf(0.4)), abs=1e-14
    )


@pytest.mark.parametrize("K", [1, 2, 7, 100, 1000])
@pytest.mark.parametrize("which", ["max", "min"])
def test_one_dimension_is_chi_square_over_K(K, which):
    law, ref = nis.extreme_eigenvalue(1, K, which), stats.chi2(K, scale=1.0 / K)
    x = ref.ppf([1e-6, 0.01, 0.3, 0.5, 0.9, 0.999])
    np.testing.assert_allclose(law.cdf(x), ref.cdf(x), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(law.sf(x), ref.sf(x), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(law.pdf(x), ref.pdf(x), rtol=1e-10)
    q = np.array([1e-9, 0.025, 0.5, 0.975])
    np.testing.assert_allclose(law.ppf(q), ref.ppf(q), rtol=1e-10)
    np.testing.assert_allclose(law.isf(q), ref.isf(q), rtol=1e-10)
    assert law.mean() == pytest.approx(1.0, rel=1e-10)
    assert law.var() == pytest.approx(2.0 / K, rel=1e-8)


@pytest.mark.parametrize("m, K", [(2, 2), (3, 9), (5, 60), (6, 1000)])
@pytest.mark.parametrize("which", ["max", "min"])
def test_pdf_is_the_derivative_of_the_cdf(m, K, which):
    law = nis.extreme_eigenvalue(m, K, which)
    x = law.ppf([0.05, 0.3, 0.6, 0.95])
    h = 1e-5 * x
    slope = (law.cdf(x + h) - law.cdf(x - h)) / (2 * h)
    np.testing.assert_allclose(law.pdf(x), slope, rtol=1e-5)


@pytest.mark.parametrize(
    "m, K, which", [(2, 2, "min"), (3, 3, "max"), (4, 25, "min"), (6, 1000, "max")]
)
def test_mean_and_variance_against_numerical_integration(m, K, which):
    law = nis.extreme_eigenvalue(m, K, which)
    lo, hi = float(law.ppf(1e-13)), float(law.isf(1e-13))
    # Independent route: integrate x pdf(x) and x^2 pdf(x) with adaptive quadrature.
    first = integrate.quad(lambda v: v * float(law.pdf(v)), lo, hi, limit=400, epsabs=1e-13)[0]
    second = integrate.quad(lambda v: v * v * float(law.pdf(v)), lo, hi, limit=400, epsabs=1e-13)[0]
    assert law.mean() == pytest.approx(first, rel=1e-7)
    assert law.var() == pytest.approx(second - first**2, rel=1e-5)


def test_quantiles_invert_the_cdf():
    for which in ("max", "min"):
        law = nis.extreme_eigenvalue(4, 30, which)
        q = np.array([1e-8, 0.001, 0.025, 0.5, 0.975, 0.999])
        np.testing.assert_allclose(law.cdf(law.ppf(q)), q, rtol=1e-9)
        np.testing.assert_allclose(law.sf(law.isf(q)), q, rtol=1e-9)
        lo, hi = law.interval(0.95)
        assert float(law.cdf(hi) - law.cdf(lo)) == pytest.approx(0.95, abs=1e-12)


# ---------------------------------------------------------------------------
# large K: naive double precision fails here, the standardised basis does not
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("which", ["max", "min"])
def test_large_K_is_monotone_bounded_and_sensible(which):
    m, K = 6, 1000
    law = nis.extreme_eigenvalue(m, K, which)
    x = np.linspace(0.0, 2.0, 2001)
    F = law.cdf(x)
    assert np.all((F >= 0) & (F <= 1))
    assert np.all(np.diff(F) >= -1e-15)
    assert F[0] == 0.0 and F[-1] == 1.0
    np.testing.assert_allclose(F + law.sf(x), 1.0, atol=1e-14)
    q = law.ppf([0.001, 0.025, 0.5, 0.975, 0.999])
    assert np.all(np.diff(q) > 0)
    # Marchenko-Pastur edges of W/K: (1 +- sqrt(m/K))^2 = 1.16 and 0.85;
    # the extremes fluctuate around them on the scale K^(-2/3).
    edge = (1 + np.sqrt(m / K)) ** 2 if which == "max" else (1 - np.sqrt(m / K)) ** 2
    assert abs(float(q[2]) - edge) < 0.05
    assert np.all(np.isfinite(law.pdf(x))) and np.all(law.pdf(x) >= 0)


def test_very_large_K_still_matches_the_trace_bound():
    # P(lmax > x) <= P(tr W > K x) and P(lmin > x) <= P(tr W > m K x), any K.
    m, K = 5, 20000
    law_max, law_min = nis.extreme_eigenvalue(m, K, "max"), nis.extreme_eigenvalue(m, K, "min")
    trace = stats.chi2(m * K)
    x = np.linspace(0.95, 1.08, 27)
    assert np.all(law_max.sf(x) <= trace.sf(K * x) + 1e-15)
    assert np.all(law_min.sf(x) <= trace.sf(m * K * x) + 1e-15)
    assert 0.97 < float(law_min.ppf(0.5)) < 1.0 < float(law_max.ppf(0.5)) < 1.04


# ---------------------------------------------------------------------------
# Monte Carlo: CDFs, quantiles and the sampler
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("m, K", [(2, 5), (3, 3), (4, 40), (6, 1000)])
def test_cdf_and_quantiles_against_monte_carlo(m, K):
    rng = np.random.default_rng(20240 + 7 * m + K)
    n = 100_000
    lmin, lmax = nis.simulate_extreme_eigenvalues(m, K, n, rng=rng)
    eps = dkw_halfwidth(n)
    for which, sample in (("max", np.sort(lmax)), ("min", np.sort(lmin))):
        law = nis.extreme_eigenvalue(m, K, which)
        grid = np.quantile(sample, np.linspace(0.002, 0.998, 300))
        ecdf = np.searchsorted(sample, grid, side="right") / n
        assert np.max(np.abs(ecdf - law.cdf(grid))) < eps
        for q in (0.025, 0.5, 0.975):
            share = np.mean(sample <= law.ppf(q))
            lo, hi = binomial_band(n, q)
            assert lo <= share <= hi


def test_sampler_matches_direct_wishart_sampling():
    m, K, n = 3, 8, 40_000
    rng = np.random.default_rng(5)
    lmin, lmax = nis.simulate_extreme_eigenvalues(m, K, n, rng=rng)
    X = rng.standard_normal((n, K, m))
    direct = np.linalg.eigvalsh(np.einsum("nki,nkj->nij", X, X) / K)
    assert stats.ks_2samp(lmax, direct[:, -1]).pvalue > MISS
    assert stats.ks_2samp(lmin, direct[:, 0]).pvalue > MISS


def test_rvs_is_seeded_and_shaped():
    law = nis.extreme_eigenvalue(3, 10, "min")
    a = law.rvs(size=(4, 5), rng=np.random.default_rng(3))
    b = law.rvs(size=(4, 5), rng=np.random.default_rng(3))
    assert a.shape == (4, 5) and np.array_equal(a, b) and np.all(a > 0)
    with pytest.raises(TypeError, match="Generator"):
        law.rvs(size=3, rng=np.random.RandomState(0))


def test_monte_carlo_mean_agrees_with_exact_mean():
    law = nis.extreme_eigenvalue(2, 6, "max")
    sample = law.rvs(size=200_000, rng=np.random.default_rng(11))
    se = sample.std() / np.sqrt(sample.size)
    assert abs(sample.mean() - law.mean()) < stats.norm.isf(MISS / 2) * se


# ---------------------------------------------------------------------------
# the fast approximation
# ---------------------------------------------------------------------------
def test_tracy_widom_approximation_is_close_only_for_large_sizes():
    exact = nis.extreme_eigenvalue(6, 1000, "max")
    approx = nis.extreme_eigenvalue(6, 1000, "max", method="tracy-widom")
    x = exact.ppf([0.025, 0.5, 0.975])
    assert np.max(np.abs(approx.cdf(x) - exact.cdf(x))) < 0.03
    # ... but at m = 2, K = 10 it is far off (an honest comparison).
    exact = nis.extreme_eigenvalue(2, 10, "max")
    approx = nis.extreme_eigenvalue(2, 10, "max", method="tracy-widom")
    assert abs(float(approx.cdf(exact.ppf(0.025))) - 0.025) > 0.05


def test_tracy_widom_approximation_is_a_consistent_distribution():
    for which in ("max", "min"):
        approx = nis.extreme_eigenvalue(4, 200, which, method="tracy-widom")
        q = np.array([0.01, 0.5, 0.99])
        np.testing.assert_allclose(approx.cdf(approx.ppf(q)), q, rtol=1e-10)
        np.testing.assert_allclose(approx.sf(approx.isf(q)), q, rtol=1e-10)
        sample = approx.rvs(size=50_000, rng=np.random.default_rng(2))
        assert stats.kstest(sample, approx.cdf).pvalue > MISS
        assert approx.mean() == pytest.approx(
            sample.mean(), abs=5 * sample.std() / np.sqrt(sample.size)
        )
    # Chiani's shifted gamma has the TW1 mean -1.2065 and variance 1.6078.
    g = nis.TW1_GAMMA
    assert g["k"] * g["theta"] - g["alpha"] == pytest.approx(-1.2065, abs=1e-4)
    assert g["k"] * g["theta"] ** 2 == pytest.approx(1.6078, abs=1e-4)
    with pytest.raises(ValueError, match="K > m"):
        nis.extreme_eigenvalue(3, 3, "min", method="tracy-widom")


# ---------------------------------------------------------------------------
# the Pfaffian
# ---------------------------------------------------------------------------
def test_pfaffian_matches_formula_and_determinant():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((4, 4))
    A = A - A.T
    explicit = A[0, 1] * A[2, 3] - A[0, 2] * A[1, 3] + A[0, 3] * A[1, 2]
    assert _pfaffian(A) == pytest.approx(explicit, rel=1e-13)
    B = rng.standard_normal((50, 8, 8))
    B = B - np.swapaxes(B, -1, -2)
    np.testing.assert_allclose(_pfaffian(B) ** 2, np.linalg.det(B), rtol=1e-10)
    assert _pfaffian(np.zeros((3, 3))) == 0.0


# ---------------------------------------------------------------------------
# NIS, NEES and the NIS matrix
# ---------------------------------------------------------------------------
def test_nis_and_nis_matrix_against_dense_computation():
    rng = np.random.default_rng(1)
    K, m = 12, 3
    S = random_covariances(rng, K, m)
    eps = rng.standard_normal((K, m))
    dense = np.array([e @ np.linalg.solve(s, e) for e, s in zip(eps, S)])
    np.testing.assert_allclose(nis.nis(eps, S), dense, rtol=1e-12)
    outer = []
    for e, s in zip(eps, S):
        B = np.linalg.cholesky(s)
        z = np.linalg.solve(B, e)
        outer.append(np.outer(z, z))
    Pi = nis.nis_matrix(eps, S)
    np.testing.assert_allclose(Pi, np.mean(outer, axis=0), rtol=1e-12)
    assert np.trace(Pi) == pytest.approx(dense.mean(), rel=1e-12)  # [F] eq. (4)
    windows = nis.nis_matrix(eps, S, window=5)
    assert windows.shape == (K - 4, m, m)
    for k in range(K - 4):
        np.testing.assert_allclose(windows[k], np.mean(outer[k : k + 5], axis=0), rtol=1e-12)
    lmin, lmax = nis.nis_matrix_eigenvalues(eps, S)
    np.testing.assert_allclose([lmin, lmax], np.linalg.eigvalsh(Pi)[[0, -1]], rtol=1e-12)


def test_nis_matrix_near_the_overflow_threshold():
    # innovations ~1e154: the products z z^T overflow, their average (~1e308) does not
    rng = np.random.default_rng(3)
    K, m = 12, 2
    S = random_covariances(rng, K, m)
    eps = rng.standard_normal((2, K, m))
    eps[1] *= 1e3  # a second run at another scale: each run is scaled on its own
    c = 2.0**511  # ~6.7e153, a power of two: the scaled answers are exact multiples
    Pi = nis.nis_matrix(eps, S)
    np.testing.assert_array_equal(nis.nis_matrix(eps[:1] * c, S)[0] / c / c, Pi[0])
    np.testing.assert_array_equal(nis.nis_matrix(eps * 2.0**-500, S) * 2.0**500 * 2.0**500, Pi)
    windows = nis.nis_matrix(eps[0], S, window=5)
    np.testing.assert_array_equal(nis.nis_matrix(eps[0] * c, S, window=5) / c / c, windows)
    lmin, lmax = nis.nis_matrix_eigenvalues(eps[0], S)
    big = nis.nis_matrix_eigenvalues(eps[0] * c, S)
    np.testing.assert_allclose([big.lmin / c / c, big.lmax / c / c], [lmin, lmax], rtol=1e-14)
    # beyond double precision the answer is inf, never NaN
    assert np.all(nis.nis_matrix(eps[0] * 1e160, S)[[0, 1], [0, 1]] == np.inf)
    assert np.isposinf(nis.nis_matrix_eigenvalues(eps[0] * 1e160, S).lmax)


def test_nis_broadcasts_over_runs_and_a_constant_S():
    rng = np.random.default_rng(2)
    eps = rng.standard_normal((7, 20, 2))
    S = np.array([[2.0, 0.3], [0.3, 1.0]])
    values = nis.nis(eps, S)
    assert values.shape == (7, 20)
    np.testing.assert_allclose(values[3], nis.nis(eps[3], np.broadcast_to(S, (20, 2, 2))))
    assert nis.nis_matrix(eps, S).shape == (7, 2, 2)
    np.testing.assert_allclose(nis.nees(eps, S), values)


def test_nis_does_not_modify_its_input():
    eps = np.ones((4, 2))
    S = np.eye(2) * 2
    before = (eps.copy(), S.copy())
    nis.nis_matrix(eps, S, window=2)
    assert np.array_equal(eps, before[0]) and np.array_equal(S, before[1])


# ---------------------------------------------------------------------------
# corrections to the poster (item 2): K eps ~ chi2(mK), K Pi ~ W_m(K, I)
# ---------------------------------------------------------------------------
def test_corrected_laws_of_the_poster_statistics_by_monte_carlo():
    rng = np.random.default_rng(2024)
    runs, K, m = 20_000, 10, 3
    S = random_covariances(rng, K, m)
    eps = innovations_with(rng, runs, S)
    eps_bar = nis.nis(eps, S).mean(axis=-1)  # the poster's eq. (4), with 1/K
    Pi = nis.nis_matrix(eps, S)  # the poster's eq. (3), with 1/K
    # K eps_bar ~ chi2(mK) ...
    assert stats.kstest(K * eps_bar, stats.chi2(m * K).cdf).pvalue > MISS
    # ... while the poster's literal "eps ~ chi2(mK)" is far off (mean m, not mK).
    assert stats.kstest(eps_bar, stats.chi2(m * K).cdf).pvalue < 1e-12
    # K Pi ~ W_m(K, I): mean K I, Var of diagonal entries 2K, off-diagonal K.
    W = K * Pi
    z = stats.norm.isf(MISS / 2)
    mean_se = np.sqrt(np.where(np.eye(m, dtype=bool), 2 * K, K) / runs)
    assert np.all(np.abs(W.mean(axis=0) - K * np.eye(m)) < z * mean_se)
    diag_var = W[:, np.arange(m), np.arange(m)].var(axis=0)
    np.testing.assert_allclose(diag_var, 2 * K, rtol=0.06)
    assert W[:, 0, 1].var() == pytest.approx(K, rel=0.06)
    # The poster's literal "Pi ~ W_m(K, I)" would put the mean of Pi at K I.
    assert np.all(np.abs(Pi.mean(axis=0).diagonal() - 1.0) < 0.05)
    # And the extreme eigenvalues of Pi follow the exact laws.
    lmin, lmax = np.linalg.eigvalsh(Pi)[:, 0], np.linalg.eigvalsh(Pi)[:, -1]
    assert stats.kstest(lmax, nis.extreme_eigenvalue(m, K, "max").cdf).pvalue > MISS
    assert stats.kstest(lmin, nis.extreme_eigenvalue(m, K, "min").cdf).pvalue > MISS


# ---------------------------------------------------------------------------
# the tests: results, false-alarm rates and power
# ---------------------------------------------------------------------------
def test_nis_test_result_fields():
    rng = np.random.default_rng(3)
    eps = rng.standard_normal((40, 2))
    S = np.eye(2)
    result = nis.nis_test(eps, S, alpha=0.05)
    assert isinstance(result, TestResult)
    assert result.statistic == pytest.approx(float(np.sum(eps**2)))
    assert result.critical_value == pytest.approx(
        (stats.chi2(80).ppf(0.025), stats.chi2(80).isf(0.025))
    )
    assert result.dof == 80 and result.alternative == "two-sided"
    assert result.reject == (result.pvalue <= 0.05)
    assert "chi2(80)" in repr(result)
    # A pessimistic filter (S four times too large) is rejected from below.
    low = nis.nis_test(eps, 4 * S)
    assert low.reject and low.statistic < low.critical_value[0]


def test_nis_matrix_test_result_fields():
    rng = np.random.default_rng(4)
    eps = rng.standard_normal((30, 3))
    result = nis.nis_matrix_test(eps, np.eye(3), alpha=0.1)
    lmin, lmax = np.linalg.eigvalsh(eps.T @ eps / 30)[[0, -1]]
    assert result.statistic == pytest.approx((lmin, lmax))
    lower = float(nis.extreme_eigenvalue(3, 30, "min").ppf(0.05))
    upper = float(nis.extreme_eigenvalue(3, 30, "max").isf(0.05))
    assert result.critical_value == pytest.approx((lower, upper))
    assert result.reject == (result.pvalue <= 0.1)
    assert 0.09 < result.details["exact false-alarm rate"] <= 0.1
    assert repr(result) == repr(nis.nis_matrix_test(eps, np.eye(3), alpha=0.1))
    # One direction too small in S: the largest eigenvalue sees it.
    S = np.diag([1.0, 1.0, 0.2])
    assert nis.nis_matrix_test(eps, S).reject


def test_false_alarm_rates_under_H0():
    rng = np.random.default_rng(6)
    runs, K, m, alpha = 20_000, 25, 2, 0.05
    S = random_covariances(rng, K, m)
    eps = innovations_with(rng, runs, S)
    total = nis.nis(eps, S).sum(axis=-1)
    lo, hi = nis.nis_critical_values(m, K, alpha)
    rate = np.mean((total < lo) | (total > hi))
    band = binomial_band(runs, alpha)
    assert band[0] <= rate <= band[1]
    lmin, lmax = nis.nis_matrix_eigenvalues(eps, S)
    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)
    size = 1 - nis.prob_eigenvalues_within(m, K, lower, upper)
    assert 0.045 < size <= alpha
    rate = np.mean((lmin < lower) | (lmax > upper))
    band = binomial_band(runs, size)
    assert band[0] <= rate <= band[1]
    # The single-record test agrees with the vectorised decision.
    for r in range(40):
        assert nis.nis_matrix_test(eps[r], S, alpha).reject == bool(
            lmin[r] < lower or lmax[r] > upper
        )
        assert nis.nis_test(eps[r], S, alpha).reject == bool(total[r] < lo or total[r] > hi)


def power(rng, S_true, S_filter, K, runs=4000, alpha=0.05):
    m = S_true.shape[-1]
    eps = innovations_with(rng, runs, np.broadcast_to(S_true, (K, m, m)))
    total = nis.nis(eps, S_filter).sum(axis=-1)
    lo, hi = nis.nis_critical_values(m, K, alpha)
    lmin, lmax = nis.nis_matrix_eigenvalues(eps, S_filter)
    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)
    return np.mean((total < lo) | (total > hi)), np.mean((lmin < lower) | (lmax > upper))


def test_matrix_test_wins_when_the_error_is_directional():
    # Too large in one direction, too small in the other: the trace (NIS)
    # hardly moves, the eigenvalues do.
    rng = np.random.default_rng(7)
    p_nis, p_matrix = power(rng, np.diag([1.8, 0.3]), np.eye(2), K=30)
    assert p_nis < 0.2 and p_matrix > 0.8


def test_scalar_nis_wins_when_the_error_scales_S_uniformly():
    rng = np.random.default_rng(8)
    p_nis, p_matrix = power(rng, 1.4 * np.eye(4), np.eye(4), K=30)
    se = np.sqrt(0.25 / 4000)
    assert p_nis - p_matrix > 6 * se


def test_consistency_interval_is_chi_square_over_count():
    lo, hi = nis.consistency_interval(2, 50, alpha=0.05)
    assert lo == pytest.approx(stats.chi2(100).ppf(0.025) / 50)
    assert hi == pytest.approx(stats.chi2(100).isf(0.025) / 50)
    # Run-averaged NIS at one time step over N runs stays inside at rate 1 - alpha.
    rng = np.random.default_rng(9)
    N, steps = 50, 4000
    averages = rng.chisquare(2, size=(steps, N)).mean(axis=1)
    inside = np.mean((averages >= lo) & (averages <= hi))
    band = binomial_band(steps, 0.95)
    assert band[0] <= inside <= band[1]


# ---------------------------------------------------------------------------
# error messages
# ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "args, message",
    [
        ((0, 5), "m .* positive integer"),
        ((3, 2), "K = 2 < m = 3"),
        ((2.5, 5), "m .* integer"),
        ((True, 5), "m .* integer"),
        ((2, 5, "median"), 'which must be "max" or "min"'),
    ],
)
def test_law_arguments_are_checked(args, message):
    with pytest.raises(ValueError, match=message):
        nis.extreme_eigenvalue(*args)


def test_value_errors_of_the_law_methods():
    law = nis.extreme_eigenvalue(2, 5)
    with pytest.raises(ValueError, match="x must be >= 0"):
        law.cdf(-0.1)
    with pytest.raises(ValueError, match="x must be >= 0"):
        law.sf([0.5, -1.0])
    with pytest.raises(ValueError, match="NaN"):
        law.cdf(np.nan)
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        law.ppf(1.5)
    with pytest.raises(ValueError, match="method"):
        nis.extreme_eigenvalue(2, 5, method="saddlepoint")
    with pytest.raises(ValueError, match="lower < upper"):
        nis.prob_eigenvalues_within(2, 5, 1.0, 0.5)
    with pytest.raises(ValueError, match="size must be a non-negative integer"):
        law.rvs(size=-3, rng=np.random.default_rng(0))


def test_statistic_inputs_are_checked():
    eps = np.ones((5, 2))
    with pytest.raises(ValueError, match=r"\(K, m\)"):
        nis.nis(np.ones(5), np.eye(1))
    with pytest.raises(ValueError, match="shape"):
        nis.nis(eps, np.eye(3))
    with pytest.raises(ValueError, match="not symmetric"):
        nis.nis(eps, np.array([[1.0, 0.5], [0.0, 1.0]]))
    with pytest.raises(LinAlgError, match="not positive definite"):
        nis.nis(eps, np.array([[1.0, 2.0], [2.0, 1.0]]))
    with pytest.raises(ValueError, match="NaN"):
        nis.nis(np.array([[np.nan, 0.0]]), np.eye(2))
    with pytest.raises(ValueError, match="window"):
        nis.nis_matrix(eps, np.eye(2), window=6)
    with pytest.raises(ValueError, match="one record"):
        nis.nis_test(np.ones((3, 5, 2)), np.eye(2))
    with pytest.raises(ValueError, match="K = 2 < m = 3"):
        nis.nis_matrix_test(np.ones((2, 3)), np.eye(3))
    with pytest.raises(ValueError, match="alpha"):
        nis.nis_test(eps, np.eye(2), alpha=1.5)


# ---------------------------------------------------------------------------
# the approximation's documented error
# ---------------------------------------------------------------------------
def _documented_tracy_widom_errors():
    """{(which, m, K): error} from the two tables in TracyWidomApproximation's docstring."""
    import re

    doc = nis.TracyWidomApproximation.__doc__
    table = {}
    for which, heading in (("max", "Largest eigenvalue"), ("min", "Smallest eigenvalue")):
        block = doc[doc.index(heading) :]
        rows = re.findall(r"^\s*(\d+)((?:\s+(?:[0-9.]+|n/a)){7})\s*$", block, re.M)[:7]
        assert len(rows) == 7, f"the {which} table must have 7 rows"
        for m_text, values in rows:
            m = int(m_text)
            first = m if which == "max" else m + 1
            for K, value in zip((first, 10, 30, 100, 300, 1000, 10_000), values.split()):
                if value != "n/a":
                    table[(which, m, K)] = float(value)
    return table


def _measured_tracy_widom_error(m, K, which):
    exact = nis.extreme_eigenvalue(m, K, which)
    approx = nis.extreme_eigenvalue(m, K, which, method="tracy-widom")
    x = np.linspace(float(exact.ppf(1e-6)), float(exact.isf(1e-6)), 400)
    return float(np.max(np.abs(exact.cdf(x) - approx.cdf(x))))


@pytest.mark.parametrize(
    "which, m", [(w, m) for w in ("max", "min") for m in (1, 2, 3, 4, 6, 10, 16)]
)
def test_tracy_widom_error_is_what_its_docstring_says(which, m):
    # Every documented entry (the exact law is exact to 1e-13 on the whole table) is
    # measured again: a documented number that is too small OR too large fails.
    table = _documented_tracy_widom_errors()
    entries = {K: err for (w, mm, K), err in table.items() if w == which and mm == m}
    assert len(entries) == (7 if m <= 6 else 6)  # K = 10 < m + 1 is n/a from m = 10
    for K, documented in entries.items():
        measured = _measured_tracy_widom_error(m, K, which)
        assert measured == pytest.approx(documented, rel=0.1, abs=0.001), (which, m, K)
    # and it is never good enough to replace the exact law for a test threshold
    assert min(entries.values()) >= 0.004


# ---------------------------------------------------------------------------
# alarms: NaN only as the undefined start of a record
# ---------------------------------------------------------------------------
def test_empirical_threshold_leaves_out_only_the_undefined_start():
    x = np.arange(1, 1001, dtype=float)
    # a batch of windowed statistics: the undefined start (NaN in every run) is left out ...
    batch = np.vstack([x, x[::-1]])
    batch[:, :3] = np.nan
    assert nis.empirical_threshold(batch, 0.1) == pytest.approx(np.quantile(batch[:, 3:], 0.9))
    # ... but a failed run is refused, not dropped (that would bias the threshold)
    batch[1, 500] = np.nan
    with pytest.raises(ValueError, match=r"null_statistic is NaN at index \(1, 500\)"):
        nis.empirical_threshold(batch, 0.1)


def test_alarm_statistics_refuses_nan_after_the_undefined_start():
    # a run whose filter diverged after the fault used to count as "no alarm"
    T = np.array([[np.nan, 0.0, 0.0, 3.0, 3.0], [np.nan, 0.0, 0.0, np.nan, np.nan]])
    with pytest.raises(ValueError, match=r"statistic is NaN at index \(1, 3\) \(2 NaN"):
        nis.alarm_statistics(T, 1.0, fault_time=3)
    T[1, 3:] = 0.0
    assert nis.alarm_statistics(T, 1.0, fault_time=3).detection_probability == 0.5


def test_the_eigenvalue_laws_answer_beyond_the_range_of_k_x():
    # K x / 2 overflowed (and the Laguerre blocks failed near 1e300): innovations of
    # 1e150-1e154 with S = I raised LinAlgError from inside the laws
    eps = np.random.default_rng(12).standard_normal((10, 3))
    for scale in (1e150, 1e154):
        result = nis.nis_matrix_test(eps * scale, np.eye(3))
        assert np.isfinite(result.statistic).all()
        assert result.reject and result.pvalue == 0.0
    for which in ("max", "min"):
        law = nis.extreme_eigenvalue(3, 10, which)
        x = np.array([1e300, 1.7e308, np.inf])
        assert law.cdf(x).tolist() == [1.0, 1.0, 1.0]
        assert law.sf(x).tolist() == [0.0, 0.0, 0.0]
        assert law.pdf(x[:2]).tolist() == [0.0, 0.0]
    # far below: a p-value of +0.0, not -0.0
    tiny = nis.nis_matrix_test(eps * 1e-160, np.eye(3))
    assert tiny.reject and np.copysign(1.0, tiny.pvalue) == 1.0
