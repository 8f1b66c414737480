"""Checks of assignment 04_ekf_residuals (INSTRUCTORS ONLY: never released).

Each decorated function is the trusted reference the grader runs; cases with ``hidden=True``
are sent to the student's function only at grading time.
"""

from collections import namedtuple

import numpy as np
from scipy import stats

from course import diagnosis as dg
from course import filters as kf
from course import nis
from course.grading.authoring.checks import Band, Checks, Mistake

from . import data

# Results with several parts are named tuples: feedback names the part that is wrong
# (``critical_value``, not ``item [1]``). A student's plain tuple or list in the same order
# is just as right (the grader compares item by item).
SteadyState = namedtuple("SteadyState", "P K")
Alarm = namedtuple("Alarm", "threshold first_alarm")
FalseAlarms = namedtuple("FalseAlarms", "count_constant count_random_walk")
RLSUpdate = namedtuple("RLSUpdate", "theta_new P_new")

# The public practice record of q7_practice: the notebook's context cell builds the same one
# with the same seed (4062: a threshold with L - 1 degrees of freedom counts 19 false alarms
# instead of 14). Each student's q7 record comes from data.drift.
TS, Q_X, R = 0.1, 1e-4, 2.5e-3
N7, T_FAULT7 = 200, 150
_t7 = np.arange(N7)
U7 = np.where((_t7 // 40) % 2 == 0, 0.5, 1.5)
BETA7 = 0.8 + 0.6 * _t7 / N7
_, Y7 = dg.simulate_beta_system(
    BETA7,
    U7,
    np.random.default_rng(4062),
    Ts=TS,
    q_x=Q_X,
    r=R,
    x0=0.5,
    fault=np.where(_t7 >= T_FAULT7, 0.2, 0.0),
)
PRACTICE7 = {
    "Ts": TS,
    "q_x": Q_X,
    "r": R,
    "u": U7,
    "y": Y7,
    "t_fault": T_FAULT7,
    "window": 10,
    "alpha": 0.001,
}

# The public practice record of q5_practice (built the same way in the notebook's context
# cell): a smaller sensor offset (0.2) at t = 120, so the windowed NIS crosses the threshold
# gradually and a threshold with L - 1 degrees of freedom, or the window's first sample
# instead of its last, gives another first alarm (121 is right; 120 and 112 are not).
T_FAULT_PRACTICE = 120
_, Y_PRACTICE = dg.simulate_beta_system(
    BETA7,
    U7,
    np.random.default_rng(126),
    Ts=TS,
    q_x=Q_X,
    r=R,
    x0=0.5,
    fault=np.where(_t7 >= T_FAULT_PRACTICE, 0.2, 0.0),
)

# Records for the function questions (scalar model x(t+1) = a x(t) + w, y = x + v).
_rng = np.random.default_rng(20240604)


def _scalar_record(a, q, r, m0, p0, N, rng):
    x = m0 + np.sqrt(p0) * rng.standard_normal()
    y = np.empty(N)
    for k in range(N):
        y[k] = x + np.sqrt(r) * rng.standard_normal()
        x = a * x + np.sqrt(q) * rng.standard_normal()
    return y


Y_A = _scalar_record(0.9, 0.1, 1.0, 0.0, 1.0, 30, _rng)
Y_B = _scalar_record(1.0, 0.01, 0.5, 2.0, 4.0, 50, _rng)
Y_C = _scalar_record(-0.5, 2.0, 0.1, -1.0, 0.2, 40, _rng)


def _scalar_filter(y, a, q, r, m0, p0):
    model = kf.LinearModel(F=[[a]], H=[[1.0]], Q=[[q]], R=[[r]], x0_mean=[m0], x0_cov=[[p0]])
    return kf.kalman_filter(model, np.asarray(y, dtype=float))


CHECKS = Checks(
    "04_ekf_residuals",
    title="Assignment 4: Kalman filters and EKF residuals",
    data=data,
    timeout=10,
    preload=["course.filters", "scipy.stats"],
)

_NO_FILTERS = [  # every filter function of course.filters: "write the filter yourself"
    "course.filters.kalman_filter",
    "course.filters.extended_kalman_filter",
    "course.filters.kf_predict",
    "course.filters.kf_update",
    "course.filters.ekf_predict",
    "course.filters.ekf_update",
    "course.filters.recursive_least_squares",
    "course.filters.riccati",
    "course.filters.riccati_gains",
    "course.filters.steady_state",
]


# P(t|t-1) = P solves P = P - P^2/(P + r) + q, so P = (q + sqrt(q^2 + 4 q r))/2 and
# K = P/(P + r); the filtered variance is P(t|t) = (1 - K) P = P r/(P + r) (with q = r = 1:
# the golden ratio, 1/phi and 1/phi). The mistake is named field-wise: P(t|t) for P with K
# right, or K computed from P(t|t) as well.
def _p_filtered(q, r):
    P = (q + np.sqrt(q * q + 4.0 * q * r)) / 2.0
    return float(P * r / (P + r))


_Q1_MISTAKES = [
    Mistake(
        "looks like the FILTERED variance P(t|t): the question asks for the prediction "
        "variance P(t|t-1), the fixed point of update + predict",
        lambda q, r: (_p_filtered(q, r), _p_filtered(q, r) / (_p_filtered(q, r) + r)),
        hint="P(t|t-1) is the variance BEFORE the measurement update: one step of the "
        "recursion is update (P(t|t)) then predict (P(t|t) + q), and P(t|t-1) is its fixed "
        "point; K = P(t|t-1)/(P(t|t-1) + r).",
    ),
    Mistake(
        "P looks like the NEGATIVE root of P^2 - q P - q r = 0: a variance is positive",
        lambda q, r: _steady(q, r, (q - np.sqrt(q * q + 4.0 * q * r)) / 2.0),
    ),
    Mistake(
        "P looks like ONE step of the recursion from P = 1: the steady state is its fixed "
        "point (solve P^2 - q P - q r = 0, or iterate until P stops changing)",
        lambda q, r: _steady(q, r, 1.0 - 1.0 / (1.0 + r) + q),
    ),
    Mistake(
        "K looks like P / r: the gain divides by the innovation's variance P + r",
        lambda q, r: (_steady(q, r)[0], _steady(q, r)[0] / r),
    ),
]


def _steady(q, r, P=None):
    """(P, P / (P + r)) with the positive root, or another ``P`` (declared mistakes)."""
    P = (q + np.sqrt(q * q + 4.0 * q * r)) / 2.0 if P is None else P
    return (float(P), float(P / (P + r)))


@CHECKS.function(
    "q1",
    func="steady_state",
    forbid=[
        "course.filters.steady_state",
        "course.filters.riccati",
        "course.filters.riccati_gains",
    ],
    mistakes=_Q1_MISTAKES,
    points=1,
    rtol=1e-8,
    atol=1e-10,
    hint=[
        "P is the PREDICTION variance P(t|t-1), the fixed point of one full update + predict "
        "step of the recursion above; K follows from it. Return the pair in the order (P, K).",
        "With a = 1: P = P - P^2/(P + r) + q, that is P^2 - q P - q r = 0: take its positive "
        "root; then K = P/(P + r).",
    ],
)
def q1(q, r):
    model = kf.LinearModel(F=[[1.0]], H=[[1.0]], Q=[[q]], R=[[r]])
    ss = kf.steady_state(model)
    return SteadyState(float(ss.P_pred[0, 0]), float(ss.K[0, 0]))


q1.case(1.0, 1.0, label="q = r = 1")
### BEGIN HIDDEN TESTS
q1.case(0.2, 1.5, hidden=True)
q1.case(3.0, 0.5, hidden=True)
### END HIDDEN TESTS


_Q2_NORMALISE = (
    "Normalise each innovation by the square root of its own variance S_t = P(t|t-1) + r "
    "(not by S_t, not by P). Return one value per sample."
)


def _q2_wrong(y, a, q, r, m0, p0, scale=lambda S, P: np.sqrt(S), predict_first=False):
    """q2's filter with one slip: another scale of the innovation, or a prediction before the
    first update (the wrong answers the feedback names)."""
    x, P = float(m0), float(p0)
    z = np.empty(len(y))
    for t, y_t in enumerate(np.asarray(y, dtype=float)):
        if predict_first:
            x, P = a * x, a**2 * P + q
        S = P + r
        K = P / S
        z[t] = (y_t - x) / scale(S, P)
        x, P = x + K * (y_t - x), (1 - K) * P
        if not predict_first:
            x, P = a * x, a**2 * P + q
    return z


@CHECKS.function(
    "q2",
    func="normalized_innovations",
    points=3,
    rtol=1e-7,
    atol=1e-9,
    forbid=_NO_FILTERS,
    hint=[
        "Follow the equations above the question in their order: the first innovation uses "
        "x(0|-1) = m0 and P(0|-1) = p0, so update with y_t BEFORE predicting.",
        _Q2_NORMALISE,
        "Per sample: innovation and S, gain, measurement update of x and P, then the time "
        "update with a and q.",
    ],
    mistakes=[
        Mistake(
            "looks divided by S_t, not by its square root: a normalised innovation has variance 1",
            lambda y, a, q, r, m0, p0: _q2_wrong(y, a, q, r, m0, p0, scale=lambda S, P: S),
            hint=_Q2_NORMALISE,
        ),
        Mistake(
            "looks like the raw innovations: each must be divided by the square root of its "
            "variance S_t",
            lambda y, a, q, r, m0, p0: _q2_wrong(y, a, q, r, m0, p0, scale=lambda S, P: 1.0),
            hint=_Q2_NORMALISE,
        ),
        Mistake(
            "looks normalised by sqrt(P(t|t-1)) without r: the innovation's variance is "
            "S_t = P(t|t-1) + r",
            lambda y, a, q, r, m0, p0: _q2_wrong(y, a, q, r, m0, p0, scale=lambda S, P: np.sqrt(P)),
            hint=_Q2_NORMALISE,
        ),
        Mistake(
            "looks predicted before the first update: the first innovation uses x(0|-1) = m0 "
            "and P(0|-1) = p0 as given",
            lambda y, a, q, r, m0, p0: _q2_wrong(y, a, q, r, m0, p0, predict_first=True),
            hint="x(0|-1) = m0 and P(0|-1) = p0 are already the prediction for the first "
            "sample: per sample, update with y_t first, then predict the next.",
        ),
    ],
)
def q2(y, a, q, r, m0, p0):
    return _scalar_filter(y, a, q, r, m0, p0).normalized_innovations()[:, 0]


q2.case(Y_A, 0.9, 0.1, 1.0, 0.0, 1.0, label="a = 0.9, q = 0.1, r = 1, x0 ~ N(0, 1), 30 samples")
### BEGIN HIDDEN TESTS
q2.case(Y_B, 1.0, 0.01, 0.5, 2.0, 4.0, hidden=True)
q2.case(Y_C, -0.5, 2.0, 0.1, -1.0, 0.2, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q3",
    func="windowed_statistic",
    points=1,
    rtol=1e-9,
    atol=1e-12,
    forbid=["course.nis.windowed_sum", "course.nis.windowed_nis"],
    mistakes=[
        Mistake(
            "sums of z, not of z^2: the windowed statistic adds the SQUARED normalised innovations",
            lambda z, L: _window_sums(np.asarray(z, dtype=float), int(L)),
        ),
        Mistake(
            "window means (divided by L): the statistic is the SUM of the squares, chi2(L) "
            "under H0",
            lambda z, L: _window_sums(np.asarray(z, dtype=float) ** 2, int(L)) / int(L),
        ),
    ],
    hint=[
        "Squares, summed (not averaged), over full windows only: how many full windows of "
        "length L fit in N samples?",
        "T[k] = z[k]^2 + ... + z[k+L-1]^2 for k = 0, ..., N-L. np.cumsum or np.convolve do "
        "it without a Python loop.",
    ],
)
def q3(z, L):
    return _window_sums(np.asarray(z, dtype=float) ** 2, int(L))


def _window_sums(x, L):
    """The sums of ``x`` over the full windows of length ``L``."""
    return nis.windowed_sum(x, L)[L - 1 :]


q3.case(np.arange(6.0), 3, label="z = 0..5, L = 3")
### BEGIN HIDDEN TESTS
q3.case(np.linspace(-2.0, 2.0, 17), 1, hidden=True)
q3.case(np.sin(np.arange(40.0)), 10, hidden=True)
q3.case(np.array([0.5, -1.5, 2.0]), 3, hidden=True)
### END HIDDEN TESTS


@CHECKS.function(
    "q4",
    func="window_threshold",
    forbid=[
        "course.nis.windowed_nis_threshold",
    ],
    points=1,
    rtol=1e-6,
    atol=1e-8,
    mistakes=[
        Mistake(
            "L - 1 degrees of freedom: nothing is estimated from the window, so a sum of L "
            "squares keeps all L",
            lambda L, alpha: float(stats.chi2.isf(alpha, L - 1)) if L > 1 else np.nan,
        ),
        Mistake(
            "looks two-sided: only LARGE sums alarm, so all of alpha belongs in the upper tail",
            lambda L, alpha: float(stats.chi2.isf(alpha / 2, L)),
        ),
        Mistake(
            "a lower-tail quantile: the alarm is for large sums (isf, not ppf)",
            lambda L, alpha: float(stats.chi2.ppf(alpha, L)),
        ),
        Mistake(
            "looks like the threshold at alpha/100: alpha is already a probability "
            "(0.01 is 1 %), not a percentage",
            lambda L, alpha: float(stats.chi2.isf(alpha / 100, L)),
            hint="Pass alpha to chi2.isf as it is given: a probability between 0 and 1.",
        ),
        Mistake(
            "looks like the normal approximation L + z_alpha sqrt(2L): the sum of L squares is "
            "exactly chi2(L), whose upper quantile the question asks for",
            lambda L, alpha: float(L + stats.norm.isf(alpha) * np.sqrt(2.0 * L)),
        ),
        Mistake(
            "divided by L: the statistic is the SUM of the L squares (q3), not their mean",
            lambda L, alpha: float(stats.chi2.isf(alpha, L)) / L,
        ),
    ],
    hint=[
        "Which law does a sum of L squared independent N(0, 1) values follow under H0, "
        "and with how many degrees of freedom?",
        "The test alarms only for LARGE sums (one upper tail): the threshold is the upper "
        "alpha quantile, scipy.stats.chi2.isf.",
    ],
)
def q4(L, alpha):
    return float(stats.chi2.isf(alpha, L))


q4.case(10, 0.001, label="L = 10, alpha = 0.001")
### BEGIN HIDDEN TESTS
q4.case(5, 0.01, hidden=True)
q4.case(12, 0.002, hidden=True)
q4.case(3, 0.05, hidden=True)
### END HIDDEN TESTS


def _first_alarm(y, u, window, alpha, Ts=TS, q_beta=1e-4, q_x=Q_X, r=R, dof=None, shift=0):
    """(threshold, first alarm) of the windowed NIS of the beta-drift EKF; -1: no alarm.

    ``dof`` and ``shift`` make the declared mistakes (another dof, the window's first sample).
    """
    model = dg.beta_drift_model(Ts=Ts, q_beta=q_beta, q_x=q_x, r=r, x0_mean=(1.0, 0.5))
    T = nis.windowed_nis(kf.extended_kalman_filter(model, y, u), window)
    if dof is None:
        threshold = nis.windowed_nis_threshold(window, alpha)
    else:
        threshold = float(stats.chi2.isf(alpha, dof))
    with np.errstate(invalid="ignore"):
        alarms = np.flatnonzero(threshold < T)
    return Alarm(float(threshold), int(alarms[0]) + shift if alarms.size else -1)


def _alarm_mistakes(record):
    """The declared mistakes of q5_practice / q5; ``record(arg)`` gives the record dict."""

    def settings(rec):
        return rec["y"], rec["u"], rec["window"], rec["alpha"], rec["Ts"], rec["q_beta"]

    def wrong(arg, **change):
        rec = record(arg)
        return _first_alarm(*settings(rec), q_x=rec["q_x"], r=rec["r"], **change)

    return [
        Mistake(
            "threshold with L - 1 degrees of freedom: a window of L squared normalised "
            "innovations is chi2 with L degrees of freedom",
            lambda arg: wrong(arg, dof=record(arg)["window"] - 1),
        ),
        Mistake(
            "looks like the index of the window's FIRST sample: a window belongs to its last one",
            lambda arg: wrong(arg, shift=1 - record(arg)["window"]),
        ),
    ]


_HINT_ALARM = [
    "Three steps: the EKF's normalised innovations, their window sums, the first window "
    "above the threshold. Which sample does nis.windowed_nis(result, L)[t] belong to?",
    "A window of L squared normalised innovations (one output) is chi2 with L degrees of "
    "freedom under H0 -- not L - 1: nothing is estimated from the window. "
    "nis.windowed_nis(result, L)[t] is the window that ENDS at t (NaN before L - 1); report that t.",
    "threshold = stats.chi2.isf(alpha, L) (or nis.windowed_nis_threshold(L, alpha)); "
    "first_alarm = the first t with T[t] > threshold (np.flatnonzero), as an int.",
]


@CHECKS.function(
    "q5_practice",
    func="find_alarm",
    points=1,
    rtol=1e-6,
    atol=1e-8,
    hint=_HINT_ALARM,
    mistakes=_alarm_mistakes(lambda record: record),
)
def q5_practice(record):
    return _record_alarm(record)


def _record_alarm(d):
    return _first_alarm(
        d["y"], d["u"], d["window"], d["alpha"], d["Ts"], d["q_beta"], d["q_x"], d["r"]
    )


PRACTICE5 = {
    "Ts": TS,
    "q_x": Q_X,
    "r": R,
    "q_beta": 1e-4,
    "u": U7,
    "y": Y_PRACTICE,
    "window": 10,
    "alpha": 0.001,
}
q5_practice.case(PRACTICE5, label="the notebook's practice record")
### BEGIN HIDDEN TESTS
for _seed in (71, 72, 73):
    q5_practice.case(data.record(np.random.default_rng(_seed)), hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q5",
    var="alarm",
    points=2,
    rtol=1e-6,
    atol=1e-8,
    data="record",
    properties="record_alarm_properties",
    hint=["Do q5_practice first: the same code must pass its public check there.", *_HINT_ALARM],
    mistakes=_alarm_mistakes(lambda d: d),
)
def q5(d):
    return _record_alarm(d)


FalseAlarmRates = namedtuple("FalseAlarmRates", "rate_last rate_any")


def _false_alarm_rates(a, q, r, N, L, alpha, n_runs, seed, dof=None, raw=False):
    """(rate_last, rate_any) of the prescribed simulation: x0, W, V drawn in this order
    (``dof``: another threshold's degrees of freedom; ``raw``: window sums of the innovations
    not normalised; the declared mistakes)."""
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(n_runs)
    W = rng.standard_normal((N, n_runs))
    V = rng.standard_normal((N, n_runs))
    y = np.empty((n_runs, N, 1))
    for t in range(N):
        y[:, t, 0] = x + np.sqrt(r) * V[t]
        x = a * x + np.sqrt(q) * W[t]
    model = kf.LinearModel(F=[[a]], H=[[1.0]], Q=[[q]], R=[[r]], x0_mean=[0.0], x0_cov=[[1.0]])
    result = kf.kalman_filter(model, y)
    if raw:
        c = np.cumsum(np.asarray(result.innovations)[..., 0] ** 2, axis=1)
        c = np.concatenate([np.zeros((n_runs, 1)), c], axis=1)
        sums = c[:, L:] - c[:, :-L]
    else:
        sums = nis.windowed_nis(result, L)[:, L - 1 :]  # full windows only
    alarm = sums > stats.chi2.isf(alpha, L if dof is None else dof)
    return FalseAlarmRates(float(np.mean(alarm[:, -1])), float(np.mean(alarm.any(axis=1))))


@CHECKS.function(
    "q6",
    func="false_alarm_rates",
    points=2,
    timeout=30,
    rtol=0.0,
    atol=0.1 / 20000,  # the same counts of runs: fractions k / n_runs, exactly
    hint=[
        "Two rates over the runs: filter each run with the correct model, sum the squared "
        "normalised innovations over full windows of L, and compare each sum with "
        "chi2.isf(alpha, L); the grader repeats your draws, so a right simulation counts "
        "exactly the same alarms.",
        "rng = np.random.default_rng(seed); x0 = rng.standard_normal(n_runs); then "
        "W = rng.standard_normal((N, n_runs)) and V = rng.standard_normal((N, n_runs)); "
        "y_t = x_t + sqrt(r) V[t], x_(t+1) = a x_t + sqrt(q) W[t]. Filter with the correct "
        "model, window sums of the squared normalised innovations (full windows only), "
        "threshold chi2.isf(alpha, L). Return (fraction of runs whose LAST window exceeds it, "
        "fraction of runs with AT LEAST ONE window above it).",
    ],
    mistakes=[
        Mistake(
            "rate_last is alpha itself: that is what the test promises for one window, not what "
            "your simulation measured",
            lambda a, q, r, N, L, alpha, n_runs, seed: (float(alpha), Band(0.0, 1.0)),
        ),
        Mistake(
            "rate_any looks like 1 - (1 - alpha)^(number of windows): that holds for independent "
            "windows, but overlapping windows share innovations",
            lambda a, q, r, N, L, alpha, n_runs, seed: (
                Band(0.0, 1.0),
                float(1.0 - (1.0 - alpha) ** (N - L + 1)),
            ),
        ),
        Mistake(
            "the threshold looks like chi2 with L - 1 degrees of freedom: a window sums L "
            "squared normalised innovations, chi2(L)",
            lambda a, q, r, N, L, alpha, n_runs, seed: _false_alarm_rates(
                a, q, r, int(N), int(L), alpha, int(n_runs), seed, dof=int(L) - 1
            ),
        ),
        Mistake(
            "the innovations look not normalised: each is divided by its standard deviation "
            "sqrt(S_t) before squaring",
            lambda a, q, r, N, L, alpha, n_runs, seed: _false_alarm_rates(
                a, q, r, int(N), int(L), alpha, int(n_runs), seed, raw=True
            ),
        ),
        Mistake(
            "these look like counts of runs: return the fractions of the n_runs runs",
            lambda a, q, r, N, L, alpha, n_runs, seed: tuple(
                float(v) * int(n_runs)
                for v in _false_alarm_rates(a, q, r, int(N), int(L), alpha, int(n_runs), seed)
            ),
        ),
    ],
)
def q6(a, q, r, N, L, alpha, n_runs, seed):
    # The simulation the question prescribes, run with the case's seed: a right answer counts
    # exactly the same alarms however it filters, while alpha (the last window's promised rate),
    # an independence formula for "any window", another random sample or a wrong threshold all
    # differ from it.
    return _false_alarm_rates(a, q, r, int(N), int(L), alpha, int(n_runs), seed)


q6.case(0.9, 0.1, 1.0, 40, 10, 0.05, 10000, 2024, label="a = 0.9, q = 0.1, r = 1, N = 40, L = 10")
### BEGIN HIDDEN TESTS
q6.case(1.0, 0.01, 0.5, 30, 5, 0.01, 20000, 7, hidden=True)
### END HIDDEN TESTS


def _false_alarms(d, q_betas=(0.0, 1e-4), dof=None, before=None):
    """(count_constant, count_random_walk) of the record ``d`` of data.drift; ``dof`` and
    ``before`` make the declared mistakes (another threshold, windows after the fault too)."""
    L, alpha = d["window"], d["alpha"]
    thr = nis.windowed_nis_threshold(L, alpha) if dof is None else stats.chi2.isf(alpha, dof)
    before = d["t_fault"] if before is None else before
    counts = []
    for q_beta in q_betas:
        model = dg.beta_drift_model(
            Ts=d["Ts"], q_beta=q_beta, q_x=d["q_x"], r=d["r"], x0_mean=(1.0, 0.5)
        )
        T = nis.windowed_nis(kf.extended_kalman_filter(model, d["y"], d["u"]), L)
        with np.errstate(invalid="ignore"):
            counts.append(int(np.sum(T[:before] > thr)))
    return FalseAlarms(*counts)


_HINT_COUNTS = [
    "Count alarms only BEFORE the fault (t < record['t_fault']): every one of them is false. "
    "The first L - 1 values of nis.windowed_nis are NaN (no full window yet).",
    "Run kf.extended_kalman_filter with q_beta=0.0 and with q_beta=1e-4 on the same "
    "(record['y'], record['u']); count the samples t < record['t_fault'] where "
    "nis.windowed_nis(result, record['window']) exceeds "
    "nis.windowed_nis_threshold(record['window'], record['alpha']). Return "
    "(count_constant, count_random_walk).",
]
_COUNT_MISTAKES = [
    Mistake(
        "windows after the fault look counted too: only those that end before it are false alarms",
        lambda d: _false_alarms(d, before=len(d["y"])),
    ),
    Mistake(
        "threshold with L - 1 degrees of freedom: a window of L squared normalised "
        "innovations is chi2 with L degrees of freedom",
        lambda d: _false_alarms(d, dof=d["window"] - 1),
    ),
    Mistake(
        "one window too many looks counted: the window that ends at t_fault holds the fault's "
        "first sample, so only those that end before t_fault are false alarms",
        lambda d: _false_alarms(d, before=d["t_fault"] + 1),
    ),
]


@CHECKS.function(
    "q7_practice",
    func="count_false_alarms",
    points=1,
    rtol=0,
    atol=0,
    hint=_HINT_COUNTS,
    mistakes=_COUNT_MISTAKES,
)
def q7_practice(record):
    return _false_alarms(record)


def _drift_case(seed):
    return data.drift(np.random.default_rng(seed))


q7_practice.case(PRACTICE7, label="the notebook's practice record")
### BEGIN HIDDEN TESTS
for _seed in (81, 85, 86, 89):
    q7_practice.case(_drift_case(_seed), hidden=True)
### END HIDDEN TESTS


@CHECKS.value(
    "q7",
    var="false_alarms",
    points=2,
    rtol=0,
    atol=0,
    data="drift",
    properties="drift_count_properties",
    hint=[
        "Do q7_practice first: the same function must pass its public check there.",
        *_HINT_COUNTS,
    ],
    mistakes=_COUNT_MISTAKES,
)
def q7(d):
    return _false_alarms(d)


@CHECKS.choice(
    "q7_why",
    var="false_alarm_cause",
    options=["model", "noise", "threshold", "fault"],
    points=1,
    data="drift",
    hint='Answer one of "model", "noise", "threshold" or "fault". Which of your two filters '
    "raises the alarms: one of them, or both?",
)
def q7_why(d):
    # data.drift makes one of two records: beta drifts (only the constant-beta filter alarms:
    # its model is wrong) or the sensor is noisier than the r both filters assume (both alarm).
    # The threshold and the windows (all before the fault) are the same for both filters.
    random_walk = data._windowed_alarms(
        d["y"], d["u"], d["Ts"], 1e-4, d["q_x"], d["r"], d["window"], d["alpha"], d["t_fault"]
    )
    return "noise" if random_walk > 0 else "model"


def _rls(theta, P, phi, y, r, p_sign=-1.0, divide=True, with_r=True, innovation=1.0):
    """One RLS step with a declared mistake (the sign of P's update, no division by S, S
    without r, the innovation's sign)."""
    theta, P, phi = (np.asarray(v, dtype=float) for v in (theta, P, phi))
    Pphi = P @ phi
    S = phi @ Pphi + (float(r) if with_r else 0.0)
    K = Pphi / S if divide else Pphi
    return (theta + innovation * K * (float(y) - phi @ theta), P + p_sign * np.outer(K, Pphi))


@CHECKS.function(
    "q8",
    func="rls_update",
    points=2,
    rtol=1e-9,
    atol=1e-12,
    forbid=_NO_FILTERS,
    mistakes=[
        Mistake(
            "P_new looks updated with a plus sign: a measurement REDUCES the uncertainty, "
            "P <- P - K phi^T P",
            lambda theta, P, phi, y, r: _rls(theta, P, phi, y, r, p_sign=1.0),
        ),
        Mistake(
            "the gain looks not divided by S: K = P phi / S with S = phi^T P phi + r",
            lambda theta, P, phi, y, r: _rls(theta, P, phi, y, r, divide=False),
        ),
        Mistake(
            "S looks computed without r: the innovation's variance is phi^T P phi + r, the "
            "measurement noise included",
            lambda theta, P, phi, y, r: _rls(theta, P, phi, y, r, with_r=False),
        ),
        Mistake(
            "P_new is the old covariance: the measurement update reduces it, P - K phi^T P",
            lambda theta, P, phi, y, r: _rls(theta, P, phi, y, r, p_sign=0.0),
        ),
        Mistake(
            "the innovation's sign looks flipped: theta + K (y - phi^T theta)",
            lambda theta, P, phi, y, r: _rls(theta, P, phi, y, r, innovation=-1.0),
        ),
    ],
    hint=[
        "RLS is the Kalman measurement update with H = phi^T and no time update (the "
        "parameter is constant): no F, no Q.",
        "S = phi^T P phi + r, K = P phi / S, theta <- theta + K (y - phi^T theta), "
        "P <- P - K phi^T P (or the Joseph form). Return (theta_new, P_new).",
    ],
)
def q8(theta, P, phi, y, r):
    x, Pn, _, _, _ = kf.kf_update(
        np.asarray(theta, float),
        np.asarray(P, float),
        np.array([float(y)]),
        np.asarray(phi, float)[None, :],
        np.array([[float(r)]]),
    )
    return RLSUpdate(x, Pn)


q8.case(
    np.array([0.0, 0.0]),
    np.eye(2),
    np.array([1.0, 2.0]),
    3.0,
    1.0,
    label="theta = 0, P = I, phi = (1, 2), y = 3, r = 1",
)
### BEGIN HIDDEN TESTS
q8.case(
    np.array([1.0, -1.0, 0.5]),
    np.diag([2.0, 1.0, 0.5]),
    np.array([0.3, -1.0, 2.0]),
    0.7,
    0.2,
    hidden=True,
)
q8.case(np.array([5.0]), np.array([[0.01]]), np.array([2.0]), 9.0, 4.0, hidden=True)
### END HIDDEN TESTS
