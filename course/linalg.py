"""Linear-algebra building blocks shared by every course module.

One home for each of the course's factorisations, so that every module
computes them the same way:

Cholesky factors and whitening
    :func:`cholesky_lower` (one matrix), :func:`cholesky_factor` (a stack of
    covariances, checked), :func:`whiten` (``L^{-1} b`` for one factor),
    :func:`whiten_vectors` and :func:`whitened_squared_norms` (vectors along
    the last axis, one factor per vector: the NIS), :func:`solve_spd`.
Least squares
    :func:`qr_solve` (full column rank: thin or full QR, the solution and
    ``R^{-1}``, whose product ``R^{-1} R^{-T}`` is the covariance factor) and
    :func:`lstsq_min_norm` (rank-revealing SVD: the minimum-norm solution and
    the residual, unique whatever the rank).
Numerical rank (one rule)
    :func:`rank_tolerance`, :func:`numerical_rank`, :func:`matrix_rank`, :func:`range_basis`,
    :func:`column_rank_deficiency`, :func:`check_full_column_rank`.  A
    singular value (or a diagonal entry of a pivoted QR factor) counts as
    zero when it is at most ``max(m, n) * eps * s_max``: numpy's
    ``matrix_rank`` rule, used everywhere.
Small helpers
    :func:`symmetrize`, :func:`psd_sqrt`, :func:`readonly`.

The rules are the course's rules: no explicit inverse where a Cholesky
factor, a triangular solve or a QR decomposition does the job, and a failed
factorisation raises :class:`numpy.linalg.LinAlgError` naming the argument.

The input checks (``as_float_array``, ``as_covariance``, ``check_alpha``,
...) live in :mod:`course.validation`; they are re-exported here because
they were importable from this module before.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.linalg import LinAlgError
from scipy import linalg as sla

from course.validation import (
    SYMMETRY_RTOL,
    as_covariance,
    as_float_array,
    as_matrix,
    as_vector,
    check_alpha,
)

__all__ = [
    "SYMMETRY_RTOL",
    "LinAlgError",
    "MinNormSolution",
    "QRSolution",
    "as_covariance",
    "as_float_array",
    "as_matrix",
    "as_vector",
    "check_alpha",
    "check_full_column_rank",
    "cholesky_factor",
    "cholesky_lower",
    "column_rank_deficiency",
    "lstsq_min_norm",
    "matrix_rank",
    "numerical_rank",
    "psd_sqrt",
    "qr_solve",
    "range_basis",
    "rank_tolerance",
    "readonly",
    "solve_spd",
    "symmetrize",
    "whiten",
    "whiten_vectors",
    "whitened_squared_norms",
]


# ---------------------------------------------------------------------------
# small helpers
# ---------------------------------------------------------------------------
def readonly(array: np.ndarray) -> np.ndarray:
    """Mark ``array`` read-only and return it (results never change under the user).

    Examples
    --------
    >>> a = readonly(np.zeros(2))
    >>> a.flags.writeable
    False
    """
    array.setflags(write=False)
    return array


def symmetrize(P: np.ndarray) -> np.ndarray:
    """Return (P + Pᵀ)/2 over the last two axes (works for stacks of matrices).

    Examples
    --------
    >>> symmetrize(np.array([[1.0, 2.0], [0.0, 1.0]]))
    array([[1., 1.],
           [1., 1.]])
    """
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def psd_sqrt(C: np.ndarray) -> np.ndarray:
    """Symmetric square root of a positive semi-definite matrix.

    Small negative eigenvalues from rounding are set to zero; the caller has
    already validated ``C`` (see :func:`course.validation.as_covariance`
    with ``allow_singular=True``).

    Examples
    --------
    >>> psd_sqrt(np.diag([4.0, 0.0]))
    array([[2., 0.],
           [0., 0.]])
    """
    eigenvalues, vectors = np.linalg.eigh(symmetrize(np.asarray(C, dtype=float)))
    eigenvalues = np.clip(eigenvalues, 0.0, None)
    return (vectors * np.sqrt(eigenvalues)) @ vectors.T


# ---------------------------------------------------------------------------
# Cholesky factors and whitening
# ---------------------------------------------------------------------------
def cholesky_lower(matrix: np.ndarray, name: str = "matrix") -> np.ndarray:
    """Lower Cholesky factor L with ``matrix = L @ L.T`` (one matrix, unchecked input).

    Raises a :class:`numpy.linalg.LinAlgError` naming ``name`` when the
    matrix is not positive definite.

    Examples
    --------
    >>> cholesky_lower(np.array([[4.0, 2.0], [2.0, 2.0]]))
    array([[2., 0.],
           [1., 1.]])
    """
    try:
        return sla.cholesky(np.asarray(matrix, dtype=float), lower=True, check_finite=False)
    except (LinAlgError, sla.LinAlgError):
        raise LinAlgError(
            f"{name} is not positive definite (Cholesky factorisation failed); "
            "check that it is a valid covariance matrix"
        ) from None


def cholesky_factor(S, name: str = "S") -> np.ndarray:
    """Checked lower Cholesky factors of a covariance or a stack of them.

    Parameters
    ----------
    S : array_like, shape (..., m, m)
        Symmetric positive definite matrices.  A stack that is a broadcast
        view (stride 0 along a batch axis, as a Kalman filter's shared
        innovation covariances are) is factored once per distinct matrix.
    name : str
        The argument's name for messages.

    Returns
    -------
    numpy.ndarray, shape (..., m, m)
        ``L`` with ``S = L L^T``; broadcast axes of ``S`` come back with
        length 1, which broadcasts the same way.

    Raises
    ------
    ValueError
        Not square, NaN or inf, or not symmetric (relative tolerance
        :data:`course.validation.SYMMETRY_RTOL`).
    numpy.linalg.LinAlgError
        Some matrix is not positive definite.

    Examples
    --------
    >>> S = np.stack([np.eye(2), 4 * np.eye(2)])
    >>> cholesky_factor(S)[1]
    array([[2., 0.],
           [0., 2.]])
    """
    if isinstance(S, np.ndarray) and S.ndim > 2:
        S = S[
            tuple(
                slice(0, 1) if stride == 0 and size > 1 else slice(None)
                for stride, size in zip(S.strides[:-2], S.shape[:-2])
            )
        ]
    cov = as_float_array(S, name)
    if cov.ndim < 2 or cov.shape[-1] != cov.shape[-2]:
        raise ValueError(f"{name} must be a square matrix or a stack (..., m, m), got {cov.shape}")
    scale = np.max(np.abs(cov), axis=(-2, -1), keepdims=True)
    if np.any(np.abs(cov - np.swapaxes(cov, -1, -2)) > SYMMETRY_RTOL * scale):
        raise ValueError(f"{name} is not symmetric; a covariance matrix must equal its transpose")
    try:
        return np.linalg.cholesky(cov)
    except LinAlgError:
        raise LinAlgError(
            f"{name} is not positive definite (Cholesky factorisation failed); "
            "check that it is a valid covariance matrix"
        ) from None


def whiten(L: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Solve ``L z = values`` for one lower-triangular ``L`` (no inverse formed).

    ``values`` is a vector ``(m,)`` or a matrix ``(m, k)`` whose columns are
    whitened (the convention of :func:`scipy.linalg.solve_triangular`).

    Examples
    --------
    >>> whiten(np.array([[2.0, 0.0], [1.0, 1.0]]), np.array([2.0, 2.0]))
    array([1., 1.])
    """
    return sla.solve_triangular(L, values, lower=True, check_finite=False)


