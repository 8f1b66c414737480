"""The NIS, the NEES and the NIS matrix of whitened innovations."""

from __future__ import annotations

import numbers

import numpy as np
from numpy.linalg import LinAlgError

from course.linalg import (
    as_float_array,
)

_SYMMETRY_RTOL = 1e-10


# ---------------------------------------------------------------------------
# input checks
# ---------------------------------------------------------------------------
def _check_int(value, name: str, minimum: int, what: str) -> int:
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} ({what}) must be an integer, got {value!r}")
    if not isinstance(value, numbers.Integral):
        if isinstance(value, numbers.Real) and float(value).is_integer():
            value = int(value)
        else:
            raise ValueError(f"{name} ({what}) must be an integer, got {value!r}")
    value = int(value)
    if value < minimum:
        raise ValueError(f"{name} ({what}) must be at least {minimum}, got {value}")
    return value


def _check_dims(m, K) -> tuple[int, int]:
    m = _check_int(m, "m", 1, "the innovation dimension")
    K = _check_int(K, "K", 1, "the number of time steps")
    if m > K:
        raise ValueError(
            f"K = {K} < m = {m}: a sum of K < m outer products is singular, so its smallest "
            "eigenvalue is 0 and the Wishart law does not apply; use at least m time steps"
        )
    return m, K


def _check_which(which) -> str:
    if which not in ("max", "min"):
        raise ValueError(f'which must be "max" or "min", got {which!r}')
    return which


def _innovations_and_factor(innovations, S, name_eps="innovations", name_S="S"):
    """Validate (..., K, m) innovations and their covariances; return (eps, L)."""
    eps = as_float_array(innovations, name_eps)
    if eps.ndim < 2:
        raise ValueError(
            f"{name_eps} must have shape (K, m) or (..., K, m) (time along the second-to-last "
            f"axis), got shape {eps.shape}; for a scalar output pass {name_eps}[:, None]"
        )
    m = eps.shape[-1]
    if isinstance(S, np.ndarray) and S.ndim > 2:
        # A covariance shared by all runs often arrives as a broadcast view
        # (stride 0, e.g. a Kalman filter's S): factor each distinct matrix once.
        S = S[
            tuple(
                slice(0, 1) if stride == 0 and size > 1 else slice(None)
                for stride, size in zip(S.strides[:-2], S.shape[:-2])
            )
        ]
    cov = as_float_array(S, name_S)
    if cov.ndim < 2 or cov.shape[-2:] != (m, m):
        raise ValueError(
            f"{name_S} must have shape ({m}, {m}) or (..., K, {m}, {m}) to match {name_eps} of "
            f"shape {eps.shape}, got {cov.shape}"
        )
    try:
        np.broadcast_shapes(cov.shape[:-2], eps.shape[:-1])
    except ValueError:
        raise ValueError(
            f"{name_S} of shape {cov.shape} does not broadcast against {name_eps} of shape "
            f"{eps.shape}: give one ({m}, {m}) matrix or one per time step, (K, {m}, {m})"
        ) from None
    scale = np.max(np.abs(cov), axis=(-2, -1), keepdims=True)
    if np.any(np.abs(cov - np.swapaxes(cov, -1, -2)) > _SYMMETRY_RTOL * scale):
        raise ValueError(f"{name_S} is not symmetric; a covariance matrix must equal its transpose")
    try:
        L = np.linalg.cholesky(cov)
    except LinAlgError:
        raise LinAlgError(
            f"{name_S} is not positive definite (Cholesky factorisation failed); "
            "check that it is a valid innovation covariance"
        ) from None
    return eps, L


