"""Checks of assignment 03_estimation_and_likelihood (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

import numpy as np
from scipy import stats

from course import diagnosis as dg
from course.grading.checks import Checks

from . import data

# The notebook's context: the three-gain model with u2 partly driven by u1.
N = 40
T_AXIS = np.arange(N)
U1 = 1.0 + 0.5 * np.sin(2 * np.pi * T_AXIS / 20)
U2 = 0.6 * U1 + np.cos(2 * np.pi * T_AXIS / 13)
U3 = np.where((T_AXIS // 8) % 2 == 0, 1.0, -1.0)
U = np.column_stack([U1, U2, U3])
SIGMA = 0.2
NOMINAL = np.ones(3)
MODES = {"NF": (), "F1": (0,), "F2": (1,), "F3": (2,)}


def _record(theta, seed, sigma=SIGMA):
    return U @ np.asarray(theta, dtype=float) + sigma * np.random.default_rng(seed).standard_normal(
        N
    )


CHECKS = Checks(
    "03_estimation_and_likelihood",
    title="Assignment 3: parameter estimates and the likelihood",
    data=data,
    timeout=10,
    preload=["course.diagnosis", "scipy.stats", "scipy.linalg"],
)


@CHECKS.function(
    "q1",
    func="joint_parameter_test",
    points=2,
    rtol=1e-7,
    atol=1e-10,
    forbid=[
        "course.diagnosis.regression_parameter_test",
        "course.diagnosis.estimate_parameters",
        "course.diagnosis.parameter_estimate_test",
    ],
    hint="Regress y - u3 on [u1, u2] (QR or lstsq); the covariance of the estimate is "
    "sigma^2 (Phi^T Phi)^{-1} = sigma^2 R^{-1} R^{-T}. Reject when |theta2_hat - 1| > "
    "std * stats.norm.isf(alpha / 2). Return (theta2_hat, std, reject).",
)
def q1(U_, y, sigma, alpha):
    est = dg.estimate_parameters(y, U_, NOMINAL, [0, 1], sigma=sigma)
    std = float(est.std[1])
    theta2 = float(est.theta[1])
    return (theta2, std, bool(abs(theta2 - 1.0) > std * stats.norm.isf(alpha / 2)))


q1.case(U, _record([1.0, 1.0, 1.0], 1), SIGMA, 0.05, label="no fault")
q1.case(U, _record([1.5, 1.0, 1.0], 2), SIGMA, 0.05, label="F1: theta1 = 1.5 (decoupled)")
q1.case(
    U,
    _record([1.0, 1.08, 1.0], 37),
    SIGMA,
    0.05,
    label="a small F2: |theta2_hat - 1| / s lies between z_alpha and z_alpha/2",
)
q1.case(U, _record([1.0, 1.08, 1.0], 27), SIGMA, 0.10, hidden=True)  # also between them
q1.case(U, _record([1.0, 1.2, 1.0], 3), SIGMA, 0.05, hidden=True)
q1.case(U, _record([1.0, 1.0, 1.4], 4), SIGMA, 0.01, hidden=True)
q1.case(U, _record([0.7, 1.05, 1.0], 5, 0.05), 0.05, 0.10, hidden=True)


@CHECKS.value(
    "q2",
    var="leak_theta2",
    points=1,
    rtol=1e-8,
    atol=1e-10,
    hint="With theta1 fixed at 1 the estimate of theta2 regresses the data minus u1 - u3 on u2; "
    "take the expectation with theta1 = 1.3: E theta2_hat = 1 + 0.3 u2'u1 / u2'u2.",
)
def q2():
    return float(1.0 + 0.3 * (U2 @ U1) / (U2 @ U2))


@CHECKS.value(
    "q3",
    var="power_pair",
    points=2,
    rtol=1e-6,
    atol=1e-9,
    hint="Parameter test: b = 0.1, s = std of theta2_hat (joint estimate), power = "
    "Phi(b/s - z) + Phi(-b/s - z) with z = norm.isf(alpha/2). Prediction-error test T1 (theta1 "
    "free): non-central chi2(N - 1) with lambda = ||(I - P1) u2 0.1||^2 / sigma^2.",
)
def q3():
    theta = [1.0, 1.1, 1.0]
    p_param = dg.parameter_estimate_power(U, NOMINAL, [0, 1], 1, theta, sigma=SIGMA, alpha=0.05)
    p_pe = dg.prediction_error_power(U, NOMINAL, [0], theta, sigma=SIGMA, alpha=0.05)
    return (p_param, p_pe)


CHECKS.short_answer(
    "q3b",
    points=1,
    rubric="1 point: says the parameter-estimate test is more powerful (larger power) AND why: it "
    "targets the one direction theta2 of the fault (one degree of freedom; all of the fault's "
    "signal is in its statistic), while T1 spreads the same non-centrality over N - 1 = 39 "
    "degrees of freedom, so its threshold is far above the mean shift. 0.5: right order, no or "
    "vague reason. 0: says the prediction-error test is more powerful.",
    hint="Compare how many degrees of freedom each statistic spreads the fault's signal over.",
)


@CHECKS.function(
    "q4",
    func="likelihood",
    points=1,
    rtol=1e-8,
    atol=1e-14,
    forbid=["course.diagnosis.normal_likelihood", "course.diagnosis.normal_log_likelihood"],
    hint="L(theta | z) is the product over the observations of the N(theta, sigma^2) density at "
    "z_i; return one value per theta (an array shaped like theta).",
)
def q4(theta, z, sigma):
    return np.asarray(dg.normal_likelihood(np.asarray(theta, dtype=float), z, sigma=sigma))


q4.case(np.linspace(-2.0, 6.0, 9), np.array([2.0]), 1.0, label="z = 2")
q4.case(np.linspace(0.0, 8.0, 9), np.array([3.0, 5.0]), 1.0, label="z = (3, 5)")
q4.case(np.array([0.5, 1.0, 4.0]), np.array([1.0, 2.0, 0.5, 3.0]), 2.0, hidden=True)
q4.case(np.array([-1.0, 10.0]), np.array([3.0, 5.0]), 0.5, hidden=True)


@CHECKS.value(
    "q5",
    var="ml_35",
    points=1,
    rtol=1e-6,
    atol=1e-9,
    hint="Maximise L(theta | 3, 5) for N(theta, 1): the maximiser is the sample mean; give "
    "(theta_ml, L(theta_ml | 3, 5)).",
)
def q5():
    return (4.0, float(np.exp(-1.0) / (2 * np.pi)))


@CHECKS.function(
    "q6",
    func="glr_nf_vs_f2",
    points=2,
    rtol=1e-6,
    atol=1e-9,
    forbid=[
        "course.diagnosis.linear_glr_test",
        "course.diagnosis.glr_test",
        "course.diagnosis.prediction_error",
    ],
    hint="-2 log Lambda = (T0 - T1)/sigma^2 with T0 = ||y - u1 - u2 - u3||^2 (NF) and T1 the "
    "smallest prediction error with theta2 free (others 1). It is chi2(1) under NF: "
    "return (statistic, stats.chi2.sf(statistic, 1)).",
)
def q6(U_, y, sigma):
    r = dg.linear_glr_test(y, U_, NOMINAL, free0=[], free1=[1], sigma=sigma)
    return (r.statistic, r.pvalue)


q6.case(U, _record([1.0, 1.0, 1.0], 11), SIGMA, label="no fault")
q6.case(U, _record([1.0, 1.15, 1.0], 12), SIGMA, label="F2: theta2 = 1.15")
q6.case(U, _record([1.3, 1.0, 1.0], 13), SIGMA, hidden=True)
q6.case(U, _record([1.0, 1.0, 0.9], 14, 0.1), 0.1, hidden=True)


@CHECKS.function(
    "q7",
    func="np_power",
    points=2,
    rtol=1e-7,
    atol=1e-10,
    hint="log Q is N(-d^2/2, d^2) under H0 and N(d^2/2, d^2) under H1 with "
    "d = sqrt(n) |theta1 - theta0| / sigma, so the power is Phi(d - z_alpha).",
)
def q7(n, theta0, theta1, sigma, alpha):
    z = np.zeros(int(n))
    return float(
        dg.neyman_pearson_test(z, theta0, theta1, sigma=sigma, alpha=alpha).details["power"]
    )


q7.case(2, 0.0, 1.0, 1.0, 0.05, label="the lecture's two observations, theta1 = 1")
q7.case(4, 0.0, 1.0, 1.0, 0.05, label="four observations")
q7.case(10, 1.0, 0.8, 0.5, 0.01, hidden=True)
q7.case(1, -2.0, 3.0, 2.0, 0.1, hidden=True)


@CHECKS.function(
    "q8",
    func="boundary_false_alarm",
    points=2,
    timeout=30,
    atol=0.1 / 20000,  # the same count of alarms: a fraction k / n_runs, exactly
    rtol=0.0,
    hint="Draw all the samples with one call, rng.standard_normal((n_runs, n)) with "
    "rng = np.random.default_rng(seed) (row r is sample r), compute -2 log Lambda = "
    "n max(0, mean)^2 of each row, and return the fraction above stats.chi2.isf(alpha, 1).",
)
def q8(n, alpha, n_runs, seed):
    # The simulation the question prescribes, with the case's seed: a correct answer counts
    # exactly the same alarms; the theoretical rate alpha / 2 (-2 log Lambda is 0 with
    # probability 1/2, chi2(1) otherwise) or another random sample differs by a Monte Carlo error.
    zbar = np.random.default_rng(seed).standard_normal((n_runs, n)).mean(axis=1)
    return float(np.mean(n * np.maximum(zbar, 0.0) ** 2 > stats.chi2.isf(alpha, 1)))


q8.case(25, 0.05, 20000, 2024, label="n = 25, alpha = 0.05")
q8.case(5, 0.10, 20000, 7, hidden=True)
q8.case(40, 0.01, 20000, 11, hidden=True)


# The public practice record of q9_practice: the notebook's signals, a fault F2 of 0.25.
Y_MODES = _record([1.0, 1.25, 1.0], 31)
PRIORS = np.array([0.7, 0.1, 0.1, 0.1])


def _posterior(y, U_, sigma, tau, priors):
    logl = dg.mode_log_likelihoods(y, U_, NOMINAL, MODES, sigma=sigma, prior_std=tau)
    post = dg.bayes_ranking(logl, dict(zip(MODES, priors))).as_dict()
    return np.array([post[m] for m in MODES])


@CHECKS.value(
    "q9_practice",
    var="posterior_practice",
    points=1,
    rtol=1e-6,
    atol=1e-300,
    hint="The marginal likelihood integrates the faulty gain out: under Fi, y ~ N(U 1, sigma^2 I + "
    "tau^2 u_i u_i^T). Maximising over the gain instead is a different (and here wrong) quantity.",
)
def q9_practice():
    return _posterior(Y_MODES, U, SIGMA, 0.3, PRIORS)


@CHECKS.value(
    "q9",
    var="posterior_mine",
    points=3,
    data="modes",
    properties="posterior_properties",
    rtol=1e-6,
    # relative only: a decisive record has posteriors like 1e-13, and the maximised likelihood
    # (a wrong method) differs there by orders of magnitude, within any absolute tolerance
    atol=1e-300,
    hint="Under Fi, y ~ N(U 1, sigma^2 I + tau^2 u_i u_i^T); under NF, y ~ N(U 1, sigma^2 I) "
    "(stats.multivariate_normal.logpdf). Combine with mine['priors'] by Bayes' rule, in the "
    "log domain, and return the four posteriors in the order NF, F1, F2, F3.",
)
def q9(d):
    return _posterior(d["y"], d["U"], d["sigma"], d["tau"], d["priors"])
