"""Test quantities from the likelihood: ML, GLR, Neyman-Pearson, Bayes ranking of faults.

Source: the LiU lecture on test quantities (Linköping University, Swedish
slides; full reference in the course bibliography, :doc:`/docs/bibliography`),
slides "Likelihood-funktionen" to "Likelihood och Bayes".
"""

from __future__ import annotations

import dataclasses
import html
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize, special, stats

from course._law_inputs import _levels
from course.chi2 import residual_norm_law
from course.diagnosis._common import _check_sigma, _indices, _model, _void_test_message
from course.diagnosis._prediction_error import prediction_error
from course.distributions import FrozenDistribution
from course.linalg import cholesky_lower, whiten
from course.results import TestResult, format_number
from course.validation import (
    InputTypeError,
    as_callable,
    as_count,
    as_finite,
    as_float_array,
    as_matrix,
    as_positive,
    as_probability,
    as_vector,
)


# ---------------------------------------------------------------------------
# likelihood
# ---------------------------------------------------------------------------
def normal_log_likelihood(theta: Any, z: Any, *, sigma: float = 1.0) -> Any:
    r"""``log L(theta | z)`` for independent ``z_i ~ N(theta, sigma^2)``.

    Parameters
    ----------
    theta : float or array_like
        Parameter value(s); an array gives the log-likelihood on a grid.
    z : float or array_like
        The observations.
    sigma : float, default 1
        Noise standard deviation (keyword-only).

    Returns
    -------
    float or numpy.ndarray, shaped like ``theta``

    See Also
    --------
    normal_likelihood : The likelihood itself.
    maximum_likelihood : Its maximiser.

    Notes
    -----
    .. math::

        L(\theta \mid z) = f(z \mid \theta)
        = \prod_i (2\pi\sigma^2)^{-1/2} \exp\!\left(-\frac{(z_i - \theta)^2}{2\sigma^2}\right)

    (lecture, slides "Likelihood-funktionen, normalfördelning": independence
    makes the joint density the product).  Working with the logarithm avoids
    underflow for many observations.

    Examples
    --------
    The lecture's two observations z = (3, 5): the maximum is at theta = 4.

    >>> round(normal_log_likelihood(4.0, [3.0, 5.0]), 6)
    -2.837877
    """
    # In logs and in units of sigma, so that sigma = 1e300 or 1e-300 cannot overflow:
    # log L = -N/2 log(2 pi) - N log(sigma) - sum(((z - theta) / sigma)^2) / 2, which is
    # -inf (not NaN) when the data lie further than ~1e154 sigma from theta.
    sigma = as_positive(sigma, "sigma", what="the noise standard deviation")
    z = np.atleast_1d(as_float_array(z, "z", empty=False)).ravel()
    theta = as_float_array(theta, "theta", empty=False)
    with np.errstate(over="ignore"):
        scaled = (z[..., :] - theta[..., None]) / sigma if theta.ndim else (z - theta) / sigma
        sq = np.sum(scaled**2, axis=-1)
    value = -0.5 * z.size * np.log(2 * np.pi) - z.size * np.log(sigma) - 0.5 * sq
    return float(value) if np.ndim(value) == 0 else value


def normal_likelihood(theta: Any, z: Any, *, sigma: float = 1.0) -> Any:
    r"""``L(theta | z) = f(z | theta)`` for independent ``z_i ~ N(theta, sigma^2)``.

    Parameters
    ----------
    theta : float or array_like
        Parameter value(s); an array gives the likelihood on a grid.
    z : float or array_like
        The observations.
    sigma : float, default 1
        Noise standard deviation (keyword-only).

    Returns
    -------
    float or numpy.ndarray, shaped like ``theta``

    See Also
    --------
    normal_log_likelihood : The same in logarithms, safe for long records.

    Notes
    -----
    .. math::

        L(\theta \mid z) = \prod_i (2\pi\sigma^2)^{-1/2}
        \exp\!\left(-\frac{(z_i - \theta)^2}{2\sigma^2}\right)

    (lecture, slides "Likelihood-funktionen, normalfördelning"), computed as
    the exponential of :func:`normal_log_likelihood`.  For :math:`z = (3, 5)`
    and :math:`\sigma = 1` the maximum is :math:`L(4) = e^{-1}/(2\pi)`.
    Underflows to 0 for long records: use the log-likelihood there.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(normal_likelihood(4.0, [3.0, 5.0]), np.exp(-1) / (2 * np.pi)))
    True
    """
    value = np.exp(normal_log_likelihood(theta, z, sigma=sigma))
    return float(value) if np.ndim(value) == 0 else value


