"""Checks of assignment 06_mismatched_filters (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

from collections import namedtuple

import numpy as np
from scipy import stats

from course import filters, mismatched
from course.grading.authoring.checks import Checks, Mistake
from course.quadform import QuadraticForm, WeightedChiSquare

from . import data

# Results with several parts are named tuples: feedback names the part that is wrong
# (``critical_value``, not ``item [1]``). A student's plain tuple or list in the same order
# is just as right (the grader compares item by item).
Augmented = namedtuple("Augmented", "F_tilde H_tilde")
SectionStatistics = namedtuple("SectionStatistics", "mean_sq_norm c_j c_jk")
CriticalValues = namedtuple("CriticalValues", "lower upper")
PValues = namedtuple("PValues", "p_mean p_corr")

_FORBID_MOMENTS = [
    "course.mismatched.residual_moments",
    "course.mismatched.residual_moments_as_printed",
]
_FORBID_TESTS = [
    "course.mismatched.mean_test",
    "course.mismatched.covariance_test",
    "course.mismatched.correlation_test",
    "course.mismatched.statistic_law",
    "course.mismatched.power",
    # a critical value, p-value or power of a law in one line (issue 26)
    "course.results.critical_value",
    "course.results.rejection_probability",
    "course.results.decide",
    "course.results.TestResult.from_null",
    "course.results.TestResult.power",
]

# a reduced-order pair (2 true states, 1 filter state) and a same-order pair with two outputs
F0_A, H0_A = np.array(data.M0.F), np.array(data.M0.H)
F1_A, H1_A = np.array(data.M1.F), np.array(data.M1.H)
K_A = filters.riccati_gains(data.M1, 6)

_B0 = filters.LinearModel(
    F=[[0.8, 0.3], [0.0, 0.7]],
    H=[[1.0, 0.0], [0.5, 1.0]],
    Q=np.diag([0.4, 0.3]),
    R=[[1.0, 0.3], [0.3, 0.8]],
    x0_cov=np.diag([1.0, 0.5]),
)
_B1 = filters.LinearModel(
    F=[[0.6, 0.0], [0.1, 0.9]],
    H=np.eye(2),
    Q=np.eye(2),
    R=[[0.5, 0.0], [0.0, 0.7]],
    x0_cov=2 * np.eye(2),
)
K_B = filters.riccati_gains(_B1, 5)
_C0 = filters.LinearModel(
    F=[[0.5, 0.2, 0.0], [0.0, 0.9, 0.1], [0.0, 0.0, 0.95]],
    H=[[1.0, 0.0, 1.0]],
    Q=np.diag([1.0, 0.2, 0.05]),
    R=[[0.5]],
    x0_cov=np.eye(3),
)
_C1 = filters.LinearModel(F=[[0.7]], H=[[1.0]], Q=[[1.5]], R=[[0.8]], x0_cov=[[3.0]])
K_C = filters.riccati_gains(_C1, 8)

CHECKS = Checks(
    "06_mismatched_filters",
    title="Assignment 6: mismatched filters, many records and Imhof's method",
    data=data,
    timeout=10,
    preload=["course.mismatched", "course.quadform", "course.filters"],
)


def _augmented(F0, H0, F1, H1, K):
    n0, n1 = F0.shape[0], F1.shape[0]
    F = np.zeros((n0 + n1, n0 + n1))
    F[:n0, :n0] = F0
    F[n0:, :n0] = F1 @ K @ H0
    F[n0:, n0:] = F1 @ (np.eye(n1) - K @ H1)
    return Augmented(F, np.hstack([H0, -H1]))


@CHECKS.function(
    "q1",
    func="augmented_matrices",
    points=2,
    rtol=1e-10,
    atol=1e-12,
    forbid=_FORBID_MOMENTS,
    mistakes=[
        Mistake(
            "a sign error: the residual is H0 x - H1 xhat, so the block of H1 in H~ carries a minus sign",
            lambda F0, H0, F1, H1, K: (
                q1.reference(F0, H0, F1, H1, K)[0],
                np.hstack([np.asarray(H0, float), np.asarray(H1, float)]),
            ),
        ),
    ],
    hint=[
        "The filter may have fewer states than the true model: the blocks have shapes "
        "(n0, n0), (n0, n1), (n1, n0), (n1, n1). Mind the sign in H~: r = H0 x - H1 xhat + v.",
        "F~ = [[F0, 0], [F1 K H0, F1 (I - K H1)]] (np.block or slices of a zero matrix) and "
        "H~ = [H0, -H1] (np.hstack).",
    ],
)
def q1(F0, H0, F1, H1, K):
    return _augmented(
        np.asarray(F0, float),
        np.asarray(H0, float),
        np.asarray(F1, float),
        np.asarray(H1, float),
        np.asarray(K, float),
    )


q1.case(F0_A, H0_A, F1_A, H1_A, K_A[0], label="2 true states, 1 filter state, p = 1")
# two filter states: the order of F1 and (I - K H1) matters (it does not for one state)
q1.case(
    np.array(_B0.F),
    np.array(_B0.H),
    np.array(_B1.F),
    np.array(_B1.H),
    K_B[1],
    label="2 true states, 2 filter states, p = 2",
)
### BEGIN HIDDEN TESTS
q1.case(np.array(_B0.F), np.array(_B0.H), np.array(_B1.F), np.array(_B1.H), K_B[2], hidden=True)
q1.case(np.array(_C0.F), np.array(_C0.H), np.array(_C1.F), np.array(_C1.H), K_C[4], hidden=True)
### END HIDDEN TESTS


def _model_args(m0, m1, K):
    return (
        np.array(m0.F),
        np.array(m0.G),
        np.array(m0.Q),
        np.array(m0.H),
        np.array(m0.R),
        np.array(m0.x0_cov),
        np.array(m1.F),
        np.array(m1.H),
        np.array(K),
    )


@CHECKS.function(
    "q2",
    func="residual_covariances",
    points=2,
    rtol=1e-9,
    atol=1e-12,
    forbid=_FORBID_MOMENTS,
    hint=[
        "Record P_t BEFORE propagating Psi~ to t + 1 (P_0 comes from Psi~_0), and use the "
        "gain of the same step, K[t]. The filter's own process noise is not a random input.",
        "P_t = H~ Psi~_t H~^T + R0, then Psi~_{t+1} = F~_t Psi~_t F~_t^T + G~_t "
        "blockdiag(Q0, R0) G~_t^T with G~_t = [[G0, 0], [0, F1 K_t]].",
    ],
)
def q2(F0, G0, Q0, H0, R0, Psi0, F1, H1, K):
    n0, n1 = F0.shape[0], F1.shape[0]
    N, p = K.shape[0], H0.shape[0]
    Psi = np.zeros((n0 + n1, n0 + n1))
    Psi[:n0, :n0] = Psi0
    out = np.empty((N, p, p))
    for t in range(N):
        F, H = _augmented(F0, H0, F1, H1, K[t])
        out[t] = H @ Psi @ H.T + R0
        noise = np.zeros_like(Psi)
        noise[:n0, :n0] = G0 @ Q0 @ G0.T
        FK = F1 @ K[t]
        noise[n0:, n0:] = FK @ R0 @ FK.T
        Psi = F @ Psi @ F.T + noise
    return out


q2.case(*_model_args(data.M0, data.M1, K_A), label="notebook 06 pair, N = 6")
### BEGIN HIDDEN TESTS
q2.case(*_model_args(_B0, _B1, K_B), hidden=True)
q2.case(*_model_args(_C0, _C1, K_C), hidden=True)
### END HIDDEN TESTS

P_Q3 = np.array([[2.0, 0.5], [0.5, 1.0]])


@CHECKS.function(
    "q3",
    func="expected_c",
    points=1,
    rtol=1e-9,
    atol=1e-12,
    mistakes=[
        Mistake(
            "tr(P_j) would be the expectation around the TRUE mean; the sample mean is "
            "subtracted here",
            lambda P, M: float(np.trace(P)),
        ),
        Mistake(
            "the factor looks inverted: M/(M - 1) tr(P_j) instead of (M - 1)/M tr(P_j): "
            "subtracting the sample mean makes the sum of squares SMALLER",
            lambda P, M: M / (M - 1.0) * float(np.trace(P)),
            hint="The sample mean is fitted to the very records it is subtracted from: the "
            "expected squared deviation shrinks, by (M - 1)/M.",
        ),
        Mistake(
            "divided by M once too often: (M - 1)/M² tr(P_j); c_j already averages over the "
            "M records once",
            lambda P, M: (M - 1.0) / M**2 * float(np.trace(P)),
        ),
        Mistake(
            "only the first output (P[0, 0]): the squared NORM of a residual sums every output, "
            "so its expectation has the trace of P_j",
            lambda P, M: (M - 1.0) / M * float(np.asarray(P, float)[0, 0]),
        ),
    ],
    hint=[
        "The sample mean is subtracted before squaring: how many independent deviations are "
        "left out of M?",
        "E[c_j] = (M - 1)/M tr(P_j): the divisor is M, but only M - 1 degrees of freedom remain.",
    ],
)
def q3(P, M):
    return (M - 1.0) / M * float(np.trace(P))


q3.case(P_Q3, 4, label="P = [[2, .5], [.5, 1]], M = 4")
### BEGIN HIDDEN TESTS
q3.case(np.diag([3.0, 1.0, 0.2]), 10, hidden=True)
q3.case(np.array([[2.4]]), 2, hidden=True)
### END HIDDEN TESTS


def _section_statistics(residuals, j, k, divisor=0, centred=True):
    """q4's statistics with a declared mistake: divided by M + divisor, or not centred."""
    r = np.asarray(residuals, float)
    M = r.shape[0]
    rbar_j = r[:, j].mean(axis=0)
    dj = r[:, j] - rbar_j if centred else r[:, j]
    dk = r[:, k] - r[:, k].mean(axis=0) if centred else r[:, k]
    return (
        float(rbar_j @ rbar_j),
        float(np.sum(dj * dj) / (M + divisor)),
        float(np.sum(dj * dk) / (M + divisor)),
    )


