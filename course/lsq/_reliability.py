"""Internal reliability (the minimal detectable bias) and the confidence band of a fit.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from scipy import linalg as sla
from scipy import stats

from course.chi2 import noncentrality
from course.lsq._fit import LeastSquaresFit, _check_fit, _require_redundancy
from course.lsq._tests import _w_quantities
from course.validation import (
    as_float_array,
    as_probability,
)


# ---------------------------------------------------------------------------
# reliability
# ---------------------------------------------------------------------------
def mdb(fit: LeastSquaresFit, alpha: float = 0.001, power: float = 0.80) -> np.ndarray:
    r"""Minimal detectable bias of every observation (internal reliability).

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    alpha : float
        Level of significance of the w-test.
    power : float
        Probability with which the bias must be detected.

    Returns
    -------
    ndarray, shape (m,)
        ``|∇_i|``, in the units of y; ``inf`` where an observation is untestable.

    See Also
    --------
    w_tests : The tests whose detectable biases these are.
    course.chi2.noncentrality : The non-centrality for a given power.

    Notes
    -----
    An outlier :math:`\nabla` in observation :math:`i` shifts the mean of
    :math:`w_i` to
    :math:`\nabla \sqrt{c_i^{\mathsf T} Q_{yy}^{-1} Q_{\hat e\hat e} Q_{yy}^{-1} c_i}`,
    so :math:`w_i^2` is :math:`\chi^2(1, \lambda)` with
    :math:`\lambda = \nabla^2 c_i^{\mathsf T} Q_{yy}^{-1} Q_{\hat e\hat e} Q_{yy}^{-1} c_i`.
    The smallest bias found with probability ``power`` is therefore

    .. math::

        |\nabla_i| = \sqrt{\frac{\lambda_0}
        {c_i^{\mathsf T} Q_{yy}^{-1} Q_{\hat e\hat e} Q_{yy}^{-1} c_i}}

    with :math:`\lambda_0` = ``noncentrality(alpha, power, 1)``; for diagonal
    :math:`Q_{yy}` this is :math:`\sigma_i \sqrt{\lambda_0 / r_i}` with
    :math:`r_i` the redundancy number. Beyond the chapter; reference: Baarda
    (1968).

    Examples
    --------
    >>> import numpy as np
    >>> from course.lsq import fit
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> mdb(fit(A, [14, 20, 20, 24])).round(2)
    array([7.54, 4.94, 4.94, 7.54])
    """
    fit = _check_fit(fit)
    _require_redundancy(fit, "minimal detectable bias")
    lam0 = noncentrality(alpha, power, 1)
    _, denom2, testable = _w_quantities(fit)
    out = np.full(fit.m, np.inf)
    out[testable] = np.sqrt(lam0 / denom2[testable])
    return out


# ---------------------------------------------------------------------------
# confidence band
# ---------------------------------------------------------------------------
class ConfidenceBand(NamedTuple):
    """Result of :func:`confidence_band` (unpacks as ``y_new_hat, half_width``)."""

    y_new_hat: np.ndarray
    """``A_new x̂``, ``(k,)``."""
    half_width: np.ndarray
    """Half-widths of the confidence intervals, ``(k,)``."""


def confidence_band(fit: LeastSquaresFit, A_new: Any, level: float = 0.95) -> ConfidenceBand:
    r"""Fitted values at new design rows and their confidence half-widths.

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    A_new : array_like, shape (k, n)
        Design rows at which to evaluate the model (e.g. a fine time grid).
    level : float
        Confidence level, in (0, 1).

    Returns
    -------
    ConfidenceBand
        ``y_new_hat = A_new x̂`` and ``half_width = norm.isf((1 - level) / 2) * σ``,
        with ``σ² = diag(A_new Q_x̂x̂ A_new^T)``, each of shape ``(k,)``.

    See Also
    --------
    fit : The fit whose curve it bands.

    Notes
    -----
    Section 10.4 and Figure 10.3: with :math:`Q_{yy}` known,
    :math:`\hat y(t) = a(t)^{\mathsf T} \hat x` is normal with variance
    :math:`\sigma_{\hat y}^2(t) = a(t)^{\mathsf T} Q_{\hat x\hat x} a(t)` (error
    propagation law 7.9), so the interval

    .. math::

        \hat y(t) \pm r_\alpha\, \sigma_{\hat y}(t), \qquad
        r_\alpha = N_{(1-\text{level})/2}(0, 1)

    (1.96 for 95 %) covers the true :math:`E\,y(t)` with probability
    ``level``. For day 1 of the line-fitting example
    :math:`\sigma_{\hat y_2} \approx 0.55` and the half-width is
    :math:`\approx 1.07`. The variance is evaluated as
    :math:`\lVert R^{-\mathsf T} a \rVert^2` by a triangular solve.

    Examples
    --------
    Day 1 of the chapter: the fitted value at t = 2 and its 95 % half-width.

    >>> import numpy as np
    >>> from course.lsq import fit
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> band = confidence_band(fit(A, [14, 20, 20, 24]), [[1.0, 2.0]])
    >>> round(float(band.y_new_hat[0]), 6), round(float(band.half_width[0]), 2)
    (18.0, 1.07)
    """
    fit = _check_fit(fit)
    level = as_probability(level, "level")
    A_new = as_float_array(A_new, "A_new")
    if A_new.ndim != 2 or A_new.shape[1] != fit.n:
        raise ValueError(
            f"A_new must have shape (k, n) with n = {fit.n} columns like A, got shape "
            f"{A_new.shape}; for a single row use np.reshape(row, (1, -1))"
        )
    y_new = A_new @ fit.x_hat
    G = sla.solve_triangular(fit._R, A_new.T, trans="T", lower=False, check_finite=False)
    # column norms scaled by a power of two (exact): rows ~1e160 square past double precision
    scale = np.ldexp(1.0, np.frexp(np.max(np.abs(G), axis=0, initial=0.0))[1])
    sigma = scale * np.sqrt(np.sum((G / scale) ** 2, axis=0))
    return ConfidenceBand(y_new, stats.norm.isf((1.0 - level) / 2) * sigma)
