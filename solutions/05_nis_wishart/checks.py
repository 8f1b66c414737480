"""Checks of assignment 05_nis_wishart (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

from collections import namedtuple

import numpy as np
from scipy import stats

from course import nis
from course.grading.authoring.checks import Band, Checks, Mistake, binomial_band

from . import data

# Results with several parts are named tuples: feedback names the part that is wrong
# (``critical_value``, not ``item [1]``). A student's plain tuple or list in the same order
# is just as right (the grader compares item by item).
Interval = namedtuple("Interval", "lower upper")
MatrixTest = namedtuple("MatrixTest", "lmin lmax reject")
PValues = namedtuple("PValues", "p_nis p_matrix")

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


def _record_with_eigenvalues(targets, S, rng):
    """Innovations (K of them, targets = (K, eigenvalues)) whose NIS matrix has exactly the eigenvalues ``targets``.

    Whitened innovations z (K, m) are rotated and rescaled along the eigenvectors of their
    NIS matrix z^T z / K = V diag(l) V^T: z V diag(sqrt(t / l)) V^T has NIS matrix
    V diag(t) V^T. Used to put an extreme eigenvalue between the thresholds at alpha and at
    alpha/2, where a one-sided test and the two-sided test disagree.
    """
    K, m = targets[0], len(targets[1])
    white = rng.standard_normal((K, m))
    lam, V = np.linalg.eigh(white.T @ white / K)
    white = white @ V @ np.diag(np.sqrt(np.asarray(targets[1]) / lam)) @ V.T
    return white @ np.linalg.cholesky(np.asarray(S, dtype=float)).T


# m = 2, K = 12, alpha = 0.05: thresholds (0.2377, 2.3303) at alpha/2, (0.2834, 2.1343) at alpha.
EPS_GAP_HI = _record_with_eigenvalues((12, [0.8, 2.23]), S_A, _rng)
EPS_GAP_LO = _record_with_eigenvalues((12, [0.26, 1.3]), np.eye(2), _rng)
# m = 3, K = 10, alpha = 0.1: upper thresholds 2.5966 (alpha/2) and 2.3504 (alpha).
S_F = np.array([[1.5, 0.3, 0.0], [0.3, 1.0, -0.2], [0.0, -0.2, 0.7]])
EPS_GAP_3 = _record_with_eigenvalues((10, [0.6, 1.0, 2.47]), S_F, _rng)

# Public cases that see the decision (their own generator, so the records above stay as they
# were). m = 2, K = 12, alpha = 0.05: thresholds (0.2377, 2.3303). Both extreme eigenvalues
# outside (any "or" or "and" rule rejects, a test that never rejects does not), then only
# lmax outside and only lmin outside (the test rejects, "and instead of or" does not).
_rng_decision = np.random.default_rng(2026_11_26)
EPS_BOTH_OUT = _record_with_eigenvalues((12, [0.15, 2.7]), S_A, _rng_decision)
EPS_MAX_OUT = _record_with_eigenvalues((12, [0.9, 2.6]), S_A, _rng_decision)
EPS_MIN_OUT = _record_with_eigenvalues((12, [0.18, 1.4]), np.eye(2), _rng_decision)
# A public stack of S (one covariance per step), as the preamble allows: K = 6, m = 3.
_A_STACK = _rng_decision.standard_normal((6, 3, 3))
S_STACK = _A_STACK @ np.swapaxes(_A_STACK, -1, -2) + 0.5 * np.eye(3)
EPS_STACK = np.einsum(
    "kij,kj->ki", np.linalg.cholesky(S_STACK), _rng_decision.standard_normal((6, 3))
)

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
    forbid=[
        "course.nis.nis",
        "course.nis.nees",
        "course.nis.nis_matrix",
        "course.linalg.whitened_squared_norms",
    ],
    hint="For each step solve with the Cholesky factor: z = solve(B_k, eps_k) with "
    "S_k = B_k B_k^T, then NIS_k = z @ z. S is one (m, m) matrix or a (K, m, m) "
    "stack: np.broadcast_to(S, (K, m, m)) handles both.",
    mistakes=[
        Mistake(
            "looks like eps^T S eps: the NIS weighs each innovation by S^{-1}, eps^T S^{-1} eps",
            lambda eps, S: np.einsum("ki,kij,kj->k", *_with_stack(eps, S, S_of=lambda s: s)),
        ),
        Mistake(
            "whitened with the transposed factor: with S_k = B_k B_k^T (B_k lower), z_k = "
            "B_k^{-1} eps_k; B_k^{-T} eps_k does not whiten",
            lambda eps, S: np.sum(_whitened_upper(eps, S) ** 2, axis=1),
        ),
        Mistake(
            "looks divided by m: the NIS of one step is the whole quadratic form, chi2(m)",
            lambda eps, S: nis.nis(eps, S) / np.shape(eps)[1],
        ),
        Mistake(
            "only the diagonal of S looks used: with correlated innovations the NIS needs the "
            "whole S (its Cholesky factor)",
            lambda eps, S: np.einsum(
                "ki,kij,kj->k",
                *_with_stack(eps, S, S_of=lambda s: np.diag(1.0 / np.diag(s))),
            ),
        ),
        Mistake(
            "one S for every step: with a stack, step k uses its own S_k",
            lambda eps, S: nis.nis(
                eps, np.asarray(S, float) if np.ndim(S) == 2 else np.asarray(S, float)[0]
            ),
        ),
    ],
)
def q1(eps, S):
    return nis.nis(eps, S)


q1.case(EPS_A, S_A, label="K = 5, m = 2, one S for all steps")
q1.case(EPS_STACK, S_STACK, label="K = 6, m = 3, a stack of S (one per step)")
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
    mistakes=[
        Mistake(
            "looks like the SUM of the outer products z_k z_k^T: Pi is their mean (divide by K)",
            lambda eps, S: q2.reference(eps, S) * np.shape(eps)[0],
        ),
        Mistake(
            "looks divided by K - 1: Pi is the mean of the K outer products (nothing is "
            "estimated from the innovations), divide by K",
            lambda eps, S: q2.reference(eps, S) * np.shape(eps)[0] / (np.shape(eps)[0] - 1),
        ),
        Mistake(
            "one S for every step: with a stack, step k is whitened with its own S_k",
            lambda eps, S: nis.nis_matrix(
                eps, np.asarray(S, float) if np.ndim(S) == 2 else np.asarray(S, float)[0]
            ),
        ),
        Mistake(
            "looks like the outer products of eps itself: whiten first, z_k = B_k^{-1} eps_k "
            "with S_k = B_k B_k^T",
            lambda eps, S: np.einsum("ki,kj->ij", eps, eps) / np.shape(eps)[0],
        ),
        Mistake(
            "whitened with another square root of S (the symmetric S^(1/2)?): with one S for "
            "all steps its NIS matrix is a rotation of the right one, with the same eigenvalues "
            "(q5 would not see it), but not the same matrix; use the lower Cholesky factor B_k "
            "(S_k = B_k B_k^T), z_k = B_k^{-1} eps_k",
            lambda eps, S: _nis_matrix_symmetric_root(eps, S),
        ),
        Mistake(
            "whitened with the transposed factor: with S_k = B_k B_k^T (B_k lower), "
            "z_k = B_k^{-1} eps_k; B_k^{-T} eps_k (or scipy's upper factor U_k, solve(U_k, eps_k)) "
            "does not whiten",
            lambda eps, S: _nis_matrix_upper_factor(eps, S),
        ),
    ],
    hint="Pi = (1/K) sum_k z_k z_k^T with z_k = B_k^{-1} eps_k (B_k lower Cholesky "
    "factor of S_k): the mean of the outer products of the whitened innovations. "
    "Its trace equals the average NIS of q1.",
)
def q2(eps, S):
    return nis.nis_matrix(eps, S)


def _with_stack(eps, S, S_of):
    """(eps, the stack of S_of(S_k)) for an einsum over the steps (q1's mistakes)."""
    eps, stack = _stack(eps, S)
    return eps, np.stack([S_of(s) for s in stack]), eps


def _whitened_upper(eps, S):
    """z_k = B_k^{-T} eps_k (a mistake of q1)."""
    eps, S = _stack(eps, S)
    B = np.linalg.cholesky(S)
    return np.linalg.solve(np.swapaxes(B, -1, -2), eps[:, :, None])[:, :, 0]


def _stack(eps, S):
    eps = np.asarray(eps, dtype=float)
    K, m = eps.shape
    return eps, np.broadcast_to(np.asarray(S, dtype=float), (K, m, m))


def _nis_matrix_symmetric_root(eps, S):
    """q2 whitened with S_k^(-1/2) (symmetric) instead of the Cholesky factor (a mistake)."""
    eps, S = _stack(eps, S)
    w, V = np.linalg.eigh(S)
    z = np.einsum("kij,kj,klj,kl->ki", V, 1.0 / np.sqrt(w), V, eps)
    return z.T @ z / len(eps)


def _nis_matrix_upper_factor(eps, S):
    """q2 whitened with B_k^T instead of B_k (a mistake)."""
    eps, S = _stack(eps, S)
    B = np.linalg.cholesky(S)
    z = np.linalg.solve(np.swapaxes(B, -1, -2), eps[:, :, None])[:, :, 0]
    return z.T @ z / len(eps)


q2.case(EPS_A, S_A, label="K = 5, m = 2, one S for all steps")
q2.case(EPS_STACK, S_STACK, label="K = 6, m = 3, a stack of S (one per step)")
### BEGIN HIDDEN TESTS
q2.case(EPS_B, S_B, hidden=True)
q2.case(EPS_C, S_C, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q3",
    func="eps_bar_interval",
    points=1,
    rtol=1e-7,
    atol=1e-10,
    forbid=[
        "course.nis.consistency_interval",
        "course.nis.nis_critical_values",
        "course.nis.nis_test",
    ],
    mistakes=[
        Mistake(
            "the poster's law: eps_bar itself is not chi2(mK) -- with the 1/K average, K times "
            "eps_bar is",
            lambda m, K, alpha: (
                float(stats.chi2(m * K).ppf(alpha / 2)),
                float(stats.chi2(m * K).isf(alpha / 2)),
            ),
        ),
        Mistake(
            "alpha not split: a two-sided interval leaves alpha/2 in each tail",
            lambda m, K, alpha: (
                float(stats.chi2(m * K).ppf(alpha)) / K,
                float(stats.chi2(m * K).isf(alpha)) / K,
            ),
        ),
        Mistake(
            "divided by m K: K eps_bar is chi2(m K), so the quantiles are divided by K only "
            "(eps_bar's mean is m, not 1)",
            lambda m, K, alpha: _interval(m * K, m * K, alpha),
        ),
        Mistake(
            "chi2(m K - 1): nothing is estimated from the innovations, so all m K degrees of "
            "freedom stay",
            lambda m, K, alpha: _interval(m * K - 1, K, alpha),
        ),
        Mistake(
            "the quantiles of one step's chi2(m), divided by K: the SUM of K steps is chi2(m K)",
            lambda m, K, alpha: _interval(m, K, alpha),
        ),
    ],
    hint=[
        "The poster's 1/K hides a factor: is eps_bar itself chi-square, or a multiple of it?",
        "Find a two-sided interval (alpha/2 in each tail) for the chi-square variable first, "
        "then turn it into an interval for eps_bar.",
        "K * eps_bar ~ chi2(m K): divide the two quantiles of chi2(m K) by K.",
    ],
)
def q3(m, K, alpha):
    law = stats.chi2(m * K)
    return Interval(float(law.ppf(alpha / 2)) / K, float(law.isf(alpha / 2)) / K)


def _interval(dof, divisor, alpha, tail=None):
    """The quantiles of chi2(dof) at ``tail`` (alpha/2) and 1 - tail, divided by ``divisor``
    (the declared mistakes of q3 and q8)."""
    tail = alpha / 2 if tail is None else tail
    law = stats.chi2(dof)
    return (float(law.ppf(tail)) / divisor, float(law.isf(tail)) / divisor)


q3.case(3, 20, 0.05, label="m = 3, K = 20, 95 %")
### BEGIN HIDDEN TESTS
q3.case(2, 50, 0.01, hidden=True)
q3.case(1, 8, 0.1, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q4",
    func="matrix_thresholds",
    points=1,
    rtol=1e-7,
    atol=1e-10,
    forbid=["course.nis.nis_matrix_critical_values", "course.nis.nis_matrix_test"],
    mistakes=[
        Mistake(
            "alpha not split: each of the two thresholds gets alpha/2",
            lambda m, K, alpha: tuple(
                float(v) for v in nis.nis_matrix_critical_values(m, K, 2 * alpha)
            ),
            hint="Two thresholds share alpha: each tail gets half of it.",
        ),
        Mistake(
            "the laws look swapped: the lower threshold bounds lambda_min (a quantile of ITS "
            "law), the upper one lambda_max",
            lambda m, K, alpha: _thresholds(m, K, alpha, low="max", high="min"),
            hint="Too small a NIS matrix shows in its SMALLEST eigenvalue: the lower threshold "
            "is nis.extreme_eigenvalue(m, K, 'min').ppf(alpha/2), the upper one "
            "nis.extreme_eigenvalue(m, K, 'max').isf(alpha/2).",
        ),
        Mistake(
            "both thresholds come from the law of lambda_max: the lower one bounds lambda_min, "
            "a quantile of its own law",
            lambda m, K, alpha: _thresholds(m, K, alpha, low="max", high="max"),
        ),
        Mistake(
            "these are the NIS test's chi2(m K)/K thresholds: the matrix test bounds the "
            "extreme eigenvalues, whose laws are wider",
            lambda m, K, alpha: (
                float(stats.chi2(m * K).ppf(alpha / 2) / K),
                float(stats.chi2(m * K).isf(alpha / 2) / K),
            ),
        ),
        Mistake(
            "the lower threshold is an upper-tail quantile: lambda_min alarms when SMALL "
            "(ppf(alpha/2) of its law)",
            lambda m, K, alpha: (
                float(nis.extreme_eigenvalue(m, K, "min").isf(alpha / 2)),
                float(nis.extreme_eigenvalue(m, K, "max").isf(alpha / 2)),
            ),
        ),
    ],
    hint=[
        "Two thresholds share alpha: each tail gets half of it.",
        "The lower threshold is a quantile of the law of lambda_min (ppf), the upper one an "
        "upper quantile of the law of lambda_max (isf): nis.extreme_eigenvalue(m, K, which).",
    ],
)
def q4(m, K, alpha):
    return nis.nis_matrix_critical_values(m, K, alpha)


def _thresholds(m, K, alpha, low="min", high="max"):
    """(ppf(alpha/2) of the law of lambda_low, isf(alpha/2) of the law of lambda_high)."""
    return (
        float(nis.extreme_eigenvalue(m, K, low).ppf(alpha / 2)),
        float(nis.extreme_eigenvalue(m, K, high).isf(alpha / 2)),
    )


q4.case(2, 30, 0.05, label="m = 2, K = 30, alpha = 0.05")
### BEGIN HIDDEN TESTS
q4.case(3, 12, 0.1, hidden=True)
q4.case(2, 60, 0.01, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q5",
    func="matrix_test",
    points=2,
    rtol=1e-7,
    atol=1e-10,
    forbid=["course.nis.nis_matrix_test"],
    # Order matters where two mistakes give the same value on a case: the public cases are
    # ordered so that each mistake's FIRST failing case tells it apart (see the cases below).
    mistakes=[
        Mistake(
            "rejects only when BOTH extreme eigenvalues are outside: one eigenvalue outside "
            "its threshold is enough (lmin below the lower OR lmax above the upper)",
            lambda eps, S, alpha: _decided(eps, S, alpha, lambda low, high: low and high),
        ),
        Mistake(
            "the decision is never a rejection, even with both extreme eigenvalues outside "
            "their thresholds: is reject always False, or the comparisons the wrong way round?",
            lambda eps, S, alpha: _decided(eps, S, alpha, lambda low, high: False),
        ),
        Mistake(
            "rejects although both extreme eigenvalues lie between the thresholds: is reject "
            "always True, or are the comparisons the wrong way round?",
            lambda eps, S, alpha: _decided(eps, S, alpha, lambda low, high: True),
        ),
        Mistake(
            "the decision looks one-sided: thresholds at alpha instead of alpha/2",
            lambda eps, S, alpha: q5.reference(eps, S, 2 * alpha),
        ),
    ],
    hint=[
        "The test of q4 at level alpha: a two-sided test with two thresholds; m and K come "
        "from eps.shape (K rows, m columns).",
        "lmin and lmax are the extreme eigenvalues (np.linalg.eigvalsh) of your "
        "nis_matrix(eps, S); reject when lmin is below the lower threshold or lmax above the "
        "upper one, each threshold at alpha/2. Return (lmin, lmax, reject) with reject a bool.",
    ],
)
def q5(eps, S, alpha):
    result = nis.nis_matrix_test(eps, S, alpha)
    lmin, lmax = result.statistic
    return MatrixTest(lmin, lmax, bool(result.reject))


def _decided(eps, S, alpha, rule):
    """q5 with another decision ``rule(lmin below, lmax above)`` (the mistakes of q5)."""
    right = q5.reference(eps, S, alpha)
    K, m = np.shape(eps)
    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)
    return MatrixTest(right.lmin, right.lmax, bool(rule(right.lmin < lower, right.lmax > upper)))


