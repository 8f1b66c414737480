"""The rule that refuses a numerically singular Cholesky factor, shared by validation and linalg.

Internal (no public names): the tolerance is documented as
:data:`course.validation.SINGULAR_RTOL`.
"""

from __future__ import annotations

import numpy as np
from numpy.linalg import LinAlgError

SINGULAR_RTOL = 4 * np.finfo(float).eps


def _refuse_singular_pivots(L: np.ndarray, variances: np.ndarray, name: str) -> None:
    """Raise a LinAlgError when a Cholesky factor ``L`` of a covariance is numerically singular.

    ``L`` may be a stack ``(..., m, m)`` with ``variances`` the diagonals of
    the factored matrices ``(..., m)``; the rule is :data:`course.validation.SINGULAR_RTOL`.
    """
    _refuse_small_pivots(np.diagonal(L, axis1=-2, axis2=-1) ** 2, variances, name)


def _refuse_small_pivots(pivots: np.ndarray, variances: np.ndarray, name: str) -> None:
    """The rule of :func:`_refuse_singular_pivots` on the squared pivots ``L_ii**2`` alone
    (a banded factor stores only its bands)."""
    m = pivots.shape[-1]
    tolerance = SINGULAR_RTOL * m * variances
    singular = ~(pivots > tolerance)
    if not singular.any():
        return
    where = tuple(int(i) for i in np.argwhere(singular)[0])
    *stack, i = where
    share = float(pivots[where] / variances[where]) if variances[where] > 0 else 0.0
    place = f" (matrix {tuple(stack)} of the stack)" if stack else ""
    previous = f"variables 0..{i - 1}" if i else "nothing (its variance is 0)"
    raise LinAlgError(
        f"{name} is numerically singular{place}: variable {i} is a linear combination of "
        f"{previous} up to rounding (1 - R^2 = {share:.2g} < {SINGULAR_RTOL * m:.2g}); "
        "remove the redundant variable or add its independent variance"
    )
