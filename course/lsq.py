"""Least-squares residuals and the tests built on them.

This module follows Chapter 10 "Validation" of Tiberius, van der Marel,
Reudink and van Leijen (2021), *Surveying and Mapping*, TU Delft Open
Textbook (full reference in the course bibliography, :doc:`/docs/bibliography`):
the model of observation equations

.. math:: E(\\underline{y}) = A x, \\qquad D(\\underline{y}) = Q_{yy},

its best linear unbiased estimate, the least-squares residuals, the overall
model test (a chi-square test of the weighted squared norm of the residuals),
Baarda's w-test for single outliers, data snooping, the minimal detectable
bias (internal reliability) and the confidence band of the fitted model.

Public functions
----------------
fit
    Weighted least squares (BLUE): estimates, residuals and their covariances.
overall_model_test
    ``T = ê^T Qyy^{-1} ê ~ chi2(m - n)`` under H0.
w_tests
    One normalised residual per observation, two-sided normal test.
data_snooping
    Remove the most suspicious observation and refit, until nothing is rejected.
noncentrality, mdb
    Non-centrality of a test with given power (:func:`course.chi2.noncentrality`,
    re-exported here), and the minimal detectable bias.
confidence_band
    Fitted values at new design rows with their confidence half-widths.
load_sea_level
    The four MUDE sea-level data sets shipped with the course.

Numerics
--------
Everything is computed in the *whitened* problem. With a factor
``Qyy = L L^T`` (a vector of standard deviations for diagonal Qyy, a banded
Cholesky factor for sparse Qyy, a dense Cholesky factor otherwise, see
:func:`course.linalg.covariance_factor`) the model becomes
``L^{-1} y = (L^{-1} A) x + ε`` with ``D(ε) = I``; a thin QR factorisation
``L^{-1} A = Q1 R`` (Q1 of shape m x n) then gives the estimate
``x̂ = R^{-1} Q1^T L^{-1} y`` by a triangular solve, the covariance of the
estimate ``Qxx = R^{-1} R^{-T}``, the whitened residuals
``ẽ = L^{-1} y - Q1 Q1^T L^{-1} y`` and the w-test quantities, without ever
forming ``(A^T Qyy^{-1} A)^{-1}``, ``Qyy^{-1}`` or any m x m matrix. The
tests need only diagonals, so a fit costs O(m n²) time and O(m n) memory for
diagonal Qyy; the m x m matrices ``Qee`` and ``Qyy_hat`` are computed when
asked for.
"""

from __future__ import annotations

import html
import io
import warnings
from dataclasses import dataclass
from functools import cached_property, lru_cache
from importlib import resources
from typing import Any, NamedTuple

import numpy as np
from scipy import linalg as sla
from scipy import stats
from scipy.linalg import lapack

from course.chi2 import noncentrality, residual_norm_law
from course.linalg import (
    CovarianceFactor,
    check_full_column_rank,
    covariance_factor,
    readonly,
    symmetrize,
)
from course.results import TestResult, decide, format_number
from course.validation import (
    InputTypeError,
    as_count,
    as_float_array,
    as_index,
    as_matrix,
    as_probability,
)

