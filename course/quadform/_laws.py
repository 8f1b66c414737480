"""Frozen laws: :class:`WeightedChiSquare` and the quadratic form :class:`QuadraticForm`.

The works cited here are in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import optimize, special, stats

from .._law_inputs import _levels
from ..distributions import FrozenDistribution
from ..linalg import symmetrize
from ..validation import as_covariance, as_finite, as_generator, as_matrix, as_vector
from ._contour import _density, _probabilities
from ._ltz import _ltz_matching, _ltz_points, _ltz_quantiles
from ._search import _search
from ._terms import (
    _ZERO_RTOL,
    ATOL,
    RTOL,
    _fmt,
    _merged,
    _readonly,
    _squeeze,
    _terms,
    _tolerances,
    _warn_unconverged,
)

# Half-width, in standard deviations, of the first bracket of a quantile
# around its Liu-Tang-Zhang guess (see WeightedChiSquare._quantiles).
_LTZ_BRACKET = 0.05
# Interpolation nodes in a bracket of a quantile (the coarse interpolant takes every other).
_NODES = 9
# ... the Chebyshev-Lobatto points of [-1, 1], increasing
_CHEBYSHEV = np.cos(np.pi * np.arange(_NODES) / (_NODES - 1))[::-1]
# Evaluations of a quantile's estimate in the bracket before the root search takes it
# (a safeguarded Newton-secant step each; bisection alone would need ~50).
_POLISH_STEPS = 60


# ---------------------------------------------------------------------------
# frozen distributions
# ---------------------------------------------------------------------------
class WeightedChiSquare(FrozenDistribution):
    r"""Law of :math:`\sum_r w_r \chi^2(h_r, \delta_r^2) + \sigma Z + q_0` (``offset`` :math:`q_0`).

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

    See Also
    --------
    QuadraticForm : The law of :math:`x^T A x`, reduced to this one.
    imhof_cdf, imhof_sf : The integrals behind ``cdf`` and ``sf``.
    liu_tang_zhang_sf : The approximation that starts the quantile search.

    Notes
    -----
    The cumulants are

    .. math::

        \kappa_j = 2^{j-1} (j-1)! \sum_r w_r^j (h_r + j \delta_r^2)
            \quad (j \ge 3),

    and the first two carry the normal term and the offset:

    .. math::

        \operatorname{E} Q = \sum_r w_r (h_r + \delta_r^2) + q_0, \qquad
        \operatorname{Var} Q = 2 \sum_r w_r^2 (h_r + 2 \delta_r^2) + \sigma^2 .

    Every method works on the law scaled to :math:`\max(|w_r|, \sigma) = 1`:
    a law with weights of 1e300 has an infinite variance in doubles, not an
    overflow.

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

    def _outside(self, lower, upper):
        """``P(X <= lower) + P(X > upper)`` (a two-sided critical region) in one evaluation."""
        points = np.array([lower, upper], dtype=float)
        lo_bound, hi_bound = self._bounds
        if not ((points > lo_bound) & (points < hi_bound)).all():
            return self.cdf(lower) + self.sf(upper)
        sf, cdf, err, conv = self._both(points)
        _warn_unconverged(conv, err, stacklevel=4)
        return cdf[0] + sf[1]

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

    # -- quantiles: one vectorised search for every level (and both tails) -----
    def _invert(self, q, func, increasing):
        """``ppf`` (``increasing``) or ``isf`` at the levels ``q``, by :meth:`_quantiles`.

        A single level is memoised together with its mirror: a two-sided
        critical region asks ``ppf(alpha/2)`` and then ``isf(alpha/2)``, and
        one search finds both.
        """
        if isinstance(q, (float, int)) and not isinstance(q, bool) and 0.0 < q < 1.0:
            memo = self.__dict__.setdefault("_quantile_memo", {})
            key = (increasing, float(q))
            if key not in memo:
                low, high = self._quantiles(np.array([float(q), float(q)]), np.array([True, False]))
                memo[(True, float(q))], memo[(False, float(q))] = low, high
            return np.float64(memo[key])
        levels = _levels(q)
        out = np.empty(levels.shape)
        lower, upper = self._bounds
        out[levels == 0.0] = lower if increasing else upper
        out[levels == 1.0] = upper if increasing else lower
        inside = (levels > 0.0) & (levels < 1.0)
        if inside.any():
            out[inside] = self._quantiles(levels[inside], np.full(int(inside.sum()), increasing))
        return out[()] if out.ndim == 0 else out

    def _quantiles(self, levels, lower):
        """The points where ``P(X <= x)`` (``lower``) or ``P(X > x)`` equals ``levels``.

        Newton's method from the Liu-Tang-Zhang guess on contours set up once
        at the guesses (:mod:`course.quadform._search`: one integral set-up for
        every level and both tails, the derivative from the same nodes); the
        levels it does not settle go to the bracketing search of
        :meth:`_quantiles_by_nodes`.
        """
        big = levels > 0.5
        small = np.where(big, 1.0 - levels, levels)
        tail_lower = lower ^ big
        guess = _ltz_quantiles(small, tail_lower, self._ltz_matching, self.offset)
        terms = (*self._arrays, self.sigma)
        tol = max(4.0 * self.rtol, 1e-13)
        x, accepted = _search(
            self._sides, terms, self.offset, guess, small, tail_lower, self.atol, self.rtol, tol
        )
        lo_bound, hi_bound = self._bounds
        accepted &= (x > lo_bound) & (x < hi_bound)
        if not accepted.all():
            rest = ~accepted
            x[rest] = self._quantiles_by_nodes(levels[rest], lower[rest])
        return x

    def _quantiles_by_nodes(self, levels, lower):
        """The quantiles of :meth:`_quantiles` by a bracket and interpolation (the fallback).

        Usually one vectorised evaluation for every level together, instead of
        a root search per level (~12 integrals each).  (1) The Liu-Tang-Zhang
        approximation (:func:`_ltz_quantiles`, closed form) guesses each
        quantile; the 9 Chebyshev points of a bracket of ``+-0.05`` standard
        deviations around it (at most 5 % of ``x - b`` next to a bound ``b`` of
        the support) are evaluated in one call.  (2) Levels that bracket
        misses take a grid around a normal guess (steps of the standard
        deviation, and points approaching a bound geometrically) and then the 7
        inner Chebyshev points of the grid's bracket.  (3) The inverse of the
        log tail probability interpolated through the 9 values gives the first
        estimate; an estimate is accepted only where the log tail evaluated
        there meets its goal within the integrals' accuracy (``4 rtol``), and
        until then Newton/secant steps inside the bracket (which each value
        narrows; bisection where a step would leave it) improve it.  Next to a
        bound the coordinate is ``log|x - b|``, in which the log tail of a
        one-signed form is nearly linear (``P(X <= x) ~ C x^k``).  A level the
        grid does not bracket either, or not settled in ``_POLISH_STEPS``
        evaluations, falls back to the root search of :meth:`_root`.
        """
        # the search runs on the smaller tail (1 - p is exact for p >= 1/2)
        big = levels > 0.5
        levels = np.where(big, 1.0 - levels, levels)
        lower = lower ^ big
        mean, std = self._mean_std
        lo_bound, hi_bound = self._bounds
        goal = np.where(lower, 1.0, -1.0) * np.log(levels)
        n = levels.size
        t = _CHEBYSHEV

        def kind_of(x):
            """The coordinate of a bracket around ``x``: 1 (log(x - lo)), -1 (log(hi - x)), 0."""
            return np.where(
                math.isfinite(lo_bound) & (x < mean),
                1,
                np.where(math.isfinite(hi_bound) & (x > mean), -1, 0),
            )

        def to_y(x, kind):
            with np.errstate(divide="ignore", invalid="ignore"):  # (branches not taken)
                return np.where(
                    kind > 0,
                    np.log(np.abs(x - lo_bound)),
                    np.where(kind < 0, np.log(np.abs(hi_bound - x)), x),
                )

        # (1) a narrow bracket around the LTZ guess: every node in one evaluation
        guess = _ltz_quantiles(levels, lower, self._ltz_matching, self.offset)
        kind = np.zeros(n, dtype=int)
        y_left, y_right = np.zeros(n), np.ones(n)
        g_nodes = np.zeros((n, t.size))
        found = np.zeros(n, dtype=bool)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            kind_guess = kind_of(guess)
            y_guess = to_y(guess, kind_guess)
            # +-_LTZ_BRACKET std in x; in log|x - bound| at most +-_LTZ_BRACKET (5 % of x - bound)
            distance = np.where(kind_guess > 0, guess - lo_bound, hi_bound - guess)
            half = np.where(
                kind_guess == 0,
                _LTZ_BRACKET * std,
                np.minimum(_LTZ_BRACKET * std / distance, _LTZ_BRACKET),
            )
            usable = np.isfinite(y_guess) & np.isfinite(half) & (half > 0)
        if usable.any():
            i = slice(None) if usable.all() else np.flatnonzero(usable)  # (a slice: views)
            kind[i] = kind_guess[i]
            # (y decreases with x next to an upper bound)
            signed = np.where(kind[i] < 0, -half[i], half[i])
            y_left[i], y_right[i] = y_guess[i] - signed, y_guess[i] + signed
            y_nodes = (
                0.5 * (y_left[i] + y_right[i])[:, None]
                + 0.5 * (y_right[i] - y_left[i])[:, None] * t
            )
            g_nodes[i] = self._log_tail(
                self._from_y(y_nodes, kind[i][:, None], lo_bound, hi_bound), lower[i]
            )
            g = g_nodes[i]
            found[i] = (
                np.all(np.diff(g, axis=1) > 0, axis=1) & (g[:, 0] < goal[i]) & (goal[i] <= g[:, -1])
            )
        # (2) the others: a grid around the normal guess, then Chebyshev points inside
        miss = np.flatnonzero(~found)
        if miss.size:
            z = np.where(lower[miss], 1.0, -1.0) * special.ndtri(levels[miss])
            # (the smaller tail's quantile lies below the median: few steps beyond the mean)
            steps = [-13, -8, -5, -3, -2, -1.5, -1, -0.5, 0, 0.5, 1, 1.5, 2, 3, 5]
            with np.errstate(over="ignore"):  # (beyond the doubles: inf, outside the support)
                grid = mean + std * (z[:, None] + np.array(steps))
            near = np.array([1e-12, 1e-6, 1e-3, 0.03, 0.2])
            if math.isfinite(lo_bound):
                extra = lo_bound + (mean - lo_bound) * near
                grid = np.column_stack([grid, np.broadcast_to(extra, (grid.shape[0], near.size))])
            if math.isfinite(hi_bound):
                extra = hi_bound - (hi_bound - mean) * near
                grid = np.column_stack([grid, np.broadcast_to(extra, (grid.shape[0], near.size))])
            # strictly inside the support: at a bound the tail is exactly 0 or 1
            grid = np.sort(grid, axis=1)
            inside = (grid > lo_bound) & (grid < hi_bound)
            grid = np.where(inside, grid, mean)
            g = self._log_tail(grid, lower[miss])
            above = (g >= goal[miss, None]) & inside
            below = (g < goal[miss, None]) & inside
            first = np.argmax(above, axis=1)
            hit = above.any(axis=1) & (first > 0)
            hit[hit] = below[hit, first[hit] - 1]
            if hit.any():
                i, first, g = miss[hit], first[hit], g[hit]
                rows = np.arange(i.size)
                left, right = grid[hit, first - 1], grid[hit, first]
                kind[i] = kind_of(0.5 * (left + right))
                y_left[i], y_right[i] = to_y(left, kind[i]), to_y(right, kind[i])
                y_inner = (
                    0.5 * (y_left[i] + y_right[i])[:, None]
                    + 0.5 * (y_right[i] - y_left[i])[:, None] * t[1:-1]
                )
                x_inner = self._from_y(y_inner, kind[i][:, None], lo_bound, hi_bound)
                g_inner = self._log_tail(x_inner, lower[i])
                g_nodes[i] = np.column_stack([g[rows, first - 1], g_inner, g[rows, first]])
                found[i] = True
        result = np.empty(levels.shape)
        rows = np.flatnonzero(found)
        if rows.size:
            kind, y_left, y_right, g_nodes = kind[rows], y_left[rows], y_right[rows], g_nodes[rows]
            # (3) the inverse t(g) interpolated through the 9 nodes gives the first
            # estimate (g is mapped to [-1, 1] as t is, so the interpolation is
            # scale-free), and its slope the first Newton step
            g_mid = 0.5 * (g_nodes[:, -1] + g_nodes[:, 0])
            g_half = 0.5 * (g_nodes[:, -1] - g_nodes[:, 0])
            g_unit = (g_nodes - g_mid[:, None]) / g_half[:, None]
            goal_rows = goal[rows]
            goal_unit = (goal_rows - g_mid) / g_half
            t_nodes = np.broadcast_to(t, g_unit.shape)
            # the interpolant at the goal and 1e-6 to either side (its slope), in one call
            fine = _lagrange(g_unit, t_nodes, goal_unit[:, None] + np.array([0.0, 1e-6, -1e-6]))
            with np.errstate(divide="ignore", invalid="ignore"):
                slope = g_half * 2e-6 / (fine[:, 1] - fine[:, 2])  # d g / d t
            # the bracket: the adjacent nodes around the goal (g increases along t,
            # and g_nodes[:, 0] < goal <= g_nodes[:, -1])
            right = np.argmax(g_nodes >= goal_rows[:, None], axis=1)
            t_low, t_high = t[right - 1], t[right]
            inside = (fine[:, 0] > t_low) & (fine[:, 0] < t_high)
            at = np.where(inside, fine[:, 0], 0.5 * (t_low + t_high))
            y_mid, y_half = 0.5 * (y_left + y_right), 0.5 * (y_right - y_left)
            # an estimate is accepted only where the log tail evaluated there meets its
            # goal within the integrals' accuracy (4 rtol); until then Newton steps on
            # the interpolant's slope (a secant once two values are known) inside the
            # bracket, which every value narrows, and bisection where a step would
            # leave it (agreement of two interpolants, the old rule, is no proof: it
            # accepted a tail 1.8e-8 off at level 1e-9)
            tol = max(4.0 * self.rtol, 1e-13)
            todo = np.arange(rows.size)
            previous = None
            for _ in range(_POLISH_STEPS):
                if todo.size == 0:
                    break
                x_at = self._from_y(
                    y_mid[todo] + y_half[todo] * at[todo], kind[todo], lo_bound, hi_bound
                )
                gap = self._log_tail(x_at[:, None], lower[rows[todo]])[:, 0] - goal_rows[todo]
                keep = ~(np.abs(gap) <= tol)
                todo, gap, here = todo[keep], gap[keep], at[todo][keep]
                below = gap < 0
                t_low[todo] = np.where(below, here, t_low[todo])
                t_high[todo] = np.where(below, t_high[todo], here)
                if previous is not None:
                    at_prev, gap_prev = previous
                    with np.errstate(divide="ignore", invalid="ignore"):
                        secant = (gap - gap_prev[keep]) / (here - at_prev[keep])
                    slope[todo] = np.where(np.isfinite(secant) & (secant > 0), secant, slope[todo])
                with np.errstate(divide="ignore", invalid="ignore"):
                    step = here - gap / slope[todo]
                bisect = ~((step > t_low[todo]) & (step < t_high[todo]))
                at[todo] = np.where(bisect, 0.5 * (t_low[todo] + t_high[todo]), step)
                previous = here, gap
            result[rows] = self._from_y(y_mid + y_half * at, kind, lo_bound, hi_bound)
            # (the few still unsettled take the root search below)
            found[rows[todo]] = False
        for row in np.flatnonzero(~found):
            func = self.cdf if lower[row] else self.sf
            result[row] = self._root(func, float(levels[row]), bool(lower[row]))
        return result

    @functools.cached_property
    def _ltz_matching(self):
        """The Liu-Tang-Zhang chi-square of the law (the quantiles' first guess)."""
        return _ltz_matching(self.weights, self.dof, self.noncentrality, self.sigma)

    @functools.cached_property
    def _mean_std(self):
        """Mean and standard deviation, from the law scaled to ``max(|w|, sigma) = 1``."""
        scale = max(float(np.max(np.abs(self.weights), initial=0.0)), self.sigma)
        w = self.weights / scale
        std = scale * math.sqrt(
            float(2.0 * (w * w) @ (self.dof + 2.0 * self.noncentrality)) + (self.sigma / scale) ** 2
        )
        mean = self.offset + scale * float(w @ (self.dof + self.noncentrality))
        return mean, std

    @staticmethod
    def _from_y(y, kind, lo_bound, hi_bound):
        """``x`` from the coordinate of :meth:`_quantiles` (``log|x - bound|`` or ``x``)."""
        # (np.where evaluates every branch: inf - inf in one not taken is harmless)
        with np.errstate(over="ignore", invalid="ignore"):
            return np.where(
                kind > 0, lo_bound + np.exp(y), np.where(kind < 0, hi_bound - np.exp(y), y)
            )

    def _log_tail(self, x, lower):
        """``log P(X <= x)`` (rows where ``lower``) or ``-log P(X > x)``: increasing in ``x``."""
        sf, cdf, err, conv = self._both(x)
        _warn_unconverged(conv, err, stacklevel=6)
        with np.errstate(divide="ignore"):
            g = np.where(np.repeat(lower, x.shape[1]), np.log(cdf), -np.log(sf))
        return g.reshape(x.shape)

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


