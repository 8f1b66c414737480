"""Test quantities from parameter estimates: estimate, compare with nominal, power.

Source: the LiU lecture on test quantities (Linköping University, Swedish
slides; full reference in the course bibliography, :doc:`/docs/bibliography`),
slide "Teststorheter baserade på parameterskattningar".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats

from course.chi2 import chi2_power, residual_norm_law
from course.diagnosis._common import (
    _answer,
    _check_sigma,
    _indices,
    _model,
    _parameter_vectors,
    _records,
    _split,
)
from course.linalg import check_full_column_rank, cholesky_lower, qr_solve, solve_spd, symmetrize
from course.linalg import whiten as _whiten
from course.results import TestResult, critical_value, format_number, rejection_probability
from course.validation import as_covariance, as_float_array, as_probability, as_vector


@dataclass(frozen=True, repr=False, eq=False)
class ParameterEstimate:
    """Least-squares estimate of some parameters with the others at nominal.

    Attributes
    ----------
    theta : numpy.ndarray
        Full parameter vector ``(p,)``, or one per record ``(M, p)``:
        estimates at ``indices``, nominal values elsewhere.
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
        return f"ParameterEstimate(indices={self.indices}, records={self.theta.shape[0]})"


def _check_estimate(U: np.ndarray, estimate: Any) -> list[int]:
    est = _indices(estimate, U.shape[1], "estimate")
    if not est:
        raise ValueError("estimate must name at least one parameter")
    return est


def _estimate_columns(Y, U, nominal, est, sigma):
    """Estimates as columns ``(p, M)`` (or ``(p,)``) and their covariance."""
    Phi, known = _split(U, nominal, est)
    check_full_column_rank(Phi, "the regressors of the estimated parameters")
    target = Y - (known[:, None] if Y.ndim == 2 else known)
    solution = qr_solve(Phi, target)
    cov = sigma**2 * symmetrize(solution.R_inv @ solution.R_inv.T)
    theta = np.repeat(nominal[:, None], Y.shape[1], axis=1) if Y.ndim == 2 else nominal.copy()
    theta[est] = solution.x
    return theta, cov


def estimate_parameters(
    y: Any, U: Any, nominal: Any, estimate: Sequence[int], *, sigma: float
) -> ParameterEstimate:
    r"""Estimate the parameters ``estimate`` by least squares, the rest at nominal.

    Parameters
    ----------
    y : array_like, shape (N,) or (M, N)
        One record, or ``M`` records as rows.
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

    See Also
    --------
    parameter_estimate_test : A test of the estimates.
    course.linalg.qr_solve : The solver it uses.

    Notes
    -----
    From the thin QR factorisation :math:`U_{\text{est}} = QR`
    (:func:`course.linalg.qr_solve`),

    .. math::

        \hat\theta = R^{-1} Q^{\mathsf T} (y - U_{\text{fixed}} \theta_{\text{fixed}}), \qquad
        \operatorname{Cov}\hat\theta = \sigma^2 R^{-1} R^{-\mathsf T}
        \;(= \sigma^2 (\Phi^{\mathsf T}\Phi)^{-1}),

    without forming :math:`\Phi^{\mathsf T}\Phi`.  The lecture's warning (slide
    "Teststorheter baserade på parameterskattningar"): this needs excitation.

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(4), np.arange(4.0)])
    >>> est = estimate_parameters([1.0, 3.0, 5.0, 7.0], U, [0.0, 0.0], [0, 1], sigma=1.0)
    >>> est.theta.round(12) + 0.0, est.std.round(4)
    (array([1., 2.]), array([0.8367, 0.4472]))
    """
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    est = _check_estimate(U, estimate)
    Y, layout = _records(y, U.shape[0])
    theta, cov = _estimate_columns(Y, U, nominal, est, sigma)
    return ParameterEstimate(theta=_answer(theta, layout), indices=tuple(est), covariance=cov)


def parameter_estimate_test(
    estimate: Any,
    covariance: Any,
    nominal: Any,
    alpha: float = 0.05,
    name: str = "parameter-estimate test",
) -> TestResult:
    r"""Test ``H0: theta = nominal`` from an estimate and its covariance.

    Parameters
    ----------
    estimate : float or array_like, shape (k,)
        The estimate ``theta_hat`` of the tested parameter(s).
    covariance : float or array_like, shape (k, k)
        Its covariance (a variance for one parameter).
    nominal : float or array_like, shape (k,)
        The fault-free value(s).
    alpha : float, default 0.05
        Level of significance.
    name : str
        Name shown in the result.

    Returns
    -------
    TestResult
        One parameter: ``statistic = |theta_hat - nominal|`` with null law
        ``halfnorm(scale=std)`` and threshold ``std * z_{alpha/2}``.
        Several: the Wald statistic
        ``(theta_hat - nominal)^T C^{-1} (theta_hat - nominal)`` with
        null law ``chi2(k)``.

    See Also
    --------
    estimate_parameters : The estimates and their covariance.
    parameter_estimate_power : Its power against a fault.

    Notes
    -----
    The lecture's :math:`T = |\hat\theta_i - \theta_i^0|` (slide
    "Teststorheter baserade på parameterskattningar").  For a Gaussian
    estimate, :math:`\hat\theta - \theta^0 \sim N(0, s^2)` under H0, so
    :math:`T` is half-normal and

    .. math::

        P(T > s\, z_{\alpha/2}) = \alpha:

    the covariance turns a false-alarm rate into a threshold.  The Wald form
    is the same idea for a vector (a quadratic form in a Gaussian vector,
    :math:`\chi^2(k)`).

    Examples
    --------
    >>> r = parameter_estimate_test(1.3, 0.01, 1.0)
    >>> round(r.statistic, 12), round(r.critical_value, 4), r.reject
    (0.3, 0.196, True)
    """
    alpha = as_probability(alpha)
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
        stat = abs(float(diff[0]))
        return TestResult.from_null(
            name,
            stat,
            stats.halfnorm(scale=std),
            alpha,
            details={"estimate": float(est[0]), "std": std, "z": stat / std},
        )
    wald = float(diff @ solve_spd(cov, diff, "covariance"))
    return TestResult.from_null(name, wald, residual_norm_law(k), alpha, dof=k)


