"""Per-student data of assignment 03_estimation_and_likelihood (PUBLIC: released to students).

Only the data generator and harmless property checks live here; the references are in
checks.py, which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own record.
"""

import numpy as np


def modes(rng):
    """A record of the three-gain model in an unknown mode, with priors for Bayes' rule."""
    N = 30
    t = np.arange(N)
    u1 = 1.0 + 0.5 * np.sin(2 * np.pi * t / 15 + rng.uniform(0, 2 * np.pi))
    u2 = 0.5 * u1 + np.cos(2 * np.pi * t / 11 + rng.uniform(0, 2 * np.pi))
    u3 = np.where((t // int(rng.choice([5, 6, 7]))) % 2 == 0, 1.0, -1.0)
    U = np.round(np.column_stack([u1, u2, u3]), 6)
    theta = np.ones(3)
    mode = int(rng.choice(4, p=[0.4, 0.2, 0.2, 0.2]))
    if mode > 0:
        theta[mode - 1] += rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.3)
    sigma = 0.15
    y = U @ theta + sigma * rng.standard_normal(N)
    return {
        "U": U,
        "y": np.round(y, 4),
        "sigma": sigma,
        "tau": 0.3,
        "priors": np.array([0.7, 0.1, 0.1, 0.1]),
    }


def posterior_properties(d, value):
    """Public sanity checks of a posterior vector (they do not reveal it)."""
    v = np.asarray(value, dtype=float)
    ok = v.shape == (4,)
    return [
        ("four probabilities, in the order NF, F1, F2, F3", ok),
        (
            "non-negative and summing to one",
            bool(ok and np.all(v >= 0) and abs(v.sum() - 1) < 1e-9),
        ),
    ]
