"""The input checks of a law's methods (points and probabilities), shared by every law's class.

Internal: :class:`course.distributions.FrozenDistribution` and the laws of
:mod:`course.nis` and :mod:`course.diagnosis` check their arguments with these.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from course.validation import as_float_array


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
