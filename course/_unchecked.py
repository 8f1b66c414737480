"""Numerical kernels that trust their inputs, shared by the packages' hot loops.

Each is the unchecked twin of a public function (:func:`course.linalg.symmetrize`,
:func:`course.linalg.whiten_vectors`, :func:`course.linalg.whitened_squared_norms`,
:func:`course.nis.nis`) for arrays the library built or validated itself; this module is
internal (no public names) and imports nothing from the course.
"""

from __future__ import annotations

import numpy as np


def _symmetrize(P: np.ndarray) -> np.ndarray:
    """:func:`course.linalg.symmetrize` without input checks (for arrays the library built)."""
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def _whiten_vectors(L: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """:func:`course.linalg.whiten_vectors` without input checks (for arrays the library validated)."""
    m = vectors.shape[-1]
    shape = np.broadcast_shapes(L.shape[:-2], vectors.shape[:-1]) + (m,)
    z = np.empty(shape)
    for i in range(m):
        acc = vectors[..., i] - np.einsum("...j,...j->...", L[..., i, :i], z[..., :i])
        z[..., i] = acc / L[..., i, i]
    return z


def _whitened_squared_norms(L: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """:func:`course.linalg.whitened_squared_norms` without input checks."""
    z = _whiten_vectors(L, vectors)
    return np.einsum("...i,...i->...", z, z)


def _normalized(eps: np.ndarray, S: np.ndarray) -> np.ndarray:
    """``L_t^{-1} eps_t`` for a filter's own arrays (trusted; NaN marks undefined samples).

    ``S`` may be a broadcast view shared by a batch: each distinct matrix is
    factored once.  With one output the whitening is a division, through
    which NaN passes.
    """
    if S.shape[-1] == 1:
        return eps / np.sqrt(S[..., 0])
    if S.ndim > 2:
        S = S[
            tuple(
                slice(0, 1) if stride == 0 and size > 1 else slice(None)
                for stride, size in zip(S.strides[:-2], S.shape[:-2])
            )
        ]
    return _whiten_vectors(np.linalg.cholesky(S), eps)


def _nis(eps: np.ndarray, S: np.ndarray) -> np.ndarray:
    """``eps_t^T S_t^{-1} eps_t`` for a filter's own arrays (see :func:`_normalized`)."""
    z = _normalized(eps, S)
    return np.einsum("...i,...i->...", z, z)