_rng = np.random.default_rng(20250606)
R_A = _rng.normal(size=(6, 5, 1)) + 0.4
R_B = _rng.normal(size=(9, 4, 2)) @ np.array([[1.0, 0.4], [0.0, 0.8]])
R_C = _rng.normal(size=(3, 7, 3))


@CHECKS.function(
    "q4",
    func="section_statistics",
    points=2,
    rtol=1e-10,
    atol=1e-12,
    forbid=[
        "course.mismatched.mean_statistic",
        "course.mismatched.covariance_statistic",
        "course.mismatched.correlation_statistic",
    ],
    mistakes=[
        Mistake(
            "the covariance and correlation statistics look divided by M - 1: the question's "
            "statistics are means over the M records (divide by M)",
            lambda residuals, j, k: _section_statistics(residuals, j, k, divisor=-1),
        ),
        Mistake(
            "the sample means look not subtracted: the covariance and correlation statistics "
            "use r_ij - rbar_j",
            lambda residuals, j, k: _section_statistics(residuals, j, k, centred=False),
        ),
    ],
    hint=[
        "Averages run over the RECORDS (axis 0), at fixed times j and k; the mean statistic "
        "is a squared norm; divide by M, not M - 1.",
        "rbar_j = residuals[:, j].mean(axis=0); covariance statistic: mean over records of "
        "|r_ij - rbar_j|^2; correlation statistic: mean over records of "
        "(r_ij - rbar_j) . (r_ik - rbar_k).",
    ],
)
def q4(residuals, j, k):
    r = np.asarray(residuals, float)
    return SectionStatistics(
        mismatched.mean_statistic(r, j),
        mismatched.covariance_statistic(r, j),
        mismatched.correlation_statistic(r, j, k),
    )


