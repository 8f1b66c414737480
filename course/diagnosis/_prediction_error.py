"""Test quantities from prediction errors: linear regressions and general models."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize, stats

from course.diagnosis._common import (
    _check_dof,
    _check_sigma,
    _data,
    _indices,
    _model,
    _numerical_rank,
    _range_basis,
    _scaled_chi2,
    _split,
    _void_test_message,
)
from course.linalg import (
    as_float_array,
    as_matrix,
    as_vector,
    check_alpha,
)
from course.results import TestResult, format_number


# ---------------------------------------------------------------------------
# prediction errors: linear regression
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class RegressionFit:
    """Least-squares fit of a linear regression that may lack excitation.

    Attributes
    ----------
    theta : numpy.ndarray
        A minimising parameter vector, ``(p,)`` or ``(p, M)``: the unique one
        when ``rank == p``, else the one of smallest norm (any other differs
        by a null-space vector of the regressors and fits equally well).
    residual : numpy.ndarray
        ``Y - Phi theta`` (unique even when theta is not), ``(N,)`` or ``(N, M)``.
    statistic : float or numpy.ndarray
        ``T = ||residual||^2``, one per record.
    rank : int
        Numerical rank of the regressor matrix.
    dof : int
        ``N - rank``: the dimension of the residual space.
    n_parameters : int
        Number of estimated parameters (for :func:`prediction_error`, the
        free ones; ``theta`` then holds the full vector).
    """

    theta: np.ndarray
    residual: np.ndarray
    statistic: Any
    rank: int
    dof: int
    n_parameters: int

    @property
    def unique(self) -> bool:
        """True when the regressors have full column rank (theta is unique)."""
        return self.rank == self.n_parameters

    def __repr__(self) -> str:
        if np.ndim(self.statistic) == 0:
            stat = format_number(float(self.statistic))
        else:
            stat = f"<{np.size(self.statistic)} records>"
        return (
            f"RegressionFit(statistic={stat}, rank={self.rank} of {self.n_parameters}, "
            f"dof={self.dof}, unique={self.unique})"
        )


def least_squares_residual(y, Phi, rcond: float | None = None) -> RegressionFit:
    """``min over theta of ||y - Phi theta||^2``, correct also without excitation.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, M)
        One record, or ``M`` records as columns.
    Phi : array_like, shape (N, p)
        Regressor matrix; it may be rank deficient and ``p`` may be 0.
    rcond : float, optional
        Singular values below ``rcond * s_max`` count as zero; by default
        ``max(N, p) * eps`` (numpy's ``matrix_rank`` rule).

    Returns
    -------
    RegressionFit

    Notes
    -----
    The minimum is ``T = ||(I - Phi (Phi^T Phi)^{-1} Phi^T) y||^2`` (the
    lecture's projection form, slide "Linjär regression;
    minstakvadrat-metoden").  Forming ``Phi^T Phi`` squares the condition
    number and fails when the regressors lack excitation, so the projection
    is computed from the thin SVD ``Phi = W S V^T``: with ``W_r`` the left
    singular vectors of the ``r`` non-negligible singular values,
    ``residual = y - W_r (W_r^T y)``, which is the orthogonal projection of
    ``y`` on the complement of range(Phi) whatever the rank; and
    ``theta = V_r S_r^{-1} W_r^T y`` is the minimum-norm minimiser.  Every
    minimiser gives the same residual (slide "Excitation": there is always
    one shortest distance from a point to a subspace).
    """
    Phi = as_matrix(Phi, "Phi")
    N, p = Phi.shape
    Y = _data(y, N)
    if p == 0:
        theta = np.zeros((0,) + Y.shape[1:])
        return _fit_result(theta, Y.copy(), 0, N, 0)
    left, s, right_t = np.linalg.svd(Phi, full_matrices=False)
    rank = _numerical_rank(s, N, p, rcond)
    W, V = left[:, :rank], right_t[:rank].T
    coords = W.T @ Y
    residual = Y - W @ coords
    scaled = coords / (s[:rank, None] if Y.ndim == 2 else s[:rank])
    theta = V @ scaled
    return _fit_result(theta, residual, rank, N, p)


def _fit_result(theta, residual, rank, N, p) -> RegressionFit:
    stat = np.sum(residual**2, axis=0)
    stat = float(stat) if residual.ndim == 1 else stat
    return RegressionFit(
        theta=theta,
        residual=residual,
        statistic=stat,
        rank=int(rank),
        dof=int(N - rank),
        n_parameters=int(p),
    )


def prediction_error(
    y, U, nominal, free: Sequence[int] = (), rcond: float | None = None
) -> RegressionFit:
    """Prediction-error test quantity ``T = min over theta in Theta_0 of ||y - U theta||^2``.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, M)
        Measurements (``M`` records as columns for a Monte Carlo study).
    U : array_like, shape (N, p)
        The signals ``u_i(t)`` of ``y(t) = sum_i theta_i u_i(t) + v(t)``.
    nominal : array_like, shape (p,)
        Fault-free parameter values.
    free : sequence of int, default ()
        Parameters left free under H0 (the faults the test decouples).  With
        no free parameters ``T = V(nominal, y)``, the prediction error of a
        single model.
    rcond : float, optional
        Rank tolerance, see :func:`least_squares_residual`.

    Returns
    -------
    RegressionFit
        ``theta`` is the full parameter vector (nominal values in the fixed
        places), ``statistic`` is ``T``.

    Notes
    -----
    ``V(theta, z) = sum_t (y(t) - yhat(t|theta))^2`` and
    ``T(z) = min over theta in Theta_0 of V(theta, z)`` (lecture, slide
    "Teststorhet baserad på prediktionsfelen").  With the fixed parameters
    moved to the left, ``y - U_fixed nominal_fixed = U_free theta_free + v``
    is a linear regression in the free parameters.

    Examples
    --------
    The lecture's test T1, H0: Fp in {NF, F1} (theta_1 free):

    >>> import numpy as np
    >>> U = np.array([[1., 0, 1], [2, 1, 0], [0, 1, 1], [1, 1, 1]])
    >>> y = U @ [3.0, 1, 1]           # a fault in theta_1 only
    >>> round(prediction_error(y, U, [1, 1, 1], free=[0]).statistic, 12)
    0.0
    """
    U, nominal = _model(U, nominal)
    free = _indices(free, U.shape[1])
    Y = _data(y, U.shape[0])
    Phi, known = _split(U, nominal, free)
    target = Y - (known[:, None] if Y.ndim == 2 else known)
    fit = least_squares_residual(target, Phi, rcond=rcond)
    theta = np.repeat(nominal[:, None], Y.shape[1], axis=1) if Y.ndim == 2 else nominal.copy()
    theta[free] = fit.theta
    return RegressionFit(
        theta=theta,
        residual=fit.residual,
        statistic=fit.statistic,
        rank=fit.rank,
        dof=fit.dof,
        n_parameters=len(free),
    )


def residual_threshold(alpha: float, dof: int, sigma: float = 1.0) -> float:
    """Threshold ``J`` on ``T = ||residual||^2`` with false-alarm rate ``alpha``.

    Parameters
    ----------
    alpha : float
        False-alarm probability ``P(T > J | H0)``.
    dof : int
        Residual degrees of freedom ``N - rank``.
    sigma : float, default 1
        Noise standard deviation.

    Returns
    -------
    float
        ``J = sigma^2 * chi2.isf(alpha, dof)``.

    Notes
    -----
    Under H0 the residual is ``(I - P) v`` with ``v ~ N(0, sigma^2 I)`` and
    ``I - P`` an orthogonal projection of rank ``N - rank(Phi)``, so
    ``T / sigma^2 ~ chi2(N - rank)`` (Cochran's theorem).  The lecture
    leaves threshold selection to the next lecture (last slide).  The
    argument order follows ``scipy.stats.chi2.isf(alpha, dof)``; for a
    windowed sum of normalised innovations use
    :func:`course.filters.windowed_nis_threshold`.
    """
    alpha = check_alpha(alpha)
    dof = _check_dof(dof)
    return float(_check_sigma(sigma) ** 2 * stats.chi2.isf(alpha, dof))


def prediction_error_test(
    y,
    U,
    nominal,
    free: Sequence[int] = (),
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str = "prediction-error test",
    rcond: float | None = None,
) -> TestResult:
    """Chi-square test of the prediction error ``T = min over Theta_0 ||y - U theta||^2``.

    Parameters
    ----------
    y : array_like, shape (N,)
        One record.
    U, nominal, free, rcond
        As in :func:`prediction_error`.
    sigma : float
        Known noise standard deviation.
    alpha : float, default 0.05
        False-alarm rate.
    name : str
        Name shown in the result.

    Returns
    -------
    TestResult
        ``statistic = T``, ``null = sigma^2 chi2(N - rank)``, critical value
        ``sigma^2 chi2.isf(alpha, N - rank)``; details hold the normalised
        statistic ``T / sigma^2`` and the rank.

    Raises
    ------
    ValueError
        Bad shapes or NaN, ``sigma <= 0``, or no redundancy (``N = rank``).

    Notes
    -----
    See :func:`residual_threshold` for the null law and :func:`prediction_error`
    for ``T``.
    """
    alpha = check_alpha(alpha)
    sigma = _check_sigma(sigma)
    y = as_vector(y, "y")
    fit = prediction_error(y, U, nominal, free, rcond=rcond)
    if fit.dof < 1:
        raise ValueError(_void_test_message(f"N = rank = {fit.rank}"))
    null = _scaled_chi2(fit.dof, sigma)
    crit = sigma**2 * stats.chi2.isf(alpha, fit.dof)
    stat = fit.statistic
    return TestResult(
        name=name,
        statistic=stat,
        alpha=alpha,
        critical_value=crit,
        pvalue=stats.chi2.sf(stat / sigma**2, fit.dof),
        reject=stat > crit,
        null=null,
        dof=fit.dof,
        alternative="greater",
        details={"T/sigma^2": stat / sigma**2, "rank": fit.rank},
    )


def fault_noncentrality(U, nominal, free: Sequence[int], theta, sigma: float = 1.0) -> Any:
    """Non-centrality of a test's ``T / sigma^2`` when the data come from ``theta``.

    Parameters
    ----------
    U, nominal, free
        The test, as in :func:`prediction_error`.
    theta : array_like, shape (p,) or (p, K)
        True parameter vector(s).
    sigma : float
        Noise standard deviation.

    Returns
    -------
    float or numpy.ndarray
        ``lambda = ||(I - P)(U (theta - nominal))||^2 / sigma^2``, one per column.

    Notes
    -----
    With ``y = U theta + v`` the residual of the test is
    ``(I - P)(U (theta - nominal)) + (I - P) v``: the fault part is a fixed
    vector, so ``T / sigma^2`` is non-central chi-square with this
    non-centrality.  The free parameters' deviations are annihilated by
    ``I - P``: the test is blind to them, which is the decoupling.  (Not to
    be confused with :func:`course.lsq.noncentrality`, the non-centrality a
    test *needs* for a given power.)
    """
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    free = _indices(free, U.shape[1])
    theta = as_float_array(theta, "theta")
    if theta.ndim not in (1, 2) or theta.shape[0] != U.shape[1]:
        raise ValueError(
            f"theta must have shape ({U.shape[1]},) or ({U.shape[1]}, K), got {theta.shape}"
        )
    shift = U @ (theta - (nominal[:, None] if theta.ndim == 2 else nominal))
    basis = _range_basis(U[:, free])
    leftover = shift - basis @ (basis.T @ shift)
    lam = np.sum(leftover**2, axis=0) / sigma**2
    return float(lam) if theta.ndim == 1 else lam


def prediction_error_power(
    U, nominal, free: Sequence[int], theta, *, sigma: float, alpha: float = 0.05
) -> Any:
    """Probability that the prediction-error test alarms when the truth is ``theta``.

    Parameters
    ----------
    U, nominal, free
        The test, as in :func:`prediction_error`.
    theta : array_like, shape (p,) or (p, K)
        True parameter vector(s), e.g. a fault of growing size.
    sigma : float
        Noise standard deviation.
    alpha : float
        False-alarm rate of the test.

    Returns
    -------
    float or numpy.ndarray
        ``P(T > J)`` with ``J`` the threshold of :func:`residual_threshold`;
        equal to ``alpha`` when the fault is invisible to the test.

    Notes
    -----
    ``T / sigma^2 ~ chi2'(N - rank, lambda)`` (non-central chi-square, see
    :func:`fault_noncentrality`), so the power is
    ``ncx2.sf(chi2.isf(alpha, dof), dof, lambda)``: the answer to the
    lecture's closing question "how good is a test?".
    """
    alpha = check_alpha(alpha)
    U, nominal = _model(U, nominal)
    free = _indices(free, U.shape[1])
    lam = np.asarray(fault_noncentrality(U, nominal, free, theta, sigma))
    dof = U.shape[0] - _range_basis(U[:, free]).shape[1]
    if dof < 1:
        raise ValueError(_void_test_message(f"N - rank = {dof}"))
    crit = stats.chi2.isf(alpha, dof)
    power = np.where(lam > 0, stats.ncx2.sf(crit, dof, np.maximum(lam, 1e-300)), alpha)
    return float(power) if power.ndim == 0 else power


# ---------------------------------------------------------------------------
# prediction errors: general models
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class NonlinearFit:
    """Result of :func:`nonlinear_prediction_error`.

    Attributes
    ----------
    theta : numpy.ndarray
        Minimising full parameter vector (nominal values in fixed places).
    residual : numpy.ndarray
        ``y - yhat(theta)`` (flattened).
    statistic : float
        ``T = ||residual||^2``.
    success : bool
        Whether the optimiser reported convergence.
    message : str
        The optimiser's message.
    jacobian : numpy.ndarray
        Jacobian of the prediction w.r.t. the free parameters at the optimum.
    """

    theta: np.ndarray
    residual: np.ndarray
    statistic: float
    success: bool
    message: str
    jacobian: np.ndarray

    def __repr__(self) -> str:
        return (
            f"NonlinearFit(statistic={format_number(self.statistic)}, "
            f"theta=[{', '.join(format_number(float(v)) for v in self.theta)}], success={self.success})"
        )


def nonlinear_prediction_error(
    y,
    predict: Callable,
    nominal,
    free: Sequence[int] = (),
    *,
    theta_init=None,
    bounds=None,
    **options,
) -> NonlinearFit:
    """``T = min over theta in Theta_0 of sum_t ||y(t) - yhat(t|theta)||^2`` for any model.

    Parameters
    ----------
    y : array_like
        Measurements (any shape; compared element-wise with the prediction).
    predict : callable
        ``predict(theta)`` returns ``yhat(theta)`` with the shape of ``y``,
        for a full parameter vector ``theta``.
    nominal : array_like, shape (p,)
        Values of the parameters that are fixed under H0.
    free : sequence of int, default ()
        Parameters estimated under H0.
    theta_init : array_like, optional
        Starting values of the free parameters (their nominal values by default).
    bounds : (lower, upper), optional
        Bounds on the free parameters, as for :func:`scipy.optimize.least_squares`.
    **options
        Passed to :func:`scipy.optimize.least_squares` (e.g. ``x_scale``).

    Returns
    -------
    NonlinearFit

    Notes
    -----
    The general form of the lecture's prediction-error test quantity (slide
    "Minimering av V(θ, z)": general optimisation, system identification).
    The minimisation is local (trust-region reflective): for a criterion
    with several minima, start from several ``theta_init`` and keep the
    smallest ``T``.
    """
    nominal = as_vector(nominal, "nominal")
    p = nominal.size
    free = _indices(free, p)
    y = as_float_array(y, "y")

    def full(theta_free):
        theta = nominal.copy()
        theta[free] = theta_free
        return theta

    def residual(theta_free):
        pred = np.asarray(predict(full(theta_free)), dtype=float)
        if pred.shape != y.shape:
            raise ValueError(f"predict returned shape {pred.shape}, but y has shape {y.shape}")
        return (y - pred).ravel()

    if not free:
        r = residual(np.zeros(0))
        return NonlinearFit(
            theta=nominal.copy(),
            residual=r,
            statistic=float(r @ r),
            success=True,
            message="no free parameters",
            jacobian=np.zeros((r.size, 0)),
        )
    start = nominal[free] if theta_init is None else as_vector(theta_init, "theta_init", len(free))
    kwargs = dict(options)
    if bounds is not None:
        kwargs["bounds"] = bounds
    kwargs.setdefault("xtol", 1e-12)
    kwargs.setdefault("ftol", 1e-12)
    kwargs.setdefault("gtol", 1e-12)
    sol = optimize.least_squares(residual, start, **kwargs)
    r = residual(sol.x)
    return NonlinearFit(
        theta=full(sol.x),
        residual=r,
        statistic=float(r @ r),
        success=bool(sol.success),
        message=str(sol.message),
        jacobian=-sol.jac,
    )
