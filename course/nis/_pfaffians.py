"""Pfaffian numerics of Chiani's closed forms, in an orthonormal basis that keeps its digits.

Sources: Chiani (2014, 2017) for the Pfaffians, de Bruijn (1955) for the integration formula
behind them, Parlett and Reid (1970) for the elimination that evaluates a Pfaffian; full
references in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.polynomial import legendre
from scipy import special

_HALF_LOG_2PI = 0.5 * np.log(2 * np.pi)


# ---------------------------------------------------------------------------
# the exact laws: Chiani's Pfaffian in an orthonormal Laguerre basis
# ---------------------------------------------------------------------------
def _stirling_correction(x: float) -> float:
    """``log Gamma(x) - [(x - 1/2) log x - x + log(2 pi)/2]`` for x >= 10."""
    inv, inv2 = 1.0 / x, 1.0 / (x * x)
    return inv * (1 / 12 - inv2 * (1 / 360 - inv2 * (1 / 1260 - inv2 * (1 / 1680 - inv2 / 1188))))


def _log1pmx(d: np.ndarray) -> np.ndarray:
    """``log(1 + d) - d`` without cancellation for small ``|d|``."""
    d = np.asarray(d, dtype=float)
    shape = d.shape
    d = d.reshape(-1)
    out = np.log1p(d) - d
    small = np.abs(d) < 0.1
    if np.any(small):
        ds = d[small]
        term, total = ds * ds, np.zeros_like(ds)
        for k in range(2, 20):
            total += term / k if k % 2 == 0 else -term / k
            term = term * ds
        out[small] = -total
    return out.reshape(shape)


def _log_gamma_kernel(a: float, t: np.ndarray) -> np.ndarray:
    """``a log t - t - log Gamma(a)`` (log of ``t`` times the Gamma(a) density).

    For large ``a`` the three terms are each about ``a log a`` while their sum
    is O(log a); it is rewritten as ``a (log(1+d) - d) + log(a)/2 - log(2 pi)/2
    - stirling(a)`` with ``d = t/a - 1`` so the digits survive.
    """
    t = np.asarray(t, dtype=float)
    if a < 10:
        with np.errstate(divide="ignore"):
            return special.xlogy(a, t) - t - special.gammaln(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = a * _log1pmx(t / a - 1.0) + 0.5 * np.log(a) - _HALF_LOG_2PI - _stirling_correction(a)
    return np.where(t > 0, out, -np.inf)


def _log_gamma_density(a: float, t: np.ndarray) -> np.ndarray:
    """log of the Gamma(a) density at ``t >= 0`` (``-inf``, 0 or ``inf`` at ``t = 0``)."""
    t = np.asarray(t, dtype=float)
    if a < 10:
        with np.errstate(divide="ignore"):
            return special.xlogy(a - 1.0, t) - t - special.gammaln(a)
    positive = t > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        out = _log_gamma_kernel(a, t) - np.log(np.where(positive, t, 1.0))
    return np.where(positive, out, -np.inf)


def _log_gamma_ratio_half(a: float) -> float:
    """``log(Gamma(a + 1/2) / Gamma(a))``, accurate for large ``a`` too."""
    if a < 10:
        return float(special.gammaln(a + 0.5) - special.gammaln(a))
    # Stirling for both: a log(a + 1/2) - (a - 1/2) log a - 1/2 = a (log1p(h) - h) + log(a)/2.
    h = 0.5 / a
    return float(
        a * _log1pmx(np.array(h))
        + 0.5 * np.log(a)
        + _stirling_correction(a + 0.5)
        - _stirling_correction(a)
    )


def _pfaffian(A: np.ndarray) -> np.ndarray:
    """Pfaffian of a stack of skew-symmetric matrices ``(..., n, n)``.

    Parlett-Reid elimination with partial pivoting (a skew ``L T L^T``
    factorisation), O(n^3) per matrix; ``Pf(A)^2 = det(A)``.
    """
    A = np.array(A, dtype=float)
    n: int = A.shape[-1]
    batch: tuple[int, ...] = A.shape[:-2]
    if n % 2:
        return np.zeros(batch)
    A = A.reshape((-1, n, n))
    rows = np.arange(len(A))
    pf = np.ones(len(A))
    for k in range(0, n - 1, 2):
        pivot = k + 1 + np.argmax(np.abs(A[:, k + 1 :, k]), axis=1)
        swap = pivot != k + 1
        if np.any(swap):
            r, p = rows[swap], pivot[swap]
            A[r, k + 1, :], A[r, p, :] = A[r, p, :], A[r, k + 1, :].copy()
            A[r, :, k + 1], A[r, :, p] = A[r, :, p], A[r, :, k + 1].copy()
            pf[swap] = -pf[swap]
        head = A[:, k, k + 1].copy()
        pf *= head
        if k + 2 < n:
            safe = np.where(head != 0.0, head, 1.0)
            tau = A[:, k, k + 2 :] / safe[:, None]
            col = A[:, k + 2 :, k + 1]
            A[:, k + 2 :, k + 2 :] += (
                tau[:, :, None] * col[:, None, :] - col[:, :, None] * tau[:, None, :]
            )
    return pf.reshape(batch)


#: Gauss-Legendre nodes per panel and panel width in v = sqrt(y) of the quadrature of
#: :class:`_LaguerreBasis`: the CDFs agree with the high-precision reference to ~1e-14
#: (16 nodes per 1.0 already lose three digits, 32 per 3.0 lose four).
_PANEL_NODES = 24
_PANEL_WIDTH = 1.5
#: Distance in v past the finite end of a tail interval beyond the basis' support after
#: which its integrands have fallen below 1e-30 of their value at that end.
_V_MARGIN = 6.0


@functools.cache
def _panel_rule(n: int):
    """Gauss-Legendre nodes and weights on [-1, 1] and the running-integral matrix.

    ``S @ f`` integrates the degree ``n - 1`` interpolant of the values ``f``
    at the nodes from -1 up to each node.  Gauss-Legendre integrates products
    of two such functions (degree ``2n - 2``) exactly, which is what the
    double integrals need.
    """
    x, weights = legendre.leggauss(n)
    to_coefficients = np.linalg.solve(legendre.legvander(x, n - 1), np.eye(n))
    S = legendre.legvander(x, n) @ legendre.legint(to_coefficients, lbnd=-1, axis=0)
    return x, weights, S


class _LaguerreBasis:
    """Chiani's skew matrix in a basis of Laguerre functions, entries by quadrature.

    The basis is ``f_k(y) = c w(y) P_k(2y)``, ``k < m``: ``w`` the Gamma(a)
    density, ``P_k`` the generalised Laguerre polynomial ``L_k^(alpha)``,
    ``alpha = 2a - 1 = K - m``, normalised so that the ``f_k`` are
    orthonormal for the inner product ``int f_i f_j y dy`` (the weight
    ``y^alpha e^{-2y}``); ``c = sqrt(2) pi^(1/4) (Gamma(a)/Gamma(a+1/2))^(1/2)``.
    Orthonormal functions make the skew matrix of the whole half-line well
    conditioned (condition number below 100 for m <= 30 at every K), where
    the powers of a standardised variable reached 1e34 at m = 24, K = 30.

    In ``v = sqrt(y)`` the integrands ``2 v f_k(v^2) = 2 c' v^alpha e^{-v^2}
    P_k(2 v^2)`` are smooth (``alpha`` is a non-negative integer), so the
    running integrals ``G_k(z) = int_lo^z f_k`` and the double integrals
    ``H_kl = int f_l G_k`` come from composite Gauss-Legendre panels (the
    running integral by the spectral integration matrix of each panel).  The
    functions are negligible (below 1e-30 of their largest value) outside
    ``[v_low, v_high]``, found once per law on a grid around the turning
    points of ``P_{m-1}``, so an interval is cut there; a tail interval
    beyond them is cut :data:`_V_MARGIN` past its finite end, where its
    integrand has fallen by 1e-30 relative to that end, so tiny tail
    probabilities keep their relative accuracy.
    """

    def __init__(self, m: int, a: float):
        self.m, self.a = m, a
        self.alpha = 2.0 * a - 1.0
        self.log_scale = 0.5 * np.log(2.0) + 0.25 * np.log(np.pi) - 0.5 * _log_gamma_ratio_half(a)
        # The basis lives between the outer turning points of P_{m-1}; beyond them it decays
        # like a Gaussian of width 1/2 in v.  Cut where every function is below 1e-30 of the
        # largest value, found on a grid of step 0.05 in v.
        k = m - 1
        centre, spread = 2 * k + self.alpha + 1, 2 * np.sqrt(k * (k + self.alpha + 1))
        v = np.arange(
            max(np.sqrt(max(centre - spread, 0.0) / 2) - 2 * _V_MARGIN, 0.0),
            np.sqrt((centre + spread) / 2) + 2 * _V_MARGIN,
            0.05,
        )
        envelope = np.max(np.abs(self._integrand(v)), axis=0)
        kept = v[envelope >= 1e-30 * np.max(envelope)]
        self.v_low, self.v_high = max(kept[0] - 0.05, 0.0), kept[-1] + 0.05
        self.panels = max(1, int(np.ceil((self.v_high - self.v_low) / _PANEL_WIDTH)))

    def _laguerre(self, half_gap: np.ndarray) -> np.ndarray:
        """``P_k(2y)``, ``k < m``, shape ``(m,) + y.shape``, from ``half_gap = a - y``.

        Three-term recurrence of the orthonormal polynomials:
        ``r_k P_{k+1} = (2k + alpha + 1 - x) P_k - r_{k-1} P_{k-1}``,
        ``r_k = sqrt((k+1)(k+1+alpha))``, ``x = 2y``; ``alpha + 1 - x = 2(a - y)``
        is passed exactly (no cancellation at large ``a``).  The degree is the
        leading axis so that every step writes contiguous memory.
        """
        P = np.empty((self.m,) + half_gap.shape)
        P[0] = 1.0
        for k in range(self.m - 1):
            r = np.sqrt((k + 1) * (k + 1 + self.alpha))
            P[k + 1] = (2 * k + 2 * half_gap) * P[k]
            if k:
                P[k + 1] -= np.sqrt(k * (k + self.alpha)) * P[k - 1]
            P[k + 1] /= r
        return P

    def values(self, t: np.ndarray) -> np.ndarray:
        """``f_k(t)``, shape ``t.shape + (m,)`` (per unit of ``y``)."""
        w = np.exp(_log_gamma_density(self.a, t) + self.log_scale)
        return np.moveaxis(w * self._laguerre(self.a - t), 0, -1)

    def _integrand(self, v: np.ndarray) -> np.ndarray:
        """``2 v f_k(v^2)``, shape ``(m,) + v.shape``: the basis per unit of ``v``, smooth at 0."""
        y = v * v
        if self.a == 0.5:  # alpha = 0: 2 v w(v^2) = 2 e^{-v^2} / sqrt(pi), also at v = 0
            w = 2.0 * np.exp(-y + self.log_scale - 0.5 * np.log(np.pi))
        else:  # 2 v w(v^2) = 2 v^alpha e^{-v^2} / Gamma(a), 0 at v = 0
            with np.errstate(divide="ignore", invalid="ignore"):
                w = 2.0 * np.exp(_log_gamma_kernel(self.a, y) - np.log(v) + self.log_scale)
            w = np.where(v > 0, w, 0.0)
        root_a = np.sqrt(self.a)
        return w * self._laguerre((root_a - v) * (root_a + v))

    def blocks(self, lo: np.ndarray, hi: np.ndarray):
        """``(J, g)`` over ``[lo, hi]`` (``lo`` may be 0, ``hi`` infinite), stacked like ``lo``.

        ``J_kl = int int_{[lo,hi]^2} sgn(z - y) f_k(y) f_l(z) dy dz = H_kl - H_lk``
        with ``H_kl = int_lo^hi f_l(z) G_k(z) dz``, and ``g_k = int_lo^hi f_k``.
        """
        lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
        shape = lo.shape
        v0, v1 = np.sqrt(lo.reshape(-1)), np.sqrt(hi.reshape(-1))
        # Cut where the integrands are negligible (relative to the interval's own mass).
        v1 = np.minimum(v1, np.maximum(self.v_high, v0 + _V_MARGIN))
        v0 = np.maximum(v0, np.minimum(self.v_low, v1 - _V_MARGIN))
        x, weights, S = _panel_rule(_PANEL_NODES)
        J = np.empty((v0.size, self.m, self.m))
        g = np.empty((v0.size, self.m))
        # Chunks bound the memory of the (m, points, panels, nodes) arrays.
        step = max(1, 4_000_000 // (self.panels * (_PANEL_NODES + 1) * self.m))
        for start in range(0, v0.size, step):
            part = slice(start, start + step)
            edges = np.linspace(v0[part], v1[part], self.panels + 1, axis=-1)
            half = 0.5 * np.diff(edges, axis=-1)
            v = 0.5 * (edges[:, :-1] + edges[:, 1:])[..., None] + half[..., None] * x
            F = self._integrand(v)  # (m, points, panels, nodes)
            local = half[..., None] * np.matmul(F, S.T)  # running integrals within a panel
            ends = np.cumsum(half * (F @ weights), axis=-1)
            before = np.concatenate([np.zeros_like(ends[..., :1]), ends[..., :-1]], axis=-1)
            G = (local + before[..., None]).reshape(self.m, len(v), -1)
            weighted = (F * (half[..., None] * weights)).reshape(self.m, len(v), -1)
            H = np.matmul(G.transpose(1, 0, 2), weighted.transpose(1, 2, 0))
            J[part] = H - np.swapaxes(H, -1, -2)
            g[part] = ends[..., -1].T
        return J.reshape(shape + (self.m, self.m)), g.reshape(shape + (self.m,))


def _augment(J: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Border ``J`` with ``g`` for odd m (Chiani's odd-order Pfaffian)."""
    m = J.shape[-1]
    if m % 2 == 0:
        return J
    A = np.zeros(J.shape[:-2] + (m + 1, m + 1))
    A[..., :m, :m] = J
    A[..., :m, m] = g
    A[..., m, :m] = -g
    return A


def _bordered(A: np.ndarray, U: np.ndarray, V: np.ndarray) -> np.ndarray:
    n = A.shape[-1]
    B = np.zeros(A.shape[:-2] + (n + 2, n + 2))
    B[..., :n, :n] = A
    B[..., :n, n], B[..., :n, n + 1] = U, V
    B[..., n, :n], B[..., n + 1, :n] = -U, -V
    return B
