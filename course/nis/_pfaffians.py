"""Pfaffian numerics of Chiani's closed forms, in a standardised basis that keeps its digits.

Sources: Chiani (2014, 2017) for the Pfaffians, de Bruijn (1955) for the integration formula
behind them, Parlett and Reid (1970) for the elimination that evaluates a Pfaffian; full
references in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import numpy as np
from scipy import special

_HALF_LOG_2PI = 0.5 * np.log(2 * np.pi)


# ---------------------------------------------------------------------------
# the exact laws: Chiani's Pfaffian in a standardised basis
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


def _moments(shape: float, lo: np.ndarray, hi: np.ndarray, count: int):
    """Standardised incomplete moments of the Gamma(shape) law over ``[lo, hi]``.

    ``M_k = int_lo^hi w(y) u(y)^k dy`` for ``k < count`` with ``w`` the
    Gamma(shape, 1) density, ``u = (y - shape)/sqrt(shape)``; ``lo`` may be
    0 and ``hi`` infinite.  Integration by parts gives
    ``M_{k+1} = (k/s) M_k + k M_{k-1} - [phi u^k]_lo^hi / s`` with
    ``phi(y) = y w(y)`` and ``s = sqrt(shape)``: every term is O(1), so the
    recursion keeps its digits where the raw moments ``int y^k w`` cancel.

    Returns ``(M, u(hi), phi(hi))``, ``M`` of shape ``lo.shape + (count,)``;
    ``u(hi)`` and ``phi(hi)`` are 0 where ``hi`` is infinite.
    """
    s = np.sqrt(shape)
    lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
    zeros = np.zeros(lo.shape)
    finite = np.isfinite(hi)
    has_lo = lo > 0
    # Only the special functions a side needs are evaluated: the two common
    # intervals [0, t] and [t, inf) are cheap, a general band costs more.
    if np.all(finite):
        u_hi = (hi - shape) / s
        phi_hi = np.exp(_log_gamma_kernel(shape, hi))
    else:
        u_hi = np.where(finite, (np.where(finite, hi, 0.0) - shape) / s, 0.0)
        phi_hi = np.where(finite, np.exp(_log_gamma_kernel(shape, np.where(finite, hi, 1.0))), 0.0)
    u_lo = (lo - shape) / s
    if not np.any(has_lo):
        phi_lo = zeros
    else:
        phi_lo = np.where(has_lo, np.exp(_log_gamma_kernel(shape, np.where(has_lo, lo, 1.0))), 0.0)
    # The mass of [lo, hi] from whichever regularised gamma has no cancellation.
    if not np.any(finite):
        mass = special.gammaincc(shape, lo)
    elif not np.any(has_lo):
        mass = special.gammainc(shape, hi)
    else:
        upper_side = lo >= shape
        mass = np.where(
            ~finite,
            special.gammaincc(shape, lo),
            np.where(
                ~has_lo,
                special.gammainc(shape, hi),
                np.where(
                    upper_side,
                    special.gammaincc(shape, lo) - special.gammaincc(shape, hi),
                    special.gammainc(shape, hi) - special.gammainc(shape, lo),
                ),
            ),
        )
    out = np.empty(lo.shape + (count,))
    out[..., 0] = mass
    previous = np.zeros(lo.shape)
    pow_hi, pow_lo = np.ones(lo.shape), np.ones(lo.shape)
    for k in range(count - 1):
        edge = phi_hi * pow_hi - phi_lo * pow_lo
        out[..., k + 1] = (k / s) * out[..., k] + k * previous - edge / s
        previous = out[..., k]
        pow_hi, pow_lo = pow_hi * u_hi, pow_lo * u_lo
    return out, u_hi, phi_hi


def _skew_blocks(m: int, a: float, lo: np.ndarray, hi: np.ndarray, e_scale: float):
    """Chiani's skew matrix over ``[lo, hi]``, in the basis ``w(y) u(y)^k``.

    ``J_ij = int int_{[lo,hi]^2} sgn(z - y) f_i(y) f_j(z) dy dz`` with
    ``f_k = w u^k`` (``w`` the Gamma(a) density, ``u = (y - a)/sqrt(a)``),
    and ``g_i = int_lo^hi f_i``.  Returns ``J`` of shape
    ``lo.shape + (m, m)`` and ``g`` of shape ``lo.shape + (m,)``.

    ``J = H - H^T`` with ``H_kl = int f_l(z) G_k(z) dz``,
    ``G_k(z) = int_lo^z f_k``; parts integration in ``l`` gives
    ``H_{k,l+1} = (l/s) H_kl + l H_{k,l-1} + (E_{k+l} - phi(hi) u(hi)^l g_k)/s``,
    with ``E_n = int y w(y)^2 u^n dy``, a standardised incomplete moment
    of the Gamma(2a) law over ``[2 lo, 2 hi]``:
    ``E_n = Gamma(a+1/2)/(2 sqrt(pi) Gamma(a)) 2^{-n/2} M_n^{(2a)}``
    (``e_scale`` is that constant); ``H_00 = g_0^2/2`` and
    ``H_k0 = g_0 g_k - H_0k``.
    """
    s = np.sqrt(a)
    g, u, upper = _moments(a, lo, hi, m)
    n_e = max(2 * m - 2, 1)
    m2, _, _ = _moments(2 * a, 2 * lo, 2 * hi, n_e)
    E = e_scale * m2 * 2.0 ** (-0.5 * np.arange(n_e))
    H = np.empty(g.shape[:-1] + (m, m))
    H[..., 0, 0] = 0.5 * g[..., 0] ** 2
    # Row 0 first (it fixes column 0 through H_k0 = g_0 g_k - H_0k), then
    # the remaining rows advance in l together.
    power = np.ones(g.shape[:-1])
    for l in range(m - 1):
        before = H[..., 0, l - 1] if l else 0.0
        H[..., 0, l + 1] = (
            (l / s) * H[..., 0, l] + l * before + (E[..., l] - upper * power * g[..., 0]) / s
        )
        power = power * u
    if m > 1:
        H[..., 1:, 0] = g[..., :1] * g[..., 1:] - H[..., 0, 1:]
        rows = np.arange(1, m)
        power = np.ones(g.shape[:-1])[..., None]
        for l in range(m - 1):
            before = H[..., 1:, l - 1] if l else 0.0
            H[..., 1:, l + 1] = (
                (l / s) * H[..., 1:, l]
                + l * before
                + (E[..., rows + l] - upper[..., None] * power * g[..., 1:]) / s
            )
            power = power * u[..., None]
    return H - np.swapaxes(H, -1, -2), g


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
