"""Test quantities from prediction errors: linear regressions and general models.

Source: the LiU lecture on test quantities (Linköping University, Swedish
slides; full reference in the course bibliography, :doc:`/docs/bibliography`),
slides "Teststorhet baserad på prediktionsfelen" and "Linjär regression".
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from course.chi2 import chi2_power, residual_norm_law
from course.chi2 import residual_threshold as residual_threshold
from course.diagnosis._common import (
    _answer,
    _check_sigma,
    _indices,
    _model,
    _parameter_vectors,
    _records,
    _split,
    _void_test_message,
)
from course.linalg import lstsq_min_norm, range_basis
from course.results import TestResult, format_number
from course.validation import (
    as_callable,
    as_float_array,
    as_matrix,
    as_positive,
    as_probability,
    as_vector,
)


@dataclass(frozen=True, repr=False, eq=False)
class RegressionFit:
    """Least-squares fit of a linear regression that may lack excitation.

    Attributes
    ----------
    theta : numpy.ndarray
        A minimising parameter vector, ``(p,)``, or one per record, ``(M, p)``:
        the unique one when ``rank == p``, else the one of smallest norm (any
        other differs by a null-space vector of the regressors and fits
        equally well).
    residual : numpy.ndarray
        ``y - Phi theta`` (unique even when theta is not), ``(N,)`` or ``(M, N)``.
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


def least_squares_residual(Phi: Any, y: Any, rcond: float | None = None) -> RegressionFit:
    r"""``min over theta of ||y - Phi theta||^2``, correct also without excitation.

    Parameters
    ----------
    Phi : array_like, shape (N, p)
        Regressor matrix; it may be rank deficient and ``p`` may be 0.
    y : array_like, shape (N,) or (M, N)
        One record, or ``M`` records as rows.
    rcond : float, optional
        Singular values below ``rcond * s_max`` count as zero; by default
        ``max(N, p) * eps`` (the course's rank rule,
        :func:`course.linalg.rank_tolerance`).

    Returns
    -------
    RegressionFit

    See Also
    --------
    prediction_error : The test quantity built on it.
    course.linalg.lstsq_min_norm : The solver it uses.

    Notes
    -----
    The minimum is (the lecture's projection form, slide "Linjär regression;
    minstakvadrat-metoden")

    .. math::

        T = \lVert (I - \Phi (\Phi^{\mathsf T}\Phi)^{-1} \Phi^{\mathsf T}) y \rVert^2 .

    Forming :math:`\Phi^{\mathsf T}\Phi` squares the condition number and fails
    when the regressors lack excitation, so the projection is computed from the
    thin SVD (:func:`course.linalg.lstsq_min_norm`):
    :math:`\text{residual} = y - W_r (W_r^{\mathsf T} y)` with :math:`W_r` the
    left singular vectors of the :math:`r` non-negligible singular values, the
    orthogonal projection of :math:`y` on the complement of
    :math:`\operatorname{range}(\Phi)` whatever the rank, and
    :math:`\theta = V_r S_r^{-1} W_r^{\mathsf T} y`, the minimum-norm minimiser.
    Every minimiser gives the same residual (slide "Excitation": there is
    always one shortest distance from a point to a subspace).

    The regressors come first, as in :func:`course.lsq.fit` and
    :func:`course.filters.recursive_least_squares`.

    Examples
    --------
    Two identical regressors (no excitation to tell them apart):

    >>> import numpy as np
    >>> Phi = np.column_stack([np.ones(4), np.ones(4)])
    >>> fit = least_squares_residual(Phi, [1.0, 2.0, 3.0, 4.0])
    >>> fit.rank, fit.unique, round(fit.statistic, 10)
    (1, False, 5.0)
    """
    Phi = as_matrix(Phi, "Phi")
    N, p = Phi.shape
    Y, layout = _records(y, N)
    theta, residual, rank = _lstsq_columns(Phi, Y, rcond)
    return _fit_result(theta, residual, rank, N, p, layout)


def _lstsq_columns(Phi: np.ndarray, Y: np.ndarray, rcond: float | None):
    if rcond is not None:
        rcond = as_positive(rcond, "rcond", what="the relative rank tolerance")
    solution = lstsq_min_norm(Phi, Y, rcond)
    return solution.x, solution.residual, solution.rank


