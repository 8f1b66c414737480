"""Checks of assignment 03_estimation_and_likelihood (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

from collections import namedtuple

import numpy as np
from scipy import stats

from course import diagnosis as dg
from course.grading.authoring.checks import Checks, Mistake

from . import data

# Results with several parts are named tuples: feedback names the part that is wrong
# (``critical_value``, not ``item [1]``). A student's plain tuple or list in the same order
# is just as right (the grader compares item by item).
JointParameterTest = namedtuple("JointParameterTest", "theta2_hat s reject")
PowerPair = namedtuple("PowerPair", "power_parameter_test power_prediction_error_test")
MaximumLikelihood = namedtuple("MaximumLikelihood", "theta_ml L_max")
GLR = namedtuple("GLR", "statistic pvalue")

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
    hint=(
        "Both gains are estimated together (theta1 too, that is what decouples F1); theta3 is "
        "fixed at 1. The test is two-sided: a fault may raise or lower theta2.",
        "Regress y - u3 on [u1, u2] (QR or lstsq); the covariance of the estimate is "
        "sigma^2 (Phi^T Phi)^{-1} = sigma^2 R^{-1} R^{-T}. Reject when |theta2_hat - 1| > "
        "std * stats.norm.isf(alpha / 2). Return (theta2_hat, std, reject).",
    ),
    mistakes=[
        Mistake(
            "the decision looks one-sided: z_alpha instead of z_alpha/2",
            lambda U_, y, sigma, alpha: _joint(U_, y, sigma, 2 * alpha),
        ),
        Mistake(
            "theta2 looks estimated alone (theta1 fixed at 1): estimate theta1 and theta2 "
            "together, which decouples F1",
            lambda U_, y, sigma, alpha: _joint(U_, y, sigma, alpha, free=(1,)),
        ),
        Mistake(
            "std looks like that of theta1 (the (1, 1) element): the test of theta2 needs the "
            "std of theta2_hat",
            lambda U_, y, sigma, alpha: _joint(U_, y, sigma, alpha, std_at=0),
        ),
        Mistake(
            "all three gains look estimated: theta3 is fixed at 1, only theta1 and theta2 are free",
            lambda U_, y, sigma, alpha: _joint(U_, y, sigma, alpha, free=(0, 1, 2)),
        ),
    ],
)
def q1(U_, y, sigma, alpha):
    return _joint(U_, y, sigma, alpha)


def _joint(U_, y, sigma, alpha, free=(0, 1), std_at=None):
    """(theta2_hat, std, reject) with the gains ``free`` estimated (the std of the free gain
    ``std_at``, theta2's by default; other choices are declared mistakes)."""
    est = dg.estimate_parameters(y, U_, NOMINAL, list(free), sigma=sigma)
    std = float(est.std[list(free).index(1 if std_at is None else std_at)])
    theta2 = float(est.theta[1])
    return JointParameterTest(
        theta2, std, bool(abs(theta2 - 1.0) > std * stats.norm.isf(alpha / 2))
    )


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


@CHECKS.function(
    "q2",
    func="leak_theta2",
    forbid=[
        "course.diagnosis.estimate_parameters",
    ],
    points=1,
    rtol=1e-8,
    atol=1e-10,
    hint=(
        "Here theta1 is NOT estimated: it is fixed at 1, so the unmodelled part "
        "(theta1 - 1) u1 of the data stays in what the regression on u2 sees.",
        "Regress the noise-free data minus u1 - u3 on u2 alone: the estimate is the ratio "
        "u2'(data - u1 - u3) / u2'u2, with data = U (theta1, 1, 1).",
    ),
    mistakes=[
        Mistake(
            "1 is what the JOINT estimate gives (it decouples F1); here theta1 is fixed at 1",
            lambda U_, theta1: 1.0,
        ),
        Mistake(
            "u1 looks not subtracted: theta1 is fixed at 1 in the model, so the regression on "
            "u2 sees the data minus u1 - u3",
            lambda U_, theta1: _leak(U_, theta1) + _ratio(U_),
        ),
        Mistake(
            "the leak alone, without the 1: the estimate is 1 (the true theta2) plus the leak "
            "(theta1 - 1) u2'u1 / u2'u2",
            lambda U_, theta1: _leak(U_, theta1) - 1.0,
        ),
        Mistake(
            "divided by u1'u1: the regression is on u2, so the leak is divided by u2'u2",
            lambda U_, theta1: (
                1.0
                + (theta1 - 1.0)
                * float(np.asarray(U_)[:, 1] @ np.asarray(U_)[:, 0])
                / float(np.asarray(U_)[:, 0] @ np.asarray(U_)[:, 0])
            ),
        ),
    ],
)
def q2(U_, theta1):
    return _leak(U_, theta1)


def _ratio(U_):
    """u2'u1 / u2'u2: how much of u1 a regression on u2 alone takes for u2."""
    U_ = np.asarray(U_, dtype=float)
    return float((U_[:, 1] @ U_[:, 0]) / (U_[:, 1] @ U_[:, 1]))


def _leak(U_, theta1):
    return 1.0 + (theta1 - 1.0) * _ratio(U_)


def _modes_U(seed):
    """The signals of a record of data.modes (the students' design), drawn with a fixed seed."""
    return data.modes(np.random.default_rng(seed))["U"]


q2.case(U, 1.3, label="the context's signals, theta1 = 1.3")
### BEGIN HIDDEN TESTS
q2.case(U, 0.8, hidden=True)
q2.case(_modes_U(51), 1.2, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q3",
    func="power_pair",
    forbid=[
        "course.diagnosis.parameter_estimate_power",
        "course.diagnosis.prediction_error_power",
    ],
    points=2,
    rtol=1e-6,
    atol=1e-9,
    hint=(
        "Under the fault, theta2_hat - 1 is normal with mean b = theta2 - 1 and the std s of "
        "q1; the test rejects in BOTH tails. T1/sigma^2 is non-central chi2 under the fault.",
        "Parameter test: s = std of theta2_hat (joint estimate), power = "
        "Phi(b/s - z) + Phi(-b/s - z) with z = norm.isf(alpha/2). Prediction-error test T1 "
        "(theta1 free): non-central chi2(N - 1) with lambda = ||(I - P1) u2 b||^2 / sigma^2.",
    ),
    mistakes=[
        Mistake(
            "the parameter test's power looks like one tail only: it rejects in both",
            lambda U_, sigma, theta2, alpha: (
                _one_tail_power(U_, sigma, theta2, alpha),
                _pe_power(U_, sigma, theta2, alpha),
            ),
        ),
        Mistake(
            "the parameter test's power looks computed with z_alpha: the test is two-sided, "
            "z = norm.isf(alpha/2)",
            lambda U_, sigma, theta2, alpha: (
                dg.parameter_estimate_power(
                    U_, NOMINAL, [0, 1], 1, [1.0, theta2, 1.0], sigma=sigma, alpha=2 * alpha
                ),
                _pe_power(U_, sigma, theta2, alpha),
            ),
        ),
    ],
)
def q3(U_, sigma, theta2, alpha):
    theta = [1.0, theta2, 1.0]
    p_param = dg.parameter_estimate_power(U_, NOMINAL, [0, 1], 1, theta, sigma=sigma, alpha=alpha)
    return PowerPair(p_param, _pe_power(U_, sigma, theta2, alpha))


def _pe_power(U_, sigma, theta2, alpha):
    return dg.prediction_error_power(U_, NOMINAL, [0], [1.0, theta2, 1.0], sigma=sigma, alpha=alpha)


def _one_tail_power(U_, sigma, theta2, alpha):
    s = _joint(U_, np.asarray(U_) @ NOMINAL, sigma, alpha)[1]
    return float(stats.norm.sf(stats.norm.isf(alpha / 2) - abs(theta2 - 1.0) / s))


q3.case(U, SIGMA, 1.1, 0.05, label="F2 with theta2 = 1.1, alpha = 0.05")
### BEGIN HIDDEN TESTS
q3.case(U, SIGMA, 0.93, 0.10, hidden=True)
q3.case(_modes_U(52), 0.15, 1.06, 0.10, hidden=True)
### END HIDDEN TESTS


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


_SIGMA2_SCALE = (
    "looks computed with sigma^2 as the scale: scipy's norm takes the standard deviation, "
    "scale=sigma"
)


def _likelihood(theta, z, sigma):
    """The normal likelihood of each theta."""
    return np.asarray(dg.normal_likelihood(np.asarray(theta, dtype=float), z, sigma=sigma))


@CHECKS.function(
    "q4",
    func="likelihood",
    points=1,
    rtol=1e-8,
    atol=1e-14,
    forbid=["course.diagnosis.normal_likelihood", "course.diagnosis.normal_log_likelihood"],
    hint="L(theta | z) is the product over the observations of the N(theta, sigma^2) density at "
    "z_i; return one value per theta (an array shaped like theta).",
    mistakes=[
        Mistake(
            "looks like the log-likelihood: return the likelihood itself",
            lambda theta, z, sigma: np.asarray(
                dg.normal_log_likelihood(np.asarray(theta, dtype=float), z, sigma=sigma)
            ),
        ),
        Mistake(
            _SIGMA2_SCALE,
            lambda theta, z, sigma: _likelihood(theta, z, sigma**2),
        ),
        Mistake(
            "looks like a SUM of densities: the likelihood of independent observations is "
            "their product",
            lambda theta, z, sigma: np.array(
                [float(np.sum(stats.norm.pdf(z, t, sigma))) for t in np.ravel(theta)]
            ).reshape(np.shape(theta)),
        ),
        Mistake(
            "only the first observation counts here: the likelihood is the product over EVERY "
            "observation",
            lambda theta, z, sigma: _likelihood(theta, np.asarray(z, dtype=float)[:1], sigma),
        ),
    ],
)
def q4(theta, z, sigma):
    return np.asarray(dg.normal_likelihood(np.asarray(theta, dtype=float), z, sigma=sigma))


q4.case(np.linspace(-2.0, 6.0, 9), np.array([2.0]), 1.0, label="z = 2")
q4.case(np.linspace(0.0, 8.0, 9), np.array([3.0, 5.0]), 1.0, label="z = (3, 5)")
q4.case(np.array([0.5, 1.0, 4.0]), np.array([1.0, 2.0, 0.5, 3.0]), 2.0, hidden=True)
q4.case(np.array([-1.0, 10.0]), np.array([3.0, 5.0]), 0.5, hidden=True)


@CHECKS.function(
    "q5",
    func="maximum_likelihood",
    forbid=[
        "course.diagnosis.normal_likelihood",
        "course.diagnosis.normal_log_likelihood",
        "course.diagnosis.maximum_likelihood",
    ],
    points=1,
    rtol=1e-6,
    atol=1e-300,  # relative only: likelihoods of many observations are tiny
    hint=(
        "Maximise L(theta | z) for N(theta, sigma^2); your likelihood function of q4 evaluates it.",
        "The maximiser is the sample mean; return (theta_ml, L(theta_ml | z)), the likelihood "
        "itself, not its logarithm.",
    ),
    mistakes=[
        Mistake(
            "the second value looks like the log-likelihood at the maximum",
            lambda z, sigma: (
                float(np.mean(z)),
                float(np.sum(stats.norm.logpdf(z, np.mean(z), sigma))),
            ),
        ),
        Mistake(
            _SIGMA2_SCALE,
            lambda z, sigma: (
                float(np.mean(z)),
                float(np.prod(stats.norm.pdf(z, np.mean(z), sigma**2))),
            ),
        ),
        Mistake(
            "theta_ml looks like the first observation: the maximiser is the mean of all of them",
            lambda z, sigma: (
                float(np.asarray(z)[0]),
                float(np.prod(stats.norm.pdf(z, np.asarray(z)[0], sigma))),
            ),
        ),
    ],
)
def q5(z, sigma):
    theta_ml = float(np.mean(z))
    return MaximumLikelihood(theta_ml, float(np.prod(stats.norm.pdf(z, theta_ml, sigma))))


q5.case(np.array([3.0, 5.0]), 1.0, label="the lecture's z = (3, 5), sigma = 1")
### BEGIN HIDDEN TESTS
q5.case(np.array([1.0, 2.0, 0.5, 3.0]), 2.0, hidden=True)
q5.case(np.array([-1.0, 4.0, 2.5]), 0.5, hidden=True)
### END HIDDEN TESTS


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
    hint=(
        "T0 and T1 are the smallest sums of squared prediction errors under NF and under F2; "
        "the statistic is measured in units of sigma^2.",
        "-2 log Lambda = (T0 - T1)/sigma^2 with T0 = ||y - u1 - u2 - u3||^2 (NF) and T1 the "
        "smallest prediction error with theta2 free (others 1). It is chi2(1) under NF: "
        "return (statistic, stats.chi2.sf(statistic, 1)).",
    ),
    mistakes=[
        Mistake(
            "the p-value looks like the cdf: a p-value is the upper tail, sf",
            lambda U_, y, sigma: _glr_cdf(U_, y, sigma),
        ),
        Mistake(
            "the statistic looks not divided by sigma^2: -2 log Lambda = (T0 - T1) / sigma^2",
            lambda U_, y, sigma: _glr_scaled(U_, y, sigma, sigma**2),
        ),
        Mistake(
            "the p-value looks computed with chi2(N - 1): one parameter is freed under F2, so "
            "-2 log Lambda is chi2(1)",
            lambda U_, y, sigma: _glr_scaled(U_, y, sigma, 1.0, dof=np.shape(U_)[0] - 1),
        ),
        Mistake(
            "theta1 looks freed instead of theta2: the alternative F2 is a fault of the second "
            "gain",
            lambda U_, y, sigma: _glr_scaled(U_, y, sigma, 1.0, free=0),
        ),
    ],
)
def q6(U_, y, sigma):
    r = dg.linear_glr_test(y, U_, NOMINAL, free0=[], free1=[1], sigma=sigma)
    return GLR(r.statistic, r.pvalue)


