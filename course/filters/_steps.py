"""One step of the (extended) Kalman filter: measurement update and time update.

Source: the LiU lecture on test quantities, slide "Extended Kalman Filter"
(full reference in the course bibliography, :doc:`/docs/bibliography`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.linalg import LinAlgError

from course._stacked import _T, _mm, _mv
from course._unchecked import _symmetrize as symmetrize
from course.filters._models import NonlinearModel
from course.validation import InputTypeError, as_covariance_stack, as_float_array


class MeasurementUpdate(NamedTuple):
    """Result of a measurement update (unpacks as ``x_filt, P_filt, eps, S, K``)."""

    x_filt: np.ndarray
    """``xhat(t|t)``, ``(..., n)``."""
    P_filt: np.ndarray
    """``P(t|t)``, ``(..., n, n)``."""
    eps: np.ndarray
    """The innovation ``y_t - yhat(t|t-1)``, ``(..., p)``."""
    S: np.ndarray
    """Its covariance, ``(..., p, p)``."""
    K: np.ndarray
    """The measurement-update gain, ``(..., n, p)``."""


class TimeUpdate(NamedTuple):
    """Result of a time update (unpacks as ``x_pred, P_pred``)."""

    x_pred: np.ndarray
    """``xhat(t+1|t)``, ``(..., n)``."""
    P_pred: np.ndarray
    """``P(t+1|t)``, ``(..., n, n)``."""


def kf_update(x_pred, P_pred, y, H, R, v_mean=None):
    r"""Measurement update of the Kalman filter (one step, any batch shape).

    Parameters
    ----------
    x_pred : (..., n) ndarray
        Predicted state ``xhat(t|t-1)``.
    P_pred : (..., n, n) ndarray
        Its covariance ``P(t|t-1)``.
    y : (..., p) ndarray
        Measurement ``y_t``.
    H : (..., p, n) ndarray
        Output matrix (the Jacobian of ``h`` for the EKF).
    R : (..., p, p) ndarray
        Measurement-noise covariance.
    v_mean : (p,) ndarray, optional
        Measurement-noise mean.

    Returns
    -------
    MeasurementUpdate
        ``(x_filt, P_filt, eps, S, K)``: updated estimate and covariance,
        innovation ``eps = y - H x_pred - v_mean``, its covariance ``S``, and
        the gain ``K``.

    Raises
    ------
    ValueError
        Wrong shapes, NaN or inf; ``S = H P_pred H^T + R`` beyond double
        precision (rescale ``y``, ``H`` and ``R``).
    numpy.linalg.LinAlgError
        ``S`` not positive definite.

    See Also
    --------
    kf_predict : The time update that follows.
    ekf_update : The same update for a nonlinear measurement.
    kalman_filter : The whole filter.

    Notes
    -----
    .. math::

        S &= H P H^{\mathsf T} + R, \qquad K = P H^{\mathsf T} S^{-1}, \qquad
        \hat x_{\text{filt}} = \hat x_{\text{pred}} + K \varepsilon, \\
        P_{\text{filt}} &= (I - K H) P (I - K H)^{\mathsf T} + K R K^{\mathsf T},

    with :math:`K` computed by a linear solve with :math:`S`, never an inverse.
    The Joseph form of :math:`P_{\text{filt}}` stays symmetric and positive
    semi-definite under rounding and equals :math:`(I - K H) P` in exact
    arithmetic; see the measurement update on the lecture's EKF slide (LiU
    lecture, "Extended Kalman Filter").  Inputs are never modified;
    broadcasting lets :math:`P` be shared by a batch of :math:`x`.  Where
    :math:`H P H^{\mathsf T}` overflows (:math:`|H| \sim 10^{160}`) each output is
    scaled by a power of two first (exact), so the gain and
    :math:`P_{\text{filt}}` stay right; where :math:`S` itself exceeds double
    precision a ``ValueError`` says so (an infinite :math:`S` would make the NIS 0).

    Examples
    --------
    >>> import numpy as np
    >>> step = kf_update([0.0], [[1.0]], [2.0], [[1.0]], [[1.0]])
    >>> step.x_filt, step.S, step.K
    (array([1.]), array([[2.]]), array([[0.5]]))
    """
    x_pred = _state(x_pred, "x_pred")
    P_pred = as_covariance_stack(P_pred, "P_pred", allow_singular=True)
    y = _state(y, "y")
    H = as_float_array(H, "H", min_ndim=2, empty=False)
    R = as_covariance_stack(R, "R")
    if v_mean is not None:
        v_mean = _state(v_mean, "v_mean")
        if v_mean.shape[-1] != y.shape[-1]:
            raise ValueError(
                f"v_mean must have length p = {y.shape[-1]} like y, got {v_mean.shape}"
            )
    update = _kf_update(x_pred, P_pred, y, H, R, v_mean)
    if not np.isfinite(update.S).all():
        # the gain and P_filt are right (each output is scaled), but S itself is not a
        # double: returned as inf it would make the NIS 0 without a word
        raise _innovation_covariance_overflow("S = H P_pred H^T + R", H, R, "y, H (and v_mean)")
    return update


def _innovation_covariance_overflow(what: str, H, R, rescale: str) -> ValueError:
    """The refusal of an innovation covariance beyond double precision, with the remedy.

    Shared by :func:`kf_update` and the filter drivers: their gains and estimates are
    right (each output is scaled), but ``S`` is not a double, and returned as inf it
    would make every NIS 0.
    """
    return ValueError(
        f"the innovation covariance {what} exceeds the range of doubles "
        f"(~1.8e308; largest |H| = {float(np.max(np.abs(H))):.3g}, largest R = "
        f"{float(np.max(np.abs(R))):.3g}); rescale the measurements: dividing {rescale} "
        "by c and R by c^2 leaves the estimates and the NIS unchanged"
    )


def _state(value, name: str) -> np.ndarray:
    """A finite vector ``(..., d)`` of a filter step (a state, a measurement)."""
    return as_float_array(value, name, min_ndim=1, empty=False)


def _kf_update(x_pred, P_pred, y, H, R, v_mean=None):
    """:func:`kf_update` for arrays the library built (no value checks: the filters' loop)."""
    x_pred, P_pred, y, H, R = (np.asarray(a, dtype=float) for a in (x_pred, P_pred, y, H, R))
    _check_update_shapes(x_pred, P_pred, y, H, R)
    y_hat = _mv(H, x_pred)
    if v_mean is not None:
        y_hat = y_hat + v_mean
    return _update_core(x_pred, P_pred, y - y_hat, H, R)


def _check_update_shapes(x_pred, P_pred, y, H, R) -> None:
    """Shape check of one measurement update; names the offending argument."""
    n = x_pred.shape[-1] if x_pred.ndim else 0
    p = y.shape[-1] if y.ndim else 0
    problems = []
    if x_pred.ndim < 1:
        problems.append(f"x_pred must be (..., n), got shape {x_pred.shape}")
    if P_pred.ndim < 2 or P_pred.shape[-2:] != (n, n):
        problems.append(
            f"P_pred must be (..., {n}, {n}) for the n = {n} states of x_pred, got {P_pred.shape}"
        )
    if y.ndim < 1:
        problems.append(f"y must be (..., p), got shape {y.shape}")
    if H.ndim < 2 or H.shape[-2:] != (p, n):
        problems.append(
            f"H must be (..., p, n) = (..., {p}, {n}) for the lengths of y and x_pred, got {H.shape}"
        )
    if R.ndim < 2 or R.shape[-2:] != (p, p):
        problems.append(f"R must be (..., {p}, {p}) for the p = {p} outputs of y, got {R.shape}")
    if problems:
        raise ValueError("measurement update: " + "; ".join(problems))


def _check_predict_shapes(x_filt, P_filt, F, GQG) -> None:
    n = x_filt.shape[-1] if x_filt.ndim else 0
    problems = []
    if x_filt.ndim < 1:
        problems.append(f"x_filt must be (..., n), got shape {x_filt.shape}")
    for name, a in (("P_filt", P_filt), ("F", F), ("GQG", GQG)):
        if a.ndim < 2 or a.shape[-2:] != (n, n):
            problems.append(
                f"{name} must be (..., {n}, {n}) for the n = {n} states of x_filt, got {a.shape}"
            )
    if problems:
        raise ValueError("time update: " + "; ".join(problems))


def _update_core(x_pred, P_pred, eps, H, R):
    """Shared by the linear and extended filters: gain, estimate, Joseph update."""
    with np.errstate(over="ignore", invalid="ignore"):
        PHt = _mm(P_pred, _T(H))
        S = symmetrize(_mm(H, PHt) + R)
        in_range = math.isfinite(S.sum())  # one number: the cheapest check in the loop
    if in_range:
        K = _gain(S, PHt)
    else:
        # H P H^T beyond double precision (|H| ~ 1e160): S is, but the gain and P_filt are
        # not. Scale each output by a power of two d_i (exact): with H = D H~ and
        # R = D R~ D, S = D S~ D and K = P H~^T S~^{-1} D^{-1}.
        d = _output_scales(H, R)
        H_scaled = H / d[..., :, None]
        PHt_scaled = _mm(P_pred, _T(H_scaled))
        R_scaled = R / d[..., :, None] / d[..., None, :]
        S_scaled = symmetrize(_mm(H_scaled, PHt_scaled) + R_scaled)
        K = _gain(S_scaled, PHt_scaled) / d[..., None, :]
        with np.errstate(over="ignore"):
            S = S_scaled * d[..., :, None] * d[..., None, :]  # inf where the true S overflows
    x_filt = x_pred + _mv(K, eps)
    I_KH = np.eye(P_pred.shape[-1]) - _mm(K, H)
    P_filt = symmetrize(_mm(_mm(I_KH, P_pred), _T(I_KH)) + _mm(_mm(K, R), _T(K)))
    return MeasurementUpdate(x_filt, P_filt, eps, S, K)


def _output_scales(H, R):
    """Per output a power of two ``d_i >= max(max_j |H_ij|, sqrt(R_ii))``, shape ``(..., p)``."""
    size = np.maximum(np.max(np.abs(H), axis=-1), np.sqrt(np.diagonal(R, axis1=-2, axis2=-1)))
    return np.ldexp(1.0, np.frexp(size)[1])


def _gain(S, PHt):
    """``K = P H^T S^{-1}`` by a solve with ``S``, which must be positive definite."""
    if S.shape[-1] == 1:
        # one output: the solve with a 1 x 1 S is a division
        if np.any(S <= 0):
            raise LinAlgError(
                "the innovation variance S = H P H^T + R is not positive; "
                "R must be positive definite"
            )
        return PHt / S
    # the Cholesky factorisation is the positive-definiteness check a plain
    # solve would skip (an indefinite S solves without complaint)
    try:
        np.linalg.cholesky(S)
    except LinAlgError:
        raise LinAlgError(
            "the innovation covariance S = H P H^T + R is not positive definite; "
            "R must be positive definite and P positive semi-definite"
        ) from None
    return _T(np.linalg.solve(S, _T(PHt)))


def kf_predict(x_filt, P_filt, F, GQG, offset=None):
    r"""Time update of the Kalman filter (one step, any batch shape).

    Parameters
    ----------
    x_filt : (..., n) ndarray
        Filtered state ``xhat(t|t)``.
    P_filt : (..., n, n) ndarray
        Its covariance.
    F : (..., n, n) ndarray
        Transition matrix (the Jacobian of ``g`` for the EKF).
    GQG : (..., n, n) ndarray
        ``G Q G^T``.
    offset : (..., n) ndarray, optional
        Known additive term, ``B u_t + G w_mean``.

    Returns
    -------
    TimeUpdate
        ``x_pred = xhat(t+1|t) = F xhat(t|t) + offset`` and
        ``P_pred = P(t+1|t) = F P(t|t) F^T + G Q G^T`` (symmetrised).

    See Also
    --------
    kf_update : The measurement update before it.
    ekf_predict : The same step for a nonlinear state equation.

    Notes
    -----
    The time update of the lecture's EKF slide with constant :math:`G` (LiU
    lecture, "Extended Kalman Filter"):

    .. math::

        \hat x(t+1|t) = F \hat x(t|t) + \text{offset}, \qquad
        P(t+1|t) = F P(t|t) F^{\mathsf T} + G Q G^{\mathsf T}.

    Examples
    --------
    >>> step = kf_predict([1.0], [[1.0]], [[2.0]], [[0.5]])
    >>> step.x_pred, step.P_pred
    (array([2.]), array([[4.5]]))
    """
    x_filt = _state(x_filt, "x_filt")
    P_filt = as_covariance_stack(P_filt, "P_filt", allow_singular=True)
    F = as_float_array(F, "F", min_ndim=2, empty=False)
    GQG = as_covariance_stack(GQG, "GQG", allow_singular=True)
    if offset is not None:
        offset = _state(offset, "offset")
        if offset.shape[-1] != x_filt.shape[-1]:
            raise ValueError(
                f"offset must have length n = {x_filt.shape[-1]} like x_filt, got {offset.shape}"
            )
    return _kf_predict(x_filt, P_filt, F, GQG, offset)


def _kf_predict(x_filt, P_filt, F, GQG, offset=None):
    """:func:`kf_predict` without value checks (the filters' loop)."""
    x_filt, P_filt, F, GQG = (np.asarray(a, dtype=float) for a in (x_filt, P_filt, F, GQG))
    _check_predict_shapes(x_filt, P_filt, F, GQG)
    x_pred = _mv(F, x_filt)
    if offset is not None:
        x_pred = x_pred + offset
    P_pred = symmetrize(_mm(_mm(F, P_filt), _T(F)) + GQG)
    return TimeUpdate(x_pred, P_pred)


def ekf_update(model, x_pred, P_pred, y):
    r"""Measurement update of the extended Kalman filter (one step, any batch shape).

    Parameters
    ----------
    model : NonlinearModel
        Supplies ``h``, its Jacobian, ``R`` and ``v_mean``.
    x_pred : (..., n) ndarray
        Predicted state ``xhat(t|t-1)``.
    P_pred : (..., n, n) ndarray
        Its covariance ``P(t|t-1)``.
    y : (..., p) ndarray
        Measurement ``y_t``.

    Returns
    -------
    MeasurementUpdate
        As :func:`kf_update`, with ``eps = y - h(x_pred) - v_mean`` and
        ``H = dh/dx`` at ``x_pred``.

    See Also
    --------
    ekf_predict : The time update that follows.
    kf_update : The linear update it applies with the Jacobian.

    Notes
    -----
    Lecture (LiU lecture, "Extended Kalman Filter"): with
    :math:`H_t = \partial h/\partial x` at :math:`\hat x(t|t-1)`,

    .. math::

        K_t &= P(t|t-1) H_t^{\mathsf T} \bigl(H_t P(t|t-1) H_t^{\mathsf T} + R_t\bigr)^{-1}, \\
        \hat x(t|t) &= \hat x(t|t-1) + K_t \bigl(y_t - h(\hat x(t|t-1))\bigr).

    The lecture's :math:`P(t|t) = P(t|t-1) - K_t H_t P(t|t-1)` is replaced by the
    equivalent Joseph form (see :func:`kf_update`).

    Examples
    --------
    >>> from course.filters import NonlinearModel
    >>> model = NonlinearModel(g=lambda x, u: x, h=lambda x: x**2, Q=[[0.0]], R=[[1.0]],
    ...                        x0_mean=[2.0])
    >>> step = ekf_update(model, [2.0], [[1.0]], [5.0])
    >>> step.eps, step.S          # y - h(x) and H P H^T + R with H = 2x = 4
    (array([1.]), array([[17.]]))
    """
    _check_nonlinear(model)
    x_pred = _model_state(model, x_pred, "x_pred")
    P_pred = as_covariance_stack(P_pred, "P_pred", allow_singular=True)
    return _ekf_update(model, x_pred, P_pred, _state(y, "y"))


def _model_state(model, value, name: str) -> np.ndarray:
    """A state ``(..., n)`` of the model's length, checked before ``g`` or ``h`` sees it."""
    x = _state(value, name)
    if x.shape[-1] != model.n_states:
        raise ValueError(
            f"{name} must have length n = {model.n_states} (the model's states, from its "
            f"x0_mean), got shape {x.shape}"
        )
    return x


def _check_nonlinear(model) -> None:
    if not isinstance(model, NonlinearModel):
        hint = (
            " (NonlinearModel.from_linear(model) writes a LinearModel as one)"
            if hasattr(model, "F")
            else ""
        )
        raise InputTypeError(f"model must be a NonlinearModel, got {type(model).__name__}{hint}")


def _ekf_update(model, x_pred, P_pred, y):
    """:func:`ekf_update` without value checks (the filter's loop)."""
    x_pred, P_pred, y = (np.asarray(a, dtype=float) for a in (x_pred, P_pred, y))
    H = model._jacobian_h(x_pred)
    _check_update_shapes(x_pred, P_pred, y, H, model.R)
    eps = y - model.h(x_pred) - model.v_mean
    return _update_core(x_pred, P_pred, eps, H, model.R)


def ekf_predict(model, x_filt, P_filt, u=None):
    r"""Time update of the extended Kalman filter (one step, any batch shape).

    Parameters
    ----------
    model : NonlinearModel
        Supplies ``g``, its Jacobian, ``G Q G^T`` and ``G w_mean``.
    x_filt : (..., n) ndarray
        Filtered state ``xhat(t|t)``.
    P_filt : (..., n, n) ndarray
        Its covariance ``P(t|t)``.
    u : (..., m) ndarray, optional
        Input ``u_t`` (required when the model has inputs).

    Returns
    -------
    TimeUpdate
        ``xhat(t+1|t)`` and ``P(t+1|t)``.

    See Also
    --------
    ekf_update : The measurement update before it.
    kf_predict : The linear time update.

    Notes
    -----
    .. math::

        \hat x(t+1|t) = g(\hat x(t|t), u_t) + G \bar w, \qquad
        P(t+1|t) = F_t P(t|t) F_t^{\mathsf T} + G Q G^{\mathsf T},

    with :math:`F_t = \partial g/\partial x` at :math:`\hat x(t|t)` (LiU
    lecture, slide "Extended Kalman Filter", time update; its
    :math:`G_t = \partial g/\partial w` is the constant :math:`G` here because
    the noise enters additively).

    Examples
    --------
    >>> from course.filters import NonlinearModel
    >>> model = NonlinearModel(g=lambda x, u: 0.5 * x**2, h=lambda x: x, Q=[[0.1]], R=[[1.0]],
    ...                        x0_mean=[2.0])
    >>> step = ekf_predict(model, [2.0], [[1.0]])
    >>> step.x_pred, step.P_pred.round(6)  # g(x) and F P F^T + Q with F = x = 2
    (array([2.]), array([[4.1]]))
    """
    _check_nonlinear(model)
    x_filt = _model_state(model, x_filt, "x_filt")
    P_filt = as_covariance_stack(P_filt, "P_filt", allow_singular=True)
    if model.n_inputs == 0 and u is not None:
        raise ValueError("this model has no input (n_inputs = 0) but u was passed")
    if model.n_inputs and u is None:
        raise ValueError(f"this model has {model.n_inputs} input(s): pass u of shape (..., m)")
    if u is not None:
        u = _state(u, "u")
        if u.shape[-1] != model.n_inputs:
            raise ValueError(f"u must have length m = {model.n_inputs}, got shape {u.shape}")
    return _ekf_predict(model, x_filt, P_filt, u)


def _ekf_predict(model, x_filt, P_filt, u=None):
    """:func:`ekf_predict` without value checks (the filter's loop)."""
    x_filt, P_filt = np.asarray(x_filt, dtype=float), np.asarray(P_filt, dtype=float)
    F = model._jacobian_g(x_filt, u)
    _check_predict_shapes(x_filt, P_filt, F, model.GQG)
    x_pred = model.g(x_filt, u) + model.Gw
    return TimeUpdate(x_pred, symmetrize(_mm(_mm(F, P_filt), _T(F)) + model.GQG))