q4.case(R_A, 2, 3, label="M = 6 records, N = 5, p = 1")
### BEGIN HIDDEN TESTS
q4.case(R_B, 0, 3, hidden=True)
q4.case(R_C, 6, 1, hidden=True)
### END HIDDEN TESTS


_Q5_HINTS = [
    "Two-sided: alpha is split between the two tails.",
    "The weights of the weighted chi-square sum are the eigenvalues of P divided by M; "
    "each carries M - 1 degrees of freedom (not M).",
    "course.quadform.WeightedChiSquare(weights, dof=...) has ppf and isf (notebook 06, "
    "section 5: a law from its weights).",
]


@CHECKS.function(
    "q5",
    func="covariance_critical_values",
    points=2,
    rtol=1e-7,
    atol=1e-10,
    forbid=_FORBID_TESTS,
    mistakes=[
        Mistake(
            "M degrees of freedom: subtracting the sample mean leaves M - 1",
            lambda P, M, alpha: (
                float(
                    WeightedChiSquare(np.linalg.eigvalsh(np.asarray(P, float)) / M, dof=M).ppf(
                        alpha / 2
                    )
                ),
                float(
                    WeightedChiSquare(np.linalg.eigvalsh(np.asarray(P, float)) / M, dof=M).isf(
                        alpha / 2
                    )
                ),
            ),
            hint=_Q5_HINTS[1],
        ),
        Mistake(
            "alpha not split: a two-sided test puts alpha/2 in each tail",
            lambda P, M, alpha: _covariance_critical_values(P, M, 2 * alpha),
            hint=_Q5_HINTS[0],
        ),
        Mistake(
            "the weights look like the eigenvalues of P themselves: c_j averages over the M "
            "records, so each weight is an eigenvalue divided by M",
            lambda P, M, alpha: _covariance_critical_values(P, M, alpha, over=1.0),
            hint=_Q5_HINTS[1],
        ),
        Mistake(
            "the weights look like the diagonal of P: the quadratic form's weights are the "
            "EIGENVALUES of P (divided by M), which differ for a P with correlations",
            lambda P, M, alpha: _covariance_critical_values(P, M, alpha, weights=np.diag),
            hint=_Q5_HINTS[2],
        ),
        Mistake(
            "a scaled chi2 with the trace of P: it ignores how the weights differ; the law is "
            "a weighted chi-square sum with the eigenvalues of P / M",
            lambda P, M, alpha: _scaled_chi2_values(P, M, alpha),
            hint=_Q5_HINTS[2],
        ),
    ],
    hint=_Q5_HINTS,
)
def q5(P, M, alpha):
    return _covariance_critical_values(P, M, alpha)


