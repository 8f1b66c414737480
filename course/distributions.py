"""A small base for frozen distributions with the scipy.stats interface.

The course defines a few laws scipy does not have (the extreme eigenvalues of
a Wishart matrix, quadratic forms in normal variables).  They all derive from
:class:`FrozenDistribution`, so every one offers the same methods as a frozen
``scipy.stats`` object: ``cdf``, ``sf``, ``pdf``, ``ppf``, ``isf``, ``mean``,
``var``, ``std``, ``interval`` and ``rvs``.

A subclass implements ``_cdf`` (and, for accuracy in the upper tail, ``_sf``),
``_rvs`` and, where it can, ``_pdf``; quantiles come from a bracketed root
search on the cdf or sf, so they are as accurate as those.
"""

from __future__ import annotations

import numpy as np
from scipy import integrate, optimize

__all__ = ["FrozenDistribution", "as_generator"]


def as_generator(random_state) -> np.random.Generator:
    """Return a :class:`numpy.random.Generator` from a Generator, seed or None.

    Legacy ``RandomState`` objects and the global numpy state are refused:
    randomness in the course always flows through an explicit Generator.
    """
    if isinstance(random_state, np.random.Generator):
        return random_state
    if isinstance(random_state, np.random.RandomState):
        raise TypeError(
            "pass a numpy.random.Generator (np.random.default_rng(seed)), not a legacy RandomState"
        )
    return np.random.default_rng(random_state)


class FrozenDistribution:
    """Base class: scipy-style methods built from ``_cdf``, ``_sf`` and ``_rvs``.

    Attributes
    ----------
    support : tuple of float
        ``(lower, upper)`` end points of the support.
    """

    support: tuple[float, float] = (0.0, np.inf)

    # -- to implement -------------------------------------------------------
    def _cdf(self, x: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _sf(self, x: np.ndarray) -> np.ndarray:
        return 1.0 - self._cdf(x)

    def _pdf(self, x: np.ndarray) -> np.ndarray:
        # Central difference of the cdf: subclasses with a closed form override.
        h = 1e-5 * np.maximum(1.0, np.abs(x))
        return (self._cdf(x + h) - self._cdf(x - h)) / (2 * h)

    def _rvs(self, size, rng: np.random.Generator) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    # -- public interface ---------------------------------------------------
    def cdf(self, x):
        """P(X <= x)."""
        return self._apply(self._cdf, x, below=0.0, above=1.0)

    def sf(self, x):
        """P(X > x), computed directly for accuracy in the upper tail."""
        return self._apply(self._sf, x, below=1.0, above=0.0)

    def pdf(self, x):
        """Probability density at ``x``."""
        return self._apply(self._pdf, x, below=0.0, above=0.0)

    def ppf(self, q):
        """Quantile function: the x with cdf(x) = q."""
        return self._invert(q, self.cdf, increasing=True)

    def isf(self, q):
        """Inverse survival function: the x with sf(x) = q."""
        return self._invert(q, self.sf, increasing=False)

    def interval(self, confidence):
        """Equal-tailed interval holding probability ``confidence``."""
        tail = (1.0 - np.asarray(confidence, dtype=float)) / 2
        return self.ppf(tail), self.isf(tail)

    def mean(self) -> float:
        """E[X], by integrating the survival function (and cdf below 0)."""
        lower, upper = self.support
        upper_part = integrate.quad(lambda t: float(self.sf(t)), max(lower, 0.0), upper, limit=200)[
            0
        ]
        lower_part = 0.0
        if lower < 0:
            lower_part = integrate.quad(
                lambda t: float(self.cdf(t)), lower, min(upper, 0.0), limit=200
            )[0]
        return max(lower, 0.0) + upper_part - lower_part if lower >= 0 else upper_part - lower_part

    def var(self) -> float:
        """``Var[X] = E[X²] − E[X]²``, with ``E[X²] = ∫ 2|t| P(|X| > |t|) dt``."""
        mu = self.mean()
        lower, upper = self.support
        second = integrate.quad(
            lambda t: 2 * t * float(self.sf(t)), max(lower, 0.0), upper, limit=200
        )[0]
        if lower < 0:
            second += integrate.quad(
                lambda t: -2 * t * float(self.cdf(t)), lower, min(upper, 0.0), limit=200
            )[0]
        elif lower > 0:
            second += lower**2
        return second - mu**2

    def std(self) -> float:
        """Standard deviation."""
        return float(np.sqrt(self.var()))

    def rvs(self, size=None, random_state=None):
        """Random draws; ``random_state`` is a Generator (or a seed for one)."""
        return self._rvs(size, as_generator(random_state))

    def __repr__(self) -> str:
        # Deterministic by default (no memory address): the class and its numeric parameters.
        from .results import format_number

        params = [
            f"{key}={format_number(value)}"
            for key, value in vars(self).items()
            if not key.startswith("_")
            and not isinstance(value, bool)
            and isinstance(value, (int, float, np.integer, np.floating))
        ]
        return f"{type(self).__name__}({', '.join(params)})"

    # -- helpers --------------------------------------------------------------
    def _apply(self, func, x, below, above):
        x = np.asarray(x, dtype=float)
        if np.any(np.isnan(x)):
            raise ValueError("x contains NaN")
        lower, upper = self.support
        out = np.empty_like(x)
        inside = (x > lower) & (x < upper)
        out[x <= lower] = below
        out[x >= upper] = above
        if np.any(inside):
            out[inside] = func(x[inside])
        return out[()] if out.ndim == 0 else out

    def _invert(self, q, func, increasing):
        q = np.asarray(q, dtype=float)
        if np.any((q < 0) | (q > 1) | np.isnan(q)):
            raise ValueError("probabilities must lie in [0, 1]")
        lower, upper = self.support
        out = np.empty_like(q)
        for index, target in np.ndenumerate(q):
            if target == 0.0:
                out[index] = lower if increasing else upper
            elif target == 1.0:
                out[index] = upper if increasing else lower
            else:
                out[index] = self._root(func, float(target), increasing)
        return out[()] if out.ndim == 0 else out

    def _root(self, func, target, increasing):
        lower, _upper = self.support
        sign = 1.0 if increasing else -1.0

        def gap(x):
            return sign * (float(func(x)) - target)

        # Grow a bracket from a unit-scale start outward: the support may be
        # unbounded on either side.
        left = lower if np.isfinite(lower) else -1.0
        right = max(left + 1.0, 1.0)
        while gap(right) < 0:
            left, right = right, right * 2 if right > 0 else 1.0
            if right > 1e300:
                raise ValueError("could not bracket the quantile")
        if not np.isfinite(lower):
            while gap(left) > 0:
                right, left = left, left * 2 if left < 0 else -1.0
        return optimize.brentq(
            gap, left, right, xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=500
        )
