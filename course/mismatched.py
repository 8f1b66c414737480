"""Validating a model with the residuals of a mismatched Kalman filter over many records.

The filter is often deliberately simpler than the model it is meant to
validate (fewer states, other noise levels).  Its residuals are then
correlated, non-zero mean and non-stationary *even when the model is right*,
so whiteness and chi-square tests do not apply.  Y. Baram (1980), "Model
validation using mismatched filters" (full reference in the course
bibliography, :doc:`/docs/bibliography`), uses many independent data records
instead: at a fixed time ``j`` the residuals of different records (a
*cross-record section*) are independent and identically distributed, and the
mean, covariance and correlation statistics of a section are quadratic forms
in normal variables whose laws Imhof's method computes
(:mod:`course.quadform`).

Notation: ``M^0`` is the model under test (``true_model`` when it holds),
``M^1`` the model inside the filter (``filter_model``), ``M^2`` an
alternative for the power.  Times are ``t = 0, ..., N-1`` as in
:mod:`course.filters` (the paper's ``j = 1, ..., N``).

Public API
----------
residual_moments(true_model, filter_model, N) -> ResidualMoments
    Means ``m_t``, covariances ``P_t`` and cross-covariances ``C(j, k)`` of the
    residuals, by the augmented-system recursion of the paper's appendix with
    its misprints corrected (see :data:`APPENDIX_MISPRINTS`).
residual_moments_as_printed(true_model, filter_model, N, misprint)
    The same recursion with one misprint of the appendix put back, to
    measure its effect against Monte Carlo (teaching only).
simulate_records(true_model, filter_model, M, N, rng) -> (M, N, p)
    Residuals of the filter on M independent records of the true model.
moment_zscores(residuals, moments)
    Standardised differences between sample and predicted moments (the
    Monte Carlo check of a moment computation).
principal_directions, mean_statistic, covariance_statistic, correlation_statistic
    The statistics of a cross-record section (Baram (2.5)-(2.17), corrected).
mean_matrix, covariance_matrix, correlation_matrix, section_moments, pair_moments
    The same statistics as quadratic forms ``phi^T A phi`` (Baram section 3).
statistic_law
    The law of a statistic under a model pair (exact, via Imhof's method).
mean_test, covariance_test, correlation_test, power
    Tests with critical regions from the law under ``(M^0, M^1)`` and power
    against ``(M^2, M^1)``; each test returns a :class:`~course.results.TestResult`.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from course.filters import LinearModel, kalman_filter, riccati_gains
from course.linalg import readonly, symmetrize
from course.quadform import QuadraticForm, WeightedChiSquare
from course.results import TestResult, critical_value, rejection_probability
from course.validation import (
    InputTypeError,
    as_count,
    as_flag,
    as_float_array,
    as_index,
    as_probability,
)

__all__ = [
    "APPENDIX_MISPRINTS",
    "EigenDirections",
    "MomentZScores",
    "ResidualMoments",
    "SectionMoments",
    "SingularDirections",
    "correlation_matrix",
    "correlation_statistic",
    "correlation_test",
    "covariance_matrix",
    "covariance_statistic",
    "covariance_test",
    "mean_matrix",
    "mean_statistic",
    "mean_test",
    "moment_zscores",
    "pair_moments",
    "power",
    "principal_directions",
    "residual_moments",
    "residual_moments_as_printed",
    "section_moments",
    "simulate_records",
    "statistic_law",
]

#: The misprints of Baram's appendix that :func:`residual_moments_as_printed`
#: can put back: name -> (equation, as printed, as corrected). (A15), printed
#: "[H_j^0 - H_j^1]", is not among them: in the paper's block notation (blocks
#: separated by spaces, as in (A14)) it reads [H^0, -H^1], which is right.
APPENDIX_MISPRINTS = {
    "gain_of_tested_model": (
        "(A17)-(A18)",
        "K^0 from a Riccati recursion of M^0 (mixing H^0 and H^1)",
        "K^1 from the Riccati recursion of the filter's own model M^1",
    ),
    "Q1_block": (
        "(A14), (A20)",
        "a random w^1 with covariance Q^1 drives the estimate",
        "the estimate is driven by the mean of w^1 only: no Q^1 block",
    ),
    "initial_estimate_random": (
        "(A26)",
        "Psi~_0 with the filter's prior covariance in the estimate block",
        "Psi~_0 = blockdiag(Psi^0_0, 0): xhat(0|-1) is a known vector",
    ),
    "mean_without_noise_mean": (
        "(A23)",
        "m_j = H~ E[x~_j] (no measurement-noise mean)",
        "m_j = H~ E[x~_j] + m_v^0 - m_v^1",
    ),
    "cross_covariance_without_v": (
        "(A27)",
        "C(k, j) = H~ Theta(k, j) Psi~_j H~^T for j < k",
        "plus H~ Theta(k, j+1) [0; F^1 K_j R^0]: v_j enters xhat through the gain",
    ),
    "C_is_P_k": (
        "(2.4)",
        "C(j, k) = E{(r_k - m_k)(r_k - m_k)^T} (= P_k)",
        "C(j, k) = E{(r_j - m_j)(r_k - m_k)^T}",
    ),
}


# ---------------------------------------------------------------------------
# moments of the residuals
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class ResidualMoments:
    """First and second moments of mismatched-filter residuals.

    Attributes
    ----------
    mean : (N, p) ndarray
        ``m_t = E r_t``.
    cov : (N, p, p) ndarray
        ``P_t = E (r_t - m_t)(r_t - m_t)^T``.
    cross_cov : (N, N, p, p) ndarray
        ``cross_cov[j, k] = C(j, k) = E (r_j - m_j)(r_k - m_k)^T``;
        ``cross_cov[j, j] = P_j`` and ``cross_cov[k, j] = C(j, k)^T``.

    Raises
    ------
    ValueError
        Shapes that do not agree, NaN or inf (when built by hand).

    Notes
    -----
    Normally built by :func:`residual_moments` (Baram 1980, appendix,
    corrected); the arrays are read-only copies.
    """

    mean: np.ndarray
    cov: np.ndarray
    cross_cov: np.ndarray

    def __post_init__(self):
        # Built by hand too (e.g. from stored moments): check the shapes agree;
        # as_float_array copies, so the read-only arrays never alias the caller's.
        mean = as_float_array(self.mean, "mean")
        if mean.ndim != 2:
            raise ValueError(f"mean must have shape (N, p), got {mean.shape}")
        N, p = mean.shape
        cov = as_float_array(self.cov, "cov")
        if cov.shape != (N, p, p):
            raise ValueError(
                f"cov must have shape (N, p, p) = {(N, p, p)} to match mean, got {cov.shape}"
            )
        cross = as_float_array(self.cross_cov, "cross_cov")
        if cross.shape != (N, N, p, p):
            raise ValueError(
                f"cross_cov must have shape (N, N, p, p) = {(N, N, p, p)} to match mean, got {cross.shape}"
            )
        for name, value in (("mean", mean), ("cov", cov), ("cross_cov", cross)):
            object.__setattr__(self, name, _readonly(value))

    @property
    def n_steps(self) -> int:
        return self.mean.shape[0]

    @property
    def n_outputs(self) -> int:
        return self.mean.shape[1]

    def C(self, j: int, k: int) -> np.ndarray:
        """``C(j, k) = E (r_j - m_j)(r_k - m_k)^T``."""
        return self.cross_cov[_index(j, self.n_steps, "j"), _index(k, self.n_steps, "k")]

    def stacked_cov(self) -> np.ndarray:
        """Covariance of ``(r_0, ..., r_{N-1})`` stacked, ``(N p, N p)``."""
        N, p = self.mean.shape
        return self.cross_cov.transpose(0, 2, 1, 3).reshape(N * p, N * p)

    def __repr__(self) -> str:
        return f"ResidualMoments(n_steps={self.n_steps}, n_outputs={self.n_outputs})"


def _check_models(true_model, filter_model):
    for name, model in (("true_model", true_model), ("filter_model", filter_model)):
        if not isinstance(model, LinearModel):
            raise InputTypeError(
                f"{name} must be a course.filters.LinearModel, got {type(model).__name__}"
            )
        if model.n_inputs:
            raise ValueError(
                f"{name} has an input (B); the mismatched-filter analysis here has none: "
                "fold a known constant input into w_mean"
            )
    if true_model.n_outputs != filter_model.n_outputs:
        raise ValueError(
            f"true_model and filter_model must have the same number of outputs: the true "
            f"model has {true_model.n_outputs}, the filter's {filter_model.n_outputs}"
        )


def _check_moments(moments: Any, name: str = "moments") -> ResidualMoments:
    if not isinstance(moments, ResidualMoments):
        raise InputTypeError(
            f"{name} must be the ResidualMoments of a pair of models (from residual_moments), "
            f"got {type(moments).__name__}"
        )
    return moments


def _outputs(p: Any) -> int:
    return as_count(p, "p", what="the number of outputs")


def _check_steps(N: Any) -> int:
    return as_count(N, "N", what="the number of samples per record")


def residual_moments(true_model, filter_model, N) -> ResidualMoments:
    """Moments of the residuals of ``filter_model``'s Kalman filter on data of ``true_model``.

    Parameters
    ----------
    true_model : course.filters.LinearModel
        ``M^0`` (or ``M^2``), the model that generates the data.
    filter_model : course.filters.LinearModel
        ``M^1``, the model inside the filter (it may have fewer states).
    N : int
        Number of samples per record.

    Returns
    -------
    ResidualMoments
        ``mean (N, p)``, ``cov (N, p, p)``, ``cross_cov (N, N, p, p)``.

    Notes
    -----
    The residual ``r_t = y_t - H^1 xhat(t|t-1) - m_v^1`` of the filter of
    :func:`course.filters.kalman_filter` is the output of the augmented system
    (Baram 1980, appendix, (A9)-(A15), corrected)::

        x~_t = [x_t; xhat(t|t-1)],   x~_{t+1} = F~_t x~_t + G~_t [w_t; v_t] + u~_t,
        F~_t = [[F^0, 0], [F^1 K_t H^0, F^1 (I - K_t H^1)]],     (A13)
        G~_t = [[G^0, 0], [0, F^1 K_t]],                         (A14), no G^1 w^1 block
        u~_t = [G^0 m_w^0; F^1 K_t (m_v^0 - m_v^1) + G^1 m_w^1],
        r_t  = H~ x~_t + v_t - m_v^1,  H~ = [H^0, -H^1],        (A15)

    with ``K_t`` the filter's own gains (Riccati recursion of ``M^1``,
    (A17)-(A18) corrected), ``E x~_0 = [m^0_0; m^1_0]`` (A21) and
    ``Psi~_0 = blockdiag(Psi^0_0, 0)`` (A26).  Then

    - ``E x~_{t+1} = F~_t E x~_t + u~_t``; ``m_t = H~ E x~_t + m_v^0 - m_v^1`` (A23);
    - ``Psi~_{t+1} = F~_t Psi~_t F~_t^T + G~_t Q~ G~_t^T``,
      ``Q~ = blockdiag(Q^0, R^0)`` (A20), (A25);
    - ``P_t = H~ Psi~_t H~^T + R^0`` (A28);
    - for ``j < k``: ``C(k, j) = H~ Z_{k,j}`` with ``Z_{j+1,j} = F~_j Psi~_j H~^T
      + [0; F^1 K_j R^0]`` and ``Z_{t+1,j} = F~_t Z_{t,j}`` (A27 corrected: the
      transition from j to k, and ``v_j`` enters the estimate through the gain).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> moments = residual_moments(true, filt, 5)
    >>> moments.mean.shape, moments.cov.shape, moments.cross_cov.shape
    ((5, 1), (5, 1, 1), (5, 5, 1, 1))
    """
    return _moments(true_model, filter_model, N, misprint=None)


def residual_moments_as_printed(true_model, filter_model, N, misprint) -> ResidualMoments:
    """:func:`residual_moments` with one misprint of Baram's appendix put back.

    For teaching: comparing these moments with Monte Carlo shows that the
    printed formula is wrong and the corrected one right.

    Parameters
    ----------
    misprint : str
        A key of :data:`APPENDIX_MISPRINTS`.

    Returns
    -------
    ResidualMoments
        The moments the printed formula would give.

    Raises
    ------
    ValueError
        Unknown misprint, or ``"gain_of_tested_model"`` with models of
        different state dimensions (the printed gain is then not even
        conformable with ``F^1``).

    Notes
    -----
    :data:`APPENDIX_MISPRINTS` lists each printed formula (Baram 1980,
    appendix and (2.4)) next to its correction.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> printed = residual_moments_as_printed(true, filt, 5, "Q1_block")
    >>> bool(printed.cov[-1, 0, 0] != residual_moments(true, filt, 5).cov[-1, 0, 0])
    True
    """
    if misprint not in APPENDIX_MISPRINTS:
        raise ValueError(f"misprint must be one of {sorted(APPENDIX_MISPRINTS)}, got {misprint!r}")
    return _moments(true_model, filter_model, N, misprint=misprint)


def _moments(m0, m1, N, misprint):
    _check_models(m0, m1)
    N = _check_steps(N)
    n0, n1, p = m0.n_states, m1.n_states, m0.n_outputs
    if misprint == "gain_of_tested_model":
        if n0 != n1:
            raise ValueError(
                "the printed gain K^0 (from M^0) is n0 x p and cannot multiply F^1 (n1 x n1) "
                f"when the filter has fewer states ({n1} vs {n0}): the printed formula has no meaning here"
            )
        K = riccati_gains(m0, N)
    else:
        K = riccati_gains(m1, N)
    na = n0 + n1
    Ht = np.hstack([m0.H, -m1.H])
    x_mean = np.concatenate([m0.x0_mean, m1.x0_mean])
    Psi = np.zeros((na, na))
    Psi[:n0, :n0] = m0.x0_cov
    if misprint == "initial_estimate_random":
        Psi[n0:, n0:] = m1.x0_cov
    dv = m0.v_mean - m1.v_mean
    R0 = m0.R
    mean = np.empty((N, p))
    cov = np.empty((N, p, p))
    cross = np.empty((N, N, p, p))
    F_all = np.empty((N, na, na))
    Z_first = np.empty((N, na, p))  # Cov(x~_{j+1}, r_j)
    for t in range(N):
        mean[t] = Ht @ x_mean + (dv if misprint != "mean_without_noise_mean" else 0.0)
        cov[t] = symmetrize(Ht @ Psi @ Ht.T + R0)
        FK = m1.F @ K[t]
        Ft = np.zeros((na, na))
        Ft[:n0, :n0] = m0.F
        Ft[n0:, :n0] = FK @ m0.H
        Ft[n0:, n0:] = m1.F - FK @ m1.H
        F_all[t] = Ft
        Z = Ft @ Psi @ Ht.T
        if misprint != "cross_covariance_without_v":
            Z[n0:] += FK @ R0
        Z_first[t] = Z
        # noise: [w^0; v^0] through G~ = [[G^0, 0], [0, F^1 K]]
        noise = np.zeros((na, na))
        noise[:n0, :n0] = m0.GQG
        noise[n0:, n0:] = FK @ R0 @ FK.T
        if misprint == "Q1_block":
            noise[n0:, n0:] += m1.GQG
        x_mean = Ft @ x_mean + np.concatenate([m0.G @ m0.w_mean, FK @ dv + m1.G @ m1.w_mean])
        Psi = symmetrize(Ft @ Psi @ Ft.T + noise)
    for j in range(N):
        cross[j, j] = cov[j]
        Z = Z_first[j]
        for k in range(j + 1, N):
            Ckj = Ht @ Z  # C(k, j) = E (r_k - m_k)(r_j - m_j)^T
            cross[k, j] = Ckj
            cross[j, k] = Ckj.T
            Z = F_all[k] @ Z
    if misprint == "C_is_P_k":
        for j in range(N):
            for k in range(N):
                cross[j, k] = cov[k]
    return ResidualMoments(_readonly(mean), _readonly(cov), _readonly(cross))


def simulate_records(true_model, filter_model, M, N, rng) -> np.ndarray:
    """Residuals of ``filter_model``'s Kalman filter on M records of ``true_model``.

    Parameters
    ----------
    true_model, filter_model : course.filters.LinearModel
    M : int
        Number of independent records (experiments).
    N : int
        Samples per record.
    rng : numpy.random.Generator

    Returns
    -------
    ndarray, shape (M, N, p)
        ``residuals[i, t]`` is ``r_{i,t}`` of the paper (record i, time t).

    Notes
    -----
    The records are independent runs of ``true_model`` (Baram 1980,
    section 1: independent noise sequences across experiments), filtered
    by :func:`course.filters.kalman_filter` with ``filter_model``; the
    residual is that filter's innovation, (2.1).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> import numpy as np
    >>> simulate_records(true, filt, 200, 5, np.random.default_rng(0)).shape
    (200, 5, 1)
    """
    _check_models(true_model, filter_model)
    N = _check_steps(N)
    M = as_count(M, "M", what="the number of records")
    _, y = true_model.simulate(N, rng, batch=M)
    return np.array(kalman_filter(filter_model, y).eps)


class MomentZScores(NamedTuple):
    """Result of :func:`moment_zscores` (unpacks as ``z_mean, z_cov``)."""

    z_mean: np.ndarray
    """``(N, p)`` standardised errors of the sample means."""
    z_cov: np.ndarray
    """``(N, N, p, p)`` standardised errors of the sample cross-covariances."""


class EigenDirections(NamedTuple):
    """Principal directions of ``P_j`` (unpacks as ``values, vectors``)."""

    values: np.ndarray
    """Eigenvalues in decreasing order."""
    vectors: np.ndarray
    """Eigenvectors as the *columns*, in the same order."""


class SingularDirections(NamedTuple):
    """Principal directions of ``C(j, k) = U diag(s) W^T`` (unpacks as ``s, U, W``)."""

    values: np.ndarray
    """Singular values in decreasing order."""
    left: np.ndarray
    """``U``: its columns project ``r_j``."""
    right: np.ndarray
    """``W``: its columns project ``r_k``."""


class SectionMoments(NamedTuple):
    """Mean and covariance of a stacked section (unpacks as ``mean, cov``)."""

    mean: np.ndarray
    cov: np.ndarray


def moment_zscores(residuals: Any, moments: ResidualMoments) -> MomentZScores:
    """Standardised differences between sample moments and ``moments``.

    Parameters
    ----------
    residuals : (M, N, p) array_like
        Residuals of many independent records.
    moments : ResidualMoments
        Predicted moments.

    Returns
    -------
    MomentZScores
        ``z_mean`` ``(N, p)``: ``(rbar_t - m_t) / sqrt(P_t,aa / M)``;
        ``z_cov`` ``(N, N, p, p)``:
        ``(S(j, k)_ab - C(j, k)_ab) / se`` with the unbiased sample
        cross-covariance ``S`` (divisor ``M - 1``) and the normal-theory
        standard error ``se^2 = (P_j,aa P_k,bb + C(j, k)_ab^2) / M``.

    Notes
    -----
    If the moments are right, every entry is approximately ``N(0, 1)``;
    a wrong formula shows up as entries of tens or hundreds.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> import numpy as np
    >>> r = simulate_records(true, filt, 4000, 5, np.random.default_rng(0))
    >>> z = moment_zscores(r, residual_moments(true, filt, 5))
    >>> bool(np.abs(z.z_mean).max() < 5 and np.abs(z.z_cov).max() < 5)
    True
    """
    moments = _check_moments(moments)
    r = _as_records(residuals)
    M = r.shape[0]
    if r.shape[1:] != moments.mean.shape:
        raise ValueError(
            f"residuals have (N, p) = {r.shape[1:]} but the moments are for {moments.mean.shape}"
        )
    rbar = r.mean(axis=0)
    variances = np.diagonal(moments.cov, axis1=1, axis2=2)
    z_mean = (rbar - moments.mean) / np.sqrt(variances / M)
    dev = r - rbar
    sample = np.einsum("ija,ikb->jkab", dev, dev) / (M - 1)
    se = np.sqrt(
        (variances[:, None, :, None] * variances[None, :, None, :] + moments.cross_cov**2) / M
    )
    return MomentZScores(z_mean, (sample - moments.cross_cov) / se)


# ---------------------------------------------------------------------------
# statistics of a cross-record section
# ---------------------------------------------------------------------------
def _as_records(residuals) -> np.ndarray:
    r = as_float_array(residuals, "residuals", empty=False)
    if r.ndim == 2:
        r = r[..., None]
    if r.ndim != 3:
        raise ValueError(
            f"residuals must have shape (M, N, p) (records, times, outputs) or (M, N), got {r.shape}"
        )
    if r.shape[0] < 2:
        raise ValueError(
            f"residuals holds {r.shape[0]} record(s): cross-record statistics need at least "
            "two records"
        )
    return r


def _index(j: Any, N: int, name: str) -> int:
    return as_index(j, name, N, what="a time index")


def _unit(v, p, name) -> np.ndarray:
    v = as_float_array(v, name)
    if v.shape != (p,):
        raise ValueError(f"{name} must be a vector of length p = {p}, got shape {v.shape}")
    norm = np.linalg.norm(v)
    if not np.isclose(norm, 1.0, rtol=1e-8):
        raise ValueError(f"{name} must be a unit vector (norm 1), got norm {norm:.6g}")
    return v


def principal_directions(moments: ResidualMoments, j: int, k: int | None = None):
    """Principal directions of ``P_j`` or of ``C(j, k)`` under the null pair.

    Parameters
    ----------
    moments : ResidualMoments
        Moments under the null pair ``(M^0, M^1)``.
    j : int
        Section (time index).
    k : int, optional
        Second section: directions of ``C(j, k)`` instead of ``P_j``.

    Returns
    -------
    EigenDirections or SingularDirections
        For ``k is None``: :class:`EigenDirections` ``(values, vectors)``,
        the eigenvalues of ``P_j`` in decreasing order and the eigenvectors
        as the *columns* of ``vectors``.  Otherwise
        :class:`SingularDirections` ``(values, left, right)``, the singular
        value decomposition ``C(j, k) = U diag(s) W^T``: ``left[:, g]``
        projects ``r_j`` and ``right[:, g]`` projects ``r_k``.  Both unpack
        like the tuples of earlier releases, ``lam, V`` and ``s, U, W``.

    Notes
    -----
    Baram (1980), (2.7) and (2.13)-(2.15), corrected: a residual is
    projected on a principal direction by ``v_g^T r = (V^T r)_g`` (the paper
    prints ``a^(g) V_j r``, a row of ``V_j``); and ``C(j, k)`` is not
    symmetric, so its left and right principal directions differ and come
    from an SVD, with ``E c^(g)(j, k) = (M - 1)/M s_g``.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> values, vectors = principal_directions(residual_moments(true, filt, 5), 2)
    >>> vectors.shape
    (1, 1)
    """
    N = _check_moments(moments).n_steps
    j = _index(j, N, "j")
    if k is None:
        lam, V = np.linalg.eigh(moments.cov[j])
        return EigenDirections(lam[::-1], V[:, ::-1])
    k = _index(k, N, "k")
    U, s, Wt = np.linalg.svd(moments.C(j, k))
    return SingularDirections(s, U, Wt.T)


def mean_statistic(residuals, j: int) -> float:
    """Mean statistic of section ``j``: the squared norm of the cross-record mean.

    Parameters
    ----------
    residuals : (M, N, p) or (M, N) array_like
        Residuals of ``M >= 2`` records.
    j : int
        Section (time index).

    Returns
    -------
    float
        ``||rbar_j||^2 = rbar_j^T rbar_j`` with ``rbar_j = (1/M) sum_i r_ij``.

    Notes
    -----
    Baram (1980), (2.5)-(2.6): the paper writes ``||rbar_j|| = rbar_j^T
    rbar_j``; the statistic is the *squared* norm, the quadratic form
    ``phi_j^T A phi_j`` of (3.2)-(3.3) (see :func:`mean_matrix`).

    Examples
    --------
    >>> mean_statistic([[1.0, 2.0], [3.0, 0.0]], 0)   # two records, mean 2 at time 0
    4.0
    """
    r = _as_records(residuals)
    j = _index(j, r.shape[1], "j")
    rbar = r[:, j].mean(axis=0)
    return float(rbar @ rbar)


def covariance_statistic(residuals, j: int, direction=None) -> float:
    """Sample covariance statistic of section ``j``.

    Parameters
    ----------
    residuals : (M, N, p) or (M, N) array_like
        Residuals of ``M >= 2`` records.
    j : int
        Section (time index).
    direction : (p,) array_like, optional
        A unit vector ``v`` (normally a principal direction of the null
        ``P_j``, see :func:`principal_directions`).

    Returns
    -------
    float
        ``c_j = tr Pbar_j = (1/M) sum_i |r_ij - rbar_j|^2``, or with a
        direction ``c_j^(g) = (1/M) sum_i (v^T (r_ij - rbar_j))^2``.

    Notes
    -----
    Baram (1980), (2.16)-(2.17) and (2.13)-(2.14) corrected: the projected
    statistic averages the *squared* projections (averaging the projections
    themselves gives zero identically) and projects with ``V_j^T``.  With
    the divisor ``M`` and the sample mean removed,
    ``E c_j = (M - 1)/M tr P_j`` and ``E c_j^(g) = (M - 1)/M v^T P_j v``.

    Examples
    --------
    >>> covariance_statistic([[1.0, 2.0], [3.0, 0.0]], 0)   # ((1-2)^2 + (3-2)^2) / 2
    1.0
    """
    r = _as_records(residuals)
    j = _index(j, r.shape[1], "j")
    dev = r[:, j] - r[:, j].mean(axis=0)
    if direction is None:
        return float(np.mean(np.sum(dev * dev, axis=1)))
    v = _unit(direction, r.shape[2], "direction")
    return float(np.mean((dev @ v) ** 2))


def correlation_statistic(residuals, j: int, k: int, directions=None) -> float:
    """Sample correlation statistic of sections ``j`` and ``k``.

    Parameters
    ----------
    residuals : (M, N, p) or (M, N) array_like
        Residuals of ``M >= 2`` records.
    j, k : int
        The two sections (time indices).
    directions : pair of (p,) array_like, optional
        Unit vectors ``(u, w)``, normally the left and right singular
        vectors of the null ``C(j, k)`` (:func:`principal_directions`).

    Returns
    -------
    float
        ``c(j, k) = tr Cbar(j, k) = (1/M) sum_i (r_ij - rbar_j)^T (r_ik -
        rbar_k)``, or with directions ``c^(g)(j, k) = (1/M) sum_i (u^T (r_ij
        - rbar_j)) (w^T (r_ik - rbar_k))``.

    Notes
    -----
    Baram (1980), (2.12), and (2.7)-(2.9) with an SVD in place of the
    principal directions of the non-symmetric ``C(j, k)``;
    ``E c^(g)(j, k) = (M - 1)/M u^T C(j, k) w``.  With an SVD the projected
    statistics no longer add up to the trace as (2.11)-(2.12) state (that
    needs one orthonormal basis on both sides).

    Examples
    --------
    >>> correlation_statistic([[1.0, 2.0], [3.0, 0.0]], 0, 1)   # ((-1)(1) + (1)(-1)) / 2
    -1.0
    """
    r = _as_records(residuals)
    N, p = r.shape[1], r.shape[2]
    j, k = _index(j, N, "j"), _index(k, N, "k")
    dj = r[:, j] - r[:, j].mean(axis=0)
    dk = r[:, k] - r[:, k].mean(axis=0)
    if directions is None:
        return float(np.mean(np.sum(dj * dk, axis=1)))
    u, w = _pair(directions, p)
    return float(np.mean((dj @ u) * (dk @ w)))


def _pair(directions, p, name="directions"):
    if isinstance(directions, (str, bytes)):
        raise ValueError(f"{name} must be a pair (u, w) of unit vectors, got {directions!r}")
    try:
        u, w = directions
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (u, w) of unit vectors") from None
    return _unit(u, p, f"{name}[0] (u)"), _unit(w, p, f"{name}[1] (w)")


# ---------------------------------------------------------------------------
# the statistics as quadratic forms (Baram section 3)
# ---------------------------------------------------------------------------
def _centering(M) -> np.ndarray:
    return np.eye(M) - np.full((M, M), 1.0 / M)


def _check_M(M: Any) -> int:
    return as_count(M, "M", minimum=2, what="the number of records")


def mean_matrix(M: int, p: int) -> np.ndarray:
    """Matrix ``A`` of the mean statistic as a quadratic form, ``||rbar_j||^2 = phi_j^T A phi_j``.

    Parameters
    ----------
    M : int
        Number of records, ``M >= 2``.
    p : int
        Residual dimension.

    Returns
    -------
    ndarray, shape (M p, M p)
        ``A = (1/M^2) 1 1^T kron I_p``, for ``phi_j = (r_1j, ..., r_Mj)``.

    Notes
    -----
    Baram (1980), (3.1)-(3.3).  The paper writes ``I_n``; the blocks act on
    ``p``-dimensional residuals, so they are ``I_p``.

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.array([1.0, 3.0])                  # one time, two records, p = 1
    >>> float(phi @ mean_matrix(2, 1) @ phi)        # the squared norm of the mean, 2^2
    4.0
    """
    M = _check_M(M)
    return np.kron(np.full((M, M), 1.0 / M**2), np.eye(_outputs(p)))


def covariance_matrix(M: int, p: int, direction=None) -> np.ndarray:
    """Matrix ``G`` of the covariance statistic as a quadratic form, ``c_j = phi_j^T G phi_j``.

    Parameters
    ----------
    M : int
        Number of records, ``M >= 2``.
    p : int
        Residual dimension.
    direction : (p,) array_like, optional
        Unit vector ``v`` of the projected statistic.

    Returns
    -------
    ndarray, shape (M p, M p)
        ``G = (1/M) J kron I_p``, or ``D (J/M) D^T`` with ``D = I_M kron v``.

    Notes
    -----
    Baram (1980), (3.11)-(3.15); ``J = I_M - 1 1^T / M`` removes the sample
    mean (3.10), and needs ``kron I_p`` for vector residuals.

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.array([1.0, 3.0])
    >>> float(phi @ covariance_matrix(2, 1) @ phi)  # covariance_statistic of the same section
    1.0
    """
    M = _check_M(M)
    p = _outputs(p)
    J = _centering(M) / M
    if direction is None:
        return np.kron(J, np.eye(p))
    v = _unit(direction, p, "direction")[:, None]
    D = np.kron(np.eye(M), v)
    return D @ J @ D.T


def correlation_matrix(M: int, p: int, directions=None) -> np.ndarray:
    """Matrix ``B`` of the correlation statistic, ``c(j, k) = phi(j, k)^T B phi(j, k)``.

    Parameters
    ----------
    M : int
        Number of records, ``M >= 2``.
    p : int
        Residual dimension.
    directions : pair of (p,) array_like, optional
        Unit vectors ``(u, w)`` of the projected statistic.

    Returns
    -------
    ndarray, shape (2 M p, 2 M p)
        For ``phi(j, k) = (phi_j, phi_k)``:
        ``B = (1/2M) [[0, J kron I_p], [J kron I_p, 0]]``, or with directions
        ``D B_M D^T``, ``D = blockdiag(I_M kron u, I_M kron w)``.

    Notes
    -----
    Baram (1980), (3.4)-(3.10), with ``J kron I_p`` for vector residuals
    and, in (3.7)-(3.8), the left and right singular vectors of ``C(j, k)``
    in place of one set of principal directions.

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.array([1.0, 3.0, 2.0, 0.0])        # (section j, section k)
    >>> float(phi @ correlation_matrix(2, 1) @ phi)
    -1.0
    """
    M = _check_M(M)
    p = _outputs(p)
    J = _centering(M)
    zero = np.zeros((M, M))
    B_M = np.block([[zero, J], [J, zero]]) / (2 * M)
    if directions is None:
        return np.kron(B_M, np.eye(p))
    u, w = _pair(directions, p)
    D = np.zeros((2 * M * p, 2 * M))
    D[: M * p, :M] = np.kron(np.eye(M), u[:, None])
    D[M * p :, M:] = np.kron(np.eye(M), w[:, None])
    return D @ B_M @ D.T


def section_moments(moments: ResidualMoments, j: int, M: int):
    """Mean and covariance of the stacked section ``phi_j = (r_1j, ..., r_Mj)``.

    Parameters
    ----------
    moments : ResidualMoments
    j : int
        Section (time index).
    M : int
        Number of records.

    Returns
    -------
    SectionMoments
        ``mean`` ``(M p,)``: ``1 kron m_j``; ``cov`` ``(M p, M p)``:
        ``I_M kron P_j`` (records are independent).

    Notes
    -----
    Baram (1980), (3.18) and (3.20).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> mean, cov = section_moments(residual_moments(true, filt, 5), 2, M=3)
    >>> mean.shape, cov.shape
    ((3,), (3, 3))
    """
    M = _check_M(M)
    j = _index(j, _check_moments(moments).n_steps, "j")
    return SectionMoments(np.tile(moments.mean[j], M), np.kron(np.eye(M), moments.cov[j]))


def pair_moments(moments: ResidualMoments, j: int, k: int, M: int):
    """Mean and covariance of the stacked pair of sections ``phi(j, k) = (phi_j, phi_k)``.

    Parameters
    ----------
    moments : ResidualMoments
    j, k : int
        The two sections.
    M : int
        Number of records.

    Returns
    -------
    SectionMoments
        ``mean`` ``(2 M p,)`` and ``cov`` ``(2 M p, 2 M p)``,
        ``[[I_M kron P_j, I_M kron C(j, k)], [I_M kron C(j, k)^T, I_M kron P_k]]``.

    Notes
    -----
    Baram (1980), (3.19) and (3.21)-(3.23), with ``C(j, k) = E (r_j -
    m_j)(r_k - m_k)^T`` ((2.4) corrected).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> mean, cov = pair_moments(residual_moments(true, filt, 5), 1, 3, M=3)
    >>> mean.shape, cov.shape
    ((6,), (6, 6))
    """
    M = _check_M(M)
    N = _check_moments(moments).n_steps
    j, k = _index(j, N, "j"), _index(k, N, "k")
    mean = np.concatenate([np.tile(moments.mean[j], M), np.tile(moments.mean[k], M)])
    I = np.eye(M)
    Cjk = moments.C(j, k)
    cov = np.block(
        [
            [np.kron(I, moments.cov[j]), np.kron(I, Cjk)],
            [np.kron(I, Cjk.T), np.kron(I, moments.cov[k])],
        ]
    )
    return SectionMoments(mean, symmetrize(cov))


_KINDS = ("mean", "covariance", "correlation")
_LAWS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def statistic_law(
    moments: ResidualMoments,
    kind: str,
    j: int,
    M: int,
    k: int | None = None,
    direction=None,
    full: bool = False,
):
    """Exact law of a section statistic when the residuals have ``moments``.

    Parameters
    ----------
    moments : ResidualMoments
        From :func:`residual_moments` of the pair that generates the data:
        ``(M^0, M^1)`` for critical regions, ``(M^2, M^1)`` for the power.
    kind : {"mean", "covariance", "correlation"}
    j : int
        Section (time index).
    M : int
        Number of records.
    k : int, optional
        Second section, for the correlation statistic.
    direction : array_like or (u, w), optional
        A unit vector for the projected covariance statistic, a pair of unit
        vectors for the projected correlation statistic; ``None`` for the
        trace statistics.
    full : bool
        Build the paper's ``M p`` (or ``2 M p``) dimensional quadratic form
        ``phi^T A phi`` of section 3 (slow, for checking); by default the
        equivalent reduced form below is used.

    Returns
    -------
    WeightedChiSquare or QuadraticForm
        With ``cdf``, ``sf``, ``ppf``, ``isf``, ``mean``, ``var``, ``rvs``.

    Notes
    -----
    Records are independent, so the Helmert transform turns the centred
    section into ``M - 1`` independent copies of the centred residual:

    - mean: ``rbar_j ~ N(m_j, P_j / M)``, so ``||rbar_j||^2`` is
      ``QuadraticForm(I_p, m_j, P_j/M)``;
    - covariance: ``c_j = (1/M) sum_{l<M} |z_l|^2``, ``z_l ~ N(0, P_j)``:
      weights ``eig(P_j)/M``, each with ``M - 1`` degrees of freedom (hence
      ``E c_j = (M - 1)/M tr P_j``); projected: ``(v^T P_j v / M) chi2(M - 1)``;
    - correlation: ``c(j, k) = (1/M) sum_{l<M} z_l^T y_l`` with ``(z, y)``
      jointly normal, covariance ``S = [[P_j, C], [C^T, P_k]]``: weights the
      eigenvalues of ``S^{1/2} E S^{1/2} / (2M)``, ``E = [[0, I], [I, 0]]``,
      each with ``M - 1`` degrees of freedom.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> law = statistic_law(residual_moments(true, filt, 5), "covariance", 2, M=10)
    >>> round(float(law.mean()), 4) == round(0.9 * float(residual_moments(true, filt, 5).cov[2, 0, 0]), 4)
    True
    """
    moments = _check_moments(moments)
    full = as_flag(full, "full")
    if not isinstance(kind, str) or kind not in _KINDS:
        raise ValueError(f"kind must be one of {_KINDS}, got {kind!r}")
    M = _check_M(M)
    N, p = moments.n_steps, moments.n_outputs
    j = _index(j, N, "j")
    if kind == "correlation":
        if k is None:
            raise ValueError("the correlation statistic needs a second section k")
        k = _index(k, N, "k")
    elif k is not None:
        raise ValueError(
            f"k (a second section) is only for the correlation statistic, not {kind!r}"
        )
    # A law is a function of its arguments: remember it with the moments, so
    # that testing many records against one null (a Monte Carlo study) builds
    # it, and finds its quantiles, once.
    key = (kind, j, M, k, full, None if direction is None else np.asarray(direction).tobytes())
    cache = _LAWS.setdefault(moments, {})
    if key not in cache:
        cache[key] = _statistic_law(moments, kind, j, M, k, direction, full, p)
    return cache[key]


def _statistic_law(moments, kind, j, M, k, direction, full, p):
    if full:
        if kind == "mean":
            mean, cov = section_moments(moments, j, M)
            return QuadraticForm(mean_matrix(M, p), mean, cov)
        if kind == "covariance":
            mean, cov = section_moments(moments, j, M)
            return QuadraticForm(covariance_matrix(M, p, direction), mean, cov)
        mean, cov = pair_moments(moments, j, k, M)
        return QuadraticForm(correlation_matrix(M, p, direction), mean, cov)
    if kind == "mean":
        return QuadraticForm(np.eye(p), moments.mean[j], moments.cov[j] / M)
    if kind == "covariance":
        P = moments.cov[j]
        if direction is None:
            weights = np.linalg.eigvalsh(P) / M
        else:
            v = _unit(direction, p, "direction")
            weights = np.array([v @ P @ v / M])
        return WeightedChiSquare(weights, np.full(weights.size, M - 1.0))
    S = np.block([[moments.cov[j], moments.C(j, k)], [moments.C(j, k).T, moments.cov[k]]])
    if direction is None:
        E = np.block([[np.zeros((p, p)), np.eye(p)], [np.eye(p), np.zeros((p, p))]])
        shape = QuadraticForm(E / (2 * M), cov=symmetrize(S))
    else:
        u, w = _pair(direction, p)
        T = np.zeros((2, 2 * p))
        T[0, :p], T[1, p:] = u, w
        shape = QuadraticForm(
            np.array([[0.0, 1.0], [1.0, 0.0]]) / (2 * M), cov=symmetrize(T @ S @ T.T)
        )
    return WeightedChiSquare(shape.weights, shape.dof * (M - 1.0))


# ---------------------------------------------------------------------------
# tests
# ---------------------------------------------------------------------------
def _direction_for(null, kind, j, k, gamma):
    """The gamma-th principal direction (0-based) of the null pair, or None."""
    if gamma is None:
        return None
    p = null.n_outputs
    gamma = as_index(gamma, "gamma", p, what="a principal direction")
    if kind == "covariance":
        _, V = principal_directions(null, j)
        return V[:, gamma]
    _, U, W = principal_directions(null, j, k)
    return U[:, gamma], W[:, gamma]


def _run_test(name, kind, residuals, j, k, null, alpha, gamma, alternative, power_against):
    if not isinstance(null, ResidualMoments):
        raise InputTypeError(
            "null must be the ResidualMoments of the pair (M0, M1) from residual_moments, "
            f"got {type(null).__name__}"
        )
    if power_against is not None:
        _check_moments(power_against, "power_against")
        if power_against.mean.shape != null.mean.shape:
            raise ValueError(
                f"power_against holds moments of (N, p) = {power_against.mean.shape}, null of "
                f"{null.mean.shape}: both must describe the residuals tested"
            )
    r = _as_records(residuals)
    M, N, p = r.shape
    if (N, p) != null.mean.shape:
        raise ValueError(
            f"residuals have N = {N} samples of p = {p} outputs but the null moments are for "
            f"N = {null.n_steps}, p = {null.n_outputs}"
        )
    alpha = as_probability(alpha)
    direction = _direction_for(null, kind, j, k, gamma)
    if kind == "mean":
        statistic = mean_statistic(r, j)
    elif kind == "covariance":
        statistic = covariance_statistic(r, j, direction)
    else:
        statistic = correlation_statistic(r, j, k, direction)
    law = statistic_law(null, kind, j, M, k=k, direction=direction)
    details: dict[str, Any] = {"M": M, "j": j}
    if k is not None:
        details["k"] = k
    if gamma is not None:
        details["direction"] = gamma
    if power_against is not None:
        alt_law = statistic_law(power_against, kind, j, M, k=k, direction=direction)
        details["power"] = rejection_probability(
            alt_law, critical_value(law, alpha, alternative), alternative
        )
    label = (
        f"{name} (j={j}"
        + (f", k={k}" if k is not None else "")
        + (f", direction {gamma}" if gamma is not None else "")
        + f", M={M})"
    )
    return TestResult.from_null(label, statistic, law, alpha, alternative, details=details)


def mean_test(
    residuals, j, null, alpha=0.05, alternative="two-sided", power_against=None
) -> TestResult:
    """Mean test of section ``j`` on ``||rbar_j||^2``.

    Parameters
    ----------
    residuals : (M, N, p) array_like
        Filter residuals of M records.
    j : int
        Section (time index).
    null : ResidualMoments
        Moments under ``(M^0, M^1)``: the critical values are quantiles
        (``ppf``/``isf`` at ``alpha/2``, or ``alpha`` one-sided) of the law of
        :func:`statistic_law` under them.
    alpha : float
        Level.
    alternative : {"two-sided", "greater", "less"}
        Critical region.  Under a mismatched null the residual mean ``m_j``
        is not zero, and a wrong model can move ``||rbar_j||^2`` down as well
        as up, hence two-sided by default; "greater" suits a zero-mean null.
    power_against : ResidualMoments, optional
        Moments under an alternative ``(M^2, M^1)``; the power
        ``P(reject | M^2)`` is reported in ``details["power"]``.

    Returns
    -------
    TestResult
        ``statistic`` from :func:`mean_statistic`, ``null`` its exact law,
        ``critical_value`` one number or a ``(lower, upper)`` pair.

    Notes
    -----
    Baram (1980), (2.5)-(2.6) (squared norm) and (3.2)-(3.3): under the
    null pair ``rbar_j ~ N(m_j, P_j / M)``, so the statistic is a
    noncentral quadratic form (:class:`course.quadform.QuadraticForm`).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> import numpy as np
    >>> null = residual_moments(true, filt, 5)
    >>> r = simulate_records(true, filt, 20, 5, np.random.default_rng(3))
    >>> result = mean_test(r, 2, null)
    >>> result.alternative, 0.0 <= result.pvalue <= 1.0
    ('two-sided', True)
    """
    return _run_test(
        "mean test", "mean", residuals, j, None, null, alpha, None, alternative, power_against
    )


def covariance_test(
    residuals, j, null, alpha=0.05, gamma=None, alternative="two-sided", power_against=None
) -> TestResult:
    """Covariance test of section ``j`` (trace, or the gamma-th principal direction).

    Parameters
    ----------
    residuals, j, null, alpha, power_against
        As in :func:`mean_test`.
    gamma : int, optional
        0-based index of the principal direction of the null ``P_j`` in
        decreasing order of eigenvalue; ``None`` uses ``tr Pbar_j``.
    alternative : {"two-sided", "greater", "less"}
        Critical region; two-sided by default, since a wrong model can make
        the residuals too small as well as too large.

    Returns
    -------
    TestResult
        ``statistic`` from :func:`covariance_statistic`, ``null`` its law
        (:func:`statistic_law`), ``details["power"]`` with ``power_against``.

    Notes
    -----
    Baram (1980), (2.13)-(2.17) corrected, with the weighted chi-square law
    of :func:`statistic_law` (Imhof's method) for the critical region.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> import numpy as np
    >>> null = residual_moments(true, filt, 5)
    >>> noisier = LinearModel(F=true.F, H=true.H, Q=true.Q, R=[[3.0]])
    >>> r = simulate_records(noisier, filt, 50, 5, np.random.default_rng(3))
    >>> covariance_test(r, 2, null).reject
    True
    """
    return _run_test(
        "covariance test",
        "covariance",
        residuals,
        j,
        None,
        null,
        alpha,
        gamma,
        alternative,
        power_against,
    )


def correlation_test(
    residuals, j, k, null, alpha=0.05, gamma=None, alternative="two-sided", power_against=None
) -> TestResult:
    """Correlation test of sections ``j`` and ``k`` (trace, or a singular pair).

    Parameters
    ----------
    residuals, j, null, alpha, alternative, power_against
        As in :func:`mean_test`.
    k : int
        Second section.
    gamma : int, optional
        0-based index of the singular-vector pair of the null ``C(j, k)`` in
        decreasing order of singular value; ``None`` uses ``tr Cbar(j, k)``.

    Returns
    -------
    TestResult
        ``statistic`` from :func:`correlation_statistic`, ``null`` its law.

    Notes
    -----
    Baram (1980), (2.7)-(2.12) with an SVD for the non-symmetric ``C(j, k)``;
    the law has weights of both signs (the eigenvalues of
    ``S^(1/2) [[0, I], [I, 0]] S^(1/2) / (2M)``), so Imhof's method handles
    what a chi-square table cannot.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> import numpy as np
    >>> null = residual_moments(true, filt, 5)
    >>> r = simulate_records(true, filt, 50, 5, np.random.default_rng(3))
    >>> result = correlation_test(r, 1, 3, null, alternative="greater")
    >>> result.alternative, result.name
    ('greater', 'correlation test (j=1, k=3, M=50)')
    """
    return _run_test(
        "correlation test",
        "correlation",
        residuals,
        j,
        k,
        null,
        alpha,
        gamma,
        alternative,
        power_against,
    )


def power(
    null, alternative_moments, kind, j, M, alpha=0.05, k=None, gamma=None, alternative="two-sided"
) -> float:
    """Probability that a test of level ``alpha`` rejects under ``alternative_moments``.

    Parameters
    ----------
    null : ResidualMoments
        Moments under ``(M^0, M^1)``: they fix the critical region.
    alternative_moments : ResidualMoments
        Moments under ``(M^2, M^1)``.
    kind : {"mean", "covariance", "correlation"}
    j : int
        Section.
    M : int
        Number of records.
    alpha : float
        Level.
    k : int, optional
        Second section (correlation statistic).
    gamma : int, optional
        Principal direction, as in :func:`covariance_test`.
    alternative : {"two-sided", "greater", "less"}
        The critical region, two-sided by default as in the tests.

    Returns
    -------
    float
        ``P(statistic in critical region | alternative_moments)``.

    Notes
    -----
    Baram (1980), section 3: both laws are quadratic forms in the normal
    section vectors, evaluated exactly by Imhof's method.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> noisier = LinearModel(F=true.F, H=true.H, Q=true.Q, R=[[3.0]])
    >>> null, alt = residual_moments(true, filt, 5), residual_moments(noisier, filt, 5)
    >>> [round(power(null, alt, "covariance", 2, M), 2) for M in (5, 20, 50)]
    [0.17, 0.45, 0.79]
    """
    _check_moments(null, "null")
    _check_moments(alternative_moments, "alternative_moments")
    if not isinstance(kind, str) or kind not in _KINDS:
        raise ValueError(f"kind must be one of {_KINDS}, got {kind!r}")
    alpha = as_probability(alpha)
    direction = _direction_for(null, kind, j, k, gamma)
    law0 = statistic_law(null, kind, j, M, k=k, direction=direction)
    law2 = statistic_law(alternative_moments, kind, j, M, k=k, direction=direction)
    return rejection_probability(law2, critical_value(law0, alpha, alternative), alternative)


_readonly = readonly