# The order tells the mistakes apart: "always rejects" fails first on a case that does not
# reject, "never rejects" on the case with both eigenvalues outside (where "and" is right),
# "and instead of or" on a case with one eigenvalue outside, "one-sided" on the near case.
q5.case(EPS_A, S_A, 0.05, label="K = 5, m = 2, alpha = 0.05")
q5.case(EPS_BOTH_OUT, S_A, 0.05, label="K = 12, m = 2, alpha = 0.05, both eigenvalues outside")
q5.case(EPS_MAX_OUT, S_A, 0.05, label="K = 12, m = 2, alpha = 0.05, only lmax outside")
q5.case(EPS_MIN_OUT, np.eye(2), 0.05, label="K = 12, m = 2, alpha = 0.05, only lmin outside")
q5.case(EPS_GAP_HI, S_A, 0.05, label="K = 12, m = 2, alpha = 0.05, lmax near the upper threshold")
### BEGIN HIDDEN TESTS
q5.case(EPS_GAP_LO, np.eye(2), 0.05, hidden=True)
q5.case(EPS_GAP_3, S_F, 0.1, hidden=True)
q5.case(EPS_D, S_D, 0.05, hidden=True)
q5.case(EPS_C, S_C, 0.1, hidden=True)
q5.case(EPS_E, S_A, 0.01, hidden=True)
### END HIDDEN TESTS