@dataclass(frozen=True, repr=False, eq=False)
class MLResult:
    """Result of :func:`maximum_likelihood`.

    Attributes
    ----------
    theta : numpy.ndarray
        Maximiser (full vector, nominal values in fixed places).
    log_likelihood : float
        The maximum of ``log L``.
    success : bool
    message : str
    """

    theta: np.ndarray
    log_likelihood: float
    success: bool
    message: str

    def __repr__(self) -> str:
        return (
            f"MLResult(theta=[{', '.join(format_number(float(v)) for v in self.theta)}], "
            f"log_likelihood={format_number(self.log_likelihood)}, success={self.success})"
        )


_MINIMIZE_METHODS = (
    "nelder-mead", "powell", "cg", "bfgs", "newton-cg", "l-bfgs-b", "tnc", "cobyla",
    "cobyqa", "slsqp", "trust-constr", "dogleg", "trust-ncg", "trust-exact", "trust-krylov",
)  # fmt: skip


def _method(method: Any) -> Any:
    """A :func:`scipy.optimize.minimize` method: None, one of its names, or a callable."""
    if method is None or callable(method):
        return method
    if not isinstance(method, str) or method.lower() not in _MINIMIZE_METHODS:
        raise ValueError(
            f"method must be None or a scipy.optimize.minimize method {_MINIMIZE_METHODS}, "
            f"got {method!r}"
        )
    return method


def _pair_bounds(bounds: Any, n: int, name: str) -> list[tuple[float, float]] | None:
    """``None`` or one ``(low, high)`` pair per parameter; ``None`` in a pair means unbounded."""
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
            low_f = -np.inf if low is None else float(low)
            high_f = np.inf if high is None else float(high)
        except (TypeError, ValueError):
            raise ValueError(f"{name}[{j}] must be a pair (low, high), got {pair!r}") from None
        if np.isnan(low_f) or np.isnan(high_f) or not low_f < high_f:
            raise ValueError(f"{name}[{j}] = {pair!r} needs low < high (None for no bound)")
        out.append((low, high))
    return out


def _first_call(log_likelihood: Callable, nominal: np.ndarray) -> None:
    """Call the user's function once at ``nominal`` so that a mismatch is reported clearly."""
    try:
        value = log_likelihood(nominal.copy())
        float(value)
    except Exception as exc:
        raise ValueError(
            f"log_likelihood(nominal) raised {type(exc).__name__}: {exc}; it must take a full "
            f"parameter vector (here nominal, {nominal.size} values) and return a number"
        ) from exc


