"""Imhof's inversion integral on a saddle-point hyperbola: the vectorised engine.

The law is normalised (:func:`_normalised`), split into its two tails
(:class:`_Side`), and each point's integral is set up (saddle point, path,
truncation, step) and summed by the trapezoidal rule, all points of a call in
one set of numpy operations.  The numerics are described in the docstring of
:mod:`course.quadform`.

The works cited here are in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from scipy import stats

from ._terms import (
    _BLOWUP,
    _CENTRED_DOF,
    _CHUNK,
    _COMPLEX_LOG_SIZE,
    _LOG_SQRT2_OVER_PI,
    _LOG_TRUNCATION_SHARE,
    _LOG_UNDERFLOW,
    _MAX_HALVINGS,
    _MAX_NEWTON,
    _MAX_STEP,
    _MIN_OPENING,
    _NEAR_ZERO,
    _NEGLIGIBLE,
    _NORMAL_DOF,
    _SADDLE_TOL,
    _SAFE_OPENING,
    _SQRT_2PI,
    _STEP_CONSTANT,
    _U_MAX,
    _derivative_factors,
    _every,
    _log1p_minus,
    _some,
    _term_constants,
    _two_product,
)


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
        sums = np.array(_term_constants(w, h, d)).sum(axis=1).tolist()
        (w_first, w_last), (_, h_last), (_, d_last) = (
            [(float(v[0]), float(v[-1])) for v in (w, h, d)] if r else [(0.0, 0.0)] * 3
        )
        smallest = float(np.abs(w).min()) if r else 1.0
        positive = w_last > 0
        self.s_max: Any = 0.5 / w_last if positive else math.inf
        self.s_min: Any = 0.5 / w_first if w_first < 0 else -math.inf
        # the largest weight's term: it dominates the far upper tail
        self.top: Any = (w_last, h_last, d_last) if positive else None
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
        self.huge = bool(r and (h + d).max() > _CENTRED_DOF)
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
        self.minus_half_h = -0.5 * h
        parts = [self.minus_half_h, 0.5 * d] if self.noncentral else [self.minus_half_h]
        self.exponent_weights = np.concatenate(parts + [[1.0]], dtype=complex)
        self.w2 = 2.0 * w
        self.minus_w2 = -self.w2
        # per-term factors of the derivatives of K
        self.factors = _derivative_factors(w, h, d)

    def points(self, i):
        """The side of the points ``i`` of a call: the same law (see ``_batch._BatchSide``)."""
        return self

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
    @staticmethod
    def _dot(a, v):
        """``sum_r a[:, r] v[r]``: the sum over the terms (a batch sums each point's row)."""
        return a @ v

    def derivatives(self, s, x, pole):
        """``phi'``, ``phi''``, ``phi'''`` of ``phi(s) = K(s) - s x [- log|s|]``, s of shape (n,).

        The one implementation for one law and for a batch (``_batch._BatchSide``,
        whose constants have one row per point and whose ``_dot`` sums each row).
        """
        dot = self._dot
        _, hw, dw, c2, c3, n2, n3 = self.factors
        ws = s[:, None] * self.w2
        t = 1.0 / (1.0 - ws)
        t2 = t * t
        if self.centred:
            # K' - x as sum h w (t - 1) + d w (t^2 - 1) - (x - mean), t - 1 = 2 w s t:
            # no large terms cancel
            t_minus_1 = ws * t
            g1 = dot(t_minus_1, hw) + (self.sigma2 * s - self.linear(x))
            if self.noncentral:
                g1 = g1 + dot(t_minus_1 * (t + 1.0), dw)
        elif self.sigma2:
            g1 = dot(t, hw) + (self.sigma2 * s - x)
        else:
            g1 = dot(t, hw) - x
        g2 = dot(t2, c2) + self.sigma2 if self.sigma2 else dot(t2, c2)
        t3 = t2 * t
        g3 = dot(t3, c3)
        if self.noncentral:
            if not self.centred:
                g1 = g1 + dot(t2, dw)
            g2 = g2 + dot(t3, n2)
            g3 = g3 + dot(t2 * t2, n3)
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
        dot = self._dot
        if self.centred:
            u = s[:, None] * -self.w2
            value = dot(_log1p_minus(u), -0.5 * self.h) + 0.5 * self.sigma2 * s * s
            if self.noncentral:
                value = value + dot(u * u / (1.0 + u), 0.5 * self.d)
            return value
        z = 1.0 - s[:, None] * self.w2
        value = dot(np.log(z), self.minus_half_h)
        if self.sigma2:
            value = value + 0.5 * self.sigma2 * s * s
        if self.noncentral:
            value = value + dot(1.0 / z - 1.0, 0.5 * self.d)
        return value

    # -- where the saddle point lies ------------------------------------------
    def tails(self, x):
        """``[(upper, mask, side)]``: which tail each point integrates, grouped by side.

        ``upper`` holds, for every point of ``x``, whether it lies above the
        mean (its upper tail is the smaller one); ``mask`` selects the points of
        the group (``None``: every point).  One group, unless the dof are huge
        (:attr:`huge`), where points near the mean take the centred twin: both
        tails of a group are integrated in one call of :func:`_contour`.
        """
        if not self.huge:
            return [(x > self.mean, None, self)]
        delta = self.twin.linear(x)
        near = np.abs(delta) <= 0.25 * self.var
        upper = delta > 0
        return [(upper, near, self.twin), (upper, ~near, self)]

    def bracket(self, x, upper):
        """Finite ``(lo, hi)`` holding the saddle of ``phi`` (with or without the pole) and a guess.

        Upper tail: ``(0, s_max)``; lower tail: ``(s_min, 0)``.  Infinite ends
        are replaced by bounds from ``K'`` (see the comments); the guess is the
        saddle of a Gaussian model of ``K``, or of the dominant term alone in
        the far upper tail, or of the behaviour at ``-inf`` far below a
        positive form.  ``upper`` is one flag for every point or one per point.
        """
        dx = self.linear(x) if self.centred else x - self.mean
        root = np.sqrt(dx * dx + 4.0 * self.var)
        if isinstance(upper, bool):
            return self._upper_ends(x, dx, root) if upper else self._lower_ends(x, dx, root)
        # one flag per point: both ends on every point (elementwise the values of
        # either alone), then chosen; cheaper than splitting a few points
        ends = zip(self._upper_ends(x, dx, root), self._lower_ends(x, dx, root))
        lo, hi, guess = (np.where(upper, up, low) for up, low in ends)
        return lo, hi, guess

    def _upper_ends(self, x, dx, root):
        """:meth:`bracket` of the upper tail (``dx = x - mean``, ``root`` of the Gaussian model)."""
        # Gaussian model K'(s) = mean + var s: var s^2 - (x - mean) s - 1 = 0
        guess = 2.0 / (root - dx)
        lo = 0.0 * x
        if self.top is not None:
            hi = self.s_max + lo
            w, h, d = self.top
            # h w / t + d w / t^2 = x with t = 1 - 2 s w (the top term alone)
            hw = np.float64(h * w)
            with np.errstate(over="ignore", invalid="ignore"):
                root_top = np.sqrt(hw**2 + 4.0 * d * w * x)
            if not _every(np.isfinite(root_top)):
                # (h w)² and d w x overflow at dof beyond 1e154: hypot of the split root
                root_top = np.hypot(hw, 2.0 * math.sqrt(d) * np.sqrt(w * x))
            t = (hw + root_top) / (2.0 * np.maximum(x, 1e-300))
            guess = np.where(t < 1.0, np.minimum(guess, self.s_max * (1.0 - t)), guess)
        else:
            # no positive weight, a normal term: K'(s) >= mean, so phi' > 0
            # beyond the root of sigma2 s^2 - (x - mean) s - 1
            hi = (dx + np.sqrt(dx * dx + 4.0 * self.sigma2)) / (2.0 * self.sigma2)
        return lo, hi, guess

    def _lower_ends(self, x, dx, root):
        """:meth:`bracket` of the lower tail (as :meth:`_upper_ends`)."""
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
    lo, hi, guess = side.bracket(x, upper)  # (new arrays of the points' shape)
    width = hi - lo
    s = np.minimum(np.maximum(guess, lo + 1e-9 * width), hi - 1e-9 * width)
    g1, g2, g3 = side.derivatives(s, x, pole)
    # Newton steps on the points not yet close enough (the others keep theirs),
    # on compacted copies of them: no gathering and scattering at every step
    far = np.abs(g1) > _SADDLE_TOL * np.sqrt(g2)
    if not _some(far):
        return s, g2, g3
    every = _every(far)
    i = None if every else np.flatnonzero(far)
    part = side if i is None else side.points(i)  # (each point's own law in a batch)
    s_i, lo_i, hi_i, x_i, g1_i, g2_i = (
        (s.copy(), lo, hi, x, g1, g2) if every else (s[i], lo[i], hi[i], x[i], g1[i], g2[i])
    )
    for _ in range(_MAX_NEWTON):
        right = g1_i > 0
        hi_i = np.where(right, s_i, hi_i)
        lo_i = np.where(right, lo_i, s_i)
        newton = s_i - g1_i / g2_i
        inside = (newton > lo_i) & (newton < hi_i)
        s_i = newton if _every(inside) else np.where(inside, newton, _bisect(lo_i, hi_i))
        g1_i, g2_i, g3_i = part.derivatives(s_i, x_i, pole)
        if i is None:
            s, g2, g3 = s_i, g2_i, g3_i
        else:
            s[i], g2[i], g3[i] = s_i, g2_i, g3_i
        far = np.abs(g1_i) > _SADDLE_TOL * np.sqrt(g2_i)
        if not _some(far):
            break
        if not _every(far):
            if i is None:
                s, g2, g3 = s.copy(), g2.copy(), g3.copy()
                i = np.flatnonzero(far)
            else:
                i = i[far]
            s_i, lo_i, hi_i, x_i = s_i[far], lo_i[far], hi_i[far], x_i[far]
            part = side.points(i)
            g1_i, g2_i = g1_i[far], g2_i[far]
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

    Returns ``(a, b, e0, log_tol, U, step, log_vertex)``: the hyperbola's half-widths;
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
    log_vertex = np.log(vertex)
    log_tol = (math.log(rtol * _SQRT_2PI) if rtol else -math.inf) + log_vertex
    if atol > 0:
        log_tol = np.maximum(log_tol, math.log(atol * math.pi) - e0)
    U = _truncation(x, side, pole, s0, a, b, ratio, e0, log_tol)
    # -- step (the same for every point: see the docstring) ----------------------
    step = min(_STEP_CONSTANT / -math.log(max(rtol, 1e-16)), _MAX_STEP)
    return a, b, e0, log_tol, U, step, log_vertex


def _truncation(x, side, pole, s0, a, b, ratio, e0, log_tol):
    """Truncation point ``U`` of the path ``(s0, a, b)`` at ``x``: the bound of :func:`_plan`.

    Valid for any vertex ``s0`` of the side's interval (not only the saddle
    of ``x``), so a path set up at one point bounds the tail of the integral
    at a nearby one (see :mod:`course.quadform._search`).  ``log_tol`` is the
    log of the absolute tolerance on the integral scaled by ``exp(-e0)``,
    ``e0 = K(s0) - s0 x``.
    """
    # -- truncation (bounds in Y = Im s = b sinh u: see _plan's docstring) --------
    k_e = side.k + (1.0 if pole else 0.0)
    log_tol_t = log_tol + _LOG_TRUNCATION_SHARE
    # |s'| <= sqrt(2) dY/du (a <= b) and |s| >= Y
    log_rhs = side.log_d_y + _LOG_SQRT2_OVER_PI - e0 - log_tol_t
    # Re s >= s0 - a + (a/b) Y: beyond y_positive, Re s >= 0 and |exp(-s x)| <= 1
    a_minus_s0 = a - s0
    y_positive = np.maximum(a_minus_s0, 0.0) / ratio
    log_y_need = 700.0
    # (k_e is one number, or one per point for a batch of laws)
    one_law = type(k_e) is float
    if k_e > 1 if one_law else np.all(k_e > 1):
        log_k = math.log(k_e - 1.0) if one_law else np.log(k_e - 1.0)
        log_y_need = np.minimum((log_rhs - log_k) / (k_e - 1.0), 700.0)
    algebraic = np.maximum(np.exp(log_y_need), y_positive)
    # with x > 0, exp(-s x) decays like exp(-lam Y)
    lam = np.maximum(ratio * x, 1e-300)
    decay = np.maximum(log_rhs - np.log(lam) + a_minus_s0 * x, 0.0) / lam
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
    return np.maximum(np.log(ratio_y + np.sqrt(ratio_y * ratio_y + 1.0)), 1.0)


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
    r = side.r
    coef = np.empty((s0.size, side.rows_of_path, 3), dtype=complex)
    # the last three rows, filled column by column: s, s' and the linear part
    path = coef[:, -1, :]
    path[:, 0], path[:, 1], path[:, 2] = s0, a, ib
    coef[:, -2, 0], coef[:, -2, 1], coef[:, -2, 2] = ib, ib, a
    coef[:, -3, 0], coef[:, -3, 1], coef[:, -3, 2] = -c0, -x * a, -x * ib
    # (minus_w2 is (r,) for one law, (points, r) for a batch of laws: see _batch)
    np.multiply(side.minus_w2[..., None], path[:, None, :], out=coef[:, :r, :])
    if not side.centred:  # (centred: the rows hold u = z - 1, see _integrand)
        coef[:, :r, 0] += 1.0
    if side.noncentral:
        coef[:, r : 2 * r, :] = coef[:, :r, :]
    return coef, side.exponent_weights


def _integrand(basis, coef, side, pole, complex_values=False):
    """``Im[exp(E(s) - E0) s'(u) [/ s]]`` on the hyperbola, from :func:`_path_coefficients`.

    ``coef`` is what :func:`_path_coefficients` returns (matrix, weights).
    With ``complex_values``: the complex values before ``Im`` and ``s`` at the
    nodes, ``(values, s)`` (the quantile search of :mod:`course.quadform._search`
    moves the point along a fixed path with them).

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
    if weights.ndim == 1:
        e = weights @ path[..., :-2, :]
    else:  # (a batch of laws: each point's own weights, see _batch)
        e = (weights[:, None, :] @ path[..., :-2, :])[:, 0]
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
    if complex_values:
        return value, s
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
    converged = U <= _U_MAX
    U = np.minimum(U, _U_MAX)
    h = 0.5 * step
    n = math.ceil(float(U.max()) / h)
    nodes = _nodes(h, n + 1, False)
    one = x.size == 1  # (one point: its nodes up to U, no mask)
    # chunks over x keep the (points, nodes, weights) work arrays small
    size = max(1, _CHUNK // ((n + 1) * max(side.r, 1)))
    # the coefficients of every point, when they fit one chunk (kept for the halvings)
    whole = _path_coefficients(x, side, s0, a, b, k0) if size >= x.size else None
    parts = []
    for start in range(0, x.size, size):
        i = slice(start, start + size)
        coef = (
            whole
            if whole is not None
            else _path_coefficients(x[i], side.points(i), s0[i], a[i], b[i], k0[i])
        )
        if one:
            f = _integrand(nodes[1][:, : nodes[0].searchsorted(U[0], "right")], coef, side, pole)
        else:
            f = _integrand(nodes[1], coef, side, pole)
            f *= nodes[0] <= U[i, None]
        size_f = np.abs(f)
        chunk_blown = ~(size_f.max(axis=1) <= _BLOWUP * size_f[:, 0])
        f[:, 0] *= 0.5
        parts.append((h * f.sum(axis=1), 2.0 * h * f[:, ::2].sum(axis=1), chunk_blown))
    if len(parts) == 1:  # (one chunk, the usual case: no copies)
        total, coarse, blown = parts[0]
    else:
        total, coarse, blown = (np.concatenate(column) for column in zip(*parts))
    tol = np.exp(log_tol)
    diff = np.abs(total - coarse)
    # a point's error estimate is its last difference (diff is updated in place);
    # blown points get theirs from _contour's second path
    error = diff
    # (None: every point; the first level, with no point blown, indexes nothing)
    active = np.flatnonzero(~blown) if _some(blown) else None
    for level in range(_MAX_HALVINGS + 1):
        if active is None:
            done = diff <= np.maximum(tol, rtol * np.abs(total))
            active = np.flatnonzero(~done) if not _every(done) else done[:0].nonzero()[0]
        else:
            j = active
            done = diff[j] <= np.maximum(tol[j], rtol * np.abs(total[j]))
            active = j[~done]
        if active.size == 0 or level == _MAX_HALVINGS:
            break
        j = active
        h *= 0.5
        nodes = _nodes(h, n, True)
        n *= 2
        if whole is not None:
            coef = (whole[0][j], whole[1] if whole[1].ndim == 1 else whole[1][j])
        else:
            coef = _path_coefficients(x[j], side.points(j), s0[j], a[j], b[j], k0[j])
        if one:
            f = _integrand(nodes[1][:, : nodes[0].searchsorted(U[0], "right")], coef, side, pole)
        else:
            f = _integrand(nodes[1], coef, side, pole)
            f *= nodes[0] <= U[j, None]
        refined = 0.5 * total[j] + h * f.sum(axis=1)
        diff[j] = np.abs(refined - total[j])
        total[j] = refined
    if active is not None and active.size:
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
    a, b, e0, log_tol, U, step, log_vertex = plan
    # tails far below the smallest double: the best answer is 0
    live = e0 + log_vertex > _LOG_UNDERFLOW
    every = _every(live)
    if every:  # (the usual case: no copies)
        value, error, converged, blown = _integrate(
            x, side, pole, s0, a, b, k0, e0, log_tol, U, step, rtol
        )
    else:
        value, error = np.zeros(x.shape), np.zeros(x.shape)
        converged = np.ones(x.shape, dtype=bool)
        blown = np.zeros(x.shape, dtype=bool)
    if not every and _some(live):
        i = np.flatnonzero(live)
        value[i], error[i], converged[i], blown[i] = _integrate(
            x[i],
            side.points(i),
            pole,
            s0[i],
            a[i],
            b[i],
            k0[i],
            e0[i],
            log_tol[i],
            U[i],
            step,
            rtol,
        )
    if _some(blown):
        i = np.flatnonzero(blown)
        if opening is None:
            value[i], error[i], converged[i] = _contour(
                x[i],
                side.points(i),
                upper if isinstance(upper, bool) else upper[i],
                pole,
                atol,
                rtol,
                _SAFE_OPENING,
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
    # (None until a second pass needs them)
    sf: Any = None
    cdf: Any = None
    err: Any = None
    conv: Any = None
    # (every point on one side, the usual case: one pass, no copies in and out;
    # one point, the commonest call, decided without array reductions)
    negative: Any = None
    if x.size == 1:
        one_side: Any = -1.0 if x[0] < 0 else 1.0
    else:
        negative = x < 0
        one_side = (
            None
            if x.size == 0
            else (-1.0 if _every(negative) else 1.0 if not _some(negative) else None)
        )
    passes: tuple[tuple[Any, Any], ...] = (
        ((one_side, None),) if one_side else ((1.0, ~negative), (-1.0, negative))
    )
    for sign, mask in passes:
        whole = mask is None
        if not whole and not _some(mask):
            continue
        side = _side(sides, sign)
        if not whole and sf is None:
            sf, cdf = np.empty(x.shape), np.empty(x.shape)
            err, conv = np.zeros(x.shape), np.ones(x.shape, dtype=bool)
        xs = x if whole else x[mask]
        if sign < 0:
            xs = -xs
        # P(X > xs), P(X <= xs): with no positive weight and no normal term X <= 0 <= xs
        # (allocated only where some points do not come from one contour call)
        up: Any = None
        low: Any = None
        e: Any = None
        ok: Any = None

        todo = np.isfinite(xs)
        if side.top is None and not side.sigma2:
            todo[:] = False
        elif side.positive_form:
            # a positive form: P(X <= 0) = 0, and far below the weights a closed form
            # (one test for both: x <= 0 also passes the second, the slope being > 0)
            closed = xs * side.zero_slope <= _NEAR_ZERO * (side.k + 1.0)
            if _some(closed):
                zero = xs <= 0
                tiny = ~zero & closed
                up, low, e, ok = _allocated(xs)
                up[zero], low[zero] = 1.0, 0.0
                near = _near_zero(xs[tiny], side)
                low[tiny], up[tiny] = near, 1.0 - near
                todo &= ~zero & ~tiny
        for upper, group, part in side.tails(xs):
            m_ = todo if group is None else todo & group
            every = _every(m_)  # (then no copies in and out)
            if not every and not _some(m_):
                continue
            if not every:
                upper = upper[m_]
            # one flag when every point integrates the same tail (a single point)
            flag = bool(upper[0]) if upper.size == 1 or _every(upper) or not _some(upper) else upper
            v, e_m, ok_m = _contour(xs if every else xs[m_], part, flag, True, atol, rtol)
            if flag is True:
                v_up = np.minimum(np.maximum(v, 0.0), 1.0) + 0.0  # (no -0.0)
                v_low = 1.0 - v_up
            elif flag is False:
                v_low = np.minimum(np.maximum(-v, 0.0), 1.0) + 0.0
                v_up = 1.0 - v_low
            else:
                v = np.minimum(np.maximum(np.where(upper, v, -v), 0.0), 1.0) + 0.0
                v_up = np.where(upper, v, 1.0 - v)
                v_low = np.where(upper, 1.0 - v, v)
            if every:
                e, ok, up, low = e_m, ok_m, v_up, v_low
            else:
                if up is None:
                    up, low, e, ok = _allocated(xs)
                e[m_], ok[m_], up[m_], low[m_] = e_m, ok_m, v_up, v_low
        if up is None:
            up, low, e, ok = _allocated(xs)
        if whole:
            return (up, low, e, ok) if sign > 0 else (low, up, e, ok)
        if sign > 0:
            sf[mask], cdf[mask] = up, low
        else:
            cdf[mask], sf[mask] = up, low
        err[mask], conv[mask] = e, ok
    if sf is None:  # (no points)
        return x.copy(), x.copy(), x.copy(), x == x
    return sf, cdf, err, conv


def _allocated(xs):
    """``(P(X > x), P(X <= x), error, converged)`` arrays for ``xs``: 0, 1, 0, True."""
    return np.zeros(xs.shape), np.ones(xs.shape), np.zeros(xs.shape), xs == xs


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

    The law is taken as normal when its skewness and excess kurtosis are both below
    1e-20 (the Edgeworth corrections then stay below 1e-15 of the tails down to the
    smallest double); that needs more than ``_NORMAL_DOF`` degrees of freedom in some
    term (a chi-square's skewness is ``sqrt(8/k)``). Near there the cumulants' sums
    approach the largest double: they are taken on ``h/H`` and ``d/H`` (``H`` a power
    of two, so exactly), the mean as an unevaluated sum of exact products.
    """
    largest = float(np.max(h + d))
    if largest <= _NORMAL_DOF:
        return None
    H = 2.0 ** (math.frexp(largest)[1] - 1)
    hs, ds = h / H, d / H
    var = float(2.0 * (w * w) @ (hs + 2.0 * ds)) + sigma * sigma / H  # κ2 / H
    k3 = float(8.0 * (w**3) @ (hs + 3.0 * ds))  # κ3 / H
    k4 = float(48.0 * (w**4) @ (hs + 4.0 * ds))  # κ4 / H
    if not var > 0.0:
        return None
    kappa2 = var * H  # (the ratios in this order: var² may underflow)
    skewness = abs(k3) / var / math.sqrt(kappa2)
    kurtosis = abs(k4) / var / kappa2
    if not (skewness <= 1e-20 and kurtosis <= 1e-20):
        return None
    parts = np.concatenate([*_two_product(w, hs), *_two_product(w, ds)]).tolist()
    mean = math.fsum(parts)
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
    """``P(X <= x)`` of a positive form far below its weights (at ``x > 0``).

    ``M(-t) = C t^{-k} (1 + sum (d - h)/(4 w t) + O(t^-2))`` as ``t -> inf``
    with ``C = prod (2w)^{-h/2} e^{-sum d/2}``, so ``P(X <= x) = C x^k /
    Gamma(k+1) (1 + O(x sum (h + d)/(4 w)))``: where the correction is below
    the double precision, ``x sum (h + d)/(4 w) <= _NEAR_ZERO (k + 1)``, the
    leading term is the answer (computed in logs: ``imhof_cdf(1e-300, [5.0])``
    is 8e-152, where a saddle point would overflow).
    """
    return np.exp(side.k * np.log(xs) + side.log_c0)


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
        if not _some(mask):
            continue
        side = _side(sides, sign)
        if side.top is None and not side.sigma2:
            continue
        xs = sign * x[mask]
        if not side.sigma2 and not _some(xs):
            # x = 0: an end point of a one-signed support (never asked by the
            # base class), or inside a mixed one where the density is
            # finite only when k > 1
            if mixed:
                out[mask] = np.inf if side.k <= 1 else _density_core(xs, side, atol, rtol)
            continue
        finite = np.isfinite(xs)  # the density vanishes at +-inf
        if _some(finite):
            value = np.zeros(xs.shape)
            value[finite] = _density_core(xs[finite], side, atol, rtol)
            out[mask] = value
    with np.errstate(over="ignore"):
        return np.maximum(out, 0.0) / m


def _density_core(x, side, atol, rtol):
    out = np.empty(x.shape)
    for is_upper, mask, part in side.groups(x):
        if _some(mask):
            out[mask] = _contour(x[mask], part, is_upper, False, atol, rtol)[0]
    return out
