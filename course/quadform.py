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
``A`` couples to the random part.

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
the trapezoidal rule converges geometrically.  The error is controlled by
(i) a rigorous truncation bound in the style of Imhof's ``T_U`` and (ii)
successive halving of the step until two levels agree to the tolerance.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy import integrate, optimize, stats

from .distributions import _NO_STATE, FrozenDistribution, _rng_argument
from .linalg import as_covariance, as_float_array, as_matrix, as_vector, symmetrize

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
_TINY = 1e-300

# Weights closer than this (relative to the largest) are merged into one
# chi-square term: the law changes by far less than the tolerance.
_MERGE_RTOL = 1e-12
# Eigenvalues below this fraction of the largest are treated as zero.
_ZERO_RTOL = 1e-12
# Complex work arrays are processed in chunks of at most this many entries.
_CHUNK = 2_000_000
_MAX_LEVELS = 9
_U_GRID = np.arange(0.25, 120.0, 0.25)


# ---------------------------------------------------------------------------
# validation of the chi-square terms
# ---------------------------------------------------------------------------
def _terms(weights, dof, noncentrality, sigma=0.0):
    """Validate and normalise ``(weights, dof, noncentrality, sigma)``.

    Zero weights are dropped (they contribute nothing) and equal weights are
    merged: ``w chi2(h1, d1) + w chi2(h2, d2) = w chi2(h1 + h2, d1 + d2)``.
    """
    w = as_float_array(weights, "weights")
    if w.ndim != 1 or w.size == 0:
        raise ValueError(f"weights must be a non-empty 1-D array, got shape {w.shape}")
    r = w.size
    h = np.ones(r) if dof is None else as_float_array(dof, "dof")
    d = np.zeros(r) if noncentrality is None else as_float_array(noncentrality, "noncentrality")
    if h.ndim == 0:
        h = np.full(r, float(h))
    if d.ndim == 0:
        d = np.full(r, float(d))
    if h.shape != (r,) or d.shape != (r,):
        raise ValueError(
            f"dof and noncentrality must have the same length as weights ({r}), "
            f"got shapes {h.shape} and {d.shape}"
        )
    if np.any(h <= 0):
        raise ValueError("degrees of freedom must be positive")
    if np.any(d < 0):
        raise ValueError("noncentrality parameters must be non-negative (they are squared means)")
    sigma = float(sigma)
    if not math.isfinite(sigma) or sigma < 0:
        raise ValueError(
            f"sigma (the standard deviation of the normal term) must be >= 0, got {sigma}"
        )
    keep = w != 0
    w, h, d = w[keep], h[keep], d[keep]
    if w.size > 1:
        order = np.argsort(w, kind="stable")
        w, h, d = w[order], h[order], d[order]
        scale = np.max(np.abs(w))
        breaks = np.flatnonzero(np.diff(w) > _MERGE_RTOL * scale) + 1
        if breaks.size < w.size - 1:
            groups = np.split(np.arange(w.size), breaks)
            w = np.array([np.average(w[g], weights=h[g]) for g in groups])
            h = np.array([h[g].sum() for g in groups])
            d = np.array([d[g].sum() for g in groups])
    return w, h, d, sigma


# ---------------------------------------------------------------------------
# the contour integral
# ---------------------------------------------------------------------------
def _cumulant_derivatives(s, w, h, d, sigma2):
    """K'(s), K''(s), K'''(s) of the log-MGF ``K``, for real s of shape (m,)."""
    z = 1.0 - 2.0 * np.multiply.outer(s, w)
    wz = w / z
    k1 = np.sum(h * wz + d * wz / z, axis=-1) + sigma2 * s
    k2 = np.sum(2.0 * h * wz**2 + 4.0 * d * wz**2 / z, axis=-1) + sigma2
    k3 = np.sum(8.0 * h * wz**3 + 24.0 * d * wz**3 / z, axis=-1)
    return k1, k2, k3