def maximum_likelihood(
    log_likelihood: Callable,
    nominal,
    free: Sequence[int] | None = None,
    *,
    theta_init=None,
    bounds=None,
    method: str | None = None,
) -> MLResult:
    r"""Maximise ``log L(theta | z)`` over ``Theta_0`` numerically.

    Parameters
    ----------
    log_likelihood : callable
        ``log_likelihood(theta) -> float`` for a full parameter vector (the
        data are bound inside, e.g. with a lambda).
    nominal : array_like, shape (p,)
        Values of the parameters not in ``free``; also the default start.
    free : sequence of int, optional
        Parameters to maximise over; all of them by default.
    theta_init : array_like, optional
        Start for the free parameters.
    bounds : sequence of (low, high), optional
        Bounds of the free parameters.
    method : str, optional
        :func:`scipy.optimize.minimize` method (BFGS, or L-BFGS-B with bounds).

    Returns
    -------
    MLResult

    See Also
    --------
    normal_log_likelihood : A log-likelihood to maximise.
    glr_test : The test built on maximised likelihoods.

    Notes
    -----
    :math:`\hat\theta_{ML} = \arg\max_\theta L(\theta \mid z)` (lecture, slide
    "Teststorheter baserade på likelihood-funktionen, forts.").  The optimiser
    minimises :math:`-\log L`; it is local, so start it near the answer (a
    moment estimate, or a grid search) when the likelihood has several modes.

    Examples
    --------
    >>> ml = maximum_likelihood(lambda th: normal_log_likelihood(th[0], [3.0, 5.0]), [0.0])
    >>> round(float(ml.theta[0]), 6)
    4.0
    """
    log_likelihood = as_callable(log_likelihood, "log_likelihood")
    nominal = as_vector(nominal, "nominal")
    p = nominal.size
    free = list(range(p)) if free is None else _indices(free, p)
    bounds = _pair_bounds(bounds, len(free), "bounds")
    method = _method(method)
    _first_call(log_likelihood, nominal)

    def full(theta_free):
        theta = nominal.copy()
        theta[free] = theta_free
        return theta

    if not free:
        value = float(log_likelihood(nominal.copy()))
        return MLResult(
            theta=nominal.copy(), log_likelihood=value, success=True, message="no free parameters"
        )
    start = nominal[free] if theta_init is None else as_vector(theta_init, "theta_init", len(free))

    def objective(theta_free):
        value = float(log_likelihood(full(theta_free)))
        return np.inf if np.isnan(value) else -value

    sol = optimize.minimize(
        objective,
        start,
        method=method,
        bounds=bounds,
        options={"gtol": 1e-10} if method in (None, "BFGS") and bounds is None else None,
    )
    # BFGS often reports a precision loss at an optimum it cannot improve;
    # a polish by Nelder-Mead from there makes the answer trustworthy.
    if not sol.success and bounds is None:
        sol = optimize.minimize(
            objective,
            sol.x,
            method="Nelder-Mead",
            options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000},
        )
    return MLResult(
        theta=full(sol.x),
        log_likelihood=float(-sol.fun),
        success=bool(sol.success),
        message=str(sol.message),
    )


class LogLikelihoodLaw(FrozenDistribution):
    """Law of ``c - chi2(dof) / 2``: the maximised Gaussian log-likelihood under H0.

    Parameters
    ----------
    dof : int
        Residual degrees of freedom ``N - rank``.
    c : float
        The log-likelihood of a perfect fit, ``-(N/2) log(2 pi sigma^2)``.

    Examples
    --------
    >>> law = LogLikelihoodLaw(3, -1.0)
    >>> law.support(), law.mean()
    ((-inf, -1.0), -2.5)
    """

    def __init__(self, dof: int, c: float):
        self.dof = as_count(dof, "dof", what="the residual degrees of freedom")
        self.c = as_finite(c, "c")
        self._bounds = (-np.inf, self.c)

    def _cdf(self, x):
        return stats.chi2.sf(2 * (self.c - x), self.dof)

    def _sf(self, x):
        return stats.chi2.cdf(2 * (self.c - x), self.dof)

    def _pdf(self, x):
        return 2 * stats.chi2.pdf(2 * (self.c - x), self.dof)

    def _rvs(self, size, rng):
        return self.c - 0.5 * rng.chisquare(self.dof, size=size)

    def ppf(self, q):
        return self.c - 0.5 * stats.chi2.isf(_levels(q), self.dof)

    def isf(self, q):
        return self.c - 0.5 * stats.chi2.ppf(_levels(q), self.dof)

    def mean(self):
        return self.c - 0.5 * self.dof

    def var(self):
        return 0.5 * self.dof

    def __repr__(self) -> str:
        return f"c - chi2({self.dof})/2 with c = {format_number(self.c)}"