def _glr_scaled(U_, y, sigma, scale, dof=1, free=1):
    """(statistic * scale, its chi2(dof) p-value) with gain ``free`` freed (declared
    mistakes)."""
    r = dg.linear_glr_test(y, U_, NOMINAL, free0=[], free1=[free], sigma=sigma)
    statistic = float(r.statistic) * scale
    return (statistic, float(stats.chi2.sf(statistic, dof)))


def _glr_cdf(U_, y, sigma):
    r = dg.linear_glr_test(y, U_, NOMINAL, free0=[], free1=[1], sigma=sigma)
    return (r.statistic, float(stats.chi2.cdf(r.statistic, 1)))


q6.case(U, _record([1.0, 1.0, 1.0], 11), SIGMA, label="no fault")
q6.case(U, _record([1.0, 1.15, 1.0], 12), SIGMA, label="F2: theta2 = 1.15")
q6.case(U, _record([1.3, 1.0, 1.0], 13), SIGMA, hidden=True)
q6.case(U, _record([1.0, 1.0, 0.9], 14, 0.1), 0.1, hidden=True)


def _np_power(n, theta0, theta1, sigma, alpha, scale=None):
    """Phi(d - z_alpha) with d = scale |theta1 - theta0| / sigma (scale: sqrt(n), or a
    declared mistake's)."""
    d = (np.sqrt(n) if scale is None else scale) * abs(theta1 - theta0) / sigma
    return float(stats.norm.sf(stats.norm.isf(alpha) - d))