def _saddle(c, w, h, d, sigma2, lo, hi, pole):
    """Real saddle point of ``phi(s) = K(s) - s c - log|s|`` (``pole``) or
    ``K(s) - s c`` in the interval ``(lo, hi)``, with ``phi''`` and ``phi'''``.

    ``phi`` is convex on the interval, so ``phi'`` increases: Newton steps
    safeguarded by bisection find its root.  The saddle only has to be
    approximate (any point of the interval gives the same integral).
    """
    scale = 0.5 / np.max(np.abs(w)) if w.size else 1.0 / math.sqrt(sigma2)

    def derivatives(s):
        k1, k2, k3 = _cumulant_derivatives(s, w, h, d, sigma2)
        if pole:
            return k1 - c - 1.0 / s, k2 + 1.0 / s**2, k3 - 2.0 / s**3
        return k1 - c, k2, k3

    lo = np.full(c.shape, float(lo))
    hi = np.full(c.shape, float(hi))
    # an unbounded side: walk out until phi' changes sign
    if np.isinf(hi[0]):
        hi[:] = scale
        for _ in range(2000):
            grow = derivatives(hi)[0] <= 0
            if not grow.any():
                break
            hi[grow] *= 2.0
    if np.isinf(lo[0]):
        lo[:] = -scale
        for _ in range(2000):
            grow = derivatives(lo)[0] >= 0
            if not grow.any():
                break
            lo[grow] *= 2.0
    # Newton inside the bracket; when it jumps out, a secant step between the
    # bracket ends (once both values are finite), else bisection
    f_lo = np.full(c.shape, -np.inf)
    f_hi = np.full(c.shape, np.inf)
    s = 0.5 * (lo + hi)
    for _ in range(100):
        g1, g2, _ = derivatives(s)
        up = g1 > 0
        hi, f_hi = np.where(up, s, hi), np.where(up, g1, f_hi)
        lo, f_lo = np.where(up, lo, s), np.where(up, f_lo, g1)
        newton = s - g1 / g2
        with np.errstate(invalid="ignore", divide="ignore"):
            secant = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        fallback = np.where(
            np.isfinite(secant) & (secant > lo) & (secant < hi), secant, 0.5 * (lo + hi)
        )
        new = np.where((newton > lo) & (newton < hi), newton, fallback)
        done = np.all(np.abs(new - s) <= 1e-7 * np.abs(s) + 1e-300)
        s = new
        if done:
            break
    _, g2, g3 = derivatives(s)
    return s, g2, g3


def _contour_integrand(u, c, s0, a, b, w, h, d, sigma2, pole):
    """Im[f(s(u)) s'(u)] on the hyperbola ``s(u) = s0 + a(cosh u - 1) + i b sinh u``.

    ``f(s) = M(s) exp(-s c) / s`` for probabilities, ``M(s) exp(-s c)`` for
    the density; ``M`` is the moment generating function.  Shapes: u (m,),
    c/s0/a/b (n,) -> (n, m).
    """
    cu, su = np.cosh(u), np.sinh(u)
    s = s0[:, None] + a[:, None] * (cu - 1.0) + 1j * b[:, None] * su
    ds = a[:, None] * su + 1j * b[:, None] * cu
    z = 1.0 - 2.0 * s[..., None] * w
    # principal logarithm: Im z = -2 w Im s keeps z off the cut on the path
    log_m = np.sum(-0.5 * h * np.log(z) + 0.5 * d * (1.0 / z - 1.0), axis=-1)
    exponent = log_m - s * c[:, None]
    if sigma2:
        exponent = exponent + 0.5 * sigma2 * s * s
    value = np.exp(exponent) * ds
    if pole:
        value = value / s
    return value.imag


