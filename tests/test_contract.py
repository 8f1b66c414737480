"""The contract every public test of the course keeps, checked over all of them.

Discovery: every public function whose name ends in ``_test`` or ``_tests``
in the topic modules is found programmatically, so a new test cannot be
missed: without a case below, :func:`test_every_public_test_has_a_contract_case`
fails and names it.

For every test, on data simulated under H0:

* the result is a :class:`~course.results.TestResult` whose ``null`` is a law
  (the :class:`~course.results.Law` protocol) and whose repr is short and
  deterministic; it unpacks as ``statistic, pvalue = result``, like scipy's
  (the w-tests' :class:`~course.lsq.WTestResult` too);
* critical value, p-value and decision agree with ``null``, recomputed here
  from the formulas (not through the library's decision path), for the
  test's alternative; ``0 <= p <= 1``; ``power(null) == alpha``;
* calibration: over independent H0 records (multi-output cases included)
  the rejection rate lies in the binomial band around ``alpha``.
"""

from __future__ import annotations

import importlib
import pkgutil
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest
from conftest import binomial_band
from scipy import stats

import course
from course import diagnosis as dg
from course import filters as kf
from course import lsq, mismatched, nis
from course.results import Law, TestResult

#: Modules that hold shared pieces, tooling or plots, not statistical tests.
NOT_TOPICS = {"results", "linalg", "validation", "distributions", "chi2", "plotting", "cli"}
NOT_TOPICS |= {"grading"}


def public_tests() -> dict[str, Callable]:
    """Every public ``*_test``/``*_tests`` function of the topic modules, by name."""
    found: dict[str, Callable] = {}
    for info in pkgutil.iter_modules(course.__path__):
        if info.name.startswith("_") or info.name in NOT_TOPICS:
            continue
        module = importlib.import_module(f"course.{info.name}")
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if callable(obj) and re.search(r"_tests?$", name) and not isinstance(obj, type):
                # Two modules may each have a test of one name (diagnosis.glr_test on
                # likelihoods, lsq.glr_test on a fit): the later one is found as module.name.
                key = name if found.get(name, obj) is obj else f"{info.name}.{name}"
                found[key] = obj
    return found


# ---------------------------------------------------------------------------
# the cases: one call of each test on H0 data, given a seeded generator
# ---------------------------------------------------------------------------
@dataclass
class Case:
    """How to run one public test on data drawn under H0."""

    run: Callable[[np.random.Generator], object]  # -> TestResult (or WTestResult)
    reps: int  # records for the calibration
    alpha: float = 0.05


def _results(outcome) -> list[TestResult]:
    if isinstance(outcome, TestResult):
        return [outcome]
    return list(outcome.tests())  # w_tests: one TestResult per observation


def _first(outcome) -> TestResult:
    return outcome if isinstance(outcome, TestResult) else outcome.test(0)


# least squares: a line with correlated observations
_T = np.arange(1.0, 9.0)
_A = np.column_stack([np.ones(8), _T])
_QYY = 0.5 * np.eye(8) + 0.3 * np.exp(-np.abs(_T[:, None] - _T[None, :]))


def _lsq_fit(rng, variance_factor=1.0):
    y = _A @ [1.0, 0.5] + np.sqrt(variance_factor) * (
        np.linalg.cholesky(_QYY) @ rng.standard_normal(8)
    )
    return lsq.fit(_A, y, _QYY)


#: Two bias columns for the q-dimensional tests: a jump of the last three observations and
#: an outlier in the second.
_C2 = np.column_stack([np.r_[np.zeros(5), np.ones(3)], np.eye(8)[:, 1]])