def whiten_vectors(L: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """``z_k = L_k^{-1} v_k`` for vectors along the last axis, one factor per vector.

    Parameters
    ----------
    L : ndarray, shape (..., m, m)
        Lower-triangular factors (e.g. from :func:`cholesky_factor`),
        broadcast against the leading axes of ``vectors``.
    vectors : ndarray, shape (..., m)

    Returns
    -------
    ndarray
        The whitened vectors, by forward substitution over the whole stack
        (a loop over the ``m`` components, never over the stack).

    Examples
    --------
    >>> L = np.array([[2.0, 0.0], [1.0, 1.0]])
    >>> whiten_vectors(L, np.array([[2.0, 2.0], [4.0, 3.0]]))
    array([[1., 1.],
           [2., 1.]])
    """
    m = vectors.shape[-1]
    shape = np.broadcast_shapes(L.shape[:-2], vectors.shape[:-1]) + (m,)
    z = np.empty(shape)
    for i in range(m):
        acc = vectors[..., i] - np.einsum("...j,...j->...", L[..., i, :i], z[..., :i])
        z[..., i] = acc / L[..., i, i]
    return z


def whitened_squared_norms(L: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """``|L_k^{-1} v_k|^2 = v_k^T S_k^{-1} v_k`` with ``S_k = L_k L_k^T``, over stacks.

    The quadratic form of the NIS and the NEES, without an inverse.

    Examples
    --------
    >>> whitened_squared_norms(2 * np.eye(2), np.array([[2.0, 0.0], [2.0, 2.0]]))
    array([1., 2.])
    """
    z = whiten_vectors(L, vectors)
    return np.einsum("...i,...i->...", z, z)


def solve_spd(matrix: np.ndarray, rhs: np.ndarray, name: str = "matrix") -> np.ndarray:
    """Solve ``matrix @ x = rhs`` for symmetric positive definite ``matrix`` (Cholesky).

    Examples
    --------
    >>> solve_spd(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([2.0, 2.0]))
    array([1. , 0.5])
    """
    L = cholesky_lower(matrix, name)
    return sla.cho_solve((L, True), rhs, check_finite=False)


# ---------------------------------------------------------------------------
# numerical rank: one rule
# ---------------------------------------------------------------------------
def rank_tolerance(shape: tuple[int, ...], largest: float, rtol: float | None = None) -> float:
    """The threshold below which a singular value counts as zero.

    ``rtol * largest`` with ``rtol = max(m, n) * eps`` by default (numpy's
    ``matrix_rank`` rule); ``largest`` is the largest singular value (or the
    first diagonal entry of a pivoted QR factor).

    Examples
    --------
    >>> bool(rank_tolerance((10, 2), 1.0) == 10 * np.finfo(float).eps)
    True
    """
    if rtol is None:
        rtol = max(shape) * np.finfo(float).eps
    return float(rtol) * float(largest)


def numerical_rank(
    singular_values: np.ndarray, shape: tuple[int, ...], rtol: float | None = None
) -> int:
    """Number of singular values above :func:`rank_tolerance` (0 for a zero matrix).

    Examples
    --------
    >>> numerical_rank(np.array([3.0, 1e-20]), (5, 2))
    1
    """
    s = np.asarray(singular_values, dtype=float)
    if s.size == 0 or s[0] == 0.0:
        return 0
    return int(np.sum(s > rank_tolerance(shape, s[0], rtol)))


def matrix_rank(A: np.ndarray, rtol: float | None = None) -> int:
    """Numerical rank of ``A`` by the course's one rule (see :func:`rank_tolerance`).

    Examples
    --------
    >>> matrix_rank(np.array([[1.0, 2.0], [2.0, 4.0]]))
    1
    """
    A = np.asarray(A, dtype=float)
    if A.size == 0:
        return 0
    return numerical_rank(np.linalg.svd(A, compute_uv=False), A.shape, rtol)


def range_basis(A: np.ndarray, rtol: float | None = None) -> np.ndarray:
    """Orthonormal basis of range(A) from the SVD, with the course's rank rule.

    Examples
    --------
    >>> range_basis(np.array([[1.0, 2.0], [1.0, 2.0]])).shape
    (2, 1)
    """
    A = np.asarray(A, dtype=float)
    N, p = A.shape
    if p == 0 or N == 0:
        return np.zeros((N, 0))
    left, s, _ = np.linalg.svd(A, full_matrices=False)
    return left[:, : numerical_rank(s, A.shape, rtol)]


def column_rank_deficiency(A: np.ndarray, rtol: float | None = None) -> list[int]:
    """Indices of columns of ``A`` that depend linearly on the others.

    Uses QR with column pivoting: the columns pivoted to the end with a
    diagonal entry of R below :func:`rank_tolerance` are the dependent ones.

    Examples
    --------
    >>> column_rank_deficiency(np.array([[1.0, 2.0, 0.0], [1.0, 2.0, 1.0], [0.0, 0.0, 1.0]]))
    [0]
    """
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    if n == 0:
        return []
    _, R, perm = sla.qr(A, mode="economic", pivoting=True)
    rank = numerical_rank(np.abs(np.diag(R)), (m, n), rtol)
    return sorted(int(j) for j in perm[rank:])


def check_full_column_rank(A: np.ndarray, name: str = "A") -> None:
    """Raise a LinAlgError naming the dependent columns of a rank-deficient A.

    Examples
    --------
    >>> check_full_column_rank(np.eye(3))
    """
    dependent = column_rank_deficiency(A)
    if dependent:
        raise LinAlgError(
            f"{name} does not have full column rank: column(s) {dependent} are linear "
            "combinations of the others, so the parameters are not estimable; "
            "remove those columns or add observations that separate them"
        )


# ---------------------------------------------------------------------------
# least squares
# ---------------------------------------------------------------------------
class QRSolution(NamedTuple):
    """Result of :func:`qr_solve`."""

    x: np.ndarray
    """The least-squares solution, ``(n,)`` or ``(n, k)``."""
    R_inv: np.ndarray
    """``R^{-1}`` (upper triangular); ``R^{-1} R^{-T} = (A^T A)^{-1}``."""
    Q: np.ndarray
    """Orthogonal factor: ``(m, n)`` (thin) or ``(m, m)`` (full)."""
    R: np.ndarray
    """Upper-triangular factor, ``(n, n)``."""


def qr_solve(A: np.ndarray, b: np.ndarray, *, full: bool = False) -> QRSolution:
    """Least squares ``min |A x - b|`` for ``A`` of full column rank, by QR.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Full column rank, ``m >= n`` (check with :func:`check_full_column_rank`).
    b : ndarray, shape (m,) or (m, k)
        Right-hand side(s), one per column.
    full : bool, default False
        Return the full ``(m, m)`` orthogonal factor (its last ``m - n``
        columns span the residual space) instead of the thin ``(m, n)`` one.

    Returns
    -------
    QRSolution
        ``x = R^{-1} Q_1^T b`` by a triangular solve, ``R^{-1}`` (so that the
        covariance ``(A^T A)^{-1} = R^{-1} R^{-T}`` needs no normal
        equations), ``Q`` and ``R``.

    Examples
    --------
    >>> A = np.column_stack([np.ones(4), np.arange(1.0, 5.0)])
    >>> sol = qr_solve(A, np.array([14.0, 20.0, 20.0, 24.0]))
    >>> np.round(sol.x, 12) + 0.0
    array([12.,  3.])
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[1]
    Q, R_full = sla.qr(A, mode="full" if full else "economic", check_finite=False)
    R = np.triu(R_full[:n, :n])
    x = sla.solve_triangular(R, Q[:, :n].T @ b, lower=False, check_finite=False)
    R_inv = sla.solve_triangular(R, np.eye(n), lower=False, check_finite=False)
    return QRSolution(x=x, R_inv=R_inv, Q=Q, R=R)


class MinNormSolution(NamedTuple):
    """Result of :func:`lstsq_min_norm`."""

    x: np.ndarray
    """The minimum-norm minimiser, ``(n,)`` or ``(n, k)``."""
    residual: np.ndarray
    """``b - A x``: the projection of ``b`` on the complement of range(A)."""
    rank: int
    """Numerical rank of ``A`` (the course's rule)."""


def lstsq_min_norm(A: np.ndarray, b: np.ndarray, rtol: float | None = None) -> MinNormSolution:
    """Rank-revealing least squares: minimum-norm solution and residual, any rank.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Any rank; ``n`` may be 0.
    b : ndarray, shape (m,) or (m, k)
        Right-hand side(s), one per column.
    rtol : float, optional
        Relative rank tolerance (default ``max(m, n) * eps``).

    Returns
    -------
    MinNormSolution
        From the thin SVD ``A = W S V^T`` with ``W_r`` the ``r`` non-negligible
        left singular vectors: ``residual = b - W_r (W_r^T b)`` (unique even
        when the solution is not) and ``x = V_r S_r^{-1} W_r^T b``.

    Examples
    --------
    >>> A = np.array([[1.0, 2.0], [1.0, 2.0], [0.0, 0.0]])   # rank 1
    >>> sol = lstsq_min_norm(A, np.array([1.0, 1.0, 1.0]))
    >>> sol.rank, np.round(sol.residual, 12) + 0.0
    (1, array([0., 0., 1.]))
    """
    A = np.asarray(A, dtype=float)
    b = np.asarray(b, dtype=float)
    m, n = A.shape
    if n == 0:
        return MinNormSolution(np.zeros((0,) + b.shape[1:]), b.copy(), 0)
    left, s, right_t = np.linalg.svd(A, full_matrices=False)
    rank = numerical_rank(s, (m, n), rtol)
    W, V = left[:, :rank], right_t[:rank].T
    coords = W.T @ b
    residual = b - W @ coords
    x = V @ (coords / (s[:rank, None] if b.ndim == 2 else s[:rank]))
    return MinNormSolution(x, residual, rank)
