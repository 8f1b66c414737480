"""Checks of assignment 07_testing_theory (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

from collections import namedtuple

import numpy as np
from scipy import stats

from course import chi2, lsq
from course.grading.authoring.checks import Checks, Mistake

from . import data

# Results with several parts are named tuples: feedback names the part that is wrong.
GLRDecision = namedtuple("GLRDecision", "T critical_value reject")
FTest = namedtuple("FTest", "F critical_value reject")
DIAResult = namedtuple("DIAResult", "T reject identified x_hat")

# The notebook's line with an outlier: ten heights, sigma = 0.1, a blunder in observation 6.
T10 = np.arange(10.0)
A10 = np.column_stack([np.ones(10), T10])
Y10 = np.array([2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53])
Q10 = 0.01 * np.eye(10)
UNIT10 = np.eye(10)
JUMP10 = np.r_[np.zeros(7), np.ones(3)][:, None]  # a level shift of the last three heights


def _correlated(m, rho, scale=1.0):
    """An exponentially correlated covariance matrix (symmetric positive definite)."""
    idx = np.arange(m)
    return scale * rho ** np.abs(idx[:, None] - idx[None, :])


# The same line with correlated noise: a public case where Qyy is not a multiple of I.
Q10C = _correlated(10, 0.6, 0.01)

# Hidden data: a quadratic model with correlated noise, and a line with individual sigmas.
_RNG = np.random.default_rng(20261127)
T12 = np.linspace(-1.0, 1.0, 12)
A12 = np.column_stack([np.ones(12), T12, T12**2])
Q12 = _correlated(12, 0.5, 0.04) + np.diag(_RNG.uniform(0.005, 0.02, 12))
Y12 = A12 @ [1.0, 0.5, -0.3] + np.linalg.cholesky(Q12) @ _RNG.standard_normal(12)
Y12[[3, 4]] += [0.8, 0.6]
SIGMA9 = _RNG.uniform(0.5, 2.0, 9)
A9 = np.column_stack([np.ones(9), np.arange(9.0)])
Q9 = np.diag(SIGMA9**2)
Y9 = A9 @ [3.0, -0.4] + SIGMA9 * _RNG.standard_normal(9)
Y9[7] += 5.0 * SIGMA9[7]

# The public practice line of q6_practice and q7_practice (data.levelling with seed 7).
PRACTICE = data.levelling(np.random.default_rng(7))

CHECKS = Checks(
    "07_testing_theory",
    title="Assignment 7: testing theory beyond one outlier",
    data=data,
    timeout=10,
    preload=["course.lsq", "course.chi2", "scipy.stats", "scipy.linalg"],
)

#: Every function that would answer a question in one call. A q-dimensional test, its laws
#: and the DIA procedure are what the assignment asks you to build.
_TESTS = [
    "course.lsq.fit",
    "course.lsq.glr_test",
    "course.lsq.w_tests",
    "course.lsq.overall_model_test",
    "course.lsq.alternative_law",
    "course.lsq.minimal_detectable_bias",
    "course.lsq.dia",
    "course.lsq.data_snooping",
    # notebook 3's exact GLR test of nested linear models: T_q of whitened [A C] in one call
    "course.diagnosis.linear_glr_test",
    "course.diagnosis.regression_parameter_test",
]


def _fit(A, y, Qyy):
    return lsq.fit(np.asarray(A, dtype=float), np.asarray(y, dtype=float), Qyy)


def _diagonal_only(Qyy):
    return np.diag(np.diag(np.asarray(Qyy, dtype=float)))


def _unprojected_T(A, y, Qyy, C):
    """T_q with C^T Qyy^{-1} C in the middle: C not taken into the residual space."""
    f = _fit(A, y, Qyy)
    C = np.asarray(C, dtype=float)
    v = C.T @ np.linalg.solve(Qyy, f.e_hat)
    return float(v @ np.linalg.solve(C.T @ np.linalg.solve(Qyy, C), v))


# ---------------------------------------------------------------------------
# q1-q3: the test of a q-dimensional alternative
# ---------------------------------------------------------------------------
@CHECKS.function(
    "q1",
    func="glr_statistic",
    points=3,
    # tight: T_q of these small, well-conditioned lines agrees to ~1e-13 between right
    # float64 methods, while float32's round-off (2e-8 to 6e-7 here) sat just inside 1e-6
    rtol=1e-9,
    atol=1e-10,
    forbid=_TESTS,
    hint=(
        "T_q measures how much better the alternative E(y) = Ax + C∇ explains the data: it is "
        "the drop of the weighted residual norm when ∇ is estimated too.",
        "The middle matrix is C^T Qyy^{-1} Qee Qyy^{-1} C, with Qee = Qyy - A Qxx A^T: the part "
        "of the bias that the model cannot absorb. Whiten with the Cholesky factor of Qyy and "
        "project C off the whitened A (a QR factorisation).",
    ),
    mistakes=[
        Mistake(
            "C was not taken into the residual space: the middle matrix looks like "
            "C^T Qyy^{-1} C instead of C^T Qyy^{-1} Qee Qyy^{-1} C (the part of C∇ that the "
            "line can imitate must be removed first)",
            _unprojected_T,
        ),
        Mistake(
            "looks unweighted: Qyy was ignored",
            lambda A, y, Qyy, C: lsq.glr_test(_fit(A, y, None), C).statistic,
        ),
        Mistake(
            "this is the overall model test's T (every direction at once), not T_q of the "
            "columns of C",
            lambda A, y, Qyy, C: _fit(A, y, Qyy).squared_norm,
        ),
        Mistake(
            "only the diagonal of Qyy was used: with correlated observations whiten with the "
            "full Cholesky factor of Qyy",
            lambda A, y, Qyy, C: lsq.glr_test(_fit(A, y, _diagonal_only(Qyy)), C).statistic,
        ),
    ],
)
def q1(A, y, Qyy, C):
    return float(lsq.glr_test(_fit(A, y, Qyy), C).statistic)


q1.case(A10, Y10, Q10, UNIT10[:, [6]], label="the notebook's line, C = c_6 (q = 1)")
q1.case(A10, Y10, Q10, UNIT10[:, [6, 7]], label="the same line, C = [c_6 c_7] (q = 2)")
q1.case(A10, Y10, Q10C, UNIT10[:, [6, 7]], label="C = [c_6 c_7], correlated noise (rho = 0.6)")
### BEGIN HIDDEN TESTS
q1.case(A10, Y10, Q10, JUMP10, hidden=True)
q1.case(A12, Y12, Q12, np.eye(12)[:, [3, 4]], hidden=True)
q1.case(A12, Y12, Q12, np.eye(12)[:, [0, 5, 11]], hidden=True)
q1.case(A9, Y9, Q9, np.eye(9)[:, [7]], hidden=True)
### END HIDDEN TESTS


def _decision(A, y, Qyy, C, alpha, dof):
    statistic = float(lsq.glr_test(_fit(A, y, Qyy), C).statistic)
    critical = float(stats.chi2.isf(alpha, dof))
    return (statistic, critical, bool(statistic > critical))


@CHECKS.function(
    "q2",
    func="glr_decision",
    points=2,
    rtol=1e-6,
    atol=1e-8,
    forbid=_TESTS,
    hint=(
        "Under H0, T_q is chi-square: with how many degrees of freedom? Count the bias "
        "parameters, not the observations.",
        "The critical value is scipy.stats.chi2.isf(alpha, q), upper tail only; return "
        "(T, critical_value, reject).",
    ),
    mistakes=[
        Mistake(
            "the critical value looks like chi2 with m - n degrees of freedom (the overall "
            "model test's): T_q has q, the number of columns of C",
            lambda A, y, Qyy, C, alpha: _decision(
                A, y, Qyy, C, alpha, np.shape(A)[0] - np.shape(A)[1]
            ),
        ),
        Mistake(
            "the critical value looks like chi2 with 1 degree of freedom: T_q has q, the "
            "number of columns of C",
            lambda A, y, Qyy, C, alpha: _decision(A, y, Qyy, C, alpha, 1),
        ),
        Mistake(
            "the critical value looks two-sided (alpha/2): T_q rejects in the upper tail only",
            lambda A, y, Qyy, C, alpha: _decision(A, y, Qyy, C, alpha / 2, np.shape(C)[1]),
        ),
        Mistake(
            "the critical value looks like the LOWER alpha-quantile (ppf(alpha)): T_q rejects "
            "when it is large, so the threshold leaves alpha in the upper tail",
            lambda A, y, Qyy, C, alpha: _decision(A, y, Qyy, C, 1.0 - alpha, np.shape(C)[1]),
        ),
    ],
)
def q2(A, y, Qyy, C, alpha):
    result = lsq.glr_test(_fit(A, y, Qyy), C, alpha)
    return GLRDecision(float(result.statistic), float(result.critical_value), bool(result.reject))


q2.case(A10, Y10, Q10, UNIT10[:, [6, 7]], 0.01, label="the line, C = [c_6 c_7], alpha = 0.01")
q2.case(A10, Y10, Q10, JUMP10, 0.05, label="the line, a level shift of the last three, 0.05")
### BEGIN HIDDEN TESTS
q2.case(A12, Y12, Q12, np.eye(12)[:, [3, 4]], 0.05, hidden=True)
q2.case(A12, Y12, Q12, np.eye(12)[:, [0, 5, 11]], 0.01, hidden=True)
q2.case(A9, Y9, Q9, np.eye(9)[:, [6, 7]], 0.10, hidden=True)
### END HIDDEN TESTS


def _f_with(
    A,
    y,
    Qyy,
    C,
    alpha,
    *,
    sigma2_from_h0=False,
    omega_over_r_minus_q=False,
    dof2=None,
    chi2_critical=False,
    F_as=None,
):
    """F built the way a mistake builds it (``F_as``: "T" or "T/q", sigma² not estimated)."""
    f = _fit(A, y, Qyy)
    q = np.shape(C)[1]
    r = f.redundancy
    T = float(lsq.glr_test(f, C).statistic)
    rest = f.squared_norm / r if sigma2_from_h0 else (f.squared_norm - T) / (r - q)
    if omega_over_r_minus_q:
        rest = f.squared_norm / (r - q)
    F = (T / q) / rest
    if F_as is not None:
        F = T if F_as == "T" else T / q
    dof2 = r - q if dof2 is None else dof2
    critical = float(stats.chi2.isf(alpha, q) / q if chi2_critical else stats.f.isf(alpha, q, dof2))
    return (F, critical, bool(critical < F))


@CHECKS.function(
    "q3",
    func="f_test",
    points=3,
    rtol=1e-6,
    atol=1e-8,
    forbid=_TESTS,
    hint=(
        "With sigma² unknown, estimate it under the ALTERNATIVE: its residual norm is "
        "Ω - T_q, with m - n - q degrees of freedom.",
        "F = (T_q / q) / ((Ω - T_q) / (m - n - q)) ~ F(q, m - n - q) under H0, with "
        "Ω = e^T Qyy^{-1} e; the critical value is scipy.stats.f.isf(alpha, q, m - n - q). "
        "Return (F, critical_value, reject).",
    ),
    mistakes=[
        Mistake(
            "sigma² looks estimated from the null model's residuals (Ω / (m - n)): under the "
            "alternative the bias is estimated, so use (Ω - T_q) / (m - n - q)",
            lambda A, y, Qyy, C, alpha: _f_with(A, y, Qyy, C, alpha, sigma2_from_h0=True),
        ),
        Mistake(
            "the denominator looks like Ω / (m - n - q): under the alternative the residual "
            "norm is Ω - T_q (estimating the bias removes T_q from it)",
            lambda A, y, Qyy, C, alpha: _f_with(A, y, Qyy, C, alpha, omega_over_r_minus_q=True),
        ),
        Mistake(
            "F looks right but its critical value has m - n denominator degrees of freedom: "
            "the alternative uses q more parameters, leaving m - n - q",
            lambda A, y, Qyy, C, alpha: _f_with(
                A, y, Qyy, C, alpha, dof2=np.shape(A)[0] - np.shape(A)[1]
            ),
        ),
        Mistake(
            "the critical value looks like chi2(q)/q: with sigma² estimated the law is F, "
            "with heavier tails",
            lambda A, y, Qyy, C, alpha: _f_with(A, y, Qyy, C, alpha, chi2_critical=True),
        ),
        Mistake(
            "F looks like T_q itself: sigma² is unknown, so divide T_q / q by its estimate "
            "under the alternative",
            lambda A, y, Qyy, C, alpha: _f_with(A, y, Qyy, C, alpha, F_as="T"),
        ),
        Mistake(
            "F looks like T_q / q, with sigma² taken as known (as stated in Qyy): divide by "
            "the estimate of sigma² under the alternative",
            lambda A, y, Qyy, C, alpha: _f_with(A, y, Qyy, C, alpha, F_as="T/q"),
        ),
    ],
)
def q3(A, y, Qyy, C, alpha):
    result = lsq.glr_test(_fit(A, y, Qyy), C, alpha, variance="estimated")
    return FTest(float(result.statistic), float(result.critical_value), bool(result.reject))


q3.case(A10, Y10, Q10, UNIT10[:, [6, 7]], 0.05, label="the line, C = [c_6 c_7], alpha = 0.05")
q3.case(A10, Y10, 4.0 * Q10, JUMP10, 0.05, label="the line with sigma stated 0.2, a level shift")
### BEGIN HIDDEN TESTS
q3.case(A12, Y12, Q12, np.eye(12)[:, [3, 4]], 0.05, hidden=True)
q3.case(A12, Y12, 9.0 * Q12, np.eye(12)[:, [0, 5, 11]], 0.01, hidden=True)
q3.case(A9, Y9, Q9, np.eye(9)[:, [7]], 0.05, hidden=True)
### END HIDDEN TESTS


# ---------------------------------------------------------------------------
# q4: the w-test with an estimated variance
# ---------------------------------------------------------------------------
def _t_with(A, y, Qyy, *, dof_drop=1, root=True):
    """t_i built the way a mistake builds it."""
    f = _fit(A, y, Qyy)
    w = np.asarray(lsq.w_tests(f).statistic)
    estimate = (f.squared_norm - w**2) / (f.redundancy - dof_drop)
    return w / (np.sqrt(estimate) if root else estimate)


def _t_from_normalised_residuals(A, y, Qyy):
    """t_i built from e_i / sigma_e_i instead of w_i (right only for a diagonal Qyy)."""
    f = _fit(A, y, Qyy)
    Qyy = np.asarray(Qyy, dtype=float)
    A = np.asarray(A, dtype=float)
    Qxx_At = np.linalg.solve(A.T @ np.linalg.solve(Qyy, A), A.T)
    v = np.asarray(f.e_hat) / np.sqrt(np.diag(Qyy) - np.einsum("ij,ji->i", A, Qxx_At))
    return v / np.sqrt((f.squared_norm - v**2) / (f.redundancy - 1))


def _tau(A, y, Qyy):
    f = _fit(A, y, Qyy)
    return np.asarray(lsq.w_tests(f).statistic) / np.sqrt(f.squared_norm / f.redundancy)


@CHECKS.function(
    "q4",
    func="t_statistics",
    points=2,
    rtol=1e-6,
    atol=1e-8,
    forbid=_TESTS,
    hint=(
        "Start from Baarda's w_i (notebook 1) and divide by an estimate of sigma: which model's "
        "residuals estimate it when observation i is suspected?",
        "t_i = w_i / sqrt((Ω - w_i²) / (m - n - 1)), Ω = e^T Qyy^{-1} e: sigma² estimated with "
        "observation i given a bias of its own (its residual norm drops by w_i²).",
    ),
    mistakes=[
        Mistake(
            "these are Pope's tau_i = w_i / sqrt(Ω / (m - n)), sigma estimated under H0: the "
            "question asks for Student's t_i, sigma estimated under the alternative of test i",
            _tau,
        ),
        Mistake(
            "these are Baarda's w_i with sigma taken as known: divide by the estimated sigma",
            lambda A, y, Qyy: np.asarray(lsq.w_tests(_fit(A, y, Qyy)).statistic),
        ),
        Mistake(
            "sigma² under the alternative of test i looks divided by m - n: that model has one "
            "parameter more (the bias of observation i), so m - n - 1 degrees of freedom",
            lambda A, y, Qyy: _t_with(A, y, Qyy, dof_drop=0),
        ),
        Mistake(
            "these look like |t_i|: keep the sign of w_i (the test is two-sided, the "
            "statistic is not)",
            lambda A, y, Qyy: np.abs(_t_with(A, y, Qyy)),
        ),
        Mistake(
            "w_i looks divided by the estimated VARIANCE: divide by its square root, the "
            "estimated sigma",
            lambda A, y, Qyy: _t_with(A, y, Qyy, root=False),
        ),
        Mistake(
            "only the diagonal of Qyy was used: with correlated observations w_i needs the "
            "full Qyy (whiten with its Cholesky factor)",
            lambda A, y, Qyy: np.asarray(
                lsq.w_tests(_fit(A, y, _diagonal_only(Qyy)), variance="estimated").statistic
            ),
        ),
        Mistake(
            "e_i / sigma_e_i is w_i only for uncorrelated observations: with a full Qyy, "
            "w_i = (Qyy^{-1} e)_i / sqrt((Qyy^{-1} Qee Qyy^{-1})_ii)",
            lambda A, y, Qyy: _t_from_normalised_residuals(A, y, Qyy),
        ),
    ],
)
def q4(A, y, Qyy):
    return np.asarray(lsq.w_tests(_fit(A, y, Qyy), variance="estimated").statistic)


q4.case(A10, Y10, Q10, label="the notebook's line")
q4.case(A10, Y10, 4.0 * Q10, label="the same line with sigma stated 0.2")
q4.case(A10, Y10, Q10C, label="the same line with correlated noise (rho = 0.6)")
### BEGIN HIDDEN TESTS
q4.case(A12, Y12, Q12, hidden=True)
q4.case(A9, Y9, Q9, hidden=True)
### END HIDDEN TESTS


# ---------------------------------------------------------------------------
# q5: Baarda's B-method
# ---------------------------------------------------------------------------
def _b_level_with(alpha_1, power, q, *, lambda_dof=1, quantile=None):
    lam0 = chi2.noncentrality(alpha_1, power, lambda_dof)
    level = 1.0 - power if quantile is None else quantile
    return float(stats.chi2.sf(stats.ncx2.ppf(level, q, lam0), q))


@CHECKS.function(
    "q5",
    func="b_method_level",
    points=2,
    rtol=1e-6,
    atol=1e-10,
    forbid=["course.lsq.b_method"],
    hint=(
        "First the reference bias: the non-centrality lambda_0 at which the ONE-dimensional "
        "test (level alpha_1) has the given power (course.chi2.noncentrality may help).",
        "Then the level alpha_q at which the q-dimensional test has the same power at "
        "lambda_0: its critical value is the (1 - power) quantile of chi2(q, lambda_0), and "
        "alpha_q = P(chi2(q) > that critical value).",
    ),
    mistakes=[
        Mistake(
            "lambda_0 looks computed at alpha_1/2: the one-dimensional w-test of the B-method "
            "is two-sided, and chi2(1) > k at level alpha_1 already holds both tails of w",
            lambda alpha_1, power, q: _b_level_with(alpha_1 / 2, power, q),
            hint="w² ~ chi2(1): its upper tail at alpha_1 is the two tails of w at alpha_1/2 "
            "each, so lambda_0 = chi2.noncentrality(alpha_1, power, 1), with alpha_1 itself.",
        ),
        Mistake(
            "returns alpha_1 (or lambda_0 was computed with q degrees of freedom): the "
            "B-method keeps lambda_0 of the one-dimensional test fixed, not the level",
            lambda alpha_1, power, q: float(alpha_1),
        ),
        Mistake(
            "the critical value looks like the power-quantile of chi2(q, lambda_0): the test "
            "must reject with probability power, so take the (1 - power) quantile",
            lambda alpha_1, power, q: _b_level_with(alpha_1, power, q, quantile=power),
        ),
        Mistake(
            "looks like 1 - alpha_q, the probability BELOW the critical value: the level is "
            "the upper-tail probability P(chi2(q) > critical value)",
            lambda alpha_1, power, q: 1.0 - _b_level_with(alpha_1, power, q),
        ),
        Mistake(
            "this looks like the POWER of the q-dimensional test at level alpha_1 for the bias "
            "lambda_0: the question asks for the level alpha_q at which that power equals "
            "the given one",
            lambda alpha_1, power, q: float(
                stats.ncx2.sf(stats.chi2.isf(alpha_1, q), q, chi2.noncentrality(alpha_1, power, 1))
            ),
        ),
    ],
)
def q5(alpha_1, power, q):
    return float(lsq.b_method(alpha_1, power, q).alpha_q)


q5.case(0.001, 0.80, 2, label="alpha_1 = 0.001, power 0.80, q = 2")
q5.case(0.001, 0.80, 18, label="alpha_1 = 0.001, power 0.80, q = 18")
### BEGIN HIDDEN TESTS
q5.case(0.01, 0.90, 5, hidden=True)
q5.case(0.001, 0.50, 3, hidden=True)
q5.case(0.05, 0.80, 30, hidden=True)
### END HIDDEN TESTS


# ---------------------------------------------------------------------------
# q6, q7: your own levelling line
# ---------------------------------------------------------------------------
def _pair_T(d, Qyy=...):
    Qyy = d["Qyy"] if Qyy is ... else Qyy
    f = _fit(d["A"], d["y"], Qyy)
    return float(lsq.glr_test(f, np.eye(len(d["y"]))[:, d["pair"]]).statistic)


_PAIR_MISTAKES = [
    Mistake("looks unweighted: the Qyy of the data was ignored", lambda d: _pair_T(d, None)),
    Mistake(
        "this is w² of the first observation of the pair alone (q = 1): the alternative has a "
        "bias in each of the two observations",
        lambda d: float(
            lsq.glr_test(
                _fit(d["A"], d["y"], d["Qyy"]), np.eye(len(d["y"]))[:, d["pair"][0]]
            ).statistic
        ),
    ),
    Mistake(
        "this is the overall model test's T, not T_2 of the pair",
        lambda d: _fit(d["A"], d["y"], d["Qyy"]).squared_norm,
    ),
]


@CHECKS.function(
    "q6_practice",
    func="pair_statistic",
    points=1,
    rtol=1e-6,
    atol=1e-8,
    hint="Your glr_statistic on a line given as a dict like practice, with C the two columns "
    "of the identity named by line['pair'] and the weights line['Qyy'].",
    mistakes=_PAIR_MISTAKES,
)
def q6_practice(line):
    return _pair_T(line)


@CHECKS.value(
    "q6",
    var="T_pair_mine",
    points=2,
    data="levelling",
    properties="statistic_properties",
    rtol=1e-6,
    atol=1e-8,
    hint="The same as q6_practice, on your own line mine: C = the columns mine['pair'] of the "
    "identity, weights mine['Qyy'].",
    mistakes=_PAIR_MISTAKES
    + [
        Mistake(
            "this is T_2 of the public practice line: compute it on your own line mine",
            lambda d: _pair_T(PRACTICE),
        ),
        Mistake(
            "this is T_2 of another pair of observations: C holds the two columns of the "
            "identity named by mine['pair']",
            lambda d: _pair_T({**d, "pair": [d["pair"][0] - 1, d["pair"][0]]}),
        ),
    ],
)
def q6(d):
    return _pair_T(d)


def _dia(d, remove=..., Qyy=..., weighted_refit=True):
    """The DIA result (T, reject, identified, x_hat): detection by the overall model test,
    identification by the largest |w|, adaptation by the refit without it. ``remove`` names
    another observation to remove (a mistake), ``Qyy=None`` drops the weights everywhere."""
    Qyy = d["Qyy"] if Qyy is ... else Qyy
    A, y = d["A"], d["y"]
    f = _fit(A, y, Qyy)
    reject = bool(lsq.overall_model_test(f, d["alpha"]).reject)
    if not reject:
        return DIAResult(float(f.squared_norm), reject, None, np.asarray(f.x_hat))
    identified = int(lsq.w_tests(f, d["alpha"]).largest) if remove is ... else int(remove)
    keep = np.delete(np.arange(len(y)), identified)
    sub = None if Qyy is None or not weighted_refit else np.asarray(Qyy)[np.ix_(keep, keep)]
    x_hat = np.asarray(_fit(A[keep], y[keep], sub).x_hat)
    return DIAResult(float(f.squared_norm), reject, identified, x_hat)


def _largest_e(d):
    return int(np.argmax(np.abs(_fit(d["A"], d["y"], d["Qyy"]).e_hat)))


_DIA_MISTAKES = [
    Mistake(
        "x_hat is the null model's estimate: after detection and identification, adapt (re-fit "
        "without the identified observation)",
        lambda d: _dia(d)._replace(x_hat=np.asarray(_fit(d["A"], d["y"], d["Qyy"]).x_hat)),
    ),
    Mistake(
        "the observation with the largest |e| was identified: identification uses the largest "
        "|w|, each residual weighed by its own standard deviation",
        lambda d: _dia(d, remove=_largest_e(d)),
    ),
    Mistake("looks unweighted: the Qyy of the data was ignored", lambda d: _dia(d, Qyy=None)),
    Mistake(
        "the right observation was removed, but the refit without it is unweighted: keep "
        "the weights of the other observations",
        lambda d: _dia(d, weighted_refit=False),
    ),
]


@CHECKS.function(
    "q7_practice",
    func="dia_estimate",
    points=1,
    rtol=1e-6,
    atol=1e-8,
    hint="Detect: T = e^T Qyy^{-1} e of the overall model test at d['alpha'] and its decision; "
    "identify: the index of the largest |w| (None if nothing is rejected); adapt: fit the line "
    "without it. Return (T, reject, identified, x_hat), x_hat = (height at t = 0, slope).",
    # data snooping removes observations until no w-test rejects: on the practice line three
    # (on almost every personal line more than one, but not on all: so only here)
    mistakes=[
        *_DIA_MISTAKES,
        Mistake(
            "several observations were removed (data snooping repeats the w-tests until none "
            "rejects): the DIA procedure adapts once, to the one identified alternative",
            lambda d: _dia(d)._replace(
                x_hat=np.asarray(
                    lsq.data_snooping(_fit(d["A"], d["y"], d["Qyy"]), alpha=d["alpha"]).fit.x_hat
                )
            ),
        ),
    ],
)
def q7_practice(d):
    return _dia(d)


def _line(d):
    """A levelling line as the notebook's practice dict (without the times t)."""
    return {key: d[key] for key in ("A", "y", "Qyy", "alpha", "pair")}