def _covariance_critical_values(P, M, alpha, over=None, weights=np.linalg.eigvalsh, dof=None):
    """(lower, upper) of the law of c_j (the declared mistakes: weights not divided by M, the
    diagonal of P for the weights, another dof)."""
    P = np.asarray(P, float)
    law = WeightedChiSquare(weights(P) / (M if over is None else over), dof=dof or M - 1.0)
    return CriticalValues(float(law.ppf(alpha / 2)), float(law.isf(alpha / 2)))


def _scaled_chi2_values(P, M, alpha):
    """(lower, upper) of the scaled chi2 with the trace: a mistake of q5."""
    P = np.asarray(P, float)
    law = stats.chi2(len(P) * (M - 1), scale=np.trace(P) / (len(P) * M))
    return (float(law.ppf(alpha / 2)), float(law.isf(alpha / 2)))


q5.case(P_Q3, 10, 0.05, label="P = [[2, .5], [.5, 1]], M = 10, alpha = 0.05")
### BEGIN HIDDEN TESTS
q5.case(np.array([[2.4]]), 25, 0.1, hidden=True)
q5.case(np.diag([3.0, 1.0, 0.2]), 6, 0.01, hidden=True)
### END HIDDEN TESTS


# q6_practice's sections j = 4 and k = 5, as in the notebook's practice question.
J_PRACTICE = 4


