"""Many laws in one vectorised integral: the engine of :func:`imhof_cdf_batch`.

:class:`_BatchSide` is a :class:`~course.quadform._contour._Side` whose terms
are one row per point (each point with its own law, every law with the same
number of terms): its constants are arrays over the points, and the three
places where the engine sums over the terms (the derivatives and the value of
``K`` for the saddle point, in :class:`_Side`'s one implementation through
:meth:`_BatchSide._dot`; the exponent of the integrand) take each point's own row.  Everything else (saddle point, path, truncation, trapezoid levels,
step halvings) is the vectorised code of one law, so a point of a batch costs
what a point of a many-point call costs.

Laws the batch does not take (a normal term, over 1e4 degrees of freedom in
a term, zero weights) are evaluated law by law by the one-law engine.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special

from ._contour import _contour, _probabilities, _Side
from ._terms import _CENTRED_DOF, _NEAR_ZERO, _derivative_factors, _merged, _term_constants


class _BatchSide(_Side):
    """The terms ``(w, h, d)`` of one normalised law per point, rows sorted by weight.

    Built only by :meth:`of`; ``sigma2`` is 0 (laws with a normal term go
    law by law) and nothing is centred (no huge dof).
    """

    def __init__(self, w, h, d):  # (no super().__init__: every constant is per point)
        self.sigma2 = 0.0
        self.r = r = w.shape[1]
        self.w, self.h, self.d = w, h, d
        sums = np.array(_term_constants(w, h, d)).sum(axis=2)
        half_d, self.k, self.mean, self.var, self.log_d_y, d_over_w, self.zero_slope, log_c = sums
        w_first, w_last = w[:, 0], w[:, -1]
        with np.errstate(divide="ignore"):
            self.s_max = np.where(w_last > 0, 0.5 / w_last, math.inf)
            self.s_min = np.where(w_first < 0, 0.5 / w_first, -math.inf)
        self.top = (w_last, h[:, -1], d[:, -1])
        self.positive_form = w_first > 0
        self.y_unit = 0.5 / np.abs(w).min(axis=1)
        self.half_d_sum = half_d
        self.huge = False
        self.centred = False
        self.mean_low = 0.0
        self.noncentral = bool(d.any())
        self.d_over_w = np.where(w_first > 0, d_over_w, 0.0) if self.noncentral else 0.0 * half_d
        self.log_c0 = log_c - half_d - special.gammaln(self.k + 1.0)
        self.rows_of_path = (2 * r if self.noncentral else r) + 3
        self.minus_half_h = -0.5 * h
        parts = [self.minus_half_h, 0.5 * d] if self.noncentral else [self.minus_half_h]
        ones = np.ones((w.shape[0], 1))
        self.exponent_weights = np.concatenate(parts + [ones], axis=1, dtype=complex)
        self.w2 = 2.0 * w
        self.minus_w2 = -self.w2
        self.factors = _derivative_factors(w, h, d)

    @classmethod
    def of(cls, w, h, d):
        """The side of the laws ``(w, h, d)`` (rows), each row sorted by weight."""
        order = np.argsort(w, axis=1, kind="stable")
        return cls(*(np.take_along_axis(a, order, axis=1) for a in (w, h, d)))

    def points(self, i):
        """The side of the points ``i`` only (every per-point constant taken at ``i``)."""
        part = object.__new__(_BatchSide)
        for name, value in vars(self).items():
            if isinstance(value, np.ndarray) and value.ndim:
                value = value[i]
            elif isinstance(value, tuple):  # (the top term, the factors)
                value = tuple(None if v is None else v[i] for v in value)
            setattr(part, name, value)
        return part

    @staticmethod
    def _dot(a, v):
        """Each point's sum over its own terms (row i of ``a`` with row i of ``v``)."""
        return (a * v).sum(axis=1)

    def bracket(self, x, upper):
        """As :meth:`_Side.bracket`, with each point's own constants (``upper`` one flag per point)."""
        dx = x - self.mean
        root = np.sqrt(dx * dx + 4.0 * self.var)
        if isinstance(upper, bool):
            upper = np.full(x.shape, upper)
        # upper tail (every law here has a positive weight on this side)
        guess_up = 2.0 / (root - dx)
        w, h, d = self.top
        t = (h * w + np.sqrt((h * w) ** 2 + 4.0 * d * w * x)) / (2.0 * np.maximum(x, 1e-300))
        guess_up = np.where(t < 1.0, np.minimum(guess_up, self.s_max * (1.0 - t)), guess_up)
        # lower tail: a finite end, or the bound of a positive form
        guess_low = -2.0 / (root + dx)
        k1 = self.k + 1.0
        bound = (k1 + np.sqrt(k1 * k1 + 4.0 * self.d_over_w * x)) / (2.0 * np.maximum(x, 1e-300))
        far_below = x * self.k < 0.1 * self.mean
        positive = self.positive_form
        lo_low = np.where(positive, -bound, self.s_min)
        guess_pos = np.where(far_below, -bound, -np.sqrt(bound * -guess_low))
        guess_low = np.where(positive, guess_pos, guess_low)
        zero = 0.0 * x
        return (
            np.where(upper, zero, lo_low),
            np.where(upper, self.s_max, zero),
            np.where(upper, guess_up, guess_low),
        )


