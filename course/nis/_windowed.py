"""Windowed NIS: moving window sums of normalised innovations squared, thresholds, one-record test."""

from __future__ import annotations

import numpy as np
from scipy import stats

from course.linalg import (
    check_alpha,
)
from course.results import TestResult


# ---------------------------------------------------------------------------
# residual evaluation
# ---------------------------------------------------------------------------
def windowed_sum(values, window) -> np.ndarray:
    """Moving sum over the last axis: ``out[..., t] = sum(values[..., t-L+1 : t+1])``.

    Parameters
    ----------
    values : (..., N) array_like
        E.g. squared normalised innovations.  NaN marks an undefined sample
        (e.g. the diffuse start of :func:`recursive_least_squares`).
    window : int
        ``L``, between 1 and N.

    Returns
    -------
    (..., N) ndarray
        The window sums.  NaN where the window is not yet full (the first
        ``L - 1`` entries) and where it contains an undefined (NaN) sample,
        so those samples never raise an alarm and are easy to mask; a NaN
        does not spoil the windows that do not contain it.

    Notes
    -----
    Computed from cumulative sums, ``C_t = sum_{k<=t} values_k`` and
    ``out_t = C_t - C_{t-L}``, in ``O(N)`` for any ``L``; NaN samples enter
    the cumulative sum as 0 and are tracked by a cumulative count.  This is
    the discrete form of the lecture's windowed test quantity
    ``T(t) = int_{t-L}^{t} r(tau)^2 dtau`` (test_quantities_lecture_sv.txt,
    "Mer generella dynamiska fall").
    """
    try:
        values = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("values must be a numeric array of shape (..., N)") from None
    if values.ndim < 1:
        raise ValueError("values must have at least one axis (the time axis, last)")
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)) or window < 1:
        raise ValueError(f"window must be a positive integer, got {window!r}")
    N = values.shape[-1]
    if window > N:
        raise ValueError(f"window = {window} is longer than the record (N = {N})")
    undefined = np.isnan(values)
    zero = np.zeros(values.shape[:-1] + (1,))
    cs = np.concatenate([zero, np.cumsum(np.where(undefined, 0.0, values), axis=-1)], axis=-1)
    out = np.full(values.shape, np.nan)
    out[..., window - 1 :] = cs[..., window:] - cs[..., :-window]
    if undefined.any():
        cn = np.concatenate([zero, np.cumsum(undefined, axis=-1)], axis=-1)
        holes = (cn[..., window:] - cn[..., :-window]) > 0
        out[..., window - 1 :][holes] = np.nan
    return out


def _is_filter_output(result) -> bool:
    """A FilterResult or RLSResult (duck-typed: this package does not import the filters)."""
    return callable(getattr(result, "nis", None)) and all(
        hasattr(result, name) for name in ("batch_shape", "n_outputs")
    )


def windowed_nis(result, window) -> np.ndarray:
    """Windowed sum of the normalised innovations squared.

    Parameters
    ----------
    result : FilterResult or RLSResult
        Output of a filter driver (any batch shape).
    window : int
        ``L``, the number of samples summed.

    Returns
    -------
    (*batch, N) ndarray
        ``T_t``; NaN for ``t < L - 1`` and for windows that contain an
        undefined innovation (the diffuse start of RLS).

    Notes
    -----
    ``T_t = sum_{k=t-L+1}^{t} eps_k^T S_k^{-1} eps_k``.  Under H0 (the
    filter's model is true, linear Gaussian case) the normalised innovations
    are independent ``N(0, I_p)``, so ``T_t ~ chi2(L p)`` (``p = 1`` for an
    :class:`RLSResult`); for the EKF this holds approximately.  The
    threshold is :func:`windowed_nis_threshold`.  It is the normalised,
    discrete form of the lecture's ``T = int (y - h(xhat))^2`` over a window
    (test_quantities_lecture_sv.txt, "Mer generella dynamiska fall").
    """
    if not _is_filter_output(result):
        raise TypeError(
            f"result must be a FilterResult or an RLSResult, got {type(result).__name__}; "
            "for an array of NIS values use windowed_sum"
        )
    return windowed_sum(result.nis(), window)


