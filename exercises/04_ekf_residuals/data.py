"""Per-student data of assignment 04_ekf_residuals (PUBLIC: released to students).

Only data generators and harmless property checks live here; the references are in checks.py,
which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own record.
"""

import numpy as np
from scipy import stats


def record(rng):
    """The lecture's first-order system with a drifting beta and a sensor fault at an unknown time.

    x(t+1) = x(t) - Ts beta(t) x(t) + Ts u(t) + w(t),  y(t) = x(t) + f(t) + e(t),
    with beta drifting linearly and f a step of unknown size and sign.
    """
    Ts, q_x, r, N = 0.1, 1e-4, 2.5e-3, 200
    t = np.arange(N)
    u = np.where((t // 40) % 2 == 0, 0.5, 1.5)
    beta = 0.8 + rng.uniform(0.3, 0.6) * t / N
    t_fault = int(rng.integers(100, 161))
    size = rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 0.4)
    w = np.sqrt(q_x) * rng.standard_normal(N)
    e = np.sqrt(r) * rng.standard_normal(N)
    x = np.empty(N)
    x[0] = 0.5
    for k in range(N - 1):
        x[k + 1] = x[k] - Ts * beta[k] * x[k] + Ts * u[k] + w[k]
    y = x + np.where(t >= t_fault, size, 0.0) + e
    return {
        "Ts": Ts,
        "q_x": q_x,
        "r": r,
        "q_beta": 1e-4,
        "u": u,
        "y": y,
        "window": int(rng.choice([8, 10, 12])),
        "alpha": float(rng.choice([0.001, 0.002])),
    }


def _alarm_ends(y, u, Ts, q_beta, q_x, r, window, alpha):
    """Whether the windowed NIS of the beta-drift EKF (state (beta, x), prior
    N((1, 0.5), diag(0.25, 0.01))) is above chi2.isf(alpha, window) for the window that ends at
    each sample t (False for the first window - 1 samples): the design check of :func:`drift`
    (a compact copy of what the course's EKF computes)."""
    z, P = np.array([1.0, 0.5]), np.diag([0.25, 0.01])
    Q = np.diag([q_beta, q_x])
    nis = np.empty(len(y))
    for t in range(len(y)):
        S = P[1, 1] + r
        K = P[:, 1] / S
        innovation = y[t] - z[1]
        nis[t] = innovation**2 / S
        z = z + K * innovation
        P = P - np.outer(K, P[1, :])
        F = np.array([[1.0, 0.0], [-Ts * z[1], 1.0 - Ts * z[0]]])
        z = np.array([z[0], z[1] - Ts * z[0] * z[1] + Ts * u[t]])
        P = F @ P @ F.T + Q
    sums = np.convolve(nis, np.ones(window))[window - 1 : len(y)]  # sums[k] ends at k + window - 1
    return np.r_[np.zeros(window - 1, dtype=bool), sums > stats.chi2.isf(alpha, window)]


def _windowed_alarms(y, u, Ts, q_beta, q_x, r, window, alpha, before):
    """How many windows ending before ``before`` :func:`_alarm_ends` puts above the threshold."""
    return int(np.sum(_alarm_ends(y, u, Ts, q_beta, q_x, r, window, alpha)[:before]))


def drift(rng):
    """A record of the lecture's system for q7: false alarms before a sensor fault, with one of
    two causes.

    Most records (about 70 %): beta drifts from 0.8 by 0.7 to 1.0 over 200 samples, so the
    filter that takes beta constant alarms well before the fault and the random-walk filter
    stays quiet. The others: beta stays constant but the sensor is 3 to 4 times noisier than
    the r = 2.5e-3 both filters assume, so both alarm. The design is checked: at least five
    false alarms where a filter should alarm and none where it should not (one would make
    "both filters alarm", q7_why's "noise", true of a "model" record); and the window that
    ends at the fault alarms in at least one filter, so counting one window too many never
    gives the right pair of counts.
    """
    Ts, q_x, r, N, window, alpha = 0.1, 1e-4, 2.5e-3, 200, 10, 0.001
    t = np.arange(N)
    u = np.where((t // 40) % 2 == 0, 0.5, 1.5)
    while True:  # a round or two at most
        noisy = bool(rng.random() < 0.3)
        beta = 0.8 + (0.0 if noisy else rng.uniform(0.7, 1.0)) * t / N
        r_true = r * (rng.uniform(3.0, 4.0) if noisy else 1.0)
        t_fault = int(rng.integers(140, 171))
        size = rng.choice([-1.0, 1.0]) * rng.uniform(0.2, 0.3)
        w = np.sqrt(q_x) * rng.standard_normal(N)
        e = np.sqrt(r_true) * rng.standard_normal(N)
        x = np.empty(N)
        x[0] = 0.5
        for k in range(N - 1):
            x[k + 1] = x[k] - Ts * beta[k] * x[k] + Ts * u[k] + w[k]
        y = np.round(x + np.where(t >= t_fault, size, 0.0) + e, 5)
        alarms = [_alarm_ends(y, u, Ts, q_beta, q_x, r, window, alpha) for q_beta in (0.0, 1e-4)]
        constant, random_walk = (int(np.sum(a[:t_fault])) for a in alarms)
        at_fault = any(a[t_fault] for a in alarms)
        if at_fault and constant >= 5 and (random_walk >= 5 if noisy else random_walk == 0):
            return {
                "Ts": Ts,
                "q_x": q_x,
                "r": r,
                "u": u,
                "y": y,
                "t_fault": t_fault,
                "window": window,
                "alpha": alpha,
            }


def drift_count_properties(d, value):
    """Public sanity checks of ``false_alarms = (count_constant, count_random_walk)``."""
    most = d["t_fault"] - d["window"] + 1  # windows that end before the fault
    try:
        counts = [int(c) for c in value]
        ok = len(counts) == 2 and all(float(c) == int(c) for c in value)
    except (TypeError, ValueError):
        return [("a pair of counts (count_constant, count_random_walk)", False)]
    return [
        ("a pair of integer counts", ok),
        (
            f"each between 0 and {most} (the windows that end before the fault)",
            ok and all(0 <= c <= most for c in counts),
        ),
    ]


def record_alarm_properties(d, value):
    """Public sanity checks of ``alarm = (threshold, first_alarm)`` (they do not reveal it)."""
    N, L = len(d["y"]), d["window"]
    try:
        threshold, first = value
        ok_thr = np.ndim(threshold) == 0 and bool(np.isfinite(float(threshold)))
        ok_thr = ok_thr and float(threshold) > 0
        ok_first = np.ndim(first) == 0 and float(first) == int(first) and L - 1 <= int(first) < N
    except (TypeError, ValueError):
        return [("a pair (threshold, first_alarm)", False)]
    return [
        ("a positive, finite threshold", bool(ok_thr)),
        (f"first_alarm: an integer sample index between {L - 1} and {N - 1}", bool(ok_first)),
    ]