# The practice record of q6_practice: the notebook's context cell builds the same one.
S_PRACTICE = np.array([[1.2, 0.3], [0.3, 0.8]])
_mix = np.linalg.cholesky(np.array([[1.0, 0.6], [0.6, 1.0]]))
EPS_PRACTICE = (
    np.random.default_rng(5050).standard_normal((60, 2)) @ _mix.T @ np.linalg.cholesky(S_PRACTICE).T
)


def _pvalues(eps, S, alpha):
    p_nis = nis.nis_test(eps, S, alpha).pvalue
    p_matrix = nis.nis_matrix_test(eps, S, alpha).pvalue
    return PValues(float(p_nis), float(p_matrix))


def _mistaken_pvalues(eps, S, average=False, one_sided=False, no_two=False):
    """(p_nis, p_matrix) with a declared mistake: chi2(m K) at the average NIS, p_nis
    one-sided (sf), or p_matrix without its factor 2."""
    K, m = np.shape(eps)
    total = float(np.sum(nis.nis(eps, S)))
    law = stats.chi2(m * K)
    at = total / K if average else total
    p_nis = float(law.sf(at)) if one_sided else min(1.0, 2 * min(law.cdf(at), law.sf(at)))
    values = np.linalg.eigvalsh(nis.nis_matrix(eps, S))
    tail = min(
        float(nis.extreme_eigenvalue(m, K, "min").cdf(values[0])),
        float(nis.extreme_eigenvalue(m, K, "max").sf(values[-1])),
    )
    return (float(p_nis), min(1.0, (1 if no_two else 2) * tail))