__all__ = [
    "ConfidenceBand",
    "LeastSquaresFit",
    "SnoopingResult",
    "WTestResult",
    "confidence_band",
    "data_snooping",
    "fit",
    "load_mauna_loa_co2",
    "load_sea_level",
    "mdb",
    "noncentrality",
    "overall_model_test",
    "w_tests",
]

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
    """Weighted least-squares (BLUE) fit of ``E(y) = A x`` with ``D(y) = Qyy``.

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

    Notes
    -----
    The estimate minimises ``(y - A x)^T Qyy^{-1} (y - A x)`` (eq. 8.5 with
    weights); its closed form is (8.6)

    .. math:: \\hat x = (A^T Q_{yy}^{-1} A)^{-1} A^T Q_{yy}^{-1} y,
              \\quad Q_{\\hat x\\hat x} = (A^T Q_{yy}^{-1} A)^{-1} \\; (8.7),

    and ``ŷ = A x̂``, ``ê = y - ŷ`` (10.1), ``Q_ŷŷ = A Q_x̂x̂ A^T`` and
    ``Q_êê = Qyy - A Q_x̂x̂ A^T`` (Section 10.3, from the error propagation
    law 7.9). The normal equations are not used: with ``Qyy = L L^T`` and
    the thin QR factorisation ``L^{-1} A = Q1 R``,
    ``x̂ = R^{-1} Q1^T L^{-1} y``, ``Q_x̂x̂ = R^{-1} R^{-T}`` and, with
    ``G = A R^{-1} = L Q1``, ``Q_ŷŷ = G G^T`` and ``Q_êê = Qyy - G G^T``.
    The redundancy numbers ``r_i = (Q_êê Q_yy^{-1})_{ii}`` are
    ``1 - G_i · (L^{-T} Q1)_i``; they sum to ``m - n``. The Cholesky
    factorisation is also the check that Qyy is positive definite.

    Cost: O(m n²) time and O(m n) memory for diagonal Qyy (1-D, a diagonal
    matrix or a diagonal sparse matrix), O(m b² + m n b) for a sparse Qyy of
    bandwidth b after reordering, O(m³) for a dense correlated Qyy.

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


def _require_redundancy(result: LeastSquaresFit, what: str) -> None:
    if result.redundancy == 0:
        raise ValueError(
            f"the {what} is void: there is no redundancy (m - n = 0, m = n = {result.m}); "
            "every observation is needed to determine the parameters, so the residuals are "
            "zero by construction and cannot reveal anything. Add observations or use a "
            "model with fewer parameters"
        )


# ---------------------------------------------------------------------------
# overall model test
# ---------------------------------------------------------------------------
def overall_model_test(fit: LeastSquaresFit, alpha: float = 0.05) -> TestResult:
    """Overall model test: is the weighted squared norm of ``ê`` too large?

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    alpha : float
        Level of significance (false-alarm probability), in (0, 1).

    Returns
    -------
    TestResult
        ``statistic`` T, ``dof`` m - n, ``critical_value`` ``chi2.isf(alpha, m - n)``,
        ``pvalue`` ``chi2.sf(T, m - n)``, ``null`` ``chi2(m - n)``; ``details``
        holds the variance factor ``T / (m - n)``.

    Raises
    ------
    ValueError
        If ``m - n = 0``: without redundancy the test is void.

    Notes
    -----
    Eq. (10.2): under H0 (``y ~ N(Ax, Qyy)``)

    .. math:: T = \\hat e^T Q_{yy}^{-1} \\hat e \\sim \\chi^2(m - n, 0),

    rejected (right-sided) when ``T > chi2_alpha(m - n)``. For diagonal Qyy
    ``T = Σ (ê_i / σ_i)²`` (10.3); for m repeated measurements of one
    quantity ``T / (m - 1) = σ̂² / σ²`` (Section 10.1.4), which is why
    ``T / (m - n)`` is reported as the (a-posteriori) variance factor. T is
    evaluated as ``||ẽ||²`` with ``ẽ = L^{-1} ê`` the whitened residuals, the
    same number without ``Qyy^{-1}``.

    A 1-D Qyy filled with standard deviations instead of variances is a
    likely slip that no check of Qyy alone can see (both are positive
    numbers). It shows here, and only here: the variance factor is then
    about the typical standard deviation instead of 1. A :class:`UserWarning`
    says so when Qyy was given as a 1-D array, T falls outside the central
    range ``[chi2_{1-α}(m - n), chi2_α(m - n)]``, the same data with Qyy's
    entries read as standard deviations (variances ``Qyy_i²``) fall inside
    it, and the residuals' pattern does not favour the values as variances
    (a likelihood ratio of the two readings with a free common scale, above
    1/10; it is 1 when all values are equal). With equal values the slip
    looks exactly like a wrong variance factor, so the warning names both.

    Examples
    --------
    The chapter's second day of line fitting: the line is rejected.

    >>> import numpy as np
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> result = overall_model_test(fit(A, [28, 20, 16, 36]), alpha=0.01)
    >>> round(result.statistic, 6), round(result.critical_value, 4), result.reject
    (216.0, 9.2103, True)
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    _require_redundancy(fit, "overall model test")
    dof = fit.redundancy
    T = fit.squared_norm
    null = residual_norm_law(dof)
    result = TestResult.from_null(
        "overall model test",
        T,
        null,
        alpha,
        dof=dof,
        details={"variance factor T/(m-n)": T / dof},
    )
    hint = _standard_deviation_hint(fit, result)
    if hint:
        warnings.warn(hint, UserWarning, stacklevel=2)
    return result