def _finite_float(value, name: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not np.isfinite(out):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return out


def _variance(value, name: str, positive: bool = False) -> float:
    out = _finite_float(value, name)
    if out < 0 or (positive and out == 0):
        kind = "positive" if positive else "non-negative"
        raise ValueError(f"{name} must be {kind} (it is a variance), got {value!r}")
    return out


def _positive_int(value, name: str, meaning: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} ({meaning}) must be a positive integer, got {value!r}")
    return int(value)


def windowed_nis_threshold(alpha, window, n_outputs=1) -> float:
    """Threshold of the windowed NIS for a per-sample false-alarm probability ``alpha``.

    Parameters
    ----------
    alpha : float
        False-alarm probability ``P(T_t > threshold | H0)`` at each ``t``
        with a full window.
    window : int
        Window length ``L`` of :func:`windowed_nis`.
    n_outputs : int, default 1
        Number of outputs ``p`` per sample (1 for :class:`RLSResult`).

    Returns
    -------
    float
        ``chi2.isf(alpha, L p)``.

    Notes
    -----
    Under H0 the normalised innovations of the correct (linear Gaussian)
    filter are independent ``N(0, I_p)``, so the window sum of ``L``
    NIS values is ``chi2(L p)`` (see :func:`windowed_chi2_test`).  The
    argument order follows ``scipy.stats.chi2.isf(alpha, dof)``.
    """
    alpha = check_alpha(alpha)
    window = _positive_int(window, "window", "the number of samples L in the window")
    n_outputs = _positive_int(n_outputs, "n_outputs", "the number of outputs p per sample")
    return float(stats.chi2.isf(alpha, window * n_outputs))


def windowed_chi2_test(result, window, alpha=0.05, t=-1, n_outputs=None):
    """Test H0 "the filter's model holds" on the window of ``L`` samples ending at ``t``.

    Parameters
    ----------
    result : FilterResult, RLSResult or (N,) array_like
        A single-record filter result, or its normalised innovations squared
        (then give ``n_outputs``, default 1; NaN marks undefined samples).
    window : int
        ``L``.
    alpha : float
        Level of significance.
    t : int
        Last sample of the window (default: the last sample); it must end a
        full window without undefined samples.
    n_outputs : int, optional
        ``p``, only with an array of NIS values.

    Returns
    -------
    TestResult
        Statistic ``T_t = sum NIS`` over the window, null ``chi2(L p)``,
        critical value ``chi2.isf(alpha, L p)``, p-value ``chi2.sf(T, L p)``.

    Notes
    -----
    Under H0 the innovations of the correct Kalman filter are independent
    with ``eps_t ~ N(0, S_t)``, so ``eps_t^T S_t^{-1} eps_t ~ chi2(p)``
    independently over time and the window sum is ``chi2(L p)``.  The lecture
    builds the observer test quantity the same way, as the square of the
    residual summed (integrated) over a window.
    """
    alpha = check_alpha(alpha)
    window = _positive_int(window, "window", "the number of samples L in the window")
    if _is_filter_output(result):
        if result.batch_shape:
            raise ValueError(
                "windowed_chi2_test takes one record; for a batch use windowed_nis and "
                "windowed_nis_threshold"
            )
        if n_outputs is not None:
            raise ValueError(
                "n_outputs is read from the filter result; give it only with NIS values"
            )
        nis = result.nis()
        p = result.n_outputs
    else:
        try:
            nis = np.asarray(result, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(
                "result must be a FilterResult, an RLSResult or a 1-D array of NIS values"
            ) from None
        if nis.ndim != 1:
            raise ValueError(f"nis must be a 1-D vector (one record), got shape {nis.shape}")
        # NaN marks undefined samples (allowed); inf or negative values are not NIS values
        if np.isinf(nis).any() or (nis < 0).any():
            raise ValueError(
                "NIS values must be finite and non-negative (NaN marks undefined samples)"
            )
        p = (
            1
            if n_outputs is None
            else _positive_int(n_outputs, "n_outputs", "the number of outputs p per sample")
        )
    T = windowed_sum(nis, window)
    N = nis.shape[-1]
    if isinstance(t, bool) or not isinstance(t, (int, np.integer)):
        raise ValueError(f"t must be an integer sample index, got {t!r}")
    t_index = int(t) + N if int(t) < 0 else int(t)
    if not window - 1 <= t_index < N:
        raise ValueError(
            f"t = {t} does not end a full window: it must lie in [{window - 1}, {N - 1}]"
        )
    if np.isnan(T[t_index]):
        raise ValueError(
            f"the window ending at t = {t_index} contains undefined (NaN) samples, e.g. the "
            "diffuse start of recursive least squares; test a later window"
        )
    dof = int(window) * p
    statistic = float(T[t_index])
    null = stats.chi2(dof)
    critical = float(null.isf(alpha))
    return TestResult(
        name=f"windowed NIS test (L = {int(window)}, t = {t_index})",
        statistic=statistic,
        alpha=alpha,
        critical_value=critical,
        pvalue=float(null.sf(statistic)),
        reject=statistic > critical,
        null=null,
        dof=dof,
        details={"window": int(window), "t": t_index},
    )
