"""The mean, covariance and correlation tests and their power.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

from typing import Any

from course.mismatched._moments import (  # residual_moments, simulate_records: the Examples call them
    ResidualMoments,
    _as_records,
    _check_moments,
    residual_moments,  # noqa: F401
    simulate_records,  # noqa: F401
)
from course.mismatched._quadratic_forms import _KINDS, statistic_law
from course.mismatched._statistics import (
    correlation_statistic,
    covariance_statistic,
    mean_statistic,
    principal_directions,
)
from course.results import TestResult, critical_value, rejection_probability
from course.validation import (
    InputTypeError,
    as_index,
    as_probability,
)


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
    r"""Mean test of section ``j`` on ``||rbar_j||^2``.

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

    See Also
    --------
    covariance_test : The test of the spread of a section.
    correlation_test : The test of two sections together.
    power : The power of these tests against an alternative.

    Notes
    -----
    Baram (1980), (2.5)-(2.6) (squared norm) and (3.2)-(3.3): under the null
    pair :math:`\bar r_j \sim N(m_j, P_j / M)`, so the statistic
    :math:`\lVert \bar r_j \rVert^2` is a noncentral quadratic form
    (:class:`course.quadform.QuadraticForm`).

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

    See Also
    --------
    mean_test : The test of the mean of a section.
    statistic_law : The law of the statistic.

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
    r"""Correlation test of sections ``j`` and ``k`` (trace, or a singular pair).

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

    See Also
    --------
    mean_test : The test of the mean of a section.
    statistic_law : The law of the statistic.

    Notes
    -----
    Baram (1980), (2.7)-(2.12) with an SVD for the non-symmetric
    :math:`C(j, k)`; the law has weights of both signs (the eigenvalues of
    :math:`S^{1/2} \begin{bmatrix} 0 & I \\ I & 0 \end{bmatrix} S^{1/2} / (2M)`),
    so Imhof's method handles what a chi-square table cannot.

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

    See Also
    --------
    mean_test : The mean test.
    covariance_test : The covariance test.
    correlation_test : The correlation test.

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
