"""Checks of assignment 05_nis_wishart (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

import numpy as np
from scipy import stats

from course import nis
from course.grading.checks import Checks, binomial_band

from . import data

_rng = np.random.default_rng(20250605)


def _covariances(count, m):
    A = _rng.standard_normal((count, m, m))
    return A @ np.swapaxes(A, -1, -2) + 0.5 * np.eye(m)


EPS_A = np.array([[1.0, -0.5], [0.3, 2.0], [-1.2, 0.4], [0.8, 0.8], [-0.1, -1.5]])
S_A = np.array([[2.0, 0.5], [0.5, 1.0]])
S_B = _covariances(7, 3)
EPS_B = np.einsum("kij,kj->ki", np.linalg.cholesky(S_B), _rng.standard_normal((7, 3)))
S_C = _covariances(40, 2)
EPS_C = np.einsum("kij,kj->ki", np.linalg.cholesky(S_C), _rng.standard_normal((40, 2)))
# A record whose true covariance has a correlation the filter ignores (the matrix test rejects).
EPS_D = _rng.standard_normal((80, 2)) @ np.linalg.cholesky(np.array([[1.0, 0.8], [0.8, 1.0]])).T
S_D = np.eye(2)
EPS_E = _rng.standard_normal((30, 2)) @ np.linalg.cholesky(S_A).T

CHECKS = Checks(
    "05_nis_wishart",
    title="Assignment 5: the NIS matrix and Wishart eigenvalue tests",
    data=data,
    timeout=10,
    preload=["course.nis", "scipy.stats"],
)


@CHECKS.function(
    "q1",
    func="nis_per_step",
    points=2,
    rtol=1e-9,
    atol=1e-12,
    forbid=["course.nis.nis", "course.nis.nees", "course.nis.nis_matrix"],
    hint="For each step solve with the Cholesky factor: z = solve(B_k, eps_k) with "
    "S_k = B_k B_k^T, then NIS_k = z @ z. S is one (m, m) matrix or a (K, m, m) "
    "stack: np.broadcast_to(S, (K, m, m)) handles both.",
)
def q1(eps, S):
    return nis.nis(eps, S)


q1.case(EPS_A, S_A, label="K = 5, m = 2, one S for all steps")
### BEGIN HIDDEN TESTS
q1.case(EPS_B, S_B, hidden=True)
q1.case(EPS_C, S_C, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q2",
    func="nis_matrix",
    points=2,
    rtol=1e-9,
    atol=1e-12,
    forbid=[
        "course.nis.nis_matrix",
        "course.nis.nis_matrix_eigenvalues",
        "course.nis.nis_matrix_test",
    ],
    hint="Pi = (1/K) sum_k z_k z_k^T with z_k = B_k^{-1} eps_k (B_k lower Cholesky "
    "factor of S_k): the mean of the outer products of the whitened innovations. "
    "Its trace equals the average NIS of q1.",
)
def q2(eps, S):
    return nis.nis_matrix(eps, S)


q2.case(EPS_A, S_A, label="K = 5, m = 2, one S for all steps")
### BEGIN HIDDEN TESTS
q2.case(EPS_B, S_B, hidden=True)
q2.case(EPS_C, S_C, hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q3",
    var="eps_bar_interval",
    points=1,
    rtol=1e-7,
    atol=1e-10,
    forbid=["course.nis.consistency_interval", "course.nis.nis_critical_values"],
    hint="With the poster's 1/K, K * eps_bar ~ chi2(m K): take the chi2(60) quantiles "
    "at 0.025 and 0.975 and divide them by K = 20.",
)
def q3():
    law = stats.chi2(60)
    return (float(law.ppf(0.025)) / 20, float(law.isf(0.025)) / 20)


@CHECKS.value(
    "q4",
    var="thresholds",
    points=1,
    rtol=1e-7,
    atol=1e-10,
    forbid=["course.nis.nis_matrix_critical_values"],
    hint="Split alpha equally: the lower threshold is the alpha/2 quantile (ppf) of the "
    "law of lambda_min, the upper one the alpha/2 upper quantile (isf) of the law of "
    "lambda_max: nis.extreme_eigenvalue(2, 30, 'min' / 'max').",
)
def q4():
    return nis.nis_matrix_critical_values(2, 30, 0.05)


@CHECKS.function(
    "q5",
    func="matrix_test",
    points=2,
    rtol=1e-7,
    atol=1e-10,
    forbid=["course.nis.nis_matrix_test"],
    hint="lmin and lmax are the extreme eigenvalues (np.linalg.eigvalsh) of your "
    "nis_matrix(eps, S); reject when lmin < ppf_min(alpha/2) or "
    "lmax > isf_max(alpha/2) of the exact laws with m = eps.shape[1], "
    "K = eps.shape[0]. Return (lmin, lmax, reject) with reject a bool.",
)
def q5(eps, S, alpha):
    result = nis.nis_matrix_test(eps, S, alpha)
    lmin, lmax = result.statistic
    return (lmin, lmax, bool(result.reject))


q5.case(EPS_A, S_A, 0.05, label="K = 5, m = 2, alpha = 0.05")
### BEGIN HIDDEN TESTS
q5.case(EPS_D, S_D, 0.05, hidden=True)
q5.case(EPS_C, S_C, 0.1, hidden=True)
q5.case(EPS_E, S_A, 0.01, hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q6",
    var="pvalues",
    points=2,
    rtol=1e-6,
    atol=1e-9,
    data="record",
    properties="record_properties",
    hint="p_nis = 2 min(F, 1 - F) of chi2(m K) at the NIS sum K * eps_bar; "
    "p_matrix = min(1, 2 min(F_min(lmin), 1 - F_max(lmax))) with the exact laws "
    "of nis.extreme_eigenvalue. nis.nis_test and nis.nis_matrix_test compute both.",
)
def q6(d):
    p_nis = nis.nis_test(d["eps"], d["S"], d["alpha"]).pvalue
    p_matrix = nis.nis_matrix_test(d["eps"], d["S"], d["alpha"]).pvalue
    return (float(p_nis), float(p_matrix))


@CHECKS.function(
    "q7",
    func="false_alarm_rate",
    points=2,
    timeout=30,
    forbid=["course.nis.simulate_extreme_eigenvalues", "course.nis.prob_eigenvalues_within"],
    hint="rng = np.random.default_rng(seed); draw innovations of shape (n_runs, K, m) "
    "from N(0, I) (any S would do after whitening), form the NIS matrices of all "
    "runs at once (np.einsum), take their extreme eigenvalues (np.linalg.eigvalsh "
    "works on stacks) and return the fraction of runs outside the thresholds of "
    "nis.nis_matrix_critical_values(m, K, alpha).",
)
def q7(m, K, alpha, n_runs, seed):
    # The exact false-alarm rate is 1 - P(all eigenvalues inside the thresholds).
    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)
    size = 1.0 - nis.prob_eigenvalues_within(m, K, lower, upper)
    return binomial_band(n_runs, size, miss=1e-4)


q7.case(2, 30, 0.05, 20000, 2024, label="m = 2, K = 30, alpha = 0.05, 20000 runs")
### BEGIN HIDDEN TESTS
q7.case(3, 10, 0.1, 20000, 7, hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q8",
    var="nees_interval",
    points=1,
    rtol=1e-7,
    atol=1e-10,
    forbid=["course.nis.consistency_interval"],
    hint="N times the run-averaged NEES is chi2(n N) with n = 4 states and N = 50 runs: "
    "divide the chi2(200) quantiles at 0.025 and 0.975 by N.",
)
def q8():
    law = stats.chi2(200)
    return (float(law.ppf(0.025)) / 50, float(law.isf(0.025)) / 50)