def likelihood_test(
    y,
    U,
    nominal,
    free: Sequence[int] = (),
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str = "maximum-likelihood test",
) -> TestResult:
    r"""The lecture's likelihood test quantity ``T = max over Theta_0 of L``, reject when small.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal, free
        As in :func:`prediction_error`; the model is ``y = U theta + v``,
        ``v ~ N(0, sigma^2 I)``.
    sigma : float
    alpha : float

    Returns
    -------
    TestResult
        ``statistic = log max L`` (the log of the lecture's ``T``, which
        underflows for long records), ``alternative="less"``: H0 is
        rejected when the best achievable likelihood is *below* the
        critical value.

    See Also
    --------
    prediction_error_test : The test that makes the same decisions.
    glr_test : The likelihood ratio against an alternative.

    Notes
    -----
    For this model

    .. math::

        \max_{\theta \in \Theta_0} \log L = -\frac N2 \log(2\pi\sigma^2)
        - \frac{T_{pe}}{2\sigma^2}

    with :math:`T_{pe}` the prediction error of :func:`prediction_error`: the
    likelihood test and the prediction-error test make the same decisions.
    The null law is :math:`c - \chi^2(N - \operatorname{rank})/2` (lecture,
    "Teststorheter baserade på likelihood-funktionen, forts.": "H0 is rejected
    when T(z) is below a threshold").

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(5), np.arange(5.0)])
    >>> y = np.array([0.1, 1.0, 1.9, 3.2, 3.9])
    >>> result = likelihood_test(y, U, [0.0, 1.0], [0], sigma=0.1)
    >>> result.alternative, result.reject
    ('less', False)
    """
    alpha = as_probability(alpha)
    sigma = _check_sigma(sigma)
    y = as_vector(y, "y")
    fit = prediction_error(y, U, nominal, free)
    if fit.dof < 1:
        raise ValueError(_void_test_message(f"N = rank = {fit.rank}"))
    c = -0.5 * y.size * np.log(2 * np.pi * sigma**2)
    stat = c - fit.statistic / (2 * sigma**2)
    return TestResult.from_null(
        name,
        stat,
        LogLikelihoodLaw(fit.dof, c),
        alpha,
        "less",
        dof=fit.dof,
        details={"prediction error T": fit.statistic},
    )


def glr_test(
    log_likelihood: Callable,
    nominal,
    free0: Sequence[int] = (),
    free1: Sequence[int] | None = None,
    *,
    alpha: float = 0.05,
    theta_init=None,
    bounds=None,
    name: str = "generalised likelihood ratio test",
) -> TestResult:
    r"""Generalised likelihood ratio test, calibrated by Wilks' theorem.

    Parameters
    ----------
    log_likelihood : callable
        ``log_likelihood(theta) -> float`` for a full parameter vector.
    nominal : array_like, shape (p,)
        Values of the parameters fixed under H0.
    free0 : sequence of int, default ()
        Parameters free under H0.
    free1 : sequence of int, optional
        Parameters free under H1 (a superset of ``free0``); all by default.
    alpha : float
    theta_init : array_like, shape (p,), optional
        Start of both maximisations (``nominal`` by default).
    bounds : sequence of (low, high) for all p parameters, optional

    Returns
    -------
    TestResult
        ``statistic = 2 (max_{Theta_1} log L - max_{Theta_0} log L)``,
        ``null = chi2(|free1| - |free0|)``.

    See Also
    --------
    linear_glr_test : The exact law for a linear-Gaussian model.
    neyman_pearson_test : The most powerful test of two simple hypotheses.

    Notes
    -----
    .. math::

        \Lambda = \frac{\max_{\Theta_0} L}{\max_{\Theta_1} L}, \qquad
        -2 \log \Lambda \;\xrightarrow{d}\; \chi^2(\dim\Theta_1 - \dim\Theta_0)

    under H0 (Wilks 1938) when the hypotheses are nested, the true parameter
    is an *interior* point, the model is identifiable with a non-singular
    Fisher information, and the sample is large.  It fails, for example, when
    the null value lies on the boundary (a fault size restricted to be
    :math:`\ge 0` gives a 50:50 mixture of 0 and :math:`\chi^2(1)`), or when a
    parameter is meaningless under H0 (the onset time of a fault of size 0).
    For a linear-Gaussian model with known variance the law is exact:
    :func:`linear_glr_test`.  The lecture mentions generalised Neyman-Pearson
    results for composite hypotheses (slide "Neyman-Pearson lemma,
    likelihood-kvot").

    Examples
    --------
    The rate of exponential data: ``-2 log Lambda`` against Wilks' ``chi2(1)``.

    >>> import numpy as np
    >>> z = np.array([0.5, 1.7, 0.9, 1.2, 0.3, 2.1])
    >>> result = glr_test(lambda th: z.size * th[0] - np.exp(th[0]) * z.sum(), [0.0])
    >>> result.dof, round(result.statistic, 4)
    (1, 0.0758)
    """
    alpha = as_probability(alpha)
    log_likelihood = as_callable(log_likelihood, "log_likelihood")
    nominal = as_vector(nominal, "nominal")
    p = nominal.size
    free0 = _indices(free0, p, "free0")
    free1 = list(range(p)) if free1 is None else _indices(free1, p, "free1")
    if not set(free0) < set(free1):
        raise ValueError(
            f"free0 {free0} must be a proper subset of free1 {free1} (nested hypotheses)"
        )
    start = nominal if theta_init is None else as_vector(theta_init, "theta_init")
    if start.shape != (p,):
        raise ValueError(
            f"theta_init must have length {p}, one value per entry of nominal, got {start.shape[0]}"
        )
    if bounds is not None:
        bounds = _pair_bounds(bounds, p, "bounds")
    _first_call(log_likelihood, nominal)
    base = nominal.copy()
    # Under H1 the parameters outside free1 keep their nominal values.
    fit1 = maximum_likelihood(
        log_likelihood,
        np.where(np.isin(np.arange(p), free1), start, base),
        free1,
        bounds=None if bounds is None else [bounds[j] for j in free1],
    )
    init0 = np.where(np.isin(np.arange(p), free0), start, base)
    fit0 = maximum_likelihood(
        log_likelihood, init0, free0, bounds=None if bounds is None else [bounds[j] for j in free0]
    )
    stat = max(2.0 * (fit1.log_likelihood - fit0.log_likelihood), 0.0)
    dof = len(free1) - len(free0)
    return TestResult.from_null(
        name,
        stat,
        residual_norm_law(dof),
        alpha,
        dof=dof,
        details={
            "max log L under H0": fit0.log_likelihood,
            "max log L under H1": fit1.log_likelihood,
            "calibration": "Wilks (asymptotic)",
            "converged": fit0.success and fit1.success,
        },
    )