def _truncation_point(c, s0, a, b, w, h, d, sigma2, s_max, pole, tol):
    """Smallest grid value U whose rigorous tail bound is below ``tol``.

    For ``Re s = x >= 1/max(w)`` every factor obeys ``|1 - 2 w s| >= |w| x``,
    so ``|M(s)| <= D x^{-k}`` with ``D = prod |w|^{-h/2} exp(-sum_{w>0} d/2)``
    (the noncentral factors only help; the normal factor is at most one once
    ``Im s >= Re s``).  With ``|s'(u)| <= kappa dx/du`` the neglected integral
    is below ``kappa D int_x^inf t^{-k-e} exp(-c t) dt / pi`` (``e = 1`` with
    the pole): the analogue of Imhof's (1961) truncation bound ``T_U``.
    """
    k = 0.5 * np.sum(h)
    e = 1.0 if pole else 0.0
    log_d = -np.sum(0.5 * h * np.log(np.abs(w))) - 0.5 * np.sum(d[w > 0])
    U = _U_GRID[None, :]
    x = s0[:, None] + a[:, None] * (np.cosh(U) - 1.0)
    kappa = np.sqrt(1.0 + (b / a)[:, None] ** 2 / np.tanh(U) ** 2)
    cc = c[:, None]
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        log_x = np.log(x)
        bound = np.full(x.shape, np.inf)
        if k + e > 1:
            bound = np.exp(log_d + (1 - k - e) * log_x) / (k + e - 1)
        decay = np.exp(log_d - (k + e) * log_x - cc * x) / np.where(cc > 0, cc, 1.0)
        bound = np.minimum(bound, np.where(cc > 0, decay, np.inf)) * kappa / np.pi
    ok = (bound <= np.reshape(tol, (-1, 1))) & (x > 0)
    if np.isfinite(s_max):
        ok &= x >= 2.0 * s_max
    if sigma2:
        ok &= b[:, None] * np.sinh(U) >= x
    first = np.argmax(ok, axis=1)
    found = ok[np.arange(len(c)), first]
    return np.where(found, _U_GRID[first], _U_GRID[-1]), found


def _path(c, w, h, d, sigma2, lo, hi, pole):
    """Vertex, shape (a, b) of the hyperbola through the saddle in (lo, hi).

    ``b = phi''^{-1/2}`` is the saddle's width; ``a/b = phi'''/(3 phi''^{3/2})``
    makes the hyperbola osculate the steepest-descent path at the vertex
    (clipped to [0.02, 1]; at most 1/2 with a normal term, so that
    ``exp(sigma^2 s^2/2)`` decays along it).
    """
    s0, g2, g3 = _saddle(c, w, h, d, sigma2, lo, hi, pole)
    b = 1.0 / np.sqrt(g2)
    ratio = np.clip(g3 / (3.0 * g2**1.5), 0.02, 0.5 if sigma2 else 1.0)
    return s0, ratio * b, b


def _contour(c, w, h, d, sigma2, atol, rtol):
    """Tail probabilities of X = sum w chi2(h, d) + N(0, sigma2) at c >= 0.

    Points above the mean get ``P(X > c)`` from a vertex in ``(0, s_max)``;
    points at or below it get ``P(X <= c)`` from a vertex in ``(s_min, 0)``
    (left of the pole at 0; the residue there is 1).  Each is the small tail
    at its point, computed without cancellation.  Returns (sf, cdf, error,
    converged).  Needs a positive weight or a normal term.
    """
    pos, neg = w[w > 0], w[w < 0]
    s_max = 0.5 / pos.max() if pos.size else np.inf
    s_min = 0.5 / neg.min() if neg.size else -np.inf
    mean = float(np.sum(w * (h + d)))
    sf, cdf = np.empty_like(c), np.empty_like(c)
    err = np.empty_like(c)
    conv = np.ones(c.shape, dtype=bool)
    for upper in (True, False):
        mask = (c > mean) if upper else (c <= mean)
        if not mask.any():
            continue
        cm = c[mask]
        lo, hi = (0.0, s_max) if upper else (s_min, 0.0)
        s0, a, b = _path(cm, w, h, d, sigma2, lo, hi, pole=True)
        integral, e, ok = _integrate(cm, s0, a, b, w, h, d, sigma2, s_max, True, atol, rtol)
        tail = np.clip(integral if upper else -integral, 0.0, 1.0)
        sf[mask], cdf[mask] = (tail, 1.0 - tail) if upper else (1.0 - tail, tail)
        err[mask], conv[mask] = e, ok
    return sf, cdf, err, conv


