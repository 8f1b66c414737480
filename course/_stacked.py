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
    out = _component_major(_batch_shape(A.shape[:-2], B.shape[:-2]), (m, n), A, B)
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
    out = _component_major(_batch_shape(A.shape[:-2], x.shape[:-1]), (m,), A, x)
    for i in range(m):
        entry = A[..., i, 0] * x[..., 0]
        for inner in range(1, k):
            entry = entry + A[..., i, inner] * x[..., inner]
        out[..., i] = entry
    return out


def _batch_shape(a: tuple, b: tuple) -> tuple:
    """The broadcast of two batch shapes (equal shapes, the usual case, without a call)."""
    return a if a == b else np.broadcast_shapes(a, b)


def _component_major(batch: tuple, entries: tuple, *operands) -> np.ndarray:
    """An empty ``(*batch, *entries)`` array stored entry by entry: each entry contiguous.

    A view of a ``(*entries, *batch)`` block.  ``_mm`` and ``_mv`` read and
    write one entry over the whole batch at a time; in the default layout
    such an entry is a strided column (stride ``n * n`` doubles), here it is
    a contiguous run, and the products and sums of the next step read it at
    full speed (elementwise ufuncs keep the layout of their inputs).  The
    values are the same as in any layout: only memory order changes.
    """
    block = np.empty(entries + batch, dtype=np.result_type(*operands))
    k, nb = len(entries), len(batch)
    # a transpose, not np.moveaxis: this runs a dozen times per filter step
    return block.transpose(tuple(range(k, k + nb)) + tuple(range(k)))


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