def linear_glr_test(
    y,
    U,
    nominal,
    free0: Sequence[int] = (),
    free1: Sequence[int] | None = None,
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str = "generalised likelihood ratio test (linear)",
) -> TestResult:
    r"""Exact GLR test of nested parameter sets in ``y = U theta + v``, known ``sigma``.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal
        As in :func:`prediction_error`.
    free0 : sequence of int
        Free parameters under H0.
    free1 : sequence of int, optional
        Free parameters under H1 (superset of ``free0``); all by default.
    sigma, alpha, name

    Returns
    -------
    TestResult
        ``statistic = (T0 - T1) / sigma^2`` with ``Ti`` the prediction
        errors under the two hypotheses, ``null = chi2(rank1 - rank0)``.

    See Also
    --------
    glr_test : The asymptotic test for any model.
    prediction_error : The sums of squares it compares.

    Notes
    -----
    For Gaussian noise of known variance

    .. math::

        -2 \log \Lambda = \frac{T_0 - T_1}{\sigma^2}, \qquad
        T_0 - T_1 = \lVert (P_1 - P_0) y \rVert^2,

    with :math:`P_1 - P_0` the projection on the part of
    :math:`\operatorname{range}(U_{\text{free},1})` orthogonal to
    :math:`\operatorname{range}(U_{\text{free},0})`: exactly
    :math:`\sigma^2 \chi^2(\operatorname{rank}_1 - \operatorname{rank}_0)` under
    H0, for every :math:`N`.  Wilks' theorem is exact here.

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(5), np.arange(5.0)])
    >>> y = np.array([0.1, 1.0, 1.9, 3.2, 3.9])
    >>> result = linear_glr_test(y, U, [0.0, 1.0], free0=[0], sigma=0.1)
    >>> result.dof, result.reject
    (1, False)
    """
    alpha = as_probability(alpha)
    sigma = _check_sigma(sigma)
    U, nominal = _model(U, nominal)
    p = U.shape[1]
    free0 = _indices(free0, p, "free0")
    free1 = list(range(p)) if free1 is None else _indices(free1, p, "free1")
    if not set(free0) < set(free1):
        raise ValueError(
            f"free0 {free0} must be a proper subset of free1 {free1} (nested hypotheses)"
        )
    y = as_vector(y, "y", U.shape[0])
    fit0 = prediction_error(y, U, nominal, free0)
    fit1 = prediction_error(y, U, nominal, free1)
    dof = fit1.rank - fit0.rank
    if dof < 1:
        raise ValueError(
            "the extra parameters of H1 add no new regressor direction (rank did not grow), so the "
            "two hypotheses fit every record equally well; the test is void"
        )
    stat = max(fit0.statistic - fit1.statistic, 0.0) / sigma**2
    return TestResult.from_null(
        name,
        stat,
        residual_norm_law(dof),
        alpha,
        dof=dof,
        details={"T0": fit0.statistic, "T1": fit1.statistic},
    )


