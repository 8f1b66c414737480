"""Tests of course.quadform: Imhof's method, the LTZ approximation, QuadraticForm.

Reference values
----------------
The parameter sets are the 13 test cases (39 points) of Davies' algorithm
AS 155 (Davies 1980, Applied Statistics 29, 323-333).  The first seven are
the cases of Davies' Table 3 (p. 327) that the documentation of the R
package CompQuadForm reproduces (``man/davies.Rd``); cases 1, 2 and 5 are
Imhof's (1961, Biometrika 48, Table 1) forms Q1, Q2 and Q6 with every
weight multiplied by 10 (CompQuadForm ``man/imhof.Rd``).

``DAVIES_CASES`` holds values computed with mpmath (``mp.dps = 30``, stored to
17 digits in ``tests/reference/quadform_davies_cases.json``) by Imhof's original real-axis integral, ``P(Q > x) = 1/2 +
(1/pi) int_0^inf sin(theta(u)) / (u rho(u)) du``, evaluated with
``mpmath.quadosc`` (``python tests/quadform_reference.py --write``) -- an independent
method, not the library's contour integral.  ``DAVIES_PUBLISHED`` holds the
six-decimal output of Davies' own program for the same 39 points (run with
his accuracy ``acc = 1e-4``), as listed in the test suite of hail
(``hail-is/hail``, ``GeneralizedChiSquaredDistributionSuite.scala``).  The
high-precision values agree with them to 1.8e-5, inside Davies' 1e-4.
"""

import math
import warnings

import numpy as np
import pytest
from conftest import binomial_band
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.linalg import LinAlgError
from references import load as load_reference
from scipy import special, stats

from course import quadform
from course.quadform import (
    QuadraticForm,
    WeightedChiSquare,
    _search,
    imhof_cdf,
    imhof_sf,
    inversion_integrands,
    liu_tang_zhang_cdf,
    liu_tang_zhang_sf,
)
from course.quadform._terms import _terms
from course.results import rejection_probability

# (weights, dof, noncentrality): [(c, P(Q <= c)), ...], from tests/reference/ with its provenance
DAVIES_CASES: dict[tuple, list[tuple]] = {}
for *_case, _c, _p in load_reference("quadform_davies_cases")["values"]:
    DAVIES_CASES.setdefault(tuple(map(tuple, _case)), []).append((_c, _p))

# Davies' program output (acc = 1e-4) for the same points, six decimals
DAVIES_PUBLISHED = {
    ((6, 3, 1), (1, 1, 1), (0, 0, 0)): [0.054213, 0.493555, 0.876027],
    ((6, 3, 1), (2, 2, 2), (0, 0, 0)): [0.006435, 0.600208, 0.983897],
    ((6, 3, 1), (6, 4, 2), (0, 0, 0)): [0.002697, 0.564753, 0.991229],
    ((7, 3), (6, 2), (6, 2)): [0.006125, 0.591339, 0.977914],
    ((7, 3), (1, 1), (6, 2)): [0.045126, 0.592431, 0.977648],
    ((7, 3, 7, 3), (6, 2, 1, 1), (6, 2, 6, 2)): [0.043679, 0.584765, 0.953774],
    ((7, 3, -7, -3), (6, 2, 1, 1), (6, 2, 6, 2)): [0.078208, 0.522108, 0.960370],
    ((6, 3, 1), (2, 4, 6), (0, 0, 0)): [0.033357, 0.580446, 0.991283],
    ((6, 3, 1, 12, 6, 2), (6, 4, 2, 2, 4, 6), (0, 0, 0, 0, 0, 0)): [0.010950, 0.654735, 0.984606],
    (
        (6, 3, 1, 6, 3, 1, 7, 3, 7, 3),
        (6, 4, 2, 2, 4, 6, 6, 2, 1, 1),
        (0, 0, 0, 0, 0, 0, 6, 2, 6, 2),
    ): [0.015844, 0.573625, 0.988332],
    ((30, 1), (1, 10), (0, 0)): [0.015392, 0.510819, 0.916340],
    ((30, 1), (1, 20), (0, 0)): [0.004925, 0.573251, 0.896501],
    ((30, 1), (1, 30), (0, 0)): [0.017101, 0.566488, 0.871323],
}


# ---------------------------------------------------------------------------
# published test cases
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("case", list(DAVIES_CASES))
def test_davies_and_imhof_test_cases_to_1e9(case):
    weights, dof, nc = case
    c = np.array([v[0] for v in DAVIES_CASES[case]], float)
    ref = np.array([v[1] for v in DAVIES_CASES[case]])
    cdf, err = imhof_cdf(c, weights, dof, nc, full_output=True)
    assert np.max(np.abs(cdf - ref)) < 1e-9
    assert np.all(err < 1e-9)
    # the survival function is computed separately and must agree
    assert np.max(np.abs(imhof_sf(c, weights, dof, nc) - (1 - ref))) < 1e-9
    # one point at a time gives the same numbers as the vectorised call
    for ci, ri in zip(c, ref):
        assert abs(imhof_cdf(ci, weights, dof, nc) - ri) < 1e-9


def test_published_davies_values_within_his_accuracy():
    # Davies ran AS 155 with acc = 1e-4: his six-decimal output must lie
    # within that of ours (it does, to 1.8e-5)
    worst = 0.0
    for case, published in DAVIES_PUBLISHED.items():
        c = [v[0] for v in DAVIES_CASES[case]]
        worst = max(worst, np.max(np.abs(imhof_cdf(c, *case) - np.array(published))))
    assert worst < 1e-4


def test_imhof_table_forms_are_davies_cases_scaled():
    # Imhof's Q1 = 0.6 chi2(1) + 0.3 chi2(1) + 0.1 chi2(1), P(Q1 > 0.1), P(Q1 > 2)
    sf = imhof_sf([0.1, 0.7, 2.0], [0.6, 0.3, 0.1])
    ref = 1 - np.array([v[1] for v in DAVIES_CASES[((6, 3, 1), (1, 1, 1), (0, 0, 0))]])
    assert np.max(np.abs(sf - ref)) < 1e-9
    # Imhof's Q6 = 0.7 chi2(1, 6) + 0.3 chi2(1, 2)
    sf = imhof_sf([1.0, 6.0, 15.0], [0.7, 0.3], [1, 1], [6, 2])
    ref = 1 - np.array([v[1] for v in DAVIES_CASES[((7, 3), (1, 1), (6, 2))]])
    assert np.max(np.abs(sf - ref)) < 1e-9


def test_real_axis_imhof_agrees_with_contour():
    # Imhof's own integral is practical when k = sum(dof)/2 is not small
    weights, dof, nc = (7, 3, -7, -3), (6, 2, 1, 1), (6, 2, 6, 2)
    c = np.array([-40.0, 40.0, 140.0])
    slow = imhof_cdf(c, weights, dof, nc, method="imhof", atol=1e-11)
    assert np.max(np.abs(slow - imhof_cdf(c, weights, dof, nc))) < 1e-9


def test_real_axis_imhof_refuses_hopeless_truncation():
    # one degree of freedom: Imhof's bound needs U ~ 1/atol^2
    with pytest.raises(ValueError, match="truncation point"):
        imhof_cdf(1.0, [1.0], method="imhof", atol=1e-10)


# ---------------------------------------------------------------------------
# closed forms
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("k", [1, 2, 3, 4, 7, 10, 30])
def test_single_chi_square(k):
    x = np.linspace(0.01, 4 * k + 20, 40)
    assert np.max(np.abs(imhof_cdf(x, [1.0], [k]) - stats.chi2.cdf(x, k))) < 1e-12
    assert np.max(np.abs(imhof_sf(x, [1.0], [k]) - stats.chi2.sf(x, k))) < 1e-12


