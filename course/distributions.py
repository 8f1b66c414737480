"""Frozen distributions with the scipy.stats interface.

The course defines a few laws scipy does not have (the extreme eigenvalues of
a Wishart matrix, quadratic forms in normal variables, the maximised
log-likelihood).  They all derive from :class:`FrozenDistribution`, so every
one offers the methods of a frozen ``scipy.stats`` object: ``cdf``, ``sf``,
``logcdf``, ``logsf``, ``pdf``, ``ppf``, ``isf``, ``support()``, ``median``,
``mean``, ``var``, ``std``, ``interval``, ``expect`` and ``rvs``.

A subclass implements ``_cdf`` (and, for accuracy in the upper tail, ``_sf``),
``_rvs`` and, where it can, ``_pdf``; it states its support in ``_bounds``.
Quantiles come from a bracketed root search on the cdf or sf, so they are as
accurate as those.

:class:`TailPair` is the null law of a two-sided test that judges *two*
statistics, one per tail (the smallest and largest eigenvalue of the NIS
matrix).

Random draws take ``rng=`` (a :class:`numpy.random.Generator` or a seed), as
everything random in the course does; ``random_state=`` is deprecated.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from scipy import integrate, optimize

from course import _deprecation
from course.validation import (
    as_callable,
    as_finite,
    as_flag,
    as_float_array,
    as_generator,
    as_law,
    as_size,
)

__all__ = ["FrozenDistribution", "TailPair", "as_generator"]

_NO_STATE = object()


def _rng_argument(rng: Any, random_state: Any, where: str) -> np.random.Generator:
    """The generator of a call that may still use the deprecated ``random_state=``."""
    if random_state is not _NO_STATE:
        if rng is not None:
            raise TypeError(f"{where}: pass rng= only (random_state= is its deprecated name)")
        _deprecation.warn(f"{where}: random_state= is now rng=", stacklevel=4)
        rng = random_state
    return as_generator(rng)


class _Support(tuple):
    """``(lower, upper)`` that is also callable: ``law.support()`` as in scipy.

    Reading it as a tuple (the old attribute form) still works, with a
    DeprecationWarning.
    """

    def __call__(self) -> tuple[float, float]:
        return (self._lower, self._upper)

    @property
    def _lower(self) -> float:
        return tuple.__getitem__(self, 0)

    @property
    def _upper(self) -> float:
        return tuple.__getitem__(self, 1)

    def __iter__(self) -> Iterator[float]:
        _deprecation.warn("law.support is a method now: write law.support()")
        return tuple.__iter__(self)

    def __getitem__(self, index: Any) -> Any:
        _deprecation.warn("law.support is a method now: write law.support()")
        return tuple.__getitem__(self, index)


class FrozenDistribution:
    """Base class: scipy-style methods built from ``_cdf``, ``_sf`` and ``_rvs``.

    Subclasses set ``_bounds = (lower, upper)``, the end points of the
    support, as a class attribute or in ``__init__``.

    Examples
    --------
    A uniform law on [0, 2], from its cdf alone:

    >>> class Uniform2(FrozenDistribution):
    ...     _bounds = (0.0, 2.0)
    ...     def _cdf(self, x):
    ...         return x / 2
    ...     def _rvs(self, size, rng):
    ...         return rng.uniform(0.0, 2.0, size)
    >>> law = Uniform2()
    >>> law.support(), float(law.median()), round(law.mean(), 12)
    ((0.0, 2.0), 1.0, 1.0)
    >>> round(float(law.expect(lambda x: x**2)), 12)
    1.333333333333
    """

    _bounds: tuple[float, float] = (0.0, np.inf)

    @property
    def support(self) -> _Support:
        """``support()`` gives ``(lower, upper)``, the end points of the support."""
        return _Support(self._bounds)

    @support.setter
    def support(self, bounds: tuple[float, float]) -> None:
        self._bounds = (float(bounds[0]), float(bounds[1]))

    # -- to implement -------------------------------------------------------
    def _cdf(self, x: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _sf(self, x: np.ndarray) -> np.ndarray:
        return 1.0 - self._cdf(x)

    def _pdf(self, x: np.ndarray) -> np.ndarray:
        # Central difference of the cdf: subclasses with a closed form override.
        h = 1e-5 * np.maximum(1.0, np.abs(x))
        return (self._cdf(x + h) - self._cdf(x - h)) / (2 * h)

    def _rvs(self, size: Any, rng: np.random.Generator) -> Any:  # pragma: no cover
        raise NotImplementedError

    # -- public interface ---------------------------------------------------
    def cdf(self, x: Any) -> Any:
        """P(X <= x)."""
        return self._apply(self._cdf, x, below=0.0, above=1.0)

    def sf(self, x: Any) -> Any:
        """P(X > x), computed directly for accuracy in the upper tail."""
        return self._apply(self._sf, x, below=1.0, above=0.0)

    def logcdf(self, x: Any) -> Any:
        """log P(X <= x) (``-inf`` below the support)."""
        with np.errstate(divide="ignore"):
            return np.log(self.cdf(x))

    def logsf(self, x: Any) -> Any:
        """log P(X > x), from the directly computed upper tail."""
        with np.errstate(divide="ignore"):
            return np.log(self.sf(x))

    def pdf(self, x: Any) -> Any:
        """Probability density at ``x``."""
        return self._apply(self._pdf, x, below=0.0, above=0.0)

    def ppf(self, q: Any) -> Any:
        """Quantile function: the x with cdf(x) = q."""
        return self._invert(q, self.cdf, increasing=True)

    def isf(self, q: Any) -> Any:
        """Inverse survival function: the x with sf(x) = q."""
        return self._invert(q, self.sf, increasing=False)

    def median(self) -> float:
        """The median, ``ppf(0.5)``."""
        return float(self.ppf(0.5))

    def interval(self, confidence: Any) -> tuple[Any, Any]:
        """Equal-tailed interval holding probability ``confidence``."""
        tail = (1.0 - _levels(confidence, "confidence")) / 2
        return self.ppf(tail), self.isf(tail)

    def mean(self) -> float:
        """E[X], by integrating the survival function (and cdf below 0)."""
        lower, upper = self._bounds
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
        lower, upper = self._bounds
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

    def expect(
        self,
        func: Callable[[float], float] | None = None,
        lb: float | None = None,
        ub: float | None = None,
        conditional: bool = False,
    ) -> float:
        """E[func(X)] (over ``[lb, ub]``), by integrating ``func`` against the density.

        As :meth:`scipy.stats.rv_continuous.expect`: ``func`` defaults to the
        identity, the bounds to the support; ``conditional=True`` divides by
        the probability of ``[lb, ub]``.
        """
        lower, upper = self._bounds
        lb = lower if lb is None else max(_bound(lb, "lb"), lower)
        ub = upper if ub is None else min(_bound(ub, "ub"), upper)
        if lb > ub:
            raise ValueError(f"lb = {lb} exceeds ub = {ub}: the interval of integration is empty")
        func = as_callable(func, "func", optional=True)
        conditional = as_flag(conditional, "conditional")
        f = (lambda x: x) if func is None else func
        value = integrate.quad(lambda x: f(x) * float(self.pdf(x)), lb, ub, limit=200)[0]
        if conditional:
            value /= float(self.cdf(ub)) - float(self.cdf(lb))
        return float(value)

    def rvs(self, size: Any = None, random_state: Any = _NO_STATE, *, rng: Any = None) -> Any:
        """Random draws from a Generator ``rng`` (or a seed for one).

        ``random_state=`` is the deprecated name of ``rng=``.
        """
        generator = _rng_argument(rng, random_state, f"{type(self).__name__}.rvs")
        return self._rvs(as_size(size), generator)

    def __repr__(self) -> str:
        # Deterministic by default (no memory address): the class and its numeric parameters.
        from course.results import format_number

        params = [
            f"{key}={format_number(value)}"
            for key, value in vars(self).items()
            if not key.startswith("_")
            and not isinstance(value, bool)
            and isinstance(value, (int, float, np.integer, np.floating))
        ]
        return f"{type(self).__name__}({', '.join(params)})"

    # -- helpers --------------------------------------------------------------
    def _apply(self, func: Callable, x: Any, below: float, above: float) -> Any:
        x = _points(x)
        lower, upper = self._bounds
        out = np.empty_like(x)
        inside = (x > lower) & (x < upper)
        out[x <= lower] = below
        out[x >= upper] = above
        if np.any(inside):
            out[inside] = func(x[inside])
        return out[()] if out.ndim == 0 else out

    def _invert(self, q: Any, func: Callable, increasing: bool) -> Any:
        if isinstance(q, (float, int)) and not isinstance(q, bool) and 0.0 <= q <= 1.0:
            # A frozen law does not change: a test's critical values (root
            # searches on an exact cdf) are computed once per law and level.
            memo = self.__dict__.setdefault("_quantile_memo", {})
            key = (increasing, float(q))
            if key not in memo:
                memo[key] = self._invert(np.asarray(q, dtype=float), func, increasing)
            return memo[key]
        q = _levels(q)
        lower, upper = self._bounds
        out = np.empty_like(q)
        for index, target in np.ndenumerate(q):
            if target == 0.0:
                out[index] = lower if increasing else upper
            elif target == 1.0:
                out[index] = upper if increasing else lower
            else:
                out[index] = self._root(func, float(target), increasing)
        return out[()] if out.ndim == 0 else out

    def _root(self, func: Callable, target: float, increasing: bool) -> float:
        lower, _upper = self._bounds
        sign = 1.0 if increasing else -1.0

        def gap(x: float) -> float:
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
        return float(
            optimize.brentq(gap, left, right, xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=500)
        )


def _points(x: Any, name: str = "x") -> np.ndarray:
    """Points where a law is evaluated: real numbers, +-inf allowed, NaN refused."""
    return as_float_array(x, name, finite=False)


def _levels(q: Any, name: str = "q") -> np.ndarray:
    """Probabilities for ``ppf``/``isf``: real numbers in [0, 1] (True is not 1)."""
    if isinstance(q, (bool, np.bool_)) or getattr(getattr(q, "dtype", None), "kind", "") == "b":
        raise ValueError(f"{name} must be probabilities (numbers in [0, 1]), got {q!r}")
    q = as_float_array(q, name)
    if np.any((q < 0) | (q > 1)):
        raise ValueError(f"{name}: probabilities must lie in [0, 1], got {q}")
    return q


def _bound(value: Any, name: str) -> float:
    """An integration bound: a real number or +-inf."""
    if isinstance(value, (int, float, np.integer, np.floating)) and np.isinf(value):
        return float(value)
    return as_finite(value, name)


class TailPair:
    """Null law of a two-sided test that judges a pair of statistics ``(low, high)``.

    The lower tail is that of ``lower`` (the law of ``low``), the upper tail
    that of ``upper`` (the law of ``high``): ``cdf`` and ``ppf`` are
    ``lower``'s, ``sf`` and ``isf`` are ``upper``'s.  With the course's
    decision path (:func:`course.results.decide`) this gives the critical
    values ``(lower.ppf(alpha/2), upper.isf(alpha/2))`` and the Bonferroni
    p-value ``min(1, 2 min(lower.cdf(low), upper.sf(high)))``.  It is not a
    univariate law (``cdf + sf != 1``): it is the pair of tails a two-sided
    decision needs.

    Parameters
    ----------
    lower, upper : Law
        Laws of the two statistics.
    joint_rvs : callable, optional
        ``joint_rvs(size, rng) -> (low, high)``: draws of the *pair* (the two
        statistics are usually dependent); without it :meth:`rvs` raises.

    Notes
    -----
    Unpacking still works (``law_min, law_max = result.null``), as when the
    null of the NIS-matrix test was a tuple of two laws.

    Examples
    --------
    >>> from scipy import stats
    >>> pair = TailPair(stats.norm(loc=-1), stats.norm(loc=1))
    >>> round(float(pair.ppf(0.025)), 4), round(float(pair.isf(0.025)), 4)
    (-2.96, 2.96)
    """

    def __init__(
        self,
        lower: Any,
        upper: Any,
        joint_rvs: Callable[[Any, np.random.Generator], tuple[Any, Any]] | None = None,
    ):
        self.lower = as_law(lower, "lower")
        self.upper = as_law(upper, "upper")
        self._joint_rvs = as_callable(joint_rvs, "joint_rvs", optional=True)

    def cdf(self, x: Any) -> Any:
        """P(low <= x), the lower tail."""
        return self.lower.cdf(_points(x))

    def sf(self, x: Any) -> Any:
        """P(high > x), the upper tail."""
        return self.upper.sf(_points(x))

    def ppf(self, q: Any) -> Any:
        """Quantile of ``low``."""
        return self.lower.ppf(_levels(q)[()])

    def isf(self, q: Any) -> Any:
        """Inverse survival function of ``high``."""
        return self.upper.isf(_levels(q)[()])

    def rvs(self, size: Any = None, *, rng: Any = None) -> tuple[Any, Any]:
        """Joint draws ``(low, high)``, when a joint sampler was given."""
        if self._joint_rvs is None:
            raise NotImplementedError(
                "this TailPair has no joint sampler: the two statistics are dependent, "
                "so drawing each from its own law would be wrong"
            )
        return self._joint_rvs(as_size(size), as_generator(rng))

    def __iter__(self) -> Iterator[Any]:
        return iter((self.lower, self.upper))

    def __getitem__(self, index: int) -> Any:
        return (self.lower, self.upper)[index]

    def __len__(self) -> int:
        return 2

    def __repr__(self) -> str:
        from course.results import describe_distribution

        return (
            f"TailPair(lower={describe_distribution(self.lower)}, "
            f"upper={describe_distribution(self.upper)})"
        )
