"""Test-suite wide settings and the helpers the test modules share.

Small-matrix BLAS calls are many times slower with a threaded OpenBLAS on a
busy 2-core machine, so the suite (and the notebook kernels nbval starts,
which inherit this environment) runs single-threaded BLAS.

Helpers (import them with ``from conftest import ...``):

:func:`binomial_band`
    The interval that holds the share of successes in ``n`` Bernoulli(``p``)
    trials with probability ``1 - miss``: a Monte Carlo rate outside it is a
    real disagreement, not bad luck.
:func:`assert_rate`
    Assert that a Monte Carlo rate lies in that band, with a readable message.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from scipy import stats  # noqa: E402  (after the thread settings)


def binomial_band(n, p, miss=1e-4):
    """``(lo, hi)``: rates of ``n`` Bernoulli(``p``) trials fall outside with probability ``miss``.

    The argument order is scipy's ``binom(n, p)``.
    """
    lo, hi = stats.binom.interval(1 - miss, n, p)
    return lo / n, hi / n


def assert_rate(rate, n, p, miss=1e-4):
    """Assert that the Monte Carlo ``rate`` of ``n`` trials is consistent with probability ``p``."""
    rate = float(rate)
    lo, hi = binomial_band(n, p, miss)
    assert lo <= rate <= hi, (
        f"rate {rate:.4f} of {n} trials outside the binomial band [{lo:.4f}, {hi:.4f}] "
        f"around {p:.4f}"
    )