def _integrate(c, s0, a, b, w, h, d, sigma2, s_max, pole, atol, rtol):
    """(1/pi) int_0^inf Im[f(s(u)) s'(u)] du with truncation and step control."""
    # the integrand at the vertex sets the scale of the result (saddle-point
    # estimate), so the truncation error can be made small *relative* to it
    vertex = np.abs(_contour_integrand(np.zeros(1), c, s0, a, b, w, h, d, sigma2, pole)[:, 0])
    scale = 1.25 * vertex / np.pi
    tol = np.maximum(atol, 1e-3 * rtol * scale) / 4
    U, found = _truncation_point(c, s0, a, b, w, h, d, sigma2, s_max, pole, tol)
    value = np.empty_like(c)
    error = np.empty_like(c)
    converged = np.array(found)
    # chunks over c keep the (n_c, n_nodes, n_weights) work array small
    size = max(1, _CHUNK // (int(np.max(U) * 32) * max(w.size, 1)))
    for start in range(0, len(c), size):
        i = slice(start, start + size)
        value[i], error[i], ok = _trapezoid(
            c[i], s0[i], a[i], b[i], U[i], w, h, d, sigma2, pole, atol, rtol
        )
        converged[i] &= ok
    return value, error, converged


def _trapezoid(c, s0, a, b, U, w, h, d, sigma2, pole, atol, rtol):
    """Trapezoidal rule on [0, U] with step halving until two levels agree.

    The integrand is even in u and analytic in a strip around the real axis,
    so the rule converges geometrically; the difference between successive
    levels over-estimates the error of the finer one.
    """
    step = 0.5
    n = int(np.ceil(np.max(U) / step))
    nodes = step * np.arange(n + 1)
    f = _contour_integrand(nodes, c, s0, a, b, w, h, d, sigma2, pole)
    total = step * (f.sum(axis=1) - 0.5 * f[:, 0])
    error = np.full(c.shape, np.inf)
    active = np.arange(len(c))
    for _ in range(_MAX_LEVELS):
        step *= 0.5
        nodes = step * (2 * np.arange(n) + 1)
        n *= 2
        i = active
        f = _contour_integrand(nodes, c[i], s0[i], a[i], b[i], w, h, d, sigma2, pole)
        refined = 0.5 * total[i] + step * f.sum(axis=1)
        error[i] = np.abs(refined - total[i]) / np.pi
        total[i] = refined
        done = error[i] <= np.maximum(max(atol, _TINY), rtol * np.abs(refined) / np.pi)
        active = i[~done]
        if active.size == 0:
            break
    converged = np.ones(c.shape, dtype=bool)
    converged[active] = False
    return total / np.pi, error, converged


def _probabilities(x, w, h, d, sigma, atol, rtol):
    """``P(X > x)`` and ``P(X <= x)``, the smaller of the two computed directly.

    Returns (sf, cdf, error, converged).  Points x >= 0 use X, points x < 0
    the mirrored variable -X (``P(X <= x) = P(-X >= -x)`` for a continuous
    law), so the contour always opens where ``exp(-s x)`` decays.
    """
    sigma2 = sigma * sigma
    err = np.zeros_like(x)
    conv = np.ones(x.shape, dtype=bool)
    if w.size == 0:
        # no chi-square term: a normal law
        return stats.norm.sf(x / sigma), stats.norm.cdf(x / sigma), err, conv
    sf, cdf = np.empty_like(x), np.empty_like(x)
    for sign, mask in ((1.0, x >= 0), (-1.0, x < 0)):
        if not mask.any():
            continue
        ws, xs = sign * w, sign * x[mask]
        up, low = np.zeros(xs.shape), np.ones(xs.shape)
        e, ok = np.zeros(xs.shape), np.ones(xs.shape, dtype=bool)
        if np.any(ws > 0) or sigma2 > 0:
            # with every weight positive and no normal term, P(X > 0) = 1
            todo = xs > 0 if not (np.any(ws < 0) or sigma2 > 0) else np.ones(xs.shape, dtype=bool)
            up[~todo], low[~todo] = 1.0, 0.0
            if todo.any():
                up[todo], low[todo], e[todo], ok[todo] = _contour(
                    xs[todo], ws, h, d, sigma2, atol, rtol
                )
        # else: every weight <= 0 and no normal term, so X <= 0 <= xs
        if sign > 0:
            sf[mask], cdf[mask] = up, low
        else:
            cdf[mask], sf[mask] = up, low
        err[mask], conv[mask] = e, ok
    return sf, cdf, err, conv


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


def _evaluate(c, weights, dof, noncentrality, sigma, offset, atol, rtol, method):
    w, h, d, sigma = _terms(weights, dof, noncentrality, sigma)
    c = as_float_array(c, "c")
    shape = c.shape
    x = np.ravel(c) - float(offset)
    if not (atol >= 0 and rtol >= 0 and atol + rtol > 0):
        raise ValueError("atol and rtol must be non-negative and not both zero")
    if w.size == 0 and sigma == 0:
        # the form is the constant `offset`
        sf = (x < 0).astype(float)
        return sf.reshape(shape), (1 - sf).reshape(shape), np.zeros(shape)
    if method == "contour":
        sf, cdf, err, conv = _probabilities(x, w, h, d, sigma, atol, rtol)
        if not conv.all():
            warnings.warn(
                f"imhof: requested accuracy not reached at {int((~conv).sum())} point(s) "
                f"(largest error estimate {float(np.max(err[~conv])):.2g})",
                RuntimeWarning,
                stacklevel=3,
            )
    elif method == "imhof":
        if w.size == 0:
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
        the error estimate is below ``max(atol, rtol * p_tail)``.
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
        Mismatched lengths, non-positive dof, negative noncentrality, NaN.

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
    """
    _sf, cdf, err = _evaluate(c, weights, dof, noncentrality, sigma, 0.0, atol, rtol, method)
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
    """
    sf, _cdf, err = _evaluate(c, weights, dof, noncentrality, sigma, 0.0, atol, rtol, method)
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
    c = float(c)
    if c <= 0 or not np.any(w > 0):
        raise ValueError("inversion_integrands needs c > 0 and at least one positive weight")
    u = np.linspace(0.0, 10.0, 401) if u is None else as_float_array(u, "u")
    with np.errstate(invalid="ignore", divide="ignore"):
        wu = np.multiply.outer(u, w)
        theta = 0.5 * np.sum(h * np.arctan(wu) + d * wu / (1 + wu**2), axis=-1) - 0.5 * c * u
        log_rho = np.sum(0.25 * h * np.log1p(wu**2) + 0.5 * d * wu**2 / (1 + wu**2), axis=-1)
        real_axis = np.where(
            u == 0, 0.5 * (np.sum(w * (h + d)) - c), np.sin(theta) / (u * np.exp(log_rho))
        )
    pos, neg = w[w > 0], w[w < 0]
    upper = c > float(np.sum(w * (h + d)))
    lo, hi = (0.0, 0.5 / pos.max()) if upper else ((0.5 / neg.min()) if neg.size else -np.inf, 0.0)
    s0, a, b = _path(np.array([c]), w, h, d, 0.0, lo, hi, pole=True)
    contour = _contour_integrand(u, np.array([c]), s0, a, b, w, h, d, 0.0, True)[0]
    return real_axis, contour, ("upper" if upper else "lower")


def _density(x, w, h, d, sigma, atol, rtol):
    """Density of ``sum w chi2(h, d) + N(0, sigma^2)`` at x (1-D array).

    ``f(x) = (1/pi) int_0^inf Im[M(s) e^{-sx} s'(u)] du`` on a hyperbola
    through the saddle of ``K(s) - s x`` (no pole); x < 0 uses -X.
    """
    sigma2 = sigma * sigma
    out = np.zeros_like(x)
    k = 0.5 * np.sum(h)
    mixed = np.any(w > 0) and np.any(w < 0)
    for sign, mask in ((1.0, x > 0), (-1.0, x < 0), (1.0, x == 0)):
        ws = sign * w
        if not mask.any() or not (np.any(ws > 0) or sigma2 > 0):
            continue
        if not np.any(x[mask]) and not sigma2:
            # x = 0: an end point of a one-signed support (never asked by the
            # base class), or inside a mixed one where the density is
            # finite only when k > 1
            if mixed:
                out[mask] = (
                    np.inf if k <= 1 else _density_core(x[mask], ws, h, d, sigma2, atol, rtol)
                )
            continue
        out[mask] = _density_core(sign * x[mask], ws, h, d, sigma2, atol, rtol)
    return np.maximum(out, 0.0)


def _density_core(c, w, h, d, sigma2, atol, rtol):
    pos, neg = w[w > 0], w[w < 0]
    s_max = 0.5 / pos.max() if pos.size else np.inf
    s_min = 0.5 / neg.min() if neg.size else -np.inf
    s0, a, b = _path(c, w, h, d, sigma2, s_min, s_max, pole=False)
    value, _, _ = _integrate(c, s0, a, b, w, h, d, sigma2, s_max, False, atol, rtol)
    return value


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
    """(sf, cdf) of the LTZ approximation; negative skewness uses -Q."""
    c1, c2, c3, c4 = _ltz_parameters(w, h, d, sigma, offset)
    if c2 <= 0:
        sf = (x < c1).astype(float)
        return sf, 1 - sf
    flip = c3 < 0
    if flip:
        x, c1, c3 = -x, -c1, -c3
    if c3 == 0:
        z = (x - c1) / math.sqrt(2 * c2)
        sf, cdf = stats.norm.sf(z), stats.norm.cdf(z)
    else:
        s1 = c3 / c2**1.5
        s2 = c4 / c2**2
        if s1**2 > s2:
            a = 1.0 / (s1 - math.sqrt(s1**2 - s2))
            delta = s1 * a**3 - a**2
            l = a**2 - 2 * delta
        else:
            a = 1.0 / s1
            delta = 0.0
            l = 1.0 / s1**2
        t = (x - c1) / math.sqrt(2 * c2) * math.sqrt(2) * a + l + delta
        law = stats.ncx2(l, delta) if delta > 0 else stats.chi2(l)
        sf, cdf = law.sf(t), law.cdf(t)
    if flip:
        sf, cdf = cdf, sf
    return np.asarray(sf, dtype=float), np.asarray(cdf, dtype=float)


def _ltz_at(x, name, w, h, d, sigma, offset):
    """:func:`_ltz` at the points ``x`` (array_like), each result shaped like ``x``."""
    x = as_float_array(x, name)
    sf, cdf = _ltz(np.ravel(x), w, h, d, sigma, offset)
    return _squeeze(sf.reshape(x.shape)), _squeeze(cdf.reshape(x.shape))


def liu_tang_zhang_sf(c, weights, dof=None, noncentrality=None, *, sigma=0.0):
    """Fast approximation of ``P(Q > c)`` (Liu, Tang & Zhang 2009).

    Matches the first four cumulants of ``Q`` (skewness exactly, kurtosis
    as closely as possible) with a noncentral chi-square.  Typical absolute
    errors are 1e-3 in the body and larger in relative terms in the far
    tails; see the course benchmark for an honest comparison with
    :func:`imhof_sf`.  Forms with negative skewness are approximated through
    ``-Q``.

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
    sf, _ = _ltz_at(c, "c", w, h, d, sigma, 0.0)
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
    ``1 - `` :func:`liu_tang_zhang_sf`, computed from the complementary
    noncentral chi-square function; Liu, Tang & Zhang (2009), (3)-(8).
    """
    w, h, d, sigma = _terms(weights, dof, noncentrality, sigma)
    _, cdf = _ltz_at(c, "c", w, h, d, sigma, 0.0)
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
    ``kappa_j = 2^{j-1} (j-1)! sum w^j (h + j delta^2)``).
    """

    def __init__(
        self, weights, dof=None, noncentrality=None, sigma=0.0, offset=0.0, atol=ATOL, rtol=RTOL
    ):
        w, h, d, sigma = _terms(weights, dof, noncentrality, sigma)
        self._set_terms(w, h, d, sigma, offset, atol, rtol)

    def _set_terms(self, w, h, d, sigma, offset, atol=ATOL, rtol=RTOL):
        offset = float(offset)
        if not math.isfinite(offset):
            raise ValueError("offset must be finite")
        if w.size == 0 and sigma == 0:
            raise ValueError(
                "the law is a point mass (no chi-square term and no normal term); "
                "a constant has no distribution to compute"
            )
        for array in (w, h, d):
            array.setflags(write=False)
        self.weights, self.dof, self.noncentrality = w, h, d
        self.sigma, self.offset = float(sigma), offset
        self.atol, self.rtol = float(atol), float(rtol)
        lower = offset if (sigma == 0 and np.all(w > 0)) else -np.inf
        upper = offset if (sigma == 0 and np.all(w < 0)) else np.inf
        self.support = (lower, upper)

    def __repr__(self) -> str:
        return f"WeightedChiSquare(terms={self.weights.size}, dof={_fmt(np.sum(self.dof))})"

    # -- closed forms ------------------------------------------------------
    def cumulant(self, j: int) -> float:
        """The j-th cumulant ``2^{j-1} (j-1)! sum w^j (h + j delta^2)`` (+ normal, offset)."""
        j = int(j)
        if j < 1:
            raise ValueError("cumulant order must be a positive integer")
        w, h, d = self.weights, self.dof, self.noncentrality
        value = 2.0 ** (j - 1) * math.factorial(j - 1) * float(np.sum(w**j * (h + j * d)))
        if j == 1:
            value += self.offset
        if j == 2:
            value += self.sigma**2
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
        )

    def _cdf(self, x):
        _sf, cdf, err, conv = self._both(x)
        _warn_unconverged(conv, err)
        return cdf.reshape(np.shape(x))

    def _sf(self, x):
        sf, _cdf, err, conv = self._both(x)
        _warn_unconverged(conv, err)
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
        )
        return out.reshape(x.shape)

    def approx_sf(self, x):
        """``P(Q > x)`` by the Liu-Tang-Zhang approximation (fast, approximate)."""
        sf, _ = _ltz_at(x, "x", self.weights, self.dof, self.noncentrality, self.sigma, self.offset)
        return sf

    def approx_cdf(self, x):
        """``P(Q <= x)`` by the Liu-Tang-Zhang approximation (fast, approximate)."""
        _, cdf = _ltz_at(
            x, "x", self.weights, self.dof, self.noncentrality, self.sigma, self.offset
        )
        return cdf

    def _rvs(self, size, rng):
        shape = () if size is None else ((int(size),) if np.ndim(size) == 0 else tuple(size))
        out = np.full(shape, self.offset)
        for w, h, d in zip(self.weights, self.dof, self.noncentrality):
            draw = rng.noncentral_chisquare(h, d, shape) if d > 0 else rng.chisquare(h, shape)
            out = out + w * draw
        if self.sigma:
            out = out + self.sigma * rng.standard_normal(shape)
        return _squeeze(out)

    def _root(self, func, target, increasing):
        # bracket from the approximate quantile outward in steps of the std
        std = math.sqrt(max(self.var(), 0.0))
        lower, upper = self.support()
        guess = self._approx_quantile(target if increasing else 1.0 - target)
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
        return optimize.brentq(
            gap, left, right, xtol=1e-13 * max(1.0, std), rtol=8 * np.finfo(float).eps, maxiter=200
        )

    def _approx_quantile(self, q):
        c1, c2, _c3, _c4 = _ltz_parameters(
            self.weights, self.dof, self.noncentrality, self.sigma, self.offset
        )
        lower, upper = self.support()
        guess = c1 + math.sqrt(2 * c2) * stats.norm.ppf(q)
        return min(
            max(guess, lower if np.isfinite(lower) else guess),
            upper if np.isfinite(upper) else guess,
        )


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
        ``A`` not square or not symmetric; wrong shapes; NaN.
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
    ``2 tr((A cov)^2) + 4 mean^T A cov A mean``.
    """

    def __init__(self, A, mean=None, cov=None, atol=ATOL, rtol=RTOL):
        A = as_matrix(A, "A")
        n = A.shape[0]
        if A.shape != (n, n):
            raise ValueError(f"A must be square (n x n), got shape {A.shape}")
        scale = max(float(np.max(np.abs(A))), np.finfo(float).tiny)
        asym = float(np.max(np.abs(A - A.T)))
        if asym > 1e-10 * scale:
            raise ValueError(
                f"A is not symmetric (largest |A - A^T| = {asym:.3g}); x^T A x only depends on the "
                "symmetric part, so pass (A + A.T) / 2"
            )
        mean = np.zeros(n) if mean is None else as_vector(mean, "mean", n)
        cov = np.eye(n) if cov is None else as_covariance(cov, "cov", n, allow_singular=True)
        self.A = _readonly(symmetrize(A))
        self.mean_vector = _readonly(mean)
        self.cov = _readonly(symmetrize(cov))
        w, h, d, sigma, offset, rank = _reduce(self.A, self.mean_vector, self.cov)
        self.rank = rank
        if w.size == 0 and sigma == 0:
            raise ValueError(
                "the quadratic form is constant (A cov A = 0 and no linear term): "
                f"x^T A x = {offset:.6g} with probability one"
            )
        self._set_terms(w, h, d, sigma, offset, atol, rtol)

    def __repr__(self) -> str:
        return f"QuadraticForm(dim={self.A.shape[0]}, rank={self.rank}, terms={self.weights.size})"

    def mean(self) -> float:
        """``tr(A cov) + mean^T A mean``."""
        A, mu, S = self.A, self.mean_vector, self.cov
        return float(np.sum(A * S) + mu @ A @ mu)

    def var(self) -> float:
        """``2 tr((A cov)^2) + 4 mean^T A cov A mean``."""
        A, mu, S = self.A, self.mean_vector, self.cov
        AS = A @ S
        return float(2 * np.sum(AS * AS.T) + 4 * mu @ AS @ A @ mu)

    def rvs_direct(self, size, random_state=_NO_STATE, *, rng=None):
        """Draw ``x ~ N(mean, cov)`` and return ``x^T A x`` (slow; for checks)."""
        rng = _rng_argument(rng, random_state, "QuadraticForm.rvs_direct")
        size = int(size)
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


def _warn_unconverged(conv, err):
    if not np.all(conv):
        warnings.warn(
            f"imhof: requested accuracy not reached at {int(np.sum(~conv))} point(s) "
            f"(largest error estimate {float(np.max(err[~conv])):.2g})",
            RuntimeWarning,
            stacklevel=4,
        )


def _squeeze(a):
    """A 0-d result as a scalar, others unchanged."""
    return a[()] if a.ndim == 0 else a


def _readonly(a):
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def _fmt(value) -> str:
    value = float(value)
    return str(int(value)) if value.is_integer() else f"{value:.4g}"
