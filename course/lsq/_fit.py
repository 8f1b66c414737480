"""The weighted least-squares fit (BLUE) in the whitened problem, and its result.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy import linalg as sla
from scipy import stats
from scipy.linalg import lapack

from course.linalg import (
    CovarianceFactor,
    check_full_column_rank,
    covariance_factor,
    readonly,
    symmetrize,
)
from course.results import format_number
from course.validation import (
    InputTypeError,
    as_float_array,
    as_matrix,
)

#: An observation whose residual carries less than this fraction of its
#: weight (a generalised redundancy number) cannot be tested: its w-statistic
#: would be 0/0.  Rounding leaves ~1e-30 for a truly untestable observation.
_UNTESTABLE_RTOL = 1e-10

#: |w_i| within this relative distance of the largest count as equally large.
_TIE_RTOL = 1e-10


@lru_cache(maxsize=1)
def _standard_normal():
    # Freezing a scipy distribution costs ~1 ms; Monte Carlo loops reuse it.
    return stats.norm()


_readonly = readonly


def _format_vector(values, digits: int = 5, limit: int = 6) -> str:
    values = np.asarray(values, dtype=float).ravel()
    shown = ", ".join(format_number(float(v), digits) for v in values[:limit])
    if values.size > limit:
        shown += f", ... ({values.size} values)"
    return f"[{shown}]"


# ---------------------------------------------------------------------------
# the fit
# ---------------------------------------------------------------------------
#: Below this reciprocal condition number of R the design is checked for
#: rank deficiency by the library's rank rule (pivoted QR of A); above it,
#: the columns are far from dependent and the check would be wasted work.
_RCOND_CHECK = float(np.sqrt(np.finfo(float).eps))


def _rcond_upper(R: np.ndarray) -> float:
    """The reciprocal 1-norm condition number of the upper-triangular ``R`` (0 if singular).

    LAPACK's ``dtrcon`` estimate where scipy has it (scipy >= 1.15); on older scipy (and
    Pyodide's) the exact value ``1 / (||R||_1 ||R^-1||_1)`` from the n x n inverse, which
    costs no more than the ``R^-1`` that the fit forms anyway.
    """
    trcon = getattr(lapack, "dtrcon", None)
    if trcon is not None:
        rcond, _ = trcon(R, norm="1", uplo="U")
        return float(rcond)
    if not (np.all(np.isfinite(R)) and np.all(np.diag(R) != 0)):
        return 0.0
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        R_inv = sla.solve_triangular(R, np.eye(R.shape[0]), lower=False, check_finite=False)
        rcond = 1.0 / (np.linalg.norm(R, 1) * np.linalg.norm(R_inv, 1))
    return float(rcond) if np.isfinite(rcond) else 0.0


def _row_norms_squared(X: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", X, X)


def _dense_on_demand(build, what: str, m: int) -> np.ndarray:
    """Build an m x m matrix the user asked for, with a message that helps if it does not fit."""
    try:
        return _readonly(build())
    except MemoryError as exc:
        raise MemoryError(
            f"{what} is an m x m matrix, {8 * m * m / 1e9:.3g} GB at m = {m}, and does not fit "
            "in memory; the tests need only its diagonal: use sigma_e_hat, sigma_y_hat or "
            "redundancy_numbers"
        ) from exc


@dataclass(frozen=True, repr=False, eq=False)
class LeastSquaresFit:
    """Result of a (weighted) least-squares fit of ``E(y) = A x``, ``D(y) = Qyy``.

    Build it with :func:`fit`; all arrays are read-only. The fit stores
    vectors and the n x n matrices; the m x m matrices ``Qyy``, ``Qee`` and
    ``Qyy_hat`` are computed on first access (8 m² bytes each: 80 GB at
    m = 10⁵), and ``redundancy_numbers`` likewise. Their diagonals, which is
    all the tests need, are cheap: ``sigma_e_hat``, ``sigma_y_hat``.

    Attributes
    ----------
    A : ndarray, shape (m, n)
        Design matrix.
    y : ndarray, shape (m,)
        Observations.
    Qyy : ndarray, shape (m, m)
        Covariance matrix of the observations, dense (computed on access
        when Qyy was given as variances or sparse).
    x_hat : ndarray, shape (n,)
        BLUE of the parameters, eq. (8.6).
    y_hat : ndarray, shape (m,)
        Adjusted observations ``A x̂``.
    e_hat : ndarray, shape (m,)
        Least-squares residuals ``y - ŷ``, eq. (10.1).
    Qxx : ndarray, shape (n, n)
        Covariance of ``x̂``, ``(A^T Qyy^{-1} A)^{-1}``, eq. (8.7).
    Qyy_hat : ndarray, shape (m, m)
        Covariance of ``ŷ``, ``A Qxx A^T`` (computed on access).
    Qee : ndarray, shape (m, m)
        Covariance of ``ê``, ``Qyy - A Qxx A^T`` (Section 10.3; computed on access).
    redundancy_numbers : ndarray, shape (m,)
        ``diag(Qee Qyy^{-1})``; each in [0, 1] for diagonal Qyy, summing to m - n.
    m, n : int
        Number of observations and of parameters.
    """

    A: np.ndarray
    y: np.ndarray
    x_hat: np.ndarray
    y_hat: np.ndarray
    e_hat: np.ndarray
    Qxx: np.ndarray
    m: int
    n: int
    _covariance: CovarianceFactor
    _R: np.ndarray  # upper triangular, L^{-1} A = Q1 R
    _Q1: np.ndarray  # m x n, orthonormal columns spanning L^{-1} A
    _e_w: np.ndarray  # whitened residuals L^{-1} ê, orthogonal to Q1

    @property
    def redundancy(self) -> int:
        """Degrees of freedom left for the residuals, ``m - n``."""
        return self.m - self.n

    @property
    def squared_norm(self) -> float:
        """Weighted squared norm of the residuals, ``ê^T Qyy^{-1} ê`` (eq. 10.2)."""
        return float(self._e_w @ self._e_w)

    @cached_property
    def Qyy(self) -> np.ndarray:
        """Covariance matrix of the observations as a dense (m, m) array."""
        return _dense_on_demand(lambda: self._covariance.dense(copy=False), "Qyy", self.m)

    @cached_property
    def _G(self) -> np.ndarray:
        # G = A R^{-1} = L Q1, so that Q_ŷŷ = G G^T; one triangular solve, O(m n²).
        return _readonly(
            sla.solve_triangular(self._R, self.A.T, trans="T", lower=False, check_finite=False).T
        )

    @cached_property
    def Qyy_hat(self) -> np.ndarray:
        """Covariance of the adjusted observations, ``A Qxx A^T`` (m x m, built on access)."""
        return _dense_on_demand(lambda: symmetrize(self._G @ self._G.T), "Qyy_hat", self.m)

    @cached_property
    def Qee(self) -> np.ndarray:
        """Covariance of the residuals, ``Qyy - A Qxx A^T`` (m x m, built on access)."""

        def build():
            Q = self._covariance.dense()
            Q -= self._G @ self._G.T
            return symmetrize(Q)

        return _dense_on_demand(build, "Qee", self.m)

    @cached_property
    def redundancy_numbers(self) -> np.ndarray:
        """``r_i = (Qee Qyy^{-1})_ii``, evaluated as ``1 - (L Q1)_i · (L^{-T} Q1)_i``."""
        LtQ1 = self._covariance.whiten_transpose(self._Q1)
        return _readonly(1.0 - np.einsum("ij,ij->i", self._G, LtQ1))

    @cached_property
    def _w_parts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Numerators, squared denominators and weights of Baarda's w_i (see :func:`w_tests`)."""
        cov = self._covariance
        numerator = cov.whiten_transpose(self._e_w)  # c_i^T Qyy^{-1} ê
        weight = cov.inverse_diagonal()  # c_i^T Qyy^{-1} c_i
        # c_i^T Qyy^{-1} Qee Qyy^{-1} c_i = |L^{-1} c_i|² - |Q1^T L^{-1} c_i|²
        denom2 = weight - _row_norms_squared(cov.whiten_transpose(self._Q1))
        return _readonly(numerator), _readonly(denom2), _readonly(weight)

    @property
    def sigma_x_hat(self) -> np.ndarray:
        """Standard deviations of the estimated parameters, ``sqrt(diag(Qxx))``."""
        return np.sqrt(np.diag(self.Qxx))

    @property
    def sigma_y_hat(self) -> np.ndarray:
        """Standard deviations of the adjusted observations, ``sqrt(diag(Qyy_hat))``."""
        return np.sqrt(_row_norms_squared(self._G))

    @property
    def sigma_e_hat(self) -> np.ndarray:
        """Standard deviations of the residuals, ``sqrt(diag(Qee))``."""
        variances = self._covariance.diagonal() - _row_norms_squared(self._G)
        return np.sqrt(np.clip(variances, 0.0, None))

    def __repr__(self) -> str:
        return (
            f"LeastSquaresFit(m={self.m}, n={self.n}, redundancy={self.redundancy}, "
            f"x_hat={_format_vector(self.x_hat)}, "
            f"squared_norm={format_number(self.squared_norm, 5)})"
        )

    def _repr_html_(self) -> str:
        rows = "".join(
            f"<tr><td>x{j + 1}</td><td>{format_number(float(v), 6)}</td>"
            f"<td>{format_number(float(s), 4)}</td></tr>"
            for j, (v, s) in enumerate(zip(self.x_hat, self.sigma_x_hat))
        )
        caption = (
            f"least-squares fit: m = {self.m}, n = {self.n}, redundancy = {self.redundancy}, "
            f"ê<sup>T</sup>Q<sub>yy</sub><sup>-1</sup>ê = {format_number(self.squared_norm, 5)}"
        )
        return (
            f"<table><caption>{caption}</caption>"
            "<tr><th>parameter</th><th>estimate</th><th>std</th></tr>"
            f"{rows}</table>"
        )


