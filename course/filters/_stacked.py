"""Small helpers for stacks of matrices and for the time-major work layout of the filters."""

from __future__ import annotations

import numpy as np


# ---------------------------------------------------------------------------
# small helpers
# ---------------------------------------------------------------------------
def _mm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Matrix product over stacks, fast for large batches of tiny matrices.

    ``np.matmul`` loops over a stack of 2 x 2 matrices one small product at
    a time; for a small inner dimension, a few whole-batch multiply-adds are
    several times faster.  Same arithmetic, so results agree to rounding.
    """
    k = A.shape[-1]
    if k > 4 or (A.ndim <= 2 and B.ndim <= 2):
        return A @ B
    out = A[..., :, 0, None] * B[..., None, 0, :]
    for j in range(1, k):
        out = out + A[..., :, j, None] * B[..., None, j, :]
    return out


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Matrix times vector over stacks: ``A (..., m, n)``, ``x (..., n)``."""
    k = A.shape[-1]
    if k > 4 or (A.ndim <= 2 and x.ndim <= 1):
        return (A @ x[..., None])[..., 0]
    out = A[..., :, 0] * x[..., None, 0]
    for j in range(1, k):
        out = out + A[..., :, j] * x[..., None, j]
    return out


def _T(A: np.ndarray) -> np.ndarray:
    return np.swapaxes(A, -1, -2)


def _time_major(a: np.ndarray) -> np.ndarray:
    """A signal ``(*batch, N, d)`` as contiguous ``(N, *batch, d)``."""
    return np.ascontiguousarray(np.moveaxis(a, -2, 0))


def _batch_major(a: np.ndarray, n_batch: int) -> np.ndarray:
    """Inverse of the time-major layout: ``(N, *batch, ...)`` to ``(*batch, N, ...)``.

    A view, not a copy: reordering memory would cost more than the filter.
    """
    return np.moveaxis(a, 0, n_batch)
