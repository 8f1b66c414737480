"""Chi-square tests of a squared residual norm: null law, threshold, power, non-centrality.

Every module of the course ends in the same test: a squared norm of
residuals ``T`` (the overall model test's ``ê^T Qyy^{-1} ê``, a prediction
error ``||(I - P) y||^2``, a window of NIS values, a Wald statistic) is
``sigma^2 chi2(dof)`` under H0 and ``sigma^2 chi2'(dof, lambda)`` (non-central)
when a fault shifts its mean.  This module is the one home of that idea:

:func:`residual_norm_law`
    The null law ``sigma^2 chi2(dof)``, frozen once and cached.
:func:`residual_threshold`
    Its upper ``alpha``-quantile, the threshold of a level-``alpha`` test.
:func:`chi2_power`
    ``P(T > threshold)`` when ``T / sigma^2 ~ chi2'(dof, lambda)``.
:func:`noncentrality`
    The ``lambda`` at which the test reaches a given power (the inverse of
    :func:`chi2_power`), for minimal detectable biases.

The chi-square laws follow from Cochran's theorem (Cochran 1934); the minimal detectable
bias is Baarda's (1968), with Teunissen (2000): full references in the course bibliography,
:doc:`/docs/bibliography`.

Conventions: the law's parameters come first, ``alpha`` after them, scale
parameters (``sigma``) are keyword-only.

Examples
--------
The threshold of the chapter's overall model test, m - n = 2, alpha = 1 %:

>>> round(residual_threshold(2, 0.01), 4)
9.2103
>>> round(chi2_power(1, 17.07, 0.001), 3)
0.8
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
from scipy import stats

from course._noncentral import SMALLEST_MISS, noncentrality_for_miss
from course.validation import as_count, as_float_array, as_probability, as_std

__all__ = ["chi2_power", "noncentrality", "residual_norm_law", "residual_threshold"]


@lru_cache(maxsize=256)
def _frozen_chi2(dof: int, scale: float) -> Any:
    # Freezing a scipy distribution costs ~1 ms; Monte Carlo loops reuse it.
    return stats.chi2(dof) if scale == 1.0 else stats.chi2(dof, scale=scale)


def residual_norm_law(dof: Any, *, sigma: Any = 1.0) -> Any:
    r"""Null law of a squared residual norm: ``sigma^2 chi2(dof)`` (frozen scipy law).

    Parameters
    ----------
    dof : int
        Residual degrees of freedom (observations minus estimated parameters).
    sigma : float, default 1
        Noise standard deviation (1 when the residuals are already normalised);
        ``sigma**2`` must be a normal double (``sigma`` between about 1e-154
        and 1e154), else a ValueError says to rescale the data.

    Returns
    -------
    scipy.stats frozen distribution
        ``chi2(dof)``, or ``chi2(dof, scale=sigma**2)``; cached, so repeated
        calls in a Monte Carlo loop cost nothing.

    See Also
    --------
    residual_threshold : The critical value of a residual norm test.
    noncentrality : The non-centrality a test needs for a given power.

    Notes
    -----
    Cochran's theorem: a Gaussian vector :math:`v \sim N(0, \sigma^2 I)`
    projected on a subspace of dimension :math:`d` (``dof``) by the orthogonal
    projection :math:`P` has

    .. math::

        \frac{\lVert P v \rVert^2}{\sigma^2} \sim \chi^2(d).

    Examples
    --------
    >>> float(residual_norm_law(3).mean())
    3.0
    >>> round(float(residual_norm_law(3, sigma=2.0).mean()), 12)
    12.0
    """
    dof = as_count(dof, "dof", what="the residual degrees of freedom")
    # the law's scale is sigma**2: refused where it over- or underflows
    sigma = as_std(sigma, "sigma", what="the noise standard deviation")
    return _frozen_chi2(dof, sigma**2)


def residual_threshold(dof: Any, alpha: Any = 0.05, *, sigma: Any = 1.0) -> float:
    r"""Threshold ``J`` on ``T = ||residual||^2`` with false-alarm rate ``alpha``.

    Parameters
    ----------
    dof : int
        Residual degrees of freedom ``N - rank``.
    alpha : float, default 0.05
        False-alarm probability ``P(T > J | H0)``.
    sigma : float, default 1
        Noise standard deviation (keyword-only); as in :func:`residual_norm_law`.

    Returns
    -------
    float
        ``J = sigma^2 * chi2.isf(alpha, dof)``.

    See Also
    --------
    residual_norm_law : The law this threshold is a quantile of.
    course.lsq.overall_model_test : The same test on a least-squares fit.

    Notes
    -----
    Under H0 the residual is :math:`(I - P) v` with
    :math:`v \sim N(0, \sigma^2 I)` and :math:`I - P` an orthogonal projection
    of rank :math:`N - \operatorname{rank}(\Phi)`, so (Cochran's theorem)

    .. math::

        \frac{T}{\sigma^2} \sim \chi^2(N - \operatorname{rank}\Phi), \qquad
        J = \sigma^2 \chi^2_{N - \operatorname{rank}\Phi}(1 - \alpha).

    Examples
    --------
    >>> round(residual_threshold(49, 0.05, sigma=0.2), 5)
    2.65355
    """
    alpha = as_probability(alpha)
    return float(residual_norm_law(dof, sigma=sigma).isf(alpha))


def chi2_power(dof: Any, noncentrality: Any, alpha: Any = 0.05) -> Any:
    """Power of the level-``alpha`` chi-square test when ``T ~ chi2'(dof, lambda)``.

    Parameters
    ----------
    dof : int
        Degrees of freedom of the test.
    noncentrality : float or array_like
        ``lambda >= 0`` (0: no fault, the power is ``alpha``).
    alpha : float, default 0.05
        Level of the test.

    Returns
    -------
    float or numpy.ndarray
        ``ncx2.sf(chi2.isf(alpha, dof), dof, lambda)``, shaped like ``noncentrality``.

    Examples
    --------
    >>> chi2_power(2, [0.0, 10.0], 0.01).round(4)
    array([0.01  , 0.6148])
    """
    dof = as_count(dof, "dof")
    alpha = as_probability(alpha)
    lam = as_float_array(noncentrality, "noncentrality")
    if np.any(lam < 0):
        raise ValueError(
            f"noncentrality must be non-negative (it is a squared bias over a variance), "
            f"got {lam.min()!r}"
        )
    critical = residual_norm_law(dof).isf(alpha)
    # ncx2 at lambda = 0 is the central law; scipy wants lambda > 0.
    power = np.where(lam > 0, stats.ncx2.sf(critical, dof, np.maximum(lam, 1e-300)), alpha)
    return float(power) if power.ndim == 0 else power


def noncentrality(alpha: Any, power: Any, dof: Any = 1) -> float:
    r"""Non-centrality λ0 at which a chi-square test has the given power.

    Parameters
    ----------
    alpha : float
        Level of significance of the test, in (0, 1).
    power : float
        Required detection probability ``γ = 1 - β``, with ``alpha < power < 1``.
    dof : int
        Degrees of freedom of the test (1 for the w-test).

    Returns
    -------
    float
        λ0 solving ``chi2_power(dof, λ0, alpha) = power``.

    See Also
    --------
    residual_norm_law : The central law under H0.
    course.lsq.mdb : The smallest outlier a w-test finds with this power.
    course.diagnosis.fault_noncentrality : The non-centrality a fault produces.

    Notes
    -----
    Under an alternative with bias the test statistic follows a non-central
    :math:`\chi^2(d, \lambda)`; the power grows with :math:`\lambda`, and
    :math:`\lambda_0` solves

    .. math::

        P\bigl(\chi^2(d, \lambda_0) > \chi^2_d(1 - \alpha)\bigr) = \gamma

    (found with ``scipy.optimize.brentq`` on :math:`\log P(\chi^2(d, \lambda) \le
    \chi^2_d(1 - \alpha)) = \log(1 - \gamma)`, the miss probability in logarithms, so
    that λ0 is accurate to about 1e-15 relative up to :math:`\gamma = 1 - 10^{-15}`;
    nearer 1 is refused). For :math:`d = 1` the test
    :math:`w^2 > \chi^2_1(1 - \alpha)` is the two-sided w-test, whose power is

    .. math::

        \Phi(\sqrt\lambda - z_{\alpha/2}) + \Phi(-\sqrt\lambda - z_{\alpha/2});

    dropping the (tiny) second term gives the familiar approximation
    :math:`\sqrt{\lambda_0} \approx z_{\alpha/2} + z_{1-\gamma}` with
    :math:`z_{1-\gamma} = \Phi^{-1}(\gamma)` (e.g. 17.07 for
    :math:`\alpha = 0.001`, :math:`\gamma = 0.80`), which slightly overstates the
    exact :math:`\lambda_0`. Reference: W. Baarda (1968), *A testing procedure
    for use in geodetic networks*; P. J. G. Teunissen (2000), *Testing theory*,
    ch. 4. (The non-centrality a given fault *produces* in a test is
    :func:`course.diagnosis.fault_noncentrality`.)

    Examples
    --------
    >>> round(noncentrality(0.001, 0.80), 2)
    17.07
    """
    alpha = as_probability(alpha)
    power = as_probability(power, "power")
    dof = as_count(dof, "dof")
    if power <= alpha:
        raise ValueError(
            f"power ({power!r}) must exceed alpha ({alpha!r}): even without a bias the test "
            "rejects with probability alpha"
        )
    miss = 1.0 - power
    if miss < SMALLEST_MISS:
        raise ValueError(
            f"power must be at most 1 - 1e-15, got {power!r}: nearer 1 the miss probability "
            "1 - power is not known to 12 digits in double precision, and neither is λ0"
        )
    critical = float(residual_norm_law(dof).isf(alpha))
    # On the miss probability β = 1 - power, in logarithms: near power 1 the gap
    # sf - power would cancel every digit of β (λ0 3 % off at power 1 - 1e-16).
    return noncentrality_for_miss(critical, dof, miss)
