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
Covariance factors for least squares at scale
    :func:`covariance_factor` validates a covariance given as ``None``, a
    vector of variances, a dense or a ``scipy.sparse`` matrix and keeps it as
    a :class:`CovarianceFactor` (variances, a banded or a dense Cholesky
    factor) with the whitening solves and diagonals least squares needs.
Small helpers
    :func:`symmetrize`, :func:`psd_sqrt`, :func:`readonly`.

The rules are the course's rules: no explicit inverse where a Cholesky
factor, a triangular solve or a QR decomposition does the job, and a failed
factorisation raises :class:`numpy.linalg.LinAlgError` naming the argument.
A Cholesky factorisation that succeeds only by rounding is refused too: a
covariance is *numerically singular* when some ``L_ii**2 <= 4 eps m Q_ii``
(:data:`course.validation.SINGULAR_RTOL`).  The public functions check
their arguments (:mod:`course.validation`); the library's hot loops call
unchecked twins (``_symmetrize``, ``_whiten_vectors``, ... in the shared
internal module ``course._unchecked``) on arrays it has already validated.

The diagonal of a banded covariance comes from the recurrence of Takahashi, Fagan and Chin
(1973), listed with the course's other sources in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.linalg import LinAlgError
from scipy import linalg as sla
from scipy import sparse
from scipy.linalg import lapack
from scipy.sparse import csgraph

from course._pivots import _refuse_singular_pivots, _refuse_small_pivots
from course._unchecked import _symmetrize, _whiten_vectors, _whitened_squared_norms
from course.validation import (
    SYMMETRY_RTOL,
    InputTypeError,
    as_count,
    as_covariance,
    as_finite,
    as_flag,
    as_float_array,
    as_matrix,
    as_positive,
    as_vector,
)

