"""The shared result vocabulary of the course.

Every statistical test in the library returns a :class:`TestResult`.  It
always carries the same fields, so a student who has read one result can read
them all:

``statistic``
    the observed value of the test quantity,
``dof``
    its degrees of freedom, where the null law has them (else ``None``),
``alpha``
    the level of significance (the false-alarm probability),
``critical_value``
    the threshold; a ``(lower, upper)`` pair for a two-sided test,
``pvalue``
    the probability under H0 of a value at least as extreme,
``reject``
    the decision, ``True`` when H0 is rejected,
``null``
    the distribution of the statistic under H0, a frozen scipy-style object
    with ``cdf``, ``sf``, ``ppf``, ``isf`` and ``rvs`` (the :class:`Law`
    protocol).

All numbers are stored as plain Python ``float``/``int``/``bool``, so what is
printed never shows numpy scalar reprs, and the ``repr`` is short and
deterministic (no addresses, no timestamps).

One decision path
-----------------
Critical value, p-value and decision always come from the frozen null law,
by :func:`decide` (for arrays of statistics too) or
:meth:`TestResult.from_null`:

=============  ==========================  ==============================  ===================
alternative    critical value              p-value                         reject H0 when
=============  ==========================  ==============================  ===================
``greater``    ``null.isf(alpha)``         ``null.sf(T)``                  ``T > critical``
``less``       ``null.ppf(alpha)``         ``null.cdf(T)``                 ``T < critical``
``two-sided``  ``(null.ppf(alpha/2),       ``min(1, 2 min(null.cdf(T),     ``T`` outside the pair
               null.isf(alpha/2))``        null.sf(T)))``
=============  ==========================  ==============================  ===================

A two-sided test may also decide on a *pair* of statistics ``(low, high)``
(the smallest and largest eigenvalue of the NIS matrix): the lower tail is
then judged on ``low`` and the upper tail on ``high``, with a
:class:`course.distributions.TailPair` as the null law.  For continuous
laws ``reject == (pvalue < alpha)`` up to rounding, and
:meth:`TestResult.power` gives the probability of the same critical region
under any other law.
"""

from __future__ import annotations

import html
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np

__all__ = [
    "ALTERNATIVES",
    "CriticalValues",
    "Decision",
    "Law",
    "TestResult",
    "as_plain",
    "critical_value",
    "decide",
    "describe_distribution",
    "format_number",
    "rejection_probability",
]

ALTERNATIVES = ("greater", "less", "two-sided")
_ALTERNATIVES = ALTERNATIVES


@runtime_checkable
class Law(Protocol):
    """A frozen univariate law, as scipy.stats' frozen distributions are.

    What the decision path needs: ``cdf``, ``sf`` and their inverses
    ``ppf``, ``isf``; what simulation needs: ``rvs``.  Every frozen
    ``scipy.stats`` distribution and every
    :class:`course.distributions.FrozenDistribution` satisfies it.
    """

    def cdf(self, x: Any) -> Any: ...

    def sf(self, x: Any) -> Any: ...

    def ppf(self, q: Any) -> Any: ...

    def isf(self, q: Any) -> Any: ...

    def rvs(self, *args: Any, **kwargs: Any) -> Any: ...


class CriticalValues(NamedTuple):
    """The two thresholds of a two-sided test: reject outside ``[lower, upper]``."""

    lower: float
    upper: float


class Decision(NamedTuple):
    """Result of :func:`decide`."""

    critical_value: Any
    """A float, or a :class:`CriticalValues` pair for a two-sided test."""
    pvalue: Any
    """A float, or an array shaped like the statistic."""
    reject: Any
    """A bool, or a boolean array shaped like the statistic."""


def _check_alternative(alternative: str) -> str:
    if not isinstance(alternative, str) or alternative not in ALTERNATIVES:
        raise ValueError(f"alternative must be one of {ALTERNATIVES}, got {alternative!r}")
    return alternative


