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
from scipy import sparse
from scipy.linalg import lapack
from scipy.sparse import csgraph

__all__ = [
    "CovarianceFactor",
    "LinAlgError",
    "as_covariance",
    "as_float_array",
    "as_matrix",
    "as_vector",
    "check_alpha",
    "check_full_column_rank",
    "cholesky_lower",
    "column_rank_deficiency",
    "covariance_factor",
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

    Notes
    -----
    Costs: O(m) for diagonal covariances; O(m b²) time and O(m b) memory for
    a sparse matrix of bandwidth b after reordering (block-diagonal
    covariances, e.g. 3 x 3 blocks of GNSS baselines, have b = 2); O(m³/3)
    time and O(m²) memory for a dense one.
    """
    m = int(size)
    if value is None:
        return _DiagonalFactor(np.ones(m), "identity", None)
    if sparse.issparse(value):
        return _sparse_factor(value, name, m)
    if np.ndim(value) == 1:
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
    if np.ndim(value) == 0:
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
        return _DenseFactor(L, "sparse matrix", matrix)
    lower = rows >= cols
    band = np.zeros((bandwidth + 1, m))
    band[rows[lower] - cols[lower], cols[lower]] = reordered.data[lower]
    try:
        band = sla.cholesky_banded(band, lower=True, check_finite=False)
    except (LinAlgError, sla.LinAlgError):
        raise _not_positive_definite(name, "banded Cholesky factorisation failed") from None
    return _BandedFactor(band, perm, matrix)
