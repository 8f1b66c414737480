"""High-precision reference for the Wishart extreme-eigenvalue laws (mpmath).

An independent implementation used to produce the reference values in
``test_nis.py``: Chiani's Pfaffian in his own monomial basis
``f_i(y) = y^(a-1+i) e^-y`` (``y = lambda/2``, ``a = (K - m + 1)/2``), whose
entries follow from the closed-form recursion (integration by parts)::

    J(p, q+1) = q J(p, q) - (hi^q e^-hi + lo^q e^-lo) gamma(p; lo, hi)
                + 2^(1-p-q) gamma(p+q; 2 lo, 2 hi),     J(p, p) = 0,

with ``gamma(p; lo, hi)`` the (unregularised) incomplete gamma integral, and
the Pfaffian by Parlett-Reid elimination in mpmath.  In this basis double
precision loses all digits at large K (and at large m), so :func:`prob_within`
runs with 80 significant digits (enough for the table's m <= 6) and
:func:`checked_probabilities` raises the precision until two evaluations agree
to 30 digits (m = 30, K = 1000 needs about 100 digits, K = 10^5 several hundred).
``python tests/nis_reference.py --write`` (needs ``mpmath``, seconds) writes the tables
``tests/reference/nis_extreme_eigenvalues.json`` and ``nis_eigenvalue_bands.json`` that
``test_nis.py`` reads, with their provenance.
"""

from __future__ import annotations


def _pfaffian(A):
    """Pfaffian by Parlett-Reid skew elimination with pivoting, in mpmath arithmetic."""
    import mpmath as mp

    A = [list(row) for row in A]
    n = len(A)
    if n % 2:
        return mp.mpf(0)
    pf = mp.mpf(1)
    for k in range(0, n - 1, 2):
        pivot = max(range(k + 1, n), key=lambda i: abs(A[i][k]))
        if pivot != k + 1:
            A[k + 1], A[pivot] = A[pivot], A[k + 1]
            for row in A:
                row[k + 1], row[pivot] = row[pivot], row[k + 1]
            pf = -pf
        head = A[k][k + 1]
        if head == 0:
            return mp.mpf(0)
        pf *= head
        tau = [A[k][j] / head for j in range(n)]
        col = [A[i][k + 1] for i in range(n)]
        for i in range(k + 2, n):
            row = A[i]
            for j in range(k + 2, n):
                row[j] += tau[i] * col[j] - col[i] * tau[j]
    return pf


def _skew(m, a, lo, hi):
    import mpmath as mp

    def edge(q):
        value = mp.mpf(0)
        if hi != mp.inf:
            value += hi**q * mp.exp(-hi)
        if lo > 0:
            value += lo**q * mp.exp(-lo)
        return value

    A = [[mp.mpf(0)] * m for _ in range(m)]
    for i in range(m):
        p = a + i
        gp = mp.gammainc(p, lo, hi)
        J = mp.mpf(0)
        for j in range(i + 1, m):
            q = a + j - 1
            J = q * J - edge(q) * gp + mp.mpf(2) ** (1 - p - q) * mp.gammainc(p + q, 2 * lo, 2 * hi)
            A[i][j], A[j][i] = J, -J
    if m % 2:
        g = [mp.gammainc(a + i, lo, hi) for i in range(m)]
        for i in range(m):
            A[i].append(g[i])
        A.append([-gi for gi in g] + [mp.mpf(0)])
    return A


def prob_within(m, K, lower, upper, dps=80):
    """P(lower <= every eigenvalue of W/K <= upper), W ~ W_m(K, I), as an mpf."""
    import mpmath as mp

    with mp.workdps(dps):
        a = mp.mpf(K - m + 1) / 2
        lo = mp.mpf(K) * mp.mpf(lower) / 2
        hi = mp.inf if upper == float("inf") else mp.mpf(K) * mp.mpf(upper) / 2
        return _pfaffian(_skew(m, a, lo, hi)) / _pfaffian(_skew(m, a, mp.mpf(0), mp.inf))