def fit(A, y, Qyy=None) -> LeastSquaresFit:
    r"""Weighted least-squares (BLUE) fit of ``E(y) = A x`` with ``D(y) = Qyy``.

    Parameters
    ----------
    A : array_like, shape (m, n)
        Design matrix with full column rank and ``m >= n``.
    y : array_like, shape (m,)
        Observations.
    Qyy : array_like of shape (m,) or (m, m), scipy.sparse matrix, optional
        Covariance of ``y``. A 1-D array holds the VARIANCES ``σ_i²`` of
        uncorrelated observations (square standard deviations first: the
        slip cannot be seen in Qyy itself, and :func:`overall_model_test`
        warns when the data point to it); a matrix, dense or
        ``scipy.sparse``, must be symmetric positive definite. The identity
        when omitted (unit-weight, uncorrelated observations).

    Returns
    -------
    LeastSquaresFit
        Estimates, residuals, covariances and redundancy numbers.

    Raises
    ------
    ValueError
        Shape mismatch, NaN or inf, ``m < n``, non-symmetric ``Qyy``, a
        non-positive variance in a 1-D ``Qyy``.
    numpy.linalg.LinAlgError
        ``A`` rank deficient (the dependent columns are named) or ``Qyy``
        not positive definite.

    See Also
    --------
    overall_model_test : The test of the whole model.
    w_tests : Baarda's test of each observation.
    confidence_band : Confidence band of the fitted curve.
    mdb : Minimal detectable biases.

    Notes
    -----
    The estimate minimises :math:`(y - Ax)^{\mathsf T} Q_{yy}^{-1} (y - Ax)`
    (eq. 8.5 with weights); its closed form is (8.6)

    .. math::

        \hat x = (A^{\mathsf T} Q_{yy}^{-1} A)^{-1} A^{\mathsf T} Q_{yy}^{-1} y,
        \qquad Q_{\hat x\hat x} = (A^{\mathsf T} Q_{yy}^{-1} A)^{-1} \quad (8.7),

    and :math:`\hat y = A\hat x`, :math:`\hat e = y - \hat y` (10.1),
    :math:`Q_{\hat y\hat y} = A Q_{\hat x\hat x} A^{\mathsf T}` and
    :math:`Q_{\hat e\hat e} = Q_{yy} - A Q_{\hat x\hat x} A^{\mathsf T}` (Section
    10.3, from the error propagation law 7.9). The normal equations are not
    used: with :math:`Q_{yy} = LL^{\mathsf T}` and the thin QR factorisation
    :math:`L^{-1}A = Q_1 R`,

    .. math::

        \hat x = R^{-1} Q_1^{\mathsf T} L^{-1} y, \qquad
        Q_{\hat x\hat x} = R^{-1} R^{-\mathsf T},

    and, with :math:`G = AR^{-1} = LQ_1`, :math:`Q_{\hat y\hat y} = GG^{\mathsf T}`
    and :math:`Q_{\hat e\hat e} = Q_{yy} - GG^{\mathsf T}`. The redundancy
    numbers :math:`r_i = (Q_{\hat e\hat e} Q_{yy}^{-1})_{ii}` are
    :math:`1 - G_i \cdot (L^{-\mathsf T} Q_1)_i`; they sum to :math:`m - n`. The
    Cholesky factorisation is also the check that :math:`Q_{yy}` is positive
    definite.

    Cost: :math:`O(mn^2)` time and :math:`O(mn)` memory for diagonal
    :math:`Q_{yy}` (1-D, a diagonal matrix or a diagonal sparse matrix),
    :math:`O(mb^2 + mnb)` for a sparse :math:`Q_{yy}` of bandwidth :math:`b`
    after reordering, :math:`O(m^3)` for a dense correlated :math:`Q_{yy}`.

    Examples
    --------
    >>> import numpy as np
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> f = fit(A, [14, 20, 20, 24])
    >>> [float(v) for v in np.round(f.x_hat, 10)], round(f.squared_norm, 10)
    ([12.0, 3.0], 6.0)

    Uncorrelated observations with standard deviations ``sigma`` give their
    variances as a vector; with ``sigma = 2`` the squared norm is 6 / 2²:

    >>> sigma = np.full(4, 2.0)
    >>> round(fit(A, [14, 20, 20, 24], sigma**2).squared_norm, 10)
    1.5
    """
    A = as_matrix(A, "A")
    m, n = A.shape
    if m == 0 or n == 0:
        raise ValueError(f"A must have at least one row and one column, got shape {A.shape}")
    y = as_float_array(y, "y")
    if y.ndim != 1:
        raise ValueError(
            f"y must be a 1-D vector of the m = {m} observations, got shape {y.shape}; "
            "pass it flattened, e.g. np.ravel(y)"
        )
    if y.shape[0] != m:
        raise ValueError(
            f"shape mismatch: y has {y.shape[0]} observations but A has {m} rows; "
            "every observation needs exactly one row of A"
        )
    if m < n:
        raise ValueError(
            f"A has fewer rows than columns (m = {m} observations, n = {n} parameters): "
            "the parameters are not determined; add observations or remove parameters"
        )
    covariance = covariance_factor(Qyy, "Qyy", m)
    y_w = covariance.whiten(y)
    # LAPACK works column-major: a Fortran-ordered input halves the QR's time at m = 1e5.
    A_w = np.asfortranarray(covariance.whiten(A))
    Q1, R = sla.qr(A_w, mode="economic", overwrite_a=True, check_finite=False)
    if not _rcond_upper(R) > _RCOND_CHECK:
        check_full_column_rank(A, "A")  # names the dependent columns, if any
    coefficients = Q1.T @ y_w
    x_hat = sla.solve_triangular(R, coefficients, lower=False, check_finite=False)
    e_w = y_w - Q1 @ coefficients
    R_inv = sla.solve_triangular(R, np.eye(n), lower=False, check_finite=False)
    with np.errstate(over="ignore", invalid="ignore"):
        Qxx_raw = R_inv @ R_inv.T
        y_hat = A @ x_hat
    if not all(np.all(np.isfinite(v)) for v in (Qxx_raw, x_hat, y_hat)):
        # A scaled near the limits of floating point (A * 1e-300): Qxx ~ 1/|A|^2 overflows.
        raise ValueError(
            "A is scaled so far from 1 that the estimate or its covariance overflows double "
            f"precision (largest |A| = {float(np.max(np.abs(A))):.3g}); rescale the columns of A "
            "(change the parameters' units), fit, and scale x_hat back"
        )
    Qxx = symmetrize(Qxx_raw)
    return LeastSquaresFit(
        A=_readonly(A),
        y=_readonly(y),
        x_hat=_readonly(x_hat),
        y_hat=_readonly(y_hat),
        e_hat=_readonly(y - y_hat),
        Qxx=_readonly(Qxx),
        m=int(m),
        n=int(n),
        _covariance=covariance,
        _R=_readonly(R),
        _Q1=_readonly(Q1),
        _e_w=_readonly(e_w),
    )


