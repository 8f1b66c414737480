"""The non-central chi-square law's tails in logarithms, for the root searches of power.

Shared by :func:`course.chi2.noncentrality` and :func:`course.lsq.b_method`: both solve
"the test misses the bias with probability β" for λ or for a threshold, and near power 1
(β down to 1e-15) that is only accurate on the miss probability itself, in logarithms
(``sf - power`` cancels every digit of β). scipy's ``ncx2`` returns NaN beyond about
1e11 degrees of freedom; here the law is its Poisson mixture of central laws,

.. math:: P(\\chi^2(d, \\lambda) \\le x) = \\sum_j \\frac{e^{-\\lambda/2}(\\lambda/2)^j}{j!}
          P(\\chi^2(d + 2j) \\le x),

a sum of positive terms (no cancellation), summed in logarithms over the Poisson
weights' bulk (mean ± 12 standard deviations and 40 terms, beyond which they are below
1e-31 of the sum) (Johnson, Kotz and Balakrishnan 1995, *Continuous univariate
distributions* 2, ch. 29; full reference in the course bibliography,
:doc:`/docs/bibliography`).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, special, stats

#: The largest β = 1 - power whose root search is accurate to 1e-12 (relative): below
#: it power is within a few ulps of 1 and β itself is not known to 1e-12.
SMALLEST_MISS = 0.99e-15  # (1 - power for the float power nearest 1 - 1e-15 is 9.992e-16)


def _terms(lam: float) -> np.ndarray:
    mean = lam / 2.0
    spread = 12.0 * math.sqrt(mean) + 40.0
    return np.arange(max(0, math.floor(mean - spread)), math.ceil(mean + spread) + 1)


def log_cdf(x: float, dof: float, lam: float, upper: bool = False) -> float:
    """``log P(chi2(dof, lam) <= x)`` (``upper``: ``log P(... > x)``)."""
    j = _terms(lam)
    log_weights = stats.poisson.logpmf(j, lam / 2.0) if lam > 0 else np.where(j == 0, 0.0, -np.inf)
    tail = stats.chi2.logsf if upper else stats.chi2.logcdf
    return float(special.logsumexp(log_weights + tail(x, dof + 2.0 * j)))


def noncentrality_for_miss(critical: float, dof: float, miss: float) -> float:
    """λ at which ``P(chi2(dof, λ) <= critical) = miss``, relative accuracy ~1e-15."""
    target = math.log(miss)

    def gap(lam: float) -> float:
        return log_cdf(critical, dof, lam) - target

    upper = 1.0
    while gap(upper) > 0:
        upper *= 2.0
    return float(optimize.brentq(gap, 0.0, upper, xtol=1e-300, rtol=4 * np.finfo(float).eps))


def lower_quantile(miss: float, dof: float, lam: float) -> float:
    """The x with ``P(chi2(dof, lam) <= x) = miss``, relative accuracy ~1e-15."""
    target = math.log(miss)

    def gap(x: float) -> float:
        return log_cdf(x, dof, lam) - target

    mean, spread = dof + lam, math.sqrt(2.0 * (dof + 2.0 * lam))
    hi = mean + spread
    while gap(hi) < 0:
        hi += 4.0 * spread
    lo = max(mean - spread, 0.0)
    while lo > 0 and gap(lo) > 0:
        lo = max(lo - 4.0 * spread, 0.0)
    return float(optimize.brentq(gap, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps))