_PVALUE_MISTAKES = [
    (
        "p_nis looks computed at the AVERAGE NIS: chi2(m K) is the law of the SUM K eps_bar",
        {"average": True},
    ),
    ("p_matrix looks like one tail: the matrix test is two-sided, 2 min(...)", {"no_two": True}),
]
_ONE_SIDED_NIS = "p_nis looks one-sided: the NIS test is two-sided, p = 2 min(F, 1 - F)"


@CHECKS.function(
    "q6_practice",
    func="nis_pvalues",
    forbid=[
        "course.nis.nis_test",
        "course.nis.nis_matrix_test",
    ],
    points=1,
    rtol=1e-6,
    atol=1e-9,
    mistakes=[
        Mistake(
            _ONE_SIDED_NIS,
            lambda eps, S: (
                float(stats.chi2(np.size(eps)).sf(np.sum(nis.nis(eps, S)))),
                _pvalues(eps, S, 0.05)[1],
            ),
        ),
        *[
            Mistake(message, lambda eps, S, how=how: _mistaken_pvalues(eps, S, **how))
            for message, how in _PVALUE_MISTAKES
        ],
    ],
    hint=[
        "Both p-values are two-sided: 2 min(F, 1 - F), capped at 1 for the matrix test.",
        "p_nis uses the chi2(m K) law of the NIS SUM K * eps_bar (not of the average); "
        "p_matrix uses F_min at lmin and 1 - F_max at lmax of nis.extreme_eigenvalue(m, K, ...).",
    ],
)
def q6_practice(eps, S):
    return _pvalues(eps, S, 0.05)


