"""State-space models and Kalman filters: the one home for the whole course.

A filter turns a dynamic model into a residual generator: its innovations
``eps_t = y_t - yhat(t|t-1)`` are zero-mean, white and ``N(0, S_t)`` while the
model holds, and they grow when it does not.  Everything here works on a
*batch* of independent Monte Carlo runs at once (a leading batch dimension),
so studies with 10^4 runs cost seconds.

Time convention
---------------
Samples are numbered ``t = 0, ..., N-1``.  The prior ``x_0 ~ N(x0_mean,
x0_cov)`` describes the state at the *first* measurement, so the first filter
step is a measurement update with ``xhat(0|-1) = x0_mean``,
``P(0|-1) = x0_cov``::

    x_{t+1} = F x_t + B u_t + G w_t,   w_t ~ N(w_mean, Q)
    y_t     = H x_t + v_t,             v_t ~ N(v_mean, R)

Arrays are laid out ``(*batch, N, ...)``: a state sequence is ``(N, n)`` or
``(B, N, n)``, a covariance sequence ``(N, n, n)`` or ``(B, N, n, n)``.

API
---
Models
    ``LinearModel(F, H, Q, R, G=None, x0_mean=None, x0_cov=None, w_mean=None,
    v_mean=None, B=None)``: attributes of those names plus ``n_states``,
    ``n_outputs``, ``n_noise``, ``n_inputs``, ``GQG``; method
    ``simulate(N, rng, batch=None, u=None) -> (states, outputs)``.
    ``NonlinearModel(g, h, Q, R, x0_mean, x0_cov=None, G=None, jac_g=None,
    jac_h=None, w_mean=None, v_mean=None, n_inputs=0)`` for
    ``x_{t+1} = g(x_t, u_t) + G w_t``, ``y_t = h(x_t) + v_t``; methods
    ``jacobian_g(x, u)``, ``jacobian_h(x)`` (user's or central differences),
    ``simulate(...)`` as above, ``NonlinearModel.from_linear(model)``.
    ``numerical_jacobian(f, x, step=None)``: central differences over a batch.
Pure steps (state in, state out; any leading batch dimensions broadcast)
    ``kf_update(x_pred, P_pred, y, H, R, v_mean=None) -> (x_filt, P_filt, eps, S, K)``
    ``kf_predict(x_filt, P_filt, F, GQG, offset=None) -> (x_pred, P_pred)``
    ``ekf_update(model, x_pred, P_pred, y) -> (x_filt, P_filt, eps, S, K)``
    ``ekf_predict(model, x_filt, P_filt, u=None) -> (x_pred, P_pred)``
Drivers
    ``kalman_filter(model, y, u=None, x0_mean=None, x0_cov=None) -> FilterResult``
    ``extended_kalman_filter(model, y, u=None, x0_mean=None, x0_cov=None,
    store_covariances=True) -> FilterResult``
    ``riccati(model, N, x0_cov=None) -> RiccatiResult`` (the covariance
    recursion alone: ``P_pred, S, K, P_filt``, each ``(N, ...)``)
    ``riccati_gains(model, N, x0_cov=None) -> K`` of shape ``(N, n, p)``
    ``steady_state(model) -> RiccatiResult`` (single matrices, from the DARE)
Results
    ``FilterResult`` with per-step arrays ``x_pred, P_pred, eps, S, K,
    x_filt, P_filt`` and the one-step-ahead prediction after the last sample
    ``x_next, P_next``; aliases ``innovations`` (= ``eps``), ``gain``
    (= ``K``); methods ``normalized_innovations()`` (``L_t^{-1} eps_t`` with
    ``S_t = L_t L_t^T``, so ``eps/sqrt(S)`` for one output) and ``nis()``
    (``eps^T S^{-1} eps``).  Arrays of the batch drivers may be views
    (broadcast, or time-major memory seen batch-first); copy before writing.
Recursive least squares
    ``recursive_least_squares(Phi, y, r=1.0, q=None, theta0=None, P0=None)
    -> RLSResult(theta, P, eps, S, first)``: the Kalman filter of a
    random-walk parameter (the course's only RLS); ``q = 0`` with the diffuse
    start is batch least squares after every sample, with a prior ``(theta0,
    P0)`` the regularised estimate.  ``RLSResult`` has the alias
    ``innovations`` and the methods ``normalized_innovations()`` and ``nis()``
    of ``FilterResult``, so ``windowed_nis`` accepts it too.
Residual evaluation
    ``windowed_sum(values, window)`` (NaN until the window is full),
    ``windowed_nis(result, window)``, ``windowed_nis_threshold(alpha, window,
    n_outputs=1)``, ``windowed_chi2_test(result_or_nis, window, alpha=0.05,
    t=-1, n_outputs=None) -> TestResult``, ``empirical_threshold(null_statistic,
    alpha)``, ``alarm_statistics(statistic, threshold, fault_time=None) ->
    AlarmStatistics`` (false-alarm rate, run false-alarm probability,
    detection probability, delays).
The lecture's example and observer
    ``beta_drift_model(Ts=0.1, q_beta=1e-4, q_x=1e-4, r=1e-2,
    x0_mean=(1.0, 0.0), x0_cov=None) -> NonlinearModel`` (state ``(beta, x)``),
    ``simulate_beta_system(beta, u, rng, Ts=0.1, q_x=1e-4, r=1e-2, x0=0.0,
    fault=None, batch=None) -> (states, outputs)``,
    ``observer_residuals(y, u, f, h, x0, theta0, K1, K2, Ts) -> ObserverResult``
    (``x_hat, theta_hat, r``, ``windowed_energy(window, Ts)``).

Gain convention: ``K_t = P(t|t-1) H^T S_t^{-1}`` is the *measurement-update*
gain, ``xhat(t|t) = xhat(t|t-1) + K_t eps_t``; the one-step predictor gain is
``F K_t``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.linalg import LinAlgError
from scipy import linalg as sla
from scipy import stats

from course.distributions import as_generator
from course.linalg import (
    as_covariance,
    as_float_array,
    as_matrix,
    as_vector,
    check_alpha,
    psd_sqrt,
    symmetrize,
)
from course.results import TestResult, format_number

__all__ = [
    "AlarmStatistics",
    "FilterResult",
    "LinearModel",
    "NonlinearModel",
    "ObserverResult",
    "RLSResult",
    "RiccatiResult",
    "alarm_statistics",
    "beta_drift_model",
    "ekf_predict",
    "ekf_update",
    "empirical_threshold",
    "extended_kalman_filter",
    "kalman_filter",
    "kf_predict",
    "kf_update",
    "numerical_jacobian",
    "observer_residuals",
    "recursive_least_squares",
    "riccati",
    "riccati_gains",
    "simulate_beta_system",
    "steady_state",
    "windowed_chi2_test",
    "windowed_nis",
    "windowed_nis_threshold",
    "windowed_sum",
]


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


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def _batch_shape(batch) -> tuple:
    if batch is None:
        return ()
    if isinstance(batch, (int, np.integer)):
        batch = (int(batch),)
    batch = tuple(int(b) for b in batch)
    if any(b < 1 for b in batch):
        raise ValueError(f"batch sizes must be positive integers, got {batch}")
    return batch


def _check_steps(N) -> int:
    if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or N < 1:
        raise ValueError(f"N (the number of samples) must be a positive integer, got {N!r}")
    return int(N)


def _as_signal(value, name: str, width: int, N: int | None = None) -> np.ndarray:
    """A signal of shape ``(*batch, N, width)``; ``(N,)`` is accepted when width is 1."""
    array = as_float_array(value, name)
    if array.ndim == 1:
        if width != 1:
            raise ValueError(
                f"{name} has shape {array.shape} but the model has {width} channels; "
                f"pass an array of shape (N, {width}) or (batch, N, {width})"
            )
        array = array[:, None]
    if array.ndim < 2 or array.shape[-1] != width:
        raise ValueError(
            f"{name} must have shape (N, {width}) or (batch, N, {width}), got {array.shape}"
        )
    if N is not None and array.shape[-2] != N:
        raise ValueError(f"{name} must have N = {N} samples along axis -2, got {array.shape[-2]}")
    if array.shape[-2] < 1:
        raise ValueError(f"{name} has no samples")
    return array


def _noise(rng, sqrt_cov: np.ndarray, mean: np.ndarray, shape: tuple) -> np.ndarray:
    """Draws of N(mean, sqrt_cov^2) with shape ``shape + (dim,)``."""
    z = rng.standard_normal(shape + (sqrt_cov.shape[0],))
    return mean + z @ sqrt_cov.T


def _noise_terms(n, p, Q, G, x0_cov, w_mean, v_mean):
    """Checked ``Q``, ``G`` (identity by default), ``x0_cov``, ``w_mean``, ``v_mean`` of a model
    with ``n`` states and ``p`` outputs (defaults: ``x0_cov = I``, zero means)."""
    Q = as_matrix(Q, "Q")
    q = Q.shape[0]
    if G is None:
        if Q.shape != (n, n):
            raise ValueError(
                f"Q has shape {Q.shape} but without G it must be n x n = ({n}, {n}); "
                "pass G (n x q) to say how a q-dimensional noise enters the state"
            )
        G = np.eye(n)
    else:
        G = as_matrix(G, "G", shape=(n, None))
        if G.shape[1] != q:
            raise ValueError(
                f"G has {G.shape[1]} columns but Q is {Q.shape[0]} x {Q.shape[1]}; "
                "G must be n x q where Q is q x q"
            )
    Q = as_covariance(Q, "Q", q, allow_singular=True)
    x0_cov = (
        np.eye(n) if x0_cov is None else as_covariance(x0_cov, "x0_cov", n, allow_singular=True)
    )
    w_mean = np.zeros(q) if w_mean is None else as_vector(w_mean, "w_mean", q)
    v_mean = np.zeros(p) if v_mean is None else as_vector(v_mean, "v_mean", p)
    return Q, G, x0_cov, w_mean, v_mean


def _model_inputs(model, u, N: int):
    """``u`` checked against a Linear/NonlinearModel: None or ``(*batch, N, m)``."""
    if model.n_inputs == 0:
        if u is not None:
            raise ValueError(f"this model has no input ({model._no_input}) but u was passed")
        return None
    if u is None:
        raise ValueError(f"this model has {model.n_inputs} input(s): pass u of shape (N, m)")
    return _as_signal(u, "u", model.n_inputs, N)


def _model_records(model, y, u):
    """Measurements and inputs checked against ``model``, and their common batch shape.

    ``y`` is broadcast to that batch shape; ``u`` is returned as given.
    """
    y = _as_signal(y, "y", model.n_outputs)
    N = y.shape[-2]
    batch = y.shape[:-2]
    u = _model_inputs(model, u, N)
    if u is not None:
        batch = np.broadcast_shapes(batch, u.shape[:-2])
        y = np.broadcast_to(y, batch + y.shape[-2:])
    return y, u, N, batch


def _simulation_draws(model, N, rng, batch, u):
    """Inputs and random draws of a Linear/NonlinearModel's ``simulate``.

    Returns ``N``, the batch shape, the inputs (time-major, broadcast to the
    batch; None without inputs), the first states ``(*batch, n)`` and the
    process noise as it enters the state ``G w_t`` and measurement noise,
    time-major ``(N, *batch, d)`` (contiguous per step).
    """
    N = _check_steps(N)
    rng = as_generator(rng)
    shape = _batch_shape(batch)
    u = _model_inputs(model, u, N)
    if u is not None:
        shape = np.broadcast_shapes(shape, u.shape[:-2])
        u = _time_major(np.broadcast_to(u, shape + u.shape[-2:]))
    x0 = _noise(rng, psd_sqrt(model.x0_cov), model.x0_mean, shape)
    Gw = _noise(rng, psd_sqrt(model.Q), model.w_mean, (N,) + shape) @ model.G.T
    v = _noise(rng, psd_sqrt(model.R), model.v_mean, (N,) + shape)
    return N, shape, u, x0, Gw, v


# ---------------------------------------------------------------------------
# the linear model
# ---------------------------------------------------------------------------
class LinearModel:
    """Time-invariant linear Gaussian state-space model.

    ``x_{t+1} = F x_t + B u_t + G w_t``, ``y_t = H x_t + v_t`` with
    ``w_t ~ N(w_mean, Q)``, ``v_t ~ N(v_mean, R)`` independent and white, and
    ``x_0 ~ N(x0_mean, x0_cov)``.

    Parameters
    ----------
    F : (n, n) array_like
        State transition matrix.
    H : (p, n) array_like
        Output matrix.
    Q : (q, q) array_like
        Process-noise covariance, symmetric positive semi-definite (a zero
        matrix is allowed: a constant parameter has no process noise).
    R : (p, p) array_like
        Measurement-noise covariance, symmetric positive definite.
    G : (n, q) array_like, optional
        How the process noise enters the state; the identity by default (then
        ``Q`` must be ``n x n``).
    x0_mean : (n,) array_like, optional
        Prior mean of the first state; zeros by default.
    x0_cov : (n, n) array_like, optional
        Prior covariance of the first state (positive semi-definite); the
        identity by default.
    w_mean : (q,) array_like, optional
        Mean of the process noise; zeros by default.
    v_mean : (p,) array_like, optional
        Mean of the measurement noise; zeros by default.
    B : (n, m) array_like, optional
        Input matrix; without it the model has no input.

    Attributes
    ----------
    F, H, Q, R, G, B, x0_mean, x0_cov, w_mean, v_mean : numpy.ndarray
        Read-only validated copies (``B`` is ``(n, 0)`` without input).
    n_states, n_outputs, n_noise, n_inputs : int
        ``n``, ``p``, ``q`` and ``m``.
    GQG : numpy.ndarray
        ``G Q G^T``, the process-noise covariance as it enters the state.

    Raises
    ------
    ValueError
        Wrong shapes, NaN/inf, non-symmetric covariances.
    numpy.linalg.LinAlgError
        ``R`` not positive definite, ``Q`` or ``x0_cov`` not positive
        semi-definite.

    Notes
    -----
    The linear special case of the lecture's state-space model
    ``x(t+1) = g(x(t), u(t)) + G w(t)``, ``y(t) = h(x(t)) + v(t)``
    (test_quantities_lecture_sv.txt, slide "Extended Kalman Filter") with
    ``g = F x + B u``, ``h = H x``; the noise means ``w_mean``, ``v_mean``
    are those of Baram (1980), eqs. (2.1)-(2.2)
    (mismatched_filters_baram.txt), where a filter may be driven by a model
    other than the one that made the data.  ``R`` must be positive definite
    so that every innovation covariance ``S = H P H^T + R`` is.
    """

    _no_input = "B was not given"  # completes "this model has no input (...)"

    def __init__(
        self, F, H, Q, R, G=None, x0_mean=None, x0_cov=None, w_mean=None, v_mean=None, B=None
    ):
        F = as_matrix(F, "F")
        n = F.shape[0]
        if F.shape != (n, n):
            raise ValueError(f"F must be square (n x n), got shape {F.shape}")
        H = as_matrix(H, "H", shape=(None, n))
        p = H.shape[0]
        if p < 1:
            raise ValueError("H must have at least one row (one output)")
        Q, G, x0_cov, w_mean, v_mean = _noise_terms(n, p, Q, G, x0_cov, w_mean, v_mean)
        q = Q.shape[0]
        R = as_covariance(R, "R", p)
        x0_mean = np.zeros(n) if x0_mean is None else as_vector(x0_mean, "x0_mean", n)
        B = np.zeros((n, 0)) if B is None else as_matrix(B, "B", shape=(n, None))

        self.F, self.H, self.Q, self.R, self.G, self.B = (_readonly(a) for a in (F, H, Q, R, G, B))
        self.x0_mean, self.x0_cov = _readonly(x0_mean), _readonly(x0_cov)
        self.w_mean, self.v_mean = _readonly(w_mean), _readonly(v_mean)
        self.n_states, self.n_outputs, self.n_noise, self.n_inputs = n, p, q, B.shape[1]
        self.GQG = _readonly(symmetrize(G @ Q @ G.T))

    def __repr__(self) -> str:
        return (
            f"LinearModel(n_states={self.n_states}, n_outputs={self.n_outputs}, "
            f"n_noise={self.n_noise}, n_inputs={self.n_inputs})"
        )

    def simulate(self, N, rng, batch=None, u=None):
        """Draw state and output sequences from the model.

        Parameters
        ----------
        N : int
            Number of samples ``t = 0, ..., N-1``.
        rng : numpy.random.Generator
            Source of randomness.
        batch : int or tuple of int, optional
            Number of independent runs (a leading batch dimension).
        u : array_like, optional
            Input, ``(N, m)`` shared by all runs or ``(*batch, N, m)``;
            required when the model has an input.

        Returns
        -------
        states : numpy.ndarray
            ``(*batch, N, n)``, ``states[..., t, :] = x_t``.
        outputs : numpy.ndarray
            ``(*batch, N, p)``.
        """
        N, shape, u, x, drive, v = _simulation_draws(self, N, rng, batch, u)
        if u is not None:
            drive = drive + u @ self.B.T
        states = np.empty((N,) + shape + (self.n_states,))
        for t in range(N):
            states[t] = x
            x = x @ self.F.T + drive[t]
        outputs = states @ self.H.T + v
        nb = len(shape)
        return _batch_major(states, nb), _batch_major(outputs, nb)


# ---------------------------------------------------------------------------
# pure filter steps
# ---------------------------------------------------------------------------
def kf_update(x_pred, P_pred, y, H, R, v_mean=None):
    """Measurement update of the Kalman filter (one step, any batch shape).

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
    x_filt, P_filt, eps, S, K : ndarray
        Updated estimate and covariance, innovation ``eps = y - H x_pred -
        v_mean``, its covariance ``S``, and the gain ``K``.

    Notes
    -----
    ``S = H P H^T + R``, ``K = P H^T S^{-1}`` (computed by a linear solve with
    ``S``, never an inverse), ``x_filt = x_pred + K eps`` and the Joseph form
    ``P_filt = (I - K H) P (I - K H)^T + K R K^T``, which stays symmetric and
    positive semi-definite under rounding and equals ``(I - K H) P`` in exact
    arithmetic; see the measurement update on the lecture's EKF slide
    (test_quantities_lecture_sv.txt, "Extended Kalman Filter").  Inputs are
    never modified; broadcasting lets ``P`` be shared by a batch of ``x``.
    """
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
        problems.append(f"P_pred must be (..., {n}, {n}) for n = {n} states, got {P_pred.shape}")
    if y.ndim < 1:
        problems.append(f"y must be (..., p), got shape {y.shape}")
    if H.ndim < 2 or H.shape[-2:] != (p, n):
        problems.append(f"H must be (..., p, n) = (..., {p}, {n}), got {H.shape}")
    if R.ndim < 2 or R.shape[-2:] != (p, p):
        problems.append(f"R must be (..., {p}, {p}) for p = {p} outputs, got {R.shape}")
    if problems:
        raise ValueError("measurement update: " + "; ".join(problems))


def _check_predict_shapes(x_filt, P_filt, F, GQG) -> None:
    n = x_filt.shape[-1] if x_filt.ndim else 0
    problems = []
    if x_filt.ndim < 1:
        problems.append(f"x_filt must be (..., n), got shape {x_filt.shape}")
    for name, a in (("P_filt", P_filt), ("F", F), ("GQG", GQG)):
        if a.ndim < 2 or a.shape[-2:] != (n, n):
            problems.append(f"{name} must be (..., {n}, {n}) for n = {n} states, got {a.shape}")
    if problems:
        raise ValueError("time update: " + "; ".join(problems))


def _update_core(x_pred, P_pred, eps, H, R):
    """Shared by the linear and extended filters: gain, estimate, Joseph update."""
    PHt = _mm(P_pred, _T(H))
    S = symmetrize(_mm(H, PHt) + R)
    if S.shape[-1] == 1:
        # one output: the solve with a 1 x 1 S is a division
        if np.any(S <= 0):
            raise LinAlgError(
                "the innovation variance S = H P H^T + R is not positive; "
                "R must be positive definite"
            )
        K = PHt / S
    else:
        # the Cholesky factorisation is the positive-definiteness check a plain
        # solve would skip (an indefinite S solves without complaint)
        try:
            np.linalg.cholesky(S)
        except LinAlgError:
            raise LinAlgError(
                "the innovation covariance S = H P H^T + R is not positive definite; "
                "R must be positive definite and P positive semi-definite"
            ) from None
        K = _T(np.linalg.solve(S, _T(PHt)))
    x_filt = x_pred + _mv(K, eps)
    I_KH = np.eye(P_pred.shape[-1]) - _mm(K, H)
    P_filt = symmetrize(_mm(_mm(I_KH, P_pred), _T(I_KH)) + _mm(_mm(K, R), _T(K)))
    return x_filt, P_filt, eps, S, K


def kf_predict(x_filt, P_filt, F, GQG, offset=None):
    """Time update of the Kalman filter (one step, any batch shape).

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
    x_pred, P_pred : ndarray
        ``xhat(t+1|t) = F xhat(t|t) + offset`` and
        ``P(t+1|t) = F P(t|t) F^T + G Q G^T`` (symmetrised).

    Notes
    -----
    The time update of the lecture's EKF slide with constant ``G``
    (test_quantities_lecture_sv.txt, "Extended Kalman Filter").
    """
    x_filt, P_filt, F, GQG = (np.asarray(a, dtype=float) for a in (x_filt, P_filt, F, GQG))
    _check_predict_shapes(x_filt, P_filt, F, GQG)
    x_pred = _mv(F, x_filt)
    if offset is not None:
        x_pred = x_pred + offset
    P_pred = symmetrize(_mm(_mm(F, P_filt), _T(F)) + GQG)
    return x_pred, P_pred


# ---------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------
def _first_of_broadcast(a: np.ndarray, nbatch: int) -> np.ndarray:
    """Drop leading batch axes that are pure broadcasts (stride 0)."""
    if nbatch and all(s == 0 for s in a.strides[:nbatch]):
        return a[(0,) * nbatch]
    return a


@dataclass(frozen=True, repr=False, eq=False)
class FilterResult:
    """Per-step output of a (extended) Kalman filter.

    All arrays have the layout ``(*batch, N, ...)``.  For the linear filter
    the covariances and gains do not depend on the data; they are then
    read-only broadcast views of one ``(N, ...)`` array (no memory cost).

    Attributes
    ----------
    x_pred : (*batch, N, n)
        ``xhat(t|t-1)``.
    P_pred : (*batch, N, n, n)
        ``P(t|t-1)``.
    eps : (*batch, N, p)
        Innovations ``y_t - yhat(t|t-1)``.
    S : (*batch, N, p, p)
        Innovation covariances.
    K : (*batch, N, n, p)
        Measurement-update gains.
    x_filt : (*batch, N, n)
        ``xhat(t|t)``.
    P_filt : (*batch, N, n, n)
        ``P(t|t)``.
    x_next : (*batch, n)
        ``xhat(N|N-1)``, the prediction after the last sample.
    P_next : (*batch, n, n)
        Its covariance.
    """

    x_pred: np.ndarray
    P_pred: np.ndarray | None
    eps: np.ndarray
    S: np.ndarray
    K: np.ndarray | None
    x_filt: np.ndarray
    P_filt: np.ndarray | None
    x_next: np.ndarray
    P_next: np.ndarray

    @property
    def innovations(self) -> np.ndarray:
        """Alias of :attr:`eps`."""
        return self.eps

    @property
    def gain(self) -> np.ndarray | None:
        """Alias of :attr:`K`."""
        return self.K

    @property
    def n_steps(self) -> int:
        return self.eps.shape[-2]

    @property
    def batch_shape(self) -> tuple:
        return self.eps.shape[:-2]

    def __repr__(self) -> str:
        return (
            f"FilterResult(batch_shape={self.batch_shape}, n_steps={self.n_steps}, "
            f"n_states={self.x_pred.shape[-1]}, n_outputs={self.eps.shape[-1]})"
        )

    def normalized_innovations(self) -> np.ndarray:
        """Whitened innovations ``L_t^{-1} eps_t`` where ``S_t = L_t L_t^T``.

        Under H0 (the filter's model is true) they are independent ``N(0, I)``
        over time; with one output this is ``eps_t / sqrt(S_t)``.
        """
        S = _first_of_broadcast(self.S, len(self.batch_shape))
        if S.shape[-1] == 1:
            return self.eps / np.sqrt(S[..., 0])
        L = np.linalg.cholesky(S)
        L = np.broadcast_to(L, self.eps.shape[:-1] + L.shape[-2:])
        return np.linalg.solve(L, self.eps[..., None])[..., 0]

    def nis(self) -> np.ndarray:
        """Normalised innovation squared ``eps_t^T S_t^{-1} eps_t``, shape ``(*batch, N)``.

        Under H0 each value is ``chi2(p)``.
        """
        z = self.normalized_innovations()
        return np.einsum("...i,...i->...", z, z)


@dataclass(frozen=True, repr=False, eq=False)
class RiccatiResult:
    """The covariance recursion of a Kalman filter alone.

    Attributes
    ----------
    P_pred, S, K, P_filt : ndarray
        ``(N, n, n)``, ``(N, p, p)``, ``(N, n, p)``, ``(N, n, n)`` for
        :func:`riccati`; single matrices for :func:`steady_state`.
    """

    P_pred: np.ndarray
    S: np.ndarray
    K: np.ndarray
    P_filt: np.ndarray

    def __repr__(self) -> str:
        return f"RiccatiResult(shape of P_pred={self.P_pred.shape})"


# ---------------------------------------------------------------------------
# drivers
# ---------------------------------------------------------------------------
def _check_model(model) -> None:
    if not isinstance(model, LinearModel):
        raise TypeError(f"model must be a LinearModel, got {type(model).__name__}")


def _prior(model, x0_mean, x0_cov):
    n = model.n_states
    x0 = model.x0_mean if x0_mean is None else as_vector(x0_mean, "x0_mean", n)
    P0 = model.x0_cov if x0_cov is None else as_covariance(x0_cov, "x0_cov", n, allow_singular=True)
    return x0, P0


def riccati(model, N, x0_cov=None) -> RiccatiResult:
    """Covariance recursion (Riccati equation) of the model's own Kalman filter.

    Parameters
    ----------
    model : LinearModel
    N : int
        Number of steps.
    x0_cov : (n, n) array_like, optional
        Prior covariance; the model's ``x0_cov`` by default.

    Returns
    -------
    RiccatiResult
        ``P_pred (N, n, n)``, ``S (N, p, p)``, ``K (N, n, p)``,
        ``P_filt (N, n, n)``.

    Notes
    -----
    ``P(0|-1) = x0_cov``; ``S_t = H P(t|t-1) H^T + R``;
    ``K_t = P(t|t-1) H^T S_t^{-1}``; Joseph update for ``P(t|t)``;
    ``P(t+1|t) = F P(t|t) F^T + G Q G^T``.  The gains do not depend on the
    data, which is what a mismatched-filter analysis needs (Baram 1980,
    (A17)-(A18): the filter's gain comes from the Riccati recursion of its
    own model).
    """
    _check_model(model)
    N = _check_steps(N)
    _, P = _prior(model, None, x0_cov)
    n, p = model.n_states, model.n_outputs
    out = RiccatiResult(
        np.empty((N, n, n)), np.empty((N, p, p)), np.empty((N, n, p)), np.empty((N, n, n))
    )
    x = np.zeros(n)
    y = np.zeros(p)
    for t in range(N):
        out.P_pred[t] = P
        _, P_f, _, S, K = kf_update(x, P, y, model.H, model.R)
        out.S[t], out.K[t], out.P_filt[t] = S, K, P_f
        _, P = kf_predict(x, P_f, model.F, model.GQG)
    return out


def riccati_gains(model, N, x0_cov=None) -> np.ndarray:
    """The gains ``K_t`` of the model's own Riccati recursion.

    Parameters
    ----------
    model : LinearModel
    N : int
        Number of steps.
    x0_cov : (n, n) array_like, optional
        Prior covariance; the model's ``x0_cov`` by default.

    Returns
    -------
    (N, n, p) ndarray
        Measurement-update gains ``K_t = P(t|t-1) H^T S_t^{-1}``.

    Notes
    -----
    See :func:`riccati` (Baram 1980, (A17)-(A18): the filter's gain comes
    from the Riccati recursion of its own model).
    """
    return riccati(model, N, x0_cov).K


def steady_state(model) -> RiccatiResult:
    """Stationary Kalman filter from the discrete algebraic Riccati equation.

    Parameters
    ----------
    model : LinearModel
        Time-invariant model with ``(F, H)`` detectable.

    Returns
    -------
    RiccatiResult
        Single matrices: the limits of ``P(t|t-1)``, ``S_t``, ``K_t``, ``P(t|t)``.

    Raises
    ------
    numpy.linalg.LinAlgError
        When the DARE has no stabilising solution (``(F, H)`` not detectable
        or ``(F, G Q^{1/2})`` not stabilisable).

    Notes
    -----
    ``P = F P F^T - F P H^T (H P H^T + R)^{-1} H P F^T + G Q G^T``, solved by
    :func:`scipy.linalg.solve_discrete_are` on the dual (transposed) system.
    """
    _check_model(model)
    try:
        P = sla.solve_discrete_are(model.F.T, model.H.T, model.GQG, model.R)
    except (ValueError, LinAlgError, sla.LinAlgError) as exc:
        raise LinAlgError(
            "no stabilising solution of the Riccati equation: (F, H) must be detectable "
            f"and (F, G Q^(1/2)) stabilisable ({exc})"
        ) from None
    P = symmetrize(P)
    n, p = model.n_states, model.n_outputs
    _, P_f, _, S, K = kf_update(np.zeros(n), P, np.zeros(p), model.H, model.R)
    return RiccatiResult(P, S, K, P_f)


def kalman_filter(model, y, u=None, x0_mean=None, x0_cov=None) -> FilterResult:
    """Run the Kalman filter of ``model`` on one record or a batch of records.

    Parameters
    ----------
    model : LinearModel
        The filter's model (it may differ from the model that made ``y``).
    y : array_like
        Measurements, ``(N, p)`` or ``(*batch, N, p)`` (``(N,)`` when p = 1).
    u : array_like, optional
        Inputs, ``(N, m)`` shared by all runs or ``(*batch, N, m)``.
    x0_mean, x0_cov : array_like, optional
        Prior of ``x_0``; the model's by default.

    Returns
    -------
    FilterResult
        Per-step arrays; the covariances and gains are broadcast views of
        the single ``(N, ...)`` Riccati recursion (they do not depend on y).

    Notes
    -----
    Each step is :func:`kf_update` then :func:`kf_predict` with offset
    ``B u_t + G w_mean``; the innovation subtracts ``v_mean``.  Because the
    covariances are data-independent, they are computed once and shared by
    every run of the batch, so a batch costs little more than one run.
    """
    _check_model(model)
    y, u, N, batch = _model_records(model, y, u)
    x, P = _prior(model, x0_mean, x0_cov)
    x = np.broadcast_to(x, batch + x.shape)
    n, p = model.n_states, model.n_outputs
    Gw = model.G @ model.w_mean
    y_t = _time_major(y)
    Bu = None if u is None else _time_major(u) @ model.B.T
    x_pred = np.empty((N,) + batch + (n,))
    x_filt = np.empty((N,) + batch + (n,))
    eps = np.empty((N,) + batch + (p,))
    P_pred, P_filt = np.empty((N, n, n)), np.empty((N, n, n))
    S_all, K_all = np.empty((N, p, p)), np.empty((N, n, p))
    for t in range(N):
        x_pred[t] = x
        P_pred[t] = P
        xf, Pf, e, S, K = kf_update(x, P, y_t[t], model.H, model.R, model.v_mean)
        x_filt[t], eps[t] = xf, e
        P_filt[t], S_all[t], K_all[t] = Pf, S, K
        offset = Gw if Bu is None else Gw + Bu[t]
        x, P = kf_predict(xf, Pf, model.F, model.GQG, offset)
    nb = len(batch)
    x_pred, x_filt, eps = (_batch_major(a, nb) for a in (x_pred, x_filt, eps))

    def shared(a):
        return _readonly(a) if not batch else np.broadcast_to(a, batch + a.shape)

    return FilterResult(
        x_pred=x_pred,
        P_pred=shared(P_pred),
        eps=eps,
        S=shared(S_all),
        K=shared(K_all),
        x_filt=x_filt,
        P_filt=shared(P_filt),
        x_next=np.array(np.broadcast_to(x, batch + (n,))),
        P_next=shared(P),
    )


# ---------------------------------------------------------------------------
# nonlinear models and the extended Kalman filter
# ---------------------------------------------------------------------------
_FD_SCALE = np.finfo(float).eps ** (1.0 / 3.0)


def numerical_jacobian(f, x, step=None) -> np.ndarray:
    """Central-difference Jacobian of ``f`` at ``x``, vectorised over a batch.

    Parameters
    ----------
    f : callable
        Maps ``(..., n)`` to ``(..., k)`` and broadcasts over leading axes.
    x : (..., n) ndarray
        Points of linearisation (a batch of them).
    step : float, optional
        Relative step; ``eps^(1/3)`` by default, the step that balances the
        O(h^2) truncation error against the O(eps/h) rounding error.

    Returns
    -------
    (..., k, n) ndarray
        ``J[..., i, j] = d f_i / d x_j``.

    Notes
    -----
    ``J[:, j] = (f(x + h_j e_j) - f(x - h_j e_j)) / (2 h_j)`` with
    ``h_j = step * max(1, |x_j|)``.  All ``2 n`` perturbed points of every
    batch member are evaluated in one call of ``f`` (an extra axis of size
    ``n`` before the last), so the cost is one vectorised call.
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[-1]
    h = (_FD_SCALE if step is None else float(step)) * np.maximum(1.0, np.abs(x))
    # the step actually taken, (x + h) - x, is what must be divided by
    offsets = np.eye(n) * h[..., None, :]
    xp = x[..., None, :] + offsets
    xm = x[..., None, :] - offsets
    dx = np.diagonal(xp - xm, axis1=-2, axis2=-1)
    diff = np.asarray(f(xp)) - np.asarray(f(xm))  # (..., n, k)
    return _T(diff / dx[..., :, None])


class NonlinearModel:
    """Nonlinear state-space model with additive Gaussian noise.

    ``x_{t+1} = g(x_t, u_t) + G w_t``, ``y_t = h(x_t) + v_t``, with
    ``w_t ~ N(w_mean, Q)``, ``v_t ~ N(v_mean, R)`` and
    ``x_0 ~ N(x0_mean, x0_cov)``.

    Parameters
    ----------
    g : callable
        ``g(x, u)`` with ``x`` of shape ``(..., n)`` and ``u`` of shape
        ``(..., m)`` (``None`` when the model has no input); returns
        ``(..., n)``.  It must broadcast over leading axes, so write it with
        ``x[..., i]`` rather than ``x[i]``.
    h : callable
        ``h(x)`` returning ``(..., p)``.
    Q : (q, q) array_like
        Process-noise covariance (positive semi-definite).
    R : (p, p) array_like
        Measurement-noise covariance (positive definite).
    x0_mean : (n,) array_like
        Prior mean of the first state; it fixes ``n``.
    x0_cov : (n, n) array_like, optional
        Prior covariance; the identity by default.
    G : (n, q) array_like, optional
        Noise input matrix; identity by default.
    jac_g : callable, optional
        ``jac_g(x, u)`` returning ``(..., n, n)``; central differences by
        default (:func:`numerical_jacobian`).
    jac_h : callable, optional
        ``jac_h(x)`` returning ``(..., p, n)``; central differences by default.
    w_mean, v_mean : array_like, optional
        Noise means; zeros by default.
    n_inputs : int
        ``m``, the dimension of ``u`` (0: no input).

    Raises
    ------
    ValueError
        When shapes disagree; ``g``, ``h`` and the Jacobians are called once
        at ``x0_mean`` to check the shapes they return (and a function that
        fails there is reported with the shape it was called with).

    Notes
    -----
    The model of the lecture's EKF slide (test_quantities_lecture_sv.txt,
    "Extended Kalman Filter"), ``x(t+1) = g(x(t), u(t), w(t))``,
    ``y(t) = h(x(t)) + e(t)``, restricted to additive process noise, so that
    ``G_t = dg/dw = G`` is constant.  The Jacobians ``F_t = dg/dx`` and
    ``H_t = dh/dx`` are the user's or central differences
    (:func:`numerical_jacobian`).
    """

    _no_input = "n_inputs = 0"

    def __init__(
        self,
        g,
        h,
        Q,
        R,
        x0_mean,
        x0_cov=None,
        G=None,
        jac_g=None,
        jac_h=None,
        w_mean=None,
        v_mean=None,
        n_inputs=0,
    ):
        for name, fun in (("g", g), ("h", h), ("jac_g", jac_g), ("jac_h", jac_h)):
            if fun is not None and not callable(fun):
                raise ValueError(f"{name} must be callable, got {type(fun).__name__}")
        x0_mean = as_vector(x0_mean, "x0_mean")
        n = x0_mean.shape[0]
        R = as_matrix(R, "R")
        p = R.shape[0]
        R = as_covariance(R, "R", p)
        Q, G, x0_cov, w_mean, v_mean = _noise_terms(n, p, Q, G, x0_cov, w_mean, v_mean)
        q = Q.shape[0]
        if (
            isinstance(n_inputs, bool)
            or not isinstance(n_inputs, (int, np.integer))
            or n_inputs < 0
        ):
            raise ValueError(f"n_inputs must be a non-negative integer, got {n_inputs!r}")

        self.g, self.h, self.jac_g, self.jac_h = g, h, jac_g, jac_h
        self.Q, self.R, self.G = _readonly(Q), _readonly(R), _readonly(G)
        self.x0_mean, self.x0_cov = _readonly(x0_mean), _readonly(x0_cov)
        self.w_mean, self.v_mean = _readonly(w_mean), _readonly(v_mean)
        self.n_states, self.n_outputs, self.n_noise, self.n_inputs = n, p, q, int(n_inputs)
        self.GQG = _readonly(symmetrize(G @ Q @ G.T))
        self.Gw = _readonly(G @ w_mean)
        self._check_functions()

    def _check_functions(self):
        n, p = self.n_states, self.n_outputs
        u0 = np.zeros(self.n_inputs) if self.n_inputs else None
        for name, value, shape in (
            ("g(x0_mean, u)", lambda: self.g(self.x0_mean, u0), (n,)),
            ("h(x0_mean)", lambda: self.h(self.x0_mean), (p,)),
            ("jacobian_g(x0_mean, u)", lambda: self.jacobian_g(self.x0_mean, u0), (n, n)),
            ("jacobian_h(x0_mean)", lambda: self.jacobian_h(self.x0_mean), (p, n)),
        ):
            try:
                got = np.shape(value())
            except Exception as exc:
                raise ValueError(
                    f"{name} raised {type(exc).__name__}: {exc}. The functions are called with "
                    f"x of shape (..., {n}) (a batch of states) and must index it as x[..., i]"
                ) from exc
            if got != shape:
                raise ValueError(
                    f"{name} returned shape {got}, expected {shape} "
                    f"(n_states = {n} from x0_mean, n_outputs = {p} from R)"
                )

    def __repr__(self) -> str:
        return (
            f"NonlinearModel(n_states={self.n_states}, n_outputs={self.n_outputs}, "
            f"n_noise={self.n_noise}, n_inputs={self.n_inputs})"
        )

    @classmethod
    def from_linear(cls, model: LinearModel, numerical_jacobians: bool = False) -> NonlinearModel:
        """The linear model written as a nonlinear one (``g = F x + B u``, ``h = H x``).

        With ``numerical_jacobians=False`` the exact Jacobians ``F`` and ``H``
        are supplied, so the EKF reproduces the Kalman filter to rounding.
        """
        _check_model(model)
        F, H, B = model.F, model.H, model.B
        has_u = model.n_inputs > 0

        def g(x, u):
            out = x @ F.T
            return out + u @ B.T if has_u else out

        def h(x):
            return x @ H.T

        jac_g = jac_h = None
        if not numerical_jacobians:

            def jac_g(x, u):
                return np.broadcast_to(F, np.shape(x)[:-1] + F.shape)

            def jac_h(x):
                return np.broadcast_to(H, np.shape(x)[:-1] + H.shape)

        return cls(
            g,
            h,
            model.Q,
            model.R,
            model.x0_mean,
            model.x0_cov,
            G=model.G,
            jac_g=jac_g,
            jac_h=jac_h,
            w_mean=model.w_mean,
            v_mean=model.v_mean,
            n_inputs=model.n_inputs,
        )

    def jacobian_g(self, x, u=None) -> np.ndarray:
        """``dg/dx`` at ``(x, u)``: the user's ``jac_g`` or central differences."""
        if self.jac_g is not None:
            return np.asarray(self.jac_g(x, u), dtype=float)
        if u is None:
            return numerical_jacobian(lambda z: self.g(z, None), x)
        u = np.asarray(u)[..., None, :]  # one copy per perturbed point
        return numerical_jacobian(lambda z: self.g(z, u), x)

    def jacobian_h(self, x) -> np.ndarray:
        """``dh/dx`` at ``x``: the user's ``jac_h`` or central differences."""
        if self.jac_h is not None:
            return np.asarray(self.jac_h(x), dtype=float)
        return numerical_jacobian(self.h, x)

    def simulate(self, N, rng, batch=None, u=None):
        """Draw state and output sequences; see :meth:`LinearModel.simulate`."""
        # g always sees u with the same batch shape as x
        N, shape, u, x, w, v = _simulation_draws(self, N, rng, batch, u)
        states = np.empty((N,) + shape + (self.n_states,))
        for t in range(N):
            states[t] = x
            x = self.g(x, None if u is None else u[t]) + w[t]
        outputs = self.h(states) + v
        nb = len(shape)
        return _batch_major(states, nb), _batch_major(outputs, nb)


def ekf_update(model, x_pred, P_pred, y):
    """Measurement update of the extended Kalman filter (one step, any batch shape).

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
    x_filt, P_filt, eps, S, K : ndarray
        As :func:`kf_update`, with ``eps = y - h(x_pred) - v_mean`` and
        ``H = dh/dx`` at ``x_pred``.

    Notes
    -----
    Lecture (test_quantities_lecture_sv.txt, "Extended Kalman Filter"):
    ``H_t = dh/dx`` at ``xhat(t|t-1)``,
    ``K_t = P(t|t-1) H_t^T (H_t P(t|t-1) H_t^T + R_t)^{-1}``,
    ``xhat(t|t) = xhat(t|t-1) + K_t (y_t - h(xhat(t|t-1)))``.  The lecture's
    ``P(t|t) = P(t|t-1) - K_t H_t P(t|t-1)`` is replaced by the equivalent
    Joseph form (see :func:`kf_update`).
    """
    x_pred, P_pred, y = (np.asarray(a, dtype=float) for a in (x_pred, P_pred, y))
    H = model.jacobian_h(x_pred)
    _check_update_shapes(x_pred, P_pred, y, H, model.R)
    eps = y - model.h(x_pred) - model.v_mean
    return _update_core(x_pred, P_pred, eps, H, model.R)


def ekf_predict(model, x_filt, P_filt, u=None):
    """Time update of the extended Kalman filter (one step, any batch shape).

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
    x_pred, P_pred : ndarray
        ``xhat(t+1|t)`` and ``P(t+1|t)``.

    Notes
    -----
    ``xhat(t+1|t) = g(xhat(t|t), u_t) + G w_mean`` and
    ``P(t+1|t) = F_t P(t|t) F_t^T + G Q G^T`` with ``F_t = dg/dx`` at
    ``xhat(t|t)`` (test_quantities_lecture_sv.txt, slide "Extended Kalman
    Filter", time update; its ``G_t = dg/dw`` is the constant ``G`` here
    because the noise enters additively).
    """
    x_filt, P_filt = np.asarray(x_filt, dtype=float), np.asarray(P_filt, dtype=float)
    F = model.jacobian_g(x_filt, u)
    _check_predict_shapes(x_filt, P_filt, F, model.GQG)
    x_pred = model.g(x_filt, u) + model.Gw
    return x_pred, symmetrize(_mm(_mm(F, P_filt), _T(F)) + model.GQG)


def extended_kalman_filter(
    model, y, u=None, x0_mean=None, x0_cov=None, store_covariances=True
) -> FilterResult:
    """Run the EKF of a :class:`NonlinearModel` on one record or a batch.

    Parameters
    ----------
    model : NonlinearModel
        The filter's model.  A :class:`LinearModel` is accepted and converted
        with :meth:`NonlinearModel.from_linear` (exact Jacobians).
    y : array_like
        ``(N, p)`` or ``(*batch, N, p)`` (``(N,)`` when p = 1).
    u : array_like, optional
        ``(N, m)`` shared by all runs, or ``(*batch, N, m)``.
    x0_mean, x0_cov : array_like, optional
        Prior; the model's by default.
    store_covariances : bool
        Keep ``P_pred``, ``P_filt`` and ``K`` (set False in large Monte Carlo
        studies that only need the innovations; ``S`` is always kept).

    Returns
    -------
    FilterResult
        Covariances are per run, ``(*batch, N, n, n)``, since they depend on
        the linearisation points.

    Notes
    -----
    Measurement update :func:`ekf_update`, then time update
    :func:`ekf_predict`, for ``t = 0, ..., N-1``; every operation acts on the
    whole batch at once.
    """
    if isinstance(model, LinearModel):
        model = NonlinearModel.from_linear(model)
    if not isinstance(model, NonlinearModel):
        raise TypeError(f"model must be a NonlinearModel, got {type(model).__name__}")
    y, u, N, batch = _model_records(model, y, u)
    if u is not None:
        u = np.broadcast_to(u, batch + u.shape[-2:])
    n, p = model.n_states, model.n_outputs
    x0, P = _prior(model, x0_mean, x0_cov)
    x = np.broadcast_to(x0, batch + (n,))
    P = np.broadcast_to(P, batch + (n, n))
    # time-major work arrays: each step then reads and writes contiguous blocks
    y_t = _time_major(y)
    u_t = None if u is None else _time_major(u)
    x_pred, x_filt = np.empty((N,) + batch + (n,)), np.empty((N,) + batch + (n,))
    eps, S_all = np.empty((N,) + batch + (p,)), np.empty((N,) + batch + (p, p))
    if store_covariances:
        P_pred, P_filt = np.empty((N,) + batch + (n, n)), np.empty((N,) + batch + (n, n))
        K_all = np.empty((N,) + batch + (n, p))
    for t in range(N):
        x_pred[t] = x
        xf, Pf, e, S, K = ekf_update(model, x, P, y_t[t])
        x_filt[t], eps[t], S_all[t] = xf, e, S
        if store_covariances:
            P_pred[t], P_filt[t], K_all[t] = P, Pf, K
        x, P = ekf_predict(model, xf, Pf, None if u_t is None else u_t[t])
    nb = len(batch)
    if store_covariances:
        P_pred, P_filt, K_all = (_batch_major(a, nb) for a in (P_pred, P_filt, K_all))
    else:
        P_pred = P_filt = K_all = None
    return FilterResult(
        x_pred=_batch_major(x_pred, nb),
        P_pred=P_pred,
        eps=_batch_major(eps, nb),
        S=_batch_major(S_all, nb),
        K=K_all,
        x_filt=_batch_major(x_filt, nb),
        P_filt=P_filt,
        x_next=np.array(x),
        P_next=np.array(P),
    )


# ---------------------------------------------------------------------------
# recursive least squares as a Kalman filter
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class RLSResult:
    """Output of :func:`recursive_least_squares`.

    Attributes
    ----------
    theta : (*batch, N, k)
        ``thetahat(t|t)``, the estimate from samples ``0..t``; NaN before
        ``first``.
    P : (N, k, k)
        Its covariance (shared by the batch); NaN before ``first``.
    eps : (*batch, N)
        Innovations ``y_t - phi_t^T thetahat(t-1|t-1)``; NaN up to and
        including ``first`` with the diffuse start (no prediction exists).
    S : (N,)
        Innovation variances (NaN where ``eps`` is).
    first : int
        First sample with an estimate: 0 with a prior, ``k0 - 1`` with the
        diffuse start, where ``k0`` is the number of rows that first give
        ``Phi`` full column rank.
    """

    theta: np.ndarray
    P: np.ndarray
    eps: np.ndarray
    S: np.ndarray
    first: int

    def __repr__(self) -> str:
        return (
            f"RLSResult(n_steps={self.theta.shape[-2]}, n_params={self.theta.shape[-1]}, "
            f"first={self.first})"
        )

    @property
    def innovations(self) -> np.ndarray:
        """Alias of ``eps`` (as in :class:`FilterResult`)."""
        return self.eps

    def normalized_innovations(self) -> np.ndarray:
        """``eps_t / sqrt(S_t)``, ``(*batch, N)``: independent N(0, 1) under the model.

        NaN where ``eps`` is (the diffuse start).  The scalar-output case of
        :meth:`FilterResult.normalized_innovations` (without its trailing
        output axis: RLS has one output).
        """
        return self.eps / np.sqrt(self.S)

    def nis(self) -> np.ndarray:
        """Normalised innovations squared ``eps_t^2 / S_t``, ``(*batch, N)``.

        Independent ``chi2(1)`` over time under the model, so
        :func:`windowed_nis` of an ``RLSResult`` is ``chi2(L)`` with a full
        window (threshold :func:`windowed_nis_threshold` with ``n_outputs=1``).
        """
        z = self.normalized_innovations()
        return z * z


def _first_full_rank(Phi: np.ndarray) -> int:
    """Smallest k0 with rank(Phi[:k0]) = k (rank only grows with rows: bisect)."""
    N, k = Phi.shape
    if k > N or np.linalg.matrix_rank(Phi) < k:
        raise LinAlgError(
            "Phi never reaches full column rank: the data do not excite every parameter, "
            "so least squares has no unique solution; give a proper prior P0 (and theta0) "
            "or more exciting regressors"
        )
    lo, hi = k, N
    while lo < hi:
        mid = (lo + hi) // 2
        if np.linalg.matrix_rank(Phi[:mid]) == k:
            hi = mid
        else:
            lo = mid + 1
    return lo


def recursive_least_squares(Phi, y, r=1.0, q=None, theta0=None, P0=None) -> RLSResult:
    """Recursive least squares: a Kalman filter for a random-walk parameter.

    Model: ``theta_{t+1} = theta_t + w_t``, ``w_t ~ N(0, q)``;
    ``y_t = phi_t^T theta_t + e_t``, ``e_t ~ N(0, r)``.

    Parameters
    ----------
    Phi : (N, k) array_like
        Regressors, one row ``phi_t^T`` per sample.
    y : array_like
        ``(N,)`` or ``(*batch, N)`` outputs (a batch shares ``Phi``).  Records
        stored as the columns of an ``(N, M)`` array (``course.diagnosis``'s
        layout) go in as ``Y.T``.  A known part of the prediction, e.g. the
        fixed parameters' contribution under H0, is subtracted beforehand:
        ``y - offset``.
    r : float
        Measurement-noise variance (> 0).
    q : float or (k, k) array_like, optional
        Process-noise covariance of the parameter (``q * I`` for a scalar);
        zero by default: a constant parameter.
    theta0, P0 : array_like, optional
        Prior mean and covariance of ``theta_0``.  Without ``P0`` the start
        is *diffuse* (no prior information): the first ``k0`` samples that
        make ``Phi`` full column rank are solved by least squares (QR), and
        the recursion runs from there.  With ``q > 0`` the parameter is
        treated as constant during those first ``k0`` samples.

    Returns
    -------
    RLSResult

    Notes
    -----
    The lecture's recursive linear regression (test_quantities_lecture_sv.txt,
    "Linjär regression - rekursiv lösare"): describe the parameter as a random
    walk and apply a standard Kalman filter; RLS is the special case
    ``q = 0``.  Each step is :func:`kf_update` with ``H = phi_t^T``, then
    ``P <- P + q``.  With ``q = 0`` and the diffuse start,
    ``thetahat(t|t)`` equals the batch least-squares estimate from samples
    ``0..t`` and ``P(t|t) = r (Phi_t^T Phi_t)^{-1}``, exactly in exact
    arithmetic; with a prior it equals the regularised estimate minimising
    ``||y - Phi theta||^2 / r + (theta - theta0)^T P0^{-1} (theta - theta0)``.
    The covariances do not depend on the data, so a batch shares them.  The
    normalised innovations are independent ``N(0, 1)`` while the model holds,
    which makes :func:`windowed_nis` of the result a recursive test quantity
    (chapter 2, "recursive computation").
    """
    Phi = as_matrix(Phi, "Phi")
    N, k = Phi.shape
    y = as_float_array(y, "y")
    if y.ndim < 1 or y.shape[-1] != N:
        raise ValueError(
            f"y must have shape (N,) or (batch, N) with N = {N} (the rows of Phi), got {y.shape}"
        )
    r = _variance(r, "r (the measurement-noise variance)", positive=True)
    if q is None:
        Qw = np.zeros((k, k))
    elif np.ndim(q) == 0:
        Qw = _variance(q, "q") * np.eye(k)
    else:
        Qw = as_covariance(q, "q", k, allow_singular=True)
    batch = y.shape[:-1]
    R = np.array([[r]])
    theta = np.full(batch + (N, k), np.nan)
    P_all = np.full((N, k, k), np.nan)
    eps = np.full(batch + (N,), np.nan)
    S_all = np.full(N, np.nan)

    if P0 is None:
        if theta0 is not None:
            raise ValueError("theta0 without P0: give its covariance P0 as well (or neither)")
        k0 = _first_full_rank(Phi)
        first = k0 - 1
        Qr, Rr = np.linalg.qr(Phi[:k0])
        # least squares on the first k0 rows, all runs at once (QR, no normal equations)
        rhs = np.moveaxis(y[..., :k0], -1, 0).reshape(k0, -1)
        coef = sla.solve_triangular(Rr, Qr.T @ rhs, lower=False, check_finite=False)
        x = np.moveaxis(coef.reshape((k,) + batch), 0, -1)
        Ri = sla.solve_triangular(Rr, np.eye(k), lower=False, check_finite=False)
        P = symmetrize(r * (Ri @ Ri.T))  # r (Phi^T Phi)^{-1}
        theta[..., first, :] = x
        P_all[first] = P
        P = P + Qw
        start = k0
    else:
        x = np.zeros(k) if theta0 is None else as_vector(theta0, "theta0", k)
        P = as_covariance(P0, "P0", k, allow_singular=True)
        x = np.broadcast_to(x, batch + (k,))
        first = start = 0
    for t in range(start, N):
        x, P, e, S, _ = kf_update(x, P, y[..., t, None], Phi[t][None, :], R)
        theta[..., t, :], P_all[t], eps[..., t], S_all[t] = x, P, e[..., 0], S[0, 0]
        P = P + Qw
    return RLSResult(theta=theta, P=P_all, eps=eps, S=S_all, first=first)


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
    if not isinstance(result, (FilterResult, RLSResult)):
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
    if isinstance(result, (FilterResult, RLSResult)):
        batch = result.batch_shape if isinstance(result, FilterResult) else result.eps.shape[:-1]
        if batch:
            raise ValueError(
                "windowed_chi2_test takes one record; for a batch use windowed_nis and "
                "windowed_nis_threshold"
            )
        if n_outputs is not None:
            raise ValueError(
                "n_outputs is read from the filter result; give it only with NIS values"
            )
        nis = result.nis()
        p = result.eps.shape[-1] if isinstance(result, FilterResult) else 1
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


def empirical_threshold(null_statistic, alpha) -> float:
    """Threshold with a per-sample false-alarm rate ``alpha`` from fault-free runs.

    Parameters
    ----------
    null_statistic : array_like
        Test quantities simulated under H0, any shape (for instance a batch
        of windowed statistics); NaN entries (undefined samples) are ignored.
    alpha : float
        Designed false-alarm probability.

    Returns
    -------
    float
        The empirical ``1 - alpha`` quantile of the finite values.

    Notes
    -----
    For test quantities whose law under H0 is not known in closed form
    (the observer's windowed energy), ``J = F_hat^{-1}(1 - alpha)`` with
    ``F_hat`` the empirical distribution function of the simulated values
    (numpy's linear-interpolation quantile).  Its accuracy is that of a
    Monte Carlo quantile: simulate many more than ``1 / alpha`` values.
    """
    alpha = check_alpha(alpha)
    try:
        values = np.asarray(null_statistic, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("null_statistic must be a numeric array") from None
    values = values[np.isfinite(values)]
    if values.size == 0:
        raise ValueError("null_statistic has no finite values")
    return float(np.quantile(values, 1.0 - alpha))


@dataclass(frozen=True, repr=False, eq=False)
class AlarmStatistics:
    """False alarms and detection delays of a thresholded statistic over many runs.

    Attributes
    ----------
    threshold : float
    false_alarm_rate : float
        Fraction of (run, sample) pairs before the fault (all samples without
        a fault) with a full window where the statistic exceeds the threshold.
    n_checked : int
        Number of such pairs.
    run_false_alarm_probability : float
        Fraction of runs with at least one alarm before the fault.
    detection_probability : float
        Fraction of runs with an alarm at or after the fault (NaN without one).
    delays : (n_runs,) ndarray
        First alarm time at or after ``fault_time`` minus ``fault_time``;
        NaN for runs that never alarm after the fault (empty without a fault).
    fault_time : int or None
    """

    threshold: float
    false_alarm_rate: float
    n_checked: int
    run_false_alarm_probability: float
    detection_probability: float
    delays: np.ndarray
    fault_time: int | None

    def __repr__(self) -> str:
        parts = [
            f"threshold={format_number(self.threshold)}",
            f"false_alarm_rate={format_number(self.false_alarm_rate, 4)}",
            f"run_false_alarm_probability={format_number(self.run_false_alarm_probability, 4)}",
        ]
        if self.fault_time is not None:
            parts += [
                f"detection_probability={format_number(self.detection_probability, 4)}",
                f"median_delay={format_number(self.median_delay, 4)}",
            ]
        return "AlarmStatistics(" + ", ".join(parts) + ")"

    @property
    def median_delay(self) -> float:
        """Median delay over the runs that detect (NaN if none does)."""
        d = self.delays[np.isfinite(self.delays)]
        return float(np.median(d)) if d.size else float("nan")

    @property
    def mean_delay(self) -> float:
        """Mean delay over the runs that detect (NaN if none does)."""
        d = self.delays[np.isfinite(self.delays)]
        return float(np.mean(d)) if d.size else float("nan")


def alarm_statistics(statistic, threshold, fault_time=None) -> AlarmStatistics:
    """Count false alarms and measure detection delays, vectorised over runs.

    Parameters
    ----------
    statistic : (n_runs, N) array_like
        A test quantity per run and sample (NaN where undefined, e.g. before
        the first full window).
    threshold : float
        Alarm when ``statistic > threshold``.
    fault_time : int, optional
        First faulty sample; without it every sample counts for false alarms.

    Returns
    -------
    AlarmStatistics

    Notes
    -----
    With alarms ``a_{i,t} = [T_{i,t} > threshold]`` (NaN never alarms):
    the false-alarm rate is ``sum a_{i,t} / #{(i, t) : t < fault_time,
    T_{i,t} defined}``, an estimate of the per-sample ``alpha`` of
    :func:`windowed_nis_threshold`; the run false-alarm probability is the
    fraction of runs with ``max_{t < fault_time} a_{i,t} = 1``, the
    quantity that grows with the record length (multiple testing); the
    delay of run ``i`` is ``min{t >= fault_time : a_{i,t}} - fault_time``.
    The lecture leaves the choice of threshold and the quality of a test
    (false alarms, detection) to the next lecture
    (test_quantities_lecture_sv.txt, last slide); these are its Monte Carlo
    estimates.
    """
    try:
        T = np.array(statistic, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("statistic must be a numeric (n_runs, N) array") from None
    if T.ndim != 2:
        raise ValueError(
            f"statistic must have shape (n_runs, N), got {T.shape}; "
            "for a single run pass statistic[None, :]"
        )
    if np.isinf(T).any():
        raise ValueError("statistic contains inf; only NaN (undefined samples) is allowed")
    _n_runs, N = T.shape
    threshold = _finite_float(threshold, "threshold")
    if fault_time is not None:
        if isinstance(fault_time, bool) or not isinstance(fault_time, (int, np.integer)):
            raise ValueError(f"fault_time must be an integer sample index, got {fault_time!r}")
        fault_time = int(fault_time)
        if not 0 <= fault_time < N:
            raise ValueError(f"fault_time must lie in [0, {N - 1}], got {fault_time}")
    end = N if fault_time is None else fault_time
    with np.errstate(invalid="ignore"):
        alarms = threshold < T  # NaN compares False
    before = alarms[:, :end]
    n_checked = int(np.isfinite(T[:, :end]).sum())
    rate = float(before.sum() / n_checked) if n_checked else float("nan")
    run_fa = float(before.any(axis=1).mean()) if end > 0 else float("nan")
    if fault_time is None:
        return AlarmStatistics(threshold, rate, n_checked, run_fa, float("nan"), np.empty(0), None)
    after = alarms[:, fault_time:]
    hit = after.any(axis=1)
    delays = np.where(hit, np.argmax(after, axis=1), np.nan).astype(float)
    return AlarmStatistics(
        threshold, rate, n_checked, run_fa, float(hit.mean()), delays, fault_time
    )


# ---------------------------------------------------------------------------
# the lecture's example: a first-order system with a drifting parameter
# ---------------------------------------------------------------------------
def beta_drift_model(
    Ts=0.1, q_beta=1e-4, q_x=1e-4, r=1e-2, x0_mean=(1.0, 0.0), x0_cov=None
) -> NonlinearModel:
    """The EKF model of the lecture's example, state ``z = (beta, x)``.

    ``beta_{t+1} = beta_t + w1_t``,
    ``x_{t+1} = x_t - Ts beta_t x_t + Ts u_t + w2_t``,
    ``y_t = x_t + e_t``, with ``w ~ N(0, diag(q_beta, q_x))``, ``e ~ N(0, r)``.

    Parameters
    ----------
    Ts : float
        Sampling interval.
    q_beta : float
        Variance of the random-walk step of ``beta``; ``0`` gives the filter
        that takes ``beta`` as an unknown constant.
    q_x, r : float
        Process- and measurement-noise variances.
    x0_mean : (2,) array_like
        Prior mean of ``(beta_0, x_0)``.
    x0_cov : (2, 2) array_like, optional
        Prior covariance; ``diag(0.25, 0.01)`` by default.

    Returns
    -------
    NonlinearModel
        With exact Jacobians
        ``dg/dz = [[1, 0], [-Ts x, 1 - Ts beta]]`` and ``dh/dz = [0, 1]``.

    Notes
    -----
    test_quantities_lecture_sv.txt, "Exempel på EKF som residualgenerator":
    to detect a sensor fault ``f`` in ``y = x + f`` while ``beta`` varies
    slowly, augment the state with ``beta`` modelled as a random walk.
    """
    Ts = _finite_float(Ts, "Ts")
    if Ts <= 0:
        raise ValueError(f"Ts must be a positive sampling interval, got {Ts!r}")
    q_beta, q_x = _variance(q_beta, "q_beta"), _variance(q_x, "q_x")
    r = _variance(r, "r", positive=True)

    def g(z, u):
        beta, x = z[..., 0], z[..., 1]
        return np.stack([beta, x - Ts * beta * x + Ts * u[..., 0]], axis=-1)

    def h(z):
        return z[..., 1:2]

    def jac_g(z, u):
        beta, x = z[..., 0], z[..., 1]
        J = np.zeros(np.shape(z)[:-1] + (2, 2))
        J[..., 0, 0] = 1.0
        J[..., 1, 0] = -Ts * x
        J[..., 1, 1] = 1.0 - Ts * beta
        return J

    H = np.array([[0.0, 1.0]])

    def jac_h(z):
        return np.broadcast_to(H, np.shape(z)[:-1] + (1, 2))

    if x0_cov is None:
        x0_cov = np.diag([0.25, 0.01])
    return NonlinearModel(
        g,
        h,
        np.diag([float(q_beta), float(q_x)]),
        [[float(r)]],
        x0_mean,
        x0_cov,
        jac_g=jac_g,
        jac_h=jac_h,
        n_inputs=1,
    )


def simulate_beta_system(beta, u, rng, Ts=0.1, q_x=1e-4, r=1e-2, x0=0.0, fault=None, batch=None):
    """Simulate the lecture's system for a given ``beta`` trajectory and sensor fault.

    ``x_{t+1} = x_t - Ts beta_t x_t + Ts u_t + w_t``, ``y_t = x_t + f_t + e_t``.

    Parameters
    ----------
    beta : (N,) or (*batch, N) array_like
        The true (e.g. slowly drifting) parameter.
    u : (N,) or (*batch, N) array_like
        Input.
    rng : numpy.random.Generator
    Ts, q_x, r : float
        Sampling interval, process- and measurement-noise variances.
    x0 : float
        Initial state.
    fault : (N,) or (*batch, N) array_like, optional
        Additive sensor fault ``f_t`` (zero by default).
    batch : int or tuple, optional
        Number of independent runs.

    Returns
    -------
    states : (*batch, N, 2) ndarray
        ``(beta_t, x_t)``, the layout of :func:`beta_drift_model`.
    outputs : (*batch, N, 1) ndarray
        ``y_t``.

    Notes
    -----
    The lecture's example (test_quantities_lecture_sv.txt, "Exempel på EKF
    som residualgenerator"): ``x(t+1) = x(t) - Ts beta(t) x(t) + Ts u(t)``,
    ``y(t) = x(t) + f(t)``, the forward-Euler discretisation of
    ``dx/dt = -beta x + u``, here with process noise ``w ~ N(0, q_x)`` and
    measurement noise ``e ~ N(0, r)``.  Unlike :func:`beta_drift_model`,
    ``beta`` is a given trajectory (a ramp, a sine, ...), not a random walk.
    """
    rng = as_generator(rng)
    beta = as_float_array(beta, "beta")
    u = as_float_array(u, "u")
    N = beta.shape[-1]
    if beta.ndim < 1 or u.ndim < 1 or u.shape[-1] != N:
        raise ValueError(
            f"beta and u must be (N,) or (batch, N) with equal N, got {beta.shape}, {u.shape}"
        )
    f = np.zeros(N) if fault is None else as_float_array(fault, "fault")
    if f.shape[-1] != N:
        raise ValueError(f"fault must have N = {N} samples, got shape {f.shape}")
    shape = np.broadcast_shapes(_batch_shape(batch), beta.shape[:-1], u.shape[:-1], f.shape[:-1])
    Ts, x0 = _finite_float(Ts, "Ts"), _finite_float(x0, "x0")
    q_x, r = _variance(q_x, "q_x"), _variance(r, "r")
    # time-major (N, *batch) so that every step touches contiguous memory
    w = np.sqrt(q_x) * rng.standard_normal((N,) + shape)
    e = np.sqrt(r) * rng.standard_normal((N,) + shape)
    beta_t = np.moveaxis(np.broadcast_to(beta, shape + (N,)), -1, 0)
    u_t = np.moveaxis(np.broadcast_to(u, shape + (N,)), -1, 0)
    x = np.empty((N,) + shape)
    xt = np.full(shape, float(x0))
    for t in range(N):
        x[t] = xt
        xt = xt - Ts * beta_t[t] * xt + Ts * u_t[t] + w[t]
    x = np.moveaxis(x, 0, -1)
    states = np.stack([np.broadcast_to(beta, x.shape), x], axis=-1)
    return states, (x + f + np.moveaxis(e, 0, -1))[..., None]


@dataclass(frozen=True, repr=False, eq=False)
class ObserverResult:
    """Output of :func:`observer_residuals`.

    Attributes
    ----------
    x_hat : (*batch, N, n)
        State estimate used at sample ``t`` (before the correction with y_t).
    theta_hat : (*batch, N, k)
        Parameter estimate used at sample ``t``.
    r : (*batch, N, p)
        Residual ``y_t - h(x_hat_t)``.
    """

    x_hat: np.ndarray
    theta_hat: np.ndarray
    r: np.ndarray

    def __repr__(self) -> str:
        return f"ObserverResult(shape of r={self.r.shape})"

    def windowed_energy(self, window, Ts=1.0) -> np.ndarray:
        """``T_t = Ts sum_{k=t-L+1}^{t} |r_k|^2``: the windowed integral of the squared residual."""
        return float(Ts) * windowed_sum(np.sum(self.r**2, axis=-1), window)


def observer_residuals(y, u, f, h, x0, theta0, K1, K2, Ts) -> ObserverResult:
    """Observer-based residual generator with parameter adaptation, Euler-discretised.

    Continuous-time design (lecture):
    ``dx_hat/dt = f(x_hat, u, theta_hat) + K1 (y - h(x_hat))``,
    ``dtheta_hat/dt = K2 (y - h(x_hat))``; discretised with forward Euler:
    ``x_hat_{t+1} = x_hat_t + Ts (f(x_hat_t, u_t, theta_hat_t) + K1 r_t)``,
    ``theta_hat_{t+1} = theta_hat_t + Ts K2 r_t``, ``r_t = y_t - h(x_hat_t)``.

    Parameters
    ----------
    y : (N, p) or (*batch, N, p) array_like
        Measurements (``(N,)`` when p = 1).
    u : (N, m) or (*batch, N, m) array_like, or None
        Inputs (``(N,)`` when m = 1).
    f : callable
        ``f(x, u, theta)`` -> ``(..., n)``, the continuous-time right-hand side.
    h : callable
        ``h(x)`` -> ``(..., p)``.
    x0 : (n,) array_like
    theta0 : (k,) array_like
    K1 : (n, p) array_like or callable
        Constant gain, or ``K1(x_hat, theta_hat, u)`` returning ``(..., n, p)``.
    K2 : (k, p) array_like or callable
        Constant gain, or ``K2(x_hat, theta_hat, u)`` returning ``(..., k, p)``;
        a state-dependent ``K2`` is how the sign of the parameter correction
        follows the sign of the sensitivity ``dh/dtheta`` (see the notebook).
    Ts : float
        Sampling interval.

    Returns
    -------
    ObserverResult
        Use :meth:`ObserverResult.windowed_energy` for the lecture's
        ``T = integral over a window of (y - h(x_hat))^2``.

    Notes
    -----
    test_quantities_lecture_sv.txt, "Mer generella dynamiska fall": the
    observer with a parameter update driven by the output error, and the
    test quantity ``T(t) = int_{t-L}^{t} (y(tau) - h(x_hat(tau)))^2 dtau``.
    """
    x0 = as_vector(x0, "x0")
    theta0 = as_vector(theta0, "theta0")
    n, k = x0.shape[0], theta0.shape[0]
    h0 = np.shape(h(x0))
    if len(h0) != 1:
        raise ValueError(f"h(x0) must return a 1-D vector, got shape {h0}")
    p = h0[0]
    y = _as_signal(y, "y", p)
    N = y.shape[-2]
    if u is not None:
        u = as_float_array(u, "u")
        if u.ndim == 1:
            u = u[:, None]
        if u.shape[-2] != N:
            raise ValueError(f"u must have N = {N} samples along axis -2, got shape {u.shape}")
    batch = y.shape[:-2] if u is None else np.broadcast_shapes(y.shape[:-2], u.shape[:-2])
    Ts = float(Ts)
    if not np.isfinite(Ts) or Ts <= 0:
        raise ValueError(f"Ts must be positive, got {Ts!r}")

    def gain(K, name, rows):
        if callable(K):
            return K
        K = as_matrix(K, name, shape=(rows, p))
        return lambda *_: K

    K1, K2 = gain(K1, "K1", n), gain(K2, "K2", k)
    x = np.broadcast_to(x0, batch + (n,))
    th = np.broadcast_to(theta0, batch + (k,))
    X, TH, Rs = np.empty(batch + (N, n)), np.empty(batch + (N, k)), np.empty(batch + (N, p))
    for t in range(N):
        ut = None if u is None else u[..., t, :]
        X[..., t, :], TH[..., t, :] = x, th
        res = y[..., t, :] - h(x)
        Rs[..., t, :] = res
        x, th = (
            x + Ts * (f(x, ut, th) + _mv(K1(x, th, ut), res)),
            th + Ts * _mv(K2(x, th, ut), res),
        )
    return ObserverResult(x_hat=X, theta_hat=TH, r=Rs)
