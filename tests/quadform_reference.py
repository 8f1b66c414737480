"""High-precision reference values for ``test_quadform.py`` (mpmath).

Imhof's (1961) real-axis integral,
``P(Q > c) = 1/2 + (1/pi) int_0^inf sin(theta(u)) / (u rho(u)) du`` with
``theta(u) = 1/2 sum [h atan(w u) + d w u / (1 + w^2 u^2)] - c u / 2`` and
``rho(u) = prod (1 + w^2 u^2)^(h/4) exp(1/2 sum d w^2 u^2 / (1 + w^2 u^2))``,
evaluated with 30 digits by ``mpmath.quadosc`` (the tail oscillates with
angular frequency ``|c|/2``).  Independent of the library's contour
integral.  ``python tests/quadform_reference.py --write`` (needs ``mpmath``, several
minutes) writes ``P(Q <= c)`` for every case of :data:`CASES` to
``tests/reference/quadform_davies_cases.json``, with its provenance.
"""

from __future__ import annotations

#: Davies' (1980) AS 155 test cases: (weights, degrees of freedom, non-centralities) and the
#: points c at which P(Q <= c) is tabulated.
CASES = {
    ((6, 3, 1), (1, 1, 1), (0, 0, 0)): [1, 7, 20],
    ((6, 3, 1), (2, 2, 2), (0, 0, 0)): [2, 20, 60],
    ((6, 3, 1), (6, 4, 2), (0, 0, 0)): [10, 50, 120],
    ((7, 3), (6, 2), (6, 2)): [20, 100, 200],
    ((7, 3), (1, 1), (6, 2)): [10, 60, 150],
    ((7, 3, 7, 3), (6, 2, 1, 1), (6, 2, 6, 2)): [70, 160, 260],
    ((7, 3, -7, -3), (6, 2, 1, 1), (6, 2, 6, 2)): [-40, 40, 140],
    ((6, 3, 1), (2, 4, 6), (0, 0, 0)): [10, 30, 80],
    ((6, 3, 1, 12, 6, 2), (6, 4, 2, 2, 4, 6), (0, 0, 0, 0, 0, 0)): [45, 120, 210],
    (
        (6, 3, 1, 6, 3, 1, 7, 3, 7, 3),
        (6, 4, 2, 2, 4, 6, 6, 2, 1, 1),
        (0, 0, 0, 0, 0, 0, 6, 2, 6, 2),
    ): [120, 240, 400],
    ((30, 1), (1, 10), (0, 0)): [5, 25, 100],
    ((30, 1), (1, 20), (0, 0)): [10, 40, 100],
    ((30, 1), (1, 30), (0, 0)): [20, 50, 100],
}


def imhof_cdf_mp(c, weights, dof, noncentrality, digits=30):
    import mpmath as mp

    mp.mp.dps = digits
    terms = [(mp.mpf(w), mp.mpf(h), mp.mpf(d)) for w, h, d in zip(weights, dof, noncentrality)]
    c = mp.mpf(c)

    def integrand(u):
        if u == 0:
            return (sum(w * (h + d) for w, h, d in terms) - c) / 2
        theta = (
            sum(h * mp.atan(w * u) + d * w * u / (1 + (w * u) ** 2) for w, h, d in terms) / 2
            - c * u / 2
        )
        log_rho = sum(
            h / 4 * mp.log(1 + (w * u) ** 2) + d * (w * u) ** 2 / (2 * (1 + (w * u) ** 2))
            for w, h, d in terms
        )
        return mp.sin(theta) / (u * mp.exp(log_rho))

    sf = mp.mpf(1) / 2 + mp.quadosc(integrand, [0, mp.inf], omega=abs(c) / 2) / mp.pi
    return 1 - sf


if __name__ == "__main__":  # pragma: no cover - generator of the reference file
    import sys

    import mpmath as mp
    from references import write

    rows = []
    for case, points in CASES.items():
        for c in points:
            rows.append([*map(list, case), c, float(mp.nstr(imhof_cdf_mp(c, *case), 17))])
            print(rows[-1], flush=True)
    if "--write" in sys.argv:
        write(
            "quadform_davies_cases",
            script="tests/quadform_reference.py",
            about="P(Q <= c) of Davies' (1980) AS 155 test cases by Imhof's real-axis integral "
            "in mpmath (30 digits, quadosc), rounded to 17 significant digits.",
            columns=["weights", "dof", "noncentrality", "c", "P(Q <= c)"],
            values=rows,
            tools=["mpmath"],
        )