def _pvalues(residuals, j, k, null, alpha):
    p_mean = mismatched.mean_test(residuals, j, null, alpha).pvalue
    p_corr = mismatched.correlation_test(residuals, j, k, null, alpha).pvalue
    return PValues(float(p_mean), float(p_corr))


_HINT_PVALUES = [
    "Both p-values are two-sided: 2 min(cdf, sf) of the statistic's exact law, capped at 1. "
    "Compare your statistics with q4's section_statistics.",
    "Mean test: rbar_j ~ N(m_j, P_j / M): the law of its squared norm is a QuadraticForm "
    "with that mean and covariance. Correlation test: the weights of the quadratic form in the "
    "question, each weight with M - 1 degrees of freedom (the sample means are subtracted).",
]


def _mistaken_pvalues(
    r, mean, cov, cross_cov, j, k, *, one_sided=False, over_m=True, dof_m=False, central=False
):
    """(p_mean, p_corr) computed as a student would, with one declared mistake: the mean's
    p-value one-sided, its covariance P_j not divided by M, M degrees of freedom for the
    correlation's weights, or the mean m_j left out of the mean's law."""
    r = np.asarray(r, float)
    mean, cov, cross_cov = (np.asarray(a, float) for a in (mean, cov, cross_cov))
    M = r.shape[0]
    rbar = r[:, j].mean(axis=0)
    law_mean = QuadraticForm(
        np.eye(len(rbar)), None if central else mean[j], cov[j] / (M if over_m else 1)
    )
    stat = float(rbar @ rbar)
    if one_sided:
        p_mean = float(law_mean.sf(stat))
    else:
        p_mean = min(1.0, 2 * min(float(law_mean.cdf(stat)), float(law_mean.sf(stat))))
    S = np.block([[cov[j], cross_cov[j, k]], [cross_cov[j, k].T, cov[k]]])
    p = cov[j].shape[0]
    A = np.block([[np.zeros((p, p)), np.eye(p)], [np.eye(p), np.zeros((p, p))]]) / (2 * M)
    shape = QuadraticForm(A, cov=S)
    law_corr = WeightedChiSquare(shape.weights, dof=shape.dof * (M if dof_m else M - 1))
    dj = r[:, j] - r[:, j].mean(axis=0)
    dk = r[:, k] - r[:, k].mean(axis=0)
    stat = float(np.mean(np.sum(dj * dk, axis=1)))
    p_corr = min(1.0, 2 * min(float(law_corr.cdf(stat)), float(law_corr.sf(stat))))
    return (p_mean, p_corr)


#: The declared mistakes of the p-values: (message, the keyword that makes it), for q6_practice
#: (the case's arguments) and q6 (the student's data).
_PVALUE_MISTAKES = [
    (
        "p_mean looks one-sided (sf alone): both tails count, 2 min(cdf, sf), capped at 1",
        {"one_sided": True},
    ),
    (
        "p_mean's law looks built with covariance P_j: the mean of M records has P_j / M",
        {"over_m": False},
    ),
    (
        "p_corr's law looks built with M degrees of freedom per weight: subtracting the sample "
        "means leaves M - 1",
        {"dof_m": True},
    ),
    (
        "p_mean's law looks central: under H0 rbar_j has the mean m_j of the null moments, so "
        "its squared norm is a non-central quadratic form",
        {"central": True},
    ),
]


def _pvalue_mistake(message, how):
    return Mistake(
        message,
        lambda r, mean, cov, cross_cov, j, k: _mistaken_pvalues(
            r, mean, cov, cross_cov, j, k, **how
        ),
    )


