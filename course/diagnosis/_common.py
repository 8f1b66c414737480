"""Input checks shared by the diagnosis modules: the regression model and record layouts."""

from __future__ import annotations

from typing import Any

import numpy as np

from course.validation import as_float_array, as_indices, as_matrix, as_std, as_vector


def _records(y: Any, N: int | None, name: str = "y") -> tuple[np.ndarray, str]:
    """Data as columns ``(N, M)`` for the computation, and the layout to answer in.

    ``y`` is one record ``(N,)`` or ``M`` records as the rows of an
    ``(M, N)`` array (records leading, the course's batch convention).  A
    square ``(N, N)`` array is read as records leading.
    """
    Y = as_float_array(y, name, empty=False)
    if Y.ndim not in (1, 2):
        raise ValueError(
            f"{name} must be one record of shape (N,) or M records as the rows of an (M, N) "
            f"array, got shape {Y.shape}"
        )
    if Y.ndim == 1:
        if N is not None and Y.shape[0] != N:
            raise ValueError(
                f"shape mismatch: {name} has {Y.shape[0]} samples but the regressors have {N} "
                "rows; one regressor row per sample is needed"
            )
        return Y, "one"
    if N is None or Y.shape[1] == N:
        return Y.T, "rows"
    if Y.shape[0] == N:
        raise ValueError(
            f"{name} of shape (N, M) = {Y.shape} holds the records as columns; the course's "
            f"layout is records leading: pass {name}.T, of shape (M, N) = {Y.shape[::-1]}"
        )
    raise ValueError(
        f"shape mismatch: {name} has shape {Y.shape} but the regressors have {N} rows; pass "
        f"M records of N = {N} samples as an (M, {N}) array"
    )


def _answer(columns: np.ndarray, layout: str) -> np.ndarray:
    """A per-record array computed as columns ``(d, M)``, in the caller's layout."""
    return columns.T if layout == "rows" else columns


def _parameter_vectors(theta: Any, p: int, name: str = "theta") -> tuple[np.ndarray, bool]:
    """Parameter vector(s) as columns ``(p, K)`` (or ``(p,)``), and whether there were several.

    ``theta`` is ``(p,)`` or ``K`` vectors as the rows of ``(K, p)``.
    """
    theta = as_float_array(theta, name, empty=False)
    if theta.ndim == 1:
        if theta.shape[0] != p:
            raise ValueError(f"{name} must have shape ({p},) or (K, {p}), got {theta.shape}")
        return theta, False
    if theta.ndim == 2 and theta.shape[1] == p:
        return theta.T, True
    if theta.ndim == 2 and theta.shape[0] == p:
        raise ValueError(
            f"{name} of shape (p, K) = {theta.shape} holds the parameter vectors as columns; "
            f"pass them as rows, {name}.T of shape (K, p) = {theta.shape[::-1]}"
        )
    raise ValueError(f"{name} must have shape ({p},) or (K, {p}), got {theta.shape}")


def _indices(free: Any, p: int, what: str = "free") -> list[int]:
    return as_indices(free, what, p)


def _model(U: Any, nominal: Any) -> tuple[np.ndarray, np.ndarray]:
    U = as_matrix(U, "U")
    nominal = as_vector(nominal, "nominal")
    if nominal.shape[0] != U.shape[1]:
        raise ValueError(
            f"nominal has {nominal.shape[0]} parameters but U has {U.shape[1]} columns; "
            "give one nominal value per column of U"
        )
    return U, nominal


def _split(U: np.ndarray, nominal: np.ndarray, free: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Regressors of the free parameters and the known part of the prediction."""
    p = U.shape[1]
    fixed = [j for j in range(p) if j not in free]
    return U[:, free], U[:, fixed] @ nominal[fixed]


def _check_sigma(sigma: Any, name: str = "sigma") -> float:
    """The noise standard deviation: positive, with a representable variance.

    The laws and covariances of the diagnosis tests are in units of
    ``sigma**2``, so a ``sigma`` whose square over- or underflows (1e300,
    1e-300) is refused with advice to rescale (:func:`course.validation.as_std`),
    never turned into an ``OverflowError`` or a division by zero.
    """
    return as_std(sigma, name, what="the noise standard deviation")


def _void_test_message(dof_what: str) -> str:
    return (
        f"the test has no redundancy ({dof_what}): the model under H0 fits any data exactly, "
        "so T is identically 0 and carries no information; use more samples or fewer free parameters"
    )