def critical_value(null: Law, alpha: float, alternative: str = "greater") -> Any:
    """The threshold(s) of a level-``alpha`` test from its null law.

    Parameters
    ----------
    null : Law
        Law of the statistic under H0.
    alpha : float
        Level of significance, in (0, 1).
    alternative : {"greater", "less", "two-sided"}

    Returns
    -------
    float or CriticalValues
        ``null.isf(alpha)``, ``null.ppf(alpha)`` or the pair
        ``(null.ppf(alpha/2), null.isf(alpha/2))``.

    Examples
    --------
    >>> from scipy import stats
    >>> round(critical_value(stats.chi2(2), 0.01), 4)
    9.2103
    >>> critical_value(stats.norm(), 0.05, "two-sided")  # doctest: +ELLIPSIS
    CriticalValues(lower=-1.959..., upper=1.959...)
    """
    from course.validation import as_law, as_probability

    null = as_law(null, "null")
    alpha = as_probability(alpha)
    alternative = _check_alternative(alternative)
    if alternative == "greater":
        return float(null.isf(alpha))
    if alternative == "less":
        return float(null.ppf(alpha))
    return CriticalValues(float(null.ppf(alpha / 2)), float(null.isf(alpha / 2)))


def _statistic(value: Any, name: str = "statistic") -> np.ndarray:
    """A statistic (or an array of them): real, not NaN; +-inf is a possible value."""
    from course.validation import as_float_array

    return as_float_array(value, name, finite=False, empty=False)


def _tails(statistic: Any, alternative: str):
    """The statistic judged in the lower and in the upper tail."""
    if alternative == "two-sided" and isinstance(statistic, tuple):
        if len(statistic) != 2:
            raise ValueError(
                "a two-sided test on several statistics takes a pair (low, high), "
                f"got {len(statistic)} values"
            )
        return _statistic(statistic[0]), _statistic(statistic[1])
    value = _statistic(statistic)
    return value, value


def _scalar_or_array(value: Any) -> Any:
    value = np.asarray(value)
    return value.item() if value.ndim == 0 else value


def decide(null: Law, statistic: Any, alpha: float, alternative: str = "greater") -> Decision:
    """Critical value, p-value and decision of a test, from its frozen null law.

    The course's one decision path: every test computes these three numbers
    here (see the table in the module docstring).

    Parameters
    ----------
    null : Law
        Law of the statistic under H0.
    statistic : float, array_like or pair
        The observed statistic; an array (or list) gives one decision per
        entry; for a two-sided test, a *tuple* ``(low, high)`` judges ``low``
        against the lower tail and ``high`` against the upper one.
    alpha : float
        Level of significance, in (0, 1).
    alternative : {"greater", "less", "two-sided"}

    Returns
    -------
    Decision
        ``(critical_value, pvalue, reject)``.

    Examples
    --------
    >>> from scipy import stats
    >>> d = decide(stats.chi2(2), 216.0, 0.01)
    >>> round(d.critical_value, 4), d.reject
    (9.2103, True)
    >>> d = decide(stats.norm(), [0.5, -3.0], 0.05, "two-sided")
    >>> d.reject
    array([False,  True])
    """
    alternative = _check_alternative(alternative)
    critical = critical_value(null, alpha, alternative)
    low, high = _tails(statistic, alternative)
    if alternative == "greater":
        pvalue, reject = null.sf(high), high > critical
    elif alternative == "less":
        pvalue, reject = null.cdf(low), low < critical
    else:
        tails = np.minimum(np.asarray(null.cdf(low), float), np.asarray(null.sf(high), float))
        pvalue = np.minimum(1.0, 2.0 * tails)
        reject = (low < critical.lower) | (high > critical.upper)
    return Decision(critical, _scalar_or_array(pvalue), _scalar_or_array(reject))


def rejection_probability(law: Law, critical: Any, alternative: str = "greater") -> float:
    """Probability that a statistic with law ``law`` falls in the critical region.

    Under the null law this is the level; under an alternative it is the
    power.  For a two-sided region it is ``law.cdf(lower) + law.sf(upper)``.

    Examples
    --------
    >>> from scipy import stats
    >>> round(rejection_probability(stats.norm(loc=3), 1.6449, "greater"), 4)
    0.9123
    """
    from course.validation import as_finite, as_law

    law = as_law(law, "law")
    alternative = _check_alternative(alternative)
    if alternative == "two-sided":
        lower, upper = _critical_pair(critical)
        # a law that evaluates both tails of several points in one call (the
        # quadratic forms: one integral setup instead of two) says so by `_outside`
        outside = getattr(law, "_outside", None)
        if outside is not None:
            return float(outside(lower, upper))
        return float(law.cdf(lower) + law.sf(upper))
    if isinstance(critical, tuple):
        raise ValueError(
            f"critical must be one number for a {alternative!r} test, got {critical!r}"
        )
    critical = as_finite(critical, "critical", what="the critical value")
    if alternative == "greater":
        return float(law.sf(critical))
    return float(law.cdf(critical))


