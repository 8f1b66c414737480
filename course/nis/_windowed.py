"""Windowed NIS: moving window sums of normalised innovations squared, thresholds, one-record test.

The window is the discrete form of the LiU lecture's windowed test quantity
``T(t) = int_{t-L}^{t} r(tau)^2 dtau`` (slide "Mer generella dynamiska
fall"; full reference in the course bibliography, :doc:`/docs/bibliography`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from course.chi2 import residual_norm_law
from course.results import TestResult
from course.validation import InputTypeError, as_count, as_float_array, as_index, as_probability


def _window(window: Any) -> int:
    return as_count(window, "window", what="the number of samples L in the window")


def windowed_sum(values: Any, window: Any) -> np.ndarray:
    r"""Moving sum over the last axis: ``out[..., t] = sum(values[..., t-L+1 : t+1])``.

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

    See Also
    --------
    windowed_nis : The window sum of NIS values.

    Notes
    -----
    Computed from cumulative sums,

    .. math::

        C_t = \sum_{k \le t} x_k, \qquad \text{out}_t = C_t - C_{t-L},

    in :math:`O(N)` for any :math:`L`; NaN samples enter the cumulative sum as
    0 and are tracked by a cumulative count.  This is the discrete form of the
    lecture's windowed test quantity
    :math:`T(t) = \int_{t-L}^{t} r(\tau)^2\,d\tau` (LiU lecture, "Mer generella
    dynamiska fall").

    Examples
    --------
    >>> windowed_sum([1.0, 2.0, 3.0, float("nan"), 5.0, 6.0], 2)
    array([nan,  3.,  5., nan, nan, 11.])
    """
    # NaN marks undefined samples; inf is no value of a test quantity
    values = as_float_array(values, "values", nan=True, min_ndim=1, empty=False)
    window = _window(window)
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


def windowed_nis(result: Any, window: Any) -> np.ndarray:
    r"""Windowed sum of the normalised innovations squared.

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

    See Also
    --------
    windowed_nis_threshold : Its threshold under H0.
    windowed_chi2_test : The same window sum as a test result.
    nis : The NIS of each sample.

    Notes
    -----
    .. math::

        T_t = \sum_{k=t-L+1}^{t} \nu_k^{\mathsf T} S_k^{-1} \nu_k ,

    with :math:`\nu_k` the innovation and :math:`S_k` its covariance.

    Under H0 (the filter's model is true, linear Gaussian case) the normalised
    innovations are independent :math:`N(0, I_p)`, so
    :math:`T_t \sim \chi^2(Lp)` (:math:`p = 1` for an :class:`RLSResult`); for
    the EKF this holds approximately.  The threshold is
    :func:`windowed_nis_threshold`.  It is the normalised, discrete form of the
    lecture's :math:`T = \int (y - h(\hat x))^2` over a window (LiU lecture,
    "Mer generella dynamiska fall").

    Examples
    --------
    >>> import numpy as np
    >>> from course.filters import LinearModel, kalman_filter
    >>> model = LinearModel(F=[[1.0]], H=[[1.0]], Q=[[0.01]], R=[[1.0]])
    >>> _, y = model.simulate(100, np.random.default_rng(0), batch=5)
    >>> windowed_nis(kalman_filter(model, y), 20).shape
    (5, 100)
    """
    if not _is_filter_output(result):
        raise InputTypeError(
            f"result must be a FilterResult or an RLSResult, got {type(result).__name__}; "
            "for an array of NIS values use windowed_sum"
        )
    return windowed_sum(result.nis(), window)


def windowed_nis_threshold(window: Any, alpha: Any = 0.05, *, n_outputs: Any = 1) -> float:
    r"""Threshold of the windowed NIS for a per-sample false-alarm probability ``alpha``.

    Parameters
    ----------
    window : int
        Window length ``L`` of :func:`windowed_nis`.
    alpha : float, default 0.05
        False-alarm probability ``P(T_t > threshold | H0)`` at each ``t``
        with a full window.
    n_outputs : int, default 1
        Number of outputs ``p`` per sample (1 for an RLS result); keyword-only.

    Returns
    -------
    float
        ``chi2.isf(alpha, L p)``.

    See Also
    --------
    windowed_nis : The test quantity this threshold is for.
    empirical_threshold : A threshold from simulated values.
    course.chi2.residual_norm_law : The chi-square law it is the quantile of.

    Notes
    -----
    Under H0 the normalised innovations of the correct (linear Gaussian)
    filter are independent :math:`N(0, I_p)`, so the window sum of :math:`L`
    NIS values is :math:`\chi^2(Lp)` (see :func:`windowed_chi2_test`), the law of
    :func:`course.chi2.residual_norm_law`, and

    .. math::

        J = \chi^2_{Lp}(1 - \alpha),

    its upper :math:`\alpha` quantile (``isf``).

    Examples
    --------
    >>> round(windowed_nis_threshold(20, 0.001), 4)
    45.3147
    """
    alpha = as_probability(alpha)
    window = _window(window)
    n_outputs = as_count(n_outputs, "n_outputs", what="the number of outputs p per sample")
    return float(residual_norm_law(window * n_outputs).isf(alpha))


def windowed_chi2_test(
    result: Any, window: Any, alpha: float = 0.05, t: Any = -1, n_outputs: Any = None
) -> TestResult:
    r"""Test H0 "the filter's model holds" on the window of ``L`` samples ending at ``t``.

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

    See Also
    --------
    windowed_nis : The window sums alone.
    windowed_nis_threshold : The threshold alone.
    nis_test : The two-sided test of one window's average.

    Notes
    -----
    Under H0 the innovations of the correct Kalman filter are independent with
    :math:`\nu_t \sim N(0, S_t)`, so

    .. math::

        \nu_t^{\mathsf T} S_t^{-1} \nu_t \sim \chi^2(p)

    independently over time and the window sum is :math:`\chi^2(Lp)`.  The
    lecture builds the observer test quantity the same way, as the square of
    the residual summed (integrated) over a window.

    Examples
    --------
    >>> import numpy as np
    >>> nis_values = np.random.default_rng(1).chisquare(2, size=50)
    >>> windowed_chi2_test(nis_values, 10, n_outputs=2).dof
    20
    """
    alpha = as_probability(alpha)
    window = _window(window)
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
        # NaN marks undefined samples (allowed); inf or negative values are not NIS values
        nis = as_float_array(result, "result", nan=True, empty=False)
        if nis.ndim != 1:
            raise ValueError(
                "result must be a FilterResult, an RLSResult or a 1-D array of the NIS values "
                f"of one record, got an array of shape {nis.shape}"
            )
        if (nis < 0).any():
            raise ValueError(
                "result holds NIS values, which must be non-negative (NaN marks undefined samples)"
            )
        p = (
            1
            if n_outputs is None
            else as_count(n_outputs, "n_outputs", what="the number of outputs p per sample")
        )
    T = windowed_sum(nis, window)
    N = nis.shape[-1]
    t_index = as_index(t, "t", N, negative=True, what="the last sample of the window")
    if not window - 1 <= t_index:
        raise ValueError(
            f"t = {t} does not end a full window: it must lie in [{window - 1}, {N - 1}]"
        )
    if np.isnan(T[t_index]):
        raise ValueError(
            f"the window ending at t = {t_index} contains undefined (NaN) samples, e.g. the "
            "diffuse start of recursive least squares; test a later window"
        )
    dof = window * p
    return TestResult.from_null(
        f"windowed NIS test (L = {window}, t = {t_index})",
        float(T[t_index]),
        residual_norm_law(dof),
        alpha,
        dof=dof,
        details={"window": window, "t": t_index},
    )
