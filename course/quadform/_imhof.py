"""The public integrals: ``imhof_cdf``, ``imhof_sf`` and ``inversion_integrands``.

The works cited here are in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from ..validation import as_finite, as_vector
from ._contour import _integrand, _path_coefficients, _plan, _probabilities, _saddle, _Side
from ._terms import (
    _U_DRAWN,
    ATOL,
    RTOL,
    _points,
    _squeeze,
    _terms,
    _tolerances,
    _warn_unconverged,
)


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
