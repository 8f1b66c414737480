"""Per-student data of assignment 05_nis_wishart (PUBLIC: released to students).

Only data generators and harmless property checks live here; the references are in checks.py,
which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own record.
"""

import numpy as np


def record(rng):
    """K = 60 innovations of a two-output filter, with the filter's covariance S.

    The filter believes eps_k ~ N(0, S). Whether that is true in your record is for you to test:
    the truth may be S itself, a covariance with a correlation between the outputs that S
    ignores, or S at the wrong scale.
    """
    m, K = 2, 60
    a, b = rng.uniform(0.5, 2.0, size=2)
    c = rng.uniform(-0.4, 0.4) * np.sqrt(a * b)
    S = np.array([[a, c], [c, b]])
    kind = rng.choice(["correlation", "consistent", "scale"], p=[0.4, 0.3, 0.3])
    rho = rng.choice([-1.0, 1.0]) * rng.uniform(0.45, 0.7) if kind == "correlation" else 0.0
    scale = rng.uniform(1.35, 1.7) if kind == "scale" else 1.0
    mix = np.sqrt(scale) * np.linalg.cholesky(np.array([[1.0, rho], [rho, 1.0]]))
    z = rng.standard_normal((K, m)) @ mix.T
    eps = z @ np.linalg.cholesky(S).T
    return {"eps": eps, "S": S, "alpha": 0.05}


def record_properties(d, value):
    """Public sanity checks of the two p-values (they do not reveal them)."""
    try:
        p = [float(v) for v in value]
    except (TypeError, ValueError):
        return [("a pair (p_nis, p_matrix) of numbers", False)]
    return [
        ("a pair (p_nis, p_matrix)", len(p) == 2),
        ("both p-values lie in [0, 1]", len(p) == 2 and all(0.0 <= v <= 1.0 for v in p)),
    ]
