"""The lecture's example: a first-order system whose parameter beta drifts slowly.

Source: the LiU lecture on test quantities (Linköping University, Swedish
slides; full reference in the course bibliography, :doc:`/docs/bibliography`),
slide "Exempel på EKF som residualgenerator".
"""

from __future__ import annotations

from typing import Any

import numpy as np

from course._signals import _batch_shape
from course._stacked import _component_major
from course.filters import NonlinearModel, Simulation
from course.validation import as_finite, as_float_array, as_generator, as_positive, as_variance


def beta_drift_model(
    *,
    Ts: float = 0.1,
    q_beta: float = 1e-4,
    q_x: float = 1e-4,
    r: float = 1e-2,
    x0_mean: Any = (1.0, 0.0),
    x0_cov: Any = None,
) -> NonlinearModel:
    r"""The EKF model of the lecture's example, state ``z = (beta, x)``.

    ``beta_{t+1} = beta_t + w1_t``,
    ``x_{t+1} = x_t - Ts beta_t x_t + Ts u_t + w2_t``,
    ``y_t = x_t + e_t``, with ``w ~ N(0, diag(q_beta, q_x))``, ``e ~ N(0, r)``.

    Parameters
    ----------
    Ts : float
        Sampling interval (all parameters are keyword-only).
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

    See Also
    --------
    simulate_beta_system : Data of the same system with a given beta trajectory.
    course.filters.extended_kalman_filter : The filter that runs this model.

    Notes
    -----
    LiU lecture, "Exempel på EKF som residualgenerator": to detect a sensor
    fault :math:`f` in :math:`y = x + f` while :math:`\beta` varies slowly,
    augment the state with :math:`\beta` modelled as a random walk,
    :math:`\beta(t+1) = \beta(t) + w_\beta(t)`.

    Examples
    --------
    >>> model = beta_drift_model(Ts=0.1, r=2.5e-3)
    >>> model.n_states, model.n_outputs, model.n_inputs
    (2, 1, 1)
    """
    Ts = as_positive(Ts, "Ts", what="the sampling interval")
    q_beta, q_x = as_variance(q_beta, "q_beta"), as_variance(q_x, "q_x")
    r = as_variance(r, "r", positive=True)

    def g(z, u):
        beta, x = z[..., 0], z[..., 1]
        # stored entry by entry (see course.filters._stacked): the filter's next
        # products read each component of the batch as one contiguous run
        out = _component_major(np.shape(z)[:-1], (2,), z)
        out[..., 0] = beta
        out[..., 1] = x - Ts * beta * x + Ts * u[..., 0]
        return out

    def h(z):
        return z[..., 1:2]

    def jac_g(z, u):
        beta, x = z[..., 0], z[..., 1]
        J = _component_major(np.shape(z)[:-1], (2, 2), z)
        J[..., 0, 0] = 1.0
        J[..., 0, 1] = 0.0
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


def simulate_beta_system(
    beta: Any,
    u: Any,
    rng: Any,
    *,
    Ts: float = 0.1,
    q_x: float = 1e-4,
    r: float = 1e-2,
    x0: float = 0.0,
    fault: Any = None,
    batch: Any = None,
) -> Simulation:
    r"""Simulate the lecture's system for a given ``beta`` trajectory and sensor fault.

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

    See Also
    --------
    beta_drift_model : The filter model of this system.

    Notes
    -----
    The lecture's example (LiU lecture, "Exempel på EKF som
    residualgenerator"):

    .. math::

        x(t+1) = x(t) - T_s \beta(t) x(t) + T_s u(t) + w(t), \qquad
        y(t) = x(t) + f(t) + e(t),

    the forward-Euler discretisation of :math:`\dot x = -\beta x + u`, here
    with process noise :math:`w \sim N(0, q_x)` and measurement noise
    :math:`e \sim N(0, r)`.  Unlike :func:`beta_drift_model`, :math:`\beta` is
    a given trajectory (a ramp, a sine, ...), not a random walk.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(100)
    >>> states, y = simulate_beta_system(0.8 + 0.002 * t, np.ones(100), np.random.default_rng(0),
    ...                                  fault=np.where(t >= 60, 0.2, 0.0), batch=3)
    >>> states.shape, y.shape
    ((3, 100, 2), (3, 100, 1))
    """
    rng = as_generator(rng)
    beta = as_float_array(beta, "beta", min_ndim=1, empty=False)
    u = as_float_array(u, "u", min_ndim=1, empty=False)
    N = beta.shape[-1]
    if beta.ndim < 1 or u.ndim < 1 or u.shape[-1] != N:
        raise ValueError(
            f"beta and u must be (N,) or (batch, N) with equal N, got {beta.shape}, {u.shape}"
        )
    f = np.zeros(N) if fault is None else as_float_array(fault, "fault", min_ndim=1)
    if f.shape[-1] != N:
        raise ValueError(f"fault must have N = {N} samples, got shape {f.shape}")
    shape = np.broadcast_shapes(_batch_shape(batch), beta.shape[:-1], u.shape[:-1], f.shape[:-1])
    Ts = as_positive(Ts, "Ts", what="the sampling interval")
    x0 = as_finite(x0, "x0")
    q_x, r = as_variance(q_x, "q_x"), as_variance(r, "r")
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
    return Simulation(states, (x + f + np.moveaxis(e, 0, -1))[..., None])