def _critical_pair(critical: Any, name: str = "critical") -> tuple[float, float]:
    """The ``(lower, upper)`` thresholds of a two-sided test."""
    from course.validation import as_finite

    if isinstance(critical, (str, bytes)) or not isinstance(critical, (tuple, list)):
        raise ValueError(
            f"{name} of a two-sided test must be a pair (lower, upper), got {critical!r}"
        )
    if len(critical) != 2:
        raise ValueError(
            f"{name} of a two-sided test must be a pair (lower, upper), got {critical!r}"
        )
    lower, upper = (as_finite(c, name, what="a critical value") for c in critical)
    if lower > upper:
        raise ValueError(f"{name} = ({lower}, {upper}): the lower threshold exceeds the upper one")
    return lower, upper


_ALTERNATIVES = ("greater", "less", "two-sided")


def as_plain(value: Any) -> Any:
    """Convert numpy scalars (and tuples/lists of them) to plain Python values.

    Arrays are returned unchanged: only scalars are converted, so that a
    result prints ``6.0`` and never ``np.float64(6.0)``.

    Examples
    --------
    >>> import numpy as np
    >>> as_plain((np.float64(6.0), np.int64(2)))
    (6.0, 2)
    """
    # numpy scalars first: np.float64 subclasses float and would slip through.
    if isinstance(value, np.generic) or (isinstance(value, np.ndarray) and value.ndim == 0):
        return value.item()
    if isinstance(value, (tuple, list)):
        return _same_sequence_type(value, [as_plain(v) for v in value])
    return value


def _same_sequence_type(template: Any, items: list) -> Any:
    """``items`` as a list, tuple or named tuple like ``template``."""
    if hasattr(template, "_fields"):  # a NamedTuple keeps its field names
        return type(template)(*items)
    return type(template)(items)


def format_number(value: Any, digits: int = 5) -> str:
    """Format a number for people: ``digits`` significant digits, no noise.

    Integers (and floats that are whole numbers of modest size) print
    without a decimal point; other floats use ``digits`` significant digits;
    tuples print as ``(a, b)``.

    Examples
    --------
    >>> format_number(6.0), format_number(0.0497870684), format_number((74.2219, 129.5612), 4)
    ('6', '0.049787', '(74.22, 129.6)')
    """
    from course.validation import as_count

    digits = as_count(digits, "digits", what="the number of significant digits")
    value = as_plain(value)
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, (tuple, list)):
        return "(" + ", ".join(format_number(v, digits) for v in value) + ")"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value) or math.isinf(value):
            return str(value)
        if value.is_integer() and abs(value) < 1e15:
            return str(int(value))
        return f"{value:.{digits}g}"
    return str(value)


def describe_distribution(dist: Any) -> str:
    """A short, deterministic name for a frozen distribution, e.g. ``chi2(2)``.

    Examples
    --------
    >>> from scipy import stats
    >>> describe_distribution(stats.chi2(3, scale=0.04))
    'chi2(3, scale=0.04)'
    """
    if dist is None:
        return "None"
    inner = getattr(dist, "dist", None)
    if inner is not None and hasattr(dist, "args"):
        name = getattr(inner, "name", type(inner).__name__).removesuffix("_gen")
        args = [format_number(a) for a in dist.args]
        kwds = getattr(dist, "kwds", {}) or {}
        args += [f"{k}={format_number(v)}" for k, v in sorted(kwds.items())]
        return f"{name}({', '.join(args)})"
    return repr(dist)


