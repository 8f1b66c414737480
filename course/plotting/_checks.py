"""Input checks of the plotting functions: refuse bad data before drawing anything.

A figure drawn from NaN, an empty array or an array of the wrong shape is
silently wrong (or, for a 2-D histogram input, takes minutes), so every
plotting function checks its data here and raises a ``ValueError`` that
names the argument and says what to pass instead.  The rules are those of
:mod:`course.validation` (a number is a real number, never the text
``"0.05"``; a count is a whole number); this module only adds what a figure
needs on top (the numbers of dimensions a plot can draw, a smallest number of
entries, arrays that pair up) and takes ``(name, value)`` in the order the
plotting code reads best.
"""

from __future__ import annotations

import numpy as np

from course.validation import (
    as_count,
    as_finite,
    as_flag,
    as_float_array,
    as_positive,
    as_probability,
)

__all__ = ["array", "flag", "positive_int", "probability", "same_length", "scalar"]


def array(
    name: str,
    value,
    *,
    ndim: int | tuple[int, ...] | None = 1,
    min_size: int = 1,
    allow_nan: bool = False,
    what: str = "values",
) -> np.ndarray:
    """``value`` as a float array, checked by :func:`course.validation.as_float_array`.

    Parameters
    ----------
    name : str
        The argument's name, used in the error message.
    value : array_like
    ndim : int or tuple of int or None
        Allowed numbers of dimensions (None: any).
    min_size : int
        Smallest number of entries.
    allow_nan : bool
        Allow NaN (a documented "undefined" marker, e.g. the first samples of
        a windowed statistic); infinities are always refused, and an array
        that is NaN everywhere too.
    what : str
        What the entries are, for the message.
    """
    out = as_float_array(value, name, nan=allow_nan)
    if ndim is not None:
        allowed = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if out.ndim not in allowed:
            wanted = " or ".join(f"{d}-D" for d in allowed)
            raise ValueError(
                f"{name} must be {wanted} ({what}), got an array of shape {out.shape}"
                + ("; flatten it with .ravel() if every entry is one value" if 1 in allowed else "")
            )
    if out.size < min_size:
        raise ValueError(
            f"{name} is empty: pass at least {min_size} {what}"
            if out.size == 0
            else f"{name} has {out.size} entries: pass at least {min_size} {what}"
        )
    if allow_nan and out.size and np.isnan(out).all():
        raise ValueError(f"{name} is NaN everywhere: there is nothing to draw")
    return out


def scalar(name: str, value, *, positive: bool = False, allow_none: bool = False):
    """A finite float (optionally > 0); None passes through when allowed."""
    if value is None and allow_none:
        return None
    return as_positive(value, name) if positive else as_finite(value, name)


def probability(name: str, value, *, allow_none: bool = False):
    """A level such as alpha, strictly between 0 and 1."""
    if value is None and allow_none:
        return None
    return as_probability(value, name)


def positive_int(name: str, value, *, allow_none: bool = False):
    """A whole number >= 1 (a count of bins, degrees of freedom, ...)."""
    if value is None and allow_none:
        return None
    return as_count(value, name)


def flag(name: str, value) -> bool:
    """A true boolean switch (so that ``"no"`` is not read as True)."""
    return as_flag(value, name)


def same_length(name_a: str, a: np.ndarray, name_b: str, b: np.ndarray, axis: int = 0) -> None:
    """Refuse two arrays that must pair up entry by entry but do not."""
    if a.shape[axis] != b.shape[axis]:
        raise ValueError(
            f"{name_a} and {name_b} must have the same length, got {a.shape[axis]} and {b.shape[axis]}"
        )