# public: the notebook's practice line; hidden: lines of the students' design (data.levelling)
for _q in (q6_practice, q7_practice):
    _q.case(_line(PRACTICE), label="the notebook's practice line")
### BEGIN HIDDEN TESTS
for _q in (q6_practice, q7_practice):
    for _seed in (71, 72, 73):
        _q.case(_line(data.levelling(np.random.default_rng(_seed))), hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q7",
    var="dia_mine",
    points=2,
    data="levelling",
    properties="dia_properties",
    rtol=1e-6,
    atol=1e-8,
    hint="The same procedure as q7_practice on your own line mine: (T, reject, identified, x_hat).",
    mistakes=_DIA_MISTAKES
    + [
        Mistake(
            "this is the DIA result of the public practice line: run it on your own line mine",
            lambda d: _dia(PRACTICE),
        )
    ],
)
def q7(d):
    return _dia(d)


# ---------------------------------------------------------------------------
# q8: why? The law of the DIA estimator
# ---------------------------------------------------------------------------
@CHECKS.choice(
    "q8",
    var="dia_law",
    options=[
        "normal, with the covariance of the null model",
        "normal, with the covariance of the adapted model",
        "a mixture, not normal",
    ],
    points=1,
    hint="Copy one of the three options (case and surrounding spaces do not matter). Think of "
    "what the estimate is in the runs where nothing was detected and in those where an "
    "observation was removed.",
)
def q8():
    return "a mixture, not normal"