def regression_parameter_test(
    y: Any,
    U: Any,
    nominal: Any,
    estimate: Sequence[int],
    test: Any,
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str | None = None,
) -> TestResult:
    r"""Estimate parameters ``estimate`` and test ``theta_test = nominal_test``.

    Parameters
    ----------
    y : array_like, shape (N,)
        One record.
    U, nominal
        As in :func:`prediction_error`.
    estimate : sequence of int
        Parameters estimated together (the tested ones and the ones to
        decouple).
    test : int or sequence of int
        Parameter(s) compared with nominal; a subset of ``estimate``.
    sigma : float
        Noise standard deviation.
    alpha : float
        Level of significance.
    name : str, optional
        Name shown in the result.

    Returns
    -------
    TestResult
        See :func:`parameter_estimate_test`.

    See Also
    --------
    parameter_estimate_test : The general form.

    Notes
    -----
    The lecture's :math:`T_1 = |\hat\theta_2 - 1|` with

    .. math::

        (\hat\theta_1, \hat\theta_2) = \arg\min \sum_t (y - \theta_1 u_1 - \theta_2 u_2 - u_3)^2:

    the fault in :math:`\theta_1` is decoupled because :math:`\theta_1` is
    estimated too.

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(6), np.arange(6.0)])
    >>> y = U @ [0.0, 1.0] + np.array([0.1, -0.1, 0.0, 0.1, -0.1, 0.0])
    >>> regression_parameter_test(y, U, [0.0, 1.0], [0, 1], 1, sigma=0.1).reject
    False
    """
    U, nominal = _model(U, nominal)
    est = _check_estimate(U, estimate)
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
    U: Any,
    nominal: Any,
    estimate: Sequence[int],
    test: Any,
    theta: Any,
    *,
    sigma: float,
    alpha: float = 0.05,
) -> Any:
    r"""Alarm probability of :func:`regression_parameter_test` when the truth is ``theta``.

    Parameters
    ----------
    U, nominal, estimate, test, sigma, alpha
        As in :func:`regression_parameter_test`.
    theta : array_like, shape (p,) or (K, p)
        True parameter vector(s), one per row.

    Returns
    -------
    float or numpy.ndarray

    See Also
    --------
    parameter_estimate_test : The test whose power this is.
    course.chi2.chi2_power : The power of a chi-square test.

    Notes
    -----
    The estimate is unbiased for the estimated parameters, but a deviation of
    a *fixed* parameter leaks into it through the regressors:

    .. math::

        E\hat\theta = \theta_{\text{est}}
        + (\Phi^{\mathsf T}\Phi)^{-1} \Phi^{\mathsf T} U_{\text{fixed}}
          (\theta - \theta_{\text{nominal}})_{\text{fixed}} .

    That leak is the isolation problem of the lecture.  With mean shift
    :math:`b` and standard deviation :math:`s` of the tested estimate, the
    power of the two-sided test is
    :math:`\Phi\bigl((b - c)/s\bigr) + \Phi\bigl((-b - c)/s\bigr)` with
    :math:`c = s\, z_{\alpha/2}`; for several tested parameters the Wald
    statistic is :math:`\chi'^2(k, b^{\mathsf T} C^{-1} b)`
    (:func:`course.chi2.chi2_power`).

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(6), np.arange(6.0)])
    >>> parameter_estimate_power(U, [0, 1], [0, 1], 1, [[0, 1.0], [0, 1.05]], sigma=0.1).round(3)
    array([0.05 , 0.552])
    """
    alpha = as_probability(alpha)
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    p = U.shape[1]
    est = _check_estimate(U, estimate)
    tested = _indices(test, p, "test")
    if not tested or not set(tested) <= set(est):
        raise ValueError(f"test {tested} must be a non-empty subset of estimate {est}")
    theta, several = _parameter_vectors(theta, p)
    # The mean of the estimate is the noise-free fit to U theta.
    mean, cov_all = _estimate_columns(U @ theta, U, nominal, est, sigma)
    shift = mean[tested] - (nominal[tested][:, None] if several else nominal[tested])
    pos = [est.index(j) for j in tested]
    cov = cov_all[np.ix_(pos, pos)]
    if len(tested) == 1:
        s = float(np.sqrt(cov[0, 0]))
        region = critical_value(stats.norm(), alpha, "two-sided")
        # the standardised estimate is N(b, 1) under the fault b = shift / s
        power = np.array(
            [
                rejection_probability(stats.norm(loc=b), region, "two-sided")
                for b in np.ravel(shift[0] / s)
            ]
        )
        return float(power[0]) if not several else power
    lam = np.sum(_whiten(cholesky_lower(cov, "covariance"), shift) ** 2, axis=0)
    return chi2_power(len(tested), lam, alpha)
