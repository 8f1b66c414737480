"""Per-student data of assignment 04_ekf_residuals (PUBLIC: released to students).

Only data generators and harmless property checks live here; the references are in checks.py,
which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own record.
"""

import numpy as np


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
