"""Quantiles by Newton's method on a frozen contour: one integral setup for every level.

A quantile search evaluates the tail probability at a point ``x`` and at
points near it.  Set up once at a guess ``x0`` (saddle point, hyperbola,
truncation point, step), the contour integral of :mod:`course.quadform._contour`
stays valid at every other point ``x0 + delta``: the path does not have to
pass through the saddle of ``x`` (Cauchy's theorem), and moving the point only
multiplies the integrand by ``exp(-s delta)``.  So, from the complex integrand
values ``v_j`` at the nodes ``s_j`` of the path at ``x0``,

.. math::

    P(\\delta) \\propto \\sum_j c_j \\operatorname{Im}\\bigl[v_j e^{-s_j \\delta}\\bigr],
    \\qquad
    P'(\\delta) \\propto \\sum_j c_j \\operatorname{Im}\\bigl[-s_j v_j e^{-s_j \\delta}\\bigr]

(``c_j`` the trapezoid weights), and Newton's method on ``log P`` converges
without another integral: a few products over the nodes each.  The root is
checked as a fresh integral would be: the two trapezoid levels agree within
the tolerance (else the step is halved, new nodes only), the truncation bound
of :func:`course.quadform._contour._truncation` at ``x0 + delta`` lies within
the nodes, and the sum lost nothing to cancellation beyond rounding.  Moves
are kept within ``|delta| <= 30 / (a (cosh U - 1))`` (``exp(-s delta)`` grows
by at most ``e^30`` at the truncation point; the checks decide); a level whose
root lies beyond is set up again at the last estimate, and the few that still
fail go to the bracketing search of :meth:`WeightedChiSquare._quantiles_by_nodes`
(``_search`` returns them unaccepted).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ._contour import (
    _integrand,
    _nodes,
    _normalised,
    _path_coefficients,
    _plan,
    _saddle,
    _side,
    _truncation,
)
from ._terms import _BLOWUP, _LOG_UNDERFLOW, _MAX_HALVINGS, _NEAR_ZERO, _SQRT_2PI, _U_MAX

# Set-ups of the path per level before the level goes to the bracketing search,
# and Newton steps on each path.
_SETUPS = 3
_NEWTON_STEPS = 8
# Largest move of the point along a path, in units of 1/(a (cosh U - 1)) where
# exp(-s delta) grows by e at the truncation point: wide, since every root is
# checked as a fresh integral would be (the levels agree, the truncation bound
# holds, no cancellation beyond rounding); on random laws 30 lets ~97 % of the
# levels settle on their first path.
_WINDOW = 30.0
# Nodes beyond the truncation point of the path's own point (see _newton_on_path).
_U_MARGIN = 0.5
# Rounding error of a sum, relative to the sum of magnitudes (generous).
_EPS_SUM = 1e-14


def _search(sides, law_terms, offset, guess, levels, lower, atol, rtol, tol):
    """Quantiles near ``guess`` where ``P(X <= x)`` (``lower``) or ``P(X > x)`` is ``levels``.

    ``law_terms`` is ``(w, h, d, sigma)``; ``levels`` are at most 1/2 (the
    smaller tail, as :meth:`WeightedChiSquare._quantiles` passes them);
    ``tol`` the accuracy of ``log P`` at the root.  Returns ``(x, accepted)``:
    the levels not accepted (no usable guess, a law in its normal limit or of
    huge dof, a root that no path reached) are left to the caller.
    """
    n = levels.size
    result = np.full(n, np.nan)
    accepted = np.zeros(n, dtype=bool)
    m, normal = _normalised(sides, *law_terms)
    if normal or sides["limit"] is not None:
        return result, accepted
    with np.errstate(over="ignore", invalid="ignore"):
        x = (guess - offset) / m
    pending = np.isfinite(x) & (x != 0)
    # a root across 0 (a mixed law) is looked for again on the other side: the
    # path of one side is not valid beyond 0, where exp(-s x) grows along it
    for sign in (1.0, -1.0, 1.0):
        rows = np.flatnonzero(pending & ((x > 0) if sign > 0 else (x < 0)))
        if rows.size == 0:
            continue
        pending[rows] = False
        side = _side(sides, sign)
        if side.huge or (side.top is None and not side.sigma2):
            continue
        xs = sign * x[rows]
        if side.positive_form:
            # where the closed form near 0 applies, the contour is not used
            keep = xs * side.zero_slope > _NEAR_ZERO * (side.k + 1.0)
            rows, xs = rows[keep], xs[keep]
        # P(Xs <= xs) for a lower level when sign > 0; mirrored, the other tail
        wanted_lower = lower[rows] ^ (sign < 0)
        for _ in range(_SETUPS):
            if rows.size == 0:
                break
            root, done = _newton_on_path(xs, side, wanted_lower, levels[rows], atol, rtol, tol)
            ok = done & (root > 0)
            result[rows[ok]] = offset + sign * m * root[ok]
            accepted[rows[ok]] = True
            across = ~ok & (root < 0)
            x[rows[across]] = sign * root[across]
            pending[rows[across]] = True
            again = ~ok & np.isfinite(root) & (root > 0)
            rows, xs, wanted_lower = rows[again], root[again], wanted_lower[again]
    return result, accepted


def _newton_on_path(x, side, wanted_lower, levels, atol, rtol, tol):
    """Newton's method on ``log P`` along the paths set up at ``x`` (points of one side).

    Returns the last estimates (kept within the window of the module
    docstring; NaN where the path itself was unusable) and whether each
    meets the goal with a checked integral.  Where the two trapezoid levels
    disagree at the root the step is halved (new nodes only), as
    :func:`course.quadform._contour._integrate` does.
    """
    upper = x > side.mean
    flag = bool(upper[0]) if upper.all() or not upper.any() else upper
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        s0, g2, g3 = _saddle(x, side, flag, True)
        k0 = side.cgf(s0)
        a, b, e0, _, U, step, log_vertex = _plan(x, side, flag, True, atol, rtol, s0, g2, g3, k0)
    root = np.full(x.shape, np.nan)
    done = np.zeros(x.shape, dtype=bool)
    usable = (U <= _U_MAX) & (e0 + log_vertex > _LOG_UNDERFLOW) & np.isfinite(s0 + a + e0)
    i: Any = slice(None)  # (every point, the usual case: views, no copies)
    if not usable.all():
        if not usable.any():
            return root, done
        i = np.flatnonzero(usable)
        x, s0, a, b, k0, e0, upper = x[i], s0[i], a[i], b[i], k0[i], e0[i], upper[i]
        U, log_vertex, wanted_lower, levels = U[i], log_vertex[i], wanted_lower[i], levels[i]
    # nodes a little beyond the truncation point at x: the bound at the root
    # (a point nearby) needs about as many
    U = np.minimum(U + _U_MARGIN, _U_MAX)
    h = 0.5 * step
    count = math.ceil(float(U.max()) / h) + 1
    u, basis = _nodes(h, count, False)
    coef = _path_coefficients(x, side, s0, a, b, k0)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        values, s = _integrand(basis, coef, side, True, True)
    imag = values.imag
    blown = ~(np.abs(imag).max(axis=1) <= _BLOWUP * np.abs(imag[:, 0]))
    # the tail integrated (the smaller one at x) against the one whose level is given
    goal = np.log(np.where(upper != wanted_lower, levels, 1.0 - levels))
    sign = np.where(upper, 1.0, -1.0)  # P = sign * integral (-P(X <= x) on a lower path)
    window = _WINDOW / (a * (np.cosh(U) - 1.0))
    # the relative part of _plan's tolerance (the saddle-point estimate of rtol times the tail)
    log_tol_path = math.log(rtol * _SQRT_2PI) + log_vertex if rtol else -np.inf
    delta = np.zeros(x.size)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        for halving in range(_MAX_HALVINGS + 1):
            weight = h * (u <= U[:, None])
            weight[:, 0] *= 0.5
            delta, total, gap, moved = _newton(
                values, s, s0, weight, e0, sign, goal, window, delta, tol
            )
            coarse = 2.0 * np.einsum("ij,ij->i", weight[:, ::2], moved[:, ::2].imag)
            e0_root = e0 - s0 * delta
            # the tolerance of _plan and _integrate at the root: the larger of the
            # saddle-point estimate and rtol times the integral, or atol
            log_tol = np.log(np.maximum(rtol * np.abs(total), atol * math.pi * np.exp(-e0_root)))
            log_tol = np.maximum(log_tol, log_tol_path)
            fine_enough = np.abs(total - coarse) <= np.exp(log_tol)
            if fine_enough.all() or halving == _MAX_HALVINGS:
                break
            # the step halved: the midpoints' values interleaved with the others
            h *= 0.5
            u_odd, basis_odd = _nodes(h, count - 1, True)
            values_odd, s_odd = _integrand(basis_odd, coef, side, True, True)
            count = 2 * count - 1
            u = _interleaved(u[None, :], u_odd[None, :])[0]
            values, s = _interleaved(values, values_odd), _interleaved(s, s_odd)
        U_root = _truncation(x + delta, side, True, s0, a, b, a / b, e0_root, log_tol)
        # no cancellation of large values beyond what rounding allows
        rounding = _EPS_SUM * np.einsum("ij,ij->i", weight, np.abs(moved.imag)) <= np.exp(log_tol)
        done[i] = ~blown & (np.abs(gap) <= tol) & fine_enough & (U_root <= U) & rounding
    root[i] = x + delta
    return root, done


def _newton(values, s, s0, weight, e0, sign, goal, window, delta, tol):
    """Newton steps on ``log P(x + delta)`` from ``delta``; ``(delta, total, gap, moved)`` at the last.

    ``total`` is the trapezoid sum (``P = sign exp(e0 - s0 delta) total / pi``),
    ``gap`` the error of ``log P`` against ``goal``, ``moved`` the integrand
    values at ``delta``.  Every row at every step: a handful of rows, no
    index bookkeeping.
    """
    live = np.ones(delta.size, dtype=bool)
    # one step more than the tolerance needs, nearly free (the convergence is
    # quadratic): the quantile then carries the integral's own accuracy, which
    # is far better than its tolerance (within rounding of log P)
    tight = np.maximum(1e-3 * tol, 1e-14 * (1.0 + np.abs(goal)))
    for _ in range(_NEWTON_STEPS + 1):
        moved = values * np.exp((s - s0[:, None]) * -delta[:, None]) if delta.any() else values
        total = np.einsum("ij,ij->i", weight, moved.imag)
        gap = e0 - s0 * delta + np.log(sign * total / math.pi) - goal
        live &= ~(np.abs(gap) <= tight)
        if not live.any():
            break
        # d log P / d delta from the same nodes: the integrand times -s
        slope = -np.einsum("ij,ij->i", weight, (moved * s).imag) / total
        step = -gap / slope
        live &= np.isfinite(step)
        delta = np.minimum(np.maximum(np.where(live, delta + step, delta), -window), window)
    return delta, total, gap, moved


def _interleaved(even, odd):
    """Columns of ``even`` and ``odd`` alternating (``even`` one column longer)."""
    out = np.empty((even.shape[0], even.shape[1] + odd.shape[1]), dtype=even.dtype)
    out[:, ::2], out[:, 1::2] = even, odd
    return out
