"""Input validation and linear-algebra helpers shared by every course module.

The rules these helpers enforce are the course's rules: nothing a user typed
is silently changed, bad input fails early with a message that says what is
wrong and what to do, and no explicit inverse is formed where a Cholesky
factor, a triangular solve or a QR decomposition does the job.
"""

from __future__ import annotations

import numpy as np
from numpy.linalg import LinAlgError
from scipy import linalg as sla

__all__ = [
    "LinAlgError",
    "as_covariance",
    "as_float_array",
    "as_matrix",
    "as_vector",
    "check_alpha",
    "check_full_column_rank",
    "cholesky_lower",
    "column_rank_deficiency",
    "psd_sqrt",
    "solve_spd",
    "symmetrize",
    "whiten",
]

#: Relative tolerance for "symmetric": |Q - Q^T| <= SYMMETRY_RTOL * max|Q|.
SYMMETRY_RTOL = 1e-10


def as_float_array(value, name: str, ndim: int | None = None) -> np.ndarray:
    """Return ``value`` as a float64 array, refusing NaN, inf and wrong ndim.

    Parameters
    ----------
    value : array_like
        What the user passed.
    name : str
        The argument's name, used in error messages.
    ndim : int, optional
        Required number of dimensions.

    Raises
    ------
    ValueError
        If the value is None, complex or not numeric, has the wrong number of
        dimensions, or contains NaN or inf.
    """
    if value is None:
        raise ValueError(f"{name} is None; pass an array of numbers")
    if _is_complex(value):
        # float() would drop the imaginary part with only a warning: refuse instead.
        raise ValueError(
            f"{name} is complex; pass real numbers (e.g. np.real(...) if the "
            "imaginary parts are rounding noise)"
        )
    try:
        array = np.array(value, dtype=float)  # a copy: callers may not mutate input
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {type(value).__name__}: {exc}") from None
    if ndim is not None and array.ndim != ndim:
        raise ValueError(
            f"{name} must be {ndim}-dimensional, got shape {array.shape}"
            + (
                " (pass a column as a 2-D array of shape (m, 1))"
                if ndim == 2 and array.ndim == 1
                else ""
            )
        )
    if not np.all(np.isfinite(array)):
        bad = np.argwhere(~np.isfinite(array))
        where = tuple(int(i) for i in bad[0])
        raise ValueError(
            f"{name} contains NaN or inf ({len(bad)} entries, first at index {where}); "
            "remove or replace those values before fitting"
        )
    return array


def _is_complex(value) -> bool:
    try:
        return bool(np.iscomplexobj(value))
    except (TypeError, ValueError):  # ragged or non-numeric: reported by the caller
        return False


def as_vector(value, name: str, size: int | None = None) -> np.ndarray:
    """Return a finite 1-D float array of the given ``size``."""
    vector = as_float_array(value, name)
    if vector.ndim == 2 and 1 in vector.shape:
        raise ValueError(
            f"{name} must be a 1-D vector, got shape {vector.shape}; "
            "pass it flattened, e.g. np.ravel(...)"
        )
    if vector.ndim != 1:
        raise ValueError(f"{name} must be a 1-D vector, got shape {vector.shape}")
    if size is not None and vector.shape[0] != size:
        raise ValueError(f"{name} must have length {size}, got {vector.shape[0]}")
    return vector


def as_matrix(value, name: str, shape: tuple[int | None, int | None] | None = None) -> np.ndarray:
    """Return a finite 2-D float array, checking ``shape`` where given."""
    matrix = as_float_array(value, name, ndim=2)
    if shape is not None:
        for axis, expected in enumerate(shape):
            if expected is not None and matrix.shape[axis] != expected:
                raise ValueError(f"{name} must have shape {_shape_text(shape)}, got {matrix.shape}")
    return matrix