@pytest.mark.parametrize("k, nc", [(1, 0.5), (3, 2.5), (2, 40.0), (1, 1000.0)])
def test_single_noncentral_chi_square(k, nc):
    mean, sd = k + nc, math.sqrt(2 * (k + 2 * nc))
    x = np.linspace(max(mean - 4 * sd, 0.01), mean + 6 * sd, 25)
    assert np.max(np.abs(imhof_cdf(x, [1.0], [k], [nc]) - stats.ncx2.cdf(x, k, nc))) < 1e-10


def test_equal_weights_sum_to_one_chi_square():
    # 2 chi2(1) + 2 chi2(2) + 2 chi2(3, 1.5) = 2 chi2(6, 1.5)
    x = np.linspace(0.1, 60, 30)
    got = imhof_cdf(x, [2.0, 2.0, 2.0], [1, 2, 3], [0, 0, 1.5])
    assert np.max(np.abs(got - stats.ncx2.cdf(x / 2, 6, 1.5))) < 1e-11
    law = WeightedChiSquare([2.0, 2.0, 2.0], [1, 2, 3], [0, 0, 1.5])
    assert law.weights.tolist() == [2.0] and law.dof.tolist() == [6.0]


def test_two_exponentials_closed_form():
    # chi2(2) = 2 Exp(1): Q = a chi2(2) + b chi2(2) has
    # P(Q > x) = (a e^{-x/2a} - b e^{-x/2b}) / (a - b)
    a, b = 3.0, 0.5
    x = np.linspace(0.01, 60, 30)
    exact = (a * np.exp(-x / (2 * a)) - b * np.exp(-x / (2 * b))) / (a - b)
    assert np.max(np.abs(imhof_sf(x, [a, b], [2, 2]) - exact)) < 1e-12
    # relative accuracy far in the upper tail
    far = np.array([200.0, 400.0])
    exact_far = (a * np.exp(-far / (2 * a)) - b * np.exp(-far / (2 * b))) / (a - b)
    assert np.max(np.abs(imhof_sf(far, [a, b], [2, 2]) / exact_far - 1)) < 1e-8


def test_negative_weight_closed_form():
    # Q = a chi2(2) - b chi2(2): P(Q > x) = a/(a+b) e^{-x/2a} (x >= 0),
    # P(Q <= x) = b/(a+b) e^{x/2b} (x <= 0)
    a, b = 2.0, 0.7
    xp = np.linspace(0.0, 30, 16)
    xn = -np.linspace(0.01, 12, 16)
    assert (
        np.max(np.abs(imhof_sf(xp, [a, -b], [2, 2]) - a / (a + b) * np.exp(-xp / (2 * a)))) < 1e-12
    )
    assert (
        np.max(np.abs(imhof_cdf(xn, [a, -b], [2, 2]) - b / (a + b) * np.exp(xn / (2 * b)))) < 1e-12
    )
    # the lower tail keeps its relative accuracy: computed on -Q
    far = -40.0
    assert abs(imhof_cdf(far, [a, -b], [2, 2]) / (b / (a + b) * math.exp(far / (2 * b))) - 1) < 1e-8


def test_symmetric_difference_is_half_at_zero():
    assert abs(imhof_cdf(0.0, [1.0, -1.0]) - 0.5) < 1e-12
    assert abs(imhof_cdf(0.0, [1.5, -1.5], [3, 3], [2, 2]) - 0.5) < 1e-12


def test_normal_term_alone_and_with_chi_square():
    assert abs(imhof_cdf(0.7, [0.0], sigma=2.0) - stats.norm.cdf(0.35)) < 1e-12
    # chi2(2) + N(0, s^2): P(Q <= x) = Phi(x/s) - exp(-x/2 + s^2/8) Phi(x/s - s/2)
    s = 1.3
    x = np.linspace(-4, 12, 17)
    exact = stats.norm.cdf(x / s) - np.exp(-x / 2 + s**2 / 8) * stats.norm.cdf(x / s - s / 2)
    assert np.max(np.abs(imhof_cdf(x, [1.0], [2], sigma=s) - exact)) < 1e-11


def test_extreme_tails_relative_accuracy():
    assert abs(imhof_sf(200.0, [1.0]) / stats.chi2.sf(200.0, 1) - 1) < 1e-8
    assert abs(imhof_cdf(1e-8, [1.0]) / stats.chi2.cdf(1e-8, 1) - 1) < 1e-8
    assert abs(imhof_cdf(0.01, [1.0], [6]) / stats.chi2.cdf(0.01, 6) - 1) < 1e-8


def test_support_ends_and_shapes():
    assert imhof_cdf(-1.0, [1.0, 2.0]) == 0.0
    assert imhof_sf(-1.0, [1.0, 2.0]) == 1.0
    assert imhof_cdf(1.0, [-1.0, -2.0]) == 1.0
    c = np.array([[1.0, 2.0], [3.0, 4.0]])
    assert imhof_cdf(c, [1.0]).shape == (2, 2)
    assert isinstance(imhof_cdf(1.0, [1.0]), float)


# ---------------------------------------------------------------------------
# Monte Carlo
# ---------------------------------------------------------------------------
def test_mixed_form_against_monte_carlo():
    rng = np.random.default_rng(20240607)
    weights = np.array([2.5, 1.0, -0.8, -3.0, 0.4])
    dof = np.array([1, 3, 2, 1, 5])
    nc = np.array([0.0, 2.0, 0.0, 4.0, 1.0])
    law = WeightedChiSquare(weights, dof, nc, sigma=0.6)
    n = 200_000
    draws = law.rvs(n, rng=rng)
    points = np.quantile(draws, [0.001, 0.02, 0.3, 0.5, 0.8, 0.99, 0.9995])
    cdf = law.cdf(points)
    empirical = (draws[:, None] <= points).mean(axis=0)
    for p, f in zip(cdf, empirical):
        lo, hi = binomial_band(n, p, miss=1e-4 / len(points))
        assert lo <= f <= hi


def test_quadratic_form_against_direct_simulation():
    # x ~ N(mu, S) drawn directly, Q = x^T A x: checks the eigen-reduction
    rng = np.random.default_rng(7)
    n = 6
    A = rng.normal(size=(n, n))
    A = A + A.T
    L = rng.normal(size=(n, n))
    S = L @ L.T / n + 0.1 * np.eye(n)
    mu = rng.normal(size=n)
    form = QuadraticForm(A, mu, S)
    draws = form.rvs_direct(100_000, rng=rng)
    points = np.quantile(draws, [0.005, 0.1, 0.5, 0.9, 0.995])
    cdf = form.cdf(points)
    empirical = (draws[:, None] <= points).mean(axis=0)
    for p, f in zip(cdf, empirical):
        lo, hi = binomial_band(draws.size, p, miss=1e-4 / len(points))
        assert lo <= f <= hi


def test_quadratic_form_singular_covariance_against_simulation():
    # rank-2 covariance in 4 dimensions, mean partly outside its range
    rng = np.random.default_rng(11)
    B = rng.normal(size=(4, 2))
    S = B @ B.T
    A = np.diag([1.0, -2.0, 0.5, 1.5]) + 0.3
    mu = np.array([1.0, -0.5, 2.0, 0.3])
    form = QuadraticForm(A, mu, S)
    assert form.rank == 2
    draws = form.rvs_direct(100_000, rng=rng)
    assert abs(draws.mean() - form.mean()) < 5 * math.sqrt(form.var() / draws.size)
    points = np.quantile(draws, [0.01, 0.3, 0.7, 0.99])
    for p, f in zip(form.cdf(points), (draws[:, None] <= points).mean(axis=0)):
        lo, hi = binomial_band(draws.size, p, miss=1e-4 / len(points))
        assert lo <= f <= hi


def test_singular_covariance_gives_a_normal_term():
    # x = (mu1 + z, mu2): x^T A x = 2 x1 x2 = 2 mu2 (mu1 + z), a normal law
    A = np.array([[0.0, 1.0], [1.0, 0.0]])
    form = QuadraticForm(A, mean=[0.5, 1.5], cov=np.diag([1.0, 0.0]))
    assert form.weights.size == 0
    assert form.sigma == pytest.approx(3.0)
    assert form.offset == pytest.approx(1.5)
    x = np.linspace(-5, 8, 9)
    assert np.max(np.abs(form.cdf(x) - stats.norm.cdf(x, 1.5, 3.0))) < 1e-11