def _whiten(L: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """Forward substitution ``L z = eps`` over stacks (no inverse is formed)."""
    m = eps.shape[-1]
    shape = np.broadcast_shapes(L.shape[:-2], eps.shape[:-1]) + (m,)
    z = np.empty(shape)
    for i in range(m):
        acc = eps[..., i] - np.einsum("...j,...j->...", L[..., i, :i], z[..., :i])
        z[..., i] = acc / L[..., i, i]
    return z


# ---------------------------------------------------------------------------
# statistics
# ---------------------------------------------------------------------------
def nis(innovations, S) -> np.ndarray:
    """Normalised innovation squared ``eps_k^T S_k^{-1} eps_k`` at every step.

    Parameters
    ----------
    innovations : array_like, shape (K, m) or (..., K, m)
        Innovations, time along the second-to-last axis (leading axes are
        independent runs).
    S : array_like, shape (m, m) or (..., K, m, m)
        Innovation covariances: one for all steps or one per step
        (broadcast against ``innovations``).

    Returns
    -------
    numpy.ndarray, shape (..., K)
        Under H0 each value is ``chi2(m)`` and the values are independent.

    Raises
    ------
    ValueError
        Wrong shapes, NaN/inf, non-symmetric ``S``.
    numpy.linalg.LinAlgError
        ``S`` not positive definite.

    Notes
    -----
    With ``S_k = B_k B_k^T`` (lower Cholesky factor),
    ``eps_k^T S_k^{-1} eps_k = |B_k^{-1} eps_k|^2``; the whitened vector is
    found by forward substitution, never with an inverse ([F], eq. 4).
    """
    eps, L = _innovations_and_factor(innovations, S)
    z = _whiten(L, eps)
    return np.einsum("...i,...i->...", z, z)


def nees(errors, P) -> np.ndarray:
    """Normalised estimation error squared ``e_k^T P_k^{-1} e_k`` at every step.

    The same computation as :func:`nis` with the estimation errors
    ``e_k = x_k - xhat_k`` (known in simulation only) and the filter's
    covariances ``P_k``; under H0 each value is ``chi2(n)`` ([BS], Sec. 5.4.2).

    Parameters
    ----------
    errors : array_like, shape (K, n) or (..., K, n)
    P : array_like, shape (n, n) or (..., K, n, n)

    Returns
    -------
    numpy.ndarray, shape (..., K)

    Notes
    -----
    ``e_k^T P_k^{-1} e_k = |B_k^{-1} e_k|^2`` with ``P_k = B_k B_k^T``
    (Cholesky, forward substitution; no inverse is formed).
    """
    eps, L = _innovations_and_factor(errors, P, "errors", "P")
    z = _whiten(L, eps)
    return np.einsum("...i,...i->...", z, z)


def nis_matrix(innovations, S, window: int | None = None) -> np.ndarray:
    """The NIS matrix ``Pi = (1/K) sum_k B_k^{-1} eps_k eps_k^T B_k^{-T}``.

    Parameters
    ----------
    innovations : array_like, shape (K, m) or (..., K, m)
        Innovations, time along the second-to-last axis.
    S : array_like, shape (m, m) or (..., K, m, m)
        Innovation covariances, ``S_k = B_k B_k^T`` with ``B_k`` lower
        triangular (Cholesky).
    window : int, optional
        Average over a sliding window of this many steps (the poster's
        ``Pi_k`` for ``k = window-1, ..., K-1``); by default over all steps.

    Returns
    -------
    numpy.ndarray
        ``(..., m, m)``, or ``(..., K - window + 1, m, m)`` with a window.

    Notes
    -----
    [F], eq. (3).  Under H0, ``K * Pi ~ W_m(K, I)``: the poster states
    ``Pi ~ W_m(K, I)``, which forgets its own ``1/K``; ``Pi`` itself has mean
    ``I``.  Its trace is the time-averaged NIS ([F], eq. 4).
    """
    eps, L = _innovations_and_factor(innovations, S)
    z = _whiten(L, eps)
    K = z.shape[-2]
    if window is None:
        return np.einsum("...ki,...kj->...ij", z, z) / K
    window = _check_int(window, "window", 1, "the number of steps averaged")
    if window > K:
        raise ValueError(f"window = {window} is longer than the {K} steps given")
    outer = z[..., :, :, None] * z[..., :, None, :]
    # Exact window sums (no running-sum cancellation): a strided view, summed.
    views = np.lib.stride_tricks.sliding_window_view(outer, window, axis=-3)
    return views.sum(axis=-1) / window


def nis_matrix_eigenvalues(innovations, S) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest eigenvalue of the NIS matrix over all steps.

    Works on stacks (a leading batch of Monte Carlo runs), so a detection
    study needs no Python loop over runs.

    Parameters
    ----------
    innovations : array_like, shape (K, m) or (..., K, m)
    S : array_like, shape (m, m) or (..., K, m, m)
        As in :func:`nis_matrix`.

    Returns
    -------
    lmin, lmax : numpy.ndarray, shape (...)

    Notes
    -----
    Under H0 they follow :func:`extreme_eigenvalue` ``(m, K, "min")`` and
    ``(m, K, "max")``: ``K Pi ~ W_m(K, I)`` ([F], eq. 3, ``1/K`` restored).
    """
    values = np.linalg.eigvalsh(nis_matrix(innovations, S))
    return values[..., 0], values[..., -1]
