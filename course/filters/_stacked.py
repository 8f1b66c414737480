"""Small helpers for stacks of matrices and for the time-major work layout of the filters."""

from __future__ import annotations

import numpy as np


# ---------------------------------------------------------------------------
# small helpers
# ---------------------------------------------------------------------------
def _mm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Matrix product over stacks, fast for large batches of tiny matrices.

    ``np.matmul`` loops over a stack of 2 x 2 matrices one small product at
    a time, and a broadcast product over the last two axes runs numpy's inner
    loop over only 2 elements.  Computing each entry of the result as a sum
    of whole-batch products runs every inner loop over the batch instead.
    The entries are summed in the order of the inner index, as before, so
    results are the same to the last bit.
    """
    m, k = A.shape[-2:]
    n = B.shape[-1]
    if k > 4 or (A.ndim <= 2 and B.ndim <= 2):
        return A @ B
    if m * n > 16:  # many entries: one broadcast product per inner index
        stacked = A[..., :, 0, None] * B[..., None, 0, :]
        for inner in range(1, k):
            stacked = stacked + A[..., :, inner, None] * B[..., None, inner, :]
        return stacked
    out = np.empty(
        np.broadcast_shapes(A.shape[:-2], B.shape[:-2]) + (m, n), dtype=np.result_type(A, B)
    )
    for i in range(m):
        for j in range(n):
            entry = A[..., i, 0] * B[..., 0, j]
            for inner in range(1, k):
                entry = entry + A[..., i, inner] * B[..., inner, j]
            out[..., i, j] = entry
    return out


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Matrix times vector over stacks: ``A (..., m, n)``, ``x (..., n)``."""
    m, k = A.shape[-2:]
    if k > 4 or (A.ndim <= 2 and x.ndim <= 1):
        return (A @ x[..., None])[..., 0]
    out = np.empty(
        np.broadcast_shapes(A.shape[:-2], x.shape[:-1]) + (m,), dtype=np.result_type(A, x)
    )
    for i in range(m):
        entry = A[..., i, 0] * x[..., 0]
        for inner in range(1, k):
            entry = entry + A[..., i, inner] * x[..., inner]
        out[..., i] = entry
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
