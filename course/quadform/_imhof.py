"""The public integrals: ``imhof_cdf``, ``imhof_sf`` and ``inversion_integrands``.

The works cited here are in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from ..validation import as_finite, as_float_array, as_vector
from ._batch import _batch_probabilities
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
    r"""CDF :math:`P(Q \le c)` of :math:`Q = \sum_k w_k \chi^2(h_k, \delta_k^2) + \sigma Z`.

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

    See Also
    --------
    imhof_sf : The upper tail :math:`P(Q > c)`, computed directly.
    liu_tang_zhang_cdf : A fast approximation without error control.
    WeightedChiSquare : The same law frozen, with quantiles and moments.
    inversion_integrands : The integrands, for figures.

    Notes
    -----
    Imhof (1961), section 3: with

    .. math::

        \theta(u) = \frac12 \sum_k \Bigl[h_k \arctan(w_k u)
            + \frac{\delta_k^2 w_k u}{1 + w_k^2 u^2}\Bigr] - \frac{c u}{2},
        \qquad
        \rho(u) = \prod_k (1 + w_k^2 u^2)^{h_k/4}
            \exp\Bigl(\frac12 \sum_k \frac{(\delta_k w_k u)^2}{1 + w_k^2 u^2}\Bigr),

    .. math::

        P(Q > c) = \frac12 + \frac1\pi \int_0^\infty
            \frac{\sin\theta(u)}{u\,\rho(u)}\,du .

    This is the Gil-Pelaez inversion of the characteristic function (Baram
    1980, (3.16)) along :math:`s = iu/2` in the Laplace variable.  The default
    method moves the path (Cauchy's theorem) to the hyperbola

    .. math::

        s(u) = s_0 + a(\cosh u - 1) + i b \sinh u

    through the real saddle point :math:`s_0` of :math:`M(s) e^{-sc}/s` in
    :math:`(0, 1/(2 \max_k w_k))`, with :math:`b = a` the saddle's width, giving

    .. math::

        P(Q > c) = \frac1\pi \int_0^\infty
            \operatorname{Im}\Bigl[\frac{M(s) e^{-sc} s'(u)}{s}\Bigr]\,du .

    Upper tails (:math:`c \ge 0`) use :math:`Q`, lower tails the mirrored form
    :math:`-Q`, so small tail probabilities keep their relative accuracy.  See
    the module docstring for the error control.

    Examples
    --------
    Davies' (1980) first test case, :math:`6 \chi^2_1 + 3 \chi^2_1 + \chi^2_1`:

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
    r"""Survival function :math:`P(Q > c)`, computed directly in the upper tail.

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

    See Also
    --------
    imhof_cdf : The lower tail :math:`P(Q \le c)`; the formulas.
    liu_tang_zhang_sf : A fast approximation without error control.
    WeightedChiSquare : The same law frozen, with quantiles and moments.

    Notes
    -----
    Imhof (1961), section 3, on the deformed contour of :func:`imhof_cdf`:

    .. math::

        P(Q > c) = \frac1\pi \int_0^\infty
            \operatorname{Im}\Bigl[\frac{M(s) e^{-sc} s'(u)}{s}\Bigr]\,du ;

    whichever tail is smaller at :math:`c` is the one integrated, so small
    upper-tail probabilities keep their relative accuracy.

    Examples
    --------
    Far in the upper tail of :math:`\chi^2_1`, where ``1 - imhof_cdf`` would be 0:

    >>> from course.quadform import imhof_sf
    >>> print(f"{float(imhof_sf(1300.0, [1.0])):.6e}")
    1.130373e-284
    """
    sf, _cdf, err = _evaluate(c, weights, dof, noncentrality, sigma, atol, rtol, method)
    return (_squeeze(sf), _squeeze(err)) if full_output else _squeeze(sf)


def inversion_integrands(c, weights, dof=None, noncentrality=None, u=None):
    r"""Imhof's real-axis integrand and the deformed-contour integrand at ``u``.

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
        :math:`\sin\theta(u) / (u \rho(u))`; :math:`\frac12 + \frac1\pi
        \int_0^\infty` of it is :math:`P(Q > c)` (Imhof 1961).
    contour : ndarray
        :math:`\operatorname{Im}[f(s(u)) s'(u)]` on the saddle-point hyperbola;
        :math:`\frac1\pi \int_0^\infty` of it is :math:`P(Q > c)` when
        ``tail == "upper"`` and :math:`-P(Q \le c)` when ``tail == "lower"``.
    tail : str
        Which tail the contour computes (the smaller one).

    See Also
    --------
    imhof_cdf : The integrals of these integrands; their formulas.
    imhof_sf : The upper tail.

    Notes
    -----
    The real-axis integrand is Imhof's (1961), eq. (3.2),

    .. math::

        \frac{\sin\theta(u)}{u\,\rho(u)},

    and the contour one is

    .. math::

        \operatorname{Im}\Bigl[\frac{M(s) e^{-sc} s'(u)}{s}\Bigr]

    on the saddle-point hyperbola :math:`s(u)` of :func:`imhof_cdf`.
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


def _batch_terms(weights, dof, noncentrality, sigma):
    """Validated ``(w, h, d, sigma)`` of a batch: ``(laws, r)`` arrays and ``(laws,)`` sigmas."""
    w = as_float_array(weights, "weights", ndim=2)
    if w.size == 0:
        raise ValueError(
            f"weights is empty (shape {w.shape}); pass one row of weights per law, "
            "shape (laws, terms)"
        )
    columns = []
    for value, name, default in ((dof, "dof", 1.0), (noncentrality, "noncentrality", 0.0)):
        if value is None:
            columns.append(np.full(w.shape, default))
            continue
        array = as_float_array(value, name)
        try:
            columns.append(np.broadcast_to(array, w.shape).copy())
        except ValueError:
            raise ValueError(
                f"{name} must be one number, one per term (shape ({w.shape[1]},)) or one per "
                f"law and term (shape {w.shape}) to match weights of shape {w.shape}, got "
                f"shape {array.shape}"
            ) from None
    h, d = columns
    if h.min() <= 0:
        raise ValueError(f"dof (degrees of freedom) must be positive, got {h.min():g}")
    if d.min() < 0:
        raise ValueError(f"noncentrality must be non-negative (squared means), got {d.min():g}")
    s = as_float_array(sigma, "sigma")
    if s.ndim > 1 or (s.ndim == 1 and s.size != w.shape[0]):
        raise ValueError(
            f"sigma must be one number or one per law (shape ({w.shape[0]},)), got shape {s.shape}"
        )
    if s.size and s.min() < 0:
        raise ValueError(
            f"sigma (the standard deviation of the normal term) must be >= 0, got {s.min():g}"
        )
    return w, h, d, np.broadcast_to(s, w.shape[:1]).copy()


def _batch_points(c, laws):
    """The points of a batch as a ``(laws, n)`` array, and the shape of the result."""
    x = as_float_array(c, "c", finite=False)
    if x.ndim <= 1:
        if x.ndim == 1 and x.size != laws:
            raise ValueError(
                f"c of shape ({x.size},) gives one point per law and needs one for each of the "
                f"{laws} laws; for the same points under every law pass c[None, :] "
                "(shape (1, points))"
            )
        return np.broadcast_to(x.reshape(-1, 1), (laws, 1)), (laws,)
    if x.ndim > 2 or x.shape[0] not in (1, laws):
        raise ValueError(
            f"c must be a number, one point per law (shape ({laws},)) or points per law "
            f"(shape ({laws}, n) or (1, n)), got shape {x.shape}"
        )
    full = np.broadcast_to(x, (laws, x.shape[1]))
    return full, full.shape


def _evaluate_batch(c, weights, dof, noncentrality, sigma, atol, rtol):
    w, h, d, s = _batch_terms(weights, dof, noncentrality, sigma)
    atol, rtol = _tolerances(atol, rtol)
    x, shape = _batch_points(c, w.shape[0])
    per_law = x.shape[1]
    # one row of terms per point (views: the laws repeated along the points)
    rows = np.repeat(np.arange(w.shape[0]), per_law)
    sf, cdf, err, conv = _batch_probabilities(
        x.ravel(), w[rows], h[rows], d[rows], s[rows], atol, rtol
    )
    _warn_unconverged(conv, err, stacklevel=4)
    return sf.reshape(shape), cdf.reshape(shape), err.reshape(shape)


def imhof_cdf_batch(
    c, weights, dof=None, noncentrality=None, *, sigma=0.0, atol=ATOL, rtol=RTOL, full_output=False
):
    r"""CDF :math:`P(Q_l \le c)` of many laws :math:`Q_l` in one vectorised call.

    Each row of ``weights`` is a law :math:`Q_l = \sum_k w_{lk}
    \chi^2(h_{lk}, \delta_{lk}^2) + \sigma_l Z`, as in :func:`imhof_cdf`; every
    point of every law is set up and integrated in the same numpy operations,
    so a point costs what a point of one many-point :func:`imhof_cdf` call costs
    (a power curve, a sensitivity study: many laws at a few points each).

    Parameters
    ----------
    c : float or array_like
        A number or shape ``(laws,)``: one point per law (result of shape
        ``(laws,)``); shape ``(laws, n)`` or ``(1, n)``: ``n`` points per law
        (result ``(laws, n)``; ``c[None, :]`` puts the same points under every law).
    weights : (laws, r) array_like
        One row of weights per law (zeros are ignored; pad shorter laws with zeros).
    dof, noncentrality : array_like, optional
        One number, one per term ``(r,)`` or one per law and term ``(laws, r)``
        (ones and zeros by default).
    sigma : float or (laws,) array_like, optional
        Standard deviation of each law's normal term.
    atol, rtol : float, optional
        As in :func:`imhof_cdf`, for every point.
    full_output : bool
        Also return the error estimates.

    Returns
    -------
    p : ndarray
        ``P(Q_l <= c)``, of the shape given under ``c``.
    error : ndarray
        Only with ``full_output``: estimated absolute errors.

    Raises
    ------
    ValueError
        ``weights`` not 2-D, empty, NaN or inf; ``dof``, ``noncentrality`` or
        ``sigma`` of a shape that does not match; non-positive dof, negative
        noncentrality or sigma; a NaN point; ``c`` of a shape that matches
        neither convention; tolerances as in :func:`imhof_cdf`.

    Warns
    -----
    RuntimeWarning
        When an error estimate stays above the tolerance (as :func:`imhof_cdf`).

    See Also
    --------
    imhof_sf_batch : The upper tails of many laws.
    imhof_cdf : One law at many points; the formulas.

    Notes
    -----
    Each point is Imhof's (1961) inversion integral of its own law on the
    saddle-point hyperbola of :func:`imhof_cdf`,

    .. math::

        P(Q_l > c) = \frac1\pi \int_0^\infty
            \operatorname{Im}\Bigl[\frac{M_l(s) e^{-sc} s'(u)}{s}\Bigr]\,du ,

    with the same error control.  Laws with a normal term, over 1e4 degrees
    of freedom in a term, or zero weights are evaluated law by law by the
    engine of :func:`imhof_cdf` (same results, one set-up per law).

    Examples
    --------
    The covariance statistic of ``M`` records, :math:`\frac{\lambda}{M}
    \chi^2(M - 1)`, at its 95 % point for five values of ``M``:

    >>> import numpy as np
    >>> from scipy import stats
    >>> from course.quadform import imhof_cdf_batch
    >>> M = np.array([5, 10, 20, 40, 80])
    >>> points = stats.chi2.ppf(0.95, M - 1) / M
    >>> np.round(imhof_cdf_batch(points, (1.0 / M)[:, None], dof=(M - 1.0)[:, None]), 10)
    array([0.95, 0.95, 0.95, 0.95, 0.95])
    >>> imhof_cdf_batch([[1.0, 7.0, 20.0]], [[6.0, 3.0, 1.0], [1.0, 1.0, 1.0]]).shape
    (2, 3)
    """
    _sf, cdf, err = _evaluate_batch(c, weights, dof, noncentrality, sigma, atol, rtol)
    return (cdf, err) if full_output else cdf


def imhof_sf_batch(
    c, weights, dof=None, noncentrality=None, *, sigma=0.0, atol=ATOL, rtol=RTOL, full_output=False
):
    r"""Survival functions :math:`P(Q_l > c)` of many laws in one vectorised call.

    Parameters
    ----------
    c, weights, dof, noncentrality, sigma, atol, rtol, full_output
        As in :func:`imhof_cdf_batch`.

    Returns
    -------
    p : ndarray
        ``P(Q_l > c)``, of the shape given under ``c`` in :func:`imhof_cdf_batch`.
    error : ndarray
        Only with ``full_output``: estimated absolute errors.

    See Also
    --------
    imhof_cdf_batch : The lower tails; the shape conventions.
    imhof_sf : One law at many points.

    Notes
    -----
    :math:`P(Q_l > c) = \frac1\pi \int_0^\infty \operatorname{Im}[M_l(s)
    e^{-sc} s'(u)/s]\,du` on the hyperbola of :func:`imhof_cdf` (Imhof 1961);
    the smaller tail is computed directly, so small upper tails keep their
    relative accuracy.

    Examples
    --------
    Upper tails of :math:`w \chi^2_1 + \chi^2_1` at :math:`c = 10` for three weights:

    >>> import numpy as np
    >>> from course.quadform import imhof_sf, imhof_sf_batch
    >>> weights = np.array([[0.5, 1.0], [1.0, 1.0], [2.0, 1.0]])
    >>> batch = imhof_sf_batch(10.0, weights)
    >>> bool(np.allclose(batch, [imhof_sf(10.0, w) for w in weights], rtol=1e-9, atol=0))
    True
    """
    sf, _cdf, err = _evaluate_batch(c, weights, dof, noncentrality, sigma, atol, rtol)
    return (sf, err) if full_output else sf