@dataclass(frozen=True, repr=False, eq=False)
class TestResult:
    """Outcome of a statistical test, with one vocabulary across the course.

    Parameters
    ----------
    name : str
        What was tested, e.g. ``"overall model test"``.
    statistic : float or tuple of float
        Observed value of the test quantity (a tuple when a test uses several
        quantities, such as the smallest and largest eigenvalue).
    alpha : float
        Level of significance, in (0, 1).
    critical_value : float or tuple of float
        Threshold of the critical region; ``(lower, upper)`` for two-sided.
    pvalue : float
        Probability under H0 of a statistic at least as extreme as observed.
    reject : bool
        ``True`` when H0 is rejected at level ``alpha``.
    null : Law
        Law of the statistic under H0 (scipy.stats frozen or course-defined).
    dof : int or float, optional
        Degrees of freedom of the null law, where it has them.
    alternative : {"greater", "less", "two-sided"}
        Which tail(s) form the critical region.
    details : mapping, optional
        Extra, test-specific values (shown in the HTML table).

    See Also
    --------
    decide : The one decision path.

    Notes
    -----
    Build one with :meth:`from_null`, which computes the critical value,
    p-value and decision from ``null`` (the course's one decision path,
    :func:`decide`).  Like scipy's results it unpacks as
    ``statistic, pvalue = result``.  The class sets ``__test__ = False`` so
    that pytest does not mistake it for a test class when a test module
    imports it.

    Examples
    --------
    >>> from scipy import stats
    >>> r = TestResult.from_null("overall model test", 6.0, stats.chi2(2), 0.01, dof=2)
    >>> r
    TestResult('overall model test', statistic=6, dof=2, alpha=0.01, critical_value=9.2103, pvalue=0.04979, reject=False, null=chi2(2))
    >>> round(r.power(stats.ncx2(2, 10.0)), 4)
    0.6148
    >>> statistic, pvalue = r
    >>> statistic, round(pvalue, 5)
    (6.0, 0.04979)
    """

    __test__ = False

    name: str
    statistic: Any
    alpha: float
    critical_value: Any
    pvalue: float
    reject: bool
    null: Law
    dof: Any = None
    alternative: str = "greater"
    details: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        # Every field is checked, and checked against the others: a result that
        # contradicts itself (a decision the statistic does not support, a
        # p-value outside [0, 1]) is refused rather than shown to a student.
        from course.validation import (
            InputTypeError,
            as_finite,
            as_flag,
            as_law,
            as_probability,
        )

        set_ = object.__setattr__
        set_(self, "alpha", as_probability(self.alpha, "alpha"))
        alternative = _check_alternative(self.alternative)
        set_(self, "null", as_law(self.null, "null"))
        statistic = _plain_number(self.statistic)
        values: tuple[Any, ...]
        if isinstance(statistic, tuple):
            if alternative != "two-sided" or len(statistic) != 2:
                raise ValueError(
                    "statistic may be a pair (low, high) only for a two-sided test, "
                    f"got {statistic!r} with alternative={alternative!r}"
                )
            values = statistic
        else:
            values = (statistic,)
        for value in values:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
                raise ValueError(
                    f"statistic must be a real number (not NaN), got {self.statistic!r}"
                )
        set_(self, "statistic", statistic)
        if alternative == "two-sided":
            critical: Any = CriticalValues(*_critical_pair(self.critical_value, "critical_value"))
        else:
            critical = as_finite(self.critical_value, "critical_value")
        set_(self, "critical_value", _plain_number(critical))
        pvalue = as_finite(self.pvalue, "pvalue")
        if not 0.0 <= pvalue <= 1.0:
            raise ValueError(f"pvalue must lie in [0, 1], got {self.pvalue!r}")
        set_(self, "pvalue", pvalue)
        set_(self, "reject", as_flag(self.reject, "reject"))
        self._check_decision(values)
        dof = as_plain(self.dof)
        if dof is not None:
            dof = as_finite(dof, "dof", what="degrees of freedom")
            if dof <= 0:
                raise ValueError(f"dof (degrees of freedom) must be positive, got {self.dof!r}")
            dof = int(dof) if dof.is_integer() else dof
        set_(self, "dof", dof)
        if not isinstance(self.details, Mapping):
            raise InputTypeError(
                f"details must be a mapping (a dict), got {type(self.details).__name__}"
            )
        set_(self, "details", {key: as_plain(value) for key, value in self.details.items()})

    def __iter__(self) -> Iterator[Any]:
        """``statistic, pvalue = result``, as scipy's test results unpack."""
        return iter((self.statistic, self.pvalue))

    def _check_decision(self, values: tuple) -> None:
        """``reject`` must follow from statistic and critical value, and agree with the p-value."""
        low, high = values[0], values[-1]
        crit = self.critical_value
        if self.alternative == "greater":
            rejects = high > crit
        elif self.alternative == "less":
            rejects = low < crit
        else:
            rejects = low < crit[0] or high > crit[1]
        if self.reject != rejects:
            raise ValueError(
                f"reject={self.reject} contradicts statistic {format_number(self.statistic)} "
                f"and critical_value {format_number(crit)} ({self.alternative}): "
                f"the decision must be {rejects}; build results with TestResult.from_null"
            )
        # The p-value and the decision agree up to the accuracy of the law's
        # quantiles (root searches): p < alpha exactly when H0 is rejected.
        slack = 1e-6 * self.alpha
        if self.reject and self.pvalue > self.alpha + slack:
            raise ValueError(
                f"pvalue {self.pvalue!r} >= alpha {self.alpha!r} contradicts reject=True"
            )
        if not self.reject and self.pvalue < self.alpha - slack:
            raise ValueError(
                f"pvalue {self.pvalue!r} < alpha {self.alpha!r} contradicts reject=False"
            )

    @classmethod
    def from_null(
        cls,
        name: str,
        statistic: Any,
        null: Law,
        alpha: float,
        alternative: str = "greater",
        *,
        dof: Any = None,
        details: Mapping[str, Any] | None = None,
    ) -> TestResult:
        """The result of testing ``statistic`` against its null law ``null``.

        Parameters
        ----------
        name : str
            What was tested.
        statistic : float or pair of float
            Observed test quantity (a pair ``(low, high)`` for a two-sided
            test on two statistics, see :func:`decide`).
        null : Law
            Law of the statistic under H0.
        alpha : float
            Level of significance.
        alternative : {"greater", "less", "two-sided"}
            Which tail(s) form the critical region.
        dof : int, optional
            Degrees of freedom, shown with the result.
        details : mapping, optional
            Extra, test-specific values.

        Returns
        -------
        TestResult
            With ``critical_value``, ``pvalue`` and ``reject`` from :func:`decide`.

        Examples
        --------
        >>> from scipy import stats
        >>> TestResult.from_null("w-test", 2.5, stats.norm(), 0.05, "two-sided").summary()
        'w-test: statistic = 2.5, critical region outside [-1.96, 1.96] (alpha = 0.05), p = 0.01242: reject H0'
        """
        from course.validation import InputTypeError

        if not isinstance(statistic, tuple) and np.ndim(statistic) != 0:
            raise ValueError(
                "statistic must be one number (or, for a two-sided test, a pair (low, high)); "
                f"got shape {np.shape(statistic)}: use decide() for arrays of statistics"
            )
        if details is not None and not isinstance(details, Mapping):
            raise InputTypeError(
                f"details must be a mapping (a dict), got {type(details).__name__}"
            )
        decision = decide(null, statistic, alpha, alternative)
        return cls(
            name=name,
            statistic=statistic,
            alpha=alpha,
            critical_value=decision.critical_value,
            pvalue=decision.pvalue,
            reject=decision.reject,
            null=null,
            dof=dof,
            alternative=alternative,
            details=dict(details or {}),
        )

    def power(self, alternative_law: Law) -> float:
        """Probability that this test rejects when the statistic has ``alternative_law``.

        The critical region is this result's; under ``null`` the answer is
        ``alpha`` (for a continuous law).

        Raises
        ------
        ValueError
            When both laws are scipy's and ``alternative_law`` is not a law of this
            test's statistic: another family (an F law for a chi-square test; the
            non-central twin ``ncx2``, ``ncf``, ``nct`` counts as the same family) or
            other degrees of freedom (a q = 2 law for a q = 1 test). Location and scale
            may differ (a shifted normal, a scaled chi-square). Laws the course defines
            are taken as given.

        Examples
        --------
        >>> from scipy import stats
        >>> r = TestResult.from_null("z-test", 0.3, stats.norm(), 0.05)
        >>> round(r.power(stats.norm(loc=2.0)), 4)
        0.6388
        """
        from course.validation import as_law

        law = as_law(alternative_law, "alternative_law")
        _check_same_statistic(self.null, law)
        return rejection_probability(law, self.critical_value, self.alternative)

    # -- presentation -----------------------------------------------------
    def _fields(self):
        rows = [("test", self.name), ("statistic", format_number(self.statistic))]
        if self.dof is not None:
            rows.append(("dof", format_number(self.dof)))
        rows += [
            ("alpha", format_number(self.alpha)),
            ("critical_value", format_number(self.critical_value)),
            ("pvalue", format_number(self.pvalue, 4)),
            ("reject", str(self.reject)),
            ("null", describe_distribution(self.null)),
        ]
        return rows

    def __repr__(self) -> str:
        parts = [f"{key}={value}" for key, value in self._fields()[1:]]
        return f"TestResult({self.name!r}, " + ", ".join(parts) + ")"

    def summary(self) -> str:
        """One line a student can read aloud: statistic, threshold, decision."""
        crit = self.critical_value
        if isinstance(crit, tuple):
            region = f"outside [{format_number(crit[0], 4)}, {format_number(crit[1], 4)}]"
        elif self.alternative == "less":
            region = f"< {format_number(crit, 5)}"
        else:
            region = f"> {format_number(crit, 5)}"
        decision = "reject H0" if self.reject else "accept H0"
        return (
            f"{self.name}: statistic = {format_number(self.statistic, 5)}, "
            f"critical region {region} (alpha = {format_number(self.alpha)}), "
            f"p = {format_number(self.pvalue, 4)}: {decision}"
        )

    def _repr_html_(self) -> str:
        rows = self._fields()[1:]
        rows += [(key, format_number(value)) for key, value in self.details.items()]
        body = "".join(
            f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
            f"<td style='text-align:left'>{html.escape(v)}</td></tr>"
            for k, v in rows
        )
        caption = html.escape(self.name)
        return f"<table><caption>{caption}</caption>{body}</table>"


