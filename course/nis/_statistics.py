"""The NIS, the NEES and the NIS matrix of whitened innovations.

The one home of the normalised innovation squared: :func:`nis` for arrays a
user passes, and :func:`_nis` (no input checks, undefined samples allowed)
for the filter results of :mod:`course.filters`, whose ``nis()`` methods
delegate here.  Source: R. Forsling, poster "Matrix-Valued Statistics for
Detecting Complex Model Errors in State Estimation", eqs. (2)-(4) (full
reference in the course bibliography, :doc:`/docs/bibliography`).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from course._unchecked import _whiten_vectors as whiten_vectors
from course._unchecked import _whitened_squared_norms as whitened_squared_norms
from course.linalg import cholesky_factor
from course.validation import as_count, as_float_array


class EigenvaluePair(NamedTuple):
    """The smallest and largest eigenvalue (unpacks as ``lmin, lmax``)."""

    lmin: Any
    """Smallest eigenvalue(s)."""
    lmax: Any
    """Largest eigenvalue(s)."""


def _check_int(value: Any, name: str, minimum: int, what: str) -> int:
    return as_count(value, name, minimum=minimum, what=what)


def _check_dims(m: Any, K: Any) -> tuple[int, int]:
    m = as_count(m, "m", what="the innovation dimension")
    K = as_count(K, "K", what="the number of time steps")
    if m > K:
        raise ValueError(
            f"K = {K} < m = {m}: a sum of K < m outer products is singular, so its smallest "
            "eigenvalue is 0 and the Wishart law does not apply; use at least m time steps"
        )
    return m, K


def _check_which(which: Any) -> str:
    if which not in ("max", "min"):
        raise ValueError(f'which must be "max" or "min", got {which!r}')
    return which


def _innovations_and_factor(innovations, S, name_eps="innovations", name_S="S"):
    """Validate (..., K, m) innovations and their covariances; return (eps, L)."""
    eps = as_float_array(innovations, name_eps, empty=False)
    if eps.ndim < 2:
        raise ValueError(
            f"{name_eps} must have shape (K, m) or (..., K, m) (time along the second-to-last "
            f"axis), got shape {eps.shape}; for a scalar output pass {name_eps}[:, None]"
        )
    m = eps.shape[-1]
    shape = np.shape(S)
    if len(shape) < 2 or tuple(shape[-2:]) != (m, m):
        raise ValueError(
            f"{name_S} must have shape ({m}, {m}) or (..., K, {m}, {m}) to match {name_eps} of "
            f"shape {eps.shape}, got {shape}"
        )
    try:
        np.broadcast_shapes(tuple(shape[:-2]), eps.shape[:-1])
    except ValueError:
        raise ValueError(
            f"{name_S} of shape {shape} does not broadcast against {name_eps} of shape "
            f"{eps.shape}: give one ({m}, {m}) matrix or one per time step, (K, {m}, {m})"
        ) from None
    return eps, cholesky_factor(S, name_S)


def _whiten(L: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """Forward substitution ``L z = eps`` over stacks (no inverse is formed)."""
    return whiten_vectors(L, eps)


# ---------------------------------------------------------------------------
# statistics
# ---------------------------------------------------------------------------
def nis(innovations, S) -> np.ndarray:
    r"""Normalised innovation squared ``eps_k^T S_k^{-1} eps_k`` at every step.

    Parameters
    ----------
    innovations : array_like, shape (K, m) or (..., K, m)
        Innovations, time along the second-to-last axis (leading axes are
        independent runs).
    S : array_like, shape (m, m) or (..., K, m, m)
        Innovation covariances: one for all steps or one per step
        (broadcast against ``innovations``).

    Returns
    -------
    numpy.ndarray, shape (..., K)
        Under H0 each value is ``chi2(m)`` and the values are independent.

    Raises
    ------
    ValueError
        Wrong shapes, NaN/inf, non-symmetric ``S``.
    numpy.linalg.LinAlgError
        ``S`` not positive definite.

    See Also
    --------
    nees : The same quadratic form for state errors.
    nis_test : The test of a window's average NIS.
    windowed_nis : The NIS summed over a sliding window.

    Notes
    -----
    With :math:`S_k = B_k B_k^{\mathsf T}` (lower Cholesky factor),

    .. math::

        \epsilon_k = \nu_k^{\mathsf T} S_k^{-1} \nu_k = \lVert B_k^{-1} \nu_k \rVert^2,

    where :math:`\nu_k` is the innovation; the whitened vector
    :math:`B_k^{-1}\nu_k` is found by forward substitution, never with an
    inverse ([F], eq. 4).

    Examples
    --------
    >>> import numpy as np
    >>> nis([[1.0, 2.0], [2.0, 0.0]], np.diag([1.0, 4.0]))
    array([2., 4.])
    """
    eps, L = _innovations_and_factor(innovations, S)
    return whitened_squared_norms(L, eps)


def nees(errors, P) -> np.ndarray:
    r"""Normalised estimation error squared ``e_k^T P_k^{-1} e_k`` at every step.

    The same computation as :func:`nis` with the estimation errors
    ``e_k = x_k - xhat_k`` (known in simulation only) and the filter's
    covariances ``P_k``; under H0 each value is ``chi2(n)`` ([BS], Sec. 5.4.2).

    Parameters
    ----------
    errors : array_like, shape (K, n) or (..., K, n)
    P : array_like, shape (n, n) or (..., K, n, n)

    Returns
    -------
    numpy.ndarray, shape (..., K)

    See Also
    --------
    nis : The same quadratic form for innovations.
    consistency_interval : The interval a run-averaged NEES should lie in.

    Notes
    -----
    With :math:`P_k = B_k B_k^{\mathsf T}` (lower Cholesky factor),

    .. math::

        e_k^{\mathsf T} P_k^{-1} e_k = \lVert B_k^{-1} e_k \rVert^2,

    by forward substitution; no inverse is formed.

    Examples
    --------
    >>> import numpy as np
    >>> nees([[0.5, 0.0]], np.diag([0.25, 1.0]))
    array([1.])
    """
    eps, L = _innovations_and_factor(errors, P, "errors", "P")
    return whitened_squared_norms(L, eps)


def nis_matrix(innovations, S, window: int | None = None) -> np.ndarray:
    r"""The NIS matrix ``Pi = (1/K) sum_k B_k^{-1} eps_k eps_k^T B_k^{-T}``.

    Parameters
    ----------
    innovations : array_like, shape (K, m) or (..., K, m)
        Innovations, time along the second-to-last axis.
    S : array_like, shape (m, m) or (..., K, m, m)
        Innovation covariances, ``S_k = B_k B_k^T`` with ``B_k`` lower
        triangular (Cholesky).
    window : int, optional
        Average over a sliding window of this many steps (the poster's
        ``Pi_k`` for ``k = window-1, ..., K-1``); by default over all steps.

    Returns
    -------
    numpy.ndarray
        ``(..., m, m)``, or ``(..., K - window + 1, m, m)`` with a window.

    See Also
    --------
    nis : The NIS values; their window average is the trace of the NIS matrix.
    nis_matrix_eigenvalues : Its extreme eigenvalues.
    nis_matrix_test : The test built on it.

    Notes
    -----
    [F], eq. (3): with :math:`z_k = B_k^{-1}\nu_k` the whitened innovations,

    .. math::

        \Pi = \frac1K \sum_{k=1}^{K} z_k z_k^{\mathsf T}, \qquad
        K\,\Pi \sim W_m(K, I) \text{ under H0}.

    The poster states :math:`\Pi \sim W_m(K, I)`, which forgets its own
    :math:`1/K`; :math:`\Pi` itself has mean :math:`I`.  Its trace is the
    time-averaged NIS ([F], eq. 4): :math:`\operatorname{tr}\Pi = \bar\epsilon`.

    Examples
    --------
    >>> import numpy as np
    >>> eps = np.array([[1.0, 0.0], [0.0, 2.0]])
    >>> nis_matrix(eps, np.eye(2))
    array([[0.5, 0. ],
           [0. , 2. ]])
    """
    eps, L = _innovations_and_factor(innovations, S)
    z = _whiten(L, eps)
    K = z.shape[-2]
    if window is not None:
        window = _check_int(window, "window", 1, "the number of steps averaged")
        if window > K:
            raise ValueError(f"window = {window} is longer than the {K} steps given")
    scaled, scale = _scaled_nis_matrix(z, window)
    if window is not None:
        scale = scale[..., None]
    with np.errstate(over="ignore"):
        return scaled * scale * scale  # inf only where the true value exceeds double precision


def _scaled_nis_matrix(z: np.ndarray, window: int | None) -> tuple[np.ndarray, np.ndarray]:
    """``(Pi / c**2, c)`` with ``c`` a power of two near the largest ``|z|`` of each record.

    Products of whitened innovations near 1e154 overflow where their average does not;
    scaling by a power of two is exact, so at ordinary scales the result is the unscaled
    one to the last bit. ``c`` has shape ``(..., 1, 1)``.
    """
    largest = np.max(np.abs(z), axis=(-2, -1), keepdims=True)
    scale = np.ldexp(1.0, np.frexp(largest)[1])
    z = z / scale
    if window is None:
        return np.einsum("...ki,...kj->...ij", z, z) / z.shape[-2], scale
    outer = z[..., :, :, None] * z[..., :, None, :]
    # Exact window sums (no running-sum cancellation): a strided view, summed.
    views = np.lib.stride_tricks.sliding_window_view(outer, window, axis=-3)
    return views.sum(axis=-1) / window, scale


def nis_matrix_eigenvalues(innovations: Any, S: Any) -> EigenvaluePair:
    r"""Smallest and largest eigenvalue of the NIS matrix over all steps.

    Works on stacks (a leading batch of Monte Carlo runs), so a detection
    study needs no Python loop over runs.

    Parameters
    ----------
    innovations : array_like, shape (K, m) or (..., K, m)
    S : array_like, shape (m, m) or (..., K, m, m)
        As in :func:`nis_matrix`.

    Returns
    -------
    EigenvaluePair
        ``(lmin, lmax)``, arrays of shape ``(...)``.

    See Also
    --------
    nis_matrix : The matrix whose eigenvalues these are.
    extreme_eigenvalue : Their laws under H0.
    nis_matrix_test : The test built on them.

    Notes
    -----
    Under H0 they follow :func:`extreme_eigenvalue` ``(m, K, "min")`` and
    ``(m, K, "max")``, because ([F], eq. 3, :math:`1/K` restored)

    .. math::

        K\,\Pi \sim W_m(K, I).

    Examples
    --------
    >>> import numpy as np
    >>> eps = np.array([[1.0, 0.0], [0.0, 2.0]])
    >>> lmin, lmax = nis_matrix_eigenvalues(eps, np.eye(2))
    >>> float(lmin), float(lmax)
    (0.5, 2.0)
    """
    eps, L = _innovations_and_factor(innovations, S)
    values = _nis_matrix_eigenvalues(_whiten(L, eps))
    return EigenvaluePair(values[..., 0], values[..., -1])


def _nis_matrix_eigenvalues(z: np.ndarray) -> np.ndarray:
    """Ascending eigenvalues of the NIS matrix of whitened innovations ``z`` (``(..., m)``).

    Found from the scaled matrix (see :func:`_scaled_nis_matrix`), so that an NIS matrix
    near the overflow threshold has finite eigenvalues, not NaN.
    """
    scaled, scale = _scaled_nis_matrix(z, None)
    with np.errstate(over="ignore"):
        return np.linalg.eigvalsh(scaled) * scale[..., 0] * scale[..., 0]
