"""Per-student data of assignment 02_test_quantities (PUBLIC: released to students).

Only the data generator and harmless property checks live here; the references are in
checks.py, which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own record.
"""

import numpy as np

MODES = ("NF", "F1", "F2", "F3")


def record(rng):
    """One record of the three-gain model y = th1 u1 + th2 u2 + th3 u3 + v, in an unknown mode."""
    N = 40
    t = np.arange(N)
    u1 = 1.0 + 0.5 * np.sin(2 * np.pi * t / 20 + rng.uniform(0, 2 * np.pi))
    u2 = np.cos(2 * np.pi * t / 13 + rng.uniform(0, 2 * np.pi))
    period = int(rng.choice([6, 8, 10]))
    u3 = np.where((t // period) % 2 == 0, 1.0, -1.0)
    U = np.round(np.column_stack([u1, u2, u3]), 6)
    theta = np.ones(3)
    mode = int(rng.integers(0, 4))
    if mode > 0:
        theta[mode - 1] += rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 0.5)
    sigma = float(rng.choice([0.08, 0.1, 0.12]))
    alpha = float(rng.choice([0.01, 0.05]))
    y = U @ theta + sigma * rng.standard_normal(N)
    return {"U": U, "y": np.round(y, 4), "sigma": sigma, "alpha": alpha}


def statistics_properties(d, value):
    """Public sanity checks of the three test quantities (they do not reveal them)."""
    v = np.asarray(value, dtype=float)
    return [
        ("three numbers, one per test", v.shape == (3,)),
        (
            "test quantities are sums of squares: non-negative",
            bool(v.shape == (3,) and np.all(v >= 0)),
        ),
    ]


def threshold_properties(d, value):
    """Public sanity checks of a threshold on T (they do not reveal it)."""
    ok = np.ndim(value) == 0 and np.isfinite(float(value)) and float(value) > 0
    return [("a positive number", bool(ok))]


def diagnosis_properties(d, value):
    """Public sanity checks of a diagnosis (a list of mode names)."""
    ok = isinstance(value, (list, tuple)) and all(isinstance(m, str) and m in MODES for m in value)
    ordered = ok and list(value) == [m for m in MODES if m in value]
    return [
        ("a list of mode names among NF, F1, F2, F3", bool(ok)),
        ("in the order NF, F1, F2, F3", bool(ordered)),
    ]