def _standard_deviation_hint(fit: LeastSquaresFit, result: TestResult) -> str:
    """A message when a 1-D Qyy of variances looks like standard deviations, else ``""``."""
    cov = fit._covariance
    # T inside the central range [chi2_{1-alpha}, chi2_alpha]: nothing to explain. Read off
    # the decision (p = sf(T)), so that the usual case costs no quantile computations.
    if cov.given_as != "variances" or not (result.reject or 1.0 - result.pvalue < result.alpha):
        return ""
    T, alpha, null = result.statistic, result.alpha, result.null
    low, high = float(null.ppf(alpha)), float(null.isf(alpha))
    sigma = cov.diagonal()  # the given variances, read as standard deviations
    # The refit costs one more O(m n²) QR, paid only when the test is already surprising.
    A_w = np.asfortranarray(fit.A / sigma[:, None])
    y_w = fit.y / sigma
    Q1, _ = sla.qr(A_w, mode="economic", overwrite_a=True, check_finite=False)
    e_w = y_w - Q1 @ (Q1.T @ y_w)
    T_alt = float(e_w @ e_w)
    if not low <= T_alt <= high:
        return ""
    # With a free common scale, the log-likelihood of "standard deviations" minus that of
    # "variances" is (m log(T / T_alt) - sum log sigma) / 2: it compares the SHAPE of the
    # weights, and is 0 when all values are equal. Stay silent when the residuals' pattern
    # clearly fits the values as variances.
    log_ratio = 0.5 * (fit.m * np.log(T / T_alt) - float(np.sum(np.log(sigma))))
    if log_ratio < -np.log(10.0):
        return ""
    dof = fit.redundancy
    return (
        f"Qyy was given as a 1-D array of variances and the overall model test finds "
        f"T = {T:.4g}, a variance factor T/(m-n) = {T / dof:.3g}, outside the central range "
        f"[{low:.4g}, {high:.4g}] of chi2({dof}) at alpha = {alpha:g}. Read as standard "
        f"deviations (variances Qyy**2), the same data give T = {T_alt:.4g}, inside that "
        "range. Qyy must hold VARIANCES: if you passed standard deviations sigma, pass "
        "sigma**2 (if Qyy does hold variances, the model or the stated precision is wrong)."
    )


# ---------------------------------------------------------------------------
# w-tests
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class WTestResult:
    """Baarda's w-test applied to every observation of a fit.

    Attributes
    ----------
    w : ndarray, shape (m,)
        Test statistics (NaN where an observation cannot be tested).
    critical_value : float
        ``norm.isf(alpha / 2)``: reject observation i when ``|w_i|`` exceeds it.
    reject : ndarray of bool, shape (m,)
        Decision per observation.
    pvalues : ndarray, shape (m,)
        Two-sided p-values ``2 norm.sf(|w_i|)`` (NaN where untestable).
    largest : int
        Index (0-based) of the largest ``|w_i|``: the most suspicious observation.
    testable : ndarray of bool, shape (m,)
        False for observations with no redundancy (generalised redundancy
        number below 1e-10): an outlier there leaves no trace in ê.
    alpha : float
        Level of significance of each single test.
    null : scipy.stats frozen distribution
        ``norm()``, the law of each ``w_i`` under H0.
    """

    w: np.ndarray
    critical_value: float
    reject: np.ndarray
    pvalues: np.ndarray
    largest: int
    testable: np.ndarray
    alpha: float
    null: Any

    @property
    def any_reject(self) -> bool:
        """True when at least one observation is rejected."""
        return bool(np.any(self.reject))

    @property
    def rejected(self) -> list[int]:
        """Indices (0-based) of the rejected observations."""
        return [int(i) for i in np.flatnonzero(self.reject)]

    def test(self, i: int) -> TestResult:
        """The w-test of observation ``i`` as a :class:`~course.results.TestResult`."""
        i = as_index(i, "i", self.w.shape[0], negative=True, what="observation index")
        if not self.testable[i]:
            raise ValueError(
                f"observation {i} cannot be tested: it has no redundancy (its residual is "
                "always zero), so an outlier in it is invisible"
            )
        return TestResult.from_null(
            f"w-test, observation {i}", float(self.w[i]), self.null, self.alpha, "two-sided"
        )

    def tests(self) -> list[TestResult]:
        """One :class:`~course.results.TestResult` per testable observation."""
        return [self.test(int(i)) for i in np.flatnonzero(self.testable)]

    def summary(self) -> str:
        """One line: largest ``|w|``, threshold and the rejected observations."""
        i = self.largest
        return (
            f"w-tests (alpha = {format_number(self.alpha)}): critical |w| = "
            f"{format_number(self.critical_value, 5)}, largest |w| = "
            f"{format_number(abs(float(self.w[i])), 5)} at observation {i}, "
            f"rejected: {self.rejected if self.rejected else 'none'}"
        )

    def __repr__(self) -> str:
        i = self.largest
        return (
            f"WTestResult(m={self.w.shape[0]}, alpha={format_number(self.alpha)}, "
            f"critical_value={format_number(self.critical_value, 5)}, largest={i}, "
            f"w_largest={format_number(float(self.w[i]), 5)}, rejected={self.rejected})"
        )

    def _repr_html_(self) -> str:
        rows = []
        for i, (w, p, r, ok) in enumerate(zip(self.w, self.pvalues, self.reject, self.testable)):
            style = " style='font-weight:bold'" if r else ""
            w_text = format_number(float(w), 4) if ok else "untestable"
            p_text = format_number(float(p), 3) if ok else ""
            rows.append(
                f"<tr{style}><td>{i}</td><td>{html.escape(w_text)}</td>"
                f"<td>{p_text}</td><td>{bool(r)}</td></tr>"
            )
        caption = (
            f"w-tests, alpha = {format_number(self.alpha)}, critical |w| = "
            f"{format_number(self.critical_value, 5)}"
        )
        return (
            f"<table><caption>{caption}</caption>"
            "<tr><th>i</th><th>w</th><th>p-value</th><th>reject</th></tr>"
            + "".join(rows)
            + "</table>"
        )


