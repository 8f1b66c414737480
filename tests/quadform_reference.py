"""High-precision reference values for ``test_quadform.py`` (mpmath).

Imhof's (1961) real-axis integral,
``P(Q > c) = 1/2 + (1/pi) int_0^inf sin(theta(u)) / (u rho(u)) du`` with
``theta(u) = 1/2 sum [h atan(w u) + d w u / (1 + w^2 u^2)] - c u / 2`` and
``rho(u) = prod (1 + w^2 u^2)^(h/4) exp(1/2 sum d w^2 u^2 / (1 + w^2 u^2))``,
evaluated with 30 digits by ``mpmath.quadosc`` (the tail oscillates with
angular frequency ``|c|/2``).  Independent of the library's contour
integral.  Run ``python tests/quadform_reference.py`` (needs ``mpmath``, a
few minutes) to print ``P(Q <= c)`` for every case of ``DAVIES_CASES``.
"""

from __future__ import annotations


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


if __name__ == "__main__":
    import mpmath as mp
    from test_quadform import DAVIES_CASES

    for case, values in DAVIES_CASES.items():
        row = [(c, mp.nstr(imhof_cdf_mp(c, *case), 20)) for c, _ in values]
        print(case, row, flush=True)