def checked_probabilities(m, K, intervals, digits=30):
    """P(all eigenvalues of W/K in [lower, upper]) for each interval, to ``digits`` digits.

    Chiani's monomial basis cancels more digits the larger ``m`` and ``K``, so
    the working precision is raised until two precisions 25 digits apart
    agree to ``digits`` significant digits (absolute for values below 1).
    Returns floats.
    """
    import mpmath as mp

    dps, previous = 50, None
    while True:
        with mp.workdps(dps):
            a = mp.mpf(K - m + 1) / 2
            full = _pfaffian(_skew(m, a, mp.mpf(0), mp.inf))
            values = []
            for lower, upper in intervals:
                lo = mp.mpf(K) * mp.mpf(lower) / 2
                hi = mp.inf if upper == float("inf") else mp.mpf(K) * mp.mpf(upper) / 2
                values.append(_pfaffian(_skew(m, a, lo, hi)) / full)
        if previous is not None and all(
            abs(v - p) <= mp.mpf(10) ** -digits * max(1, abs(v)) for v, p in zip(values, previous)
        ):
            return [float(v) for v in values]
        if dps > 2000:
            raise RuntimeError(f"the reference did not settle at m = {m}, K = {K}")
        previous, dps = values, dps + 25


#: (m, K, x) points of the table: around the bulk and in the tails.
POINTS = [
    (2, 50, 1.9),
    (4, 200, 1.45),
    (6, 1000, 1.22),
    (6, 1000, 0.8),
    (3, 60, 0.3),
    (6, 8, 0.02),
    (6, 1000, 1.4),
    (6, 1000, 0.7),
    (3, 5, 0.001),
    (2, 20, 4.0),
    (1, 1, 0.3),
    (1, 7, 1.6),
    (1, 1000, 1.1),
    (2, 2, 0.05),
    (2, 2, 2.5),
    (2, 3, 1.0),
    (2, 10, 1.5),
    (2, 100, 1.25),
    (2, 1000, 0.93),
    (3, 3, 0.02),
    (3, 3, 4.0),
    (3, 4, 1.2),
    (3, 10, 0.4),
    (3, 100, 1.4),
    (3, 1000, 1.12),
    (4, 4, 0.01),
    (4, 4, 5.0),
    (4, 5, 2.0),
    (4, 20, 0.5),
    (4, 100, 1.3),
    (4, 1000, 0.9),
    (5, 5, 0.005),
    (5, 5, 6.0),
    (5, 6, 3.0),
    (5, 30, 1.8),
    (5, 300, 0.8),
    (5, 1000, 1.15),
    (6, 6, 0.003),
    (6, 6, 7.0),
    (6, 7, 3.5),
    (6, 40, 0.45),
    (6, 100, 1.6),
    (6, 1000, 1.1),
    (6, 1000, 0.87),
    (6, 1000, 1.25),
]

#: (m, K, lower, upper) for P(all eigenvalues in [lower, upper]).
BANDS = [(2, 10, 0.3, 2.0), (3, 3, 0.01, 3.0), (5, 40, 0.4, 1.9), (6, 1000, 0.85, 1.2)]


if __name__ == "__main__":  # pragma: no cover - generator of the reference files
    import sys

    import mpmath as mp
    from references import write

    extremes = []
    for m, K, x in POINTS:
        with mp.workdps(80):
            cdf_max = prob_within(m, K, 0, x)
            sf_min = prob_within(m, K, x, float("inf"))
            row = [cdf_max, 1 - cdf_max, 1 - sf_min, sf_min]
        extremes.append([m, K, x, *(float(mp.nstr(v, 17)) for v in row)])
    bands = []
    for m, K, lo, hi in BANDS:
        with mp.workdps(80):
            bands.append([m, K, lo, hi, float(mp.nstr(prob_within(m, K, lo, hi), 17))])
    if "--write" not in sys.argv:
        print(extremes, bands, sep="\n")
        raise SystemExit
    script = "tests/nis_reference.py"
    write(
        "nis_extreme_eigenvalues",
        script=script,
        about="Laws of the extreme eigenvalues of the NIS matrix (Wishart, m x m, K dof): "
        "Chiani's Pfaffian in mpmath at 80 digits, rounded to 17 significant digits.",
        columns=["m", "K", "x", "P(lmax <= x)", "P(lmax > x)", "P(lmin <= x)", "P(lmin > x)"],
        values=extremes,
        tools=["mpmath"],
    )
    write(
        "nis_eigenvalue_bands",
        script=script,
        about="P(all eigenvalues of the NIS matrix in [lower, upper]): Chiani's Pfaffian in "
        "mpmath at 80 digits, rounded to 17 significant digits.",
        columns=["m", "K", "lower", "upper", "P(all in [lower, upper])"],
        values=bands,
        tools=["mpmath"],
    )