# ---------------------------------------------------------------------------
# q9: reliability of a q-dimensional alternative
# ---------------------------------------------------------------------------
def _mdb_with(A, Qyy, C, alpha, power, direction, *, lambda_dof=None, projected=True):
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    q = C.shape[1]
    lam0 = chi2.noncentrality(alpha, power, q if lambda_dof is None else lambda_dof)
    Qi_C = np.linalg.solve(Qyy, C)
    if projected:
        Qi_A = np.linalg.solve(Qyy, A)
        middle = C.T @ Qi_C - (C.T @ Qi_A) @ np.linalg.solve(A.T @ Qi_A, Qi_A.T @ C)
    else:
        middle = C.T @ Qi_C
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    return np.sqrt(lam0 / float(d @ middle @ d)) * d


@CHECKS.function(
    "q9",
    func="mdb_along",
    points=2,
    rtol=1e-6,
    atol=1e-10,
    forbid=_TESTS + ["course.lsq.mdb"],
    hint=(
        "A bias ∇ = s d (d a unit direction) is found with the given power when its "
        "non-centrality ∇^T (C^T Qyy^{-1} Qee Qyy^{-1} C) ∇ reaches lambda_0.",
        "lambda_0 belongs to the q-dimensional test: course.chi2.noncentrality(alpha, power, q) "
        "with q the number of columns of C. Return the vector s d.",
    ),
    mistakes=[
        Mistake(
            "lambda_0 looks like that of a one-dimensional test: the test of C has q "
            "degrees of freedom, and lambda_0 grows with q",
            lambda A, Qyy, C, alpha, power, direction: _mdb_with(
                A, Qyy, C, alpha, power, direction, lambda_dof=1
            ),
        ),
        Mistake(
            "C was not taken into the residual space (C^T Qyy^{-1} C in the middle): the part "
            "of the bias the model absorbs cannot be detected",
            lambda A, Qyy, C, alpha, power, direction: _mdb_with(
                A, Qyy, C, alpha, power, direction, projected=False
            ),
        ),
        Mistake(
            "the bias points along direction but its length is off by the length of "
            "direction: normalise d to a unit vector before scaling it",
            lambda A, Qyy, C, alpha, power, direction: (
                _mdb_with(A, Qyy, C, alpha, power, direction)
                * np.linalg.norm(np.asarray(direction, dtype=float))
            ),
        ),
    ],
)
def q9(A, Qyy, C, alpha, power, direction):
    fit = lsq.fit(np.asarray(A, dtype=float), np.zeros(np.shape(A)[0]), Qyy)
    return np.asarray(lsq.minimal_detectable_bias(fit, C, alpha, power).along(direction))


q9.case(A10, Q10, UNIT10[:, [6, 7]], 0.01, 0.80, [1.0, 0.0], label="obs. 6 and 7, along c_6")
q9.case(A10, Q10, UNIT10[:, [6, 7]], 0.01, 0.80, [1.0, 1.0], label="obs. 6 and 7, equal biases")
### BEGIN HIDDEN TESTS
q9.case(A12, Q12, np.eye(12)[:, [3, 4]], 0.05, 0.90, [1.0, -1.0], hidden=True)
q9.case(A12, Q12, np.eye(12)[:, [0, 5, 11]], 0.001, 0.80, [0.2, 1.0, -0.5], hidden=True)
q9.case(A9, Q9, np.eye(9)[:, [7]], 0.001, 0.80, [1.0], hidden=True)
### END HIDDEN TESTS
