"""Checks of assignment 02_test_quantities (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

from collections import namedtuple

import numpy as np
from scipy import stats

from course import chi2
from course import diagnosis as dg
from course.grading.authoring.checks import Checks, Mistake

from . import data

# Results with several parts are named tuples: feedback names the part that is wrong
# (``critical_value``, not ``item [1]``). A student's plain tuple or list in the same order
# is just as right (the grader compares item by item).
Hypotheses = namedtuple("Hypotheses", "modes_H0 modes_H1")
RegressionResidual = namedtuple("RegressionResidual", "T dof")
ThresholdAndPower = namedtuple("ThresholdAndPower", "J power")

# The notebook's context: the three-gain model of the lecture and its signals.
N = 40
T_AXIS = np.arange(N)
U1 = 1.0 + 0.5 * np.sin(2 * np.pi * T_AXIS / 20)
U2 = np.cos(2 * np.pi * T_AXIS / 13)
U3 = np.where((T_AXIS // 8) % 2 == 0, 1.0, -1.0)
U = np.column_stack([U1, U2, U3])
# The same three signals over 60 samples (a hidden case of q9 with another N).
_T60 = np.arange(60)
U_60 = np.column_stack(
    [
        1.0 + 0.5 * np.sin(2 * np.pi * _T60 / 20),
        np.cos(2 * np.pi * _T60 / 13),
        np.where((_T60 // 8) % 2 == 0, 1.0, -1.0),
    ]
)
SIGMA = 0.2
NOMINAL = np.ones(3)
MODES = ["NF", "F1", "F2", "F3"]
LECTURE = np.array([[0, 0, 1, 1], [0, 1, 0, 1], [0, 1, 1, 0]])
# q8b: a single mode, nothing alarms, two or more fault modes remain, or no mode remains.
Q8B_OPTIONS = [
    "NF",
    "F1",
    "F2",
    "F3",
    "no fault detected",
    "several faults fit",
    "no single fault fits",
]
MODES5 = ["NF", "F1", "F2", "F3", "F4"]
STRUCTURE5 = np.array([[0, 1, 1, 0, 0], [0, 0, 1, 1, 0], [0, 1, 0, 0, 1], [0, 0, 0, 1, 1]])
Y_RECORD = U @ np.array([1.0, 1.3, 1.0]) + SIGMA * np.random.default_rng(2).standard_normal(N)

# Gain-and-bias sensor data of q5.
N_GB = 20
U_GB = np.linspace(0.0, 2.0, N_GB)
Y_GB = 1.0 * U_GB + 0.4 + 0.05 * np.random.default_rng(5).standard_normal(N_GB)

# The public practice record of q7_practice and q8_practice: a small F2 fault (theta2 = 1.1)
# that T3 detects only just; with chi2(N) or alpha / 2, the diagnosis changes.
Y_NEAR = U @ np.array([1.0, 1.1, 1.0]) + SIGMA * np.random.default_rng(148).standard_normal(N)

_R = np.random.default_rng(20240502)
_A, _B = _R.standard_normal(12), _R.standard_normal(12)

CHECKS = Checks(
    "02_test_quantities",
    title="Assignment 2: test quantities from prediction errors",
    data=data,
    timeout=10,
    preload=["course.diagnosis", "scipy.stats", "scipy.linalg"],
)


@CHECKS.function(
    "q1",
    func="single_fault_diagnoses",
    points=2,
    forbid=[
        "course.diagnosis.diagnoses",
        "course.diagnosis.diagnosis_matrix",
        "course.diagnosis.DecisionStructure",
    ],
    hint="An alarm from test k rules out every mode with a 0 in row k; a silent test rules "
    "out nothing. Keep the modes in the order of the columns; return a list.",
)
def q1(sensitivity, modes, alarms):
    structure = dg.DecisionStructure(np.asarray(sensitivity), modes=list(modes))
    return list(dg.diagnoses(structure, [bool(a) for a in alarms]))


q1.case(LECTURE, MODES, [True, False, True], label="lecture structure, T1 and T3 alarm")
q1.case(LECTURE, MODES, [False, False, False], label="lecture structure, no alarm")
q1.case(LECTURE, MODES, [True, True, True], hidden=True)
q1.case(STRUCTURE5, MODES5, [True, False, False, False], hidden=True)
q1.case(STRUCTURE5, MODES5, [True, True, False, False], hidden=True)
q1.case(STRUCTURE5, MODES5, [False, True, False, True], hidden=True)


@CHECKS.function(
    "q2",
    func="hypotheses",
    forbid=[
        "course.diagnosis.DecisionStructure",
    ],
    points=1,
    hint="Read row k of the structure: modes with 0 form H0, modes with X (1) form H1. "
    "Return (list_H0, list_H1), each in column order.",
    mistakes=[
        Mistake(
            "H0 and H1 look swapped: H0 holds the modes the test does NOT react to (a 0 in its "
            "row), H1 those it reacts to",
            lambda sensitivity, modes, k: tuple(q2.reference(sensitivity, modes, k)[::-1]),
        ),
    ],
)
def q2(sensitivity, modes, k):
    row = np.asarray(sensitivity)[int(k)]
    return Hypotheses(
        [m for m, x in zip(modes, row) if not x], [m for m, x in zip(modes, row) if x]
    )


q2.case(STRUCTURE5, MODES5, 1, label="the five-mode structure, test T2 (row 1)")
### BEGIN HIDDEN TESTS
q2.case(LECTURE, MODES, 0, hidden=True)
q2.case(STRUCTURE5, MODES5, 3, hidden=True)
### END HIDDEN TESTS


def _t1_with(y, u1, u2, u3, theta1):
    """The sum of squared residuals with theta1 = theta1(target, u1) (declared mistakes)."""
    y, u1, u2, u3 = (np.asarray(v, dtype=float) for v in (y, u1, u2, u3))
    target = y - u2 - u3
    r = target - theta1(target, u1) * u1
    return float(r @ r)


@CHECKS.function(
    "q3",
    func="T1_statistic",
    points=2,
    rtol=1e-7,
    atol=1e-10,
    forbid=[
        "course.diagnosis.prediction_error",
        "course.diagnosis.least_squares_residual",
        "course.diagnosis.prediction_error_test",
        "course.diagnosis.linear_test_statistics",
    ],
    mistakes=[
        Mistake(
            "looks divided by sigma^2: T1 is the plain sum of squared residuals (the threshold "
            "of q6 carries the sigma^2)",
            lambda y, u1, u2, u3: q3.reference(y, u1, u2, u3) / SIGMA**2,
        ),
        Mistake(
            "looks like the MEAN of the squared residuals: T1 is their sum",
            lambda y, u1, u2, u3: q3.reference(y, u1, u2, u3) / np.size(y),
        ),
        Mistake(
            "theta1 looks fixed at 1: T1 leaves theta1 free, minimising the sum over it",
            lambda y, u1, u2, u3: _t1_with(y, u1, u2, u3, lambda t, u: 1.0),
        ),
        Mistake(
            "the ratio looks upside down: the minimiser is sum(target u1) / sum(u1^2)",
            lambda y, u1, u2, u3: _t1_with(
                y, u1, u2, u3, lambda t, u: (u @ u) / (t @ u) if t @ u != 0 else 0.0
            ),
        ),
    ],
    hint=(
        "Set the derivative of the sum with respect to th1 to zero: what is left is a ratio of "
        "two sums. What happens to that ratio when u1 is identically zero?",
        "Minimise sum (y - th1 u1 - u2 - u3)^2 over th1: the minimiser is a ratio of two sums. "
        "If u1 is identically zero every th1 gives the same sum: do not divide by zero.",
    ),
)
def q3(y, u1, u2, u3):
    return float(dg.prediction_error(y, np.column_stack([u1, u2, u3]), NOMINAL, free=[0]).statistic)


q3.case(Y_RECORD, U1, U2, U3, label="the notebook's record")
q3.case(Y_RECORD, np.zeros(N), U2, U3, label="u1 identically zero")
q3.case(U @ [2.5, 1.0, 1.0], U1, U2, U3, hidden=True)
q3.case(U @ [1.0, 1.0, 0.5], U1, U2, U3, hidden=True)
q3.case(np.arange(5.0), np.array([1.0, 0, 2, 0, 1]), np.ones(5), np.zeros(5), hidden=True)
q3.case(U @ [1.0, 1.2, 1.0], np.zeros(N), U2, U3, hidden=True)  # u1 identically zero again
q3.case(np.arange(6.0), np.zeros(6), np.ones(6), np.zeros(6), hidden=True)


@CHECKS.function(
    "q4",
    func="regression_residual",
    points=2,
    rtol=1e-6,
    atol=1e-9,
    forbid=[
        "course.diagnosis.prediction_error",
        "course.diagnosis.least_squares_residual",
        "course.diagnosis.prediction_error_test",
        "course.diagnosis.linear_test_statistics",
    ],
    mistakes=[
        Mistake(
            "dof counts the columns of Phi: use its rank, dof = N - rank(Phi) (a column that "
            "repeats another, or is zero, estimates nothing and costs no degree of freedom)",
            lambda Phi, Y: RegressionResidual(
                q4.reference(Phi, Y).T, int(np.shape(Phi)[0] - np.shape(Phi)[1])
            ),
        ),
    ],
    hint="Project Y onto the orthogonal complement of the column space of Phi with an SVD "
    "(or np.linalg.lstsq, which reports the rank); never solve the normal equations. "
    "dof = N - rank(Phi). Return (T, dof).",
)
def q4(Phi, Y):
    fit = dg.least_squares_residual(Phi, Y)
    return RegressionResidual(float(fit.statistic), int(fit.dof))


q4.case(U, Y_RECORD, label="full column rank")
q4.case(
    np.column_stack([U1, 2 * U1, U3]), Y_RECORD, label="second column = 2 x first (no excitation)"
)
q4.case(np.column_stack([_A, _B, _A - 2 * _B]), _R.standard_normal(12), hidden=True)
q4.case(np.column_stack([np.zeros(12), _B]), _R.standard_normal(12), hidden=True)
q4.case(np.zeros((6, 2)), np.arange(6.0), hidden=True)


@CHECKS.function(
    "q5",
    func="bias_free_T",
    forbid=[
        "course.diagnosis.prediction_error",
        "course.diagnosis.least_squares_residual",
    ],
    points=1,
    rtol=1e-8,
    atol=1e-12,
    hint=(
        "Estimate the bias first, then measure what is left: the lecture's form is a mean, not a sum.",
        "T = (1/N) sum (y - u - b_hat)^2 with b_hat the mean of y - u (the lecture's 1/N form).",
    ),
    mistakes=[
        Mistake(
            "looks like the sum of the squared residuals: the lecture's T is their mean (1/N)",
            lambda y, u: float(np.sum((_gb(y, u) - np.mean(_gb(y, u))) ** 2)),
        ),
        Mistake(
            "the bias was not removed: subtract its estimate b_hat before squaring",
            lambda y, u: float(np.mean(_gb(y, u) ** 2)),
        ),
        Mistake(
            "looks like the sample variance with 1/(N - 1): the lecture's T divides by N",
            lambda y, u: float(np.var(_gb(y, u), ddof=1)),
        ),
    ],
)
def q5(y, u):
    return float(np.var(_gb(y, u)))  # (1/N) sum (y - u - b_hat)^2, b_hat = mean(y - u)


def _gb(y, u):
    return np.asarray(y, dtype=float) - np.asarray(u, dtype=float)


q5.case(Y_GB, U_GB, label="the notebook's gain-and-bias sensor, N = 20")
### BEGIN HIDDEN TESTS
q5.case(2.0 * U_GB - 0.3 + 0.1 * np.random.default_rng(6).standard_normal(N_GB), U_GB, hidden=True)
q5.case(
    np.linspace(0.0, 1.0, 7) + 0.5 + 0.02 * np.arange(7) ** 2, np.linspace(0.0, 1.0, 7), hidden=True
)
### END HIDDEN TESTS


@CHECKS.function(
    "q6",
    func="threshold_and_power",
    forbid=[
        "course.diagnosis.prediction_error_power",
    ],
    points=2,
    rtol=1e-6,
    atol=1e-9,
    hint=(
        "J is a threshold on T1 itself, not on T1/sigma^2; and one gain is estimated.",
        "Under H0, T1/sigma^2 ~ chi2(N - 1): J = sigma^2 chi2.isf(alpha, N - 1). Under F2, "
        "T1/sigma^2 is non-central chi2 with lambda = ||(I - P1) U2 (theta2 - 1)||^2 / sigma^2, "
        "P1 the projection on U1; use stats.ncx2.sf. Return (J, power).",
    ),
    mistakes=[
        Mistake(
            "J looks like a threshold on T1/sigma^2: the test compares T1 itself, so J = sigma^2 "
            "times the chi2 quantile",
            lambda U_, sigma, theta2, alpha: ThresholdAndPower(
                q6.reference(U_, sigma, theta2, alpha).J / sigma**2,
                q6.reference(U_, sigma, theta2, alpha).power,
            ),
        ),
        Mistake(
            "looks like chi2 with N degrees of freedom: T1 estimates one gain, so N - 1",
            lambda U_, sigma, theta2, alpha: _threshold_and_power(
                U_, sigma, theta2, alpha, np.shape(U_)[0]
            ),
        ),
        Mistake(
            "looks two-sided (alpha/2): the test alarms in the upper tail only",
            lambda U_, sigma, theta2, alpha: _threshold_and_power(
                U_, sigma, theta2, alpha / 2, np.shape(U_)[0] - 1
            ),
        ),
    ],
)
def q6(U_, sigma, theta2, alpha):
    n = np.shape(U_)[0]
    J = chi2.residual_threshold(n - 1, alpha, sigma=sigma)
    theta = [1.0, theta2, 1.0]
    power = dg.prediction_error_power(U_, NOMINAL, [0], theta, sigma=sigma, alpha=alpha)
    return ThresholdAndPower(J, power)


def _threshold_and_power(U_, sigma, theta2, alpha, dof):
    """(J, power) of q6 with other degrees of freedom or level (the mistakes)."""
    U_ = np.asarray(U_, dtype=float)
    J = float(sigma**2 * stats.chi2.isf(alpha, dof))
    d = (theta2 - 1.0) * U_[:, 1]
    d_perp = d - U_[:, 0] * (U_[:, 0] @ d) / (U_[:, 0] @ U_[:, 0])
    return (J, float(stats.ncx2.sf(J / sigma**2, dof, (d_perp @ d_perp) / sigma**2)))


q6.case(U, SIGMA, 1.15, 0.01, label="the notebook's signals, theta2 = 1.15, alpha = 0.01")
### BEGIN HIDDEN TESTS
q6.case(U, 0.1, 0.9, 0.05, hidden=True)
q6.case(U_60, 0.25, 1.2, 0.01, hidden=True)
### END HIDDEN TESTS


def _all_free(U_, y):
    """The sum of squared residuals with all three gains estimated."""
    U_, y = np.asarray(U_, dtype=float), np.asarray(y, dtype=float)
    r = y - U_ @ np.linalg.lstsq(U_, y, rcond=None)[0]
    return float(r @ r)


def _three_statistics(d):
    return dg.linear_test_statistics(d["y"], d["U"], NOMINAL, [(0,), (1,), (2,)])[0]


def _diagnosis(statistics, n, sigma, alpha):
    alarms = statistics > chi2.residual_threshold(n - 1, alpha, sigma=sigma)
    return list(dg.diagnoses(dg.DecisionStructure(LECTURE, modes=MODES), alarms))


def _conclusion(diagnosis):
    """The option of q8b that a diagnosis supports (each option's meaning is in its question)."""
    if len(diagnosis) == len(MODES):
        return "no fault detected"
    if not diagnosis:
        # every test alarms: every mode is ruled out, none of the single faults explains it
        return "no single fault fits"
    if len(diagnosis) == 1:
        return diagnosis[0]
    return "several faults fit"


@CHECKS.choice(
    "q5b",
    var="bias_decoupled",
    options=["yes", "no"],
    points=1,
    hint='Answer "yes" or "no".',
)
def q5b():
    return "yes"


@CHECKS.function(
    "q7_practice",
    func="three_statistics",
    forbid=[
        "course.diagnosis.prediction_error",
        "course.diagnosis.least_squares_residual",
        "course.diagnosis.prediction_error_test",
        "course.diagnosis.linear_test_statistics",
    ],
    points=1,
    rtol=1e-6,
    atol=1e-9,
    hint="The three test quantities of q7: T_k leaves theta_k free and fixes the other two "
    "gains at 1. Return them in the order T1, T2, T3.",
    mistakes=[
        Mistake(
            "looks divided by sigma^2: T_k is the plain sum of squared residuals",
            lambda U_, y: _three_statistics({"y": y, "U": U_}) / SIGMA**2,
        ),
        Mistake(
            "looks like a mean of squared residuals: T_k is their sum",
            lambda U_, y: _three_statistics({"y": y, "U": U_}) / np.shape(U_)[0],
        ),
        Mistake(
            "no gain looks estimated (all three fixed at 1): T_k leaves theta_k free",
            lambda U_, y: np.full(3, float(np.sum((np.asarray(y) - np.sum(U_, axis=1)) ** 2))),
        ),
        Mistake(
            "all three gains look estimated at once: T_k leaves only theta_k free and fixes "
            "the other two at 1",
            lambda U_, y: np.full(3, _all_free(U_, y)),
        ),
    ],
)
def q7_practice(U_, y):
    return _three_statistics({"y": y, "U": U_})


@CHECKS.function(
    "q8_practice",
    func="single_fault_diagnosis",
    forbid=[
        "course.diagnosis.diagnoses",
        "course.diagnosis.DecisionStructure",
        "course.diagnosis.diagnosis_matrix",
    ],
    points=1,
    hint="Each test alarms when T_k exceeds sigma^2 times the upper alpha quantile of the chi2 law "
    "of T_k / sigma^2: how many degrees of freedom does T_k have when one gain is estimated? "
    "Then your single_fault_diagnoses of q1 with the lecture structure LECTURE.",
    mistakes=[
        Mistake(
            "the alarms look like a threshold with chi2(N) or at alpha/2: one test sees this "
            "small fault only just, so the threshold must be exactly sigma^2 chi2_alpha(N - 1)",
            lambda U_, y, sigma, alpha: _diagnosis(
                _three_statistics({"y": y, "U": U_}), np.shape(U_)[0] + 1, sigma, alpha
            ),
        ),
    ],
)
def q8_practice(U_, y, sigma, alpha):
    return _diagnosis(_three_statistics({"y": y, "U": U_}), np.shape(U_)[0], sigma, alpha)


def _record_case(seed):
    d = data.record(np.random.default_rng(seed))
    return d["U"], d["y"], d["sigma"], d["alpha"]


q7_practice.case(U, Y_NEAR, label="the notebook's public record y_near")
q8_practice.case(
    U, Y_NEAR, SIGMA, 0.01, label="the notebook's public record, sigma 0.2, alpha 0.01"
)
### BEGIN HIDDEN TESTS
for _seed in (20, 22, 28, 29):  # records of data.record in F1, NF, F3 and none of them
    q7_practice.case(*_record_case(_seed)[:2], hidden=True)
    q8_practice.case(*_record_case(_seed), hidden=True)
# a small F3 (theta3 = 1.08) that T1 sees only just: chi2(N) or alpha/2 change the diagnosis
_Y_NEAR3 = U @ np.array([1.0, 1.0, 1.08]) + SIGMA * np.random.default_rng(143).standard_normal(N)
q8_practice.case(U, _Y_NEAR3, SIGMA, 0.01, hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q7",
    forbid=[
        "course.diagnosis.prediction_error",
        "course.diagnosis.least_squares_residual",
        "course.diagnosis.prediction_error_test",
        "course.diagnosis.linear_test_statistics",
    ],
    var="T_mine",
    points=2,
    data="record",
    properties="statistics_properties",
    rtol=1e-6,
    atol=1e-9,
    hint="T_k leaves theta_k free and fixes the other two at 1: apply your q3/q4 idea to each test. "
    "Return the three numbers in the order T1, T2, T3.",
)
def q7(d):
    return _three_statistics(d)


@CHECKS.value(
    "q8a",
    var="J_mine",
    points=1,
    data="record",
    properties="threshold_properties",
    rtol=1e-6,
    atol=1e-12,
    hint="The threshold on T_k for false-alarm rate mine['alpha']: sigma^2 times the upper alpha "
    "quantile of the chi2 law of T_k / sigma^2, with your sigma. How many degrees of freedom?",
    mistakes=[
        Mistake(
            "looks like chi2 with N degrees of freedom: T_k estimates one gain, so N - 1",
            lambda d: float(chi2.residual_threshold(d["y"].size, d["alpha"], sigma=d["sigma"])),
        ),
        Mistake(
            "looks two-sided (alpha/2): the test alarms in the upper tail only",
            lambda d: float(
                chi2.residual_threshold(d["y"].size - 1, d["alpha"] / 2, sigma=d["sigma"])
            ),
        ),
        Mistake(
            "looks like the quantile of chi2(N - 1) itself: T_k / sigma^2 is chi2, so the "
            "threshold on T_k is sigma^2 times that quantile",
            lambda d: float(chi2.residual_threshold(d["y"].size - 1, d["alpha"])),
        ),
        Mistake(
            "looks scaled by sigma, not sigma^2: T_k / sigma^2 is chi2, so J = sigma^2 times "
            "the quantile",
            lambda d: (
                float(d["sigma"]) * float(chi2.residual_threshold(d["y"].size - 1, d["alpha"]))
            ),
        ),
    ],
)
def q8a(d):
    return float(chi2.residual_threshold(d["y"].size - 1, d["alpha"], sigma=d["sigma"]))


@CHECKS.value(
    "q8",
    forbid=[
        "course.diagnosis.diagnoses",
        "course.diagnosis.DecisionStructure",
        "course.diagnosis.diagnosis_matrix",
    ],
    var="diagnosis_mine",
    points=1,
    data="record",
    properties="diagnosis_properties",
    hint="Each test alarms when T_k > J_mine; then apply your single_fault_diagnoses to the "
    "lecture structure LECTURE.",
    # shown only when the answer differs from the student's own diagnosis (the right answer is
    # compared first): for some records the two diagnoses agree, and then it is right
    mistakes=[
        Mistake(
            "this is the practice record's diagnosis: apply the alarms of YOUR record "
            "(T_mine > J_mine)",
            lambda d: q8_practice.reference(U, Y_NEAR, SIGMA, 0.01),
        ),
    ],
)
def q8(d):
    return _diagnosis(_three_statistics(d), d["y"].size, d["sigma"], d["alpha"])


@CHECKS.choice(
    "q8b",
    var="mode_mine",
    options=Q8B_OPTIONS,
    points=1,
    data="record",
    hint="Answer with one of the options (upper/lower case and surrounding spaces do not "
    'matter): a single mode when the diagnosis isolates it, "no fault detected" when nothing '
    'alarms, "several faults fit" when two or more fault modes remain, "no single fault fits" '
    "when the diagnosis is empty.",
)
def q8b(d):
    return _conclusion(_diagnosis(_three_statistics(d), d["y"].size, d["sigma"], d["alpha"]))


@CHECKS.function(
    "q9",
    func="detection_rate",
    points=2,
    timeout=30,
    atol=0.1 / 20000,  # the same count of detections: a fraction k / n_runs, exactly
    rtol=0.0,
    hint=(
        "The power is a rate of detections: for every simulated record, T1 (theta1 free, as in "
        "q4) above the threshold of q6 at this alpha and sigma; return the fraction of records.",
        "The grader repeats your draws, so draw them as the question says: "
        "rng = np.random.default_rng(seed) and ONE call rng.standard_normal((n_runs, N)), row "
        "r the noise of record r.",
    ),
    mistakes=[
        Mistake(
            "this is the exact power (the formula of q6), not the simulated rate",
            lambda U_, theta, sigma, alpha, n_runs, seed: dg.prediction_error_power(
                U_, NOMINAL, [0], theta, sigma=sigma, alpha=alpha
            ),
        ),
        Mistake(
            "returns alpha: the promised false-alarm rate, not the simulated rate",
            lambda U_, theta, sigma, alpha, n_runs, seed: float(alpha),
        ),
        Mistake(
            "the rate of the right statistic, but the noise drawn in another order (records in "
            "columns?): the recipe draws ONE rng.standard_normal((n_runs, N)), row r for record r",
            lambda U_, theta, sigma, alpha, n_runs, seed: _detection_rate(
                U_, theta, sigma, alpha, n_runs, seed, records_in_columns=True
            ),
        ),
        Mistake(
            "the threshold looks like chi2 with N degrees of freedom: T1 estimates one gain, "
            "so N - 1",
            lambda U_, theta, sigma, alpha, n_runs, seed: _detection_rate(
                U_, theta, sigma, alpha, n_runs, seed, dof=np.shape(U_)[0]
            ),
        ),
    ],
)
def q9(U_, theta, sigma, alpha, n_runs, seed):
    # The simulation the question prescribes, run with the case's seed: a correct answer counts
    # exactly the same detections (any vectorisation), while the exact power (the formula, not
    # a simulation) or another random sample differs from it by a Monte Carlo error.
    return _detection_rate(U_, theta, sigma, alpha, n_runs, seed)


def _detection_rate(U_, theta, sigma, alpha, n_runs, seed, records_in_columns=False, dof=None):
    """q9's simulation; ``records_in_columns`` draws the noise (N, n_runs), ``dof`` another
    threshold's degrees of freedom (the declared mistakes)."""
    U_ = np.asarray(U_, dtype=float)
    rng = np.random.default_rng(seed)
    shape = (U_.shape[0], n_runs) if records_in_columns else (n_runs, U_.shape[0])
    noise = rng.standard_normal(shape)
    Y = U_ @ np.asarray(theta, dtype=float) + sigma * (noise.T if records_in_columns else noise)
    t1 = _t1_many(U_, Y)
    dof = U_.shape[0] - 1 if dof is None else dof
    return float(np.mean(t1 > chi2.residual_threshold(dof, alpha, sigma=sigma)))


def _t1_many(U_, Y):
    """T1 of every row of Y (theta1 free, theta2 = theta3 = 1)."""
    target = Y - U_[:, 1] - U_[:, 2]
    u = U_[:, 0]
    R = target - np.outer(target @ u, u) / (u @ u)
    return np.sum(R**2, axis=1)


q9.case(U, np.array([1.0, 1.15, 1.0]), SIGMA, 0.01, 20000, 2024, label="F2 of size 0.15")
q9.case(U, np.array([1.0, 1.0, 1.0]), SIGMA, 0.05, 4000, 8, label="no fault, alpha = 0.05")
q9.case(U, np.array([1.0, 1.0, 1.0]), SIGMA, 0.05, 20000, 7, hidden=True)
q9.case(U, np.array([1.8, 1.0, 1.0]), SIGMA, 0.05, 20000, 11, hidden=True)
q9.case(U, np.array([1.0, 1.0, 1.1]), SIGMA, 0.01, 20000, 13, hidden=True)
# Other record lengths: a detection_rate that uses the notebook's N instead of U.shape[0]
# fails here.
q9.case(U[:30], np.array([1.0, 1.2, 1.0]), SIGMA, 0.05, 20000, 17, hidden=True)
q9.case(U_60, np.array([1.0, 1.0, 1.0]), SIGMA, 0.05, 20000, 19, hidden=True)
