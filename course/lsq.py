"""Least-squares residuals and the tests built on them.

This module follows Chapter 10 "Validation" of Tiberius, van der Marel,
Reudink and van Leijen (2021), *Surveying and Mapping*, TU Delft Open
Textbook (full reference in the course bibliography, docs/bibliography.md):
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
Everything is computed in the *whitened* problem. With the Cholesky factor
``Qyy = L L^T`` the model becomes ``L^{-1} y = (L^{-1} A) x + ε`` with
``D(ε) = I``; a full QR factorisation ``L^{-1} A = [Q1 Q2] [R; 0]`` then gives
the estimate ``x̂ = R^{-1} Q1^T L^{-1} y`` by a triangular solve, the
covariance of the estimate ``Qxx = R^{-1} R^{-T}``, the residual covariance
``Qee = (L Q2)(L Q2)^T`` and the w-test quantities, without ever forming
``(A^T Qyy^{-1} A)^{-1}`` or ``Qyy^{-1}``.
"""

from __future__ import annotations

import html
import io
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any, NamedTuple

import numpy as np
from scipy import linalg as sla
from scipy import stats

from course.chi2 import noncentrality, residual_norm_law
from course.linalg import (
    check_full_column_rank,
    cholesky_lower,
    qr_solve,
    readonly,
    symmetrize,
    whiten,
)
from course.results import TestResult, decide, format_number
from course.validation import (
    as_count,
    as_covariance,
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
@dataclass(frozen=True)
class _Factors:
    """Factorisations kept with a fit so that the tests need no refactoring."""

    L: np.ndarray  # lower Cholesky factor of Qyy
    Q: np.ndarray  # full orthogonal factor of L^{-1} A, m x m
    R: np.ndarray  # upper triangular factor, n x n
    z: np.ndarray  # Q2^T L^{-1} y: the m - n independent N(0, 1) "residual coordinates"


@dataclass(frozen=True, repr=False, eq=False)
class LeastSquaresFit:
    """Result of a (weighted) least-squares fit of ``E(y) = A x``, ``D(y) = Qyy``.

    Build it with :func:`fit`; all arrays are read-only.

    Attributes
    ----------
    A : ndarray, shape (m, n)
        Design matrix.
    y : ndarray, shape (m,)
        Observations.
    Qyy : ndarray, shape (m, m)
        Covariance matrix of the observations.
    x_hat : ndarray, shape (n,)
        BLUE of the parameters, eq. (8.6).
    y_hat : ndarray, shape (m,)
        Adjusted observations ``A x̂``.
    e_hat : ndarray, shape (m,)
        Least-squares residuals ``y - ŷ``, eq. (10.1).
    Qxx : ndarray, shape (n, n)
        Covariance of ``x̂``, ``(A^T Qyy^{-1} A)^{-1}``, eq. (8.7).
    Qyy_hat : ndarray, shape (m, m)
        Covariance of ``ŷ``, ``A Qxx A^T``.
    Qee : ndarray, shape (m, m)
        Covariance of ``ê``, ``Qyy - A Qxx A^T`` (Section 10.3).
    redundancy_numbers : ndarray, shape (m,)
        ``diag(Qee Qyy^{-1})``; each in [0, 1] for diagonal Qyy, summing to m - n.
    m, n : int
        Number of observations and of parameters.
    """

    A: np.ndarray
    y: np.ndarray
    Qyy: np.ndarray
    x_hat: np.ndarray
    y_hat: np.ndarray
    e_hat: np.ndarray
    Qxx: np.ndarray
    Qyy_hat: np.ndarray
    Qee: np.ndarray
    redundancy_numbers: np.ndarray
    m: int
    n: int
    _factors: _Factors = field(repr=False)

    @property
    def redundancy(self) -> int:
        """Degrees of freedom left for the residuals, ``m - n``."""
        return self.m - self.n

    @property
    def squared_norm(self) -> float:
        """Weighted squared norm of the residuals, ``ê^T Qyy^{-1} ê`` (eq. 10.2)."""
        z = self._factors.z
        return float(z @ z)

    @property
    def sigma_x_hat(self) -> np.ndarray:
        """Standard deviations of the estimated parameters, ``sqrt(diag(Qxx))``."""
        return np.sqrt(np.diag(self.Qxx))

    @property
    def sigma_y_hat(self) -> np.ndarray:
        """Standard deviations of the adjusted observations, ``sqrt(diag(Qyy_hat))``."""
        return np.sqrt(np.clip(np.diag(self.Qyy_hat), 0.0, None))

    @property
    def sigma_e_hat(self) -> np.ndarray:
        """Standard deviations of the residuals, ``sqrt(diag(Qee))``."""
        return np.sqrt(np.clip(np.diag(self.Qee), 0.0, None))

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
    Qyy : array_like, shape (m, m), optional
        Symmetric positive definite covariance matrix of ``y``; the identity
        when omitted (unit-weight, uncorrelated observations).

    Returns
    -------
    LeastSquaresFit
        Estimates, residuals, covariances and redundancy numbers.

    Raises
    ------
    ValueError
        Shape mismatch, NaN or inf, ``m < n``, non-symmetric ``Qyy``.
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
    the QR factorisation ``L^{-1} A = [Q1 Q2][R; 0]``,
    ``x̂ = R^{-1} Q1^T L^{-1} y``, ``Q_x̂x̂ = R^{-1} R^{-T}``,
    ``Q_ŷŷ = (L Q1)(L Q1)^T`` and ``Q_êê = (L Q2)(L Q2)^T``. The redundancy
    numbers ``r_i = (Q_êê Q_yy^{-1})_{ii}`` are row-wise products of
    ``L Q2`` and ``L^{-T} Q2``; they sum to ``m - n``.

    Examples
    --------
    >>> import numpy as np
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> f = fit(A, [14, 20, 20, 24])
    >>> [float(v) for v in np.round(f.x_hat, 10)], round(f.squared_norm, 10)
    ([12.0, 3.0], 6.0)
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
    check_full_column_rank(A, "A")
    if Qyy is None:
        Qyy = np.eye(m)
    else:
        if np.ndim(Qyy) == 1:
            raise ValueError(
                f"Qyy must be an (m, m) = ({m}, {m}) covariance matrix, got a 1-D array; "
                "for uncorrelated observations with variances v pass np.diag(v)"
            )
        if np.ndim(Qyy) == 0:
            raise ValueError(
                f"Qyy must be an (m, m) = ({m}, {m}) covariance matrix, got a scalar; "
                f"for equal variances s2 pass s2 * np.eye({m})"
            )
        Qyy = as_covariance(Qyy, "Qyy", m)
    L = cholesky_lower(Qyy, "Qyy")

    A_w = whiten(L, A)
    y_w = whiten(L, y)
    solution = qr_solve(A_w, y_w, full=True)
    Q, R, x_hat = solution.Q, solution.R, solution.x
    Q1, Q2 = Q[:, :n], Q[:, n:]
    Qxx = symmetrize(solution.R_inv @ solution.R_inv.T)

    y_hat = A @ x_hat
    e_hat = y - y_hat
    LQ1 = L @ Q1
    LQ2 = L @ Q2
    Qyy_hat = symmetrize(LQ1 @ LQ1.T)
    Qee = symmetrize(LQ2 @ LQ2.T)
    # diag(Qee Qyy^{-1}) = rowwise (L Q2) . (L^{-T} Q2): one triangular solve.
    LtQ2 = sla.solve_triangular(L, Q2, trans="T", lower=True, check_finite=False)
    redundancy_numbers = np.sum(LQ2 * LtQ2, axis=1)
    z = Q2.T @ y_w

    factors = _Factors(L=_readonly(L), Q=_readonly(Q), R=_readonly(R), z=_readonly(z))
    return LeastSquaresFit(
        A=_readonly(A),
        y=_readonly(y),
        Qyy=_readonly(np.array(Qyy, dtype=float)),
        x_hat=_readonly(x_hat),
        y_hat=_readonly(y_hat),
        e_hat=_readonly(e_hat),
        Qxx=_readonly(Qxx),
        Qyy_hat=_readonly(Qyy_hat),
        Qee=_readonly(Qee),
        redundancy_numbers=_readonly(redundancy_numbers),
        m=int(m),
        n=int(n),
        _factors=factors,
    )


def _check_fit(value) -> LeastSquaresFit:
    if not isinstance(value, LeastSquaresFit):
        raise TypeError(
            f"expected a LeastSquaresFit (the result of course.lsq.fit), got {type(value).__name__}"
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
    evaluated as ``||Q2^T L^{-1} y||²``, the same number without ``Qyy^{-1}``.

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
    return TestResult.from_null(
        "overall model test",
        T,
        residual_norm_law(dof),
        alpha,
        dof=dof,
        details={"variance factor T/(m-n)": T / dof},
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
        m = self.w.shape[0]
        if not -m <= int(i) < m:
            raise IndexError(f"observation index {i} out of range for m = {m}")
        i = int(i) % m
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
    f = fit._factors
    # M = L^{-T} Q; row i of M is c_i^T L^{-T} Q, whose squared norm is (Qyy^{-1})_ii.
    M = sla.solve_triangular(f.L, f.Q, trans="T", lower=True, check_finite=False)
    M2 = M[:, fit.n :]
    numerator = M2 @ f.z  # c_i^T Qyy^{-1} ê
    denom2 = np.sum(M2 * M2, axis=1)  # c_i^T Qyy^{-1} Qee Qyy^{-1} c_i
    weight = np.sum(M * M, axis=1)  # c_i^T Qyy^{-1} c_i
    testable = denom2 > _UNTESTABLE_RTOL * weight
    return numerator, denom2, testable


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
    is two-sided, ``N_{α/2}(0, 1)`` (Section 10.3). With ``Qyy = L L^T`` and
    ``L^{-1} A = [Q1 Q2][R; 0]``: ``Q_yy^{-1} ê = L^{-T} Q2 z`` and
    ``Q_yy^{-1} Q_êê Q_yy^{-1} = (L^{-T} Q2)(L^{-T} Q2)^T`` with
    ``z = Q2^T L^{-1} y``, so both come from one triangular solve.
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
    numerator, denom2, testable = _w_quantities(fit)
    w = np.full(fit.m, np.nan)
    w[testable] = numerator[testable] / np.sqrt(denom2[testable])
    null = _standard_normal()
    decision = decide(null, w[testable], alpha, "two-sided")
    critical = decision.critical_value.upper
    pvalues = np.full(fit.m, np.nan)
    pvalues[testable] = decision.pvalue
    reject = np.zeros(fit.m, dtype=bool)
    reject[testable] = decision.reject
    abs_w = np.abs(w)
    largest = int(np.nanargmax(abs_w)) if np.any(testable) else 0
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
    current = fit(A, y, Qyy)
    A_all, y_all, Q_all = current.A, current.y, current.Qyy
    kept = list(range(current.m))
    removed: list[int] = []
    rounds: list[WTestResult] = []
    round_indices: list[tuple] = []
    while True:
        if current.redundancy == 0:
            reason = "no redundancy left"
            break
        wt = w_tests(current, alpha)
        rounds.append(wt)
        round_indices.append(tuple(kept))
        if not wt.any_reject:
            reason = "no observation rejected"
            break
        if max_removals is not None and len(removed) >= max_removals:
            reason = "max_removals reached"
            break
        worst = kept.pop(wt.largest)
        removed.append(worst)
        index = np.array(kept)
        current = fit(A_all[index], y_all[index], Q_all[np.ix_(index, index)])
    return SnoopingResult(
        removed=tuple(removed),
        kept=tuple(kept),
        rounds=tuple(rounds),
        round_indices=tuple(round_indices),
        fit=current,
        stop_reason=reason,
        alpha=alpha,
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
    G = sla.solve_triangular(fit._factors.R, A_new.T, trans="T", lower=False, check_finite=False)
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