def _w_quantities(fit: LeastSquaresFit):
    """Numerators, squared denominators and testability of Baarda's w_i."""
    numerator, denom2, weight = fit._w_parts
    return numerator, denom2, denom2 > _UNTESTABLE_RTOL * weight


def _w_test_result(numerator, denom2, weight, alpha: float) -> WTestResult:
    """Baarda's w_i = numerator_i / sqrt(denom2_i) and their two-sided tests."""
    testable = denom2 > _UNTESTABLE_RTOL * weight
    m = numerator.shape[0]
    w = np.full(m, np.nan)
    w[testable] = numerator[testable] / np.sqrt(denom2[testable])
    null = _standard_normal()
    decision = decide(null, w[testable], alpha, "two-sided")
    critical = decision.critical_value.upper
    pvalues = np.full(m, np.nan)
    pvalues[testable] = decision.pvalue
    reject = np.zeros(m, dtype=bool)
    reject[testable] = decision.reject
    largest = 0
    if np.any(testable):
        # The first of the largest: |w| equal up to rounding count as a tie (with redundancy
        # 1 all testable |w_i| are equal), so the choice does not depend on round-off.
        abs_w = np.abs(w)
        largest = int(np.flatnonzero(abs_w >= (1 - _TIE_RTOL) * np.nanmax(abs_w))[0])
    return WTestResult(
        w=_readonly(w),
        critical_value=critical,
        reject=_readonly(reject),
        pvalues=_readonly(pvalues),
        largest=largest,
        testable=_readonly(testable),
        alpha=alpha,
        null=null,
    )