def _record_case(seed):
    d = data.record(np.random.default_rng(seed))
    return d["eps"], d["S"]


q6_practice.case(EPS_PRACTICE, S_PRACTICE, label="the notebook's practice record")
### BEGIN HIDDEN TESTS
for _seed in (40, 41, 46, 54):  # a wrong correlation, a wrong scale, consistent, p_matrix = 1
    q6_practice.case(*_record_case(_seed), hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q6",
    forbid=[
        "course.nis.nis_test",
        "course.nis.nis_matrix_test",
    ],
    var="pvalues",
    points=2,
    rtol=1e-6,
    atol=1e-9,
    data="record",
    properties="record_properties",
    mistakes=[
        Mistake(
            _ONE_SIDED_NIS,
            lambda d: (
                float(stats.chi2(np.size(d["eps"])).sf(np.sum(nis.nis(d["eps"], d["S"])))),
                _pvalues(d["eps"], d["S"], 0.05)[1],
            ),
        ),
        *[
            Mistake(message, lambda d, how=how: _mistaken_pvalues(d["eps"], d["S"], **how))
            for message, how in _PVALUE_MISTAKES
        ],
    ],
    hint=[
        "Do q6_practice first: the same code must pass its public check there.",
        "p_nis = 2 min(F, 1 - F) of chi2(m K) at the NIS sum K * eps_bar; "
        "p_matrix = min(1, 2 min(F_min(lmin), 1 - F_max(lmax))) with the exact laws "
        "of nis.extreme_eigenvalue. nis.nis_test and nis.nis_matrix_test compute both.",
    ],
)
def q6(d):
    return _pvalues(d["eps"], d["S"], d["alpha"])