# diagnosis: the lecture's three-gain regression
_N = 25
_t = np.arange(_N)
_U = np.column_stack(
    [1 + 0.5 * np.sin(_t / 4), np.cos(_t / 3), np.where((_t // 5) % 2 == 0, 1.0, -1.0)]
)
_NOMINAL = np.ones(3)
_SIGMA = 0.3


def _record(rng, theta=_NOMINAL):
    return _U @ theta + _SIGMA * rng.standard_normal(_N)


def _gaussian_log_likelihood(y):
    def log_likelihood(theta):
        r = y - _U @ theta
        return -0.5 * _N * np.log(2 * np.pi * _SIGMA**2) - r @ r / (2 * _SIGMA**2)

    return log_likelihood


# filters and the NIS: a two-output model and its own (correct) Kalman filter
_KF_MODEL = kf.LinearModel(
    F=[[0.9, 0.2], [0.0, 0.8]],
    H=np.eye(2),
    Q=0.2 * np.eye(2),
    R=[[1.0, 0.3], [0.3, 0.5]],
)


def _kf_result(rng, N=12):
    _, y = _KF_MODEL.simulate(N, rng)
    return kf.kalman_filter(_KF_MODEL, y)


def _rls_result(rng, N=16):
    Phi = np.column_stack([np.ones(N), np.linspace(0, 1, N)])
    y = Phi @ [1.0, -1.0] + 0.5 * rng.standard_normal(N)
    return kf.recursive_least_squares(Phi, y, r=0.25)


# mismatched filters: three states, two outputs, a reduced two-state filter
_M0 = kf.LinearModel(
    F=[[0.8, 0.3, 0.0], [0.0, 0.7, 0.2], [0.0, 0.0, 0.9]],
    H=[[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]],
    Q=np.diag([0.4, 0.3, 0.1]),
    R=[[1.0, 0.3], [0.3, 0.8]],
    x0_mean=[0.5, 0.0, -0.5],
    x0_cov=np.eye(3),
    v_mean=[0.1, -0.1],
)
_M1 = kf.LinearModel(
    F=[[0.8, 0.2], [0.0, 0.85]], H=np.eye(2), Q=0.5 * np.eye(2), R=[[1.0, 0.2], [0.2, 1.0]]
)
_MM_N, _MM_RECORDS = 4, 8
_MM_NULL = mismatched.residual_moments(_M0, _M1, _MM_N)


def _records(rng):
    return mismatched.simulate_records(_M0, _M1, _MM_RECORDS, _MM_N, rng)


CASES: dict[str, list[Case]] = {
    "overall_model_test": [Case(lambda rng: lsq.overall_model_test(_lsq_fit(rng)), 600)],
    "w_tests": [
        Case(lambda rng: lsq.w_tests(_lsq_fit(rng)), 600),
        # sigma² estimated: calibrated whatever the true variance factor
        Case(lambda rng: lsq.w_tests(_lsq_fit(rng, 4.0), variance="estimated"), 600),
    ],
    "lsq.glr_test": [
        Case(lambda rng: lsq.glr_test(_lsq_fit(rng), _C2), 600),
        Case(lambda rng: lsq.glr_test(_lsq_fit(rng, 0.25), _C2, variance="estimated"), 600),
    ],
    "prediction_error_test": [
        Case(
            lambda rng: dg.prediction_error_test(
                _record(rng, [2.0, 1, 1]), _U, _NOMINAL, [0], sigma=_SIGMA
            ),
            600,
        )
    ],
    "parameter_estimate_test": [
        Case(lambda rng: dg.parameter_estimate_test(1 + 0.2 * rng.standard_normal(), 0.04, 1), 600),
        Case(  # two parameters: the Wald form
            lambda rng: dg.parameter_estimate_test(
                [1, 2] + np.linalg.cholesky([[1, 0.5], [0.5, 2]]) @ rng.standard_normal(2),
                [[1, 0.5], [0.5, 2]],
                [1, 2],
            ),
            600,
        ),
    ],
    "regression_parameter_test": [
        Case(
            lambda rng: dg.regression_parameter_test(
                _record(rng, [1.7, 1, 1]), _U, _NOMINAL, [0, 1], 1, sigma=_SIGMA
            ),
            600,
        ),
        Case(
            lambda rng: dg.regression_parameter_test(
                _record(rng), _U, _NOMINAL, [0, 1, 2], [1, 2], sigma=_SIGMA
            ),
            600,
        ),
    ],
    "likelihood_test": [
        Case(
            lambda rng: dg.likelihood_test(_record(rng), _U, _NOMINAL, [0, 2], sigma=_SIGMA),
            600,
        )
    ],
    "glr_test": [
        Case(
            lambda rng: dg.glr_test(_gaussian_log_likelihood(_record(rng)), _NOMINAL, [], [1]),
            200,
        )
    ],
    "linear_glr_test": [
        Case(
            lambda rng: dg.linear_glr_test(_record(rng), _U, _NOMINAL, [0], sigma=_SIGMA),
            600,
        )
    ],
    "neyman_pearson_test": [
        Case(lambda rng: dg.neyman_pearson_test(rng.standard_normal(6), 0.0, 0.8), 600)
    ],
    "windowed_chi2_test": [
        Case(lambda rng: nis.windowed_chi2_test(_kf_result(rng), 10), 300),  # two outputs
        Case(lambda rng: nis.windowed_chi2_test(_rls_result(rng), 8), 300),
        Case(
            lambda rng: nis.windowed_chi2_test(rng.chisquare(3, size=20), 6, n_outputs=3),
            600,
        ),
    ],
    "nis_test": [
        Case(
            lambda rng: nis.nis_test(
                rng.standard_normal((40, 2)) @ np.linalg.cholesky([[2, 0.5], [0.5, 1]]).T,
                [[2, 0.5], [0.5, 1]],
            ),
            600,
        )
    ],
    "nis_matrix_test": [
        Case(lambda rng: nis.nis_matrix_test(rng.standard_normal((30, 2)), np.eye(2)), 300)
    ],
    "mean_test": [Case(lambda rng: mismatched.mean_test(_records(rng), 2, _MM_NULL), 150)],
    "covariance_test": [
        Case(lambda rng: mismatched.covariance_test(_records(rng), 1, _MM_NULL), 150),
        Case(lambda rng: mismatched.covariance_test(_records(rng), 1, _MM_NULL, gamma=0), 150),
    ],
    "correlation_test": [
        Case(lambda rng: mismatched.correlation_test(_records(rng), 0, 2, _MM_NULL), 150),
    ],
}

CASE_IDS = [(name, k) for name, cases in CASES.items() for k in range(len(cases))]


# ---------------------------------------------------------------------------
# discovery
# ---------------------------------------------------------------------------
def test_every_public_test_has_a_contract_case():
    found = public_tests()
    missing = sorted(set(found) - set(CASES))
    assert not missing, f"public tests without a contract case in {__file__}: {missing}"
    assert not sorted(set(CASES) - set(found)), "contract cases for tests that no longer exist"
    assert len(found) >= 15


# ---------------------------------------------------------------------------
# the contract of one result, recomputed from the formulas
# ---------------------------------------------------------------------------
def _close(a, b):
    return np.allclose(a, b, rtol=1e-9, atol=1e-12)


def check_contract(result: TestResult) -> None:
    assert isinstance(result, TestResult)
    null, alpha, T = result.null, result.alpha, result.statistic
    assert isinstance(null, Law), f"{result.name}: null must be a law, got {type(null)}"
    for method in ("cdf", "sf", "ppf", "isf", "rvs"):
        assert callable(getattr(null, method, None))
    assert 0.0 <= result.pvalue <= 1.0
    assert isinstance(result.reject, bool) and isinstance(result.pvalue, float)
    low, high = T if isinstance(T, tuple) else (T, T)
    crit = result.critical_value
    if result.alternative == "greater":
        assert _close(crit, null.isf(alpha))
        assert _close(result.pvalue, null.sf(high))
        region = high > crit
    elif result.alternative == "less":
        assert _close(crit, null.ppf(alpha))
        assert _close(result.pvalue, null.cdf(low))
        region = low < crit
    else:
        assert _close(crit, (null.ppf(alpha / 2), null.isf(alpha / 2)))
        two_sided = min(1.0, 2.0 * min(float(null.cdf(low)), float(null.sf(high))))
        assert _close(result.pvalue, two_sided)
        region = low < crit[0] or high > crit[1]
    assert result.reject == bool(region)
    if abs(result.pvalue - alpha) > 1e-9:
        assert result.reject == (result.pvalue < alpha)
    assert result.power(null) == pytest.approx(alpha, rel=1e-6)
    text = repr(result)
    assert len(text) < 400 and "0x" not in text and "np." not in text


@pytest.mark.parametrize("name, k", CASE_IDS)
def test_results_keep_the_contract(name, k):
    case = CASES[name][k]
    for seed in range(3):
        outcome = case.run(np.random.default_rng(seed))
        statistic, pvalue = outcome  # like scipy's: stat, p = test(...)
        np.testing.assert_array_equal(statistic, outcome.statistic)
        np.testing.assert_array_equal(pvalue, outcome.pvalue)
        for result in _results(outcome):
            check_contract(result)
            assert result.alpha == case.alpha
    # the repr is deterministic: the same data give the same text
    again = case.run(np.random.default_rng(0))
    first = case.run(np.random.default_rng(0))
    assert [repr(r) for r in _results(first)] == [repr(r) for r in _results(again)]


# ---------------------------------------------------------------------------
# calibration: rejection rate under H0
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("name, k", CASE_IDS)
def test_calibration_under_h0(name, k):
    case = CASES[name][k]
    rng = np.random.default_rng(20260 + 17 * k + sum(map(ord, name)))
    rejected = np.zeros(case.reps)
    for i in range(case.reps):
        rejected[i] = _first(case.run(rng)).reject  # one decision per independent record
    miss = 1e-4 / len(CASE_IDS)
    lo, hi = binomial_band(case.reps, case.alpha, miss)
    rate = rejected.mean()
    assert lo <= rate <= hi, f"{name}[{k}]: rate {rate:.4f} outside [{lo:.4f}, {hi:.4f}]"


def test_power_of_a_result_matches_monte_carlo():
    """TestResult.power under a non-central law agrees with simulated rejections."""
    fit = _lsq_fit(np.random.default_rng(0))
    result = lsq.overall_model_test(fit, 0.05)
    dof, lam = result.dof, 4.0
    power = result.power(stats.ncx2(dof, lam))
    draws = stats.ncx2(dof, lam).rvs(20000, random_state=np.random.default_rng(1))
    lo, hi = binomial_band(20000, power)
    assert lo <= np.mean(draws > result.critical_value) <= hi
