"""Consistency tests of one record: the time-averaged NIS test and the NIS-matrix test."""

from __future__ import annotations

import functools

import numpy as np
from scipy import stats

from course.linalg import (
    check_alpha,
)
from course.nis._laws import extreme_eigenvalue, prob_eigenvalues_within
from course.nis._statistics import _check_dims, _check_int, _innovations_and_factor, _whiten
from course.results import TestResult


# ---------------------------------------------------------------------------
# tests and thresholds
# ---------------------------------------------------------------------------
def nis_critical_values(m, K, alpha=0.05) -> tuple[float, float]:
    """Two-sided thresholds for the NIS sum ``K * eps_bar ~ chi2(m K)``.

    Parameters
    ----------
    m, K : int
        Innovation dimension and number of steps.
    alpha : float
        Level, split equally between the two tails.

    Returns
    -------
    (lower, upper) : tuple of float
        ``chi2_{mK}.ppf(alpha/2)`` and ``chi2_{mK}.isf(alpha/2)``; divide by
        ``K`` for thresholds on the average ``eps_bar``.

    Notes
    -----
    [F], eq. (4), with the ``1/K`` of the definition restored:
    ``K eps_bar ~ chi2(mK)``.
    """
    m, K = (
        _check_int(m, "m", 1, "the innovation dimension"),
        _check_int(K, "K", 1, "the number of time steps"),
    )
    alpha = check_alpha(alpha)
    law = stats.chi2(m * K)
    return float(law.ppf(alpha / 2)), float(law.isf(alpha / 2))


@functools.lru_cache(maxsize=256)
def _matrix_thresholds(m: int, K: int, alpha: float) -> tuple[float, float]:
    lower = float(extreme_eigenvalue(m, K, "min").ppf(alpha / 2))
    upper = float(extreme_eigenvalue(m, K, "max").isf(alpha / 2))
    return lower, upper


def nis_matrix_critical_values(m, K, alpha=0.05) -> tuple[float, float]:
    """Thresholds of the NIS-matrix test: ``(lower for lambda_min, upper for lambda_max)``.

    Parameters
    ----------
    m, K : int
        Innovation dimension and number of steps, ``K >= m``.
    alpha : float
        Level, split equally between the two eigenvalues.

    Returns
    -------
    (lower, upper) : tuple of float
        ``P(lambda_min < lower) = alpha/2`` and ``P(lambda_max > upper) =
        alpha/2`` under H0.

    Notes
    -----
    Quantiles (``ppf``/``isf``) of the exact laws of :func:`extreme_eigenvalue`
    ([C14]).  The false-alarm rate of "reject when either is outside" is at
    most ``alpha`` (Bonferroni; both together are rare); its exact value is
    ``1 - prob_eigenvalues_within(m, K, lower, upper)`` ([C17]).
    """
    m, K = _check_dims(m, K)
    alpha = check_alpha(alpha)
    # Cached: a study that tests many records of one size pays the root
    # searches once.
    return _matrix_thresholds(m, K, alpha)


def _single_record(innovations, S):
    eps, L = _innovations_and_factor(innovations, S)
    if eps.ndim != 2:
        raise ValueError(
            f"a test takes one record of shape (K, m), got shape {eps.shape}; for many runs "
            "use nis()/nis_matrix_eigenvalues() with nis_critical_values()/"
            "nis_matrix_critical_values() (vectorised)"
        )
    return eps, L


def nis_test(innovations, S, alpha=0.05) -> TestResult:
    """Two-sided chi-square test of the time-averaged NIS.

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

    Notes
    -----
    [F], eq. (4), with the poster's ``1/K``: ``eps_bar = (1/K) sum eps_k``
    and ``K * eps_bar ~ chi2(m K)`` (not ``eps_bar`` itself, as the poster
    states).  This is Bar-Shalom's time-average NIS test ([BS], Sec. 5.4.2).
    Too small a statistic (the filter's ``S`` too large: a pessimistic
    filter) is rejected as well as too large.
    """
    eps, L = _single_record(innovations, S)
    alpha = check_alpha(alpha)
    K, m = eps.shape
    z = _whiten(L, eps)
    total = float(np.sum(z * z))
    law = stats.chi2(m * K)
    lower, upper = nis_critical_values(m, K, alpha)
    pvalue = min(1.0, 2 * min(float(law.cdf(total)), float(law.sf(total))))
    return TestResult(
        name="time-averaged NIS test",
        statistic=total,
        alpha=alpha,
        critical_value=(lower, upper),
        pvalue=pvalue,
        reject=bool(total < lower or total > upper),
        null=law,
        dof=m * K,
        alternative="two-sided",
        details={"average NIS": total / K, "m": m, "K": K},
    )


def nis_matrix_test(innovations, S, alpha=0.05) -> TestResult:
    """Test the NIS matrix through its smallest and largest eigenvalues.

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
        (Bonferroni), so ``reject == (pvalue <= alpha)``.  ``null`` is the
        pair of exact laws; ``details["exact false-alarm rate"]`` is
        ``1 - P(all eigenvalues in [lower, upper])`` (slightly below
        ``alpha``), from :func:`prob_eigenvalues_within`.

    Notes
    -----
    Under H0, ``K * Pi ~ W_m(K, I)`` ([F], eq. 3 and the "Statistics" box,
    with the ``1/K`` restored).  An innovation covariance that is too small
    in *some* direction pushes ``lambda_max`` up; too large in some
    direction pulls ``lambda_min`` down, even when the trace (the NIS) is
    unchanged.
    """
    eps, L = _single_record(innovations, S)
    alpha = check_alpha(alpha)
    K, m = eps.shape
    _check_dims(m, K)
    z = _whiten(L, eps)
    values = np.linalg.eigvalsh(z.T @ z / K)
    lmin, lmax = float(values[0]), float(values[-1])
    law_min, law_max = extreme_eigenvalue(m, K, "min"), extreme_eigenvalue(m, K, "max")
    lower, upper = _matrix_thresholds(m, K, alpha)
    pvalue = min(1.0, 2 * min(float(law_min.cdf(lmin)), float(law_max.sf(lmax))))
    return TestResult(
        name="NIS-matrix eigenvalue test",
        statistic=(lmin, lmax),
        alpha=alpha,
        critical_value=(lower, upper),
        pvalue=pvalue,
        reject=bool(lmin < lower or lmax > upper),
        null=(law_min, law_max),
        dof=K,
        alternative="two-sided",
        details={
            "trace (average NIS)": float(np.sum(values)),
            "m": m,
            "K": K,
            "exact false-alarm rate": 1.0 - prob_eigenvalues_within(m, K, lower, upper),
        },
    )


def consistency_interval(dof, count, alpha=0.05) -> tuple[float, float]:
    """Two-sided interval for an average of ``count`` independent ``chi2(dof)`` values.

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
    (lower, upper) : tuple of float
        ``chi2_{dof*count}.ppf(alpha/2) / count`` and
        ``chi2_{dof*count}.isf(alpha/2) / count``.

    Notes
    -----
    [BS], Sec. 5.4.2: a sum of ``count`` independent ``chi2(dof)`` values is
    ``chi2(dof * count)``.
    """
    dof = _check_int(dof, "dof", 1, "degrees of freedom of each value")
    count = _check_int(count, "count", 1, "the number of values averaged")
    alpha = check_alpha(alpha)
    law = stats.chi2(dof * count)
    return float(law.ppf(alpha / 2)) / count, float(law.isf(alpha / 2)) / count
