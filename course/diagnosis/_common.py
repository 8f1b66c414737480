"""Input checks and rank-revealing helpers shared by the diagnosis modules."""

from __future__ import annotations

import numpy as np
from scipy import stats

from course.linalg import (
    as_float_array,
    as_matrix,
    as_vector,
)


def _range_basis(Phi: np.ndarray, rcond: float | None = None):
    """Orthonormal basis of range(Phi) from the SVD, with its rank decision."""
    N, p = Phi.shape
    if p == 0 or N == 0:
        return np.zeros((N, 0))
    left, s, _ = np.linalg.svd(Phi, full_matrices=False)
    rank = _numerical_rank(s, N, p, rcond)
    return left[:, :rank]


def _numerical_rank(s, N, p, rcond):
    if s.size == 0 or s[0] == 0.0:
        return 0
    tol = (max(N, p) * np.finfo(float).eps if rcond is None else float(rcond)) * s[0]
    return int(np.sum(s > tol))


def _data(y, N: int | None, name: str = "y") -> np.ndarray:
    y = as_float_array(y, name)
    if y.ndim not in (1, 2):
        raise ValueError(
            f"{name} must be one record of shape (N,) or M records as columns of an (N, M) "
            f"array, got shape {y.shape}"
        )
    if N is not None and y.shape[0] != N:
        raise ValueError(
            f"shape mismatch: {name} has {y.shape[0]} samples but the regressors have {N} rows; "
            "one regressor row per sample is needed"
        )
    return y


def _indices(free, p: int, what: str = "free") -> list:
    if free is None:
        return []
    if isinstance(free, (int, np.integer)):
        free = [free]
    out = []
    for j in free:
        if isinstance(j, bool) or not isinstance(j, (int, np.integer)):
            raise ValueError(f"{what} must be parameter indices (integers), got {j!r}")
        if not 0 <= int(j) < p:
            raise ValueError(f"{what} index {j} out of range for {p} parameters (0..{p - 1})")
        out.append(int(j))
    if len(set(out)) != len(out):
        raise ValueError(f"{what} contains repeated indices: {out}")
    return sorted(out)


def _model(U, nominal):
    U = as_matrix(U, "U")
    nominal = as_vector(nominal, "nominal", U.shape[1])
    return U, nominal


def _split(U, nominal, free):
    """Regressors of the free parameters and the known part of the prediction."""
    p = U.shape[1]
    fixed = [j for j in range(p) if j not in free]
    return U[:, free], U[:, fixed] @ nominal[fixed]


def _count(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _check_sigma(sigma) -> float:
    try:
        value = float(sigma)
    except (TypeError, ValueError):
        raise ValueError(
            f"sigma must be a positive number (the noise standard deviation), got {sigma!r}"
        ) from None
    if not np.isfinite(value) or value <= 0:
        raise ValueError(
            f"sigma must be a positive, finite noise standard deviation, got {sigma!r}"
        )
    return value


def _scaled_chi2(dof, sigma):
    return stats.chi2(dof) if sigma == 1.0 else stats.chi2(dof, scale=sigma**2)


def _check_dof(dof) -> int:
    if (
        isinstance(dof, bool)
        or not isinstance(dof, (int, float, np.integer, np.floating))
        or not np.isfinite(dof)
        or int(dof) != dof
        or dof < 1
    ):
        raise ValueError(
            f"dof must be a positive integer, got {dof!r}; with no residual degrees of freedom "
            "the model under H0 fits any data exactly and the test is void"
        )
    return int(dof)


def _void_test_message(dof_what: str) -> str:
    return (
        f"the test has no redundancy ({dof_what}): the model under H0 fits any data exactly, "
        "so T is identically 0 and carries no information; use more samples or fewer free parameters"
    )