# ---------------------------------------------------------------------------
# QuadraticForm reduction and moments
# ---------------------------------------------------------------------------
def test_reduction_matches_baram_3_17_for_nonsingular_cov():
    # weights: eigenvalues of S^1/2 A S^1/2; delta_k = p_k^T S^{-1/2} m
    rng = np.random.default_rng(3)
    A = rng.normal(size=(4, 4))
    A = A + A.T
    B = rng.normal(size=(4, 4))
    S = B @ B.T + np.eye(4)
    m = rng.normal(size=4)
    e, V = np.linalg.eigh(S)
    root = (V * np.sqrt(e)) @ V.T
    lam, P = np.linalg.eigh(root @ A @ root)
    delta = P.T @ np.linalg.solve(root, m)
    form = QuadraticForm(A, m, S)
    order = np.argsort(lam)
    assert np.allclose(form.weights, lam[order])
    assert np.allclose(form.noncentrality, delta[order] ** 2)
    assert form.sigma == 0.0 and abs(form.offset) < 1e-12


def test_mean_and_variance_closed_forms_agree_with_cumulants():
    rng = np.random.default_rng(5)
    A = rng.normal(size=(5, 5))
    A = A + A.T
    B = rng.normal(size=(5, 3))
    S = B @ B.T
    m = rng.normal(size=5)
    form = QuadraticForm(A, m, S)
    assert form.mean() == pytest.approx(WeightedChiSquare.mean(form), rel=1e-10, abs=1e-10)
    assert form.var() == pytest.approx(WeightedChiSquare.var(form), rel=1e-10)
    assert form.mean() == pytest.approx(np.trace(A @ S) + m @ A @ m)


def test_pdf_against_chi2_and_derivative_of_cdf():
    x = np.linspace(0.05, 15, 20)
    for k in (1, 2, 5):
        assert np.max(np.abs(WeightedChiSquare([1.0], [k]).pdf(x) - stats.chi2.pdf(x, k))) < 1e-11
    law = WeightedChiSquare([2.0, -1.0, 0.5], [1, 2, 3], [0.5, 0, 2], sigma=0.3)
    xx = np.linspace(-8, 15, 9)
    numeric = (law.cdf(xx + 1e-4) - law.cdf(xx - 1e-4)) / 2e-4
    assert np.max(np.abs(law.pdf(xx) - numeric)) < 1e-7


def test_quantiles_invert_the_distribution_function():
    law = WeightedChiSquare([2.0, -1.0, 0.5], [1, 2, 3], [0.5, 0, 2], sigma=0.3)
    q = np.array([1e-6, 0.01, 0.5, 0.99])
    assert np.allclose(law.cdf(law.ppf(q)), q, rtol=1e-8, atol=1e-12)
    assert np.allclose(law.sf(law.isf(q)), q, rtol=1e-8, atol=1e-12)
    chi = WeightedChiSquare([1.0], [3])
    assert chi.isf(0.05) == pytest.approx(stats.chi2.isf(0.05, 3), rel=1e-10)
    assert chi.ppf(0.01) == pytest.approx(stats.chi2.ppf(0.01, 3), rel=1e-9)


def test_rvs_is_reproducible_and_has_the_right_moments():
    law = WeightedChiSquare([1.0, -0.5], [2, 3], [1.0, 0.0], sigma=0.2, offset=1.0)
    a = law.rvs(1000, rng=np.random.default_rng(1))
    b = law.rvs(1000, rng=np.random.default_rng(1))
    assert np.array_equal(a, b)
    big = law.rvs(200_000, rng=np.random.default_rng(2))
    assert abs(big.mean() - law.mean()) < 5 * law.std() / math.sqrt(big.size)


# ---------------------------------------------------------------------------
# the Liu-Tang-Zhang approximation
# ---------------------------------------------------------------------------
def test_ltz_is_exact_for_one_scaled_chi_square():
    x = np.linspace(0.1, 30, 10)
    assert np.allclose(liu_tang_zhang_cdf(x, [2.0], [4]), stats.chi2.cdf(x / 2, 4), atol=1e-14)
    assert np.allclose(liu_tang_zhang_sf(x, [2.0], [4]), stats.chi2.sf(x / 2, 4), atol=1e-14)


def test_ltz_is_close_in_the_body_but_fails_in_the_lower_tail():
    # an honest measure on Davies' cases: the middle points (c near the
    # median) are within 0.02 absolute, but the lower-tail points of the
    # low-dof forms are wrong by up to 100 % relative (LTZ puts no mass there)
    middle, lower = [], []
    for (weights, dof, nc), values in DAVIES_CASES.items():
        c = np.array([v[0] for v in values], float)
        ref = np.array([v[1] for v in values])
        approx = liu_tang_zhang_cdf(c, weights, dof, nc)
        middle.append(abs(approx[1] - ref[1]))
        lower.append(abs(approx[0] / ref[0] - 1))
    assert max(middle) < 0.02
    assert max(lower) > 0.5  # e.g. 0.0542 for case 1 where LTZ gives 0
    assert max(middle) > 1e-3  # and far from Imhof's 1e-9 in the body too


