"""The four-cumulant approximation of Liu, Tang and Zhang (2009).

The works cited here are in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special, stats

from ..validation import as_float_array
from ._terms import _squeeze, _terms


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


def _ltz_matching(w, h, d, sigma):
    """The chi-square matched by :func:`_ltz` to a law, for :func:`_ltz_quantiles` (or None).

    ``(m, sign, c1, c2, a, delta, dof)``: the scale ``max(|w|, sigma)``, the
    sign of the skewness, the first two cumulants of the scaled law (times
    ``sign``) and the matched ``chi2(dof, delta)`` with its factor ``a``
    (``a = 0``: the normal law).  None where the matching is undefined or the
    dof are huge.  Per-law constants, computed once per law.
    """
    m = max(float(np.max(np.abs(w), initial=0.0)), sigma)
    if m == 0 or float(np.max(h + d, initial=1.0)) > 1e100:
        return None
    # the cumulants c_1..c_4 of the scaled law in one product (a guess: any rounding will do)
    wn = w / m
    square = wn * wn
    powers = np.array([wn, square, square * wn, square * square])
    c1, c2, c3, c4 = (powers @ h + (powers @ d) * np.array([1.0, 2.0, 3.0, 4.0])).tolist()
    c2 += 0.5 * (sigma / m) ** 2
    if not c2 > 0:
        return None
    sign = -1.0 if c3 < 0 else 1.0
    s1 = sign * c3 / c2**1.5
    if s1 * s1 < 1e-10:
        return m, sign, sign * c1, c2, 0.0, 0.0, 0.0
    s2 = c4 / c2**2
    if s1 * s1 > s2:
        a = 1.0 / (s1 - math.sqrt(s1 * s1 - s2))
        delta = s1 * a**3 - a * a
        dof = a * a - 2.0 * delta
    else:
        a, delta, dof = 1.0 / s1, 0.0, 1.0 / (s1 * s1)
    return m, sign, sign * c1, c2, a, delta, dof


def _ltz_quantiles(levels, lower, matching, offset):
    """Approximate quantiles by :func:`_ltz`: ``P(Q <= x)`` (``lower``) or ``P(Q > x)`` = levels.

    The chi-square of :func:`_ltz_matching` is inverted in closed form
    (``scipy.special``'s ``chdtri`` and ``chndtrix``) and mapped back through
    the cumulant matching; a guess for :meth:`WeightedChiSquare._quantiles`,
    NaN where the matching is None (the search then brackets by itself).
    """
    if matching is None:
        return np.full(levels.shape, np.nan)
    m, sign, c1, c2, a, delta, dof = matching
    # the tail of sign * Q whose level is given: P(sQ <= sx) for a lower level when s = 1
    upper = lower != (sign > 0)
    with np.errstate(all="ignore"):
        if a == 0.0:
            z = np.where(upper, -special.ndtri(levels), special.ndtri(levels))
            y = c1 + z * math.sqrt(2.0 * c2)
        elif delta > 0:
            t = special.chndtrix(np.where(upper, 1.0 - levels, levels), dof, delta)
            y = c1 + (t - dof - delta) * math.sqrt(c2) / a
        else:
            t = special.chdtri(dof, np.where(upper, levels, 1.0 - levels))
            y = c1 + (t - dof - delta) * math.sqrt(c2) / a
        return offset + m * sign * y


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