def neyman_pearson_test(
    z,
    theta0,
    theta1,
    *,
    sigma: float = 1.0,
    regressors=None,
    alpha: float = 0.05,
    name: str = "Neyman-Pearson test",
) -> TestResult:
    r"""Most powerful test of two simple hypotheses on a Gaussian mean.

    Parameters
    ----------
    z : array_like, shape (N,)
        Observations, ``z = regressors @ theta + v``, ``v ~ N(0, sigma^2 I)``.
    theta0, theta1 : float or array_like
        The parameter under H0 and under H1.
    sigma : float, default 1
    regressors : array_like, shape (N, p), optional
        A column of ones by default: ``z_i ~ N(theta, sigma^2)``.
    alpha : float

    Returns
    -------
    TestResult
        ``statistic = log f(z | theta1) - log f(z | theta0)``, reject when
        large; details hold the power ``P(reject | theta1)``.

    See Also
    --------
    glr_test : The likelihood ratio with estimated parameters.

    Notes
    -----
    Neyman-Pearson lemma (lecture, slide "Neyman-Pearson lemma,
    likelihood-kvot"): for :math:`H_0: \theta = \theta_0` against
    :math:`H_1: \theta = \theta_1` no test of level :math:`\alpha` has more
    power than the one rejecting for large
    :math:`f(z \mid \theta_1) / f(z \mid \theta_0)`.  Here, with
    :math:`m_i = U\theta_i` (``regressors @ theta_i``),

    .. math::

        \log \Lambda = \frac{\lVert z - m_0 \rVert^2 - \lVert z - m_1 \rVert^2}{2\sigma^2}

    is linear in :math:`z`: with :math:`d = \lVert m_1 - m_0 \rVert / \sigma` it
    is :math:`N(-d^2/2, d^2)` under H0 and :math:`N(d^2/2, d^2)` under H1, so
    threshold and power are exact: :math:`\text{power} = \Phi(d - z_\alpha)`.

    Examples
    --------
    The lecture's two observations, theta = 0 against theta = 1:

    >>> result = neyman_pearson_test([3.0, 5.0], theta0=0.0, theta1=1.0)
    >>> round(result.statistic, 6), result.reject, round(result.details["power"], 4)
    (7.0, True, 0.4088)
    """
    alpha = as_probability(alpha)
    sigma = _check_sigma(sigma)
    z = np.atleast_1d(as_float_array(z, "z"))
    if z.ndim != 1:
        raise ValueError(f"z must be a 1-D vector of observations, got shape {z.shape}")
    N = z.size
    A = (
        np.ones((N, 1))
        if regressors is None
        else as_matrix(regressors, "regressors", shape=(N, None))
    )
    t0 = np.atleast_1d(as_float_array(theta0, "theta0"))
    t1 = np.atleast_1d(as_float_array(theta1, "theta1"))
    if t0.shape != (A.shape[1],) or t1.shape != (A.shape[1],):
        raise ValueError(
            f"theta0 and theta1 must have {A.shape[1]} element(s), got {t0.shape} and {t1.shape}"
        )
    m0, m1 = A @ t0, A @ t1
    d = float(np.linalg.norm(m1 - m0) / sigma)
    if d == 0:
        raise ValueError(
            "theta0 and theta1 give the same distribution of z: the hypotheses cannot be told apart"
        )
    stat = float((np.sum((z - m0) ** 2) - np.sum((z - m1) ** 2)) / (2 * sigma**2))
    result = TestResult.from_null(name, stat, stats.norm(loc=-(d**2) / 2, scale=d), alpha)
    power = result.power(stats.norm(loc=d**2 / 2, scale=d))
    return dataclasses.replace(result, details={"power": power, "separation d": d})