@CHECKS.function(
    "q7",
    forbid=[
        "course.diagnosis.neyman_pearson_test",
    ],
    func="np_power",
    points=2,
    rtol=1e-7,
    atol=1e-10,
    hint=(
        "The likelihood-ratio test of two simple hypotheses thresholds the sample mean; the "
        "test is one-sided, towards theta1.",
        "log Q is N(-d^2/2, d^2) under H0 and N(d^2/2, d^2) under H1 with "
        "d = sqrt(n) |theta1 - theta0| / sigma, so the power is Phi(d - z_alpha).",
    ),
    mistakes=[
        Mistake(
            "looks two-sided (z_alpha/2): Neyman-Pearson for simple hypotheses is one-sided",
            lambda n, theta0, theta1, sigma, alpha: float(
                stats.norm.sf(stats.norm.isf(alpha / 2) - np.sqrt(n) * abs(theta1 - theta0) / sigma)
            ),
        ),
        Mistake(
            "looks like d with sigma^2 where sigma belongs: d = sqrt(n) |theta1 - theta0| / sigma "
            "(a distance in standard deviations, not in variances)",
            lambda n, theta0, theta1, sigma, alpha: float(
                stats.norm.sf(stats.norm.isf(alpha) - np.sqrt(n) * abs(theta1 - theta0) / sigma**2)
            ),
        ),
        Mistake(
            "sqrt(n) looks forgotten: the mean of n observations is sqrt(n) times more precise, "
            "d = sqrt(n) |theta1 - theta0| / sigma",
            lambda n, theta0, theta1, sigma, alpha: _np_power(n, theta0, theta1, sigma, alpha, 1),
        ),
        Mistake(
            "looks like n / sigma where sqrt(n) / sigma belongs: the standard deviation of the "
            "mean is sigma / sqrt(n)",
            lambda n, theta0, theta1, sigma, alpha: _np_power(
                n, theta0, theta1, sigma, alpha, float(n)
            ),
        ),
        Mistake(
            "sigma looks left out: d measures |theta1 - theta0| in standard deviations of the "
            "mean, sqrt(n) |theta1 - theta0| / sigma",
            lambda n, theta0, theta1, sigma, alpha: _np_power(n, theta0, theta1, 1.0, alpha),
        ),
        Mistake(
            "the probability of NOT detecting (cdf): the power is the upper tail, "
            "Phi(d - z_alpha) = sf(z_alpha - d)",
            lambda n, theta0, theta1, sigma, alpha: (
                1.0 - _np_power(n, theta0, theta1, sigma, alpha)
            ),
        ),
    ],
)
def q7(n, theta0, theta1, sigma, alpha):
    z = np.zeros(int(n))
    return float(
        dg.neyman_pearson_test(z, theta0, theta1, sigma=sigma, alpha=alpha).details["power"]
    )


