"""Per-student data of assignment 01_least_squares (PUBLIC: released to students).

Only data generators and harmless property checks live here; the references are in checks.py,
which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own survey.
"""

import numpy as np


def survey(rng):
    """A levelling survey along a line: 12 heights with individual precisions and ONE blunder.

    The blunder sits on a precise observation and one imprecise observation gets a large but
    acceptable error, so the largest residual |e_i| is NOT the blunder: only the w-test, which
    weighs each residual by its own standard deviation, finds it.
    """
    m = 12
    t = np.arange(m, dtype=float)
    A = np.column_stack([np.ones(m), t])
    x_true = np.array([rng.uniform(10.0, 20.0), rng.uniform(-0.5, 0.5)])
    sigma = rng.uniform(0.5, 1.5, size=m)
    # the blunder sits in the middle third, where even a precise observation keeps enough
    # redundancy for the w-test to see it (near the ends the line would follow it)
    k = int(rng.integers(m // 3, m - m // 3))
    j = int(rng.choice([i for i in range(1, m - 1) if i != k]))
    sigma[k] = rng.uniform(0.35, 0.45)
    sigma[j] = rng.uniform(2.8, 3.2)
    noise = sigma * rng.standard_normal(m)
    noise[j] = rng.choice([-1.0, 1.0]) * rng.uniform(2.0, 2.4) * sigma[j]
    noise[k] = rng.choice([-1.0, 1.0]) * rng.uniform(8.0, 10.0) * sigma[k]
    y = A @ x_true + noise
    return {
        "t": t,
        "A": A,
        "y": np.round(y, 3),
        "Qyy": np.diag(np.round(sigma, 3) ** 2),
        "alpha": 0.01,
    }


def survey_T_properties(d, value):
    """Public sanity checks of T (they do not reveal it)."""
    return [("T is a non-negative number", np.ndim(value) == 0 and float(value) >= 0.0)]


def survey_index_properties(d, value):
    """Public sanity checks of the suspected index."""
    m = len(d["y"])
    ok = np.ndim(value) == 0 and float(value) == int(value) and 0 <= int(value) < m
    return [(f"an index between 0 and {m - 1}", bool(ok))]