def _batch_probabilities(x, w, h, d, sigma, atol, rtol):
    """``(sf, cdf, error, converged)`` of each point ``x[i]`` under the law ``(w[i], h[i], d[i], sigma[i])``.

    ``x`` is 1-D; ``w``, ``h``, ``d`` are ``(points, r)``, ``sigma`` ``(points,)``,
    all validated.  Laws the batch engine does not take go law by law (each
    distinct law once, with all its points).
    """
    n = x.size
    sf, cdf = np.empty(n), np.empty(n)
    err, conv = np.zeros(n), np.ones(n, dtype=bool)
    fast = (sigma == 0) & (w != 0).all(axis=1) & ((h + d).max(axis=1) <= _CENTRED_DOF)
    fast &= np.isfinite(x)
    slow = np.flatnonzero(~fast)
    if slow.size:
        _law_by_law(slow, x, w, h, d, sigma, atol, rtol, (sf, cdf, err, conv))
    i = np.flatnonzero(fast)
    if i.size == 0:
        return sf, cdf, err, conv
    m = np.abs(w[i]).max(axis=1)
    xs = x[i] / m
    wn = w[i] / m[:, None]
    for sign in (1.0, -1.0):
        on = (xs >= 0) if sign > 0 else (xs < 0)
        if not on.any():
            continue
        j = i[on]
        side = _BatchSide.of(sign * wn[on], h[j], d[j])
        xj = sign * xs[on]
        up = np.zeros(j.size)  # P(Xs > xj)
        low = np.ones(j.size)
        e = np.zeros(j.size)
        ok = np.ones(j.size, dtype=bool)
        # no positive weight on this side: Xs <= 0 <= xj
        todo = side.w[:, -1] > 0
        positive = side.positive_form
        zero = positive & (xj <= 0)
        up[zero], low[zero] = 1.0, 0.0
        closed = positive & ~zero & (xj * side.zero_slope <= _NEAR_ZERO * (side.k + 1.0))
        if closed.any():
            near = np.exp(side.k[closed] * np.log(xj[closed]) + side.log_c0[closed])
            low[closed], up[closed] = near, 1.0 - near
        todo &= ~zero & ~closed
        if todo.any():
            k = np.flatnonzero(todo)
            part = side if k.size == j.size else side.points(k)
            upper = xj[k] > part.mean
            v, e_k, ok_k = _contour(xj[k], part, upper, True, atol, rtol)
            v = np.minimum(np.maximum(np.where(upper, v, -v), 0.0), 1.0) + 0.0
            up[k] = np.where(upper, v, 1.0 - v)
            low[k] = np.where(upper, 1.0 - v, v)
            e[k], ok[k] = e_k, ok_k
        if sign > 0:
            sf[j], cdf[j] = up, low
        else:
            sf[j], cdf[j] = low, up
        err[j], conv[j] = e, ok
    return sf, cdf, err, conv


def _law_by_law(rows, x, w, h, d, sigma, atol, rtol, out):
    """The points ``rows`` evaluated by the one-law engine, each distinct law once."""
    sf, cdf, err, conv = out
    keys = np.column_stack([w[rows], h[rows], d[rows], sigma[rows]])
    _, first, group = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    for g, row in enumerate(rows[first]):
        members = rows[group.ravel() == g]
        wm, hm, dm, sm = _merged(np.array([w[row], h[row], d[row]]), float(sigma[row]))
        if wm.size == 0 and sm == 0:  # every weight zero: the constant 0
            sf[members] = (x[members] < 0).astype(float)
            cdf[members] = 1.0 - sf[members]
            continue
        s, c, e, ok = _probabilities(x[members], wm, hm, dm, sm, atol, rtol)
        sf[members], cdf[members], err[members], conv[members] = s, c, e, ok