def _lagrange(nodes, values, at):
    """The polynomial through ``(nodes, values)`` (one row each) at ``at`` (one or more per row).

    Barycentric form; the nodes of a row are distinct.  ``at`` of shape
    ``(rows,)`` gives one value per row, of shape ``(rows, k)`` k values per row
    (the barycentric weights computed once).
    """
    gaps = nodes[:, :, None] - nodes[:, None, :]
    n = nodes.shape[1]
    gaps.reshape(len(nodes), n * n)[:, :: n + 1] = 1.0  # (the diagonals, through a view)
    weights = (1.0 / gaps.prod(axis=2))[:, None, :]
    points = at[:, None] if at.ndim == 1 else at
    offsets = points[:, :, None] - nodes[:, None, :]
    exact = offsets == 0.0
    terms = weights / np.where(exact, 1.0, offsets)
    value = (terms * values[:, None, :]).sum(axis=2) / terms.sum(axis=2)
    hit = exact.any(axis=2)
    if hit.any():
        rows, columns = np.nonzero(hit)
        value[rows, columns] = np.broadcast_to(values[:, None, :], exact.shape)[exact]
    return value[:, 0] if at.ndim == 1 else value


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
    r"""Law of :math:`Q = x^T A x`, :math:`x \sim N(\mu, \Sigma)`; :math:`\Sigma` may be singular.

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

    See Also
    --------
    WeightedChiSquare : The reduced law, with all the methods.
    imhof_cdf, imhof_sf : The integrals behind ``cdf`` and ``sf``.

    Notes
    -----
    Write :math:`\mu` for ``mean`` and :math:`\Sigma` for ``cov``.  With
    :math:`\Sigma = L L^T`, :math:`L = V_+ \operatorname{diag}(\sqrt{e_+})` from
    the eigenpairs of :math:`\Sigma` with positive eigenvalues (the nonzero
    spectrum of :math:`L^T A L` is that of :math:`\Sigma^{1/2} A \Sigma^{1/2}`),
    write :math:`\mu = L \nu + \mu_\perp` with :math:`\mu_\perp` orthogonal to
    the range of :math:`\Sigma`, and :math:`L^T A L = P \operatorname{diag}(\lambda) P^T`.
    With :math:`x = L (z + \nu) + \mu_\perp`, :math:`z \sim N(0, I)`,
    :math:`y = P^T (z + \nu) \sim N(P^T \nu, I)` and
    :math:`g = P^T L^T A \mu_\perp`,

    .. math::

        Q = \sum_r \bigl[\lambda_r y_r^2 + 2 g_r y_r\bigr] + \mu_\perp^T A \mu_\perp .

    Completing squares for :math:`\lambda_r \ne 0` gives
    :math:`\lambda_r \chi^2\bigl(1, ((P^T \nu)_r + g_r/\lambda_r)^2\bigr)`; the
    terms with :math:`\lambda_r = 0` are normal.  For a non-singular
    :math:`\Sigma` this is Baram (1980), (3.16)-(3.17):
    :math:`\delta_r = p_r^T \Sigma^{-1/2} \mu`, with no normal term and no offset.
    ``mean`` and ``var`` use the closed forms

    .. math::

        \operatorname{E} Q = \operatorname{tr}(A \Sigma) + \mu^T A \mu, \qquad
        \operatorname{Var} Q = 2 \operatorname{tr}\bigl((A \Sigma)^2\bigr)
            + 4 \mu^T A \Sigma A \mu .

    The reduction is done on :math:`A / \max|A_{ij}|` and :math:`x / \gamma`
    (:math:`\gamma` the larger of :math:`\max|\mu_i|` and
    :math:`\sqrt{\max|\Sigma_{ij}|}`) and scaled back, so the units of
    :math:`A` and :math:`x` do not matter until :math:`x^T A x` itself leaves
    the range of doubles (then a ValueError says so).

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

    def rvs_direct(self, size, *, rng=None):
        """Draw ``x ~ N(mean, cov)`` and return ``x^T A x`` (slow; for checks)."""
        rng = as_generator(rng)
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
    root = np.sqrt(ek)
    L = Vk * root
    nu = (Vk.T @ mu) / root
    # a full-rank cov leaves no mean outside its range (not even rounding)
    mu_perp = np.zeros_like(mu) if keep.all() else mu - Vk @ (Vk.T @ mu)
    B = symmetrize(L.T @ A @ L)
    lam, P = np.linalg.eigh(B) if B.size else (np.zeros(0), np.zeros((0, 0)))
    y_mean = P.T @ nu
    g = P.T @ (L.T @ (A @ mu_perp))
    size = np.abs(lam)
    big = float(np.max(size)) if lam.size else 0.0
    nonzero = size > _ZERO_RTOL * big * max(1, len(lam))
    lz, gz = lam[nonzero], g[nonzero]
    noncentrality = (y_mean[nonzero] + gz / lz) ** 2
    offset = float(mu_perp @ A @ mu_perp) - float(np.sum(gz**2 / lz))
    # zero eigenvalues: 2 g y with y ~ N(y_mean, 1) is a normal term
    sigma = 0.0
    if not nonzero.all():
        g0, m0 = g[~nonzero], y_mean[~nonzero]
        offset += float(np.sum(2 * g0 * m0))
        sigma = 2.0 * float(np.sqrt(np.sum(g0**2)))
        chi_sd = float(np.sqrt(np.sum(2 * lz**2 * (1 + 2 * noncentrality))))
        if sigma <= 1e-10 * chi_sd:
            sigma = 0.0  # rounding noise, not a normal component
    if lz.size:
        # (eigenvalues and squared means: finite and valid by construction)
        w, h, d, sigma = _merged(np.array([lz, np.ones(lz.size), noncentrality]), sigma)
    else:
        w, h, d = np.zeros(0), np.zeros(0), np.zeros(0)
    return w, h, d, sigma, offset, int(keep.sum())