# ---------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------
def test_errors_for_bad_input():
    with pytest.raises(ValueError, match="not symmetric"):
        QuadraticForm([[1.0, 2.0], [0.0, 1.0]])
    with pytest.raises(LinAlgError, match="positive semi-definite"):
        QuadraticForm(np.eye(2), cov=[[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(ValueError, match="square"):
        QuadraticForm(np.ones((2, 3)))
    with pytest.raises(ValueError, match="length 2"):
        QuadraticForm(np.eye(2), mean=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="shape"):
        QuadraticForm(np.eye(2), cov=np.eye(3))
    with pytest.raises(ValueError, match="NaN"):
        QuadraticForm(np.eye(2), mean=[np.nan, 0.0])
    with pytest.raises(ValueError, match="constant"):
        QuadraticForm(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="same length"):
        imhof_cdf(1.0, [1.0, 2.0], [1, 1, 1])
    with pytest.raises(ValueError, match="positive"):
        imhof_cdf(1.0, [1.0], [0])
    with pytest.raises(ValueError, match="non-negative"):
        imhof_cdf(1.0, [1.0], [1], [-1.0])
    with pytest.raises(ValueError, match="method"):
        imhof_cdf(1.0, [1.0], method="davies")


# ---------------------------------------------------------------------------
# the measured error of the Liu-Tang-Zhang approximation (as documented)
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("mixed, bound", [(False, 0.03), (True, 0.11)])
def test_ltz_error_in_the_body_is_within_its_documented_bound(mixed, bound):
    # the family of liu_tang_zhang_sf's docstring, where 0.01 <= P <= 0.99
    rng = np.random.default_rng(int(mixed))
    worst = 0.0
    for _ in range(40):
        r = int(rng.integers(1, 6))
        w = rng.uniform(0.1, 5, r)
        if mixed:
            w *= rng.choice([-1.0, 1.0], r)
            w[0] = -np.sign(w[-1]) * abs(w[0]) if r > 1 else w[0]
        h = rng.integers(1, 6, r).astype(float)
        d = rng.uniform(0, 5, r) * (rng.random(r) < 0.5)
        law = WeightedChiSquare(w, h, d)
        grid = law.mean() + law.std() * np.linspace(-4, 6, 41)
        exact = law.cdf(grid)
        body = (exact >= 0.01) & (exact <= 0.99)
        worst = max(worst, np.max(np.abs(liu_tang_zhang_cdf(grid, w, h, d) - exact)[body]))
    assert worst <= bound
    assert worst > bound / 20  # an approximation, not an exact law


def test_ltz_has_no_overflow_at_huge_scales():
    # OverflowError before: the cumulants of sigma = 1e300 were squared in floats
    assert liu_tang_zhang_cdf(1.0, [1.0], sigma=1e300) == pytest.approx(0.5)
    x = np.array([0.5, 2.0, 7.0])
    small = liu_tang_zhang_cdf(x, [2.0, 1.0])
    assert np.allclose(liu_tang_zhang_cdf(x * 1e300, [2e300, 1e300]), small, rtol=1e-12)
    assert np.allclose(liu_tang_zhang_sf(x * 1e-300, [2e-300, 1e-300]), 1 - small, rtol=1e-12)


# ---------------------------------------------------------------------------
# floating-point extremes: never NaN, never an overflow warning
# ---------------------------------------------------------------------------
SCALES = [1e-300, 1e-150, 1e150, 1e300]


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("scale", SCALES)
def test_laws_are_scale_invariant_down_to_the_limits_of_doubles(scale):
    weights, dof, nc = np.array([2.0, -1.0, 0.5]), [1, 3, 2], [0.5, 0.0, 1.0]
    x = np.array([-6.0, -0.3, 0.0, 0.2, 4.0, 40.0])
    reference = imhof_cdf(x, weights, dof, nc, sigma=0.3)
    got = imhof_cdf(x * scale, weights * scale, dof, nc, sigma=0.3 * scale)
    assert np.allclose(got, reference, rtol=1e-9, atol=1e-14)
    assert np.allclose(
        imhof_sf(x * scale, weights * scale, dof, nc, sigma=0.3 * scale), 1 - reference, atol=1e-12
    )
    law = WeightedChiSquare(weights * scale, dof, nc, sigma=0.3 * scale)
    assert np.allclose(law.cdf(x * scale), reference, rtol=1e-9, atol=1e-14)
    assert law.isf(0.01) == pytest.approx(
        WeightedChiSquare(weights, dof, nc, sigma=0.3).isf(0.01) * scale, rel=1e-8
    )


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("terms", [2, 30])  # merged in Python floats (a few terms) and in numpy
def test_equal_weights_near_the_largest_double_merge(terms):
    # OverflowError ("intermediate overflow in fsum") or an overflow warning and an
    # infinite weight before: the merged weight was sum(w h) / sum(h), and w h overflowed
    scale = 1e308 if terms == 2 else 1e307
    weights = np.full(terms, scale)
    weights[0] *= 1 - 1e-14  # nearly equal weights merge too
    x = np.array([0.2, 0.5, 1.5]) if terms == 2 else np.array([5.0, 10.0, 15.0])  # x scale finite
    reference = stats.chi2.cdf(x, terms)
    assert np.allclose(imhof_cdf(x * scale, weights), reference, rtol=1e-9)
    assert np.allclose(imhof_cdf(x * scale, list(weights)), reference, rtol=1e-9)
    law = WeightedChiSquare(list(weights))
    assert law.weights.size == 1 and law.weights[0] == pytest.approx(scale, rel=1e-13)
    assert law.dof[0] == terms


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("scale", SCALES)
def test_quadratic_form_is_scale_invariant_in_A_and_cov(scale):
    rng = np.random.default_rng(4)
    A = rng.normal(size=(3, 3))
    A = A + A.T
    B = rng.normal(size=(3, 3))
    S = B @ B.T + 0.1 * np.eye(3)
    mu = rng.normal(size=3)
    x = np.array([-3.0, 0.0, 2.0, 10.0])
    reference = QuadraticForm(A, mu, S).cdf(x)
    # A scaled: Q scales; cov scaled by s^2 and mean by s: Q scales by s^2
    assert np.allclose(QuadraticForm(A * scale, mu, S).cdf(x * scale), reference, atol=1e-12)
    root = math.sqrt(scale)
    assert np.allclose(QuadraticForm(A, mu * root, S * scale).cdf(x * scale), reference, atol=1e-12)


def test_quadratic_form_beyond_double_precision_is_refused_clearly():
    with pytest.raises(ValueError, match="beyond double precision"):
        QuadraticForm(np.eye(2) * 1e300, cov=np.eye(2) * 1e300)
    with pytest.raises(ValueError, match="empty"):
        QuadraticForm(np.zeros((0, 0)))


@pytest.mark.filterwarnings("error")
def test_imhof_near_zero_and_far_in_the_tails():
    # NaN before: the saddle point of 5 chi2_1 at 1e-300 overflowed
    assert imhof_cdf(1e-300, [5.0]) == pytest.approx(stats.chi2.cdf(2e-301, 1), rel=1e-12)
    x = np.array([1e-300, 1e-200, 1e-100, 1e-20, 1e-8])
    assert np.allclose(imhof_cdf(x, [1.0], [6]), stats.chi2.cdf(x, 6), rtol=1e-10, atol=0)
    assert imhof_cdf(0.0, [1.0, 2.0]) == 0.0
    # upper tails down to 1e-300 keep their relative accuracy, then underflow to 0
    x = np.array([50.0, 300.0, 800.0, 1300.0, 1380.0])
    assert np.allclose(imhof_sf(x, [1.0]), stats.chi2.sf(x, 1), rtol=1e-8, atol=0)
    assert np.allclose(imhof_sf(x, [1.0], [4]), stats.chi2.sf(x, 4), rtol=1e-8, atol=0)
    assert imhof_sf(1e4, [1.0]) == 0.0 and imhof_sf(1e300, [1.0]) == 0.0
    assert imhof_cdf(np.inf, [1.0, -1.0]) == 1.0 and imhof_cdf(-np.inf, [1.0, -1.0]) == 0.0
    # lower tail of a mixed form far below zero
    a, b = 2.0, 0.7
    far = -np.array([50.0, 400.0, 900.0])
    exact = b / (a + b) * np.exp(far / (2 * b))
    assert np.allclose(imhof_cdf(far, [a, -b], [2, 2]), exact, rtol=1e-8, atol=0)


@pytest.mark.filterwarnings("error")
def test_normal_term_dominating_the_weights():
    # a weight of 1e-300 beside sigma = 1: the normal law to double precision
    x = np.array([-2.0, 0.0, 1.5])
    assert np.allclose(imhof_cdf(x, [1e-300, -1e-300], sigma=1.0), stats.norm.cdf(x), atol=1e-15)
    assert imhof_cdf(0.0, [1.0, -1.0], sigma=1e300) == pytest.approx(0.5)


def test_inversion_integrands_refuses_a_nan_point():
    # silently NaN arrays before
    with pytest.raises(ValueError, match="c must be finite"):
        inversion_integrands(np.nan, [1.0])
    _real_axis, contour, tail = inversion_integrands(20.0, [6.0, 3.0, 1.0])
    u = np.linspace(0.0, 10.0, 401)
    # the contour integral reproduces the tail probability (upper here)
    assert tail == "upper"
    from scipy.integrate import trapezoid  # numpy < 2 (a supported floor) has no np.trapezoid

    assert trapezoid(contour, u) / np.pi == pytest.approx(imhof_sf(20.0, [6, 3, 1]), rel=1e-6)


# ---------------------------------------------------------------------------
# accuracy on demand
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8, quadform.RTOL, 1e-12])
def test_requested_relative_accuracy_is_met_on_davies_cases(rtol):
    # the smaller tail is the one integrated: its relative error is below rtol
    for (weights, dof, nc), values in DAVIES_CASES.items():
        c = np.array([v[0] for v in values], float)
        ref = np.array([v[1] for v in values])
        small = np.minimum(ref, 1 - ref)
        cdf = imhof_cdf(c, weights, dof, nc, rtol=rtol)
        got = np.where(ref < 0.5, cdf, 1 - cdf)
        assert np.all(np.abs(got - small) <= rtol * small + 2e-16)
        # one point at a time: the same accuracy
        scalar = np.array([imhof_cdf(ci, weights, dof, nc, rtol=rtol) for ci in c])
        got = np.where(ref < 0.5, scalar, 1 - scalar)
        assert np.all(np.abs(got - small) <= rtol * small + 2e-16)


def test_a_frozen_law_at_one_python_number_agrees_with_its_array_path():
    # one plain number takes Python floats (law.cdf(c) in a loop is the usual
    # use); it must give the array path's numbers, types and refusals
    law = WeightedChiSquare([7.0, 3.0, -2.0], [6, 2, 1], [6.0, 2.0, 0.5], offset=1.5, rtol=1e-8)
    for c in (-30.0, 0.0, 1.5, 20, 140.0):
        cdf, sf = law.cdf(c), law.sf(c)
        assert type(cdf) is np.float64 and type(sf) is np.float64
        assert cdf == pytest.approx(float(law.cdf(np.array([c]))[0]), rel=1e-12, abs=1e-300)
        assert sf == pytest.approx(float(law.sf(np.array([c]))[0]), rel=1e-12, abs=1e-300)
    positive = WeightedChiSquare([2.0, 1.0], offset=1.0)
    assert positive.cdf(1.0) == 0.0 and positive.sf(0.5) == 1.0 and positive.cdf(math.inf) == 1.0
    with pytest.raises(ValueError, match="NaN"):
        positive.cdf(math.nan)
    with pytest.raises(ValueError, match="rtol"):
        WeightedChiSquare([1.0], rtol=-1e-6)


def test_many_weights_agree_with_monte_carlo():
    rng = np.random.default_rng(9)
    w = np.concatenate([rng.uniform(0.1, 2, 30), -rng.uniform(0.1, 1, 10)])
    dof = rng.integers(1, 4, 40)
    nc = rng.uniform(0, 1, 40)
    x = np.array([-5.0, 0.0, 10.0, 40.0])
    numpy_path = imhof_cdf(x, w, dof, nc)
    law = WeightedChiSquare(w, dof, nc)
    draws = law.rvs(100_000, rng=rng)
    for p, f in zip(numpy_path, (draws[:, None] <= x).mean(axis=0)):
        lo, hi = binomial_band(draws.size, p, miss=1e-4 / x.size)
        assert lo <= f <= hi


def test_every_container_of_the_same_terms_gives_the_same_law():
    # lists, tuples, arrays, ints, numpy scalars and float32 give the same terms
    expected = _terms(np.array([3.0, -1.0, 3.0]), np.array([1.0, 2.0, 2.0]), [0.5, 0, 1])
    assert [a.tolist() for a in expected[:3]] == [[-1.0, 3.0], [2.0, 3.0], [0.0, 1.5]]
    containers = [
        ([3, -1, 3], [1, 2, 2], [0.5, 0, 1]),
        ((3.0, -1.0, 3.0), (1, 2, 2), (0.5, 0.0, 1.0)),
        (np.array([3, -1, 3]), np.array([1, 2, 2], dtype=np.int32), [np.float64(0.5), 0.0, 1]),
        ([3.0, -1.0, 3.0], [1.0, 2.0, 2.0], np.array([0.5, 0.0, 1.0], dtype=np.float32)),
        ([True * 3.0, -1.0, 3.0], [True, 2, 2], [0.5, False, 1.0]),
    ]
    reference = imhof_cdf(2.0, *expected[:3])
    for weights, dof, nc in containers:
        terms = _terms(weights, dof, nc)
        assert all(np.array_equal(a, b) for a, b in zip(terms, expected))
        assert imhof_cdf(2.0, weights, dof, nc) == reference


def test_tolerances_that_cannot_be_met_are_refused():
    with pytest.raises(ValueError, match="cannot be met"):
        imhof_cdf(1.0, [1.0], rtol=1e-18)
    with pytest.raises(ValueError, match="not both 0"):
        imhof_cdf(1.0, [1.0], rtol=0.0)
    # an absolute tolerance alone is accepted
    assert imhof_cdf(2.0, [1.0], rtol=0.0, atol=1e-9) == pytest.approx(
        stats.chi2.cdf(2.0, 1), abs=1e-9
    )


# ---------------------------------------------------------------------------
# property-based tests
# ---------------------------------------------------------------------------
_weight = st.floats(-5, 5).filter(lambda v: abs(v) > 0.01)
_laws = st.tuples(
    st.lists(_weight, min_size=1, max_size=5),
    st.lists(st.integers(1, 6), min_size=5, max_size=5),
    st.lists(st.sampled_from([0.0, 0.0, 0.5, 3.0]), min_size=5, max_size=5),
    st.sampled_from([0.0, 0.0, 0.7]),
)
_settings = settings(max_examples=60, deadline=None, derandomize=True)


def _law_terms(law):
    weights, dof, nc, sigma = law
    r = len(weights)
    return np.array(weights), np.array(dof[:r], float), np.array(nc[:r]), sigma


@_settings
@given(_laws, st.lists(st.floats(-10, 30), min_size=2, max_size=6))
def test_property_cdf_is_a_probability_and_monotone(law, points):
    weights, dof, nc, sigma = _law_terms(law)
    x = np.sort(np.array(points))
    cdf = imhof_cdf(x, weights, dof, nc, sigma=sigma)
    assert np.all(np.isfinite(cdf)) and np.all((cdf >= 0) & (cdf <= 1))
    # monotone up to the requested accuracy
    assert np.all(np.diff(cdf) >= -1e-9)
    sf = imhof_sf(x, weights, dof, nc, sigma=sigma)
    assert np.allclose(cdf + sf, 1.0, atol=1e-12)


@_settings
@given(_laws, st.floats(-10, 30), st.sampled_from([1e-200, 1e-7, 3.0, 1e7, 1e200]))
def test_property_scale_invariance(law, point, scale):
    weights, dof, nc, sigma = _law_terms(law)
    base = imhof_cdf(point, weights, dof, nc, sigma=sigma)
    scaled = imhof_cdf(point * scale, weights * scale, dof, nc, sigma=sigma * scale)
    assert abs(scaled - base) <= 1e-9 * min(base, 1 - base) + 1e-14


@_settings
@given(
    st.floats(0.05, 20), st.integers(1, 4), st.integers(1, 8), st.floats(0, 5), st.floats(0.0, 60)
)
def test_property_equal_weights_give_a_scaled_chi_square(weight, copies, dof, nc, point):
    # copies equal terms w chi2(dof, nc/copies) = w chi2(copies dof, nc)
    w = [weight] * copies
    got = imhof_cdf(point, w, [dof] * copies, [nc / copies] * copies)
    exact = (
        stats.ncx2.cdf(point / weight, copies * dof, nc)
        if nc
        else stats.chi2.cdf(point / weight, copies * dof)
    )
    assert got == pytest.approx(exact, abs=1e-10)


@settings(max_examples=8, deadline=None, derandomize=True)
@given(_laws)
def test_property_agrees_with_monte_carlo(law):
    weights, dof, nc, sigma = _law_terms(law)
    wcs = WeightedChiSquare(weights, dof, nc, sigma=sigma)
    rng = np.random.default_rng(abs(hash(repr(law))) % 2**32)
    draws = wcs.rvs(40_000, rng=rng)
    points = np.quantile(draws, [0.05, 0.5, 0.95])
    for p, f in zip(wcs.cdf(points), (draws[:, None] <= points).mean(axis=0)):
        lo, hi = binomial_band(draws.size, p, miss=1e-6)
        assert lo <= f <= hi


# ---------------------------------------------------------------------------
# every public function refuses bad input with a clear error naming the argument
# ---------------------------------------------------------------------------
_W = [2.0, -1.0, 0.5]
BAD_CALLS = [
    ("c", lambda: imhof_cdf(np.nan, _W)),
    ("c", lambda: imhof_sf([1.0, np.nan], _W)),
    ("c", lambda: imhof_cdf(None, _W)),
    ("c", lambda: imhof_cdf("one", _W)),
    ("weights", lambda: imhof_cdf(1.0, None)),
    ("weights", lambda: imhof_cdf(1.0, [])),
    ("weights", lambda: imhof_cdf(1.0, [1.0, np.inf])),
    ("weights", lambda: imhof_cdf(1.0, [[1.0, 2.0]])),
    ("weights", lambda: imhof_cdf(1.0, [1.0 + 2j])),
    ("weights", lambda: imhof_cdf(1.0, np.array([1.0 + 0j]))),
    ("weights", lambda: imhof_cdf(1.0, [10**400])),  # OverflowError before
    ("dof", lambda: imhof_cdf(1.0, [1.0], 10**400)),
    ("dof", lambda: imhof_cdf(1.0, _W, [1, 2])),
    ("dof", lambda: imhof_cdf(1.0, _W, [1, 0, 2])),
    ("dof", lambda: imhof_cdf(1.0, _W, [1, -2, 2])),
    ("dof", lambda: imhof_sf(1.0, _W, [1, np.nan, 2])),
    ("noncentrality", lambda: imhof_cdf(1.0, _W, None, [0.0, -1.0, 0.0])),
    ("noncentrality", lambda: imhof_cdf(1.0, _W, None, [0.0, 1.0])),
    ("sigma", lambda: imhof_cdf(1.0, _W, sigma=-1.0)),
    ("sigma", lambda: imhof_cdf(1.0, _W, sigma=np.nan)),
    ("sigma", lambda: imhof_cdf(1.0, _W, sigma=[1.0, 2.0])),
    ("rtol", lambda: imhof_cdf(1.0, _W, rtol=-1e-6)),
    ("atol", lambda: imhof_cdf(1.0, _W, atol=np.nan)),
    ("method", lambda: imhof_cdf(1.0, _W, method="davies")),
    ("weights", lambda: liu_tang_zhang_cdf(1.0, [np.nan])),
    ("x", lambda: liu_tang_zhang_sf([np.inf], _W)),
    ("c", lambda: liu_tang_zhang_cdf(None, _W)),
    ("c", lambda: inversion_integrands(np.nan, _W)),
    ("c", lambda: inversion_integrands(-1.0, _W)),
    ("u", lambda: inversion_integrands(1.0, _W, u=[0.0, np.nan])),
    ("weights", lambda: WeightedChiSquare([])),
    ("dof", lambda: WeightedChiSquare(_W, dof=[1, 1, -1])),
    ("offset", lambda: WeightedChiSquare(_W, offset=np.inf)),
    ("x", lambda: WeightedChiSquare(_W).cdf(np.nan)),
    ("probabilities", lambda: WeightedChiSquare(_W).ppf(1.5)),
    ("size", lambda: WeightedChiSquare(_W).rvs(2.5)),
    ("size", lambda: WeightedChiSquare(_W).rvs(-1)),
    ("cumulant", lambda: WeightedChiSquare(_W).cumulant(2.5)),
    ("A", lambda: QuadraticForm(None)),
    ("A", lambda: QuadraticForm(np.zeros((0, 0)))),
    ("A", lambda: QuadraticForm([[1.0, np.nan], [np.nan, 1.0]])),
    ("A", lambda: QuadraticForm([1.0, 2.0])),
    ("mean", lambda: QuadraticForm(np.eye(2), mean=[1.0])),
    ("cov", lambda: QuadraticForm(np.eye(2), cov=[[1.0, 0.0], [0.0, np.inf]])),
    ("cov", lambda: QuadraticForm(np.eye(2), cov=[[1.0, 2.0], [0.0, 1.0]])),
    ("cov", lambda: QuadraticForm(np.eye(2), cov=[[1.0, 2.0], [2.0, 1.0]])),
    ("size", lambda: QuadraticForm(np.eye(2)).rvs_direct(2.5)),
]


@pytest.mark.parametrize(
    "name, call", BAD_CALLS, ids=[f"{i}-{n}" for i, (n, _) in enumerate(BAD_CALLS)]
)
def test_bad_input_is_refused_naming_the_argument(name, call):
    with pytest.raises((ValueError, LinAlgError)) as info:
        call()
    message = str(info.value)
    assert name in message or name.rstrip("s") in message


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("rtol", [1e-4, 1e-10])
def test_normal_term_at_zero_with_few_degrees_of_freedom(rtol):
    # chi2_{1/2} + N(0, 1) at 0: the tail bound without the normal factor ran
    # past its limit (a warning); P = E[Phi(-Y)], Y ~ chi2_{1/2}
    from scipy import integrate

    exact = integrate.quad(lambda y: stats.norm.cdf(-y) * stats.chi2.pdf(y, 0.5), 0, np.inf)[0]
    assert imhof_cdf(0.0, [1.0], [0.5], sigma=1.0, rtol=rtol) == pytest.approx(
        exact, rel=max(rtol, 1e-8)
    )


@pytest.mark.filterwarnings("error")
def test_small_positive_weight_with_large_noncentrality():
    # found by a hypothesis hunt: the truncation bound in Re s assumed
    # |1 - 2 w s| >= w Re s for every positive weight, which fails for a small
    # one (2e-4 beside 18.5, noncentrality 8505): the integral was cut early
    weights = [-27.835, -2.054, 2.1568e-4, 18.548]
    nc = [0.0073, 0.2514, 8504.75, 0.11496]
    law = WeightedChiSquare(weights, noncentrality=nc)
    rng = np.random.default_rng(12)
    draws = law.rvs(200_000, rng=rng)
    points = np.array([-80.0, 0.0, 65.9, 139.8])
    for p, f in zip(law.cdf(points), (draws[:, None] <= points).mean(axis=0)):
        lo, hi = binomial_band(draws.size, p, miss=1e-4 / points.size)
        assert lo <= f <= hi
    assert law.sf(139.8) == pytest.approx(imhof_sf(139.8, weights, 1, nc, rtol=1e-12), rel=1e-9)


@pytest.mark.filterwarnings("error")
def test_drift_of_small_noncentral_weights_takes_a_vertical_path():
    # found by a hypothesis hunt: below the drift d w of a small noncentral
    # term, exp(d w s) outgrows exp(-s x) along a path opening to the right
    # (values of 1e172 cancelling): such points take a nearly vertical path
    weights, dof = [0.5, 5.105e-4, 5.646e-4, -6.819e-4], [1.0, 1.0, 1.0, 6.0]
    nc = [0.0, 0.0, 0.0, 9749.0]
    x = np.array([-3.0, -1.0, 0.0, 2.0])
    vector = imhof_cdf(x, weights, dof, nc)
    scalar = np.array([imhof_cdf(v, weights, dof, nc) for v in x])
    assert np.allclose(vector, scalar, rtol=1e-9, atol=1e-14)
    draws = WeightedChiSquare(weights, dof, nc).rvs(200_000, rng=np.random.default_rng(3))
    for p, f in zip(vector, (draws[:, None] <= x).mean(axis=0)):
        lo, hi = binomial_band(draws.size, p, miss=1e-4 / x.size)
        assert lo <= f <= hi


@pytest.mark.filterwarnings("error")
def test_tiny_weight_beside_noncentral_terms_far_below_the_mean():
    # found by hypothesis hunts: a bisection step toward the pole jumped from
    # s = -67 to -1e-140 (OverflowError in a cube), and an all-central bound
    # needed a truncation point beyond its limit for chi2_1 - chi2_1(148) at 0
    w, nc = [2.0, 2.3971e-4], [4.0, 1.0]
    assert imhof_cdf(1.0, w, 1, nc) == pytest.approx(imhof_cdf([1.0, 1.0], w, 1, nc)[0], rel=1e-9)
    exact = integrate_cdf_of_difference(148.0)
    assert imhof_sf(0.0, [1.0, -1.0], 1, [0.0, 148.0], rtol=1e-6) == pytest.approx(exact, rel=1e-5)


def integrate_cdf_of_difference(nc):
    """P(chi2_1 > Y) for Y ~ chi2_1(nc), by one-dimensional quadrature."""
    from scipy import integrate

    mean, sd = 1 + nc, math.sqrt(2 * (1 + 2 * nc))
    return integrate.quad(
        lambda y: stats.chi2.sf(y, 1) * stats.ncx2.pdf(y, 1, nc),
        max(mean - 12 * sd, 0),
        mean + 12 * sd,
        epsabs=0,
        epsrel=1e-12,
        limit=500,
    )[0]


# ---------------------------------------------------------------------------
# huge degrees of freedom and extreme scales (issue 28, items 2 and 5)
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("dof", [1e6, 1e7, 1e8, 1e12])
def test_huge_dof_meets_the_requested_accuracy_in_the_body(dof):
    # in the body (|z| <= 2.5) scipy's regularised incomplete gamma is accurate
    # (it is far in the lower tail at df >= 1e7 that it is not); the old
    # contour summed log(1 - 2 w s) of size eps h and erred by up to 1.4e-9
    sd = math.sqrt(2.0 * dof)
    c = dof + sd * np.array([-2.0, -1.0, -0.3, 0.0, 0.7, 1.5, 2.5])
    reference = special.gammainc(dof / 2, c / 2)
    got = np.array([imhof_cdf(float(ci), [1.0], [dof]) for ci in c])
    assert np.max(np.abs(got - reference)) < 1e-12
    assert np.max(np.abs(imhof_cdf(c, [1.0], [dof]) - reference)) < 1e-12


def test_huge_dof_never_fails_in_arithmetic():
    weights = [1.0, 0.5]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # at the mean of a law of dof 1e20 the truth is 1/2 up to a skewness term
        # of order 1e-10 (the old code returned 0.0)
        assert abs(imhof_cdf(1.5e20, weights, [1e20, 1e20]) - 0.5) < 1e-9
        assert abs(imhof_sf(1.5e20, weights, [1e20, 1e20]) - 0.5) < 1e-9
        for dof in (1e20, 1e200, 1.7e308):
            # far below the mean: 0 (the old code raised ZeroDivisionError, then a
            # NaN-to-integer error at 1e200)
            assert imhof_cdf(1.0, weights, [dof, dof]) == 0.0
            assert imhof_sf(1.0, weights, [dof, dof]) == 1.0
        # the normal limit: exactly 1/2 at an exactly representable mean
        assert imhof_cdf(1.5e300, weights, [1e300, 1e300]) == pytest.approx(0.5, abs=1e-15)
        assert liu_tang_zhang_cdf(1.5e200, weights, [1e200, 1e200]) == pytest.approx(0.5)
        # (powers of two: the mean 1.5 H is exact, the density there 1/sqrt(2 pi var))
        H = 2.0**660
        law = WeightedChiSquare(weights, [H, H])
        assert law.pdf(1.5 * H) == pytest.approx(1 / math.sqrt(2 * math.pi * 2.5 * H))


def test_liu_tang_zhang_is_finite_at_huge_dof():
    # the cumulants of dof 1e200 overflowed: NaN
    for dof in (1e100, 1e200, 1e300):
        p = liu_tang_zhang_cdf(0.75 * dof, [1.0, 0.5], [dof, dof])
        assert p == pytest.approx(0.0, abs=1e-12)
        assert np.isfinite(liu_tang_zhang_sf(1.5 * dof, [1.0, 0.5], [dof, dof]))


def test_inversion_integrands_are_finite_beyond_u_710():
    # cosh(710) overflows: the contour integrand was NaN there; it is 0 in doubles
    u = np.array([0.0, 1.0, 709.0, 710.0, 1e3])
    real_axis, contour, _ = inversion_integrands(1.0, [1.0, 0.5], u=u)
    assert np.isfinite(real_axis).all() and np.isfinite(contour).all()
    assert contour[2:].tolist() == [0.0, 0.0, 0.0]


def test_many_weights_give_no_spurious_overflow_warning():
    # the closed form near 0 of a positive form was evaluated at every point,
    # where k log x overflowed (k = 1500) though only points far below the mean use it
    weights = np.random.default_rng(0).uniform(0.1, 1.0, 3000)
    c = float(np.sum(weights))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = imhof_cdf(np.array([c, c + 1.0]), weights)
    assert 0.5 < p[0] < p[1] < 0.52


def test_a_bool_level_and_text_in_object_arrays_are_refused():
    law = WeightedChiSquare([1.0, 0.5])
    with pytest.raises(ValueError, match="probabilities"):
        law.ppf(True)
    with pytest.raises(ValueError, match="probabilities"):
        law.isf(np.array([True, False]))
    with pytest.raises(ValueError, match=r"weights.*text"):
        imhof_cdf(1.0, np.array(["1.0", "0.5"], dtype=object))
    with pytest.raises(ValueError, match=r"c .*text"):
        imhof_cdf(np.array(["1.0"], dtype=object), [1.0])
    with pytest.raises(ValueError, match=r"dof.*text"):
        imhof_cdf(1.0, [1.0, 0.5], [1, "2"])


@pytest.mark.parametrize("df", [0.3, 1.0, 3.0, 10.0])
def test_vectorised_quantile_search_matches_the_chi_square_quantiles(df):
    # ppf and isf search all levels (and both tails) in a few vectorised calls;
    # next to the bound 0 and far in either tail they keep full relative accuracy
    law = WeightedChiSquare([1.0], [df])
    levels = np.array([1e-12, 1e-8, 0.025, 0.5, 0.975, 1 - 1e-8])
    assert np.allclose(law.ppf(levels), stats.chi2.ppf(levels, df), rtol=1e-11, atol=0)
    assert np.allclose(law.isf(levels), stats.chi2.isf(levels, df), rtol=1e-11, atol=0)
    for p in (0.005, 0.025):
        assert float(law.ppf(p)) == pytest.approx(stats.chi2.ppf(p, df), rel=1e-11)
        assert float(law.isf(p)) == pytest.approx(stats.chi2.isf(p, df), rel=1e-11)
    assert law.ppf([0.0, 1.0]).tolist() == [0.0, math.inf]


def test_quantiles_of_a_mixed_law_invert_its_distribution_function():
    law = WeightedChiSquare([2.0, -1.0, 0.5], [1, 3, 2], [0.5, 0.0, 1.0], sigma=0.3, offset=1.0)
    levels = np.array([1e-9, 0.01, 0.3, 0.5, 0.9, 0.999])
    assert np.allclose(law.cdf(law.ppf(levels)), levels, rtol=1e-9, atol=0)
    assert np.allclose(law.sf(law.isf(levels)), levels, rtol=1e-9, atol=0)


def _random_laws(count, seed):
    """Random laws of 1-5 terms, one-signed and mixed, central and noncentral."""
    rng = np.random.default_rng(seed)
    for i in range(count):
        r = int(rng.integers(1, 6))
        weights = rng.uniform(-2, 3, r) if i % 3 else rng.uniform(0.1, 3, r)
        dof = rng.integers(1, 30, r).astype(float)
        noncentrality = rng.uniform(0, 4, r) if i % 2 else np.zeros(r)
        yield WeightedChiSquare(weights, dof, noncentrality)


def test_two_sided_quantiles_take_one_path_set_up_and_meet_the_tolerance(monkeypatch):
    # the pair of a two-sided region is found by Newton's method on the contours set
    # up once at the Liu-Tang-Zhang guesses: on nearly every law one integral set-up
    # per side of 0 settles every level (no second set-up, no bracketing
    # evaluation), and the log tail is within 4 rtol of its goal
    setups, brackets = [], []
    newton, evaluate = _search._newton_on_path, WeightedChiSquare._log_tail

    def counted_newton(x, *args):
        root, done = newton(x, *args)
        setups.append(done.all())
        return root, done

    def counted_bracket(self, x, lower):
        brackets.append(x.shape)
        return evaluate(self, x, lower)

    monkeypatch.setattr(_search, "_newton_on_path", counted_newton)
    monkeypatch.setattr(WeightedChiSquare, "_log_tail", counted_bracket)
    single, laws = 0, list(_random_laws(40, seed=7))
    for law in laws:
        setups.clear()
        brackets.clear()
        lower, upper = law.ppf(0.025), law.isf(0.025)
        single += all(setups) and not brackets
        assert abs(math.log(law.cdf(lower)) - math.log(0.025)) <= 4 * law.rtol
        assert abs(math.log(law.sf(upper)) - math.log(0.025)) <= 4 * law.rtol
    assert single >= 36


def test_quantiles_across_zero_meet_the_tolerance():
    # a mixed law's quantile below 0 guessed above it: the Newton search moves to the
    # mirrored side (the bracketing search returned a point whose tail was 1.8e-8
    # off at 1e-9, law 4 of these)
    for law in _random_laws(20, seed=8):
        levels = np.array([1e-9, 0.025, 0.5, 0.9])
        assert np.allclose(law.cdf(law.ppf(levels)), levels, rtol=4e-9, atol=0)
        assert np.allclose(law.sf(law.isf(levels)), levels, rtol=4e-9, atol=0)


def test_the_bracketing_search_still_meets_the_tolerance():
    # the fallback of the Newton search (levels its paths do not settle), on
    # positive forms (every third law of _random_laws)
    for law in list(_random_laws(30, seed=8))[::3]:
        levels = np.array([1e-9, 0.025, 0.5, 0.9])
        lower = law._quantiles_by_nodes(levels, np.ones(4, dtype=bool))
        upper = law._quantiles_by_nodes(levels, np.zeros(4, dtype=bool))
        assert np.allclose(law.cdf(lower), levels, rtol=4e-9, atol=0)
        assert np.allclose(law.sf(upper), levels, rtol=4e-9, atol=0)


def _mixed_laws(count, seed):
    """Random laws of 2-5 terms of both signs, central and noncentral."""
    rng = np.random.default_rng(seed)
    for i in range(count):
        r = int(rng.integers(2, 6))
        weights = rng.uniform(-2, 3, r)
        if (weights > 0).all() or (weights < 0).all():
            weights[0] = -weights[0]
        dof = rng.integers(1, 30, r).astype(float)
        noncentrality = rng.uniform(0, 4, r) if i % 2 else np.zeros(r)
        yield WeightedChiSquare(weights, dof, noncentrality)


def test_the_bracketing_search_meets_the_tolerance_on_mixed_laws_at_small_levels():
    # the fallback used to accept an estimate unchecked (two interpolants that agreed, or
    # the last of 8 secant steps): at level 1e-9 its tails were 28 % off on laws 11 and
    # 27 of these (and 1.8e-8 off on law 4 of _random_laws(20, seed=8)); every answer is
    # now checked, within the integrals' accuracy (4 rtol) of its level
    levels = np.array([1e-12, 1e-9, 1e-6, 1e-3, 0.3])
    for law in _mixed_laws(30, seed=5):
        lower = law._quantiles_by_nodes(levels, np.ones(levels.size, dtype=bool))
        upper = law._quantiles_by_nodes(levels, np.zeros(levels.size, dtype=bool))
        tol = 4 * law.rtol
        np.testing.assert_allclose(law.cdf(lower), levels, rtol=tol, atol=0)
        np.testing.assert_allclose(law.sf(upper), levels, rtol=tol, atol=0)


@pytest.mark.slow
def test_the_bracketing_search_against_mpmath_at_small_levels():
    # the same answers against Imhof's real-axis integral in 30 digits (quadosc; ~5 s a
    # point), independent of the library's contour: the tail at the fallback's quantile
    pytest.importorskip("mpmath")
    from quadform_reference import imhof_cdf_mp

    laws = list(_mixed_laws(30, seed=5))
    cases = [
        (list(_random_laws(5, seed=8))[4], 1e-9, True),  # old answer 1.8e-8 off
        (laws[11], 1e-9, True),  # old answer 28 % off
        (laws[27], 1e-9, False),  # old answer 28 % off
    ]
    for law, level, lower in cases:
        x = float(law._quantiles_by_nodes(np.array([level]), np.array([lower]))[0])
        cdf = imhof_cdf_mp(x, law.weights, law.dof, law.noncentrality)
        tail = float(cdf if lower else 1 - cdf)
        assert tail == pytest.approx(level, rel=4 * law.rtol, abs=0)


def test_a_two_sided_rejection_probability_is_one_evaluation_of_both_tails():
    law = WeightedChiSquare([2.0, 0.5], [3, 1], [1.0, 0.0])
    lower, upper = 1.5, 14.0
    expected = float(law.cdf(lower)) + float(law.sf(upper))
    assert rejection_probability(law, (lower, upper), "two-sided") == pytest.approx(
        expected, rel=1e-14
    )
    # thresholds outside the support (a positive form: X > 0) take the general path
    assert rejection_probability(law, (-1.0, upper), "two-sided") == pytest.approx(
        float(law.sf(upper)), rel=1e-14
    )


# ---------------------------------------------------------------------------
# many laws in one call
# ---------------------------------------------------------------------------
def _batch_of_laws(count, seed):
    """Rows of weights, dof and noncentrality: mixed and one-signed, central and noncentral."""
    rng = np.random.default_rng(seed)
    weights = rng.uniform(-2.0, 3.0, (count, 3))
    weights[::3] = np.abs(weights[::3]) + 0.1  # (positive forms)
    dof = rng.integers(1, 25, (count, 3)).astype(float)
    noncentrality = rng.uniform(0.0, 4.0, (count, 3)) * (rng.random((count, 3)) < 0.5)
    return weights, dof, noncentrality


def test_the_batch_equals_one_call_per_law():
    weights, dof, noncentrality = _batch_of_laws(60, seed=21)
    mean = np.sum(weights * (dof + noncentrality), axis=1)
    sd = np.sqrt(2 * np.sum(weights**2 * (dof + 2 * noncentrality), axis=1))
    points = mean[:, None] + sd[:, None] * np.array([-4.0, -1.0, 0.3, 2.0, 5.0])
    cdf = quadform.imhof_cdf_batch(points, weights, dof, noncentrality)
    sf = quadform.imhof_sf_batch(points, weights, dof, noncentrality)
    for law, row in enumerate(points):
        terms = (weights[law], dof[law], noncentrality[law])
        expected_cdf, expected_sf = imhof_cdf(row, *terms), imhof_sf(row, *terms)
        # the smaller tail to its relative accuracy, both within 1e-14 absolutely
        assert np.allclose(cdf[law], expected_cdf, rtol=1e-9, atol=1e-14)
        assert np.allclose(sf[law], expected_sf, rtol=1e-9, atol=1e-14)


def test_batch_shapes_follow_the_points():
    weights, dof, noncentrality = _batch_of_laws(4, seed=22)
    one_each = quadform.imhof_cdf_batch([1.0, 2.0, 3.0, 4.0], weights, dof, noncentrality)
    assert one_each.shape == (4,)
    assert quadform.imhof_cdf_batch(2.0, weights, dof, noncentrality).shape == (4,)
    shared = quadform.imhof_cdf_batch([[1.0, 2.0]], weights, dof, noncentrality)
    assert shared.shape == (4, 2)
    per_law = quadform.imhof_cdf_batch(np.full((4, 2), 3.0), weights, dof, noncentrality)
    assert np.array_equal(per_law[:, 0], quadform.imhof_cdf_batch(3.0, weights, dof, noncentrality))
    with pytest.raises(ValueError, match=r"c\[None, :\]"):
        quadform.imhof_cdf_batch([1.0, 2.0], weights, dof, noncentrality)


def test_laws_beyond_the_batch_engine_go_law_by_law():
    # a normal term, a zero weight, huge dof and infinite points: the one-law engine
    weights = np.array([[1.0, 0.5], [1.0, 0.0], [1e-3, 2e-3], [2.0, -1.0]])
    dof = np.array([[1.0, 2.0], [3.0, 1.0], [1e6, 1e6], [2.0, 2.0]])
    sigma = np.array([0.5, 0.0, 0.0, 0.0])
    points = np.array([[2.0, np.inf], [1.5, 3.0], [3000.0, 3001.0], [-np.inf, 1.0]])
    got = quadform.imhof_cdf_batch(points, weights, dof, sigma=sigma)
    for law in range(4):
        expected = imhof_cdf(points[law], weights[law], dof[law], sigma=float(sigma[law]))
        assert np.allclose(got[law], expected, rtol=1e-12, atol=0)
