"""The chi-square terms of a law: validation, merging, tolerances and shared constants."""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..validation import as_finite, as_float_array, as_vector

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
# Below this many degrees of freedom in every term the law is never normal to double
# precision (a chi-square's skewness sqrt(8/k) is above 1e-20); beyond it the normal limit
# is used where the skewness and kurtosis of the whole law are below 1e-20.
_NORMAL_DOF = 8e40
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
def _every(a) -> bool:
    """``a.all()`` without its cost on the few elements of a scalar call.

    The method goes through numpy's Python layer (~1.5 us, a dozen times a
    call); ``count_nonzero`` is one C call (~0.2 us).  NaN counts as nonzero
    in both.
    """
    return int(np.count_nonzero(a)) == a.size


def _some(a) -> bool:
    """``a.any()`` as one C call (see :func:`_every`)."""
    return int(np.count_nonzero(a)) > 0


def _plain_numbers(value):
    """``value`` as a float array when it is a list or tuple of finite Python floats and ints.

    Or a 1-D real numpy array of finite numbers.  The common cases of a law
    typed by hand or built by code, checked with a few cheap tests; anything
    else (other arrays, nesting, bools, text, NaN, inf, huge ints) returns
    None and goes through :func:`course.validation.as_float_array`, which
    explains what is wrong.
    """
    if type(value) is np.ndarray:
        # (a 1-D array of real numbers, as built by code: one copy and a finiteness test)
        if value.ndim != 1 or value.size == 0 or value.dtype.kind not in "fiu":
            return None
        array = value.astype(float)
        return array if _every(np.isfinite(array)) else None
    if type(value) not in (list, tuple) or not value:
        return None
    for entry in value:
        kind = type(entry)
        if kind is not float and kind is not int:
            return None
    try:
        array = np.array(value, dtype=float)
    except OverflowError:
        return None
    return array if _every(np.isfinite(array)) else None


def _per_term(value, name, size, default):
    """``dof`` or ``noncentrality``: one finite number for every term, or one per term."""
    if value is None:
        return np.full(size, default)
    array = _plain_numbers(value)
    if array is not None and array.size == size:
        return array
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
    # (the three typed as lists or tuples of numbers of one length: one conversion)
    columns = None
    if (
        type(dof) is type(noncentrality) is type(weights)
        and type(weights) in (list, tuple)
        and len(weights) == len(dof) == len(noncentrality)
    ):
        columns = _plain_numbers([*weights, *dof, *noncentrality])
    if columns is not None:
        columns = columns.reshape(3, -1)
    else:
        w = _plain_numbers(weights)
        if w is None:
            w = as_vector(weights, "weights")
        r = w.size
        h = _per_term(dof, "dof", r, 1.0)
        d = _per_term(noncentrality, "noncentrality", r, 0.0)
        columns = np.array([w, h, d])
    if not (type(sigma) is float and math.isfinite(sigma)):
        sigma = as_finite(sigma, "sigma", what="the standard deviation of the normal term")
    if sigma < 0:
        raise ValueError(
            f"sigma (the standard deviation of the normal term) must be >= 0, got {sigma}"
        )
    smallest_dof, smallest_noncentrality = columns[1:].min(axis=1).tolist()
    if smallest_dof <= 0:
        raise ValueError(f"dof (degrees of freedom) must be positive, got {smallest_dof:g}")
    if smallest_noncentrality < 0:
        raise ValueError(
            f"noncentrality must be non-negative (squared means), got {smallest_noncentrality:g}"
        )
    return _merged(columns, sigma)


def _merged(columns, sigma=0.0):
    """``(w, h, d, sigma)`` from validated rows ``(w, h, d)``: zeros dropped, sorted, equal merged."""
    w = columns[0]
    if not _every(w):
        columns = columns[:, w != 0]
    if columns.shape[1] > 1:
        columns = columns[:, columns[0].argsort(kind="stable")]
    w, h, d = columns
    if w.size > 1:
        scale = max(-w[0], w[-1])
        gaps = w[1:] - w[:-1]
        if gaps.min() <= _MERGE_RTOL * scale:
            breaks = np.flatnonzero(gaps > _MERGE_RTOL * scale) + 1
            starts = np.concatenate([[0], breaks])
            first = w[starts]
            # the mean of a group as its first weight plus the mean offset: w h would
            # overflow for weights near the largest double
            offsets = w - np.repeat(first, np.diff(np.append(starts, w.size)))
            h_sum = np.add.reduceat(h, starts)
            w = first + np.add.reduceat(offsets * h, starts) / h_sum
            h, d = h_sum, np.add.reduceat(d, starts)
    return w, h, d, sigma


def _term_constants(w, h, d):
    """Per-term summands of the constants of :class:`_Side`.

    ``d/2``; ``h/2`` (k); ``w (h + d)`` (mean); ``2 w^2 (h + 2d)`` (variance);
    ``-h/2 log(2|w|) - d/4`` (log D of the truncation bound, see :func:`_plan`);
    ``d/(4w)``, ``(h + d)/(4w)`` and ``-h/2 log(2w)`` (positive weights only:
    see :func:`_near_zero`).
    """
    positive = w > 0
    log_d = -0.5 * h * (np.log(np.abs(w)) + math.log(2.0))
    quarter = 0.25 / w * positive
    if not _some(d):  # (central: the same values without the zero terms)
        zero = 0.0 * d
        return zero, 0.5 * h, w * h, 2.0 * w * w * h, log_d, zero, h * quarter, log_d * positive
    h_d = h + d
    return (
        0.5 * d,
        0.5 * h,
        w * h_d,
        2.0 * w * w * (h + 2.0 * d),
        log_d - 0.25 * d,
        d * quarter,
        h_d * quarter,
        log_d * positive,
    )


def _derivative_factors(w, h, d):
    """Per-term factors of the derivatives of ``K`` (arrays; None for the noncentral ones of a central law).

    With ``t = 1/(1 - 2 w s)``: ``K' = sum t hw + t^2 dw``,
    ``K'' = sum t^2 c2 + t^3 n2``, ``K''' = sum t^3 c3 + t^4 n3``.
    """
    hw = h * w
    if not _some(d):  # (central: the noncentral factors are never used)
        return 2.0 * w, hw, None, 2.0 * w * hw, 8.0 * w * w * hw, None, None
    dw = d * w
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
        if _some(small):
            us = u[small]
            v = us / (2.0 + us)
            v2 = v * v
            series = 1.0 / 19.0
            for n in range(17, 1, -2):
                series = series * v2 + 1.0 / n
            out[small] = 2.0 * v * v2 * series - us * us / (2.0 + us)
    return out


def _tolerances(atol, rtol):
    """Validated ``(atol, rtol)``: non-negative, not both zero, and attainable in doubles."""
    plain = type(atol) is float and type(rtol) is float  # (the usual case: two floats)
    if not (plain and math.isfinite(atol) and math.isfinite(rtol)):
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
    if type(c) is float or type(c) is int:  # (one number, not NaN: the usual scalar call)
        try:
            value = float(c)
        except OverflowError:  # (an int beyond the doubles: as_float_array says so)
            value = math.nan
        if value == value:
            return np.array([value]), ()
    x = as_float_array(c, "c", finite=False)
    return x.ravel(), x.shape


def _warn_unconverged(conv, err, stacklevel=4):
    if not _every(conv):
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