WHICH_OPTIONS = ["neither", "only the NIS test", "only the matrix test", "both"]


@CHECKS.choice(
    "q6_which",
    var="which_rejects",
    options=WHICH_OPTIONS,
    points=1,
    data="record",
    hint="One of the options, as a string (upper/lower case and surrounding spaces do not matter).",
)
def q6_which(d):
    p_nis, p_matrix = _pvalues(d["eps"], d["S"], d["alpha"])
    return WHICH_OPTIONS[int(p_nis < d["alpha"]) + 2 * int(p_matrix < d["alpha"])]


CHECKS.short_answer(
    "q6_why",
    points=1,
    rubric="Full marks (1): names the kind of error -- the filter's S has the right overall "
    "size (trace) but the wrong SHAPE, e.g. a correlation between the two outputs that S "
    "ignores (or variances too large in one direction and too small in another) -- AND says "
    "why the tests differ: the NIS sum only sees the trace of the NIS matrix (the sum of its "
    "eigenvalues), which such an error leaves about unchanged, while the extreme eigenvalues "
    "spread apart. Half (0.5): only one of the two parts. 0: 'too few samples', 'bad luck' "
    "alone, or a wrong scale of S as the reason (both tests see a scale error).",
)


@CHECKS.function(
    "q7",
    func="false_alarm_rate",
    points=2,
    timeout=30,
    forbid=["course.nis.simulate_extreme_eigenvalues", "course.nis.prob_eigenvalues_within"],
    mistakes=[
        Mistake(
            "the nominal alpha: for small K the test's size is below alpha -- simulate it",
            lambda m, K, alpha, n_runs, seed: float(alpha),
        ),
        Mistake(
            "the rate of thresholds at alpha each (one-sided): the test's two thresholds share "
            "alpha, alpha/2 in each tail",
            lambda m, K, alpha, n_runs, seed: _size_band(m, K, 2 * alpha, n_runs),
        ),
        Mistake(
            "the rate of a SUM of outer products (K times Pi): the NIS matrix is their mean",
            lambda m, K, alpha, n_runs, seed: _size_band(m, K, alpha, n_runs, scale=K),
        ),
        Mistake(
            "only lambda_max looks tested: the test also alarms when lambda_min falls below "
            "the lower threshold",
            lambda m, K, alpha, n_runs, seed: binomial_band(n_runs, alpha / 2, miss=1e-4),
        ),
        Mistake(
            "looks like a count of runs: return the fraction of the n_runs runs",
            lambda m, K, alpha, n_runs, seed: _size_band(m, K, alpha, n_runs, count=True),
        ),
    ],
    hint=[
        "Simulate, do not predict: with small K the rate is not alpha (both extreme "
        "eigenvalues can fall outside at once).",
        "rng = np.random.default_rng(seed); draw innovations of shape (n_runs, K, m) from "
        "N(0, I) (any S would do after whitening), form the NIS matrices of all runs at once "
        "(np.einsum), take their extreme eigenvalues (np.linalg.eigvalsh works on stacks) and "
        "return the fraction of runs outside the thresholds.",
    ],
)
def q7(m, K, alpha, n_runs, seed):
    return _size_band(m, K, alpha, n_runs)