def as_covariance(value, name: str, size: int, allow_singular: bool = False) -> np.ndarray:
    """Validate a covariance matrix: square ``size`` x ``size``, symmetric, PD.

    Parameters
    ----------
    value : array_like
        The covariance matrix.
    name : str
        Its name in error messages (``"Qyy"``, ``"R"``, ...).
    size : int
        Required dimension.
    allow_singular : bool
        Accept positive semi-definite matrices.

    Raises
    ------
    ValueError
        Wrong shape or not symmetric.
    numpy.linalg.LinAlgError
        Not positive (semi-)definite.
    """
    matrix = as_matrix(value, name, shape=(size, size))
    scale = max(np.max(np.abs(matrix)), np.finfo(float).tiny)
    asym = np.max(np.abs(matrix - matrix.T))
    if asym > SYMMETRY_RTOL * scale:
        raise ValueError(
            f"{name} is not symmetric (largest |{name} - {name}^T| = {asym:.3g}); "
            "a covariance matrix must equal its transpose"
        )
    eigenvalues = np.linalg.eigvalsh(matrix)
    smallest = float(eigenvalues[0])
    tol = -np.finfo(float).eps * size * scale if allow_singular else 0.0
    if smallest < tol or (not allow_singular and smallest <= 0):
        kind = "positive semi-definite" if allow_singular else "positive definite"
        raise LinAlgError(
            f"{name} is not {kind} (smallest eigenvalue {smallest:.3g}); "
            "a covariance matrix needs positive variances and correlations in [-1, 1]"
        )
    return matrix


def check_alpha(alpha, name: str = "alpha") -> float:
    """Return ``alpha`` as a float after checking 0 < alpha < 1."""
    try:
        value = float(alpha)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number in (0, 1), got {alpha!r}") from None
    if not 0.0 < value < 1.0:
        raise ValueError(f"{name} must lie strictly between 0 and 1, got {alpha!r}")
    return value


def cholesky_lower(matrix, name: str = "matrix") -> np.ndarray:
    """Lower Cholesky factor L with ``matrix = L @ L.T``.

    Raises a :class:`numpy.linalg.LinAlgError` naming ``name`` when the
    matrix is not positive definite.
    """
    try:
        return sla.cholesky(np.asarray(matrix, dtype=float), lower=True, check_finite=False)
    except (LinAlgError, sla.LinAlgError):
        raise LinAlgError(
            f"{name} is not positive definite (Cholesky factorisation failed); "
            "check that it is a valid covariance matrix"
        ) from None


def whiten(L: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Solve ``L z = values`` for lower-triangular ``L`` (no inverse formed)."""
    return sla.solve_triangular(L, values, lower=True, check_finite=False)


def solve_spd(matrix: np.ndarray, rhs: np.ndarray, name: str = "matrix") -> np.ndarray:
    """Solve ``matrix @ x = rhs`` for symmetric positive definite ``matrix``."""
    L = cholesky_lower(matrix, name)
    return sla.cho_solve((L, True), rhs, check_finite=False)


def column_rank_deficiency(A: np.ndarray, rtol: float | None = None) -> list[int]:
    """Indices of columns of ``A`` that depend linearly on the others.

    Uses QR with column pivoting: the columns pivoted to the end with a
    negligible diagonal entry of R are the dependent ones.
    """
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    if n == 0:
        return []
    _, R, perm = sla.qr(A, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    if rtol is None:
        rtol = max(m, n) * np.finfo(float).eps
    rank = int(np.sum(diag > rtol * (diag[0] if diag.size else 0.0)))
    if diag.size and diag[0] == 0.0:
        rank = 0
    return sorted(int(j) for j in perm[rank:])


def check_full_column_rank(A: np.ndarray, name: str = "A") -> None:
    """Raise a LinAlgError naming the dependent columns of a rank-deficient A."""
    dependent = column_rank_deficiency(A)
    if dependent:
        raise LinAlgError(
            f"{name} does not have full column rank: column(s) {dependent} are linear "
            "combinations of the others, so the parameters are not estimable; "
            "remove those columns or add observations that separate them"
        )


def symmetrize(P: np.ndarray) -> np.ndarray:
    """Return (P + Pᵀ)/2 over the last two axes (works for stacks of matrices)."""
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def psd_sqrt(C: np.ndarray) -> np.ndarray:
    """Symmetric square root of a positive semi-definite matrix.

    Small negative eigenvalues from rounding are set to zero; the caller has
    already validated ``C`` (see :func:`as_covariance` with
    ``allow_singular=True``).
    """
    eigenvalues, vectors = np.linalg.eigh(symmetrize(np.asarray(C, dtype=float)))
    eigenvalues = np.clip(eigenvalues, 0.0, None)
    return (vectors * np.sqrt(eigenvalues)) @ vectors.T


def _shape_text(shape):
    return "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