def _check_fit(value) -> LeastSquaresFit:
    if not isinstance(value, LeastSquaresFit):
        raise InputTypeError(
            f"fit must be a LeastSquaresFit (the result of course.lsq.fit(A, y, Qyy)), "
            f"got {type(value).__name__}"
        )
    return value


def _require_residuals_for_sigma(result: LeastSquaresFit, what: str) -> None:
    """Refuse to estimate sigma² from residuals that are only round-off.

    Data that the model fits exactly leave residuals of the size of the rounding errors of
    the fit; sigma² estimated from them is 0 up to round-off, and t or F statistics built on
    it would test the rounding errors (they can reject).
    """
    y_w = result._covariance.whiten(result.y)
    scale = float(y_w @ y_w)
    roundoff = (16.0 * result.m * np.finfo(float).eps) ** 2 * scale
    if result.squared_norm <= roundoff:
        raise ValueError(
            f"{what} with variance='estimated' needs residuals: the data fit the model "
            f"exactly (the residual norm {result.squared_norm:.3g} is at the level of "
            "rounding errors), so sigma² would be estimated as 0 and the test would judge "
            "round-off; use variance='known' with the stated Qyy"
        )


def _require_redundancy(result: LeastSquaresFit, what: str) -> None:
    if result.redundancy == 0:
        raise ValueError(
            f"the {what} is void: there is no redundancy (m - n = 0, m = n = {result.m}); "
            "every observation is needed to determine the parameters, so the residuals are "
            "zero by construction and cannot reveal anything. Add observations or use a "
            "model with fewer parameters"
        )