def _fit_result(theta, residual, rank, N, p, layout) -> RegressionFit:
    stat = np.sum(residual**2, axis=0)
    stat = float(stat) if residual.ndim == 1 else stat
    return RegressionFit(
        theta=_answer(theta, layout),
        residual=_answer(residual, layout),
        statistic=stat,
        rank=int(rank),
        dof=int(N - rank),
        n_parameters=int(p),
    )


def prediction_error(
    y: Any, U: Any, nominal: Any, free: Sequence[int] = (), rcond: float | None = None
) -> RegressionFit:
    r"""Prediction-error test quantity ``T = min over theta in Theta_0 of ||y - U theta||^2``.

    Parameters
    ----------
    y : array_like, shape (N,) or (M, N)
        Measurements (``M`` records as rows for a Monte Carlo study).
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
        places; ``(M, p)`` for ``M`` records), ``statistic`` is ``T``.

    See Also
    --------
    prediction_error_test : The test of this quantity.
    least_squares_residual : The projection it computes.
    nonlinear_prediction_error : The same for a nonlinear model.

    Notes
    -----
    .. math::

        V(\theta, z) = \sum_t \bigl(y(t) - \hat y(t \mid \theta)\bigr)^2, \qquad
        T(z) = \min_{\theta \in \Theta_0} V(\theta, z)

    (LiU lecture, slide "Teststorhet baserad på prediktionsfelen").  With the
    fixed parameters moved to the left,
    :math:`y - U_{\text{fixed}}\theta_{\text{fixed}} = U_{\text{free}}\theta_{\text{free}} + v`
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
    Y, layout = _records(y, U.shape[0])
    Phi, known = _split(U, nominal, free)
    target = Y - (known[:, None] if Y.ndim == 2 else known)
    theta_free, residual, rank = _lstsq_columns(Phi, target, rcond)
    theta = np.repeat(nominal[:, None], Y.shape[1], axis=1) if Y.ndim == 2 else nominal.copy()
    theta[free] = theta_free
    fit = _fit_result(theta, residual, rank, U.shape[0], len(free), layout)
    return fit


def prediction_error_test(
    y: Any,
    U: Any,
    nominal: Any,
    free: Sequence[int] = (),
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str = "prediction-error test",
    rcond: float | None = None,
) -> TestResult:
    r"""Chi-square test of the prediction error ``T = min over Theta_0 ||y - U theta||^2``.

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

    See Also
    --------
    prediction_error : The test quantity.
    prediction_error_power : Its power against a fault.
    course.chi2.residual_norm_law : Its null law.

    Notes
    -----
    Under H0, :math:`T/\sigma^2 \sim \chi^2(N - \operatorname{rank} U_{\text{free}})`;
    see :func:`course.chi2.residual_norm_law` for the null law and
    :func:`prediction_error` for :math:`T`.

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(5), np.arange(5.0)])
    >>> y = np.array([0.1, 1.0, 1.9, 3.2, 3.9])
    >>> prediction_error_test(y, U, [0.0, 1.0], free=[0], sigma=0.1).reject
    False
    """
    alpha = as_probability(alpha)
    sigma = _check_sigma(sigma)
    y = as_vector(y, "y")
    fit = prediction_error(y, U, nominal, free, rcond=rcond)
    if fit.dof < 1:
        raise ValueError(_void_test_message(f"N = rank = {fit.rank}"))
    stat = fit.statistic
    return TestResult.from_null(
        name,
        stat,
        residual_norm_law(fit.dof, sigma=sigma),
        alpha,
        dof=fit.dof,
        details={"T/sigma^2": stat / sigma**2, "rank": fit.rank},
    )


def fault_noncentrality(
    U: Any, nominal: Any, free: Sequence[int], theta: Any, *, sigma: float = 1.0
) -> Any:
    r"""Non-centrality of a test's ``T / sigma^2`` when the data come from ``theta``.

    Parameters
    ----------
    U, nominal, free
        The test, as in :func:`prediction_error`.
    theta : array_like, shape (p,) or (K, p)
        True parameter vector(s), one per row.
    sigma : float, default 1
        Noise standard deviation (keyword-only).

    Returns
    -------
    float or numpy.ndarray
        ``lambda = ||(I - P)(U (theta - nominal))||^2 / sigma^2``, one per vector.

    See Also
    --------
    prediction_error_power : The power this non-centrality gives.
    course.chi2.noncentrality : The non-centrality a test needs for a given power.

    Notes
    -----
    With :math:`y = U\theta + v` the residual of the test is

    .. math::

        (I - P)\,U(\theta - \theta_{\text{nominal}}) + (I - P)\,v,
        \qquad \lambda = \frac{\lVert (I - P)\,U(\theta - \theta_{\text{nominal}}) \rVert^2}{\sigma^2}:

    the fault part is a fixed vector, so :math:`T/\sigma^2` is non-central
    chi-square with this non-centrality.  The free parameters' deviations are
    annihilated by :math:`I - P`: the test is blind to them, which is the
    decoupling.  (Not to be confused with :func:`course.chi2.noncentrality`,
    the non-centrality a test *needs* for a given power.)

    Examples
    --------
    >>> import numpy as np
    >>> U = np.eye(3)
    >>> fault_noncentrality(U, [1, 1, 1], [0], [[5.0, 1, 1], [1, 2.0, 1]], sigma=0.5)
    array([0., 4.])
    """
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    free = _indices(free, U.shape[1])
    theta, several = _parameter_vectors(theta, U.shape[1])
    shift = U @ (theta - (nominal[:, None] if several else nominal))
    basis = range_basis(U[:, free])
    leftover = shift - basis @ (basis.T @ shift)
    lam = np.sum(leftover**2, axis=0) / sigma**2
    return lam if several else float(lam)


def prediction_error_power(
    U: Any,
    nominal: Any,
    free: Sequence[int],
    theta: Any,
    *,
    sigma: float,
    alpha: float = 0.05,
) -> Any:
    r"""Probability that the prediction-error test alarms when the truth is ``theta``.

    Parameters
    ----------
    U, nominal, free
        The test, as in :func:`prediction_error`.
    theta : array_like, shape (p,) or (K, p)
        True parameter vector(s), one per row (e.g. a fault of growing size).
    sigma : float
        Noise standard deviation.
    alpha : float
        False-alarm rate of the test.

    Returns
    -------
    float or numpy.ndarray
        ``P(T > J)`` with ``J`` the threshold of
        :func:`course.chi2.residual_threshold`; equal to ``alpha`` when the
        fault is invisible to the test.

    See Also
    --------
    fault_noncentrality : The non-centrality of a fault.
    prediction_error_test : The test whose power this is.

    Notes
    -----
    :math:`T/\sigma^2 \sim \chi'^2(N - \operatorname{rank}, \lambda)`
    (non-central chi-square, see :func:`fault_noncentrality`), so the power is

    .. math::

        P\bigl(\chi'^2(N - \operatorname{rank}, \lambda) > J/\sigma^2\bigr),

    :func:`course.chi2.chi2_power`: the answer to the lecture's closing
    question "how good is a test?".

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(20), np.linspace(0, 1, 20)])
    >>> prediction_error_power(U, [1, 1], [0], [[1, 1.0], [1, 1.5]], sigma=0.3).round(3)
    array([0.05 , 0.203])
    """
    alpha = as_probability(alpha)
    U, nominal = _model(U, nominal)
    free = _indices(free, U.shape[1])
    theta, several = _parameter_vectors(theta, U.shape[1])
    lam = fault_noncentrality(U, nominal, free, theta.T if several else theta, sigma=sigma)
    dof = U.shape[0] - range_basis(U[:, free]).shape[1]
    if dof < 1:
        raise ValueError(_void_test_message(f"N - rank = {dof}"))
    return chi2_power(dof, lam, alpha)


# ---------------------------------------------------------------------------
# prediction errors: general models
# ---------------------------------------------------------------------------
def _bounds(bounds: Any, n: int, name: str) -> list[tuple[float, float]] | None:
    """``None`` or one ``(low, high)`` pair per parameter; ``None`` or +-inf means unbounded."""
    if bounds is None:
        return None
    if isinstance(bounds, (str, bytes)) or not isinstance(bounds, Sequence | np.ndarray):
        raise ValueError(
            f"{name} must be a list of (low, high) pairs, one per parameter; got {bounds!r}"
        )
    pairs = list(bounds)
    if len(pairs) != n:
        raise ValueError(
            f"{name} must hold {n} (low, high) pairs, one per parameter, got {len(pairs)}"
        )
    out = []
    for j, pair in enumerate(pairs):
        try:
            low, high = pair
            low = -np.inf if low is None else float(low)
            high = np.inf if high is None else float(high)
        except (TypeError, ValueError):
            raise ValueError(f"{name}[{j}] must be a pair (low, high), got {pair!r}") from None
        if np.isnan(low) or np.isnan(high) or not low < high:
            raise ValueError(f"{name}[{j}] = ({low}, {high}) needs low < high (None for no bound)")
        out.append((low, high))
    return out


def _lower_upper(bounds: Any, n: int, name: str) -> tuple[np.ndarray, np.ndarray] | None:
    """``None`` or ``(lower, upper)``, each a number or one value per parameter (least_squares)."""
    if bounds is None:
        return None
    try:
        lower, upper = bounds
        lower = np.broadcast_to(np.asarray(lower, dtype=float), (n,)).copy()
        upper = np.broadcast_to(np.asarray(upper, dtype=float), (n,)).copy()
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be (lower, upper), each a number or {n} values (one per free "
            f"parameter), as for scipy.optimize.least_squares; got {bounds!r}"
        ) from None
    if np.isnan(lower).any() or np.isnan(upper).any() or not np.all(lower < upper):
        raise ValueError(f"{name} needs lower < upper (np.inf for no bound), got {bounds!r}")
    return lower, upper


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
    r"""``T = min over theta in Theta_0 of sum_t ||y(t) - yhat(t|theta)||^2`` for any model.

    Parameters
    ----------
    y : array_like
        Measurements (any shape; compared element-wise with the prediction).
    predict : callable
        ``predict(theta)`` returns ``yhat(theta)`` with the shape of ``y``,
        for a full parameter vector ``theta``; finite where the fit starts
        (elsewhere a NaN or inf makes the optimiser take a shorter step).
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

    See Also
    --------
    prediction_error : The linear case, solved exactly.

    Notes
    -----
    The general form of the lecture's prediction-error test quantity (LiU
    lecture, slide "Minimering av V(θ, z)": general optimisation, system
    identification),
    :math:`T(z) = \min_\theta \sum_t \bigl(y(t) - \hat y(t \mid \theta)\bigr)^2`.
    The minimisation is local (trust-region reflective): for a criterion with
    several minima, start from several ``theta_init`` and keep the smallest
    :math:`T`.

    Examples
    --------
    >>> import numpy as np
    >>> u = np.linspace(0.0, 3.0, 40)
    >>> def predict(theta):
    ...     return theta[0] * (1.0 - np.exp(-theta[1] * u))
    >>> fit = nonlinear_prediction_error(predict([2.0, 1.4]), predict, [2.0, 1.0], free=[1])
    >>> round(float(fit.theta[1]), 6), round(fit.statistic, 12)
    (1.4, 0.0)
    """
    predict = as_callable(predict, "predict")
    nominal = as_vector(nominal, "nominal")
    p = nominal.size
    free = _indices(free, p)
    y = as_float_array(y, "y", empty=False)
    bounds = _lower_upper(bounds, len(free), "bounds")

    def full(theta_free):
        theta = nominal.copy()
        theta[free] = theta_free
        return theta

    try:
        first = np.shape(predict(nominal.copy()))
    except Exception as exc:
        raise ValueError(
            f"predict(nominal) raised {type(exc).__name__}: {exc}; check that nominal holds the "
            f"{p} parameters predict expects"
        ) from exc
    if first != y.shape:
        raise ValueError(f"predict(nominal) returned shape {first}, but y has shape {y.shape}")

    def residual(theta_free):
        pred = np.asarray(predict(full(theta_free)), dtype=float)
        if pred.shape != y.shape:
            raise ValueError(f"predict returned shape {pred.shape}, but y has shape {y.shape}")
        return (y - pred).ravel()

    def finite_residual(theta_free, where: str):
        # Checked at the start only: scipy shrinks a trial step whose prediction is not finite.
        r = residual(theta_free)
        if not np.all(np.isfinite(r)):
            raise ValueError(
                f"predict returned NaN or inf at {where} theta = {full(theta_free).tolist()} "
                f"({int(np.sum(~np.isfinite(r)))} of {r.size} values): the prediction must be "
                "finite where the fit starts; check predict and the parameter values "
                "(nominal, theta_init)"
            )
        return r

    if not free:
        r = finite_residual(np.zeros(0), "the nominal")
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
    finite_residual(start, "the starting")
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
