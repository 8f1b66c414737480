"""Per-student data of assignment 07_testing_theory (PUBLIC: released to students).

Only data generators and harmless property checks live here; the references are in checks.py,
which is never released. ``rng`` is seeded from the student's ID by the course, so everyone
gets their own levelling line.
"""

import numpy as np
from scipy import stats


def _whitened_fit(A, y, sigma):
    """Whitened residuals, their hat-matrix diagonal and the residuals e of the weighted fit."""
    A_w, y_w = A / sigma[:, None], y / sigma
    Q, _ = np.linalg.qr(A_w)
    r = y_w - Q @ (Q.T @ y_w)
    return r, np.sum(Q * Q, axis=1), r * sigma


def _pair_statistic(A, y, sigma, k):
    """T_2 of the alternative "a bias in observations k and k + 1" (weighted fit)."""
    A_w, y_w = A / sigma[:, None], y / sigma
    Q, _ = np.linalg.qr(A_w)
    C_w = np.eye(len(y))[:, [k, k + 1]] / sigma[:, None]
    Qc, _ = np.linalg.qr(C_w - Q @ (Q.T @ C_w))
    r = y_w - Q @ (Q.T @ y_w)
    return float(np.sum((Qc.T @ r) ** 2))


def _clear_of(value, mistaken, rtol=1e-2):
    """``mistaken`` differs from ``value`` by more than ``rtol`` relative (10^4 tolerances)."""
    return abs(value - mistaken) > rtol * abs(value)


def levelling(rng):
    """A line of 14 levelled heights with individual precisions and one blunder.

    The blunder sits on a precise observation drawn anywhere on the line and is large enough
    that the overall model test detects it and the w-test identifies it; one imprecise
    observation gets a large but acceptable error, so the largest residual |e_i| points
    elsewhere (adapting by the largest |e| gives another line). ``pair`` is q6's
    two-observation alternative, two neighbours drawn apart from the blunder and from the
    imprecise observation: it says nothing of where the blunder is, so q7 has to detect and
    identify it. The pair's second observation has an error of two to three sigma of its own,
    so that T_2 of the pair clearly exceeds w² of its first observation alone. A line on which
    a mistake declared by q6 (the neighbouring pair on the other side, no weights, w² of the
    first observation, the overall model test's T) comes within 1 % of T_2 is redrawn.
    """
    m, alpha = 14, 0.05
    t = np.arange(m, dtype=float)
    A = np.column_stack([np.ones(m), t])
    critical = stats.chi2.isf(alpha, m - 2)
    while True:  # a few rounds at most: redraw until the design holds
        x_true = np.array([rng.uniform(10.0, 20.0), rng.uniform(-0.5, 0.5)])
        sigma = np.round(rng.uniform(0.5, 1.5, size=m), 3)
        k = int(rng.integers(0, m))  # the blunder, anywhere
        j = int(rng.choice([i for i in range(m) if i != k]))
        s = int(rng.choice([i for i in range(1, m - 1) if not {i, i + 1} & {k, j}]))
        sigma[k] = round(float(rng.uniform(0.35, 0.45)), 3)
        sigma[j] = round(float(rng.uniform(2.8, 3.2)), 3)
        noise = sigma * rng.standard_normal(m)
        noise[j] = rng.choice([-1.0, 1.0]) * rng.uniform(2.0, 2.4) * sigma[j]
        noise[k] = rng.choice([-1.0, 1.0]) * rng.uniform(6.0, 9.0) * sigma[k]
        # the pair's second observation gets an error of its own, so that the pair explains
        # clearly more than its first observation alone
        noise[s + 1] = rng.choice([-1.0, 1.0]) * rng.uniform(2.0, 3.0) * sigma[s + 1]
        y = np.round(A @ x_true + noise, 3)
        r, h, e = _whitened_fit(A, y, sigma)
        w = r / np.sqrt(1.0 - h)
        T_pair = _pair_statistic(A, y, sigma, s)
        design = (
            float(r @ r) > critical + 2.0  # detected, with a margin
            and T_pair - w[s] ** 2 > 2.0
            # every mistake q6 declares must miss its tolerance (rtol 1e-6) by far
            and _clear_of(T_pair, _pair_statistic(A, y, sigma, s - 1))
            and _clear_of(T_pair, _pair_statistic(A, y, np.ones(m), s))
            and _clear_of(T_pair, float(w[s] ** 2))
            and _clear_of(T_pair, float(r @ r))
            and int(np.argmax(np.abs(w))) == k  # identified by the w-test
            and np.sort(np.abs(w))[-1] - np.sort(np.abs(w))[-2] > 0.5  # without a near tie
            and int(np.argmax(np.abs(e))) != k  # ... but the largest |e| is elsewhere
        )
        if design:
            return {
                "t": t,
                "A": A,
                "y": y,
                "Qyy": np.diag(sigma**2),
                "alpha": alpha,
                "pair": [s, s + 1],
            }


def statistic_properties(d, value):
    """Public sanity checks of a test statistic (they do not reveal it)."""
    return [("a non-negative number", np.ndim(value) == 0 and float(value) >= 0.0)]


def dia_properties(d, value):
    """Public sanity checks of a DIA result (T, reject, identified, x_hat); they do not reveal it."""
    parts = value if isinstance(value, (tuple, list)) and len(value) == 4 else None
    if parts is None:
        return [("four parts (T, reject, identified, x_hat)", False)]
    T, reject, identified, x_hat = parts
    m = len(d["y"])
    return [
        ("T: a non-negative number", np.ndim(T) == 0 and float(T) >= 0.0),
        ("reject: True or False", isinstance(reject, (bool, np.bool_))),
        (
            "identified: an observation's index (or None if nothing is rejected)",
            identified is None
            or (isinstance(identified, (int, np.integer)) and 0 <= int(identified) < m),
        ),
        (
            "x_hat: two finite numbers (height at t = 0, slope)",
            np.shape(x_hat) == (2,) and bool(np.all(np.isfinite(np.asarray(x_hat, dtype=float)))),
        ),
    ]