def w_tests(fit: LeastSquaresFit, alpha: float = 0.05) -> WTestResult:
    """Baarda's w-test of every observation for a single outlier.

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    alpha : float
        Level of significance of each (two-sided) test.

    Returns
    -------
    WTestResult
        ``w``, ``critical_value`` (``norm.isf(alpha/2)``), ``reject``,
        ``pvalues``, ``largest`` (index of max ``|w|``), ``testable``,
        ``alpha`` and ``null`` (``norm()``); ``.tests()`` gives one
        :class:`~course.results.TestResult` per observation.

    Raises
    ------
    ValueError
        If ``m - n = 0`` (nothing can be tested).

    Notes
    -----
    The alternative hypothesis of test i is ``E(y) = A x + c_i ∇`` with
    ``c_i`` the i-th unit vector (an outlier ``∇`` in observation i). Baarda's
    statistic

    .. math:: w_i = \\frac{c_i^T Q_{yy}^{-1} \\hat e}
                         {\\sqrt{c_i^T Q_{yy}^{-1} Q_{\\hat e\\hat e} Q_{yy}^{-1} c_i}}
              \\sim N(0, 1) \\text{ under H0}

    reduces for diagonal Qyy to the chapter's eq. (10.4), ``w_i = ê_i /
    σ_êi``, and also holds for correlated observations. The critical value
    is two-sided, ``N_{α/2}(0, 1)`` (Section 10.3). With ``Qyy = L L^T``,
    the thin QR ``L^{-1} A = Q1 R`` and the whitened residuals ``ẽ``:
    ``Q_yy^{-1} ê = L^{-T} ẽ`` and
    ``c_i^T Q_yy^{-1} Q_êê Q_yy^{-1} c_i = |L^{-1} c_i|² - |Q1^T L^{-1} c_i|²``,
    where ``|L^{-1} c_i|² = (Q_yy^{-1})_{ii}``; so the numerators and the
    denominators come from one whitening solve with n + 1 right-hand sides
    and the diagonal of ``Q_yy^{-1}`` (O(m n) for diagonal Qyy).
    Reference: W. Baarda (1968), *A testing procedure for use in geodetic
    networks*, Netherlands Geodetic Commission.

    Examples
    --------
    A line observed with sigma = 0.1 and an outlier of 0.6 at observation 6:

    >>> import numpy as np
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> y = [2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53]
    >>> wt = w_tests(fit(A, y, 0.01 * np.eye(10)), alpha=0.01)
    >>> wt.largest, wt.rejected, round(float(wt.w[6]), 2)
    (6, [6], 4.83)
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    _require_redundancy(fit, "w-test")
    return _w_test_result(*fit._w_parts, alpha)


# ---------------------------------------------------------------------------
# data snooping
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class SnoopingResult:
    """Outcome of :func:`data_snooping`.

    Attributes
    ----------
    removed : tuple of int
        Removed observations, in the order of removal, as 0-based indices of
        the ORIGINAL observation vector.
    kept : tuple of int
        Original indices of the observations in the final fit.
    rounds : tuple of WTestResult
        The w-tests of each round (round k tests the observations ``kept``
        before the k-th removal; its indices are positions in that round).
    round_indices : tuple of tuple of int
        For each round, the original index of each observation it tested.
    fit : LeastSquaresFit
        The final fit, on the kept observations.
    stop_reason : str
        Why the procedure stopped: ``"no observation rejected"``,
        ``"no redundancy left"`` or ``"max_removals reached"``.
    alpha : float
        Level of significance of the w-tests.
    """

    removed: tuple
    kept: tuple
    rounds: tuple
    round_indices: tuple
    fit: LeastSquaresFit
    stop_reason: str
    alpha: float

    def __repr__(self) -> str:
        return (
            f"SnoopingResult(removed={list(self.removed)}, rounds={len(self.rounds)}, "
            f"final m={self.fit.m}, n={self.fit.n}, stop_reason={self.stop_reason!r})"
        )

    def summary(self) -> str:
        """One line: what was removed and why the procedure stopped."""
        removed = list(self.removed) if self.removed else "nothing"
        return (
            f"data snooping (alpha = {format_number(self.alpha)}): removed {removed} "
            f"in {len(self.rounds)} round(s); stopped: {self.stop_reason}"
        )

    def _repr_html_(self) -> str:
        rows = []
        for k, (wt, idx) in enumerate(zip(self.rounds, self.round_indices)):
            j = wt.largest
            action = f"remove {idx[j]}" if wt.reject[j] else "stop"
            rows.append(
                f"<tr><td>{k + 1}</td><td>{len(idx)}</td><td>{idx[j]}</td>"
                f"<td>{format_number(float(wt.w[j]), 4)}</td>"
                f"<td>{format_number(wt.critical_value, 4)}</td><td>{action}</td></tr>"
            )
        caption = html.escape(self.summary())
        return (
            f"<table><caption>{caption}</caption><tr><th>round</th><th>m</th>"
            "<th>largest |w| at (original index)</th><th>w</th><th>critical</th><th>action</th></tr>"
            + "".join(rows)
            + "</table>"
        )


def data_snooping(
    A, y, Qyy=None, alpha: float = 0.01, max_removals: int | None = None
) -> SnoopingResult:
    """Iterated w-tests: remove the worst rejected observation and refit.

    Parameters
    ----------
    A, y, Qyy
        The model, as for :func:`fit`.
    alpha : float
        Level of significance of every w-test.
    max_removals : int, optional
        Stop after this many removals (default: no limit).

    Returns
    -------
    SnoopingResult
        Removed indices (original numbering), the w-tests of every round, the
        final fit and the reason for stopping.

    Notes
    -----
    Section 10.3: the observation with the largest ``|w_i|`` is the most
    likely faulty one; if its test rejects, it is removed (its row of A, its
    entry of y and its row and column of Qyy) and the estimation and
    validation are repeated, until no w-test rejects or the redundancy
    ``m - n`` is used up. Observations without redundancy are never tested,
    and removing a testable one keeps A of full column rank. With
    redundancy 1 all testable ``|w_i|`` are equal, so a rejection there
    cannot tell which observation is wrong: the removal is then arbitrary
    (the first largest), which is why practitioners want redundancy to spare.

    Each removal is a rank-one downdate, not a fresh fit: removing
    observation i gives the same estimate, T and w-tests of the others as
    keeping it with an outlier parameter of its own, ``E(y) = A x + c_i ∇_i``
    (the alternative hypothesis of its w-test). In the whitened problem that
    adds the column ``L^{-1} c_i`` to the design, i.e. one orthonormal
    vector ``q`` to ``Q1``; the whitened residuals lose their component
    along ``q`` (T drops by exactly ``w_i²``), and the numerators and squared
    denominators of the remaining ``w_j`` change by ``L^{-T} q`` terms. Qyy
    is factored once; a round costs O(m (n + k)) for diagonal Qyy and O(m²)
    for a dense one, against O(m n²) and O(m³) for a fresh fit. The final
    ``fit`` is computed once, on the kept observations. (Only the cut-off
    for untestable observations, a generalised redundancy below 1e-10, is
    measured in the full model's weights ``(Q_yy^{-1})_jj``.)

    Examples
    --------
    >>> import numpy as np
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> y = [2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53]
    >>> result = data_snooping(A, y, 0.01 * np.eye(10), alpha=0.01)
    >>> result.removed, result.stop_reason
    ((6,), 'no observation rejected')
    """
    alpha = as_probability(alpha)
    if max_removals is not None:
        max_removals = as_count(max_removals, "max_removals", minimum=0)
    first = fit(A, y, Qyy)
    model = _OutlierModel(first)
    kept = np.arange(first.m)
    removed: list[int] = []
    rounds: list[WTestResult] = []
    round_indices: list[tuple] = []
    while True:
        if first.redundancy - len(removed) == 0:
            reason = "no redundancy left"
            break
        # Round 1 tests the fit itself; later rounds read the downdated model.
        wt = model.w_tests(kept, alpha) if removed else w_tests(first, alpha)
        rounds.append(wt)
        round_indices.append(tuple(kept.tolist()))
        if not wt.any_reject:
            reason = "no observation rejected"
            break
        if max_removals is not None and len(removed) >= max_removals:
            reason = "max_removals reached"
            break
        worst = int(kept[wt.largest])
        kept = np.delete(kept, wt.largest)
        removed.append(worst)
        model.remove(worst)
    current = first
    if removed:
        current = fit(first.A[kept], first.y[kept], first._covariance.take(kept))
    return SnoopingResult(
        removed=tuple(removed),
        kept=tuple(kept.tolist()),
        rounds=tuple(rounds),
        round_indices=tuple(round_indices),
        fit=current,
        stop_reason=reason,
        alpha=alpha,
    )


class _OutlierModel:
    """A fit whose removed observations each carry an outlier parameter of their own.

    Holds the whitened residuals and the w-test numerators and squared
    denominators of every observation, and downdates them by one rank per
    removal (see :func:`data_snooping`).
    """

    def __init__(self, first: LeastSquaresFit):
        self._covariance = first._covariance
        # Orthonormal columns spanning the whitened design and the outlier columns added so
        # far, in a column-major buffer that grows by doubling (columns contiguous for BLAS).
        self._n = first.n
        self._basis = np.empty((first.m, 2 * first.n + 8), order="F")
        self._basis[:, : first.n] = first._Q1
        numerator, denom2, weight = first._w_parts
        self._e_w = first._e_w.copy()
        self._numerator = numerator.copy()
        self._denom2 = denom2.copy()
        self._weight = weight

    def remove(self, i: int) -> None:
        v = self._covariance.whiten_unit(i)  # the outlier column L^{-1} c_i
        basis = self._basis[:, : self._n]
        for _ in range(2):  # classical Gram-Schmidt, twice: orthogonal to working precision
            v -= basis @ (basis.T @ v)
        q = v / np.linalg.norm(v)
        coefficient = float(q @ self._e_w)  # = w_i of the round that removed i
        self._e_w -= coefficient * q
        Lt_q = self._covariance.whiten_transpose(q)
        self._numerator -= coefficient * Lt_q
        self._denom2 -= Lt_q * Lt_q
        if self._n == self._basis.shape[1]:
            grown = np.empty((self._basis.shape[0], 2 * self._n), order="F")
            grown[:, : self._n] = self._basis
            self._basis = grown
        self._basis[:, self._n] = q
        self._n += 1

    def w_tests(self, index: np.ndarray, alpha: float) -> WTestResult:
        return _w_test_result(
            self._numerator[index], self._denom2[index], self._weight[index], alpha
        )


# ---------------------------------------------------------------------------
# reliability
# ---------------------------------------------------------------------------
def mdb(fit: LeastSquaresFit, alpha: float = 0.001, power: float = 0.80) -> np.ndarray:
    """Minimal detectable bias of every observation (internal reliability).

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    alpha : float
        Level of significance of the w-test.
    power : float
        Probability with which the bias must be detected.

    Returns
    -------
    ndarray, shape (m,)
        ``|∇_i|``, in the units of y; ``inf`` where an observation is untestable.

    Notes
    -----
    An outlier ``∇`` in observation i shifts the mean of ``w_i`` to
    ``∇ sqrt(c_i^T Qyy^{-1} Qee Qyy^{-1} c_i)``, so ``w_i²`` is
    ``chi2(1, λ)`` with ``λ = ∇² c_i^T Qyy^{-1} Qee Qyy^{-1} c_i``. The
    smallest bias found with probability ``power`` is therefore

    .. math:: |\\nabla_i| = \\sqrt{\\frac{\\lambda_0}
              {c_i^T Q_{yy}^{-1} Q_{\\hat e\\hat e} Q_{yy}^{-1} c_i}}

    with ``λ0 = noncentrality(alpha, power, 1)``; for diagonal Qyy this is
    ``σ_i sqrt(λ0 / r_i)`` with ``r_i`` the redundancy number. Beyond the
    chapter; reference: Baarda (1968).

    Examples
    --------
    >>> import numpy as np
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> mdb(fit(A, [14, 20, 20, 24])).round(2)
    array([7.54, 4.94, 4.94, 7.54])
    """
    fit = _check_fit(fit)
    _require_redundancy(fit, "minimal detectable bias")
    lam0 = noncentrality(alpha, power, 1)
    _, denom2, testable = _w_quantities(fit)
    out = np.full(fit.m, np.inf)
    out[testable] = np.sqrt(lam0 / denom2[testable])
    return out


# ---------------------------------------------------------------------------
# confidence band
# ---------------------------------------------------------------------------
class ConfidenceBand(NamedTuple):
    """Result of :func:`confidence_band` (unpacks as ``y_new_hat, half_width``)."""

    y_new_hat: np.ndarray
    """``A_new x̂``, ``(k,)``."""
    half_width: np.ndarray
    """Half-widths of the confidence intervals, ``(k,)``."""


def confidence_band(fit: LeastSquaresFit, A_new: Any, level: float = 0.95) -> ConfidenceBand:
    """Fitted values at new design rows and their confidence half-widths.

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    A_new : array_like, shape (k, n)
        Design rows at which to evaluate the model (e.g. a fine time grid).
    level : float
        Confidence level, in (0, 1).

    Returns
    -------
    ConfidenceBand
        ``y_new_hat = A_new x̂`` and ``half_width = norm.isf((1 - level) / 2) * σ``,
        with ``σ² = diag(A_new Q_x̂x̂ A_new^T)``, each of shape ``(k,)``.

    Notes
    -----
    Section 10.4 and Figure 10.3: with Qyy known, ``ŷ(t) = a(t)^T x̂`` is
    normal with variance ``a(t)^T Q_x̂x̂ a(t)`` (error propagation law 7.9),
    so the interval ``ŷ(t) ± r_α σ_ŷ(t)``, ``r_α = N_{(1-level)/2}(0,1)``
    (1.96 for 95 %), covers the true ``E(y(t))`` with probability ``level``.
    For day 1 of the line-fitting example ``σ_ŷ2 ≈ 0.55`` and the half-width
    is ≈ 1.07. The variance is evaluated as ``||R^{-T} a||²`` by a
    triangular solve.

    Examples
    --------
    Day 1 of the chapter: the fitted value at t = 2 and its 95 % half-width.

    >>> import numpy as np
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> band = confidence_band(fit(A, [14, 20, 20, 24]), [[1.0, 2.0]])
    >>> round(float(band.y_new_hat[0]), 6), round(float(band.half_width[0]), 2)
    (18.0, 1.07)
    """
    fit = _check_fit(fit)
    level = as_probability(level, "level")
    A_new = as_float_array(A_new, "A_new")
    if A_new.ndim != 2 or A_new.shape[1] != fit.n:
        raise ValueError(
            f"A_new must have shape (k, n) with n = {fit.n} columns like A, got shape "
            f"{A_new.shape}; for a single row use np.reshape(row, (1, -1))"
        )
    y_new = A_new @ fit.x_hat
    G = sla.solve_triangular(fit._R, A_new.T, trans="T", lower=False, check_finite=False)
    sigma = np.sqrt(np.sum(G * G, axis=0))
    return ConfidenceBand(y_new, stats.norm.isf((1.0 - level) / 2) * sigma)


# ---------------------------------------------------------------------------
# data
# ---------------------------------------------------------------------------
def load_sea_level(case: int):
    """One of the four MUDE sea-level data sets shipped with the course.

    Parameters
    ----------
    case : {0, 1, 2, 3}
        0: a linear trend fits; 1: one outlier; 2: a quadratic term is
        missing; 3: the stated precision is too optimistic.

    Returns
    -------
    t : ndarray, shape (20,)
        Epochs 1, 2, ..., 20.
    y : ndarray, shape (20,)
        Sea-level observations; the source states a standard deviation of 2
        for every observation (and uses alpha = 0.05).

    Notes
    -----
    Data: TU Delft MUDE open course book, "overall model test" notebook,
    CC BY 4.0 (see ``course/data/sea_level_mude/README.md``).

    Examples
    --------
    >>> t, y = load_sea_level(1)
    >>> t.size, y.size
    (20, 20)
    """
    try:
        case = as_index(case, "case", 4)
    except ValueError:
        raise ValueError(f"case must be 0, 1, 2 or 3, got {case!r}") from None
    source = resources.files("course") / "data" / "sea_level_mude" / f"Dataset_{case}.txt"
    y = np.loadtxt(io.StringIO(source.read_text(encoding="utf-8")))
    return np.arange(1.0, y.size + 1.0), y


def load_mauna_loa_co2() -> tuple[np.ndarray, np.ndarray]:
    """The weekly Mauna Loa CO2 record 1958-2001 shipped with the course.

    Returns
    -------
    date : ndarray of datetime64[D], shape (2225,)
        The date of each week (a Saturday), weeks without data left out.
    co2 : ndarray, shape (2225,)
        The week's mean CO2 concentration in ppm (1999 calibration scale).

    Notes
    -----
    Data: the Scripps CO2 program's continuous measurements at Mauna Loa, as published by
    C. D. Keeling and T. P. Whorf (2004), *Trends: A Compendium of Data on Global Change*,
    CDIAC; public domain (see ``course/data/mauna_loa_co2/README.md``). Of the 2284 weeks
    from 1958-03-29 to 2001-12-29, the 59 without a measurement are left out.

    Examples
    --------
    >>> date, co2 = load_mauna_loa_co2()
    >>> str(date[0]), float(co2[0]), date.size
    ('1958-03-29', 316.1, 2225)
    """
    source = resources.files("course") / "data" / "mauna_loa_co2" / "co2_weekly.csv"
    lines = source.read_text(encoding="utf-8").splitlines()[1:]  # below the header date,co2
    rows = [line.split(",") for line in lines if line.strip()]
    measured = [(day, ppm) for day, ppm in rows if ppm.strip()]
    date = np.array([f"{d[:4]}-{d[4:6]}-{d[6:8]}" for d, _ in measured], dtype="datetime64[D]")
    return date, np.array([float(ppm) for _, ppm in measured])