def mode_log_likelihoods(
    y,
    U,
    nominal,
    modes: Mapping[str, Sequence[int]],
    *,
    sigma: float,
    prior_std: float | None = None,
) -> dict:
    r"""``log P(y | F)`` for every fault mode of ``y = U theta + v``.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal
        As in :func:`prediction_error`.
    modes : mapping of str to sequence of int
        The parameters that may deviate in each mode (``()`` for NF).
    sigma : float
    prior_std : float, optional
        If given, the deviating parameters of a mode have the prior
        ``N(nominal, prior_std^2)`` and the *marginal* likelihood
        ``int f(y | theta) p(theta | F) dtheta`` is returned (the proper
        Bayesian evidence).  Otherwise the maximised likelihood
        ``max over Theta_F of L(theta | y)`` of the lecture.

    Returns
    -------
    dict of str to float

    See Also
    --------
    bayes_ranking : The posterior probabilities of the modes.

    Notes
    -----
    The lecture (slide "Likelihood och Bayes") uses :math:`\max L` as
    :math:`P(z \mid F_i)`.  Because :math:`\Theta_{NF}` lies in the closure of
    every :math:`\Theta_{F_i}`,
    :math:`\max_{\Theta_{F_i}} L \ge L(\text{nominal})` for every record: with
    maximised likelihoods a fault mode always looks at least as likely as NF,
    and only the priors can favour NF.  The marginal likelihood charges a mode
    for its free parameter (an Occam factor) and prefers NF when the data do
    not need the fault.  Under :math:`F` with the prior above,

    .. math::

        y \sim N\bigl(U\theta_{\text{nominal}},\ \sigma^2 I + s^2 U_F U_F^{\mathsf T}\bigr),

    with :math:`s` = ``prior_std``.

    Examples
    --------
    >>> import numpy as np
    >>> U = np.eye(3)
    >>> logl = mode_log_likelihoods([1.0, 2.0, 1.0], U, [1, 1, 1], {"NF": (), "F2": (1,)}, sigma=1.0)
    >>> {mode: round(value, 4) for mode, value in logl.items()}
    {'NF': -3.2568, 'F2': -2.7568}
    """
    sigma = _check_sigma(sigma)
    U, nominal = _model(U, nominal)
    y = as_vector(y, "y", U.shape[0])
    N = y.size
    if not isinstance(modes, Mapping):
        raise InputTypeError(
            f"modes must be a mapping {{mode: faulty parameter indices}}, got {type(modes).__name__}"
        )
    if prior_std is not None:
        prior_std = _check_sigma(prior_std, "prior_std")
    out = {}
    for mode, faulty in modes.items():
        faulty = _indices(faulty, U.shape[1], f"modes[{mode!r}]")
        if prior_std is None or not faulty:
            T = prediction_error(y, U, nominal, faulty).statistic
            out[str(mode)] = float(-0.5 * N * np.log(2 * np.pi * sigma**2) - T / (2 * sigma**2))
        else:
            tau = prior_std
            Uf = U[:, faulty]
            cov = sigma**2 * np.eye(N) + tau**2 * (Uf @ Uf.T)
            L = cholesky_lower(cov, "marginal covariance")
            w = whiten(L, y - U @ nominal)
            out[str(mode)] = float(
                -0.5 * N * np.log(2 * np.pi) - np.sum(np.log(np.diag(L))) - 0.5 * w @ w
            )
    return out


