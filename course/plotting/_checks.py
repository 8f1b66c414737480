"""Input checks of the plotting functions: refuse bad data before drawing anything.

A figure drawn from NaN, an empty array or an array of the wrong shape is
silently wrong (or, for a 2-D histogram input, takes minutes), so every
plotting function checks its data here and raises a ``ValueError`` that
names the argument and says what to pass instead.
"""

from __future__ import annotations

import numpy as np

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
    """``value`` as a float array, checked.

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
    if value is None:
        raise ValueError(f"{name} is None: pass an array of {what}")
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be an array of numbers ({what}), got {value!r:.60}"
        ) from None
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
    if np.isinf(out).any():
        raise ValueError(f"{name} contains infinite values: pass finite {what}")
    nan = np.isnan(out)
    if nan.any():
        if not allow_nan:
            raise ValueError(
                f"{name} contains NaN at {int(nan.sum())} place(s): remove or fill them before plotting"
            )
        if nan.all():
            raise ValueError(f"{name} is NaN everywhere: there is nothing to draw")
    return out


def scalar(name: str, value, *, positive: bool = False, allow_none: bool = False):
    """A finite float (optionally > 0); None passes through when allowed."""
    if value is None and allow_none:
        return None
    if isinstance(value, (bool, np.bool_)) or value is None:
        raise ValueError(f"{name} must be a number, got {value!r}")
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r:.60}") from None
    if not np.isfinite(out):
        raise ValueError(f"{name} must be finite, got {out}")
    if positive and out <= 0:
        raise ValueError(f"{name} must be positive, got {out:g}")
    return out


def probability(name: str, value, *, allow_none: bool = False):
    """A level such as alpha, strictly between 0 and 1."""
    out = scalar(name, value, allow_none=allow_none)
    if out is not None and not 0.0 < out < 1.0:
        raise ValueError(f"{name} must lie strictly between 0 and 1, got {out:g}")
    return out


def positive_int(name: str, value, *, allow_none: bool = False):
    """A whole number >= 1 (a count of bins, degrees of freedom, ...)."""
    if value is None and allow_none:
        return None
    if isinstance(value, (bool, np.bool_)) or value is None:
        raise ValueError(f"{name} must be a whole number >= 1, got {value!r}")
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a whole number >= 1, got {value!r:.60}") from None
    if not np.isfinite(out) or out != int(out) or out < 1:
        raise ValueError(f"{name} must be a whole number >= 1, got {value!r}")
    return int(out)


def flag(name: str, value) -> bool:
    """A true boolean switch (so that ``"no"`` is not read as True)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def same_length(name_a: str, a: np.ndarray, name_b: str, b: np.ndarray, axis: int = 0) -> None:
    """Refuse two arrays that must pair up entry by entry but do not."""
    if a.shape[axis] != b.shape[axis]:
        raise ValueError(
            f"{name_a} and {name_b} must have the same length, got {a.shape[axis]} and {b.shape[axis]}"
        )
