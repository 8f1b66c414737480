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
    with ``cdf``, ``sf``, ``ppf``, ``isf`` and ``rvs``.

All numbers are stored as plain Python ``float``/``int``/``bool``, so what is
printed never shows numpy scalar reprs, and the ``repr`` is short and
deterministic (no addresses, no timestamps).
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "TestResult",
    "as_plain",
    "describe_distribution",
    "format_number",
]

_ALTERNATIVES = ("greater", "less", "two-sided")


def as_plain(value: Any) -> Any:
    """Convert numpy scalars (and tuples/lists of them) to plain Python values.

    Arrays are returned unchanged: only scalars are converted, so that a
    result prints ``6.0`` and never ``np.float64(6.0)``.
    """
    # numpy scalars first: np.float64 subclasses float and would slip through.
    if isinstance(value, np.generic) or (isinstance(value, np.ndarray) and value.ndim == 0):
        return value.item()
    if isinstance(value, (tuple, list)):
        return type(value)(as_plain(v) for v in value)
    return value


def format_number(value: Any, digits: int = 5) -> str:
    """Format a number for people: ``digits`` significant digits, no noise.

    Integers (and floats that are whole numbers of modest size) print
    without a decimal point; other floats use ``digits`` significant digits;
    tuples print as ``(a, b)``.
    """
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
    """A short, deterministic name for a frozen distribution, e.g. ``chi2(2)``."""
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
    null : frozen distribution
        Law of the statistic under H0 (scipy.stats frozen or course-defined).
    dof : int or float, optional
        Degrees of freedom of the null law, where it has them.
    alternative : {"greater", "less", "two-sided"}
        Which tail(s) form the critical region.
    details : mapping, optional
        Extra, test-specific values (shown in the HTML table).

    Notes
    -----
    The class sets ``__test__ = False`` so that pytest does not mistake it
    for a test class when a test module imports it.
    """

    __test__ = False

    name: str
    statistic: Any
    alpha: float
    critical_value: Any
    pvalue: float
    reject: bool
    null: Any
    dof: Any = None
    alternative: str = "greater"
    details: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        if not 0.0 < float(self.alpha) < 1.0:
            raise ValueError(f"alpha must lie strictly between 0 and 1, got {self.alpha!r}")
        if self.alternative not in _ALTERNATIVES:
            raise ValueError(
                f"alternative must be one of {_ALTERNATIVES}, got {self.alternative!r}"
            )
        set_ = object.__setattr__
        set_(self, "statistic", _plain_number(self.statistic))
        set_(self, "critical_value", _plain_number(self.critical_value))
        set_(self, "alpha", float(self.alpha))
        set_(self, "pvalue", float(self.pvalue))
        set_(self, "reject", bool(self.reject))
        set_(self, "dof", as_plain(self.dof))
        set_(self, "details", {key: as_plain(value) for key, value in self.details.items()})

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


def _plain_number(value):
    value = as_plain(value)
    if isinstance(value, (tuple, list)):
        return tuple(float(v) for v in value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return value