def _pvalue_mistake_mine(message, how):
    return Mistake(
        message,
        lambda d: _mistaken_pvalues(
            d["residuals"], d["mean"], d["cov"], d["cross_cov"], d["j"], d["k"], **how
        ),
    )


@CHECKS.function(
    "q6_practice",
    func="two_sided_pvalues",
    points=1,
    rtol=1e-6,
    atol=1e-9,
    forbid=_FORBID_TESTS,
    hint=_HINT_PVALUES,
    mistakes=[_pvalue_mistake(m, how) for m, how in _PVALUE_MISTAKES],
)
def q6_practice(r, mean, cov, cross_cov, j, k):
    null = mismatched.ResidualMoments(mean, cov, cross_cov)
    return _pvalues(r, j, k, null, 0.05)


def _experiment_case(seed, Q, R, drift=None):
    """(records, mean, cov, cross_cov, j, k) of a practice-design experiment for a model under
    test like M0 with the noise Q, R; the records come from it, or with ``drift`` from a model
    whose drift state starts elsewhere (the alternative of data.experiment). Other noises
    than M0's: the null moments of the notebook's pair would ship q2's answer (a public
    case) or match every student's issued data (a hidden one)."""
    m0 = filters.LinearModel(
        F=data.M0.F,
        H=data.M0.H,
        Q=np.diag(Q),
        R=[[R]],
        x0_mean=data.M0.x0_mean,
        x0_cov=data.M0.x0_cov,
        w_mean=data.M0.w_mean,
        v_mean=data.M0.v_mean,
    )
    source = m0  # the model the records come from
    if drift is not None:
        source = filters.LinearModel(
            F=m0.F,
            H=m0.H,
            Q=m0.Q,
            R=m0.R,
            x0_mean=[0.0, drift],
            x0_cov=m0.x0_cov,
            w_mean=m0.w_mean,
            v_mean=m0.v_mean,
        )
    null = mismatched.residual_moments(m0, data.M1, 12)
    records = mismatched.simulate_records(source, data.M1, 30, 12, np.random.default_rng(seed))
    j = 2 + seed % 6
    return records, np.array(null.mean), np.array(null.cov), np.array(null.cross_cov), j, j + 1


q6_practice.case(
    *_experiment_case(602, (0.4, 0.03), 0.8)[:4],
    J_PRACTICE,
    J_PRACTICE + 1,
    label="a public experiment of the practice design (another model pair), j = 4, k = 5",
)
### BEGIN HIDDEN TESTS
q6_practice.case(*_experiment_case(91, (0.6, 0.01), 1.1), hidden=True)
q6_practice.case(*_experiment_case(92, (0.45, 0.025), 0.9, drift=2.0), hidden=True)
q6_practice.case(*_experiment_case(93, (0.55, 0.02), 1.3), hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q6",
    var="pvalues",
    points=2,
    rtol=1e-6,
    atol=1e-9,
    data="experiment",
    properties="experiment_properties",
    forbid=_FORBID_TESTS,
    hint=["Do q6_practice first: the same code must pass its public check there.", *_HINT_PVALUES],
    mistakes=[_pvalue_mistake_mine(m, how) for m, how in _PVALUE_MISTAKES],
)
def q6(d):
    null = mismatched.ResidualMoments(d["mean"], d["cov"], d["cross_cov"])
    return _pvalues(d["residuals"], d["j"], d["k"], null, d["alpha"])


WHICH_OPTIONS = ["neither", "only the mean test", "only the correlation test", "both"]


@CHECKS.choice(
    "q6_which",
    var="which_rejects",
    options=WHICH_OPTIONS,
    points=1,
    data="experiment",
    hint="One of the options, as a string (upper/lower case and surrounding spaces do not matter).",
)
def q6_which(d):
    null = mismatched.ResidualMoments(d["mean"], d["cov"], d["cross_cov"])
    p_mean, p_corr = _pvalues(d["residuals"], d["j"], d["k"], null, d["alpha"])
    return WHICH_OPTIONS[int(p_mean < d["alpha"]) + 2 * int(p_corr < d["alpha"])]


