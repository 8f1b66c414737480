"""Test quantities from parameter estimates: estimate, compare with nominal, power."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import linalg as sla
from scipy import stats

from course.diagnosis._common import _check_sigma, _data, _indices, _model, _split
from course.linalg import (
    as_covariance,
    as_float_array,
    as_vector,
    check_alpha,
    check_full_column_rank,
    cholesky_lower,
    solve_spd,
    symmetrize,
)
from course.results import TestResult, format_number


# ---------------------------------------------------------------------------
# parameter estimates
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class ParameterEstimate:
    """Least-squares estimate of some parameters with the others at nominal.

    Attributes
    ----------
    theta : numpy.ndarray
        Full parameter vector ``(p,)`` or ``(p, M)``: estimates at
        ``indices``, nominal values elsewhere.
    indices : tuple of int
        The estimated parameters.
    covariance : numpy.ndarray
        ``(k, k)`` covariance of the estimated parameters,
        ``sigma^2 (Phi^T Phi)^{-1}``.
    """

    theta: np.ndarray
    indices: tuple
    covariance: np.ndarray

    @property
    def std(self) -> np.ndarray:
        """Standard deviations of the estimated parameters."""
        return np.sqrt(np.diag(self.covariance))

    def __repr__(self) -> str:
        if self.theta.ndim == 1:
            est = ", ".join(format_number(float(self.theta[j])) for j in self.indices)
            return f"ParameterEstimate(indices={self.indices}, estimate=[{est}])"
        return f"ParameterEstimate(indices={self.indices}, records={self.theta.shape[1]})"


def estimate_parameters(
    y, U, nominal, estimate: Sequence[int], *, sigma: float
) -> ParameterEstimate:
    """Estimate the parameters ``estimate`` by least squares, the rest at nominal.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, M)
    U, nominal
        As in :func:`prediction_error`.
    estimate : sequence of int
        Parameters to estimate (at least one).
    sigma : float
        Noise standard deviation (for the covariance).

    Returns
    -------
    ParameterEstimate

    Raises
    ------
    numpy.linalg.LinAlgError
        The regressors of the estimated parameters are not linearly
        independent (no excitation): the estimate is not unique.

    Notes
    -----
    ``theta_hat = R^{-1} Q^T (y - U_fixed nominal_fixed)`` from the thin QR
    factorisation ``U_est = Q R``, and ``Cov = sigma^2 R^{-1} R^{-T}``
    (``= sigma^2 (Phi^T Phi)^{-1}`` without forming ``Phi^T Phi``).  The
    lecture's warning (slide "Teststorheter baserade på
    parameterskattningar"): this needs excitation.
    """
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    est = _indices(estimate, U.shape[1], "estimate")
    if not est:
        raise ValueError("estimate must name at least one parameter")
    Y = _data(y, U.shape[0])
    Phi, known = _split(U, nominal, est)
    check_full_column_rank(Phi, "the regressors of the estimated parameters")
    Q, R = np.linalg.qr(Phi)
    target = Y - (known[:, None] if Y.ndim == 2 else known)
    theta_est = sla.solve_triangular(R, Q.T @ target, lower=False)
    R_inv = sla.solve_triangular(R, np.eye(len(est)), lower=False)
    cov = sigma**2 * symmetrize(R_inv @ R_inv.T)
    theta = np.repeat(nominal[:, None], Y.shape[1], axis=1) if Y.ndim == 2 else nominal.copy()
    theta[est] = theta_est
    return ParameterEstimate(theta=theta, indices=tuple(est), covariance=cov)


def parameter_estimate_test(
    estimate, covariance, nominal, alpha: float = 0.05, name: str = "parameter-estimate test"
) -> TestResult:
    """Test ``H0: theta = nominal`` from an estimate and its covariance.

    Parameters
    ----------
    estimate : float or array_like, shape (k,)
        The estimate ``theta_hat`` of the tested parameter(s).
    covariance : float or array_like, shape (k, k)
        Its covariance (a variance for one parameter).
    nominal : float or array_like, shape (k,)
        The fault-free value(s).
    alpha : float, default 0.05
    name : str

    Returns
    -------
    TestResult
        One parameter: ``statistic = |theta_hat - nominal|`` with null law
        ``halfnorm(scale=std)`` and threshold ``std * z_{alpha/2}``.
        Several: the Wald statistic
        ``(theta_hat - nominal)^T C^{-1} (theta_hat - nominal)`` with
        null law ``chi2(k)``.

    Notes
    -----
    The lecture's ``T = |theta_hat_i - theta_i^0|`` (slide "Teststorheter
    baserade på parameterskattningar").  For a Gaussian estimate,
    ``theta_hat - theta^0 ~ N(0, s^2)`` under H0, so ``T`` is half-normal
    and ``P(T > s z_{alpha/2}) = alpha``: the covariance turns a false-alarm
    rate into a threshold.  The Wald form is the same idea for a vector
    (a quadratic form in a Gaussian vector, ``chi2(k)``).
    """
    alpha = check_alpha(alpha)
    est = np.atleast_1d(as_float_array(estimate, "estimate"))
    if est.ndim != 1:
        raise ValueError(
            f"estimate must be a number or a 1-D vector, got shape {np.shape(estimate)}"
        )
    k = est.size
    nom = np.atleast_1d(as_float_array(nominal, "nominal"))
    if nom.shape != (k,):
        raise ValueError(f"nominal must have the shape of the estimate ({k},), got {nom.shape}")
    cov = as_float_array(covariance, "covariance")
    cov = as_covariance(cov.reshape(1, 1) if cov.ndim == 0 else cov, "covariance", k)
    diff = est - nom
    if k == 1:
        std = float(np.sqrt(cov[0, 0]))
        null = stats.halfnorm(scale=std)
        stat = abs(float(diff[0]))
        crit = std * stats.norm.isf(alpha / 2)
        return TestResult(
            name=name,
            statistic=stat,
            alpha=alpha,
            critical_value=crit,
            pvalue=stats.halfnorm.sf(stat / std),
            reject=stat > crit,
            null=null,
            alternative="greater",
            details={"estimate": float(est[0]), "std": std, "z": stat / std},
        )
    wald = float(diff @ solve_spd(cov, diff, "covariance"))
    crit = stats.chi2.isf(alpha, k)
    return TestResult(
        name=name,
        statistic=wald,
        alpha=alpha,
        critical_value=crit,
        pvalue=stats.chi2.sf(wald, k),
        reject=wald > crit,
        null=stats.chi2(k),
        dof=k,
        alternative="greater",
    )


def regression_parameter_test(
    y,
    U,
    nominal,
    estimate: Sequence[int],
    test,
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str | None = None,
) -> TestResult:
    """Estimate parameters ``estimate`` and test ``theta_test = nominal_test``.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal
        As in :func:`prediction_error`.
    estimate : sequence of int
        Parameters estimated together (the tested ones and the ones to
        decouple).
    test : int or sequence of int
        Parameter(s) compared with nominal; a subset of ``estimate``.
    sigma : float
    alpha : float
    name : str, optional

    Returns
    -------
    TestResult
        See :func:`parameter_estimate_test`.

    Notes
    -----
    The lecture's ``T1 = |theta_hat_2 - 1|`` with ``(theta_hat_1,
    theta_hat_2) = argmin sum (y - theta_1 u1 - theta_2 u2 - u3)^2``: the
    fault in ``theta_1`` is decoupled because ``theta_1`` is estimated too.
    """
    U, nominal = _model(U, nominal)
    est = _indices(estimate, U.shape[1], "estimate")
    tested = _indices(test, U.shape[1], "test")
    if not tested or not set(tested) <= set(est):
        raise ValueError(f"test {tested} must be a non-empty subset of estimate {est}")
    fit = estimate_parameters(as_vector(y, "y", U.shape[0]), U, nominal, est, sigma=sigma)
    pos = [est.index(j) for j in tested]
    if name is None:
        name = "parameter-estimate test of theta_" + ",".join(str(j + 1) for j in tested)
    return parameter_estimate_test(
        fit.theta[tested], fit.covariance[np.ix_(pos, pos)], nominal[tested], alpha=alpha, name=name
    )


def parameter_estimate_power(
    U, nominal, estimate: Sequence[int], test, theta, *, sigma: float, alpha: float = 0.05
) -> Any:
    """Alarm probability of :func:`regression_parameter_test` when the truth is ``theta``.

    Parameters
    ----------
    U, nominal, estimate, test, sigma, alpha
        As in :func:`regression_parameter_test`.
    theta : array_like, shape (p,) or (p, K)
        True parameter vector(s).

    Returns
    -------
    float or numpy.ndarray

    Notes
    -----
    The estimate is unbiased for the estimated parameters, but a deviation
    of a *fixed* parameter leaks into it through the regressors:
    ``E theta_hat = theta_est + (Phi^T Phi)^{-1} Phi^T U_fixed (theta - nominal)_fixed``.
    That leak is the isolation problem of the lecture.  With mean shift
    ``b`` and standard deviation ``s`` of the tested estimate, the power of
    the two-sided test is ``Phi((b - c)/s) + Phi((-b - c)/s)`` with
    ``c = s z_{alpha/2}``; for several tested parameters the Wald statistic
    is ``chi2'(k, b^T C^{-1} b)``.
    """
    alpha = check_alpha(alpha)
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    p = U.shape[1]
    est = _indices(estimate, p, "estimate")
    tested = _indices(test, p, "test")
    if not tested or not set(tested) <= set(est):
        raise ValueError(f"test {tested} must be a non-empty subset of estimate {est}")
    theta = as_float_array(theta, "theta")
    if theta.ndim not in (1, 2) or theta.shape[0] != p:
        raise ValueError(f"theta must have shape ({p},) or ({p}, K), got {theta.shape}")
    # The mean of the estimate is the noise-free fit to U theta.
    mean = estimate_parameters(U @ theta, U, nominal, est, sigma=sigma)
    shift = mean.theta[tested] - (nominal[tested][:, None] if theta.ndim == 2 else nominal[tested])
    pos = [est.index(j) for j in tested]
    cov = mean.covariance[np.ix_(pos, pos)]
    if len(tested) == 1:
        s = float(np.sqrt(cov[0, 0]))
        c = stats.norm.isf(alpha / 2)
        b = shift[0] / s
        power = stats.norm.sf(c - b) + stats.norm.cdf(-c - b)
    else:
        L = cholesky_lower(cov, "covariance")
        lam = np.sum(sla.solve_triangular(L, shift, lower=True) ** 2, axis=0)
        k = len(tested)
        power = np.where(
            lam > 0, stats.ncx2.sf(stats.chi2.isf(alpha, k), k, np.maximum(lam, 1e-300)), alpha
        )
    power = np.asarray(power)
    return float(power) if power.ndim == 0 else power
