"""Exact and approximate laws of the extreme eigenvalues of the NIS matrix under H0.

References ([C14], [C17], [J]) are listed in :mod:`course.nis`; the course's
own sources are in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import stats

from course._law_inputs import _levels, _points
from course.distributions import FrozenDistribution
from course.nis._pfaffians import _augment, _bordered, _LaguerreBasis, _pfaffian
from course.nis._statistics import EigenvaluePair, _check_dims, _check_which
from course.validation import as_count, as_finite, as_generator, as_size

#: Chiani's shifted-gamma fit of the Tracy-Widom law TW1 ([C14], Table 1):
#: TW1 ~ Gamma(shape=k, scale=theta) - alpha.
TW1_GAMMA = {"k": 46.44604884387787, "theta": 0.18605402228279347, "alpha": 9.848007781128567}

#: Where the exact laws are validated (CDF error below 1e-8, measured below 1e-13,
#: against a high-precision evaluation of Chiani's formula): ``m <= 30`` and
#: ``m <= K <= 10^5``. :class:`ExtremeEigenvalue` refuses other sizes.
EXACT_LAW_LIMITS = {"m": 30, "K": 100_000}


class ExtremeEigenvalue(FrozenDistribution):
    r"""Exact law of ``lambda_max`` or ``lambda_min`` of ``Pi = W/K``, ``W ~ W_m(K, I)``.

    Under H0 this is the law of the largest or smallest eigenvalue of the
    NIS matrix of ``K`` steps of ``m``-dimensional innovations.  Build it
    with :func:`extreme_eigenvalue`.

    Parameters
    ----------
    m : int
        Dimension (innovation size), ``m >= 1``.
    K : int
        Degrees of freedom (number of time steps), ``K >= m``.
    which : {"max", "min"}
        The largest or the smallest eigenvalue.

    Notes
    -----
    The eigenvalues of :math:`W \sim W_m(K, I)` have the joint density

    .. math::

        c \prod_i l_i^{(K-m-1)/2} e^{-l_i/2} \prod_{i<j} |l_i - l_j| .

    With :math:`y = l/2` and de Bruijn's integration formula, the probability
    that all eigenvalues lie in an interval :math:`I` is a Pfaffian ([C14],
    Theorem 1; [C17], Theorem 1):

    .. math::

        P(\text{all } y_i \in I) = \frac{\operatorname{Pf}(A_I)}{\operatorname{Pf}(A_{[0, \infty)})},
        \qquad
        (A_I)_{ij} = \iint_{I^2} \operatorname{sgn}(z - y)\, f_i(y) f_j(z)\, dy\, dz,

    bordered by :math:`g_i = \int_I f_i` when :math:`m` is odd, for any basis
    :math:`f_0, \dots, f_{m-1}` of :math:`y^{a-1} e^{-y} p(y)` with :math:`p` of
    degree :math:`< m`, :math:`a = (K - m + 1)/2`.  Chiani uses :math:`f_i = y^{a-1+i} e^{-y}`,
    whose entries are incomplete gamma functions; at large :math:`K` they agree
    to many digits and the Pfaffian cancels catastrophically (about 17 digits
    are lost at :math:`m = 6`, :math:`K = 1000`).  Powers of a standardised variable
    cure large :math:`K` but not large :math:`m`: near :math:`K = m` the eigenvalues
    spread over :math:`[0, 2m]` and the skew matrix of :math:`w(y)\, u^i` has a
    condition number of 1e34 at :math:`m = 24`, :math:`K = 30`, so double precision
    returns nonsense even from exactly rounded entries.  Here the basis is
    :math:`f_i(y) = c\, w(y)\, L_i^{(K-m)}(2y)`, :math:`w` the Gamma(a) density and
    :math:`L_i^{(\alpha)}` the generalised Laguerre polynomials normalised so that
    the :math:`f_i` are orthonormal for :math:`\int f_i f_j\, y\, dy` (a change of basis
    by a triangular matrix, so the ratio of Pfaffians is unchanged).  The
    skew matrix of :math:`[0, \infty)` then has a condition number below 100 for
    every :math:`m \le 30` and :math:`K`.  In :math:`v = \sqrt y` the basis functions are
    :math:`v^{K-m} e^{-v^2}` times polynomials, smooth at 0, so the running
    integrals :math:`\int_{\text{lo}}^z f_i` and the entries are computed by composite
    Gauss-Legendre quadrature (panels of width 1.5 in :math:`v`, 24 nodes each)
    over the interval cut where every :math:`f_i` is below 1e-30 of its largest
    value (:class:`course.nis._pfaffians._LaguerreBasis`).  Normalising by the
    Pfaffian over :math:`[0, \infty)` avoids the multivariate-gamma constant.

    ``cdf`` of :math:`\lambda_{\max}` uses :math:`I = [0, Kx/2]`; ``sf`` of
    :math:`\lambda_{\min}` uses :math:`I = [Kx/2, \infty)`.  The complementary probability
    is computed without the subtraction :math:`1 - p` when :math:`p > 1/2`: with
    :math:`A_{\text{full}} = A_I + D` (:math:`D` assembled from the other interval's pieces),
    :math:`p^2 = \det(I - A_{\text{full}}^{-1} D)` and :math:`1 - p = -\operatorname{expm1}(\log p)` with
    :math:`\log p = \sum_k \log|1 - \mu_k| / 2` over the eigenvalues :math:`\mu_k` of
    :math:`A_{\text{full}}^{-1} D`, so small tail probabilities keep their relative
    accuracy.  The density is the derivative of a Pfaffian under a rank-two
    skew update, :math:`d\operatorname{Pf}(A) = -\operatorname{Pf}\begin{bmatrix} A & U & V \\ -U^{\mathsf T} & 0 & 0 \\ -V^{\mathsf T} & 0 & 0 \end{bmatrix}`.
    For :math:`m = 1` the law is :math:`\chi^2(K)/K`.

    Accuracy, against Chiani's formula in his own basis evaluated with
    mpmath at a working precision raised until 30 digits settle
    (``tests/nis_reference.py``): on the validated region :math:`m \le 30`,
    :math:`m \le K \le 10^5` (:data:`EXACT_LAW_LIMITS`) the absolute CDF error is
    below :math:`10^{-13}` at every :math:`K` tested (all :math:`K` from :math:`m` to :math:`2m`
    and :math:`K` up to :math:`10^5`; the full grid is
    ``tests/benchmarks/bench_nis.py``, a hypothesis sweep of it runs in the
    test suite); relative error about :math:`10^{-12}` in the tails the tests use
    (upper tail of :math:`\lambda_{\max}`, lower tail of :math:`\lambda_{\min}`) down to
    probabilities of :math:`10^{-300}` (checked for :math:`m \le 6`; at :math:`m = 16` to
    :math:`30` checked at :math:`10^{-30}`, relative error below :math:`10^{-12}`).  In the
    opposite tails, probabilities below about :math:`10^{-12}` are accurate in
    absolute terms only.  Outside the validated region the constructor raises
    ``ValueError`` rather than return unchecked numbers.  A CDF point costs
    about 1 ms of CPU at :math:`m = 30` (building the law 2-3 ms more), a
    quantile 10-30 ms.  Quantiles come from a safeguarded Newton iteration
    on :math:`\log F` against :math:`\log x`, started at the Tracy-Widom quantile.
    """

    _bounds = (0.0, np.inf)

    def __init__(self, m, K, which="max"):
        self.m, self.K = _check_dims(m, K)
        self.which = _check_which(which)
        _check_validated(self.m, self.K)
        self._a = (self.K - self.m + 1) / 2.0
        self._basis = _LaguerreBasis(self.m, self._a)
        J, g = self._blocks(np.zeros(1), np.full(1, np.inf))
        self._A_full = _augment(J, g)[0]
        self._pf_full = float(_pfaffian(self._A_full))
        # [0, t] is this law's "inside" for lambda_max, [t, inf) for lambda_min.
        self._inside, self._outside = ("low", "high") if self.which == "max" else ("high", "low")

    def __repr__(self) -> str:
        return f"ExtremeEigenvalue(m={self.m}, K={self.K}, which={self.which!r})"

    # -- core -----------------------------------------------------------------
    def _blocks(self, lo: np.ndarray, hi: np.ndarray):
        return self._basis.blocks(lo, hi)

    def _side(self, t: np.ndarray, kind: str):
        """Blocks of [0, t] ("low") or [t, inf) ("high")."""
        if kind == "low":
            return self._blocks(np.zeros_like(t), t)
        return self._blocks(t, np.full_like(t, np.inf))

    def _inside_and_outside(self, x: np.ndarray, density: bool = False):
        """(P(all eigenvalues on this law's side of x), its complement[, pdf])."""
        shape = np.shape(x)
        with np.errstate(over="ignore"):  # (K x / 2 beyond the doubles: capped below)
            t = self.K * np.asarray(x, dtype=float).reshape(-1) / 2.0
        # Beyond t_cap = 2 m K + 2000 every eigenvalue of W/2 lies below t but with
        # probability below exp(-1500) (lambda_max <= trace, a chi2(m K), and
        # Chernoff's bound): the answer is exact in doubles, and the blocks of
        # the Laguerre basis are not evaluated there (they overflow near 1e300).
        beyond = t >= 2.0 * self.m * self.K + 2000.0
        t = np.where(beyond, 1.0, t)
        J_in, g_in = self._side(t, self._inside)
        inside = np.clip(_pfaffian(_augment(J_in, g_in)) / self._pf_full, 0.0, 1.0)
        # P(every eigenvalue <= t) is 1 beyond t_cap: "inside" for lambda_max, "outside"
        # for lambda_min (whose inside is every eigenvalue >= t)
        inside[beyond] = 1.0 if self._inside == "low" else 0.0
        outside = 1.0 - inside
        big = inside > 0.5
        if np.any(big):
            J_out, g_out = self._side(t[big], self._outside)
            g_low, g_high = (g_in[big], g_out) if self._inside == "low" else (g_out, g_in[big])
            cross = g_low[:, :, None] * g_high[:, None, :]
            D = _augment(J_out + cross - np.swapaxes(cross, -1, -2), g_out)
            mu = np.linalg.eigvals(np.linalg.solve(self._A_full, D))
            with np.errstate(divide="ignore"):
                log_inside = 0.25 * np.sum(np.log1p(np.abs(mu) ** 2 - 2.0 * mu.real), axis=-1)
            outside[big] = np.clip(-np.expm1(log_inside), 0.0, 1.0) + 0.0  # (no -0.0)
            outside[big & beyond] = 0.0 if self._inside == "low" else 1.0
            # Near 1 the direct Pfaffian carries ~1e-14 noise; 1 - (accurate
            # small complement) is monotone there.
            inside[big] = 1.0 - outside[big]
        if not density:
            return inside.reshape(shape), outside.reshape(shape)
        density_values = np.where(beyond, 0.0, self._density(t, J_in, g_in))
        return inside.reshape(shape), outside.reshape(shape), density_values.reshape(shape)

    def _density(self, t, J, g):
        """pdf at x = 2t/K from the derivative of the inside Pfaffian."""
        f = self._basis.values(t)
        if self.m % 2:
            # d/dt of the border g is +f for [0, t] and -f for [t, inf).
            border = -1.0 if self.which == "max" else 1.0
            f = np.concatenate([f, np.zeros((t.size, 1))], axis=1)
            g = np.concatenate([g, np.full((t.size, 1), border)], axis=1)
        d_pf = -_pfaffian(_bordered(_augment(J, g[:, : self.m]), g, f))
        sign = 1.0 if self.which == "max" else -1.0
        return np.clip(sign * d_pf / self._pf_full * (self.K / 2.0), 0.0, None)

    def _cdf(self, x):
        inside, outside = self._inside_and_outside(x)
        return inside if self.which == "max" else outside

    def _sf(self, x):
        inside, outside = self._inside_and_outside(x)
        return outside if self.which == "max" else inside

    def _pdf(self, x):
        with np.errstate(over="ignore"):
            t = self.K * np.asarray(x, dtype=float).reshape(-1) / 2.0
        # (0 beyond the cap of _inside_and_outside, where the basis is not evaluated)
        beyond = t >= 2.0 * self.m * self.K + 2000.0
        t = np.where(beyond, 1.0, t)
        J, g = self._side(t, self._inside)
        return np.where(beyond, 0.0, self._density(t, J, g)).reshape(np.shape(x))

    def _rvs(self, size, rng):
        lmin, lmax = simulate_extreme_eigenvalues(self.m, self.K, size, rng=rng)
        return lmax if self.which == "max" else lmin

    # -- public overrides ---------------------------------------------------------
    def _check_x(self, x):
        x = _points(x)
        if np.any(x < 0):
            raise ValueError(
                "x must be >= 0: the eigenvalues of the NIS matrix (a sum of outer products) "
                f"are never negative, got a smallest x of {float(np.min(x)):.4g}"
            )
        return x

    def cdf(self, x):
        """P(X <= x); raises ValueError for x < 0 (not a possible eigenvalue)."""
        return super().cdf(self._check_x(x))

    def sf(self, x):
        """P(X > x), computed directly (no ``1 - cdf``) in the upper tail."""
        return super().sf(self._check_x(x))

    def pdf(self, x):
        """Probability density at ``x >= 0``."""
        return super().pdf(self._check_x(x))

    def _root(self, func, target, increasing):
        # Safeguarded Newton on log F(e^y) = log target, y = log x, where F is
        # the cdf (ppf) or the sf (isf): relative accuracy for tiny quantiles
        # and tail targets alike, and quadratic convergence from the
        # Tracy-Widom guess, with bisection whenever a step leaves the bracket.
        use_cdf = func == self.cdf
        log_target = np.log(target)
        lower_is_cdf = (self.which == "max") == use_cdf

        def g_and_slope(y):
            x = np.exp(y)
            inside, outside, dens = self._inside_and_outside(np.array([x]), density=True)
            F = float(inside[0] if lower_is_cdf else outside[0])
            dF = float(dens[0]) * (1.0 if use_cdf else -1.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.log(F) - log_target, x * dF / F

        direction = 1.0 if use_cdf else -1.0  # sign of dg/dy
        tol = 4 * np.finfo(float).eps
        y, step = self._quantile_guess(target, use_cdf), 0.05
        below = above = None  # y values known to be below / above the root
        for _ in range(300):
            g, slope = g_and_slope(y)
            if g == 0:
                break
            if direction * g < 0:
                below = y
            else:
                above = y
            newton = (
                y - g / slope if np.isfinite(g) and np.isfinite(slope) and slope != 0 else np.nan
            )
            if below is not None and above is not None:
                lo, hi = min(below, above), max(below, above)
                y_new = newton if lo < newton < hi else 0.5 * (lo + hi)
                if hi - lo <= tol * max(1.0, abs(y)):
                    y = y_new
                    break
            elif np.isfinite(newton) and abs(newton - y) <= 1.0:
                y_new = newton
            else:
                # No bracket yet and no usable Newton step: walk outward.
                y_new = y + step if above is None else y - step
                step *= 2
                if abs(y_new) > 700:
                    if y_new < 0:
                        return 0.0
                    raise ValueError("could not bracket the quantile")
            if abs(y_new - y) <= tol * max(1.0, abs(y)):
                y = y_new
                break
            y = y_new
        return float(np.exp(y))

    def _quantile_guess(self, target, use_cdf) -> float:
        """log of the Tracy-Widom quantile where it is usable, else 0."""
        try:
            approx = TracyWidomApproximation(self.m, self.K, self.which)
            x = float(approx.ppf(target) if use_cdf else approx.isf(target))
        except ValueError:
            return 0.0
        return float(np.log(x)) if np.isfinite(x) and x > 1e-300 else 0.0

    def _moment_integral(self, power: int) -> float:
        # E[X^p] = int_0^inf p x^(p-1) sf(x) dx.  Below lo = ppf(1e-15) the sf
        # is 1 to double precision and above hi = isf(1e-15) it is negligible,
        # so [0, lo] is done exactly and [lo, hi] by composite Gauss-Legendre
        # in one vectorised sf evaluation.  The variable x = v^2 smooths the
        # sqrt(x) behaviour of lambda_min at x = 0 when K = m.
        if not hasattr(self, "_far_quantiles"):
            self._far_quantiles = (float(self.ppf(1e-15)), float(self.isf(1e-15)))
        lo, hi = self._far_quantiles
        nodes, weights = np.polynomial.legendre.leggauss(20)
        edges = np.linspace(np.sqrt(lo), np.sqrt(hi), 33)
        half = 0.5 * np.diff(edges)
        v = (0.5 * (edges[:-1] + edges[1:]))[:, None] + half[:, None] * nodes
        w = half[:, None] * weights * 2 * v
        x = v * v
        return lo**power + float(np.sum(w * power * x ** (power - 1) * self.sf(x)))

    def mean(self) -> float:
        """E[X], by integrating the survival function over the whole support."""
        return self._moment_integral(1)

    def var(self) -> float:
        """Var[X] = E[X^2] - E[X]^2, both from the survival function."""
        return self._moment_integral(2) - self.mean() ** 2


def _check_validated(m: int, K: int) -> None:
    if m > EXACT_LAW_LIMITS["m"] or K - EXACT_LAW_LIMITS["K"] > 0:
        raise ValueError(
            f"the exact law is validated for m <= {EXACT_LAW_LIMITS['m']} and "
            f"K <= {EXACT_LAW_LIMITS['K']:,} (got m = {m}, K = {K}); beyond that its accuracy "
            'has not been checked: use method="tracy-widom" for a quick look, or Monte Carlo '
            "(simulate_extreme_eigenvalues) for a threshold"
        )


class TracyWidomApproximation(FrozenDistribution):
    r"""Fast approximation of an extreme-eigenvalue law: Tracy-Widom via a shifted gamma.

    Parameters
    ----------
    m, K : int
        Dimension and degrees of freedom, ``K >= m`` (``K > m`` for "min").
    which : {"max", "min"}

    Notes
    -----
    Johnstone's centring and scaling for real Wishart matrices ([J], Thm 1.1),
    with :math:`n = K - 1/2` and :math:`p = m - 1/2`:

    .. math::

        \mu = (\sqrt n + \sqrt p)^2, \qquad
        \sigma = \sqrt\mu \left(\frac{1}{\sqrt n} + \frac{1}{\sqrt p}\right)^{1/3}, \qquad
        \frac{\lambda_{\max}(W) - \mu}{\sigma} \to TW_1,

    and for the smallest eigenvalue (the "soft" lower edge, :math:`K > m`)

    .. math::

        \mu = (\sqrt n - \sqrt p)^2, \qquad
        \sigma = \sqrt\mu \left(\frac{1}{\sqrt p} - \frac{1}{\sqrt n}\right)^{1/3}, \qquad
        \frac{\mu - \lambda_{\min}(W)}{\sigma} \to TW_1 .

    :math:`TW_1` itself is replaced by Chiani's shifted gamma
    :math:`\Gamma(k, \theta) - \alpha` ([C14], Sec. 5, constants
    :data:`TW1_GAMMA`), which matches its first three moments.

    The result is an asymptotic law (large ``m`` and ``K``) and costs what
    an approximation costs. Measured error, ``sup_x |F_TW(x) - F(x)|``
    against the exact law :class:`ExtremeEigenvalue` on 400 points between
    its 1e-6 and 1 - 1e-6 quantiles (every row is recomputed by the test
    suite; the exact law is accurate to 1e-13 on the whole table):

    Largest eigenvalue (``which="max"``):

    ====  =====  =====  =====  =====  =====  =====  =====
    m     K = m  K=10   K=30   K=100  K=300  K=1e3  K=1e4
    ====  =====  =====  =====  =====  =====  =====  =====
    1     0.58   0.15   0.080  0.039  0.021  0.013  0.013
    2     0.27   0.10   0.052  0.021  0.011  0.010  0.014
    3     0.16   0.086  0.046  0.020  0.009  0.009  0.012
    4     0.12   0.077  0.043  0.019  0.008  0.008  0.010
    6     0.083  0.066  0.039  0.019  0.007  0.007  0.007
    10    0.054  n/a    0.034  0.018  0.008  0.005  0.005
    16    0.038  n/a    0.029  0.017  0.009  0.004  0.004
    ====  =====  =====  =====  =====  =====  =====  =====

    Smallest eigenvalue (``which="min"``; first column ``K = m + 1``):

    ====  =====  =====  =====  =====  =====  =====  =====
    m     K=m+1  K=10   K=30   K=100  K=300  K=1e3  K=1e4
    ====  =====  =====  =====  =====  =====  =====  =====
    1     0.39   0.16   0.095  0.057  0.038  0.027  0.018
    2     0.41   0.17   0.097  0.060  0.041  0.031  0.022
    3     0.42   0.18   0.094  0.055  0.037  0.027  0.019
    4     0.42   0.19   0.092  0.052  0.034  0.024  0.017
    6     0.42   0.23   0.091  0.048  0.030  0.021  0.013
    10    0.42   n/a    0.097  0.044  0.026  0.017  0.010
    16    0.42   n/a    0.12   0.043  0.024  0.014  0.008
    ====  =====  =====  =====  =====  =====  =====  =====

    So a test at level 0.05 built on it can have a false-alarm rate off by
    as much as these numbers. The error is never below 0.004 in this range;
    near the hard edge (smallest eigenvalue, K close to m) it is about 0.4;
    for m <= 3 it stops shrinking beyond K of about 1000 (the limit needs m
    to grow too). Beyond m = 16 the course has not measured it (Monte Carlo
    spot checks at m = 20 to 50 and K >= 100 gave errors below 0.03). Use
    the exact law wherever it applies; the approximation serves as its
    quantiles' Newton starting point and for a quick look at large sizes.
    """

    def __init__(self, m, K, which="max"):
        self.m, self.K = _check_dims(m, K)
        self.which = _check_which(which)
        n, p = np.sqrt(self.K - 0.5), np.sqrt(self.m - 0.5)
        if self.which == "min" and self.m == self.K:
            raise ValueError(
                "the Tracy-Widom approximation of the smallest eigenvalue needs K > m "
                "(at K = m the lower edge is a hard edge at 0); use the exact law"
            )
        sign = 1.0 if self.which == "max" else -1.0
        root_mu = n + sign * p
        mu = root_mu**2
        sigma = root_mu * (1.0 / p + sign / n) ** (1.0 / 3.0)
        k, theta, alpha = TW1_GAMMA["k"], TW1_GAMMA["theta"], TW1_GAMMA["alpha"]
        self._gamma = stats.gamma(k, scale=theta)
        # X = (mu + sign * sigma * (G - alpha)) / K, G ~ Gamma(k, theta)
        self._loc = (mu - sign * sigma * alpha) / self.K
        self._scale = sigma / self.K
        self._sign = sign
        self._bounds = (self._loc, np.inf) if sign > 0 else (-np.inf, self._loc)

    def __repr__(self) -> str:
        return f"TracyWidomApproximation(m={self.m}, K={self.K}, which={self.which!r})"

    def _g(self, x):
        return self._sign * (np.asarray(x, dtype=float) - self._loc) / self._scale

    def _cdf(self, x):
        return self._gamma.cdf(self._g(x)) if self._sign > 0 else self._gamma.sf(self._g(x))

    def _sf(self, x):
        return self._gamma.sf(self._g(x)) if self._sign > 0 else self._gamma.cdf(self._g(x))

    def _pdf(self, x):
        return self._gamma.pdf(self._g(x)) / self._scale

    def _rvs(self, size, rng):
        return self._loc + self._sign * self._scale * self._gamma.rvs(size=size, random_state=rng)

    def _from_gamma(self, g):
        return self._loc + self._sign * self._scale * g

    def ppf(self, q):
        """Quantile, in closed form from the gamma quantile."""
        q = _levels(q)
        g = self._gamma.ppf(q) if self._sign > 0 else self._gamma.isf(q)
        return self._from_gamma(g)

    def isf(self, q):
        """Inverse survival function, in closed form."""
        q = _levels(q)
        g = self._gamma.isf(q) if self._sign > 0 else self._gamma.ppf(q)
        return self._from_gamma(g)

    def mean(self) -> float:
        return float(self._from_gamma(self._gamma.mean()))

    def var(self) -> float:
        return float(self._scale**2 * self._gamma.var())


def extreme_eigenvalue(m, K, which="max", method="exact"):
    r"""Law of the largest or smallest eigenvalue of the NIS matrix under H0.

    ``Pi = W/K`` with ``W ~ W_m(K, I)``: the NIS matrix of ``K`` steps of
    ``m``-dimensional innovations when the filter's model is right.

    Parameters
    ----------
    m : int
        Innovation dimension, ``m >= 1``.
    K : int
        Number of time steps (Wishart degrees of freedom), ``K >= m``.
    which : {"max", "min"}
        The largest or the smallest eigenvalue.
    method : {"exact", "tracy-widom"}
        ``"exact"``: Chiani's closed form (:class:`ExtremeEigenvalue`);
        ``"tracy-widom"``: the shifted-gamma Tracy-Widom approximation
        (:class:`TracyWidomApproximation`): its CDF is off by 0.004 to 0.58
        for m <= 16, K <= 10^4 (measured table in its docstring), so use it
        for a quick look, not for a test's threshold.

    Returns
    -------
    FrozenDistribution
        With ``cdf``, ``sf``, ``pdf``, ``ppf``, ``isf``, ``mean``, ``var``,
        ``interval``, ``support()``, ``median``, ``logcdf``, ``logsf``,
        ``expect`` and ``rvs(size, rng=...)``.

    Raises
    ------
    ValueError
        ``m < 1``, ``K < m``, non-integers, unknown ``which`` or ``method``;
        for ``method="exact"`` also sizes outside the validated region
        ``m <= 30``, ``K <= 10^5`` (:data:`EXACT_LAW_LIMITS`).

    See Also
    --------
    ExtremeEigenvalue : The exact law and how it is computed.
    TracyWidomApproximation : The asymptotic law.
    nis_matrix_critical_values : The thresholds of the NIS-matrix test.
    simulate_extreme_eigenvalues : Monte Carlo draws of the same laws.

    Notes
    -----
    The law of :math:`\lambda_{\min}` or :math:`\lambda_{\max}` of
    :math:`W/K`, :math:`W \sim W_m(K, I)`.  The exact law is Chiani's Pfaffian
    ([C14], Theorem 1; [C17], Theorem 1) evaluated in an orthonormal Laguerre
    basis, see :class:`ExtremeEigenvalue`; its CDF is validated to better than
    :math:`10^{-13}` (target :math:`10^{-8}`) for :math:`m \le 30` and
    :math:`m \le K \le 10^5`. The approximation is Johnstone's Tracy-Widom limit
    ([J]) with Chiani's shifted gamma for :math:`TW_1`, see
    :class:`TracyWidomApproximation`.

    Examples
    --------
    >>> law = extreme_eigenvalue(2, 50, "max")
    >>> round(float(law.isf(0.025)), 4)
    1.5848
    """
    if method == "exact":
        return ExtremeEigenvalue(m, K, which)
    if method == "tracy-widom":
        return TracyWidomApproximation(m, K, which)
    raise ValueError(f'method must be "exact" or "tracy-widom", got {method!r}')


def prob_eigenvalues_within(m, K, lower, upper) -> float:
    r"""P(every eigenvalue of ``Pi = W/K`` lies in ``[lower, upper]``), ``W ~ W_m(K, I)``.

    This is ``P(lambda_min >= lower and lambda_max <= upper)``: the
    probability that the NIS-matrix test with thresholds ``(lower, upper)``
    accepts under H0, so ``1 -`` it is the test's exact false-alarm rate.

    Parameters
    ----------
    m, K : int
        Dimension and degrees of freedom, ``K >= m``.
    lower, upper : float
        ``0 <= lower < upper`` (``upper`` may be ``inf``).

    Returns
    -------
    float
        The probability, in ``[0, 1]``.

    Raises
    ------
    ValueError
        Bad dimensions or thresholds, or sizes outside the validated region
        ``m <= 30``, ``K <= 10^5`` of the exact laws.

    See Also
    --------
    extreme_eigenvalue : The law of each extreme eigenvalue alone.
    nis_matrix_critical_values : Thresholds whose exact size this gives.

    Notes
    -----
    [C17], Theorem 1: the same Pfaffian as :class:`ExtremeEigenvalue` with
    the entries integrated over :math:`[K\ell/2,\ Ku/2]` (:math:`\ell` =
    ``lower``, :math:`u` = ``upper``), which gives

    .. math::

        P(\ell \le \lambda_{\min}(W/K),\ \lambda_{\max}(W/K) \le u),
        \qquad W \sim W_m(K, I).

    Examples
    --------
    The exact false-alarm rate of the NIS-matrix test at its thresholds:

    >>> lower, upper = 0.5530, 1.5848        # nis_matrix_critical_values(2, 50)
    >>> round(1 - prob_eigenvalues_within(2, 50, lower, upper), 3)
    0.05
    """
    m, K = _check_dims(m, K)
    lower = as_finite(lower, "lower", what="the lower threshold")
    upper = (
        float(np.inf) if _is_inf(upper) else as_finite(upper, "upper", what="the upper threshold")
    )
    if lower < 0 or not upper > lower:
        raise ValueError(
            f"need 0 <= lower < upper (thresholds on eigenvalues), got lower = {lower}, "
            f"upper = {upper}"
        )
    law = ExtremeEigenvalue(m, K, "max")
    J, g = law._blocks(np.full(1, K * lower / 2), np.full(1, K * upper / 2))
    return float(np.clip(_pfaffian(_augment(J, g))[0] / law._pf_full, 0.0, 1.0))


def _is_inf(value: Any) -> bool:
    return isinstance(value, (float, np.floating)) and value == np.inf


def simulate_extreme_eigenvalues(
    m: Any,
    K: Any,
    size: Any = None,
    *,
    rng: Any = None,
    chunk: int = 100_000,
) -> EigenvaluePair:
    r"""Monte Carlo draws of ``(lambda_min, lambda_max)`` of ``W/K``, ``W ~ W_m(K, I)``.

    Uses Bartlett's decomposition ``W = L L^T`` with ``L`` lower triangular,
    ``L_ii = sqrt(chi2(K - i))`` (``i = 0, ..., m-1``) and standard normal
    entries below the diagonal, so a draw costs ``m(m+1)/2`` random numbers
    instead of ``m K``.

    Parameters
    ----------
    m, K : int
    size : int or tuple of int, optional
        Shape of the output arrays.
    rng : numpy.random.Generator or seed
        Source of randomness (keyword-only).
    chunk : int
        Draws generated per batch (bounds the memory).

    Returns
    -------
    EigenvaluePair
        ``(lmin, lmax)``: arrays of shape ``size``, floats when ``size`` is None.

    See Also
    --------
    extreme_eigenvalue : The exact laws these draws follow.

    Notes
    -----
    Bartlett's decomposition of :math:`W \sim W_m(K, I)`: with :math:`W = BB^{\mathsf T}`,
    :math:`B` lower triangular,

    .. math::

        B_{ii}^2 \sim \chi^2(K - i + 1), \qquad B_{ij} \sim N(0, 1)\ (i > j),

    all independent (:math:`i = 1, \dots, m`).

    Examples
    --------
    >>> draws = simulate_extreme_eigenvalues(2, 50, size=1000, rng=0)
    >>> bool((draws.lmin <= draws.lmax).all()), draws.lmax.shape
    (True, (1000,))
    """
    m, K = _check_dims(m, K)
    rng = as_generator(rng)
    shape = as_size(size) or ()
    chunk = as_count(chunk, "chunk")
    total = int(np.prod(shape)) if shape else 1
    lmin, lmax = np.empty(total), np.empty(total)
    below = np.tril_indices(m, -1)
    dof = K - np.arange(m)
    for start in range(0, total, chunk):
        n = min(chunk, total - start)
        L = np.zeros((n, m, m))
        L[:, np.arange(m), np.arange(m)] = np.sqrt(rng.chisquare(dof, size=(n, m)))
        L[:, below[0], below[1]] = rng.standard_normal((n, below[0].size))
        values = np.linalg.eigvalsh(L @ np.swapaxes(L, -1, -2)) / K
        lmin[start : start + n], lmax[start : start + n] = values[:, 0], values[:, -1]
    if not shape:
        return EigenvaluePair(float(lmin[0]), float(lmax[0]))
    return EigenvaluePair(lmin.reshape(shape), lmax.reshape(shape))
