"""Testing a q-dimensional alternative: the GLR test, its power, Baarda's B-method, reliability.

Beyond chapter 10: the chapter tests the whole model (the overall model test, q = m - n)
and one observation at a time (the w-test, q = 1). Both are the same test, the generalised
likelihood-ratio test of H0: E(y) = Ax against Ha: E(y) = Ax + C∇ with a bias ∇ in a
q-dimensional space spanned by the columns of C (Teunissen 2000, *Testing theory*,
chapter 3). The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.linalg import LinAlgError
from scipy import linalg as sla
from scipy import stats

from course._noncentral import lower_quantile
from course.chi2 import noncentrality, residual_norm_law
from course.distributions import FrozenDistribution
from course.linalg import readonly
from course.lsq._fit import (
    LeastSquaresFit,
    _check_fit,
    _require_redundancy,
    _require_residuals_for_sigma,
)
from course.results import TestResult, format_number
from course.validation import (
    as_count,
    as_float_array,
    as_matrix,
    as_probability,
    as_vector,
)

#: Below this ratio of the smallest to the largest singular value of the bias columns,
#: projected off the range of A, [A C] counts as rank deficient: the bias (or a
#: combination of its columns) is absorbed by the estimate and leaves no residual.
_ABSORBED_RTOL = 1e-10

_VARIANCES = ("known", "estimated")

#: Above this non-centrality scipy's ncx2 and ncf lose accuracy and then return NaN (from
#: about 1e19); :class:`_FarAlternative` takes over, where the power is 1 to double precision.
_SCIPY_NONCENTRALITY = 1e15


class _FarAlternative(FrozenDistribution):
    """``ncx2(q, λ)`` or ``ncf(q, r, λ)`` for a λ beyond scipy's (``λ > 1e15``, ``inf`` included).

    ``X = (Z + sqrt(λ))² + chi2(q - 1)`` (over ``chi2(r)/r``, times ``1/q``, for F).
    Its cdf is computed where it underflows to 0 in double precision, i.e. wherever a
    test's critical value can be: ``P(X <= x) <= P((Z + sqrt(λ))² <= λ/4) +
    P(chi2(r)/r >= λ/(4 q x))`` (the second term for F only), and ``P(|Z + sqrt(λ)| <=
    sqrt(λ)/2) <= exp(-λ/8)`` is 0 below 1e-300 for λ > 1e15. Nearer the centre of the
    law it refuses rather than approximate. It is dressed as scipy's frozen law (``dist``,
    ``args``) so that :meth:`~course.results.TestResult.power` can check it.
    """

    def __init__(self, q: int, lam: float, remaining: int | None = None):
        self.q, self.lam, self.remaining = q, lam, remaining
        name, shapes = ("ncx2", "df, nc") if remaining is None else ("ncf", "dfn, dfd, nc")
        self.dist = _Family(name, shapes)
        self.args = (q, lam) if remaining is None else (q, remaining, lam)
        self.kwds: dict = {}

    def _log_bound(self, x: np.ndarray) -> np.ndarray:
        """log of an upper bound of ``P(X <= x)`` valid for ``x <= λ/4`` (chi2 scale)."""
        log_normal = -self.lam / 8.0
        if self.remaining is None:
            return np.where(x <= self.lam / 4.0, log_normal, 0.0)
        r = self.remaining
        with np.errstate(divide="ignore", over="ignore"):
            level = r * self.lam / (4.0 * self.q * np.maximum(x, 1e-300))
        return np.logaddexp(log_normal, stats.chi2.logsf(level, r))

    def _cdf(self, x):
        bound = self._log_bound(np.asarray(x, dtype=float))
        if np.any(bound > -745.0):  # (exp underflows to 0 below about -745)
            raise ValueError(
                f"the non-centrality λ = {self.lam:.3g} is beyond what scipy's non-central "
                "laws compute; only the far lower tail (P = 0 to double precision, where "
                "any test's critical value lies, so the power is 1) is available here"
            )
        return np.zeros_like(bound)

    def _rvs(self, size, rng):
        if not np.isfinite(self.lam):
            raise ValueError("λ is infinite: the statistic has no finite draws")
        value = (rng.standard_normal(size) + np.sqrt(self.lam)) ** 2
        if self.q > 1:
            value = value + rng.chisquare(self.q - 1, size)
        if self.remaining is None:
            return value
        return (value / self.q) / (rng.chisquare(self.remaining, size) / self.remaining)

    def __repr__(self) -> str:
        return f"{self.dist.name}({', '.join(format_number(a) for a in self.args)})"


class _Family(NamedTuple):
    name: str
    shapes: str


def _noncentral_law(q: int, lam: float, remaining: int | None = None) -> Any:
    """The law of T_q (``remaining`` None) or F under the alternative, central when λ = 0."""
    if lam > _SCIPY_NONCENTRALITY:
        return _FarAlternative(q, lam, remaining)
    if remaining is None:
        return stats.ncx2(q, lam) if lam > 0 else residual_norm_law(q)
    return stats.ncf(q, remaining, lam) if lam > 0 else stats.f(q, remaining)


def _check_variance(variance: Any) -> str:
    if not isinstance(variance, str) or variance not in _VARIANCES:
        raise ValueError(
            f"variance must be 'known' (the variance factor of Qyy is known: chi-square "
            f"laws) or 'estimated' (sigma² estimated from the residuals: F and t laws), "
            f"got {variance!r}"
        )
    return variance


@dataclass(frozen=True)
class _BiasSpace:
    """The whitened bias columns off the range of A: ``C̄ = (I - Q1 Q1^T) L^{-1} C = Qc Rc``."""

    Qc: np.ndarray  # m x q, orthonormal, orthogonal to the whitened design
    Rc: np.ndarray  # q x q upper triangular
    C_w: np.ndarray  # L^{-1} C, m x q

    @property
    def q(self) -> int:
        return int(self.Rc.shape[0])


def _bias_matrix(fit: LeastSquaresFit, C: Any, name: str = "C") -> np.ndarray:
    """``C`` as an (m, q) matrix (a vector is one column) with one row per observation."""
    C = as_float_array(C, name)
    if C.ndim == 1:
        C = C[:, None]
    C = as_matrix(C, name)
    if C.shape[0] != fit.m:
        raise ValueError(
            f"{name} must have one row per observation (m = {fit.m}), got shape {C.shape}; "
            "its columns span the bias C∇ of the alternative hypothesis"
        )
    return C


def _bias_columns(fit: LeastSquaresFit, C: Any, name: str = "C") -> np.ndarray:
    """:func:`_bias_matrix`, with no more columns than a test can have (``q <= m - n``)."""
    C = _bias_matrix(fit, C, name)
    q = C.shape[1]
    if q > fit.redundancy:
        raise ValueError(
            f"{name} has q = {q} columns but the fit has only m - n = {fit.redundancy} "
            "redundant observations: at most m - n bias parameters can be tested "
            "(q = m - n is the overall model test)"
        )
    return C


def _bias_space(fit: LeastSquaresFit, C: np.ndarray, name: str = "C") -> _BiasSpace:
    C_w = np.asfortranarray(fit._covariance.whiten(C))
    absorbed = LinAlgError(
        f"[A {name}] is not of full column rank: a column of {name} (or a combination "
        "of its columns) lies in the range of A, so that bias is absorbed by the "
        "estimate x̂ and leaves no trace in the residuals; drop it, or choose bias "
        "columns that A cannot explain"
    )
    # The test is the same for C D (D diagonal): each column is scaled by a power of two
    # (exactly) to a largest entry in [1, 2), so that neither the QR nor the rank check
    # squares a 1e160 or a 1e-200 into overflow or underflow.
    peak = np.max(np.abs(C_w), axis=0)
    if not np.all(np.isfinite(peak)):
        raise ValueError(
            f"{name} whitened by Qyy overflows double precision (largest |{name}| = "
            f"{float(np.max(np.abs(C))):.3g}); rescale the columns of {name}"
        )
    if np.any(peak == 0.0):
        raise absorbed
    scale = np.ldexp(0.5, np.frexp(peak)[1])  # (2^(e-1) <= peak: never overflows)
    projected = np.asfortranarray(C_w / scale)
    Q1 = fit._Q1
    for _ in range(2):  # classical Gram-Schmidt twice: orthogonal to working precision
        projected -= Q1 @ (Q1.T @ projected)
    Qc, Rc_scaled = sla.qr(projected, mode="economic", check_finite=False)
    diagonal = np.abs(np.diag(Rc_scaled))
    size = float(np.max(np.linalg.norm(C_w / scale, axis=0)))  # each column's in [1, 2 sqrt(m))
    if float(np.min(diagonal)) <= _ABSORBED_RTOL * size:
        raise absorbed
    with np.errstate(over="ignore"):
        Rc = Rc_scaled * scale
    if not np.all(np.isfinite(Rc)):
        raise ValueError(
            f"{name} is scaled so far from 1 that its whitened columns overflow double "
            f"precision (largest |{name}| = {float(np.max(np.abs(C))):.3g}); rescale the "
            f"columns of {name} (the bias's units) and scale the bias back"
        )
    return _BiasSpace(Qc=Qc, Rc=Rc, C_w=C_w)


def glr_test(
    fit: LeastSquaresFit, C: Any, alpha: float = 0.05, variance: str = "known"
) -> TestResult:
    r"""Generalised likelihood-ratio test of a q-dimensional alternative ``E(y) = Ax + C∇``.

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit` (the null hypothesis H0: ``E(y) = Ax``).
    C : array_like, shape (m, q) or (m,)
        Bias columns of the alternative: the bias is ``C∇`` for an unknown
        ``∇`` of q entries; ``[A C]`` must have full column rank and
        ``q <= m - n``.
    alpha : float
        Level of significance.
    variance : {"known", "estimated"}
        ``"known"``: ``Qyy`` is the covariance (T_q, chi-square law);
        ``"estimated"``: ``Qyy`` is known up to a factor σ² estimated from the
        residuals (F statistic; needs ``q < m - n``).

    Returns
    -------
    TestResult
        ``statistic`` T_q (or F), ``dof`` q, ``null`` ``chi2(q)`` (or
        ``F(q, m - n - q)``); ``details`` holds the estimated bias ``∇̂``,
        the denominator degrees of freedom (F) and ``m - n``.

    Raises
    ------
    ValueError
        ``C`` of the wrong shape or ``q > m - n``; ``variance="estimated"``
        with ``q = m - n`` (nothing left to estimate σ² from) or with data
        that the model fits exactly (residuals at round-off level).
    numpy.linalg.LinAlgError
        ``[A C]`` rank deficient (the bias is absorbed by x̂).

    See Also
    --------
    overall_model_test : The case q = m - n.
    w_tests : The case ``C = c_i`` (``T_1 = w_i²``).
    alternative_law : The law of the statistic under the alternative (power).
    minimal_detectable_bias : The biases found with a given power.

    Notes
    -----
    Teunissen (2000, *Testing theory*, chapter 3): the uniformly most powerful
    invariant test of H0 against Ha rejects for large

    .. math::

        T_q = \hat e^{\mathsf T} Q_{yy}^{-1} C\,
              (C^{\mathsf T} Q_{yy}^{-1} Q_{\hat e\hat e} Q_{yy}^{-1} C)^{-1}\,
              C^{\mathsf T} Q_{yy}^{-1} \hat e
        \sim \chi^2(q, 0) \text{ under H0}, \quad \chi^2(q, \lambda) \text{ under Ha},

    with :math:`\lambda = \nabla^{\mathsf T} C^{\mathsf T} Q_{yy}^{-1}
    Q_{\hat e\hat e} Q_{yy}^{-1} C \nabla`. For :math:`C = c_i` it is Baarda's
    :math:`w_i^2`; for any C of rank :math:`q = m - n` it is the overall model
    test's :math:`\hat e^{\mathsf T} Q_{yy}^{-1}\hat e`. With σ² unknown,
    :math:`\hat e^{\mathsf T} Q_{yy}^{-1}\hat e - T_q` is the residual norm under Ha, and

    .. math::

        F = \frac{T_q / q}{(\hat e^{\mathsf T} Q_{yy}^{-1}\hat e - T_q)/(m - n - q)}
        \sim F(q, m - n - q)

    under H0, free of σ². Computed in the whitened problem: with
    :math:`\bar C = (I - Q_1 Q_1^{\mathsf T}) L^{-1} C = Q_c R_c`,
    :math:`T_q = \lVert Q_c^{\mathsf T} \tilde e \rVert^2` and
    :math:`\hat\nabla = R_c^{-1} Q_c^{\mathsf T} \tilde e` (no inverse formed).

    Examples
    --------
    A line with an outlier in observation 6 (the w-test example): the GLR test
    of that one observation is the w-test squared,

    >>> import numpy as np
    >>> from course.lsq import fit, w_tests
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> y = [2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53]
    >>> f = fit(A, y, 0.01 * np.eye(10))
    >>> T = glr_test(f, np.eye(10)[:, 6]).statistic
    >>> round(T, 4), round(float(w_tests(f).statistic[6]) ** 2, 4)
    (23.3158, 23.3158)

    and a jump of the last three observations (q = 1, one bias for all three) is
    rejected too, for the outlier makes the last points look high:

    >>> jump = np.r_[np.zeros(7), np.ones(3)]
    >>> glr_test(f, jump, alpha=0.01).reject
    True
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    variance = _check_variance(variance)
    _require_redundancy(fit, "test of an alternative hypothesis")
    C = _bias_columns(fit, C)
    space = _bias_space(fit, C)
    q = space.q
    coordinates = space.Qc.T @ fit._e_w
    T_q = float(coordinates @ coordinates)
    bias = sla.solve_triangular(space.Rc, coordinates, lower=False, check_finite=False)
    details: dict[str, Any] = {"estimated bias": bias, "m - n": fit.redundancy}
    if variance == "known":
        return TestResult.from_null(
            f"GLR test, q = {q}", T_q, residual_norm_law(q), alpha, dof=q, details=details
        )
    remaining = fit.redundancy - q
    if remaining < 1:
        raise ValueError(
            f"variance='estimated' needs q < m - n: with q = {q} = m - n the alternative "
            "explains every residual and nothing is left to estimate sigma² from; use "
            "variance='known', or test fewer bias parameters"
        )
    _require_residuals_for_sigma(fit, "the GLR test")
    rest = max(fit.squared_norm - T_q, 0.0)
    details["denominator dof"] = remaining
    statistic = np.inf if rest == 0.0 else (T_q / q) / (rest / remaining)
    details["sigma² under Ha"] = rest / remaining
    return TestResult.from_null(
        f"GLR F-test, q = {q}",
        float(statistic),
        stats.f(q, remaining),
        alpha,
        dof=q,
        details=details,
    )


def alternative_law(fit: LeastSquaresFit, C: Any, bias: Any, variance: str = "known") -> Any:
    r"""The law of :func:`glr_test`'s statistic when the bias is ``C @ bias``.

    Parameters
    ----------
    fit : LeastSquaresFit
        The fit (its design and ``Qyy``; the observations do not matter).
    C : array_like, shape (m, q) or (m,)
        Bias columns, as for :func:`glr_test`.
    bias : float or array_like, shape (q,)
        The true bias ``∇`` (in the units of the observations per unit of C).
    variance : {"known", "estimated"}
        Which statistic: T_q (non-central chi-square) or F (non-central F).

    Returns
    -------
    scipy.stats frozen distribution
        ``ncx2(q, λ)`` or ``ncf(q, m - n - q, λ)`` (central when λ = 0), to pass
        to :meth:`~course.results.TestResult.power`. Beyond ``λ = 1e15``, where
        scipy's non-central laws fail, a law of the same name whose cdf is computed
        in the far lower tail only (0 there: the power of any test is 1); λ may be
        ``inf`` when it overflows.

    See Also
    --------
    glr_test : The test whose power this law gives.

    Notes
    -----
    :math:`\lambda = \lVert \bar C \nabla \rVert^2 = \nabla^{\mathsf T}
    C^{\mathsf T} Q_{yy}^{-1} Q_{\hat e\hat e} Q_{yy}^{-1} C \nabla`
    (Teunissen 2000, chapter 3).

    Examples
    --------
    >>> import numpy as np
    >>> from course.lsq import fit
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> f = fit(A, np.arange(10.0), 0.01 * np.eye(10))
    >>> C = np.eye(10)[:, [4, 5]]
    >>> result = glr_test(f, C, alpha=0.01)
    >>> round(result.power(alternative_law(f, C, [0.3, 0.3])), 3)
    0.818
    """
    fit = _check_fit(fit)
    variance = _check_variance(variance)
    _require_redundancy(fit, "test of an alternative hypothesis")
    C = _bias_columns(fit, C)
    space = _bias_space(fit, C)
    bias = as_vector(np.atleast_1d(as_float_array(bias, "bias")), "bias", space.q)
    # λ = |Rc ∇|², scaled: Rc ∇ of a 1e200 bias overflows before λ is known to be huge
    peak = float(np.max(np.abs(bias)))
    with np.errstate(over="ignore"):
        size = float(sla.norm(space.Rc @ (bias / peak))) * peak if peak > 0 else 0.0
        lam = size * size
    q = space.q
    if variance == "known":
        return _noncentral_law(q, lam)
    remaining = fit.redundancy - q
    if remaining < 1:
        raise ValueError(
            f"variance='estimated' needs q < m - n (q = {q}, m - n = {fit.redundancy})"
        )
    return _noncentral_law(q, lam, remaining)


class BMethod(NamedTuple):
    """Result of :func:`b_method`: tests of different dimension tuned to one bias."""

    lambda0: float
    """The common non-centrality λ0 (the w-test's, at ``alpha_1`` and ``power``)."""
    alpha_q: Any
    """Level of each q-dimensional test (float, or an array like ``q``)."""
    critical_value_q: Any
    """``chi2.isf(alpha_q, q)``: the q-dimensional test's threshold on T_q."""
    critical_value_1: float
    """``norm.isf(alpha_1 / 2)``: the w-test's threshold on ``|w|``."""


def b_method(alpha_1: float = 0.001, power: float = 0.80, q: Any = 1) -> BMethod:
    r"""Baarda's B-method: levels that let tests of every dimension detect one bias alike.

    Parameters
    ----------
    alpha_1 : float
        Level of the one-dimensional tests (the w-tests).
    power : float
        Reference power γ0 (detection probability), ``alpha_1 < power < 1``.
    q : int or array_like of int
        Dimensions of the other tests (``m - n`` for the overall model test).

    Returns
    -------
    BMethod
        ``lambda0``, ``alpha_q``, ``critical_value_q`` and ``critical_value_1``.

    See Also
    --------
    course.chi2.noncentrality : λ0 from a level and a power.
    glr_test : The q-dimensional test.

    Notes
    -----
    Baarda (1968): a bias that the w-test (level :math:`\alpha_1`) finds with
    probability :math:`\gamma_0` has non-centrality
    :math:`\lambda_0 = \lambda(\alpha_1, \gamma_0, 1)`. A q-dimensional test
    finds the same bias (it shifts :math:`T_q` by at least :math:`\lambda_0`)
    with the same probability when its level :math:`\alpha_q` solves

    .. math::

        P\bigl(\chi^2(q, \lambda_0) > \chi^2_{\alpha_q}(q)\bigr) = \gamma_0,
        \quad\text{i.e.}\quad
        \chi^2_{\alpha_q}(q) = \chi^2_{1-\gamma_0}(q, \lambda_0),\quad
        \alpha_q = P\bigl(\chi^2(q) > \chi^2_{1-\gamma_0}(q, \lambda_0)\bigr).

    The usual choice :math:`\alpha_1 = 0.001`, :math:`\gamma_0 = 0.80` gives
    :math:`\lambda_0 = 17.07`.

    Examples
    --------
    >>> b = b_method(0.001, 0.80, q=[1, 2, 5])
    >>> round(b.lambda0, 2), [round(float(a), 4) for a in b.alpha_q]
    (17.07, [0.001, 0.0028, 0.013])
    """
    alpha_1 = as_probability(alpha_1, "alpha_1")
    power = as_probability(power, "power")
    if not power > alpha_1:
        raise ValueError(
            f"power must exceed alpha_1 (a test finds a bias more often than it false-alarms), "
            f"got power = {power!r} and alpha_1 = {alpha_1!r}"
        )
    q_array = np.asarray(q)
    scalar = q_array.ndim == 0
    dims = np.array([as_count(v, "q") for v in np.atleast_1d(q_array).ravel()], dtype=int)
    if dims.size == 0:
        raise ValueError("q is empty; pass at least one dimension")
    lam0 = noncentrality(alpha_1, power, 1)  # (refuses power beyond 1 - 1e-15)
    # The q-dimensional threshold where the miss probability is 1 - power, searched in
    # logarithms on the Poisson mixture (scipy's ncx2.ppf loses digits near power 1 and is
    # NaN beyond about 1e11 dof); q = 1 gives back alpha_1.
    threshold = np.array([lower_quantile(1.0 - power, float(d), lam0) for d in dims])
    alpha_q = stats.chi2.sf(threshold, dims)
    critical_1 = float(stats.norm.isf(alpha_1 / 2.0))
    if scalar:
        return BMethod(float(lam0), float(alpha_q[0]), float(threshold[0]), critical_1)
    return BMethod(
        float(lam0),
        readonly(alpha_q.reshape(q_array.shape)),
        readonly(threshold.reshape(q_array.shape)),
        critical_1,
    )


@dataclass(frozen=True, repr=False, eq=False)
class MinimalDetectableBias:
    """The biases ``C∇`` that a q-dimensional test finds with a given power.

    Build it with :func:`minimal_detectable_bias`. The detectable biases fill
    the outside of the ellipsoid ``∇^T Q_∇̂∇̂^{-1} ∇ = λ0``.

    Attributes
    ----------
    lambda0 : float
        Non-centrality at which the test has the requested power.
    covariance : ndarray, shape (q, q)
        ``Q_∇̂∇̂``, the covariance of the estimated bias.
    lengths : ndarray, shape (q,)
        Semi-axes of the ellipsoid, ascending: the smallest and the largest
        minimal detectable bias over all directions.
    axes : ndarray, shape (q, q)
        Unit directions of the semi-axes (columns, in the order of ``lengths``).
    alpha, power : float
        The test's level and the required power.
    """

    lambda0: float
    covariance: np.ndarray
    lengths: np.ndarray
    axes: np.ndarray
    alpha: float
    power: float
    _Rc: np.ndarray

    def along(self, direction: Any) -> np.ndarray:
        """The minimal detectable bias ``∇`` (shape (q,)) along ``direction``.

        ``|∇| = sqrt(λ0 / (d^T Q_∇̂∇̂^{-1} d))`` for the unit vector ``d``.
        """
        q = self._Rc.shape[0]
        d = as_vector(np.atleast_1d(as_float_array(direction, "direction")), "direction", q)
        peak = float(np.max(np.abs(d)))
        if peak == 0.0:
            raise ValueError("direction is the zero vector; pass a direction in the bias space")
        d = d / peak  # (first to a largest entry of 1: |d|² of [1e300, 1e300] overflows)
        d = d / sla.norm(d)
        size = np.sqrt(self.lambda0) / float(sla.norm(self._Rc @ d))
        return size * d

    def __repr__(self) -> str:
        lengths = ", ".join(format_number(float(v), 5) for v in self.lengths)
        return (
            f"MinimalDetectableBias(q={self.lengths.shape[0]}, alpha={format_number(self.alpha)}, "
            f"power={format_number(self.power)}, lambda0={format_number(self.lambda0, 5)}, "
            f"lengths=[{lengths}])"
        )


def minimal_detectable_bias(
    fit: LeastSquaresFit, C: Any, alpha: float = 0.001, power: float = 0.80
) -> MinimalDetectableBias:
    r"""Minimal detectable biases of a q-dimensional alternative (internal reliability).

    Parameters
    ----------
    fit : LeastSquaresFit
        The fit (its design and ``Qyy``).
    C : array_like, shape (m, q) or (m,)
        Bias columns, as for :func:`glr_test`.
    alpha : float
        Level of the q-dimensional test.
    power : float
        Required detection probability.

    Returns
    -------
    MinimalDetectableBias
        The ellipsoid of biases found with probability ``power``: its
        semi-axes ``lengths`` and ``axes``, and ``.along(direction)``.

    See Also
    --------
    mdb : The one-dimensional case for each observation.
    external_reliability : What an undetected bias does to x̂.
    b_method : A level for the q-dimensional test that matches the w-tests.

    Notes
    -----
    Teunissen (2000, chapter 4): the test finds a bias :math:`\nabla` with
    probability :math:`\gamma` when its non-centrality
    :math:`\nabla^{\mathsf T} Q_{\hat\nabla\hat\nabla}^{-1} \nabla` reaches
    :math:`\lambda_0 = \lambda(\alpha, \gamma, q)`, with
    :math:`Q_{\hat\nabla\hat\nabla} = (C^{\mathsf T} Q_{yy}^{-1} Q_{\hat e\hat e}
    Q_{yy}^{-1} C)^{-1} = R_c^{-1} R_c^{-\mathsf T}`. Along the unit direction d the
    minimal detectable bias is
    :math:`\sqrt{\lambda_0 / (d^{\mathsf T} Q_{\hat\nabla\hat\nabla}^{-1} d)}`;
    the semi-axes are :math:`\sqrt{\lambda_0 \mu_k}` with :math:`\mu_k` the
    eigenvalues of :math:`Q_{\hat\nabla\hat\nabla}`. For :math:`C = c_i` this is
    :func:`mdb`'s value for observation i.

    Examples
    --------
    >>> import numpy as np
    >>> from course.lsq import fit, mdb
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> f = fit(A, [14, 20, 20, 24])
    >>> round(float(minimal_detectable_bias(f, np.eye(4)[:, 1]).lengths[0]), 2)
    4.94
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    power = as_probability(power, "power")
    _require_redundancy(fit, "minimal detectable bias")
    C = _bias_columns(fit, C)
    space = _bias_space(fit, C)
    lam0 = noncentrality(alpha, power, space.q)
    # Q_∇̂∇̂ = Rc^{-1} Rc^{-T}: its eigen-decomposition from the SVD of Rc (no inverse):
    # Rc = U S V^T gives Q_∇̂∇̂ = V S^{-2} V^T.
    _, singular, Vt = np.linalg.svd(space.Rc)
    order = np.argsort(singular)[::-1]  # largest singular value = smallest semi-axis
    lengths = np.sqrt(lam0) / singular[order]
    axes = Vt[order].T
    with np.errstate(over="ignore", under="ignore"):
        # (Q_∇̂∇̂ scales like 1/C²: inf or 0 when C is scaled beyond 1e±154, while the
        # lengths, like 1/C, stay exact)
        Rc_inv_t = sla.solve_triangular(space.Rc, np.eye(space.q), trans="T", lower=False)
        covariance = Rc_inv_t.T @ Rc_inv_t
    return MinimalDetectableBias(
        lambda0=float(lam0),
        covariance=readonly((covariance + covariance.T) / 2.0),
        lengths=readonly(lengths),
        axes=readonly(axes),
        alpha=alpha,
        power=power,
        _Rc=readonly(space.Rc),
    )


class ExternalReliability(NamedTuple):
    """Result of :func:`external_reliability`."""

    effect: np.ndarray
    """``∇x̂``, shape (n,): how far the undetected bias moves the estimate."""
    bias_to_noise: np.ndarray
    """``∇x̂_j / σ_x̂_j``, shape (n,): each shift in units of its standard deviation."""
    overall: float
    """``sqrt(∇x̂^T Q_x̂x̂^{-1} ∇x̂)``: the shift's size in the metric of ``Q_x̂x̂``."""


def external_reliability(fit: LeastSquaresFit, C: Any, bias: Any) -> ExternalReliability:
    r"""What an undetected bias ``C @ bias`` does to the estimate x̂ (external reliability).

    Parameters
    ----------
    fit : LeastSquaresFit
        The fit (its design and ``Qyy``).
    C : array_like, shape (m, q) or (m,)
        Bias columns.
    bias : float or array_like, shape (q,)
        The bias, typically a minimal detectable bias
        (:meth:`MinimalDetectableBias.along`).

    Returns
    -------
    ExternalReliability
        ``effect`` ∇x̂, ``bias_to_noise`` per parameter and ``overall``.

    See Also
    --------
    minimal_detectable_bias : The biases that are just detectable.

    Notes
    -----
    Baarda (1968); Teunissen (2000, chapter 4): the estimator is linear, so a
    bias :math:`b = C\nabla` in y shifts it by

    .. math::

        \nabla\hat x = Q_{\hat x\hat x} A^{\mathsf T} Q_{yy}^{-1} C \nabla
        = R^{-1} Q_1^{\mathsf T} L^{-1} C \nabla,

    and :math:`\nabla\hat x^{\mathsf T} Q_{\hat x\hat x}^{-1} \nabla\hat x =
    \lVert Q_1^{\mathsf T} L^{-1} C\nabla \rVert^2` measures it in the
    estimate's own precision (the bias-to-noise ratio).

    Examples
    --------
    An undetected 1.0 in the first of four equally precise points of a line:

    >>> import numpy as np
    >>> from course.lsq import fit
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> er = external_reliability(fit(A, [14, 20, 20, 24]), np.eye(4)[:, 0], 1.0)
    >>> er.effect.round(2), round(er.overall, 3)
    (array([ 1. , -0.3]), 0.837)
    """
    fit = _check_fit(fit)
    C = _bias_matrix(fit, C)  # any q: an undetectable bias still moves x̂
    bias = as_vector(np.atleast_1d(as_float_array(bias, "bias")), "bias", C.shape[1])
    shift_w = fit._covariance.whiten(C @ bias)
    coordinates = fit._Q1.T @ shift_w
    effect = sla.solve_triangular(fit._R, coordinates, lower=False, check_finite=False)
    return ExternalReliability(
        effect=readonly(effect),
        bias_to_noise=readonly(effect / fit.sigma_x_hat),
        overall=float(sla.norm(coordinates)),  # (BLAS nrm2: no overflow in the squares)
    )