q7.case(2, 0.0, 1.0, 1.0, 0.05, label="the lecture's two observations, theta1 = 1")
q7.case(4, 0.0, 1.0, 1.0, 0.05, label="four observations")
q7.case(5, 0.0, 0.6, 0.5, 0.05, label="five observations, sigma = 0.5")
q7.case(10, 1.0, 0.8, 0.5, 0.01, hidden=True)
q7.case(1, -2.0, 3.0, 2.0, 0.1, hidden=True)


def _boundary_rate(n, alpha, n_runs, seed, columns=False, clip=True, one=False):
    """q8's simulation with a declared mistake: samples in columns, no boundary, or one sample
    per run."""
    rng = np.random.default_rng(seed)
    if one:
        zbar, n = rng.standard_normal(n_runs), 1
    elif columns:
        zbar = rng.standard_normal((n, n_runs)).mean(axis=0)
    else:
        zbar = rng.standard_normal((n_runs, n)).mean(axis=1)
    z = np.maximum(zbar, 0.0) if clip else zbar
    return float(np.mean(n * z**2 > stats.chi2.isf(alpha, 1)))


@CHECKS.function(
    "q8",
    func="boundary_false_alarm",
    points=2,
    timeout=30,
    atol=0.1 / 20000,  # the same count of alarms: a fraction k / n_runs, exactly
    rtol=0.0,
    hint=(
        "The grader repeats your simulation with the case's seed, so draw the samples as the "
        "question says: rng = np.random.default_rng(seed) and ONE call "
        "rng.standard_normal((n_runs, n)), row r the sample r (a loop of draws or the shape "
        "(n, n_runs) gives other samples).",
        "On the boundary the constrained estimate is max(0, mean of the row), so "
        "-2 log Lambda = n max(0, mean)^2 is exactly 0 for about half of the rows; return the "
        "fraction of rows above stats.chi2.isf(alpha, 1) (not a theoretical rate).",
    ),
    mistakes=[
        Mistake(
            "this is the theoretical rate alpha/2, not the simulated one",
            lambda n, alpha, n_runs, seed: alpha / 2,
        ),
        Mistake(
            "returns alpha: that is what Wilks promises, not what the simulation measures",
            lambda n, alpha, n_runs, seed: float(alpha),
        ),
        Mistake(
            "the rate of the right statistic, but the samples drawn in another order (samples "
            "in columns?): ONE call rng.standard_normal((n_runs, n)), row r the sample r",
            lambda n, alpha, n_runs, seed: _boundary_rate(n, alpha, n_runs, seed, columns=True),
            hint="The grader repeats your draws: rng = np.random.default_rng(seed), then "
            "rng.standard_normal((n_runs, n)) with row r the sample r.",
        ),
        Mistake(
            "no boundary: n zbar^2 is the unconstrained (two-sided) statistic; on the boundary "
            "the estimate is max(0, zbar), so -2 log Lambda = n max(0, zbar)^2",
            lambda n, alpha, n_runs, seed: _boundary_rate(n, alpha, n_runs, seed, clip=False),
        ),
        Mistake(
            "one sample per run: each run has n samples, and the statistic uses their mean",
            lambda n, alpha, n_runs, seed: _boundary_rate(n, alpha, n_runs, seed, one=True),
        ),
    ],
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


_NO_PRIORS = (
    "the priors look forgotten (every mode equally likely): Bayes' rule multiplies each "
    "likelihood by its mode's prior"
)
_TAU = (
    "tau looks used as a variance: the faulty gain's prior standard deviation is tau, so its "
    "covariance adds tau^2 u_i u_i^T"
)


def _posterior(y, U_, sigma, tau, priors):
    logl = dg.mode_log_likelihoods(y, U_, NOMINAL, MODES, sigma=sigma, prior_std=tau)
    post = dg.bayes_ranking(logl, dict(zip(MODES, priors))).as_dict()
    return np.array([post[m] for m in MODES])


@CHECKS.function(
    "q9_practice",
    func="posteriors",
    forbid=[
        "course.diagnosis.bayes_ranking",
        "course.diagnosis.mode_log_likelihoods",
    ],
    points=1,
    rtol=1e-6,
    atol=1e-300,
    hint="The marginal likelihood integrates the faulty gain out: under Fi, y ~ N(U 1, sigma^2 I + "
    "tau^2 u_i u_i^T). Maximising over the gain instead is a different (and here wrong) quantity.",
    mistakes=[
        Mistake(
            "looks like the MAXIMISED likelihood (the best gain plugged in): use the marginal one",
            lambda y, U_, sigma, tau, priors: _maximised(y, U_, sigma, priors),
        ),
        Mistake(
            _NO_PRIORS,
            lambda y, U_, sigma, tau, priors: _posterior(
                y, U_, sigma, tau, np.full(len(MODES), 1.0 / len(MODES))
            ),
        ),
        Mistake(
            _TAU, lambda y, U_, sigma, tau, priors: _posterior(y, U_, sigma, np.sqrt(tau), priors)
        ),
    ],
)
def q9_practice(y, U_, sigma, tau, priors):
    return _posterior(y, U_, sigma, tau, priors)


def _modes_case(seed):
    d = data.modes(np.random.default_rng(seed))
    return d["y"], d["U"], d["sigma"], d["tau"], d["priors"]


q9_practice.case(Y_MODES, U, SIGMA, 0.3, PRIORS, label="the notebook's practice record")
### BEGIN HIDDEN TESTS
for _seed in (61, 62, 63, 64):
    q9_practice.case(*_modes_case(_seed), hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q9",
    forbid=[
        "course.diagnosis.bayes_ranking",
        "course.diagnosis.mode_log_likelihoods",
    ],
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
    mistakes=[
        Mistake(
            "looks like the MAXIMISED likelihood (the best gain plugged in): use the marginal one",
            lambda d: _maximised(d["y"], d["U"], d["sigma"], d["priors"]),
        ),
        Mistake(
            _NO_PRIORS,
            lambda d: _posterior(
                d["y"], d["U"], d["sigma"], d["tau"], np.full(len(MODES), 1.0 / len(MODES))
            ),
        ),
        Mistake(
            _TAU, lambda d: _posterior(d["y"], d["U"], d["sigma"], np.sqrt(d["tau"]), d["priors"])
        ),
    ],
)
def q9(d):
    return _posterior(d["y"], d["U"], d["sigma"], d["tau"], d["priors"])


def _maximised(y, U_, sigma, priors):
    """Posteriors from the maximised instead of the marginal likelihood (the mistake)."""
    r0 = y - U_ @ NOMINAL
    log_l = [-(r0 @ r0) / (2 * sigma**2)]
    for i in range(3):
        u = U_[:, i]
        r = r0 - u * (u @ r0) / (u @ u)
        log_l.append(-(r @ r) / (2 * sigma**2))
    log_post = np.array(log_l) + np.log(priors)
    return np.exp(log_post - np.logaddexp.reduce(log_post))