@dataclass(frozen=True, repr=False, eq=False)
class FaultRanking:
    """Fault modes ranked by posterior probability (see :func:`bayes_ranking`).

    Attributes
    ----------
    modes : tuple of str
        Most probable first.
    posterior, prior, log_likelihood : tuple of float
        In the order of ``modes``.
    """

    modes: tuple
    posterior: tuple
    prior: tuple
    log_likelihood: tuple

    def as_dict(self) -> dict:
        """``{mode: posterior}``."""
        return dict(zip(self.modes, self.posterior))

    def to_text(self, digits: int = 4) -> str:
        """The ranking as aligned plain text, numbers rounded to ``digits`` significant digits."""
        width = max(len(m) for m in self.modes)
        lines = [f"{'mode'.ljust(width)}  {'prior':>8}  {'posterior':>10}"]
        for m, pr, po in zip(self.modes, self.prior, self.posterior):
            lines.append(
                f"{m.ljust(width)}  {format_number(pr, digits):>8}  {format_number(po, digits):>10}"
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"FaultRanking(\n{self.to_text()}\n)"

    def _repr_html_(self) -> str:
        rows = "".join(
            f"<tr><th style='text-align:left'>{html.escape(m)}</th><td>{format_number(pr, 4)}</td>"
            f"<td>{format_number(po, 4)}</td></tr>"
            for m, pr, po in zip(self.modes, self.prior, self.posterior)
        )
        return (
            "<table><caption>fault modes ranked by posterior probability</caption>"
            f"<tr><th>mode</th><th>prior</th><th>posterior</th></tr>{rows}</table>"
        )


def bayes_ranking(
    log_likelihoods: Mapping[str, float], priors: Mapping[str, float]
) -> FaultRanking:
    r"""Rank fault modes by ``P(F | z)`` from ``log P(z | F)`` and priors ``P(F)``.

    Parameters
    ----------
    log_likelihoods : mapping of str to float
        ``log P(z | F)`` per mode, e.g. from :func:`mode_log_likelihoods`.
    priors : mapping of str to float
        Prior probabilities of the same modes, positive and summing to 1.

    Returns
    -------
    FaultRanking

    See Also
    --------
    mode_log_likelihoods : The likelihoods it weighs.

    Notes
    -----
    Bayes' rule (lecture, slide "Likelihood och Bayes")

    .. math::

        P(F_i \mid z) = \frac{P(z \mid F_i) P(F_i)}{\sum_j P(z \mid F_j) P(F_j)},

    computed with log-sum-exp so that tiny likelihoods do not underflow.

    Examples
    --------
    >>> ranking = bayes_ranking({"NF": -3.0, "F1": -1.0}, {"NF": 0.9, "F1": 0.1})
    >>> ranking.modes, [round(p, 3) for p in ranking.posterior]
    (('NF', 'F1'), [0.549, 0.451])
    """
    for name, value in (("log_likelihoods", log_likelihoods), ("priors", priors)):
        if not isinstance(value, Mapping):
            raise InputTypeError(
                f"{name} must be a mapping {{mode: value}}, got {type(value).__name__}"
            )
    modes = list(log_likelihoods)
    if set(modes) != set(priors):
        raise ValueError(
            f"log_likelihoods and priors must name the same modes, got {sorted(modes)} and {sorted(priors)}"
        )
    if not modes:
        raise ValueError("at least one mode is needed")
    logl = as_float_array([log_likelihoods[m] for m in modes], "log_likelihoods", finite=False)
    prior = as_float_array([priors[m] for m in modes], "priors")
    if np.any(logl == np.inf):
        raise ValueError("log_likelihoods must be finite numbers or -inf")
    if np.any(prior <= 0):
        raise ValueError("priors must be positive probabilities")
    if abs(prior.sum() - 1.0) > 1e-9:
        raise ValueError(
            f"priors must sum to 1, they sum to {prior.sum():.6g}; normalise them first"
        )
    if np.all(logl == -np.inf):
        raise ValueError(
            "every mode has likelihood 0 (log-likelihood -inf): the data are impossible under all "
            "modes, so Bayes' rule cannot rank them; check the model or the noise level"
        )
    log_post = logl + np.log(prior)
    log_post = log_post - special.logsumexp(log_post)
    post = np.exp(log_post)
    order = sorted(range(len(modes)), key=lambda i: (-post[i], i))
    return FaultRanking(
        modes=tuple(modes[i] for i in order),
        posterior=tuple(float(post[i]) for i in order),
        prior=tuple(float(prior[i]) for i in order),
        log_likelihood=tuple(float(logl[i]) for i in order),
    )