__all__ = [
    "CovarianceFactor",
    "MinNormSolution",
    "QRSolution",
    "check_full_column_rank",
    "cholesky_factor",
    "cholesky_lower",
    "column_rank_deficiency",
    "covariance_factor",
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
    if not isinstance(array, np.ndarray):
        raise InputTypeError(
            f"array must be a numpy array (readonly marks it in place), got {type(array).__name__}"
        )
    array.setflags(write=False)
    return array


def _square_stack(value, name: str) -> np.ndarray:
    """A finite float array of shape ``(..., m, m)``."""
    array = as_float_array(value, name, min_ndim=2, empty=False)
    if array.shape[-1] != array.shape[-2]:
        raise ValueError(f"{name} must be square, (m, m) or a stack (..., m, m), got {array.shape}")
    return array


def symmetrize(P: np.ndarray) -> np.ndarray:
    """Return (P + Pᵀ)/2 over the last two axes (works for stacks of matrices).

    Examples
    --------
    >>> symmetrize(np.array([[1.0, 2.0], [0.0, 1.0]]))
    array([[1., 1.],
           [1., 1.]])
    """
    return _symmetrize(_square_stack(P, "P"))


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
    C = as_float_array(C, "C", ndim=2)
    C = as_covariance(C, "C", C.shape[0], allow_singular=True)
    eigenvalues, vectors = np.linalg.eigh(_symmetrize(C))
    eigenvalues = np.clip(eigenvalues, 0.0, None)
    return (vectors * np.sqrt(eigenvalues)) @ vectors.T


# ---------------------------------------------------------------------------
# Cholesky factors and whitening
# ---------------------------------------------------------------------------
def cholesky_lower(matrix: np.ndarray, name: str = "matrix") -> np.ndarray:
    """Lower Cholesky factor L with ``matrix = L @ L.T`` (one matrix).

    Raises a :class:`numpy.linalg.LinAlgError` naming ``name`` when the
    matrix is not positive definite or numerically singular (see the module
    docstring), a ``ValueError`` when it is not a finite square matrix.

    Examples
    --------
    >>> cholesky_lower(np.array([[4.0, 2.0], [2.0, 2.0]]))
    array([[2., 0.],
           [1., 1.]])
    """
    matrix = as_float_array(matrix, name, ndim=2, empty=False)
    if matrix.shape[0] != matrix.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {matrix.shape}")
    return _checked_cholesky(matrix, name)


def _checked_cholesky(cov: np.ndarray, name: str) -> np.ndarray:
    """Cholesky factors of a finite square stack: symmetric, PD, not numerically singular.

    The factorisation runs on the correlation matrices ``D^{-1/2} S D^{-1/2}``
    (``D`` the variances), the same verdict as :func:`course.validation.as_covariance`
    at any scale; ``L = D^{1/2} L_C``.
    """
    scale = np.max(np.abs(cov), axis=(-2, -1), keepdims=True)
    if np.any(np.abs(cov - np.swapaxes(cov, -1, -2)) > SYMMETRY_RTOL * scale):
        raise ValueError(f"{name} is not symmetric; a covariance matrix must equal its transpose")
    variances = np.diagonal(cov, axis1=-2, axis2=-1)
    not_pd = LinAlgError(
        f"{name} is not positive definite (Cholesky factorisation failed); "
        "check that it is a valid covariance matrix"
    )
    if np.any(variances <= 0):
        raise not_pd
    std = np.sqrt(variances)
    try:
        L = np.linalg.cholesky(cov / std[..., :, None] / std[..., None, :])
    except LinAlgError:
        raise not_pd from None
    _refuse_singular_pivots(L, np.ones(variances.shape), name)
    return std[..., :, None] * L


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
        Some matrix is not positive definite, or numerically singular: some
        ``L_ii**2 <= 4 eps m S_ii`` (:data:`course.validation.SINGULAR_RTOL`).

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
    return _checked_cholesky(_square_stack(S, name), name)


def whiten(L: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Solve ``L z = values`` for one lower-triangular ``L`` (no inverse formed).

    ``values`` is a vector ``(m,)`` or a matrix ``(m, k)`` whose columns are
    whitened (the convention of :func:`scipy.linalg.solve_triangular`).

    Examples
    --------
    >>> whiten(np.array([[2.0, 0.0], [1.0, 1.0]]), np.array([2.0, 2.0]))
    array([1., 1.])
    """
    L = _lower_factor(L, "L", ndim=2)
    values = as_float_array(values, "values", empty=False)
    if values.ndim not in (1, 2) or values.shape[0] != L.shape[0]:
        raise ValueError(
            f"values must have shape ({L.shape[0]},) or ({L.shape[0]}, k) to match L of shape "
            f"{L.shape}, got {values.shape}"
        )
    return sla.solve_triangular(L, values, lower=True, check_finite=False)


def _lower_factor(L, name: str, ndim: int | None = None) -> np.ndarray:
    """A finite square (stack of) lower-triangular factor(s) with a non-zero diagonal."""
    L = _square_stack(L, name)
    if ndim is not None and L.ndim != ndim:
        raise ValueError(f"{name} must be one square matrix, got shape {L.shape}")
    if not np.all(np.diagonal(L, axis1=-2, axis2=-1)):
        raise LinAlgError(
            f"{name} is singular (a zero on its diagonal): it is not the Cholesky factor of a "
            "positive definite covariance"
        )
    return L


def _vectors_for(L: np.ndarray, vectors, name: str) -> np.ndarray:
    vectors = as_float_array(vectors, name, min_ndim=1, empty=False)
    m = L.shape[-1]
    if vectors.shape[-1] != m:
        raise ValueError(
            f"{name} must have length m = {m} along the last axis, got {vectors.shape}"
        )
    try:
        np.broadcast_shapes(L.shape[:-2], vectors.shape[:-1])
    except ValueError:
        raise ValueError(
            f"{name} of shape {vectors.shape} does not broadcast against L of shape {L.shape}"
        ) from None
    return vectors


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
    L = _lower_factor(L, "L")
    return _whiten_vectors(L, _vectors_for(L, vectors, "vectors"))


def whitened_squared_norms(L: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """``|L_k^{-1} v_k|^2 = v_k^T S_k^{-1} v_k`` with ``S_k = L_k L_k^T``, over stacks.

    The quadratic form of the NIS and the NEES, without an inverse.

    Examples
    --------
    >>> whitened_squared_norms(2 * np.eye(2), np.array([[2.0, 0.0], [2.0, 2.0]]))
    array([1., 2.])
    """
    L = _lower_factor(L, "L")
    return _whitened_squared_norms(L, _vectors_for(L, vectors, "vectors"))


def solve_spd(matrix: np.ndarray, rhs: np.ndarray, name: str = "matrix") -> np.ndarray:
    """Solve ``matrix @ x = rhs`` for symmetric positive definite ``matrix`` (Cholesky).

    Examples
    --------
    >>> solve_spd(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([2.0, 2.0]))
    array([1. , 0.5])
    """
    L = cholesky_lower(matrix, name)
    rhs = as_float_array(rhs, "rhs", empty=False)
    if rhs.ndim not in (1, 2) or rhs.shape[0] != L.shape[0]:
        raise ValueError(
            f"rhs must have shape ({L.shape[0]},) or ({L.shape[0]}, k) to match {name}, "
            f"got {rhs.shape}"
        )
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
    shape = _shape(shape)
    largest = as_finite(largest, "largest")
    if largest < 0:
        raise ValueError(f"largest is a singular value, so it cannot be negative; got {largest!r}")
    rtol = _rtol(rtol, shape)
    return rtol * largest


def _shape(shape) -> tuple[int, ...]:
    if isinstance(shape, (str, bytes)) or not isinstance(shape, (tuple, list)) or not shape:
        raise ValueError(
            f"shape must be the shape of a matrix, a tuple such as (m, n); got {shape!r}"
        )
    return tuple(as_count(n, "shape", minimum=0) for n in shape)


def _rtol(rtol, shape: tuple[int, ...]) -> float:
    if rtol is None:
        return max(shape) * np.finfo(float).eps
    return as_positive(rtol, "rtol", what="the relative rank tolerance")


def numerical_rank(
    singular_values: np.ndarray, shape: tuple[int, ...], rtol: float | None = None
) -> int:
    """Number of singular values above :func:`rank_tolerance` (0 for a zero matrix).

    Examples
    --------
    >>> numerical_rank(np.array([3.0, 1e-20]), (5, 2))
    1
    """
    s = as_vector(singular_values, "singular_values", empty=True)
    if np.any(s < 0):
        raise ValueError("singular_values cannot be negative")
    shape = _shape(shape)
    if s.size == 0 or s.max() == 0.0:
        return 0
    return int(np.sum(s > _rtol(rtol, shape) * s.max()))


def matrix_rank(A: np.ndarray, rtol: float | None = None) -> int:
    """Numerical rank of ``A`` by the course's one rule (see :func:`rank_tolerance`).

    Examples
    --------
    >>> matrix_rank(np.array([[1.0, 2.0], [2.0, 4.0]]))
    1
    """
    A = as_matrix(A, "A", empty=True)
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
    A = as_matrix(A, "A", empty=True)
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
    A = as_matrix(A, "A", empty=True)
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
    dependent = column_rank_deficiency(as_matrix(A, name))
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
    A, b = _system(A, b)
    full = as_flag(full, "full")
    n = A.shape[1]
    if A.shape[0] < n:
        raise ValueError(
            f"A has more columns ({n}) than rows ({A.shape[0]}): least squares by QR needs m >= n "
            "(use lstsq_min_norm for an underdetermined system)"
        )
    Q, R_full = sla.qr(A, mode="full" if full else "economic", check_finite=False)
    R = np.triu(R_full[:n, :n])
    x = sla.solve_triangular(R, Q[:, :n].T @ b, lower=False, check_finite=False)
    R_inv = sla.solve_triangular(R, np.eye(n), lower=False, check_finite=False)
    return QRSolution(x=x, R_inv=R_inv, Q=Q, R=R)


def _system(A, b, *, empty_columns: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """A finite ``(m, n)`` matrix and a right-hand side ``(m,)`` or ``(m, k)``."""
    A = as_float_array(A, "A", ndim=2)
    if A.shape[0] == 0 or (A.shape[1] == 0 and not empty_columns):
        raise ValueError(f"A is empty (shape {A.shape}); pass at least one row and column")
    b = as_float_array(b, "b", empty=False)
    if b.ndim not in (1, 2) or b.shape[0] != A.shape[0]:
        raise ValueError(
            f"b must have shape ({A.shape[0]},) or ({A.shape[0]}, k), one row per row of A, "
            f"got {b.shape}"
        )
    return A, b


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
    A, b = _system(A, b, empty_columns=True)
    m, n = A.shape
    if rtol is not None:
        rtol = as_positive(rtol, "rtol", what="the relative rank tolerance")
    if n == 0:
        return MinNormSolution(np.zeros((0,) + b.shape[1:]), b.copy(), 0)
    left, s, right_t = np.linalg.svd(A, full_matrices=False)
    rank = numerical_rank(s, (m, n), rtol)
    W, V = left[:, :rank], right_t[:rank].T
    coords = W.T @ b
    residual = b - W @ coords
    x = V @ (coords / (s[:rank, None] if b.ndim == 2 else s[:rank]))
    return MinNormSolution(x, residual, rank)


# ---------------------------------------------------------------------------
# Covariance factors for least squares at scale
# ---------------------------------------------------------------------------
# A covariance matrix Q = F F^T kept in the cheapest form that represents it
# exactly: a vector of variances (diagonal Q, O(m) memory), a banded Cholesky
# factor after a bandwidth-reducing reordering (sparse Q), or a dense Cholesky
# factor.  Least squares needs only the whitening solves F^{-1} X and F^{-T} X,
# the diagonal of Q and the diagonal of Q^{-1}; no m x m matrix is formed
# unless Q was given dense.  Positive definiteness is checked by the
# factorisation itself (a failed Cholesky, or a non-positive variance), never
# by an eigendecomposition.


class CovarianceFactor:
    """A validated covariance matrix ``Q = F F^T`` with the solves least squares needs.

    Build it with :func:`covariance_factor`.  The whitened coordinates
    ``F^{-1} x`` may be a permutation of the observation order (banded
    factors reorder); they are only ever combined with each other, and
    :meth:`whiten_transpose` maps back to observation order.

    Attributes
    ----------
    m : int
        Dimension.
    kind : {"diagonal", "banded", "dense"}
        How ``F`` is stored.
    given_as : {"identity", "variances", "diagonal matrix", "matrix", "sparse matrix"}
        The form the user passed (used in messages and by :meth:`take`).
    """

    kind = "abstract"

    def __init__(self, m: int, given_as: str, source):
        self.m = int(m)
        self.given_as = given_as
        self._source = source

    def whiten(self, X: np.ndarray) -> np.ndarray:
        """``F^{-1} X`` for ``X`` of shape (m,) or (m, k)."""
        raise NotImplementedError

    def whiten_transpose(self, X: np.ndarray) -> np.ndarray:
        """``F^{-T} X`` (so that ``Q^{-1} x = F^{-T} F^{-1} x``), in observation order."""
        raise NotImplementedError

    def whiten_unit(self, i: int) -> np.ndarray:
        """``F^{-1} c_i`` for the i-th unit vector ``c_i``."""
        unit = np.zeros(self.m)
        unit[i] = 1.0
        return self.whiten(unit)

    def diagonal(self) -> np.ndarray:
        """``diag(Q)``, the variances."""
        raise NotImplementedError

    def inverse_diagonal(self) -> np.ndarray:
        """``diag(Q^{-1})`` without forming ``Q^{-1}``'s off-diagonal part where avoidable."""
        raise NotImplementedError

    def dense(self, copy: bool = True) -> np.ndarray:
        """``Q`` as an (m, m) array (8 m² bytes: ask only when you need it).

        With ``copy=False`` a matrix that was given dense is returned as the
        validated array itself, which the caller must not modify.
        """
        if self.given_as == "identity":
            return np.eye(self.m)
        if self.given_as == "variances":
            return np.diag(self._source)
        if self.given_as == "sparse matrix":
            return self._source.toarray()
        return np.array(self._source) if copy else self._source

    def take(self, index: np.ndarray):
        """The covariance of the observations ``index``, in the form it was given.

        ``None`` stays ``None`` (the identity), variances stay a vector, a
        sparse matrix stays sparse: what a refit of a subset should be given.
        """
        index = np.asarray(index, dtype=int)
        if self.given_as == "identity":
            return None
        if self.given_as == "variances":
            return self._source[index]
        if self.given_as == "sparse matrix":
            return self._source[index][:, index]
        return self._source[np.ix_(index, index)]


class _DiagonalFactor(CovarianceFactor):
    kind = "diagonal"

    def __init__(self, variances: np.ndarray, given_as: str, source):
        super().__init__(variances.shape[0], given_as, source)
        self.variances = variances
        self._std = np.sqrt(variances)

    def _scale(self, X, factor):
        X = np.asarray(X, dtype=float)
        if X.ndim == 1:
            return X * factor
        # Rows scaled into a column-major result, the layout LAPACK's QR wants.
        out = np.empty((X.shape[1], X.shape[0]))
        np.multiply(X.T, factor, out=out)
        return out.T

    def whiten(self, X):
        return self._scale(X, 1.0 / self._std)

    def whiten_transpose(self, X):
        return self._scale(X, 1.0 / self._std)

    def whiten_unit(self, i):
        unit = np.zeros(self.m)
        unit[i] = 1.0 / self._std[i]
        return unit

    def diagonal(self):
        return self.variances

    def inverse_diagonal(self):
        return 1.0 / self.variances


class _DenseFactor(CovarianceFactor):
    kind = "dense"

    def __init__(self, L: np.ndarray, given_as: str, source):
        super().__init__(L.shape[0], given_as, source)
        self.L = L

    def whiten(self, X):
        return sla.solve_triangular(self.L, X, lower=True, check_finite=False)

    def whiten_transpose(self, X):
        return sla.solve_triangular(self.L, X, trans="T", lower=True, check_finite=False)

    def whiten_unit(self, i):
        # F^{-1} c_i vanishes above row i: solve with the trailing block only.
        out = np.zeros(self.m)
        rhs = np.zeros(self.m - i)
        rhs[0] = 1.0
        out[i:] = sla.solve_triangular(self.L[i:, i:], rhs, lower=True, check_finite=False)
        return out

    def diagonal(self):
        # ndarray and scipy.sparse (a sparse matrix without a usable band) alike
        return np.array(self._source.diagonal())

    def inverse_diagonal(self):
        # diag(Q^{-1}) = squared column norms of L^{-1}: one triangular inversion
        # (m³/3 flops, as much as the Cholesky itself); there is no cheaper exact way
        # to the diagonal of a dense inverse.
        L_inv, info = lapack.dtrtri(self.L, lower=1)
        if info != 0:  # pragma: no cover - L comes from a successful Cholesky
            raise LinAlgError(f"triangular inversion failed (LAPACK info {info})")
        return np.einsum("ij,ij->j", L_inv, L_inv)


class _BandedFactor(CovarianceFactor):
    """``Q[perm][:, perm] = L L^T`` with L lower banded, stored in LAPACK band form."""

    kind = "banded"

    def __init__(self, band: np.ndarray, perm: np.ndarray, source):
        super().__init__(band.shape[1], "sparse matrix", source)
        self.band = band  # band[d, j] = L[j + d, j]
        self.perm = perm
        self.position = np.empty_like(perm)
        self.position[perm] = np.arange(perm.size)

    def _solve(self, X, trans):
        X = np.asarray(X, dtype=float)
        rhs = X.reshape(self.m, -1)
        out, info = lapack.dtbtrs(self.band, rhs, uplo="L", trans=trans)
        if info != 0:  # pragma: no cover - L comes from a successful Cholesky
            raise LinAlgError(f"banded triangular solve failed (LAPACK info {info})")
        return out.reshape(X.shape)

    def whiten(self, X):
        return self._solve(np.asarray(X, dtype=float)[self.perm], "N")

    def whiten_transpose(self, X):
        solved = self._solve(X, "T")
        out = np.empty_like(solved)
        out[self.perm] = solved
        return out

    def whiten_unit(self, i):
        unit = np.zeros(self.m)
        unit[self.position[i]] = 1.0
        return self._solve(unit, "N")

    def diagonal(self):
        return self._source.diagonal()

    def inverse_diagonal(self):
        out = np.empty(self.m)
        out[self.perm] = _banded_inverse_diagonal(self.band)
        return out


def _banded_inverse_diagonal(band: np.ndarray) -> np.ndarray:
    """``diag(Q^{-1})`` from the banded Cholesky factor of Q, in O(m b²).

    With ``Z = Q^{-1} = L^{-T} L^{-1}``, ``Z L = L^{-T}`` is upper triangular
    with diagonal ``1/L_jj``, which gives for ``i >= j`` the recurrence
    ``Z_ij = (δ_ij / L_jj - Σ_{k>j} Z_ik L_kj) / L_jj`` (Takahashi, Fagan and
    Chin 1973).  Run from the last column backwards, it needs only entries of
    Z inside the band, held here in a sliding b x b window.
    """
    b, m = band.shape[0] - 1, band.shape[1]
    diag = np.empty(m)
    window = np.zeros((b, b))  # Z[j+1 : j+1+b, j+1 : j+1+b]
    for j in range(m - 1, -1, -1):
        pivot = band[0, j]
        column = band[1:, j]  # L[j+1 : j+1+b, j], zero beyond the matrix
        z = -(window @ column) / pivot
        diag[j] = 1.0 / pivot**2 - (z @ column) / pivot
        window[1:, 1:] = window[:-1, :-1].copy()
        window[0, 0] = diag[j]
        window[0, 1:] = window[1:, 0] = z[:-1]
    return diag


def _largest_asymmetry(matrix: np.ndarray, block: int = 256) -> float:
    """``max |Q - Q^T|``, tile by tile: reading ``Q.T`` whole strides through memory
    and costs ten times more than the tiles at m = 2000."""
    m = matrix.shape[0]
    worst = 0.0
    for i in range(0, m, block):
        for j in range(0, i + 1, block):
            tile = matrix[i : i + block, j : j + block] - matrix[j : j + block, i : i + block].T
            worst = max(worst, float(np.max(np.abs(tile))))
    return worst


def _symmetry_error(asym: float, name: str) -> ValueError:
    return ValueError(
        f"{name} is not symmetric (largest |{name} - {name}^T| = {asym:.3g}); "
        "a covariance matrix must equal its transpose"
    )


def _not_positive_definite(name: str, detail: str) -> LinAlgError:
    return LinAlgError(
        f"{name} is not positive definite ({detail}); "
        "a covariance matrix needs positive variances and correlations in [-1, 1]"
    )


def _check_positive_diagonal(diagonal: np.ndarray, name: str) -> None:
    """A diagonal covariance matrix is positive definite iff its entries are positive."""
    bad = np.flatnonzero(diagonal <= 0)
    if bad.size:
        value = float(diagonal[bad[0]])
        raise _not_positive_definite(
            name, f"diagonal entry {bad[0]} is {value!r}, not a positive variance"
        )


def covariance_factor(value, name: str, size: int) -> CovarianceFactor:
    """Validate a covariance given in any of its usual forms and factor it.

    Parameters
    ----------
    value : None, array_like of shape (size,) or (size, size), or scipy.sparse matrix
        ``None``: the identity.  A 1-D array: the VARIANCES of uncorrelated
        observations (not their standard deviations).  A dense or sparse
        symmetric positive definite matrix.
    name : str
        The argument's name in error messages.
    size : int
        Required dimension m.

    Returns
    -------
    CovarianceFactor
        Diagonal (for ``None``, a vector, or a matrix with no off-diagonal
        entries, dense or sparse), banded (other sparse matrices whose
        reverse Cuthill-McKee ordering has a bandwidth below m/2) or dense.

    Raises
    ------
    ValueError
        Wrong shape, NaN or inf, not symmetric, a non-positive variance in a
        1-D array.
    numpy.linalg.LinAlgError
        A matrix that is not positive definite: the Cholesky factorisation
        fails or a diagonal matrix has a non-positive entry.

    See Also
    --------
    course.validation.as_covariance : The check of a covariance.

    Notes
    -----
    Costs: :math:`O(m)` for diagonal covariances; :math:`O(mb^2)` time and
    :math:`O(mb)` memory for a sparse matrix of bandwidth :math:`b` after
    reordering (block-diagonal covariances, e.g. 3 x 3 blocks of GNSS
    baselines, have :math:`b = 2`); :math:`O(m^3/3)` time and :math:`O(m^2)`
    memory for a dense one.
    """
    m = as_count(size, "size")
    if value is None:
        return _DiagonalFactor(np.ones(m), "identity", None)
    if sparse.issparse(value):
        return _sparse_factor(value, name, m)
    try:
        ndim = np.ndim(value)
    except ValueError:  # ragged nested lists: as_matrix below says what is wrong
        ndim = 2
    if ndim == 1:
        variances = as_float_array(value, name)
        if variances.shape[0] != m:
            raise ValueError(
                f"{name} given as a 1-D array holds the variances of the m = {m} observations, "
                f"got {variances.shape[0]} values"
            )
        bad = np.flatnonzero(variances <= 0)
        if bad.size:
            raise ValueError(
                f"{name} given as a 1-D array holds variances, which must be positive; "
                f"{name}[{bad[0]}] = {float(variances[bad[0]])!r} ({bad.size} non-positive entries)"
            )
        return _DiagonalFactor(variances, "variances", variances)
    if ndim == 0:
        raise ValueError(
            f"{name} must be an (m, m) = ({m}, {m}) covariance matrix or a 1-D array of the "
            f"m variances, got a scalar; for equal variances s2 pass s2 * np.eye({m}), or "
            f"the vector of variances np.full({m}, s2)"
        )
    matrix = as_matrix(value, name, shape=(m, m))
    scale = max(float(np.max(np.abs(matrix))), np.finfo(float).tiny)
    asym = _largest_asymmetry(matrix)
    if asym > SYMMETRY_RTOL * scale:
        raise _symmetry_error(asym, name)
    diagonal = np.diag(matrix).copy()
    if np.count_nonzero(matrix) == np.count_nonzero(diagonal):
        _check_positive_diagonal(diagonal, name)
        return _DiagonalFactor(diagonal, "diagonal matrix", matrix)
    try:
        L = sla.cholesky(matrix, lower=True, check_finite=False)
    except (LinAlgError, sla.LinAlgError):
        raise _not_positive_definite(name, "Cholesky factorisation failed") from None
    _refuse_singular_pivots(L, diagonal, name)
    return _DenseFactor(L, "matrix", matrix)


def _sparse_factor(value, name: str, m: int) -> CovarianceFactor:
    if value.shape != (m, m):
        raise ValueError(f"{name} must have shape ({m}, {m}), got {value.shape}")
    if np.iscomplexobj(value.data if hasattr(value, "data") else value):
        raise ValueError(f"{name} is complex; pass real numbers")
    matrix = sparse.csr_array(value, dtype=float, copy=True)
    matrix.sum_duplicates()
    if not np.all(np.isfinite(matrix.data)):
        raise ValueError(
            f"{name} contains NaN or inf ({int(np.sum(~np.isfinite(matrix.data)))} stored "
            "entries); remove or replace those values before fitting"
        )
    matrix.eliminate_zeros()
    scale = max(float(np.max(np.abs(matrix.data), initial=0.0)), np.finfo(float).tiny)
    difference = (matrix - matrix.T).tocsr()
    asym = float(np.max(np.abs(difference.data), initial=0.0))
    if asym > SYMMETRY_RTOL * scale:
        raise _symmetry_error(asym, name)
    diagonal = matrix.diagonal()
    if matrix.nnz == np.count_nonzero(diagonal):
        _check_positive_diagonal(diagonal, name)
        return _DiagonalFactor(diagonal, "sparse matrix", matrix)
    perm = csgraph.reverse_cuthill_mckee(matrix, symmetric_mode=True).astype(np.intp)
    reordered = matrix[perm][:, perm].tocoo()
    rows, cols = reordered.row, reordered.col
    bandwidth = int(np.max(np.abs(rows - cols)))
    if 2 * bandwidth >= m:
        try:
            L = sla.cholesky(matrix.toarray(), lower=True, check_finite=False)
        except (LinAlgError, sla.LinAlgError):
            raise _not_positive_definite(name, "Cholesky factorisation failed") from None
        _refuse_singular_pivots(L, diagonal, name)
        return _DenseFactor(L, "sparse matrix", matrix)
    lower = rows >= cols
    band = np.zeros((bandwidth + 1, m))
    band[rows[lower] - cols[lower], cols[lower]] = reordered.data[lower]
    try:
        band = sla.cholesky_banded(band, lower=True, check_finite=False)
    except (LinAlgError, sla.LinAlgError):
        raise _not_positive_definite(name, "banded Cholesky factorisation failed") from None
    # Pivots in the reordered order, so the message's "variable i" counts in that order.
    _refuse_small_pivots(band[0] ** 2, diagonal[perm], name)
    return _BandedFactor(band, perm, matrix)