#: scipy's non-central families and their central twins: one statistic, two laws.
_CENTRAL_TWIN = {"ncx2": "chi2", "ncf": "f", "nct": "t"}


def _family_and_shapes(law: Any) -> tuple[str, dict[str, float]] | None:
    """A scipy frozen law's family (non-central named by its central twin) and shape
    parameters other than the non-centrality; None for any other law."""
    dist, args = getattr(law, "dist", None), getattr(law, "args", None)
    name = getattr(dist, "name", None)
    if not isinstance(name, str) or not isinstance(args, tuple):
        return None
    names = [part.strip() for part in (getattr(dist, "shapes", None) or "").split(",")]
    names = [part for part in names if part]
    values = dict(zip(names, args))
    values.update({k: v for k, v in (getattr(law, "kwds", None) or {}).items() if k in names})
    shapes = {k: float(np.asarray(v)) for k, v in values.items() if k != "nc"}
    return _CENTRAL_TWIN.get(name, name), shapes


def _check_same_statistic(null: Any, law: Any) -> None:
    """Refuse an alternative law that cannot be the law of this test's statistic."""
    mine, theirs = _family_and_shapes(null), _family_and_shapes(law)
    if mine is None or theirs is None or (mine == theirs):
        return
    differs = "family" if mine[0] != theirs[0] else "degrees of freedom"
    raise ValueError(
        f"alternative_law {describe_distribution(law)} is not a law of this test's statistic "
        f"(its {differs} differ from the null law {describe_distribution(null)}): the family "
        "and the degrees of freedom must be the test's (a non-central twin such as ncx2 for chi2 may add the "
        "non-centrality, loc and scale may differ); build the law for this test, e.g. with "
        "the same q and the same variance assumption"
    )


def _plain_number(value):
    value = as_plain(value)
    if isinstance(value, (tuple, list)):
        items = [float(v) for v in value]
        return _same_sequence_type(value, items) if isinstance(value, tuple) else tuple(items)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return value