def _size_band(m, K, alpha, n_runs, scale=1, count=False):
    """The band of the simulated false-alarm rate (``scale``: eigenvalues of ``scale`` Pi;
    ``count``: the number of runs, not the fraction; the declared mistakes)."""
    # The exact false-alarm rate is 1 - P(all eigenvalues inside the thresholds).
    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)
    size = 1.0 - nis.prob_eigenvalues_within(m, K, lower / scale, upper / scale)
    band = binomial_band(n_runs, size, miss=1e-4)
    return Band(band.lo * n_runs, band.hi * n_runs) if count else band


q7.case(2, 30, 0.05, 20000, 2024, label="m = 2, K = 30, alpha = 0.05, 20000 runs")
# With K = m = 3 the exact size is 0.281, not alpha = 0.3: "return alpha" lies outside the band.
q7.case(3, 3, 0.3, 20000, 11, label="m = 3, K = 3, alpha = 0.3, 20000 runs")
### BEGIN HIDDEN TESTS
q7.case(3, 10, 0.1, 20000, 7, hidden=True)
q7.case(4, 4, 0.4, 20000, 5, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q8",
    func="nees_interval",
    points=1,
    rtol=1e-7,
    atol=1e-10,
    forbid=[
        "course.nis.consistency_interval",
        "course.nis.nis_critical_values",
        "course.nis.nis_test",
    ],
    mistakes=[
        Mistake(
            "looks like the normal approximation n +- z sqrt(2n/N): the question asks for the "
            "exact chi2(n N) quantiles of the sum, divided by N",
            lambda n, N, alpha: (
                n - float(stats.norm.isf(alpha / 2)) * np.sqrt(2.0 * n / N),
                n + float(stats.norm.isf(alpha / 2)) * np.sqrt(2.0 * n / N),
            ),
        ),
        Mistake(
            "quantiles of chi2(nN) for the SUM: the run average is that sum divided by N",
            lambda n, N, alpha: (
                float(stats.chi2(n * N).ppf(alpha / 2)),
                float(stats.chi2(n * N).isf(alpha / 2)),
            ),
        ),
        Mistake(
            "looks like the normal approximation n +- 1.96 sqrt(2n/N): the question asks for "
            "the exact chi2(n N) quantiles of the sum, divided by N",
            lambda n, N, alpha: (n - 1.96 * np.sqrt(2.0 * n / N), n + 1.96 * np.sqrt(2.0 * n / N)),
        ),
        Mistake(
            "the quantiles of ONE run's chi2(n): the average of N runs is chi2(n N) / N, "
            "much narrower",
            lambda n, N, alpha: _interval(n, 1, alpha),
        ),
        Mistake(
            "divided by n N: N times the average NEES is chi2(n N), so divide by N only (the "
            "average NEES has mean n)",
            lambda n, N, alpha: _interval(n * N, n * N, alpha),
        ),
        Mistake(
            "alpha not split: a two-sided interval leaves alpha/2 in each tail",
            lambda n, N, alpha: _interval(n * N, N, alpha, tail=alpha),
        ),
        Mistake(
            "chi2(n N - 1): nothing is estimated from the runs, so all n N degrees of freedom stay",
            lambda n, N, alpha: _interval(n * N - 1, N, alpha),
        ),
    ],
    hint=[
        "Averaging over N runs works like averaging over K steps in q3: which multiple of "
        "the average is chi-square, and with how many degrees of freedom?",
        "Each run's NEES is chi2(n); the sum over N independent runs is chi2(n N).",
        "Take the two-sided quantiles of chi2(n N) (alpha/2 in each tail) and divide them by N.",
    ],
)
def q8(n, N, alpha):
    law = stats.chi2(n * N)
    return Interval(float(law.ppf(alpha / 2)) / N, float(law.isf(alpha / 2)) / N)


q8.case(4, 50, 0.05, label="n = 4 states, N = 50 runs, 95 %")
### BEGIN HIDDEN TESTS
q8.case(2, 20, 0.01, hidden=True)
q8.case(6, 100, 0.1, hidden=True)
### END HIDDEN TESTS
