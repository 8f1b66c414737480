"""Per-student data of assignment 01_least_squares (PUBLIC: released to students).

Only data generators and harmless property checks live here; the references are in checks.py,
which is never released. ``rng`` is seeded from the student's ID by the course
(``course.grading.student_rng``), so everyone gets their own survey.
"""

import numpy as np
from scipy import stats


def _weighted_T_and_w(A, y, sigma):
    """(T, w, e): the overall model test statistic, the w-test statistics and the residuals of
    the weighted fit with Qyy = diag(sigma^2)."""
    A_w, y_w = A / sigma[:, None], y / sigma
    Q, _ = np.linalg.qr(A_w)
    r = y_w - Q @ (Q.T @ y_w)  # whitened residuals, e / sigma
    # w_i = (Qyy^-1 e)_i / sqrt((Qyy^-1 Qee Qyy^-1)_ii) = r_i / sqrt(1 - h_ii), h the hat matrix
    return float(r @ r), r / np.sqrt(1.0 - np.sum(Q * Q, axis=1)), r * sigma


def _unweighted_residuals(A, y):
    """The residuals of the fit that ignores Qyy (Qyy = I)."""
    Q, _ = np.linalg.qr(A)
    return y - Q @ (Q.T @ y)


def survey(rng):
    """A levelling survey along a line: 12 heights with individual precisions and ONE blunder.

    The blunder sits on a precise observation and one imprecise observation gets a large but
    acceptable error, so the largest residual |e_i| is NOT the blunder, nor is the largest
    |e_i / sigma_i| of a fit that ignores the weights: only the w-test, which weighs each
    residual of the weighted fit by its own standard deviation, finds it. The blunder's size puts the
    overall model test statistic T just above or just below its critical value (about half
    of the class on each side), so the verdict depends on each student's data and method:
    chi2 with m or m - 1 degrees of freedom, alpha / 2, or ignoring Qyy change it.
    """
    m, alpha = 12, 0.01
    t = np.arange(m, dtype=float)
    A = np.column_stack([np.ones(m), t])
    critical = stats.chi2.isf(alpha, m - 2)
    z = stats.norm.isf(alpha / 2)
    while True:  # a few rounds at most: redraw until the design holds
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
        noise[k] = 0.0
        # T is quadratic in the blunder b: T(b) = T_min + (b - b0)^2 c; aim it at a target
        # within 1.35 of the critical value (below chi2.isf(alpha, m - 1), the nearest wrong one)
        target = critical + rng.choice([-1.0, 1.0]) * rng.uniform(0.15, 1.35)
        y0 = A @ x_true + noise
        unit = np.eye(m)[k]
        s = np.round(sigma, 3)
        t0, tp, tm = (_weighted_T_and_w(A, y0 + b * unit, s)[0] for b in (0.0, 1.0, -1.0))
        c2, c1 = (tp + tm) / 2 - t0, (tp - tm) / 2
        disc = c1**2 - 4 * c2 * (t0 - target)
        if disc <= 0:
            continue
        b = (-c1 + rng.choice([-1.0, 1.0]) * np.sqrt(disc)) / (2 * c2)
        y = np.round(y0 + b * unit, 3)
        T, w, e = _weighted_T_and_w(A, y, s)
        design = (
            abs(T - critical) > 0.1  # rounding kept the side
            and int(np.argmax(np.abs(w))) == k
            and abs(w[k]) > z  # data snooping finds the blunder first
            and int(np.argmax(np.abs(e))) != k  # ... but the largest |e| is elsewhere
            # ... and so is the largest |e_i / sigma_i| of an UNWEIGHTED fit, a method that
            # finds the blunder on most surveys without being a w-test
            and int(np.argmax(np.abs(_unweighted_residuals(A, y)) / s)) != k
        )
        if design:
            return {"t": t, "A": A, "y": y, "Qyy": np.diag(s**2), "alpha": alpha}


def survey_T_properties(d, value):
    """Public sanity checks of T (they do not reveal it)."""
    return [("T is a non-negative number", np.ndim(value) == 0 and float(value) >= 0.0)]


def survey_index_properties(d, value):
    """Public sanity checks of the suspected index."""
    m = len(d["y"])
    ok = np.ndim(value) == 0 and float(value) == int(value) and 0 <= int(value) < m
    return [(f"an index between 0 and {m - 1}", bool(ok))]
