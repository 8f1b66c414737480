"""Quadratic forms in normal variables and their exact distribution (Imhof's method).

A quadratic form ``Q = x^T A x`` in a normal vector ``x ~ N(mu, Sigma)`` is, after
an eigen-decomposition, a weighted sum of independent (noncentral) chi-square
variables,

.. math:: Q = \\sum_r \\lambda_r \\chi^2(h_r, \\delta_r^2) \\;[+\\; \\sigma Z + q_0],

where the ``lambda_r`` are the eigenvalues of ``Sigma^{1/2} A Sigma^{1/2}``
(either sign), ``h_r`` their multiplicities and ``delta_r^2`` the squared
means along the eigenvectors (Imhof 1961, section 2; Baram 1980, (3.16)-(3.17)).
The normal term ``sigma Z`` and the constant ``q_0`` appear only when
``Sigma`` is singular and the mean has a component outside its range that
``A`` couples to the random part.  Full references to Imhof (1961), Davies (1980), Liu, Tang
and Zhang (2009) and Baram (1980) are in the course bibliography, :doc:`/docs/bibliography`.

Public API
----------
imhof_cdf, imhof_sf
    ``P(Q <= c)`` and ``P(Q > c)`` of a weighted sum of noncentral chi-square
    variables, vectorised over ``c``, with a controlled error.
liu_tang_zhang_cdf, liu_tang_zhang_sf
    The fast four-cumulant approximation of Liu, Tang and Zhang (2009).
inversion_integrands
    Imhof's real-axis integrand and the contour integrand, for figures.
WeightedChiSquare
    Frozen distribution of ``sum_r w_r chi2(h_r, delta_r^2) + sigma Z + offset``.
QuadraticForm
    Frozen distribution of ``x^T A x`` with ``x ~ N(mean, cov)`` (singular
    ``cov`` allowed), built on :class:`WeightedChiSquare`.

Numerics
--------
Imhof's formula inverts the characteristic function along the imaginary
axis of the Laplace variable ``s``; there its integrand decays only like
``|s|^{-1-k}`` with ``k = sum(h)/2``, so a single chi-square with one degree
of freedom needs an astronomically long integration range for 1e-8
accuracy.  The same integral is evaluated here along a *deformed* contour:
a hyperbola through the saddle point of the integrand that opens into the
half-plane where ``exp(-s c)`` decays.  Cauchy's theorem makes the two
integrals equal; on the hyperbola the integrand decays exponentially (often
double-exponentially) in the path parameter and is analytic in a strip, so
the trapezoidal rule converges geometrically.

Accuracy on demand.  The law is first scaled to ``max(|w|, sigma) = 1``
(the laws are scale-invariant), so weights, ``sigma`` or covariances of
1e-300 or 1e300 integrate like unit ones, and the integrand is computed as
``exp(E - E0)`` with ``E0`` its exponent at the vertex, so tails down to
1e-300 keep their relative accuracy (below the smallest double the answer is
0).  The error is controlled by (i) a rigorous truncation bound in the style
of Imhof's ``T_U`` and (ii) the trapezoidal rule at two steps from one
evaluation, the coarse step chosen from ``rtol`` (``3.5/log(1/rtol)``), the
step halved while the two levels differ by more than the tolerance.  (The
square of that difference, the asymptotic error model, would halve the
nodes but erred by up to 1e3 rtol on random laws: the convergence is often
not yet in its asymptotic regime.)  A loose ``rtol`` therefore costs fewer
nodes; one point is set up in Python floats around one numpy evaluation of
the integrand (about 0.2 ms for a first call on a shared 2-core machine), many
points are processed together without a Python loop over them.  Far below
the weights of a positive form the first term of the expansion at 0 is
exact to double precision and is used instead (``imhof_cdf(1e-300,
[5.0])``).
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
from scipy import integrate, optimize, stats

from .distributions import _NO_STATE, FrozenDistribution, _rng_argument
from .linalg import as_covariance, as_matrix, symmetrize
from .validation import as_finite, as_float_array, as_vector

__all__ = [
    "QuadraticForm",
    "WeightedChiSquare",
    "imhof_cdf",
    "imhof_sf",
    "inversion_integrands",
    "liu_tang_zhang_cdf",
    "liu_tang_zhang_sf",
]

#: Default absolute and relative tolerances of :func:`imhof_cdf`.  The
#: relative one applies to the smaller tail, which is computed directly, so
#: both ``cdf`` and ``sf`` are accurate to about ``RTOL`` absolutely and the
#: small one also relatively.
ATOL = 0.0
RTOL = 1e-10

# Weights closer than this (relative to the largest) are merged into one
# chi-square term: the law changes by far less than the tolerance.
_MERGE_RTOL = 1e-12
# Eigenvalues below this fraction of the largest are treated as zero.
_ZERO_RTOL = 1e-12
# Work arrays (points x nodes x weights) are processed in chunks of at most
# this many entries.
_CHUNK = 1_000_000
# Step halvings after the first two trapezoid levels, and Newton steps.
_MAX_HALVINGS = 6
_MAX_NEWTON = 100
# Truncation points beyond this (cosh(60) ~ 6e25) mean no convergence.
_U_MAX = 60.0
# inversion_integrands draws the contour integrand up to this u (0 beyond: see there).
_U_DRAWN = 700.0
# The vertex is accepted when |phi'| phi''^{-1/2} is below this (see _saddle).
_SADDLE_TOL = 0.3
# Smallest opening a/b of the hyperbola (see _plan).
_MIN_OPENING = 0.3
# Where the integrand on the path exceeds _BLOWUP times its vertex value, a
# small positive weight's drift outgrows exp(-s x) on the right (a noncentral
# term w chi2(h, d) grows like exp(d w s) for |s| << 1/w): such points take a
# nearly vertical path, opening _SAFE_OPENING, where that factor stays bounded.
_BLOWUP = 1e3
_SAFE_OPENING = 0.02
# Coarse trapezoid step times log(1/rtol), and its largest value (see _plan).
_STEP_CONSTANT = 3.5
_MAX_STEP = 0.5
# Below exp(-760) a probability is 0 in double precision.
_LOG_UNDERFLOW = -760.0
# Beyond this many degrees of freedom (or this noncentrality) in one term the
# integrals are centred at the mean (see _Side.linear): the factors' logarithms
# otherwise lose ~eps h of the exponent (errors of 1e-8 at dof 1e8).
_CENTRED_DOF = 1e4
# Beyond this the law is normal to double precision (skewness below 1e-100) and the
# sums of its cumulants approach the largest double: the normal limit is used.
_NORMAL_DOF = 1e200
# Chi-square terms this small beside a normal term are dropped (see _normalised).
_NEGLIGIBLE = 1e-17
# Below x sum((h + d)/(4w)) = _NEAR_ZERO (k + 1) a positive form's CDF is
# its leading term at 0 to double precision (see _near_zero).
_NEAR_ZERO = 1e-17
# Relative tolerances below this cannot be met in double precision.
_MIN_RTOL = 1e-15
# Beyond this many factors the integrand takes logarithms in real arithmetic.
_COMPLEX_LOG_SIZE = 2000
# Constants of _plan's bounds: sqrt(2 pi); the share of the tolerance left to
# the truncation (log 0.01); log of sqrt(2)/pi (rounded up to 1.42/pi).
_SQRT_2PI = math.sqrt(2.0 * math.pi)
_LOG_TRUNCATION_SHARE = math.log(0.01)
_LOG_SQRT2_OVER_PI = math.log(1.42 / math.pi)
_LOG2 = math.log(2.0)


# ---------------------------------------------------------------------------
# validation of the chi-square terms
# ---------------------------------------------------------------------------
def _per_term(value, name, size, default):
    """``dof`` or ``noncentrality``: one finite number for every term, or one per term."""
    if value is None:
        return np.full(size, default)
    array = as_float_array(value, name)
    if array.ndim == 0:
        return np.full(size, float(array))
    if array.ndim != 1 or array.size != size:
        raise ValueError(
            f"{name} must be one number or have the same length as weights ({size}), "
            f"got shape {array.shape}"
        )
    return array


def _terms(weights, dof, noncentrality, sigma=0.0):
    """Validate and normalise ``(weights, dof, noncentrality, sigma)``; arrays.

    Zero weights are dropped (they contribute nothing), the weights are
    sorted increasingly and equal ones merged: ``w chi2(h1, d1) + w chi2(h2,
    d2) = w chi2(h1 + h2, d1 + d2)``.  ``dof`` may be any positive real (a
    chi-square with ``h`` degrees of freedom is a Gamma(h/2, 2) variable).
    """
    w = as_vector(weights, "weights")
    r = w.size
    h = _per_term(dof, "dof", r, 1.0)
    d = _per_term(noncentrality, "noncentrality", r, 0.0)
    sigma = as_finite(sigma, "sigma", what="the standard deviation of the normal term")
    if sigma < 0:
        raise ValueError(
            f"sigma (the standard deviation of the normal term) must be >= 0, got {sigma}"
        )
    if h.min() <= 0:
        raise ValueError(f"dof (degrees of freedom) must be positive, got {h.min():g}")
    if d.min() < 0:
        raise ValueError(f"noncentrality must be non-negative (squared means), got {d.min():g}")
    keep = w != 0
    w, h, d = w[keep], h[keep], d[keep]
    order = np.argsort(w, kind="stable")
    w, h, d = w[order], h[order], d[order]
    if w.size > 1:
        scale = max(-w[0], w[-1])
        breaks = np.flatnonzero(np.diff(w) > _MERGE_RTOL * scale) + 1
        if breaks.size < w.size - 1:
            members = np.split(np.arange(w.size), breaks)
            # the mean of a group as its first weight plus the mean offset: w h would
            # overflow for weights near the largest double
            w = np.array([w[g[0]] + np.average(w[g] - w[g[0]], weights=h[g]) for g in members])
            h = np.array([h[g].sum() for g in members])
            d = np.array([d[g].sum() for g in members])
    return w, h, d, sigma


def _term_constants(w, h, d):
    """Per-term summands of the constants of :class:`_Side`.

    ``d/2``; ``h/2`` (k); ``w (h + d)`` (mean); ``2 w^2 (h + 2d)`` (variance);
    ``-h/2 log(2|w|) - d/4`` (log D of the truncation bound, see :func:`_plan`);
    ``d/(4w)``, ``(h + d)/(4w)`` and ``-h/2 log(2w)`` (positive weights only:
    see :func:`_near_zero`).
    """
    positive = w > 0
    log_w = np.log(np.abs(w))
    quarter = 0.25 / w * positive
    return (
        0.5 * d,
        0.5 * h,
        w * (h + d),
        2.0 * w * w * (h + 2.0 * d),
        -0.5 * h * (log_w + math.log(2.0)) - 0.25 * d,
        d * quarter,
        (h + d) * quarter,
        -0.5 * h * (log_w + math.log(2.0)) * positive,
    )


def _derivative_factors(w, h, d):
    """Per-term factors of the derivatives of ``K`` (floats or arrays).

    With ``t = 1/(1 - 2 w s)``: ``K' = sum t hw + t^2 dw``,
    ``K'' = sum t^2 c2 + t^3 n2``, ``K''' = sum t^3 c3 + t^4 n3``.
    """
    hw, dw = h * w, d * w
    return 2.0 * w, hw, dw, 2.0 * w * hw, 8.0 * w * w * hw, 4.0 * w * dw, 24.0 * w * w * dw


def _two_product(a, b):
    """``a b`` as ``p + e`` exactly (Dekker's product with Veltkamp's split); arrays."""
    p = a * b

    def split(v):
        c = 134217729.0 * v  # 2^27 + 1
        high = c - (c - v)
        return high, v - high

    (ah, al), (bh, bl) = split(a), split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _log1p_minus(u):
    """``log(1 + u) - u`` for real or complex ``u``, accurate also where ``|u|`` is tiny.

    With ``v = u / (2 + u)``: ``log(1 + u) = 2 atanh v`` and ``2 v - u = -u^2 / (2 + u)``, so
    ``L(u) = -u^2/(2 + u) + 2 (v^3/3 + v^5/5 + ...)``; for ``|u| < 1/4`` (``|v| < 1/7``)
    nine terms reach double precision and nothing cancels.
    """
    small = np.abs(u) < 0.25
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        out = np.log1p(u) - u
        if small.any():
            us = u[small]
            v = us / (2.0 + us)
            v2 = v * v
            series = 1.0 / 19.0
            for n in range(17, 1, -2):
                series = series * v2 + 1.0 / n
            out[small] = 2.0 * v * v2 * series - us * us / (2.0 + us)
    return out


# ---------------------------------------------------------------------------
# the normalised terms of one tail
# ---------------------------------------------------------------------------
class _Side:
    """Terms of ``X = sum w chi2(h, d) + N(0, sigma2)`` scaled to ``max(|w|, sigma) = 1``.

    The laws are scale-invariant, ``P(Q <= c) = P(Q/m <= c/m)``, so every
    integral is done on the normalised law: whatever the user's units
    (weights of 1e-300 or 1e300 alike), the saddle point, the path and the
    integrand stay near unit size.  ``w`` is sorted increasingly and holds no
    two equal weights.  Holds the constants the contour integral needs.
    """

    def __init__(self, w, h, d, sigma2, centred=False):
        self.sigma2 = sigma2
        self.r = r = w.size
        self.w, self.h, self.d = w, h, d
        sums = [float(np.sum(column)) for column in _term_constants(w, h, d)]
        (w_first, w_last), (_, h_last), (_, d_last) = (
            [(float(v[0]), float(v[-1])) for v in (w, h, d)] if r else [(0.0, 0.0)] * 3
        )
        smallest = float(np.min(np.abs(w))) if r else 1.0
        positive = w_last > 0
        self.s_max = 0.5 / w_last if positive else math.inf
        self.s_min = 0.5 / w_first if w_first < 0 else -math.inf
        # the largest weight's term: it dominates the far upper tail
        self.top = (w_last, h_last, d_last) if positive else None
        self.positive_form = bool(r and w_first > 0 and not sigma2)
        # Im s beyond which every |1 - 2 w s| >= 1, and log of D = prod
        # (2|w|)^(-h/2) exp(-sum d/4): |M(s)| <= D Y^-k with Y = Im s, once
        # every |1 - 2 w s| >= 2 (Y >= 2 y_unit) when noncentral (see _plan)
        self.y_unit = 0.5 / smallest if r else 0.0
        half_d, self.k, self.mean, var, self.log_d_y, d_over_w, zero_slope, log_c = sums
        self.half_d_sum = half_d
        # huge dof: K(s) - s mean and x - mean are computed without the mean
        # itself (see linear, derivatives, cgf, _integrand); the mean as an
        # unevaluated sum mean + mean_low of exact products
        self.huge = bool(r and float(np.max(h + d)) > _CENTRED_DOF)
        self.centred = centred
        self.mean_low = 0.0
        if self.centred:
            parts = np.concatenate([*_two_product(w, h), *_two_product(w, d)]).tolist()
            self.mean = math.fsum(parts)
            self.mean_low = math.fsum([*parts, -self.mean])
        self.noncentral = half_d > 0
        self.var = var + sigma2
        # for the bound on the lower-tail saddle of a positive form
        self.d_over_w = d_over_w if self.noncentral and w_first > 0 else 0.0
        # P(X <= x) ~ C x^k / Gamma(k+1) near 0 for a positive form (see _near_zero)
        self.zero_slope = zero_slope
        self.log_c0 = log_c - half_d - math.lgamma(self.k + 1.0)
        # rows of the path matrix (see _path_coefficients)
        self.rows_of_path = (2 * r if self.noncentral else r) + 3
        # weights W of the rows of the path matrix in the exponent (see _integrand):
        # log z_r: -h_r/2; 1/z_r: d_r/2 (noncentral laws only); the linear part: 1
        parts = [-0.5 * h, 0.5 * d] if self.noncentral else [-0.5 * h]
        self.exponent_weights = np.concatenate(parts + [[1.0]]).astype(complex)
        self.w2 = 2.0 * w
        self.minus_w2 = -self.w2
        # per-term factors of the derivatives of K
        self.factors = _derivative_factors(w, h, d)

    @classmethod
    def mirrored(cls, w, h, d, sigma2):
        """The side of ``-X``: weights negated, kept in increasing order."""
        return cls(-w[::-1], h[::-1], d[::-1], sigma2)

    @functools.cached_property
    def twin(self):
        """The centred :class:`_Side` of the same terms (for a law of huge dof)."""
        return _Side(self.w, self.h, self.d, self.sigma2, centred=True)

    def groups(self, x):
        """``(upper, mask, side)``: the points above and below the mean, and the side for each.

        With huge dof (:attr:`huge`) points near the mean, where ``|2 w s0| <
        1/4`` for every weight (``|x - mean| <= var/4`` at unit weights), take
        the centred twin; farther out ``log z`` itself loses nothing, while
        centring would cancel ``h w s`` against ``s mean``.
        """
        if not self.huge:
            upper = x > self.mean
            return [(True, upper, self), (False, ~upper, self)]
        delta = self.twin.linear(x)
        near = np.abs(delta) <= 0.25 * self.var
        upper = delta > 0
        return [
            (True, upper & near, self.twin),
            (False, ~upper & near, self.twin),
            (True, upper & ~near, self),
            (False, ~upper & ~near, self),
        ]

    def linear(self, x):
        """The coefficient of ``-s`` in the exponent: ``x``, or ``x - mean`` when centred."""
        if not self.centred:
            return x
        return (x - self.mean) - self.mean_low

    # -- the cumulant generating function K(s) = log M(s) ---------------------
    def derivatives(self, s, x, pole):
        """``phi'``, ``phi''``, ``phi'''`` of ``phi(s) = K(s) - s x [- log|s|]``, s of shape (n,)."""
        _, hw, dw, c2, c3, n2, n3 = self.factors
        ws = np.multiply.outer(s, self.w2)
        t = 1.0 / (1.0 - ws)
        t2 = t * t
        if self.centred:
            # K' - x as sum h w (t - 1) + d w (t^2 - 1) - (x - mean), t - 1 = 2 w s t:
            # no large terms cancel
            t_minus_1 = ws * t
            g1 = t_minus_1 @ hw + (self.sigma2 * s - self.linear(x))
            if self.noncentral:
                g1 = g1 + (t_minus_1 * (t + 1.0)) @ dw
        else:
            g1 = t @ hw + (self.sigma2 * s - x)
        g2 = t2 @ c2 + self.sigma2
        g3 = (t2 * t) @ c3
        if self.noncentral:
            if not self.centred:
                g1 = g1 + t2 @ dw
            g2 = g2 + (t2 * t) @ n2
            g3 = g3 + (t2 * t2) @ n3
        if pole:
            inv = 1.0 / s
            g1 = g1 - inv
            g2 = g2 + inv * inv
            g3 = g3 - 2.0 * inv * inv * inv
        return g1, g2, g3

    def cgf(self, s):
        """``K(s)`` at real ``s`` of shape (n,) inside the interval of convergence.

        Centred (huge dof): ``K(s) - s mean`` as ``sum -h/2 L(u) + d/2
        u^2/(1 + u)`` with ``u = -2 w s`` and ``L(u) = log(1 + u) - u``.
        """
        if self.centred:
            u = np.multiply.outer(s, -self.w2)
            value = _log1p_minus(u) @ (-0.5 * self.h) + 0.5 * self.sigma2 * s * s
            if self.noncentral:
                value = value + (u * u / (1.0 + u)) @ (0.5 * self.d)
            return value
        z = 1.0 - np.multiply.outer(s, self.w2)
        value = np.log(z) @ (-0.5 * self.h) + 0.5 * self.sigma2 * s * s
        if self.noncentral:
            value = value + (1.0 / z - 1.0) @ (0.5 * self.d)
        return value

    # -- where the saddle point lies ------------------------------------------
    def bracket(self, x, upper):
        """Finite ``(lo, hi)`` holding the saddle of ``phi`` (with or without the pole) and a guess.

        Upper tail: ``(0, s_max)``; lower tail: ``(s_min, 0)``.  Infinite ends
        are replaced by bounds from ``K'`` (see the comments); the guess is the
        saddle of a Gaussian model of ``K``, or of the dominant term alone in
        the far upper tail, or of the behaviour at ``-inf`` far below a
        positive form.
        """
        dx = self.linear(x) if self.centred else x - self.mean
        root = np.sqrt(dx * dx + 4.0 * self.var)
        if upper:
            # Gaussian model K'(s) = mean + var s: var s^2 - (x - mean) s - 1 = 0
            guess = 2.0 / (root - dx)
            lo = 0.0 * x
            if self.top is not None:
                hi = self.s_max + lo
                w, h, d = self.top
                # h w / t + d w / t^2 = x with t = 1 - 2 s w (the top term alone)
                t = (h * w + np.sqrt((h * w) ** 2 + 4.0 * d * w * x)) / (
                    2.0 * np.maximum(x, 1e-300)
                )
                guess = np.where(t < 1.0, np.minimum(guess, self.s_max * (1.0 - t)), guess)
            else:
                # no positive weight, a normal term: K'(s) >= mean, so phi' > 0
                # beyond the root of sigma2 s^2 - (x - mean) s - 1
                hi = (dx + np.sqrt(dx * dx + 4.0 * self.sigma2)) / (2.0 * self.sigma2)
            return lo, hi, guess
        guess = -2.0 / (root + dx)
        hi = 0.0 * x
        if math.isfinite(self.s_min):
            return self.s_min + hi, hi, guess
        # a positive form: K'(s) <= k/|s| + sum d/(4 w s^2) for s < 0, so phi' < 0
        # left of the root of that bound + 1/|s| = x; with a normal term also
        # left of -sqrt((k + 1)/sigma2)
        k1 = self.k + 1.0
        bound = (k1 + np.sqrt(k1 * k1 + 4.0 * self.d_over_w * x)) / (2.0 * np.maximum(x, 1e-300))
        if self.sigma2:
            bound = np.minimum(bound, math.sqrt(k1 / self.sigma2))
        # far below the weights the bound is the saddle itself; nearer the mean
        # Newton starts at the geometric mean of it and the Gaussian guess (on
        # Davies' points and random positive forms, a fifth to a third fewer steps)
        far_below = x * self.k < 0.1 * self.mean
        return -bound, hi, np.where(far_below, -bound, -np.sqrt(bound * -guess))


def _saddle(x, side, upper, pole):
    """Vertex ``s0`` near the real saddle of ``phi``, with ``phi''`` and ``phi'''`` there.

    ``phi`` is convex on the bracket, so ``phi'`` increases: Newton steps
    safeguarded by bisection (in the logit of ``s`` over the far end, so that
    roots near either singular end are reached in a few steps).  The saddle
    only has to be approximate, ``|phi'| phi''^{-1/2} < 0.3``: any vertex in the
    interval gives the same integral.
    """
    lo, hi, guess = side.bracket(x, upper)
    lo, hi = np.broadcast_to(lo, x.shape).copy(), np.broadcast_to(hi, x.shape).copy()
    width = hi - lo
    s = np.clip(guess, lo + 1e-9 * width, hi - 1e-9 * width)
    g1, g2, g3 = side.derivatives(s, x, pole)
    # Newton steps on the points not yet close enough (the others keep theirs)
    active = np.flatnonzero(np.abs(g1) > _SADDLE_TOL * np.sqrt(g2))
    for _ in range(_MAX_NEWTON):
        if active.size == 0:
            break
        i = active
        right = g1[i] > 0
        hi[i] = np.where(right, s[i], hi[i])
        lo[i] = np.where(right, lo[i], s[i])
        newton = s[i] - g1[i] / g2[i]
        inside = (newton > lo[i]) & (newton < hi[i])
        s[i] = newton if inside.all() else np.where(inside, newton, _bisect(lo[i], hi[i]))
        g1[i], g2[i], g3[i] = side.derivatives(s[i], x[i], pole)
        active = i[np.abs(g1[i]) > _SADDLE_TOL * np.sqrt(g2[i])]
    return s, g2, g3


def _bisect(lo, hi):
    """Midpoint of ``(lo, hi)`` in the logit of ``s / far end`` (or plain, across 0)."""
    far = np.where(np.abs(lo) > np.abs(hi), lo, hi)
    with np.errstate(divide="ignore", invalid="ignore"):
        p = np.clip(np.stack([lo, hi]) / far, 1e-16, 1.0 - 1e-16)
        y = np.log(p) - np.log1p(-p)
        mid = far / (1.0 + np.exp(-0.5 * (y[0] + y[1])))
    return np.where(lo * hi >= 0, mid, 0.5 * (lo + hi))


# ---------------------------------------------------------------------------
# the contour integral
# ---------------------------------------------------------------------------


def _plan(x, side, upper, pole, atol, rtol, s0, g2, g3, k0, opening=None):
    """Path, scale, truncation point and step of the contour integral at ``x``.

    Returns ``(a, b, e0, log_tol, U, step)``: the hyperbola's half-widths;
    ``E0 = K(s0) - s0 x`` (the integrand is computed as ``exp(E - E0)``, so
    that tails down to 1e-300 neither underflow nor lose digits); the log of
    the absolute tolerance on that scaled integral; the truncation point
    ``U``; the trapezoid step of the coarse level.

    Truncation (the analogue of Imhof's (1961) bound ``T_U``), in ``Y = Im
    s = b sinh u``: every factor obeys ``|1 - 2 w s| >= 2 |w| Y`` (its
    imaginary part), so ``|M(s)| <= D Y^{-k}`` with ``D = prod (2|w|)^{-h/2}
    exp(-sum d/4)`` once every noncentral factor ``exp(d/2 (Re(1/z) - 1))`` is
    at most ``exp(-d/4)`` (``|z| = |1 - 2 w s| >= 2``, i.e. ``Y >= 1/min|w|``)
    and the normal factor at most one (``Im s >= Re s``).
    With ``|s'| <= sqrt(2) dY/du`` and ``|s| >= Y`` the neglected integral
    is below ``sqrt(2) D int_Y^inf t^{-k-e} |exp(-s x)| dt / pi`` (``e = 1``
    with the pole), which is below ``sqrt(2) D Y^{1-k-e} / ((k+e-1) pi)``
    where ``Re s >= 0`` and, for ``x > 0`` (``Re s >= s0 - a + (a/b) Y``), below ``sqrt(2) D
    Y^{-k-e} exp(-(s0 - a) x - (a/b) x Y) / ((a/b) x pi)`` for ``Y >= 1``.
    (The older bound in ``Re s`` used ``|1 - 2 w s| >= |w| Re s``, true only
    beyond ``1/w`` for *every* positive weight: with a small positive weight
    of large noncentrality it truncated a live integrand.)

    Step: the trapezoidal rule on an integrand analytic in a strip of
    half-width ``delta`` around the real ``u`` axis errs by about ``exp(-2 pi
    delta / step)``.  In the normalised variable ``u`` (the saddle has unit
    width) ``delta`` is of order one, so the coarse step is
    ``_STEP_CONSTANT / log(1/rtol)``: measured on Davies' 39 points, it is
    small enough for the coarse level to meet ``rtol`` at most points (the
    fine level, half the step, then agrees with it within ``rtol`` and is
    accepted); elsewhere the step is halved.
    """
    b = 1.0 / np.sqrt(g2)
    if opening is None:
        ratio = np.minimum(
            np.maximum(np.abs(g3) * b**3 / 3.0, _MIN_OPENING), 0.5 if side.sigma2 else 1.0
        )
    else:
        ratio = opening + 0.0 * b
    a = ratio * b
    e0 = k0 - s0 * side.linear(x)
    vertex = b / np.abs(s0) if pole else b
    log_tol = (math.log(rtol * _SQRT_2PI) if rtol else -math.inf) + np.log(vertex)
    if atol > 0:
        log_tol = np.maximum(log_tol, math.log(atol * math.pi) - e0)
    # -- truncation (bounds in Y = Im s = b sinh u: see the docstring) ------------
    k_e = side.k + (1.0 if pole else 0.0)
    log_tol_t = log_tol + _LOG_TRUNCATION_SHARE
    # |s'| <= sqrt(2) dY/du (a <= b) and |s| >= Y
    log_rhs = side.log_d_y + _LOG_SQRT2_OVER_PI - e0 - log_tol_t
    # Re s >= s0 - a + (a/b) Y: beyond y_positive, Re s >= 0 and |exp(-s x)| <= 1
    y_positive = np.maximum(a - s0, 0.0) / ratio
    log_y_need = 700.0
    if k_e > 1:
        log_y_need = np.minimum((log_rhs - math.log(k_e - 1.0)) / (k_e - 1.0), 700.0)
    algebraic = np.maximum(np.exp(log_y_need), y_positive)
    # with x > 0, exp(-s x) decays like exp(-lam Y)
    lam = np.maximum(ratio * x, 1e-300)
    decay = np.maximum(log_rhs - np.log(lam) + (a - s0) * x, 0.0) / lam
    y_need = np.maximum(np.minimum(algebraic, decay), 1.0)
    if side.noncentral:
        y_need = np.maximum(y_need, 2.0 * side.y_unit)
    if side.sigma2:
        # the bounds above need Im s >= Re s (then |exp(sigma2 s^2/2)| <= 1); the
        # normal factor gives another: with Y >= 4 (a + |s0|) and >= 1/(2 min|w|),
        # and Re s >= 0, every |1 - 2 w s| >= 1 so |M| <= 1,
        # |exp(sigma2 s^2/2)| <= exp(-7 sigma2 Y^2/32) and the tail beyond U is
        # below exp(-c Y^2)/(c Y^2), c = 7 sigma2/32
        y_need = np.maximum(y_need, b * np.sinh(np.log(4.0 * np.abs(s0) / b + 3.0)))
        c = 7.0 * side.sigma2 / 32.0
        y_normal = np.maximum(np.maximum(2.0 - e0 - log_tol_t, 1.0) / c, 0.0) ** 0.5
        y_normal = np.maximum(np.maximum(y_normal, 4.0 * (a + np.abs(s0))), side.y_unit)
        q = 1.0 + np.maximum(-s0, 0.0) / a
        y_normal = np.maximum(y_normal, b * np.sqrt(q * q - 1.0))
        y_need = np.minimum(y_need, y_normal)
    ratio_y = y_need / b
    U = np.maximum(np.log(ratio_y + np.sqrt(ratio_y * ratio_y + 1.0)), 1.0)
    # -- step (the same for every point: see the docstring) ----------------------
    step = min(_STEP_CONSTANT / -math.log(max(rtol, 1e-16)), _MAX_STEP)
    return a, b, e0, log_tol, U, step


@functools.lru_cache(maxsize=64)
def _nodes(step, count, odd):
    """``u`` and the complex rows ``(1, cosh u - 1, sinh u)`` at ``u = step j`` (j < count) or ``step (2j + 1)``."""
    u = np.arange(1.0, 2.0 * count, 2.0) if odd else np.arange(float(count))
    u *= step
    # filled in place: a few ufunc calls, no stacking (one point's nodes cost ~10 us)
    basis = np.zeros((3, count), dtype=complex)
    real = basis.real
    real[0] = 1.0
    np.cosh(u, out=real[1])
    real[1] -= 1.0
    np.sinh(u, out=real[2])
    return u, basis


def _path_coefficients(x, side, s0, a, b, k0):
    """Coefficients of the path quantities in the basis ``(1, cosh u - 1, sinh u)``.

    On the hyperbola ``s = s0 + a(cosh u - 1) + i b sinh u`` every factor
    ``z_r = 1 - 2 w_r s``, the linear part ``-(s - s0) x - K(s0) [- sum
    d/2]`` of ``E - E0``, ``s'(u) = a sinh u + i b cosh u`` and ``s`` itself
    are linear in ``(1, cosh u - 1, sinh u)``: one matrix product of these
    coefficients with the nodes' basis gives them all.  Rows: ``z_1 .. z_r``
    (their logarithms), ``z_1 .. z_r`` again for the noncentral terms (their
    reciprocals), the linear part, ``s'``, ``s``.  Returns the matrix and the
    weights of its rows in the exponent (:attr:`_Side.exponent_weights`);
    the matrix has one block per point, ``(points, rows, 3)``.
    """
    ib = 1j * b
    # the noncentral terms' -d/2 (0 when central; centred, K(s0) holds it)
    c0 = k0 if side.centred else k0 + side.half_d_sum
    x = side.linear(x)
    path = np.stack(np.broadcast_arrays(s0, a, ib), axis=-1)
    r = side.r
    coef = np.empty(path.shape[:-1] + (side.rows_of_path, 3), dtype=complex)
    np.multiply(side.minus_w2[:, None], path[..., None, :], out=coef[..., :r, :])
    if not side.centred:  # (centred: the rows hold u = z - 1, see _integrand)
        coef[..., :r, 0] += 1.0
    if side.noncentral:
        coef[..., r : 2 * r, :] = coef[..., :r, :]
    coef[..., -3, :] = np.stack(np.broadcast_arrays(-c0, -x * a, -x * ib), axis=-1)
    coef[..., -2, :] = np.stack(np.broadcast_arrays(ib, ib, a), axis=-1)
    coef[..., -1, :] = path
    return coef, side.exponent_weights


def _integrand(basis, coef, side, pole):
    """``Im[exp(E(s) - E0) s'(u) [/ s]]`` on the hyperbola, from :func:`_path_coefficients`.

    ``coef`` is what :func:`_path_coefficients` returns (matrix, weights).

    ``s(u) = s0 + a(cosh u - 1) + i b sinh u``, ``E(s) = K(s) - s x``;
    ``basis`` holds the rows ``1, cosh u - 1, sinh u`` of the nodes; the
    result has shape (points, nodes).  The exponent is one
    product ``W . [log z, 1/z, linear]`` with the weights ``W = (-h/2, d/2,
    1)`` of :attr:`_Side.exponent_weights`: about ten numpy calls whatever the
    number of terms (on the few dozen nodes of one point their overhead, and
    the complex logarithms, are the cost).  ``Im z = -2 w Im s`` keeps every
    ``log z`` off its cut along the path; ``E - E0`` is built from ``s -
    s0`` (the coefficients), so no digits cancel when ``s0 x`` is large.
    """
    r = side.r
    matrix, weights = coef
    path = matrix @ basis
    # the rows along the first axis: plain first-axis indexing is cheaper than path[..., i, :]
    rows = path.transpose(1, 0, 2)
    logs = rows[:r]
    if side.centred:
        # u = z - 1: -h/2 log z + d/2 (1/z - 1) = -h/2 L(u) + d/2 u^2/(1 + u) + mean s
        if side.noncentral:
            u = rows[r : 2 * r]
            u *= u / (1.0 + u)
        logs[...] = _log1p_minus(logs)
    elif logs.size > _COMPLEX_LOG_SIZE:
        # numpy's complex log costs ~100 ns a value, this real split ~45
        angle = np.arctan2(logs.imag, logs.real)
        logs.real = np.log(np.abs(logs))
        logs.imag = angle
    else:
        np.log(logs, out=logs)
    if side.noncentral and not side.centred:
        inverse = rows[r : 2 * r]
        np.reciprocal(inverse, out=inverse)
    e = weights @ path[..., :-2, :]
    s = rows[-1]
    if side.sigma2:
        # k0 = K(s0) holds sigma2 s0^2 / 2
        e += (0.5 * side.sigma2) * (s * s)
    # where a drift outgrows exp(-s x) the values are huge (capped below the
    # overflow): the callers see them above _BLOWUP and take a nearly
    # vertical path instead
    real = e.real
    np.minimum(real, 600.0, out=real)
    value = np.exp(e, out=e)
    value *= rows[-2]
    if pole:
        value /= s
    return value.imag


def _integrate(x, side, pole, s0, a, b, k0, e0, log_tol, U, step, rtol):
    """``(1/pi) int_0^U Im[...] du`` by the trapezoidal rule; (value, error, converged).

    One evaluation at the fine step gives two levels (the coarse one from
    every other node).  Their difference, the error estimate, bounds the
    coarse level's error and so (the rule converges geometrically) the fine
    level's; points where it exceeds ``max(atol, rtol |I|)`` get the step
    halved (new nodes only).
    Returns ``exp(E0)`` times the integral: ``P(X > x)`` on an upper path,
    ``-P(X <= x)`` on a lower one (the residue at the pole is 1), the density
    without the pole.
    """
    error = np.zeros(x.shape)
    converged = U <= _U_MAX
    U = np.minimum(U, _U_MAX)
    h = 0.5 * step
    n = math.ceil(float(np.max(U)) / h)
    nodes = _nodes(h, n + 1, False)
    total = np.empty(x.shape)
    coarse = np.empty(x.shape)
    blown = np.zeros(x.shape, dtype=bool)
    # chunks over x keep the (points, nodes, weights) work arrays small
    size = max(1, _CHUNK // ((n + 1) * max(side.r, 1)))
    for start in range(0, x.size, size):
        i = slice(start, start + size)
        coef = _path_coefficients(x[i], side, s0[i], a[i], b[i], k0[i])
        f = _integrand(nodes[1], coef, side, pole)
        f *= nodes[0] <= U[i, None]
        blown[i] = ~(np.abs(f).max(axis=1) <= _BLOWUP * np.abs(f[:, 0]))
        f[:, 0] *= 0.5
        total[i] = h * f.sum(axis=1)
        coarse[i] = 2.0 * h * f[:, ::2].sum(axis=1)
    tol = np.exp(log_tol)
    active = np.flatnonzero(~blown)
    diff = np.abs(total - coarse)
    for level in range(_MAX_HALVINGS + 1):
        j = active
        estimate = diff[j]
        error[j] = estimate
        done = estimate <= np.maximum(tol[j], rtol * np.abs(total[j]))
        active = j[~done]
        if active.size == 0 or level == _MAX_HALVINGS:
            break
        j = active
        h *= 0.5
        nodes = _nodes(h, n, True)
        n *= 2
        coef = _path_coefficients(x[j], side, s0[j], a[j], b[j], k0[j])
        f = _integrand(nodes[1], coef, side, pole)
        f *= nodes[0] <= U[j, None]
        refined = 0.5 * total[j] + h * f.sum(axis=1)
        diff[j] = np.abs(refined - total[j])
        total[j] = refined
    converged[active] = False
    # exp(E0) |total| / pi without overflow or underflow in between
    with np.errstate(divide="ignore"):
        log_size = e0 + np.log(np.abs(total) / math.pi)
        log_error = e0 + np.log(error / math.pi)
    return np.sign(total) * np.exp(log_size), np.exp(log_error), converged, blown


def _contour(x, side, upper, pole, atol, rtol, opening=None):
    """The contour integral at the points ``x`` (1-D) of one side; (value, error, converged)."""
    # far out (x near the largest double) intermediate squares overflow to inf
    # harmlessly: those points end as tails below the smallest double
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        s0, g2, g3 = _saddle(x, side, upper, pole)
        k0 = side.cgf(s0)
        plan = _plan(x, side, upper, pole, atol, rtol, s0, g2, g3, k0, opening)
    a, b, e0, log_tol, U, step = plan
    # tails far below the smallest double: the best answer is 0
    vertex = b / np.abs(s0) if pole else b
    live = e0 + np.log(vertex) > _LOG_UNDERFLOW
    value, error = np.zeros(x.shape), np.zeros(x.shape)
    converged = np.ones(x.shape, dtype=bool)
    blown = np.zeros(x.shape, dtype=bool)
    if live.any():
        i = np.flatnonzero(live)
        value[i], error[i], converged[i], blown[i] = _integrate(
            x[i], side, pole, s0[i], a[i], b[i], k0[i], e0[i], log_tol[i], U[i], step, rtol
        )
    if blown.any():
        i = np.flatnonzero(blown)
        if opening is None:
            value[i], error[i], converged[i] = _contour(
                x[i], side, upper, pole, atol, rtol, _SAFE_OPENING
            )
        else:
            converged[i] = False
            error[i] = np.inf
    return value, error, converged


def _probabilities(x, w, h, d, sigma, atol, rtol, sides=None):
    """``P(X > x)`` and ``P(X <= x)``, the smaller of the two computed directly.

    Returns (sf, cdf, error, converged) for the points ``x`` (1-D).  The law
    is first scaled to ``max(|w|, sigma) = 1`` (:func:`_normalised`).  Points
    x >= 0 use X, points x < 0 the mirrored variable -X (``P(X <= x) = P(-X
    >= -x)`` for a continuous law), so the contour always opens where
    ``exp(-s x)`` decays; above the mean the upper tail is integrated, below
    it the lower one.  ``sides`` caches the normalised terms of a law.
    """
    if sides is None:
        sides = {}
    m, normal = _normalised(sides, w, h, d, sigma)
    with np.errstate(over="ignore", under="ignore"):
        x = x / m
    if normal:
        return stats.norm.sf(x), stats.norm.cdf(x), np.zeros(x.shape), np.ones(x.shape, bool)
    if sides["limit"] is not None:
        z = _standardised(x, sides["limit"])
        return stats.norm.sf(z), stats.norm.cdf(z), np.zeros(x.shape), np.ones(x.shape, bool)
    sf, cdf = np.empty(x.shape), np.empty(x.shape)
    err = np.zeros(x.shape)
    conv = np.ones(x.shape, dtype=bool)
    for sign, mask in ((1.0, x >= 0), (-1.0, x < 0)):
        if not mask.any():
            continue
        side = _side(sides, sign)
        xs = sign * x[mask]
        # P(X > xs), P(X <= xs): with no positive weight and no normal term X <= 0 <= xs
        up, low = np.zeros(xs.shape), np.ones(xs.shape)
        e, ok = np.zeros(xs.shape), np.ones(xs.shape, dtype=bool)
        todo = np.isfinite(xs)
        if side.top is None and not side.sigma2:
            todo[:] = False
        elif side.positive_form:
            # a positive form: P(X <= 0) = 0, and far below the weights a closed form
            near, tiny = _near_zero(xs, side)
            zero = xs <= 0
            up[zero], low[zero] = 1.0, 0.0
            low[tiny], up[tiny] = near[tiny], 1.0 - near[tiny]
            todo &= ~zero & ~tiny
        for is_upper, group, part in side.groups(xs):
            m_ = todo & group
            if m_.any():
                v, e[m_], ok[m_] = _contour(xs[m_], part, is_upper, True, atol, rtol)
                v = np.clip(v if is_upper else -v, 0.0, 1.0) + 0.0  # (no -0.0)
                up[m_], low[m_] = (v, 1.0 - v) if is_upper else (1.0 - v, v)
        if sign > 0:
            sf[mask], cdf[mask] = up, low
        else:
            cdf[mask], sf[mask] = up, low
        err[mask], conv[mask] = e, ok
    return sf, cdf, err, conv


def _normalised(sides, w, h, d, sigma):
    """Scale ``m = max(|w|, sigma)`` of the law, and whether it is normal to double precision.

    Stores the normalised terms in ``sides`` (built once per law).  Beside a
    normal term, chi-square terms with ``|w| (h + d + 1) <= 1e-17 sigma``
    move neither the mean, the spread nor (before both tails are far below
    the smallest double) the tails: they are dropped, so that a weight of
    1e-300 next to a unit normal term costs nothing.
    """
    terms = sides.get("terms")
    if terms is None:
        m = max(-float(w[0]), float(w[-1]), sigma) if w.size else sigma
        sigma = sigma / m
        w = w / m
        if sigma and w.size:
            keep = np.abs(w) * (h + d + 1.0) > _NEGLIGIBLE * sigma
            w, h, d = w[keep], h[keep], d[keep]
        terms = sides["terms"] = (m, w, h, d, sigma * sigma)
        sides["limit"] = _normal_limit(w, h, d, sigma) if w.size else None
    return terms[0], len(terms[1]) == 0


def _normal_limit(w, h, d, sigma):
    """``(H, mean/H, its low part, sd)`` where the law is normal to double precision, else None.

    Beyond ``_NORMAL_DOF`` degrees of freedom in a term the skewness, about
    ``sqrt(8/k)``, is below 1e-100, and the cumulants' sums approach the largest
    double: they are taken on ``h/H`` and ``d/H`` (``H`` a power of two, so
    exactly), the mean as an unevaluated sum of exact products.
    """
    largest = float(np.max(h + d))
    if largest <= _NORMAL_DOF:
        return None
    H = 2.0 ** (math.frexp(largest)[1] - 1)
    hs, ds = h / H, d / H
    parts = np.concatenate([*_two_product(w, hs), *_two_product(w, ds)]).tolist()
    mean = math.fsum(parts)
    var = float(2.0 * (w * w) @ (hs + 2.0 * ds)) + sigma * sigma / H
    return H, mean, math.fsum([*parts, -mean]), math.sqrt(H) * math.sqrt(var)


def _standardised(x, limit):
    """``(x - mean) / sd`` of a law in the normal limit (:func:`_normal_limit`)."""
    H, mean, low, sd = limit
    with np.errstate(over="ignore"):
        return ((x / H - mean) - low) * (H / sd)


def _side(sides, sign):
    """The (cached) :class:`_Side` of X/m (sign 1) or -X/m (sign -1)."""
    side = sides.get(sign)
    if side is None:
        _, w, h, d, sigma2 = sides["terms"]
        side = _Side(w, h, d, sigma2) if sign > 0 else _Side.mirrored(w, h, d, sigma2)
        sides[sign] = side
    return side


def _near_zero(xs, side):
    """``P(X <= x)`` of a positive form far below its weights, and where that is exact.

    ``M(-t) = C t^{-k} (1 + sum (d - h)/(4 w t) + O(t^-2))`` as ``t -> inf``
    with ``C = prod (2w)^{-h/2} e^{-sum d/2}``, so ``P(X <= x) = C x^k /
    Gamma(k+1) (1 + O(x sum (h + d)/(4 w)))``: where the correction is below
    the double precision the leading term is the answer (computed in logs:
    ``imhof_cdf(1e-300, [5.0])`` is 8e-152, where a saddle point would
    overflow).  Returns the values and the mask where they hold.
    """
    tiny = (xs > 0) & (xs * side.zero_slope <= _NEAR_ZERO * (side.k + 1.0))
    # (evaluated at every point, used only where tiny: elsewhere it may overflow)
    with np.errstate(divide="ignore", over="ignore"):
        return np.exp(side.k * np.log(np.maximum(xs, 1e-320)) + side.log_c0), tiny


def _imhof_real_axis(x, w, h, d, sigma, atol):
    """Imhof's (1961) integral on the real axis, with his truncation bound.

    ``P(X > x) = 1/2 + (1/pi) int_0^U sin(theta(u)) / (u rho(u)) du``; ``U``
    makes Imhof's bound ``T_U`` on the neglected tail smaller than atol/2.
    A slow reference implementation (one scipy ``quad`` call per point).
    """
    k = 0.5 * np.sum(h)

    def theta(u, x0):
        return 0.5 * np.sum(h * np.arctan(w * u) + d * w * u / (1 + (w * u) ** 2)) - 0.5 * x0 * u

    def log_rho(u):
        return (
            np.sum(0.25 * h * np.log1p((w * u) ** 2) + 0.5 * d * (w * u) ** 2 / (1 + (w * u) ** 2))
            + (sigma * u) ** 2 / 8
        )

    def integrand(u, x0):
        if u == 0.0:
            return 0.5 * (np.sum(h * w + d * w) - x0)
        return math.sin(theta(u, x0)) / (u * math.exp(log_rho(u)))

    def log_bound(u):
        return -(
            math.log(math.pi * k)
            + k * math.log(u)
            + np.sum(0.5 * h * np.log(np.abs(w)))
            + 0.5 * np.sum(d * (w * u) ** 2 / (1 + (w * u) ** 2))
            + (sigma * u) ** 2 / 8
        )

    target = math.log(atol / 2)
    lo, hi = 1e-3, 1.0
    while log_bound(hi) > target:
        hi *= 2.0
        if hi > 1e12:
            raise ValueError(
                "Imhof's truncation point exceeds 1e12 for this accuracy (few degrees of "
                "freedom); use method='contour'"
            )
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if log_bound(mid) > target else (lo, mid)
    out = np.empty_like(x)
    err = np.empty_like(x)
    for i, x0 in enumerate(x):
        value, e = integrate.quad(
            integrand, 0.0, hi, args=(x0,), limit=20000, epsabs=atol / 2, epsrel=0.0
        )
        out[i] = 0.5 + value / math.pi
        err[i] = e / math.pi + atol / 2
    return np.clip(out, 0.0, 1.0), err


def _tolerances(atol, rtol):
    """Validated ``(atol, rtol)``: non-negative, not both zero, and attainable in doubles."""
    atol, rtol = as_finite(atol, "atol"), as_finite(rtol, "rtol")
    if atol < 0 or rtol < 0 or atol + rtol == 0:
        raise ValueError(f"atol and rtol must be >= 0 and not both 0, got {atol:g} and {rtol:g}")
    if 0 < rtol < _MIN_RTOL and atol < _MIN_RTOL:
        raise ValueError(
            f"rtol = {rtol:g} cannot be met in double precision; pass rtol >= {_MIN_RTOL:g}"
        )
    return atol, rtol


def _points(c):
    """The points ``c`` as a 1-D float array and their shape; NaN refused, ±inf allowed."""
    x = as_float_array(c, "c", finite=False)
    return x.ravel(), x.shape


def _evaluate(c, weights, dof, noncentrality, sigma, atol, rtol, method):
    w, h, d, sigma = _terms(weights, dof, noncentrality, sigma)
    atol, rtol = _tolerances(atol, rtol)
    x, shape = _points(c)
    if len(w) == 0 and sigma == 0:
        # every weight is zero: the form is the constant 0
        sf = (x < 0).astype(float)
        return sf.reshape(shape), (1 - sf).reshape(shape), np.zeros(shape)
    if method == "contour":
        sf, cdf, err, conv = _probabilities(x, w, h, d, sigma, atol, rtol)
        _warn_unconverged(conv, err, stacklevel=4)
    elif method == "imhof":
        if len(w) == 0:
            raise ValueError("method='imhof' needs at least one chi-square term")
        # an absolute tolerance: the real-axis integral has no relative control
        sf, err = _imhof_real_axis(x, w, h, d, sigma, atol if atol > 0 else rtol)
        if sigma == 0 and (np.all(w > 0) or np.all(w < 0)):
            # outside a one-signed support the answer is exact
            sf = np.where(w[0] * x <= 0, (w[0] > 0) * 1.0, sf)
            err = np.where(w[0] * x <= 0, 0.0, err)
        cdf = 1.0 - sf
    else:
        raise ValueError(f"method must be 'contour' or 'imhof', got {method!r}")
    return sf.reshape(shape), cdf.reshape(shape), err.reshape(shape)


def imhof_cdf(
    c,
    weights,
    dof=None,
    noncentrality=None,
    *,
    sigma=0.0,
    atol=ATOL,
    rtol=RTOL,
    method="contour",
    full_output=False,
):
    """``P(Q <= c)`` for ``Q = sum_k w_k chi2(dof_k, noncentrality_k) + sigma Z``.

    Parameters
    ----------
    c : float or array_like
        Points; the result has the same shape (vectorised).
    weights : (r,) array_like
        Weights ``w_k`` of either sign (zeros are ignored).
    dof : (r,) array_like or float, optional
        Degrees of freedom ``h_k > 0`` (ones by default; multiplicities of
        the eigenvalues of a quadratic form).
    noncentrality : (r,) array_like or float, optional
        Noncentrality parameters ``delta_k^2 >= 0`` (zeros by default).
    sigma : float, optional
        Standard deviation of an independent normal term (Davies 1980).
    atol, rtol : float, optional
        Requested absolute and relative error of the *smaller* tail
        probability (the one computed directly): the refinement stops when
        the error estimate is below ``max(atol, rtol * p_tail)``, and the
        work done follows the request (``rtol=1e-6`` takes about half the
        nodes of the default 1e-10).  ``rtol`` must be 0 or at least 1e-15
        (double precision); not both may be 0.
    method : {"contour", "imhof"}
        ``"contour"`` (default): Imhof's inversion integral on a saddle-point
        hyperbola, vectorised.  ``"imhof"``: Imhof's original real-axis
        integral with his truncation bound and ``scipy.integrate.quad`` (slow;
        a reference).
    full_output : bool
        Also return the error estimate.

    Returns
    -------
    p : float or ndarray
        ``P(Q <= c)``.
    error : float or ndarray
        Only with ``full_output``: estimated absolute error.

    Raises
    ------
    ValueError
        Weights empty, NaN or inf; mismatched lengths; non-positive dof;
        negative noncentrality or sigma; a NaN point (``c = +-inf`` is
        allowed); tolerances that are negative, both 0 or below double
        precision; an unknown method.

    Warns
    -----
    RuntimeWarning
        When the error estimate stays above the tolerance after six step
        halvings (never seen on the course's test cases).

    Notes
    -----
    Imhof (1961), section 3: with ``theta(u) = 1/2 sum[h_k atan(w_k u) +
    delta_k^2 w_k u / (1 + w_k^2 u^2)] - c u / 2`` and ``rho(u) = prod (1 +
    w_k^2 u^2)^{h_k/4} exp(1/2 sum (delta_k w_k u)^2 / (1 + w_k^2 u^2))``,

    .. math:: P(Q > c) = \\frac12 + \\frac1\\pi \\int_0^\\infty
              \\frac{\\sin\\theta(u)}{u\\,\\rho(u)}\\,du .

    This is the Gil-Pelaez inversion of the characteristic function (Baram
    1980, (3.16)) along ``s = iu/2`` in the Laplace variable.  The default
    method moves the path (Cauchy's theorem) to the hyperbola
    ``s(u) = s0 + a(cosh u - 1) + i b sinh u`` through the real saddle point
    ``s0`` of ``M(s) e^{-sc}/s`` in ``(0, 1/(2 max w))``, with ``b = a`` the
    saddle's width, giving ``P(Q > c) = (1/pi) int_0^inf Im[M(s) e^{-sc}
    s'(u)/s] du``.  Upper tails (``c >= 0``) use ``Q``, lower tails the
    mirrored form ``-Q``, so small tail probabilities keep their relative
    accuracy.  See the module docstring for the error control.

    Examples
    --------
    Davies' (1980) first test case, ``6 chi2_1 + 3 chi2_1 + chi2_1``:

    >>> import numpy as np
    >>> from course.quadform import imhof_cdf
    >>> round(float(imhof_cdf(7.0, [6, 3, 1])), 10)
    0.4935617665
    >>> np.round(imhof_cdf([1.0, 7.0, 20.0], [6, 3, 1], rtol=1e-6), 6)
    array([0.054214, 0.493562, 0.876041])
    """
    _sf, cdf, err = _evaluate(c, weights, dof, noncentrality, sigma, atol, rtol, method)
    return (_squeeze(cdf), _squeeze(err)) if full_output else _squeeze(cdf)


def imhof_sf(
    c,
    weights,
    dof=None,
    noncentrality=None,
    *,
    sigma=0.0,
    atol=ATOL,
    rtol=RTOL,
    method="contour",
    full_output=False,
):
    """``P(Q > c)``, computed directly (not as ``1 - cdf``) in the upper tail.

    Parameters
    ----------
    c, weights, dof, noncentrality, sigma, atol, rtol, method, full_output
        As in :func:`imhof_cdf`.

    Returns
    -------
    p : float or ndarray
        ``P(Q > c)``.
    error : float or ndarray
        Only with ``full_output``: estimated absolute error.

    Notes
    -----
    Imhof (1961), section 3, on the deformed contour of :func:`imhof_cdf`;
    whichever tail is smaller at ``c`` is the one integrated, so small
    upper-tail probabilities keep their relative accuracy.

    Examples
    --------
    Far in the upper tail of ``chi2_1``, where ``1 - imhof_cdf`` would be 0:

    >>> from course.quadform import imhof_sf
    >>> print(f"{float(imhof_sf(1300.0, [1.0])):.6e}")
    1.130373e-284
    """
    sf, _cdf, err = _evaluate(c, weights, dof, noncentrality, sigma, atol, rtol, method)
    return (_squeeze(sf), _squeeze(err)) if full_output else _squeeze(sf)


def inversion_integrands(c, weights, dof=None, noncentrality=None, u=None):
    """Imhof's real-axis integrand and the deformed-contour integrand at ``u``.

    For teaching figures.

    Parameters
    ----------
    c : float
        The point, ``c > 0``.
    weights, dof, noncentrality
        As in :func:`imhof_cdf`; at least one weight positive.
    u : array_like, optional
        Abscissae (``linspace(0, 10, 401)`` by default).

    Returns
    -------
    real_axis : ndarray
        ``sin(theta(u)) / (u rho(u))``; ``1/2 + (1/pi) int_0^inf`` of it is
        ``P(Q > c)`` (Imhof 1961).
    contour : ndarray
        ``Im[f(s(u)) s'(u)]`` on the saddle-point hyperbola; ``(1/pi)
        int_0^inf`` of it is ``P(Q > c)`` when ``tail == "upper"`` and
        ``-P(Q <= c)`` when ``tail == "lower"``.
    tail : str
        Which tail the contour computes (the smaller one).

    Notes
    -----
    The real-axis integrand is Imhof's (1961), eq. (3.2); the contour one is
    ``Im[M(s) e^{-sc} s'(u) / s]`` on the saddle-point hyperbola of
    :func:`imhof_cdf`.
    """
    w, h, d, _ = _terms(weights, dof, noncentrality)
    c = as_finite(c, "c")
    if c <= 0 or not np.any(w > 0):
        raise ValueError(
            f"inversion_integrands needs c > 0 and at least one positive weight, got c = {c:g}"
        )
    u = np.linspace(0.0, 10.0, 401) if u is None else as_vector(u, "u")
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        wu = np.multiply.outer(u, w)
        # wu/(1+wu^2) and wu^2/(1+wu^2) written so that wu = 0 and wu^2 = inf (weights near
        # 1e300) give their limits 0 and 1, not 0/0 or inf/inf
        wu_ratio = 1.0 / (wu + 1.0 / wu)
        wu2_share = 1.0 / (1.0 + 1.0 / wu**2)
        theta = 0.5 * np.sum(h * np.arctan(wu) + d * wu_ratio, axis=-1) - 0.5 * c * u
        log_rho = np.sum(0.25 * h * np.log1p(wu**2) + 0.5 * d * wu2_share, axis=-1)
        real_axis = np.where(
            u == 0, 0.5 * (np.sum(w * (h + d)) - c), np.sin(theta) / (u * np.exp(log_rho))
        )
    m = float(np.max(np.abs(w)))
    side = _Side(w / m, h, d, 0.0)
    x = c / m
    upper = x > side.mean
    point = np.array([x])
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        s0, g2, g3 = _saddle(point, side, upper, True)
        k0 = side.cgf(s0)
        a, b, e0, *_ = _plan(point, side, upper, True, ATOL, RTOL, s0, g2, g3, k0)
    if not np.isfinite([s0[0], a[0], b[0], e0[0]]).all():
        # c / max|w| below ~1e-290: the saddle point is not representable in doubles
        raise ValueError(
            f"c / max|weights| = {x:.3g} is too close to 0 for the contour integrand to be "
            "drawn in double precision; the law is scale-invariant, so scale c and the "
            "weights by the same factor (imhof_cdf handles such points by itself)"
        )
    # the path and its integrand in u do not depend on the scale m; beyond
    # u = _U_DRAWN (cosh u near the largest double) the integrand is 0 in doubles:
    # it decays like exp(-e^u) far beyond the truncation point (u <= _U_MAX)
    drawn = np.minimum(np.abs(u), _U_DRAWN)
    basis = np.stack([np.ones(u.size), np.cosh(drawn) - 1.0, np.sinh(drawn)])
    coef = _path_coefficients(point, side, s0, a, b, k0)
    with np.errstate(over="ignore", under="ignore"):
        contour = _integrand(basis, coef, side, True)[0] * math.exp(e0[0])
    contour[np.abs(u) >= _U_DRAWN] = 0.0
    return real_axis, contour, ("upper" if upper else "lower")


def _density(x, w, h, d, sigma, atol, rtol, sides=None):
    """Density of ``sum w chi2(h, d) + N(0, sigma^2)`` at x (1-D array).

    ``f(x) = (1/pi) int_0^inf Im[M(s) e^{-sx} s'(u)] du`` on a hyperbola
    through the saddle of ``K(s) - s x`` (no pole), on the law scaled to
    ``max(|w|, sigma) = 1``; x < 0 uses -X.
    """
    if sides is None:
        sides = {}
    m, normal = _normalised(sides, w, h, d, sigma)
    with np.errstate(over="ignore", under="ignore"):
        x = x / m
    if normal:
        return stats.norm.pdf(x) / m
    if sides["limit"] is not None:
        z = _standardised(x, sides["limit"])
        with np.errstate(under="ignore"):
            return stats.norm.pdf(z) / (m * sides["limit"][3])
    out = np.zeros(x.shape)
    w = sides["terms"][1]
    mixed = w[0] < 0 < w[-1]
    for sign, mask in ((1.0, x > 0), (-1.0, x < 0), (1.0, x == 0)):
        if not mask.any():
            continue
        side = _side(sides, sign)
        if side.top is None and not side.sigma2:
            continue
        xs = sign * x[mask]
        if not side.sigma2 and not xs.any():
            # x = 0: an end point of a one-signed support (never asked by the
            # base class), or inside a mixed one where the density is
            # finite only when k > 1
            if mixed:
                out[mask] = np.inf if side.k <= 1 else _density_core(xs, side, atol, rtol)
            continue
        finite = np.isfinite(xs)  # the density vanishes at +-inf
        if finite.any():
            value = np.zeros(xs.shape)
            value[finite] = _density_core(xs[finite], side, atol, rtol)
            out[mask] = value
    with np.errstate(over="ignore"):
        return np.maximum(out, 0.0) / m


def _density_core(x, side, atol, rtol):
    out = np.empty(x.shape)
    for is_upper, mask, part in side.groups(x):
        if mask.any():
            out[mask] = _contour(x[mask], part, is_upper, False, atol, rtol)[0]
    return out


# ---------------------------------------------------------------------------
# the Liu-Tang-Zhang approximation
# ---------------------------------------------------------------------------
def _ltz_parameters(w, h, d, sigma, offset):
    """Liu, Tang & Zhang (2009): match Q to a scaled noncentral chi-square.

    ``c_k = sum w^k h + k sum w^k d`` (``c_2`` also carries ``sigma^2/2``);
    ``s1 = c3 / c2^{3/2}``, ``s2 = c4 / c2^2``; if ``s1^2 > s2``:
    ``a = 1/(s1 - sqrt(s1^2 - s2))``, ``delta = s1 a^3 - a^2``,
    ``l = a^2 - 2 delta``; else ``a = 1/s1``, ``delta = 0``, ``l = 1/s1^2``.
    Then ``P(Q > t) ~ P(chi2(l, delta) > (t - c1)/sqrt(2 c2) * sqrt(2) a + l + delta)``.
    """
    c1 = np.sum(w * h) + np.sum(w * d) + offset
    c2 = np.sum(w**2 * h) + 2 * np.sum(w**2 * d) + 0.5 * sigma**2
    c3 = np.sum(w**3 * h) + 3 * np.sum(w**3 * d)
    c4 = np.sum(w**4 * h) + 4 * np.sum(w**4 * d)
    return c1, c2, c3, c4


def _ltz(x, w, h, d, sigma, offset):
    """(sf, cdf) of the LTZ approximation; negative skewness uses -Q.

    Computed on the law scaled to ``max(|w|, sigma) = 1`` (the cumulants of
    weights of 1e300 overflow), with the cumulants divided by ``H``, a power of
    two of the size of the largest dof (those of dof 1e200 overflow too).  Where
    the matched chi-square has over 1e10 degrees of freedom it is the normal
    law to well within the approximation's own error, and the normal is used.
    """
    m = max(float(np.max(np.abs(w), initial=0.0)), sigma)
    if m == 0:  # the constant offset
        sf = (x < offset).astype(float)
        return sf, 1 - sf
    with np.errstate(over="ignore", under="ignore"):
        x = (x - offset) / m
    largest = float(np.max(h + d, initial=1.0))
    H = 2.0 ** (math.frexp(largest)[1] - 1) if largest > 1e100 else 1.0
    # c_k / H of the law: every c_k is a sum of dof (and sigma^2) times powers of w
    c1, c2, c3, c4 = _ltz_parameters(w / m, h / H, d / H, sigma / m / math.sqrt(H), 0.0)
    if c2 <= 0:
        sf = (x < H * c1).astype(float)
        return sf, 1 - sf
    flip = c3 < 0
    if flip:
        x, c1, c3 = -x, -c1, -c3
    s1 = c3 / c2**1.5 / math.sqrt(H)
    if s1 * s1 < 1e-10:
        with np.errstate(over="ignore"):
            z = (x / H - c1) * math.sqrt(H / (2 * c2))
        sf, cdf = stats.norm.sf(z), stats.norm.cdf(z)
    else:
        s2 = c4 / c2**2 / H
        if s1**2 > s2:
            a = 1.0 / (s1 - math.sqrt(s1**2 - s2))
            delta = s1 * a**3 - a**2
            l = a**2 - 2 * delta
        else:
            a = 1.0 / s1
            delta = 0.0
            l = 1.0 / s1**2
        t = (x - H * c1) / math.sqrt(2 * H * c2) * math.sqrt(2) * a + l + delta
        law = stats.ncx2(l, delta) if delta > 0 else stats.chi2(l)
        sf, cdf = law.sf(t), law.cdf(t)
    if flip:
        sf, cdf = cdf, sf
    return np.asarray(sf, dtype=float), np.asarray(cdf, dtype=float)


def _ltz_points(x, name, w, h, d, sigma, offset):
    """:func:`_ltz` at the points ``x`` (array_like), each result shaped like ``x``."""
    x = as_float_array(x, name)
    sf, cdf = _ltz(np.ravel(x), w, h, d, sigma, offset)
    return _squeeze(sf.reshape(x.shape)), _squeeze(cdf.reshape(x.shape))


def liu_tang_zhang_sf(c, weights, dof=None, noncentrality=None, *, sigma=0.0):
    """Fast approximation of ``P(Q > c)`` (Liu, Tang & Zhang 2009).

    Matches the first four cumulants of ``Q`` (skewness exactly, kurtosis
    as closely as possible) with a noncentral chi-square; forms with negative
    skewness are approximated through ``-Q``.  It is an approximation of the
    *body* of the law, with no error control: use :func:`imhof_sf` (at
    ``rtol=1e-4`` if speed matters) for anything that is reported.

    Measured error (``tests/test_quadform.py``), where the exact ``P(Q <= c)``
    lies in [0.01, 0.99]: at most 0.03 absolute for weights of one sign and
    0.11 with weights of both signs (300 random laws of 1-5 terms, weights
    0.1-5, dof 1-5, noncentrality 0-5; 0.02 on Davies' 13 cases).  In the
    tails the relative error is unbounded: for ``0.6 chi2_1 + 0.3 chi2_1 +
    0.1 chi2_1`` it gives ``P(Q <= 0.1) = 0`` where the law has 0.054.

    Parameters
    ----------
    c, weights, dof, noncentrality, sigma
        As in :func:`imhof_cdf`.

    Returns
    -------
    float or ndarray
        Approximate ``P(Q > c)``.

    Notes
    -----
    Liu, H., Tang, Y. and Zhang, H. H. (2009), "A new chi-square
    approximation to the distribution of non-negative definite quadratic
    forms in non-central normal variables", Computational Statistics & Data
    Analysis 53, 853-856, equations (3)-(8).
    """
    w, h, d, sigma = _terms(weights, dof, noncentrality, sigma)
    sf, _ = _ltz_points(c, "c", w, h, d, sigma, 0.0)
    return sf


def liu_tang_zhang_cdf(c, weights, dof=None, noncentrality=None, *, sigma=0.0):
    """Fast approximation of ``P(Q <= c)`` (Liu, Tang & Zhang 2009).

    Parameters
    ----------
    c, weights, dof, noncentrality, sigma
        As in :func:`imhof_cdf`.

    Returns
    -------
    float or ndarray
        Approximate ``P(Q <= c)``.

    Notes
    -----
    One minus :func:`liu_tang_zhang_sf`, computed from the complementary
    noncentral chi-square function; Liu, Tang & Zhang (2009), (3)-(8).  Its
    measured error is stated in :func:`liu_tang_zhang_sf`.

    Examples
    --------
    >>> from course.quadform import imhof_cdf, liu_tang_zhang_cdf
    >>> round(float(liu_tang_zhang_cdf(7.0, [6, 3, 1])), 3), round(float(imhof_cdf(7.0, [6, 3, 1])), 3)
    (0.51, 0.494)
    """
    w, h, d, sigma = _terms(weights, dof, noncentrality, sigma)
    _, cdf = _ltz_points(c, "c", w, h, d, sigma, 0.0)
    return cdf


# ---------------------------------------------------------------------------
# frozen distributions
# ---------------------------------------------------------------------------
class WeightedChiSquare(FrozenDistribution):
    """Law of ``sum_r w_r chi2(h_r, delta_r^2) + sigma Z + offset``.

    Parameters
    ----------
    weights : (r,) array_like
        Weights of either sign.
    dof : (r,) array_like or float, optional
        Degrees of freedom (ones by default).
    noncentrality : (r,) array_like or float, optional
        Noncentrality parameters ``delta_r^2`` (zeros by default).
    sigma : float, optional
        Standard deviation of an independent normal term.
    offset : float, optional
        A constant added to the sum.
    atol, rtol : float, optional
        Accuracy of :func:`imhof_cdf` used by ``cdf``, ``sf`` and quantiles.

    Attributes
    ----------
    weights, dof, noncentrality : ndarray
        The terms after dropping zero weights and merging equal ones.
    sigma, offset : float
    support : tuple of float

    Notes
    -----
    ``mean = sum w (h + delta^2) + offset`` and
    ``var = 2 sum w^2 (h + 2 delta^2) + sigma^2`` (the first two cumulants
    ``kappa_j = 2^{j-1} (j-1)! sum w^j (h + j delta^2)``).  Every method
    works on the law scaled to ``max(|w|, sigma) = 1``: a law with weights of
    1e300 has an infinite variance in doubles, not an overflow.

    Examples
    --------
    >>> from course.quadform import WeightedChiSquare
    >>> law = WeightedChiSquare([2.0, -1.0], dof=[3, 1], noncentrality=[0.5, 0.0])
    >>> law.mean(), round(float(law.isf(0.05)), 4)
    (6.0, 17.2707)
    """

    def __init__(
        self, weights, dof=None, noncentrality=None, sigma=0.0, offset=0.0, atol=ATOL, rtol=RTOL
    ):
        w, h, d, sigma = _terms(weights, dof, noncentrality, sigma)
        self._set_terms(w, h, d, sigma, offset, atol, rtol)

    def _set_terms(self, w, h, d, sigma, offset, atol=ATOL, rtol=RTOL):
        """Store validated terms (sorted, merged arrays)."""
        offset = as_finite(offset, "offset")
        if len(w) == 0 and sigma == 0:
            raise ValueError(
                "the law is a point mass (no chi-square term and no normal term); "
                "a constant has no distribution to compute"
            )
        for array in (w, h, d):
            array.setflags(write=False)
        self._arrays = (w, h, d)
        self.sigma, self.offset = float(sigma), offset
        self.atol, self.rtol = _tolerances(atol, rtol)
        # the normalised terms of each tail, built on first use
        self._sides, self._density_sides = {}, {}
        # the weights are sorted increasingly: one-signed when the first (last) is
        one_signed = sigma == 0 and len(w) > 0
        lower = offset if one_signed and w[0] > 0 else -math.inf
        upper = offset if one_signed and w[-1] < 0 else math.inf
        self._bounds = (lower, upper)

    @property
    def weights(self) -> np.ndarray:
        """The weights after dropping zeros and merging equal ones (sorted, read-only)."""
        return self._arrays[0]

    @property
    def dof(self) -> np.ndarray:
        """The degrees of freedom of the terms of :attr:`weights` (read-only)."""
        return self._arrays[1]

    @property
    def noncentrality(self) -> np.ndarray:
        """The noncentrality parameters of the terms of :attr:`weights` (read-only)."""
        return self._arrays[2]

    def __repr__(self) -> str:
        return f"WeightedChiSquare(terms={self.weights.size}, dof={_fmt(np.sum(self.dof))})"

    # -- closed forms ------------------------------------------------------
    def cumulant(self, j: int) -> float:
        """The j-th cumulant ``2^{j-1} (j-1)! sum w^j (h + j delta^2)`` (+ normal, offset)."""
        if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or j < 1:
            raise ValueError(f"cumulant order j must be a positive integer, got {j!r}")
        j = int(j)
        w, h, d = self.weights, self.dof, self.noncentrality
        # on the normalised weights: a law with weights of 1e300 has an
        # infinite variance in doubles, not an overflow warning
        scale = float(np.max(np.abs(w), initial=0.0)) or 1.0
        log_factor = (j - 1) * math.log(2.0) + math.lgamma(j) + j * math.log(scale)
        with np.errstate(over="ignore", invalid="ignore"):
            value = float(np.exp(log_factor) * (((w / scale) ** j) @ (h + j * d)))
        if j == 1:
            value += self.offset
        if j == 2:
            value += self.sigma * self.sigma
        return value

    def mean(self) -> float:
        """E[Q] in closed form."""
        return self.cumulant(1)

    def var(self) -> float:
        """Var[Q] in closed form."""
        return self.cumulant(2)

    # -- probabilities -----------------------------------------------------
    def _both(self, x):
        return _probabilities(
            np.ravel(x) - self.offset,
            self.weights,
            self.dof,
            self.noncentrality,
            self.sigma,
            self.atol,
            self.rtol,
            self._sides,
        )

    def _cdf(self, x):
        _sf, cdf, err, conv = self._both(x)
        _warn_unconverged(conv, err, stacklevel=5)
        return cdf.reshape(np.shape(x))

    def _sf(self, x):
        sf, _cdf, err, conv = self._both(x)
        _warn_unconverged(conv, err, stacklevel=5)
        return sf.reshape(np.shape(x))

    def _pdf(self, x):
        x = np.asarray(x, dtype=float)
        out = _density(
            np.ravel(x) - self.offset,
            self.weights,
            self.dof,
            self.noncentrality,
            self.sigma,
            self.atol,
            self.rtol,
            self._density_sides,
        )
        return out.reshape(x.shape)

    def approx_sf(self, x):
        """``P(Q > x)`` by the Liu-Tang-Zhang approximation (fast, approximate)."""
        sf, _ = _ltz_points(
            x, "x", self.weights, self.dof, self.noncentrality, self.sigma, self.offset
        )
        return sf

    def approx_cdf(self, x):
        """``P(Q <= x)`` by the Liu-Tang-Zhang approximation (fast, approximate)."""
        _, cdf = _ltz_points(
            x, "x", self.weights, self.dof, self.noncentrality, self.sigma, self.offset
        )
        return cdf

    def _rvs(self, size, rng):
        shape = _sample_shape(size)
        out = np.full(shape, self.offset)
        for w, h, d in zip(self.weights, self.dof, self.noncentrality):
            draw = rng.noncentral_chisquare(h, d, shape) if d > 0 else rng.chisquare(h, shape)
            out = out + w * draw
        if self.sigma:
            out = out + self.sigma * rng.standard_normal(shape)
        return _squeeze(out)

    def _root(self, func, target, increasing):
        # bracket from a normal approximation outward in steps of the std
        # (computed on the normalised law: the std of a law with weights of
        # 1e300 is not a double)
        scale = max(float(np.max(np.abs(self.weights), initial=0.0)), self.sigma)
        w = self.weights / scale
        std_n = math.sqrt(
            float(2.0 * (w * w) @ (self.dof + 2.0 * self.noncentrality)) + (self.sigma / scale) ** 2
        )
        mean_n = float(w @ (self.dof + self.noncentrality))
        z = stats.norm.ppf(target) if increasing else stats.norm.isf(target)
        lower, upper = self.support()
        guess = min(max(self.offset + scale * (mean_n + std_n * z), lower), upper)
        std = scale * std_n
        sign = 1.0 if increasing else -1.0

        def gap(x):
            return sign * (float(func(x)) - target)

        step = 0.25 * std
        left = max(guess - step, lower)
        right = min(guess + step, upper)
        for _ in range(200):
            if gap(left) <= 0:
                break
            step *= 2
            left = max(left - step, lower)
        for _ in range(200):
            if gap(right) >= 0:
                break
            step *= 2
            right = min(right + step, upper)
        eps = 8 * np.finfo(float).eps
        root = optimize.brentq(
            gap, left, right, xtol=max(1e-13 * std, 1e-300), rtol=eps, maxiter=200
        )
        if abs(root) < 1e-3 * std:
            # near 0 (a positive form far in its lower tail): refine to relative
            # precision, not only to 1e-13 std (ppf(1e-8) of chi2_1 was 0)
            a, b = max(root - 2e-13 * std, left), min(root + 2e-13 * std, right)
            if gap(a) <= 0 <= gap(b):
                root = optimize.brentq(gap, a, b, xtol=1e-300, rtol=eps, maxiter=400)
        return root


def _sample_shape(size):
    """The shape of a sample: None, a non-negative integer or a tuple of them."""
    if size is None:
        return ()
    sizes = size if isinstance(size, tuple) else (size,)
    for n in sizes:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
            raise ValueError(
                f"size must be a non-negative integer or a tuple of them, got {size!r}"
            )
    return tuple(int(n) for n in sizes)


class QuadraticForm(WeightedChiSquare):
    """Law of ``Q = x^T A x`` with ``x ~ N(mean, cov)``; ``cov`` may be singular.

    Parameters
    ----------
    A : (n, n) array_like
        Symmetric matrix of the form.
    mean : (n,) array_like, optional
        Mean of ``x`` (zeros by default).
    cov : (n, n) array_like, optional
        Covariance of ``x``, symmetric positive semi-definite (identity by
        default).
    atol, rtol : float, optional
        Accuracy of the distribution function (see :func:`imhof_cdf`).

    Attributes
    ----------
    A, mean_vector, cov : ndarray
        Read-only validated copies of the inputs.
    weights, dof, noncentrality, sigma, offset
        The reduction ``Q = sum w_r chi2(h_r, delta_r^2) + sigma Z + offset``.
    rank : int
        Rank of ``cov``.

    Raises
    ------
    ValueError
        ``A`` empty, not square or not symmetric; wrong shapes; NaN or inf;
        a constant form; ``x^T A x`` beyond double precision.
    numpy.linalg.LinAlgError
        ``cov`` not positive semi-definite.

    Notes
    -----
    With ``cov = L L^T`` (``L = V_+ diag(sqrt(e_+))`` from the eigenpairs of
    ``cov`` with positive eigenvalues; its nonzero spectrum is that of
    ``cov^{1/2} A cov^{1/2}``), write ``mean = L nu + mu_perp`` with
    ``mu_perp`` orthogonal to the range of ``cov`` and ``L^T A L = P diag(lambda) P^T``.
    With ``y = P^T (z + nu) ~ N(P^T nu, I)`` and ``g = P^T L^T A mu_perp``,

    ``Q = sum_r [lambda_r y_r^2 + 2 g_r y_r] + mu_perp^T A mu_perp``.

    Completing squares for ``lambda_r != 0`` gives ``lambda_r chi2(1,
    ((P^T nu)_r + g_r/lambda_r)^2)``; the terms with ``lambda_r = 0`` are
    normal.  For a non-singular ``cov`` this is Baram (1980), (3.16)-(3.17):
    ``delta_r = p_r^T cov^{-1/2} mean``, with no normal term and no offset.
    ``mean`` and ``var`` use the closed forms ``tr(A cov) + mean^T A mean`` and
    ``2 tr((A cov)^2) + 4 mean^T A cov A mean``.  The reduction is done on
    ``A / max|A|`` and ``x / gamma`` (``gamma`` the larger of ``max|mean|`` and
    ``sqrt(max|cov|)``) and scaled back, so the units of ``A`` and ``x`` do
    not matter until ``x^T A x`` itself leaves the range of doubles (then a
    ValueError says so).

    Examples
    --------
    >>> from course.quadform import QuadraticForm
    >>> form = QuadraticForm([[1.0, 0.5], [0.5, -1.0]], mean=[1.0, 0.0])
    >>> form.rank, round(float(form.cdf(0.0)), 6)
    (2, 0.378713)
    """

    def __init__(self, A, mean=None, cov=None, atol=ATOL, rtol=RTOL):
        A = as_matrix(A, "A")
        n = A.shape[0]
        if A.shape != (n, n):
            raise ValueError(f"A must be square (n x n), got shape {A.shape}")
        if n == 0:
            raise ValueError("A is empty (0 x 0); pass a square matrix of at least 1 x 1")
        mean = np.zeros(n) if mean is None else as_vector(mean, "mean", n)
        cov = np.eye(n) if cov is None else as_matrix(cov, "cov", (n, n))
        # x^T A x = alpha gamma^2 (x/gamma)^T (A/alpha) (x/gamma): the reduction
        # works on unit-size matrices whatever the units (1e-300 or 1e300)
        alpha = float(np.max(np.abs(A)))
        gamma = max(math.sqrt(float(np.max(np.abs(cov)))), float(np.max(np.abs(mean))))
        if alpha == 0 or gamma == 0:
            raise ValueError(
                "the quadratic form is constant (A = 0, or cov = 0 and mean = 0): "
                "x^T A x = 0 with probability one"
            )
        A_n = A / alpha
        asym = float(np.max(np.abs(A_n - A_n.T)))
        if asym > 1e-10:
            raise ValueError(
                f"A is not symmetric (largest |A - A^T| = {asym * alpha:.3g}); x^T A x only "
                "depends on the symmetric part, so pass (A + A.T) / 2"
            )
        cov_n = as_covariance(cov / gamma / gamma, "cov", n, allow_singular=True)
        self.A = _readonly(symmetrize(A))
        self.mean_vector = _readonly(mean)
        self.cov = _readonly(symmetrize(cov))
        self._normalised = (symmetrize(A_n), mean / gamma, symmetrize(cov_n))
        w, h, d, sigma, offset, rank = _reduce(*self._normalised)
        self.rank = rank
        log_scale = math.log(alpha) + 2.0 * math.log(gamma)
        self._scale = math.exp(log_scale) if log_scale < 709.0 else math.inf
        if w.size == 0 and sigma == 0:
            raise ValueError(
                "the quadratic form is constant (A cov A = 0 and no linear term): "
                f"x^T A x = {offset * self._scale:.6g} with probability one"
            )
        with np.errstate(over="ignore"):
            w, sigma, offset = w * self._scale, sigma * self._scale, offset * self._scale
        size = max(float(np.max(np.abs(w), initial=0.0)), sigma)
        if not (1e-305 < size < math.inf and np.isfinite(w).all() and math.isfinite(offset)):
            raise ValueError(
                f"x^T A x is of order 1e{log_scale / math.log(10):.0f} (max|A| times the "
                "square of the scale of x), beyond double precision; rescale A, mean or cov"
            )
        self._set_terms(w, h, d, sigma, offset, atol, rtol)

    def __repr__(self) -> str:
        return f"QuadraticForm(dim={self.A.shape[0]}, rank={self.rank}, terms={self.weights.size})"

    def mean(self) -> float:
        """``tr(A cov) + mean^T A mean``."""
        A, mu, S = self._normalised
        return self._scale * float(np.sum(A * S) + mu @ A @ mu)

    def var(self) -> float:
        """``2 tr((A cov)^2) + 4 mean^T A cov A mean``."""
        A, mu, S = self._normalised
        AS = A @ S
        return self._scale * self._scale * float(2 * np.sum(AS * AS.T) + 4 * mu @ AS @ A @ mu)

    def rvs_direct(self, size, random_state=_NO_STATE, *, rng=None):
        """Draw ``x ~ N(mean, cov)`` and return ``x^T A x`` (slow; for checks)."""
        rng = _rng_argument(rng, random_state, "QuadraticForm.rvs_direct")
        shape = _sample_shape(size)
        if len(shape) != 1:
            raise ValueError(f"size must be a non-negative integer, got {size!r}")
        size = shape[0]
        eigenvalues, vectors = np.linalg.eigh(self.cov)
        root = vectors * np.sqrt(np.clip(eigenvalues, 0, None))
        x = self.mean_vector + rng.standard_normal((size, root.shape[1])) @ root.T
        return np.einsum("ij,jk,ik->i", x, self.A, x)


def _reduce(A, mu, S):
    """Terms of ``x^T A x``, ``x ~ N(mu, S)``: see :class:`QuadraticForm`."""
    e, V = np.linalg.eigh(S)
    top = max(float(e[-1]), 0.0)
    keep = e > _ZERO_RTOL * top * len(e)
    Vk, ek = V[:, keep], e[keep]
    L = Vk * np.sqrt(ek)
    nu = (Vk.T @ mu) / np.sqrt(ek)
    # a full-rank cov leaves no mean outside its range (not even rounding)
    mu_perp = np.zeros_like(mu) if keep.all() else mu - Vk @ (Vk.T @ mu)
    B = symmetrize(L.T @ A @ L)
    lam, P = np.linalg.eigh(B) if B.size else (np.zeros(0), np.zeros((0, 0)))
    y_mean = P.T @ nu
    g = P.T @ (L.T @ (A @ mu_perp))
    big = float(np.max(np.abs(lam))) if lam.size else 0.0
    nonzero = np.abs(lam) > _ZERO_RTOL * big * max(1, len(lam))
    lz, gz = lam[nonzero], g[nonzero]
    noncentrality = (y_mean[nonzero] + gz / lz) ** 2
    offset = float(mu_perp @ A @ mu_perp) - float(np.sum(gz**2 / lz))
    # zero eigenvalues: 2 g y with y ~ N(y_mean, 1) is a normal term
    g0, m0 = g[~nonzero], y_mean[~nonzero]
    offset += float(np.sum(2 * g0 * m0))
    sigma = 2.0 * float(np.sqrt(np.sum(g0**2)))
    chi_sd = float(np.sqrt(np.sum(2 * lz**2 * (1 + 2 * noncentrality))))
    if sigma <= 1e-10 * chi_sd:
        sigma = 0.0  # rounding noise, not a normal component
    if lz.size:
        w, h, d, sigma = _terms(lz, np.ones(lz.size), noncentrality, sigma)
    else:
        w, h, d = np.zeros(0), np.zeros(0), np.zeros(0)
    return w, h, d, sigma, offset, int(keep.sum())


def _warn_unconverged(conv, err, stacklevel=4):
    if not conv.all():
        warnings.warn(
            f"imhof: requested accuracy not reached at {int(np.sum(~conv))} point(s) "
            f"(largest error estimate {float(np.max(err[~conv])):.2g})",
            RuntimeWarning,
            stacklevel=stacklevel,
        )


def _squeeze(a):
    """A 0-d result as a scalar, others (and floats) unchanged."""
    if type(a) is float:  # (one point's answer: no attribute lookup that fails)
        return a
    return a[()] if getattr(a, "ndim", None) == 0 else a


def _readonly(a):
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def _fmt(value) -> str:
    value = float(value)
    return str(int(value)) if value.is_integer() else f"{value:.4g}"
