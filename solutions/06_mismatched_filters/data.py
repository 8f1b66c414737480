"""Per-student data of assignment 06_mismatched_filters (PUBLIC: released to students).

Only data generators and harmless property checks live here; the references are in checks.py,
which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own experiment.
"""

import numpy as np

from course import filters, mismatched

#: The model under test (M0) and the reduced filter (M1) of notebook 06.
M0 = filters.LinearModel(
    F=[[0.9, 1.0], [0.0, 0.98]],
    H=[[1.0, 0.0]],
    Q=np.diag([0.5, 0.02]),
    R=[[1.0]],
    x0_mean=[0.0, 1.0],
    x0_cov=np.diag([1.0, 0.2]),
    w_mean=[0.1, 0.0],
    v_mean=[0.3],
)
M1 = filters.LinearModel(
    F=[[0.95]],
    H=[[1.0]],
    Q=[[1.0]],
    R=[[1.2]],
    x0_mean=[0.5],
    x0_cov=[[2.0]],
    w_mean=[0.05],
    v_mean=[0.1],
)


def experiment(rng):
    """M = 30 records of N = 12 residuals of the reduced filter, and the null moments.

    The records come from M0 or from a model that differs from it; which one is for you to
    test. ``mean`` (N, 1), ``cov`` (N, 1, 1) and ``cross_cov`` (N, N, 1, 1) are the exact
    residual moments under the null pair (M0, M1).
    """
    N, M = 12, 30
    truth = M0
    if rng.random() < 0.5:
        drift = rng.uniform(1.6, 2.4)
        truth = filters.LinearModel(
            F=M0.F,
            H=M0.H,
            Q=M0.Q,
            R=M0.R,
            x0_mean=[0.0, drift],
            x0_cov=M0.x0_cov,
            w_mean=M0.w_mean,
            v_mean=M0.v_mean,
        )
    residuals = mismatched.simulate_records(truth, M1, M, N, rng)
    null = mismatched.residual_moments(M0, M1, N)
    j = int(rng.integers(2, 8))
    return {
        "residuals": residuals,
        "mean": np.array(null.mean),
        "cov": np.array(null.cov),
        "cross_cov": np.array(null.cross_cov),
        "j": j,
        "k": j + 1,
        "alpha": 0.05,
    }


def experiment_properties(d, value):
    """Public sanity checks of the two p-values (they do not reveal them)."""
    try:
        p = [float(v) for v in value]
    except (TypeError, ValueError):
        return [("a pair (p_mean, p_corr) of numbers", False)]
    return [
        ("a pair (p_mean, p_corr)", len(p) == 2),
        ("both p-values lie in [0, 1]", len(p) == 2 and all(0.0 <= v <= 1.0 for v in p)),
    ]
