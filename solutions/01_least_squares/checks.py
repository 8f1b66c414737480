"""Checks of assignment 01_least_squares (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

from collections import namedtuple

import numpy as np
from scipy import linalg, stats

from course import lsq
from course.grading.authoring.checks import Checks, Mistake

from . import data

# Results with several parts are named tuples: feedback names the part that is wrong
# (``critical_value``, not ``item [1]``). A student's plain tuple or list in the same order
# is just as right (the grader compares item by item).
OverallModelTest = namedtuple("OverallModelTest", "T critical_value reject")
Band95 = namedtuple("Band95", "sigma half_width")

# Chapter 10's line fit: t = 1..4 s, Qyy = I (days 1 and 2).
T_LINE = np.arange(1.0, 5.0)
A_LINE = np.column_stack([np.ones(4), T_LINE])
Y_DAY1 = np.array([14.0, 20.0, 20.0, 24.0])
Y_DAY2 = np.array([28.0, 20.0, 16.0, 36.0])
I4 = np.eye(4)

# A public line of q1 whose estimate is not round (2.4, 0.8333...).
T_NONROUND = np.array([0.0, 1.5, 3.0, 4.5, 6.0])
Y_NONROUND = np.array([2.3, 3.9, 4.4, 6.8, 7.1])

# A falling line at uneven times (a hidden case of q1 and q2).
T_UNEVEN = np.array([0.5, 1.0, 2.5, 4.0, 7.0])
Y_UNEVEN = np.array([3.1, 2.2, 0.4, -1.9, -6.3])

# Sea level 1998-2002 (t centred on 2000), and a quadratic model of day 2.
A_SEA = np.column_stack([np.ones(5), np.arange(-2.0, 3.0)])
Y_SEA = np.array([25.0, 24.0, 27.0, 26.0, 28.0])
A_QUAD = np.column_stack([np.ones(4), T_LINE, 0.5 * T_LINE**2])


def _correlated(m, rho, scale=1.0):
    """An exponentially correlated covariance matrix (symmetric positive definite)."""
    idx = np.arange(m)
    return scale * rho ** np.abs(idx[:, None] - idx[None, :])


_R6 = np.random.default_rng(20240601)
A6 = np.column_stack([np.ones(6), np.linspace(0.0, 5.0, 6), np.linspace(0.0, 5.0, 6) ** 2])
Q6 = _correlated(6, 0.4, 2.0) + np.diag(_R6.uniform(0.1, 0.5, 6))
Y6 = A6 @ np.array([1.0, -2.0, 0.3]) + np.linalg.cholesky(Q6) @ _R6.standard_normal(6)
Y6[2] += 9.0

# The public practice survey of q6_practice and q7_practice (data.survey's design, seed 2026):
# the largest |e| (index 6) is not the blunder, which only the w-test finds.
Y_PRACTICE = np.array(
    [12.320, 11.816, 10.894, 11.593, 8.132, 12.332, 18.837, 13.281, 15.585, 12.036, 14.720, 11.788]
)
SIGMA_PRACTICE = np.array(
    [0.967, 0.871, 0.855, 1.291, 0.433, 0.677, 2.979, 0.798, 1.467, 1.420, 1.136, 1.253]
)
A_PRACTICE = np.column_stack([np.ones(12), np.arange(12.0)])

CHECKS = Checks(
    "01_least_squares",
    title="Assignment 1: least-squares validation",
    data=data,
    timeout=10,
    preload=["course.lsq", "scipy.stats", "scipy.linalg"],
)


@CHECKS.function(
    "q1",
    func="line_estimate",
    points=1,
    rtol=1e-8,
    atol=1e-8,
    hint=(
        "Two unknowns: the position at t0 and the velocity. Build A from the t you are given "
        "(its length is len(t), not always 4).",
        "Stack a column of ones and the times into A, then solve the least-squares problem "
        "(np.linalg.lstsq, or lsq.fit) and return x_hat = (position at t0, velocity). On day 1 "
        "the chapter's answer is a round pair.",
    ),
    mistakes=[
        Mistake(
            "the order looks like (velocity, position): x_hat is (x1, x2) = (position at t0, "
            "velocity), the columns of A (np.polyfit returns the highest power first)",
            lambda t, y: _line_fit(t, y).x_hat[::-1],
        ),
    ],
)
def q1(t, y):
    return _line_fit(t, y).x_hat


def _line_fit(t, y):
    """The least-squares fit of y = x1 + x2 t (Qyy = I)."""
    t = np.asarray(t, dtype=float)
    return lsq.fit(np.column_stack([np.ones_like(t), t]), np.asarray(y, dtype=float))


# Public: the chapter's worked examples (the self-check reproduces its numbers); hidden: other
# lines, other lengths, uneven times and a falling line, on which the grade rests.
q1.case(T_LINE, Y_DAY1, label="day 1 of the chapter's line fit")
# a non-round answer: one computed in float32 misses the tolerance here, at the self-check
# (day 1's round answer is exact in float32, so it passed there and failed only at grading)
q1.case(T_NONROUND, Y_NONROUND, label="five heights at uneven times (a non-round estimate)")
### BEGIN HIDDEN TESTS
q1.case(np.arange(-2.0, 3.0), Y_SEA, hidden=True)
q1.case(np.linspace(0.0, 5.0, 6), Y6, hidden=True)
q1.case(T_UNEVEN, Y_UNEVEN, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q2",
    func="line_residuals",
    points=1,
    rtol=1e-8,
    atol=1e-8,
    hint=(
        "Residuals belong to one fit: estimate x_hat from the y you are given (q1's function), "
        "then compare.",
        "Residuals are observations minus adjusted observations: e = y - A x_hat, one per "
        "observation, in the order of the observations.",
    ),
    mistakes=[
        Mistake(
            "the sign looks flipped: e = y - A x_hat (observed minus adjusted), not A x_hat - y",
            lambda t, y: -_line_fit(t, y).e_hat,
        ),
        Mistake(
            "these look like the squared residuals: return e itself, with its sign",
            lambda t, y: _line_fit(t, y).e_hat ** 2,
        ),
    ],
)
def q2(t, y):
    return _line_fit(t, y).e_hat


q2.case(T_LINE, Y_DAY2, label="day 2 of the chapter's line fit")
### BEGIN HIDDEN TESTS
q2.case(T_LINE, Y_DAY1, hidden=True)
q2.case(np.arange(-2.0, 3.0), Y_SEA, hidden=True)
q2.case(T_UNEVEN, Y_UNEVEN, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q3",
    func="overall_model_test_stat",
    points=3,
    rtol=1e-6,
    atol=1e-8,
    forbid=[
        "course.lsq.overall_model_test",
        "course.lsq.fit",
        "course.lsq.data_snooping",
        "course.diagnosis.least_squares_residual",
        "course.diagnosis.prediction_error",
    ],
    hint=(
        "Does your T change when Qyy changes? Each residual must be weighed by the precision of "
        "its observation.",
        "How many degrees of freedom does T have when n parameters are estimated from m "
        "observations? The test rejects in the upper tail only.",
        "T = e^T Qyy^{-1} e with the WEIGHTED residuals, m - n degrees of freedom, and the "
        "critical value scipy.stats.chi2.isf(alpha, m - n). Avoid inverting Qyy: whiten with "
        "its Cholesky factor. Return (T, critical_value, reject).",
    ),
    mistakes=[
        Mistake(
            "T looks unweighted: Qyy was ignored (the fit and T must both use Qyy)",
            lambda A, y, Qyy, alpha: _omt(
                A, y, np.eye(len(y)), alpha, np.shape(A)[0] - np.shape(A)[1]
            ),
            hint="Each residual must be weighed by the precision of its observation: fit and "
            "form T = e^T Qyy^{-1} e with Qyy (whiten with its Cholesky factor).",
        ),
        Mistake(
            "the critical value looks like chi2 with m degrees of freedom: n parameters were "
            "estimated",
            lambda A, y, Qyy, alpha: _omt(A, y, Qyy, alpha, np.shape(A)[0]),
            hint="Estimating n parameters from m observations leaves m - n degrees of freedom "
            "in the residuals: chi2.isf(alpha, m - n).",
        ),
        Mistake(
            "the critical value looks two-sided (alpha/2): the overall model test rejects in the "
            "upper tail only",
            lambda A, y, Qyy, alpha: _omt(A, y, Qyy, alpha / 2, np.shape(A)[0] - np.shape(A)[1]),
            hint="Only a LARGE T speaks against the model: all of alpha goes in the upper "
            "tail, chi2.isf(alpha, m - n).",
        ),
        Mistake(
            "T looks divided by m - n (the variance factor): the test statistic is the weighted "
            "sum of squared residuals itself, compared with chi2(m - n)",
            lambda A, y, Qyy, alpha: _omt(
                A, y, Qyy, alpha, np.shape(A)[0] - np.shape(A)[1], scale=True
            ),
        ),
    ],
)
def q3(A, y, Qyy, alpha):
    result = lsq.overall_model_test(lsq.fit(A, y, Qyy), alpha)
    return OverallModelTest(result.statistic, result.critical_value, bool(result.reject))


def _omt(A, y, Qyy, alpha, dof, scale=False):
    """(T, critical value, reject) with the given weights, level and degrees of freedom (T
    divided by m - n when ``scale``)."""
    stat = lsq.fit(A, y, Qyy).squared_norm
    if scale:
        stat /= np.shape(A)[0] - np.shape(A)[1]
    c = float(stats.chi2.isf(alpha, dof))
    return (stat, c, bool(stat > c))


q3.case(A_LINE, Y_DAY1, I4, 0.01, label="day 1 of the line fit, alpha = 0.01")
q3.case(A_LINE, Y_DAY2, I4, 0.01, label="day 2 of the line fit, alpha = 0.01")
q3.case(
    A_LINE,
    Y_DAY2,
    np.diag([1.0, 4.0, 4.0, 1.0]),
    0.01,
    label="day 2 with sigma = 2 for the two middle observations (Qyy not I), alpha = 0.01",
)
### BEGIN HIDDEN TESTS
q3.case(A_SEA, Y_SEA, np.eye(5), 0.10, hidden=True)
q3.case(A_QUAD, Y_DAY2, np.diag([1.0, 4.0, 4.0, 1.0]), 0.05, hidden=True)
q3.case(A6, Y6, Q6, 0.05, hidden=True)
q3.case(A_SEA, Y_SEA, np.diag([1.0, 1.0, 4.0, 1.0, 1.0]), 0.10, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q4",
    func="w_statistics",
    points=3,
    rtol=1e-6,
    atol=1e-8,
    forbid=["course.lsq.w_tests", "course.lsq.fit", "course.lsq.data_snooping"],
    hint=(
        "Each residual is divided by ITS OWN standard deviation, which is smaller than that of "
        "its observation: the fit has absorbed part of the noise.",
        "Baarda: w_i = (Qyy^{-1} e)_i / sqrt((Qyy^{-1} Qee Qyy^{-1})_ii) with "
        "Qee = Qyy - A Qxx A^T; for a diagonal Qyy this is e_i / sigma_ei. "
        "Return one w per observation.",
    ),
    mistakes=[
        Mistake(
            "looks like e_i / sigma_yi: divide by the residual's standard deviation (from Qee), "
            "not the observation's",
            lambda A, y, Qyy: lsq.fit(A, y, Qyy).e_hat / np.sqrt(np.diag(Qyy)),
        ),
        Mistake(
            "e_i / sigma_ei is w_i only for uncorrelated observations: with a full Qyy, "
            "w_i = (Qyy^{-1} e)_i / sqrt((Qyy^{-1} Qee Qyy^{-1})_ii)",
            lambda A, y, Qyy: lsq.fit(A, y, Qyy).e_hat / np.sqrt(np.diag(lsq.fit(A, y, Qyy).Qee)),
        ),
    ],
)
def q4(A, y, Qyy):
    return np.asarray(lsq.w_tests(lsq.fit(A, y, Qyy), 0.05).statistic)


q4.case(A_LINE, Y_DAY2, I4, label="day 2 of the line fit")
### BEGIN HIDDEN TESTS
q4.case(A_SEA, Y_SEA, np.diag([1.0, 1.0, 4.0, 1.0, 1.0]), hidden=True)
q4.case(A6, Y6, Q6, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q5",
    func="band_95",
    points=1,
    rtol=1e-4,  # the printed 1.96 is as right as norm.isf(0.025) = 1.959964
    atol=1e-8,
    hint=(
        "a^T x_hat is a linear function of x_hat: propagate Qxx through a. Qxx depends on A "
        "and Qyy only, not on y.",
        "Qxx = (A^T Qyy^{-1} A)^{-1} (weighted), sigma = sqrt(a^T Qxx a); the 95 % half-width "
        "multiplies it by scipy.stats.norm.isf(0.025). Return (sigma, half_width).",
    ),
    mistakes=[
        Mistake(
            "the half-width looks one-sided (z_0.05): a 95 % interval leaves 2.5 % in each tail",
            lambda A, Qyy, a: _band(A, Qyy, a, float(stats.norm.isf(0.05))),
        ),
        Mistake(
            "looks like the variance a^T Qxx a, not its square root",
            lambda A, Qyy, a: _band(A, Qyy, a, float(stats.norm.isf(0.025)), squared=True),
        ),
        Mistake(
            "Qyy looks ignored: Qxx = (A^T A)^{-1} holds only for Qyy = I; weigh with Qyy^{-1}",
            lambda A, Qyy, a: _band(A, np.eye(np.shape(A)[0]), a, float(stats.norm.isf(0.025))),
        ),
        Mistake(
            "the unknowns look swapped: a weighs x_hat in the order of A's columns, (position "
            "at t0, velocity), so a^T Qxx a with a as given, not reversed",
            lambda A, Qyy, a: _band(A, Qyy, np.asarray(a)[::-1], float(stats.norm.isf(0.025))),
            hint="x_hat = (x1, x2) in the order of A's columns: a = (1, t) picks x1 + t x2.",
        ),
        Mistake(
            "a Student t quantile: Qyy is known, so the estimate is normal and the half-width "
            "uses norm.isf(0.025)",
            lambda A, Qyy, a: _band(
                A, Qyy, a, float(stats.t.isf(0.025, np.shape(A)[0] - np.shape(A)[1]))
            ),
        ),
    ],
)
def q5(A, Qyy, a):
    f = lsq.fit(A, np.zeros(np.shape(A)[0]), Qyy)  # Qxx does not depend on the data
    _, half = lsq.confidence_band(f, np.atleast_2d(a), level=0.95)
    return Band95(float(np.sqrt(a @ f.Qxx @ a)), float(half[0]))


def _band(A, Qyy, a, z, squared=False):
    """(sigma, z sigma) of a^T x_hat for the fit with design A and covariance Qyy (with the
    variance in place of sigma when ``squared``)."""
    a = np.asarray(a, dtype=float)
    var = float(a @ lsq.fit(A, np.zeros(np.shape(A)[0]), Qyy).Qxx @ a)
    s = var if squared else np.sqrt(var)
    return (float(s), z * float(s))


q5.case(A_LINE, I4, np.array([1.0, 2.0]), label="day 1 of the line fit at t = 2 (Qyy = I)")
q5.case(
    A_LINE,
    np.diag([1.0, 4.0, 4.0, 1.0]),
    np.array([1.0, 2.0]),
    label="the line fit at t = 2 with sigma = 2 for the two middle observations",
)
### BEGIN HIDDEN TESTS
q5.case(A_SEA, np.diag([1.0, 1.0, 4.0, 1.0, 1.0]), np.array([1.0, 0.5]), hidden=True)
q5.case(A_QUAD, np.diag([1.0, 4.0, 4.0, 1.0]), np.array([1.0, 2.5, 3.125]), hidden=True)
q5.case(A6, Q6, A6[2], hidden=True)
### END HIDDEN TESTS


def _practice_survey(y, sigma):
    return {"A": A_PRACTICE, "y": y, "Qyy": np.diag(sigma**2), "alpha": 0.01}


def _drawn_survey(seed):
    """A survey of data.survey's design (the students' own), drawn with a fixed seed."""
    d = data.survey(np.random.default_rng(seed))
    return {key: d[key] for key in ("A", "y", "Qyy", "alpha")}


@CHECKS.function(
    "q6_practice",
    func="survey_T",
    points=1,
    rtol=1e-6,
    atol=1e-8,
    hint="The same computation as q3, on a survey given as a dict like mine (keys 'A', 'y', "
    "'Qyy', 'alpha'): fit with its (diagonal, not identity) Qyy and return the overall model "
    "test statistic T.",
    mistakes=[
        Mistake(
            "T looks unweighted: the survey's Qyy was ignored",
            lambda survey: lsq.fit(survey["A"], survey["y"]).squared_norm,
        ),
        Mistake(
            "fitted with diag(sigma) as Qyy: Qyy holds the VARIANCES sigma^2 (the survey's "
            "Qyy as given, not the square roots of its diagonal)",
            lambda survey: (
                lsq.fit(
                    survey["A"], survey["y"], np.diag(np.sqrt(np.diag(survey["Qyy"])))
                ).squared_norm
            ),
            hint="Pass the survey's Qyy itself: it is already the covariance matrix, sigma^2 on "
            "its diagonal.",
        ),
        Mistake(
            "the practice survey's Qyy was used, not the Qyy of the survey passed in",
            lambda survey: (
                lsq.fit(survey["A"], survey["y"], np.diag(SIGMA_PRACTICE**2)).squared_norm
            ),
        ),
        Mistake(
            "each squared residual looks divided by sigma instead of sigma^2 (the variance)",
            lambda survey: float(
                np.sum(
                    lsq.fit(survey["A"], survey["y"], survey["Qyy"]).e_hat ** 2
                    / np.sqrt(np.diag(survey["Qyy"]))
                )
            ),
        ),
    ],
)
def q6_practice(survey):
    fit = lsq.fit(survey["A"], survey["y"], survey["Qyy"])
    return lsq.overall_model_test(fit, survey["alpha"]).statistic


def _unweighted_suspect(survey):
    """The largest |e_i / sigma_i| of the UNWEIGHTED fit: no w-test, though it often finds the
    same observation (data.survey's design makes it differ)."""
    e = lsq.fit(survey["A"], survey["y"]).e_hat
    return int(np.argmax(np.abs(e) / np.sqrt(np.diag(survey["Qyy"]))))


_NOT_W_TEST = (
    "this is the largest |e_i / sigma_i| of a fit WITHOUT the weights: the w-test fits with Qyy "
    "and divides each residual by its own standard deviation sigma_ei (from Qee)"
)
_LARGEST_E = (
    "this is the largest |e|, not the largest |w|: a residual is large or small only relative "
    "to its own standard deviation"
)


@CHECKS.function(
    "q7_practice",
    func="first_suspect",
    points=1,
    hint=(
        "Data snooping on a survey given as a dict like mine: the observation with the largest "
        "|w| (each residual of the WEIGHTED fit divided by ITS OWN standard deviation), as a "
        "0-based index.",
        "lsq.data_snooping(lsq.fit(survey['A'], survey['y'], survey['Qyy']), alpha=survey['alpha']) "
        "lists the removed observations in their original numbering; return the first as an int.",
    ),
    mistakes=[
        Mistake(
            _LARGEST_E,
            lambda survey: int(
                np.argmax(np.abs(lsq.fit(survey["A"], survey["y"], survey["Qyy"]).e_hat))
            ),
        ),
        Mistake(_NOT_W_TEST, _unweighted_suspect),
    ],
)
def q7_practice(survey):
    snooping = lsq.data_snooping(
        lsq.fit(survey["A"], survey["y"], survey["Qyy"]), alpha=survey["alpha"]
    )
    return int(snooping.removed[0])


# Public: the notebook's practice survey, and one more survey of the students' design, on
# which the largest |e_i / sigma_i| of an unweighted fit is not the blunder (on the practice
# survey it happens to be, so that wrong method must lose a public case here).
for _q in (q6_practice, q7_practice):
    _q.case(_practice_survey(Y_PRACTICE, SIGMA_PRACTICE), label="the notebook's practice survey")
    _q.case(_drawn_survey(2027), label="another survey of the same design")
### BEGIN HIDDEN TESTS
for _q in (q6_practice, q7_practice):
    for _seed in (31, 32, 33):
        _q.case(_drawn_survey(_seed), hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q6",
    var="T_mine",
    points=2,
    data="survey",
    properties="survey_T_properties",
    rtol=1e-6,
    atol=1e-8,
    hint="Fit mine['A'], mine['y'] with mine['Qyy'] (weighted!) and take the overall model "
    "test statistic of the full data set.",
    mistakes=[
        Mistake(
            "T looks unweighted: mine['Qyy'] was ignored",
            lambda d: lsq.fit(d["A"], d["y"]).squared_norm,
        ),
        Mistake(
            "each squared residual looks divided by sigma instead of sigma^2 (the variance)",
            lambda d: float(
                np.sum(lsq.fit(d["A"], d["y"], d["Qyy"]).e_hat ** 2 / np.sqrt(np.diag(d["Qyy"])))
            ),
        ),
        Mistake(
            "T looks divided by m - n (the variance factor): the test statistic is the weighted "
            "sum of squared residuals itself",
            lambda d: (
                lsq.fit(d["A"], d["y"], d["Qyy"]).squared_norm
                / (np.shape(d["A"])[0] - np.shape(d["A"])[1])
            ),
        ),
    ],
)
def q6(d):
    return lsq.overall_model_test(lsq.fit(d["A"], d["y"], d["Qyy"]), d["alpha"]).statistic


@CHECKS.choice(
    "q6b",
    var="verdict_mine",
    options=["accepted", "rejected"],
    points=1,
    data="survey",
    hint='Answer "accepted" or "rejected".',
)
def q6b(d):
    result = lsq.overall_model_test(lsq.fit(d["A"], d["y"], d["Qyy"]), d["alpha"])
    return "rejected" if result.reject else "accepted"


@CHECKS.value(
    "q7",
    var="suspect_mine",
    points=1,
    data="survey",
    properties="survey_index_properties",
    hint="Data snooping at mine['alpha'] removes the observation with the largest rejected |w| "
    "first; give its 0-based index as an int.",
    mistakes=[
        Mistake(
            _LARGEST_E,
            lambda d: int(np.argmax(np.abs(lsq.fit(d["A"], d["y"], d["Qyy"]).e_hat))),
        ),
        Mistake(_NOT_W_TEST, _unweighted_suspect),
    ],
)
def q7(d):
    return int(lsq.data_snooping(lsq.fit(d["A"], d["y"], d["Qyy"]), alpha=d["alpha"]).removed[0])


@CHECKS.function(
    "q8",
    func="rejection_rate",
    points=2,
    timeout=30,
    atol=0.1 / 20000,  # the same count of rejections: a fraction k / n_runs, exactly
    rtol=0.0,
    hint=(
        "The grader repeats your simulation, so the random numbers must be drawn in the same "
        "order: rng = np.random.default_rng(seed), ONE call Z = rng.standard_normal((n_runs, m)) "
        "(row r for data set r), L = np.linalg.cholesky(Qyy), and data set r is bias + L z_r.",
        "Each data set is fitted with the weights Qyy and tested like q3: n = A.shape[1] "
        "parameters are estimated from m observations, so T has m - n degrees of freedom. "
        "Count T > stats.chi2.isf(alpha, m - n) and return the fraction of the n_runs data sets "
        "rejected.",
    ),
    mistakes=[
        Mistake(
            "this is the exact rejection probability (a formula), not the simulated rate",
            lambda A, Qyy, alpha, n_runs, seed, bias: _exact_rate(A, Qyy, alpha, bias),
        ),
        Mistake(
            "returns alpha: that is what the test promises, not what the simulation measures",
            lambda A, Qyy, alpha, n_runs, seed, bias: float(alpha),
        ),
        Mistake(
            "the critical value looks like chi2 with m degrees of freedom: n parameters are "
            "estimated, so T has m - n",
            lambda A, Qyy, alpha, n_runs, seed, bias: _rejection_rate(
                A, Qyy, alpha, n_runs, seed, bias, dof=np.shape(A)[0]
            ),
        ),
        Mistake(
            "the rate of the right test, but the noise drawn in another order (as (m, n_runs)?): "
            "ONE call rng.standard_normal((n_runs, m)), row r for data set r",
            lambda A, Qyy, alpha, n_runs, seed, bias: _rejection_rate(
                A, Qyy, alpha, n_runs, seed, bias, columns=True
            ),
        ),
    ],
)
def q8(A, Qyy, alpha, n_runs, seed, bias):
    return _rejection_rate(A, Qyy, alpha, n_runs, seed, bias)


def _rejection_rate(A, Qyy, alpha, n_runs, seed, bias, dof=None, columns=False):
    """q8's simulation (``dof``, ``columns``: the declared mistakes of another dof, the noise
    drawn as (m, n_runs))."""
    # The simulation the question prescribes, run with the case's seed: a correct answer counts
    # exactly the same rejections however it computes T, while the exact probability (ncx2),
    # alpha, a wrong dof, ignoring Qyy or the bias, or another random sample all differ from it.
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    L = np.linalg.cholesky(Qyy)
    rng = np.random.default_rng(seed)
    Z = rng.standard_normal((m, n_runs)).T if columns else rng.standard_normal((n_runs, m))
    Y = np.asarray(bias, dtype=float) + Z @ L.T  # row r: data set r
    A_w = linalg.solve_triangular(L, A, lower=True)
    Y_w = linalg.solve_triangular(L, Y.T, lower=True)  # whitened data sets as columns
    Q, _ = np.linalg.qr(A_w)
    R = Y_w - Q @ (Q.T @ Y_w)
    stats_ = np.sum(R * R, axis=0)
    return float(np.mean(stats_ > stats.chi2.isf(alpha, m - n if dof is None else dof)))


def _exact_rate(A, Qyy, alpha, bias):
    """The exact rejection probability: T ~ chi2(m - n, lambda), lambda the weighted squared norm
    of the residuals of fitting the bias itself."""
    m, n = np.shape(A)
    lam = lsq.fit(A, bias, Qyy).squared_norm
    return alpha if lam < 1e-12 else float(stats.ncx2.sf(stats.chi2.isf(alpha, m - n), m - n, lam))


q8.case(
    A_LINE, I4, 0.05, 20000, 2024, np.zeros(4), label="line fit, Qyy = I, alpha = 0.05, no bias"
)
q8.case(
    A_LINE,
    I4,
    0.05,
    20000,
    2025,
    np.array([0.0, 0.0, 3.0, 0.0]),
    label="line fit, Qyy = I, alpha = 0.05, bias 3 in observation 2",
)
### BEGIN HIDDEN TESTS
q8.case(A_QUAD, _correlated(4, 0.6, 1.5), 0.01, 20000, 7, np.zeros(4), hidden=True)
q8.case(A_SEA, np.diag([1.0, 2.0, 0.5, 1.0, 3.0]), 0.10, 20000, 11, np.zeros(5), hidden=True)
q8.case(
    A_SEA,
    np.diag([1.0, 2.0, 0.5, 1.0, 3.0]),
    0.05,
    20000,
    13,
    np.array([0.0, 0.0, 0.0, 3.0, 0.0]),
    hidden=True,
)
q8.case(A6, Q6, 0.05, 20000, 17, np.array([0.0, 0.0, 4.0, 0.0, 0.0, 0.0]), hidden=True)
### END HIDDEN TESTS
