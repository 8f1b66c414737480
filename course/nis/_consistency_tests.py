"""Consistency tests of one record: the time-averaged NIS test and the NIS-matrix test.

Sources: R. Forsling, poster "Matrix-Valued Statistics for Detecting Complex
Model Errors in State Estimation", eqs. (3)-(4) ([F]); Bar-Shalom, Li and
Kirubarajan (2001), Sec. 5.4 ([BS]); full references in the course
bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from course._unchecked import _whiten_vectors as whiten_vectors
from course.chi2 import residual_norm_law
from course.distributions import TailPair
from course.nis._laws import (
    extreme_eigenvalue,
    prob_eigenvalues_within,
    simulate_extreme_eigenvalues,
)
from course.nis._statistics import _check_dims, _innovations_and_factor, _nis_matrix_eigenvalues
from course.results import CriticalValues, TestResult, critical_value
from course.validation import as_count, as_probability


def nis_critical_values(m: Any, K: Any, alpha: float = 0.05) -> CriticalValues:
    r"""Two-sided thresholds for the NIS sum ``K * eps_bar ~ chi2(m K)``.

    Parameters
    ----------
    m, K : int
        Innovation dimension and number of steps.
    alpha : float
        Level, split equally between the two tails.

    Returns
    -------
    CriticalValues
        ``(lower, upper) = (chi2_{mK}.ppf(alpha/2), chi2_{mK}.isf(alpha/2))``;
        divide by ``K`` for thresholds on the average ``eps_bar``.

    See Also
    --------
    nis_test : The test these thresholds belong to.
    nis_matrix_critical_values : Thresholds of the NIS-matrix test.

    Notes
    -----
    [F], eq. (4), with the :math:`1/K` of the definition restored:

    .. math::

        K\,\bar\epsilon \sim \chi^2(mK).

    Examples
    --------
    >>> lower, upper = nis_critical_values(2, 50)
    >>> round(lower, 2), round(upper, 2)
    (74.22, 129.56)
    """
    m = as_count(m, "m", what="the innovation dimension")
    K = as_count(K, "K", what="the number of time steps")
    return critical_value(residual_norm_law(m * K), alpha, "two-sided")


@functools.lru_cache(maxsize=64)
def _eigenvalue_null(m: int, K: int) -> TailPair:
    """The null law of the NIS-matrix test, shared (with its cached quantiles) by all calls."""
    return TailPair(
        extreme_eigenvalue(m, K, "min"),
        extreme_eigenvalue(m, K, "max"),
        joint_rvs=lambda size, rng: tuple(simulate_extreme_eigenvalues(m, K, size, rng=rng)),
    )


@functools.lru_cache(maxsize=256)
def _matrix_thresholds(m: int, K: int, alpha: float) -> CriticalValues:
    return critical_value(_eigenvalue_null(m, K), alpha, "two-sided")


@functools.lru_cache(maxsize=256)
def _exact_false_alarm_rate(m: int, K: int, alpha: float) -> float:
    lower, upper = _matrix_thresholds(m, K, alpha)
    return 1.0 - prob_eigenvalues_within(m, K, lower, upper)


def nis_matrix_critical_values(m: Any, K: Any, alpha: float = 0.05) -> CriticalValues:
    r"""Thresholds of the NIS-matrix test: ``(lower for lambda_min, upper for lambda_max)``.

    Parameters
    ----------
    m, K : int
        Innovation dimension and number of steps, ``K >= m``.
    alpha : float
        Level, split equally between the two eigenvalues.

    Returns
    -------
    CriticalValues
        ``(lower, upper)`` with ``P(lambda_min < lower) = alpha/2`` and
        ``P(lambda_max > upper) = alpha/2`` under H0.

    See Also
    --------
    nis_matrix_test : The test these thresholds belong to.
    extreme_eigenvalue : The exact laws whose quantiles they are.
    prob_eigenvalues_within : The exact size of the two-sided test.

    Notes
    -----
    Quantiles (``ppf``/``isf``) of the exact laws of :func:`extreme_eigenvalue`
    ([C14]): :math:`\ell = F_{\min}^{-1}(\alpha/2)` and
    :math:`u = F_{\max}^{-1}(1 - \alpha/2)`.  The false-alarm rate of "reject
    when either is outside" is at most :math:`\alpha` (Bonferroni; both
    together are rare); its exact value is

    .. math::

        1 - P(\ell \le \lambda_{\min},\ \lambda_{\max} \le u),

    computed by :func:`prob_eigenvalues_within` ([C17]).  Cached: a study that
    tests many records of one size pays the root searches once.

    Examples
    --------
    >>> lower, upper = nis_matrix_critical_values(2, 50)
    >>> round(lower, 3), round(upper, 3)
    (0.553, 1.585)
    """
    m, K = _check_dims(m, K)
    return _matrix_thresholds(m, K, as_probability(alpha))


def _single_record(innovations: Any, S: Any):
    eps, L = _innovations_and_factor(innovations, S)
    if eps.ndim != 2:
        raise ValueError(
            f"innovations must be one record of shape (K, m), got shape {eps.shape}; for many runs "
            "use nis()/nis_matrix_eigenvalues() with nis_critical_values()/"
            "nis_matrix_critical_values() (vectorised)"
        )
    return eps, L


def nis_test(innovations: Any, S: Any, alpha: float = 0.05) -> TestResult:
    r"""Two-sided chi-square test of the time-averaged NIS.

    Parameters
    ----------
    innovations : array_like, shape (K, m)
        One record of innovations.
    S : array_like, shape (m, m) or (K, m, m)
        Their covariances as the filter computed them.
    alpha : float
        Level of significance (false-alarm probability).

    Returns
    -------
    TestResult
        ``statistic`` is the NIS sum ``K * eps_bar``, ``null`` is
        ``chi2(m K)``, ``critical_value`` the pair ``(lower, upper)``,
        ``pvalue = 2 min(cdf, sf)``; ``details`` holds ``eps_bar``, ``m``, ``K``.

    See Also
    --------
    nis : The NIS values it averages.
    nis_critical_values : Its two thresholds.
    nis_matrix_test : The test that also sees the direction of an error.
    windowed_chi2_test : The sliding-window form for alarms in time.

    Notes
    -----
    [F], eq. (4), with the poster's :math:`1/K`:

    .. math::

        \bar\epsilon = \frac1K \sum_{k=1}^{K} \epsilon_k, \qquad
        K\,\bar\epsilon \sim \chi^2(mK)

    (not :math:`\bar\epsilon` itself, as the poster states).  This is
    Bar-Shalom's time-average NIS test ([BS], Sec. 5.4.2).  Too small a
    statistic (the filter's :math:`S` too large: a pessimistic filter) is
    rejected as well as too large.

    Examples
    --------
    >>> import numpy as np
    >>> eps = np.random.default_rng(0).standard_normal((50, 2))
    >>> result = nis_test(eps, np.eye(2))
    >>> [round(c, 2) for c in result.critical_value], result.dof
    ([74.22, 129.56], 100)
    """
    eps, L = _single_record(innovations, S)
    K, m = eps.shape
    z = whiten_vectors(L, eps)
    total = float(np.sum(z * z))
    return TestResult.from_null(
        "time-averaged NIS test",
        total,
        residual_norm_law(m * K),
        alpha,
        "two-sided",
        dof=m * K,
        details={"average NIS": total / K, "m": m, "K": K},
    )


def nis_matrix_test(innovations: Any, S: Any, alpha: float = 0.05) -> TestResult:
    r"""Test the NIS matrix through its smallest and largest eigenvalues.

    Parameters
    ----------
    innovations : array_like, shape (K, m)
        One record of innovations, ``K >= m``.
    S : array_like, shape (m, m) or (K, m, m)
        Their covariances as the filter computed them.
    alpha : float
        Level of significance, split equally between the two eigenvalues.

    Returns
    -------
    TestResult
        ``statistic = (lambda_min, lambda_max)`` of ``Pi``,
        ``critical_value = (lower, upper)`` with ``lower`` the
        ``alpha/2``-quantile of the exact law of ``lambda_min`` and ``upper``
        the ``1 - alpha/2``-quantile of ``lambda_max``; H0 is rejected when
        ``lambda_min < lower`` or ``lambda_max > upper``, i.e. when some
        eigenvalue leaves ``[lower, upper]``.
        ``pvalue = min(1, 2 min(F_min(lambda_min), 1 - F_max(lambda_max)))``
        (Bonferroni), so ``reject == (pvalue <= alpha)``.  ``null`` is a
        :class:`course.distributions.TailPair` of the two exact laws (it
        unpacks as ``law_min, law_max``, and draws the eigenvalue pair
        jointly); ``details["exact false-alarm rate"]`` is
        ``1 - P(all eigenvalues in [lower, upper])`` (slightly below
        ``alpha``), from :func:`prob_eigenvalues_within`.

    See Also
    --------
    nis_matrix : The matrix whose extreme eigenvalues it tests.
    nis_matrix_critical_values : Its two thresholds.
    nis_test : The test of the trace alone.

    Notes
    -----
    Under H0 ([F], eq. 3 and the "Statistics" box, with the :math:`1/K`
    restored)

    .. math::

        K\,\Pi \sim W_m(K, I).

    An innovation covariance that is too small in *some* direction pushes
    :math:`\lambda_{\max}(\Pi)` up; too large in some direction pulls
    :math:`\lambda_{\min}(\Pi)` down, even when the trace (the NIS) is
    unchanged.

    Examples
    --------
    >>> import numpy as np
    >>> eps = np.random.default_rng(0).standard_normal((50, 2))
    >>> r = nis_matrix_test(eps, np.eye(2))
    >>> r.null
    TailPair(lower=ExtremeEigenvalue(m=2, K=50, which='min'), upper=ExtremeEigenvalue(m=2, K=50, which='max'))
    """
    eps, L = _single_record(innovations, S)
    alpha = as_probability(alpha)
    K, m = eps.shape
    if m > K:
        raise ValueError(
            f"innovations has K = {K} < m = {m} (steps < outputs): the NIS matrix of fewer "
            "steps than outputs is singular and the Wishart laws do not apply; test at least m steps"
        )
    values = _nis_matrix_eigenvalues(whiten_vectors(L, eps))
    lmin, lmax = float(values[0]), float(values[-1])
    with np.errstate(over="ignore"):
        trace = float(np.sum(values))  # inf where the true trace exceeds double precision
    return TestResult.from_null(
        "NIS-matrix eigenvalue test",
        (lmin, lmax),
        _eigenvalue_null(m, K),
        alpha,
        "two-sided",
        dof=K,
        details={
            "trace (average NIS)": trace,
            "m": m,
            "K": K,
            "exact false-alarm rate": _exact_false_alarm_rate(m, K, alpha),
        },
    )


def consistency_interval(dof: Any, count: Any, alpha: float = 0.05) -> CriticalValues:
    r"""Two-sided interval for an average of ``count`` independent ``chi2(dof)`` values.

    Bar-Shalom's consistency bounds ([BS], Sec. 5.4.2): the **time-averaged**
    NIS of one run over ``K`` steps (``count = K``, ``dof = m``) and the
    **run-averaged** NIS (or NEES, ``dof = n``) at one time step over ``N``
    Monte Carlo runs (``count = N``) both satisfy
    ``count * average ~ chi2(dof * count)``.

    Parameters
    ----------
    dof : int
        Degrees of freedom of each value (``m`` for the NIS, ``n`` for the NEES).
    count : int
        Number of values averaged (``K`` steps or ``N`` runs).
    alpha : float
        Level, split equally between the two tails.

    Returns
    -------
    CriticalValues
        ``chi2_{dof*count}.ppf(alpha/2) / count`` and
        ``chi2_{dof*count}.isf(alpha/2) / count``.

    See Also
    --------
    nis_test : The test of a time-averaged NIS.
    nees : The NEES values the interval also applies to.

    Notes
    -----
    [BS], Sec. 5.4.2: a sum of :math:`n` (``count``) independent
    :math:`\chi^2(d)` values (``dof``) is :math:`\chi^2(nd)`, so the average
    lies in

    .. math::

        \left[\frac{\chi^2_{nd}(\alpha/2)}{n},\ \frac{\chi^2_{nd}(1-\alpha/2)}{n}\right]

    with probability :math:`1 - \alpha` (:math:`\chi^2_{\nu}(p)` the
    :math:`p`-quantile).

    Examples
    --------
    >>> lo, hi = consistency_interval(2, 100)
    >>> round(lo, 4), round(hi, 4)
    (1.6273, 2.4106)
    """
    dof = as_count(dof, "dof", what="degrees of freedom of each value")
    count = as_count(count, "count", what="the number of values averaged")
    lower, upper = critical_value(residual_norm_law(dof * count), alpha, "two-sided")
    return CriticalValues(lower / count, upper / count)