CHECKS.short_answer(
    "q6_why",
    points=1,
    rubric="Full marks (1): (a) the alternative that data.py may draw -- a wrong initial mean "
    "of the drift state -- moves the MEAN of the residuals (m_j), not their covariances; "
    "(b) the covariance and correlation statistics subtract the sample mean of each section, "
    "so a common shift of all records cancels: they cannot see it, while the mean test "
    "compares rbar_j with m_j directly. Accept any wording of 'mean shift, centred statistics "
    "are blind to it'. Half (0.5): only (a) or only (b). 0: 'more records needed' or "
    "'the correlation test is less powerful' without the reason.",
)


P0_Q7 = np.array([[1.5, 0.4], [0.4, 1.0]])
P2_Q7 = np.array([[2.2, 0.4], [0.4, 1.1]])


@CHECKS.function(
    "q7",
    func="power_cov",
    points=1,
    rtol=1e-6,
    atol=1e-9,
    forbid=_FORBID_TESTS,
    mistakes=[
        Mistake(
            "looks like 1 - power: the probability that the test does NOT reject",
            lambda P0, P2, M, alpha: 1.0 - q7.reference(P0, P2, M, alpha),
        ),
        Mistake(
            "the critical values look computed from the ALTERNATIVE's law (P2): they are the "
            "null's (P0), whose level is alpha; P2 gives only the probability of crossing them",
            lambda P0, P2, M, alpha: _power(P2, P2, M, alpha),
            hint="Thresholds from the NULL law (your q5 with P0); only the probability of "
            "crossing them from the alternative's law (P2).",
        ),
        Mistake(
            "the alternative's law has M degrees of freedom here: subtracting the sample mean "
            "leaves M - 1 under the alternative too",
            lambda P0, P2, M, alpha: _power(P0, P2, M, alpha, dof2=float(M)),
        ),
        Mistake(
            "only the upper tail counts here: the two-sided test also rejects below the lower "
            "critical value, power = F2(lower) + 1 - F2(upper)",
            lambda P0, P2, M, alpha: _power(P0, P2, M, alpha, lower_tail=False),
        ),
        Mistake(
            "one-sided: the upper critical value at alpha alone; the covariance test is "
            "two-sided, alpha/2 in each tail",
            lambda P0, P2, M, alpha: _power(P0, P2, M, 2 * alpha, lower_tail=False),
        ),
    ],
    hint=[
        "Thresholds come from the NULL law (P0); the probability of crossing them from the "
        "ALTERNATIVE's law (P2). Both tails count.",
        "power = F2(lower) + 1 - F2(upper), with (lower, upper) from your q5 under P0 and F2 "
        "the law of c_j under P2.",
    ],
)
def q7(P0, P2, M, alpha):
    return _power(P0, P2, M, alpha)


def _power(P0, P2, M, alpha, dof2=None, lower_tail=True):
    """The covariance test's power (the declared mistakes: another dof under P2, the upper
    tail only)."""
    lower, upper = _covariance_critical_values(P0, M, alpha)
    law = WeightedChiSquare(np.linalg.eigvalsh(np.asarray(P2, float)) / M, dof=dof2 or M - 1.0)
    return float((law.cdf(lower) if lower_tail else 0.0) + law.sf(upper))


q7.case(
    P0_Q7, P2_Q7, 20, 0.05, label="P0 = [[1.5, .4], [.4, 1]], P2 = [[2.2, .4], [.4, 1.1]], M = 20"
)
### BEGIN HIDDEN TESTS
q7.case(np.array([[1.0]]), np.array([[1.6]]), 15, 0.10, hidden=True)
q7.case(np.diag([2.0, 1.0, 0.5]), np.diag([1.2, 0.8, 0.5]), 30, 0.01, hidden=True)
### END HIDDEN TESTS
