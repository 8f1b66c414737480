"""State-space models: the linear Gaussian model, the nonlinear model and their simulation.

Sources: the LiU lecture on test quantities (slide "Extended Kalman Filter")
and Y. Baram (1980), "Model validation using mismatched filters", eqs.
(2.1)-(2.2); full references in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from course._signals import _as_signal, _batch_shape
from course._stacked import _T, _batch_major, _time_major
from course._unchecked import _symmetrize as symmetrize
from course.linalg import psd_sqrt, readonly
from course.validation import (
    InputTypeError,
    as_callable,
    as_count,
    as_covariance,
    as_flag,
    as_float_array,
    as_generator,
    as_matrix,
    as_positive,
    as_vector,
)

_readonly = readonly


class Simulation(NamedTuple):
    """State and output sequences drawn from a model (unpacks as ``states, outputs``)."""

    states: np.ndarray
    """``(*batch, N, n)``, ``states[..., t, :] = x_t``."""
    outputs: np.ndarray
    """``(*batch, N, p)``."""


def _check_steps(N: Any) -> int:
    return as_count(N, "N", what="the number of samples")


def _noise(rng, sqrt_cov: np.ndarray, mean: np.ndarray, shape: tuple) -> np.ndarray:
    """Draws of N(mean, sqrt_cov^2) with shape ``shape + (dim,)``."""
    z = rng.standard_normal(shape + (sqrt_cov.shape[0],))
    return mean + z @ sqrt_cov.T


def _noise_terms(n, p, Q, G, x0_cov, w_mean, v_mean, n_from="F"):
    """Checked ``Q``, ``G`` (identity by default), ``x0_cov``, ``w_mean``, ``v_mean`` of a model
    with ``n`` states and ``p`` outputs (defaults: ``x0_cov = I``, zero means)."""
    Q = as_matrix(Q, "Q")
    q = Q.shape[0]
    if G is None:
        if Q.shape != (n, n):
            raise ValueError(
                f"Q has shape {Q.shape} but without G it must be n x n = ({n}, {n}) "
                f"(n from {n_from}); "
                "pass G (n x q) to say how a q-dimensional noise enters the state"
            )
        G = np.eye(n)
    else:
        G = as_matrix(G, "G")
        if G.shape[0] != n:
            raise ValueError(
                f"G must have n = {n} rows (the number of states, from {n_from}), got shape {G.shape}"
            )
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
    r"""Time-invariant linear Gaussian state-space model.

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

    See Also
    --------
    NonlinearModel : The model of the extended Kalman filter.
    kalman_filter : The filter of this model.

    Notes
    -----
    The linear special case of the lecture's state-space model

    .. math::

        x(t+1) = g(x(t), u(t)) + G w(t), \qquad y(t) = h(x(t)) + v(t)

    (LiU lecture, slide "Extended Kalman Filter") with :math:`g = F x + B u`,
    :math:`h = H x`; the noise means ``w_mean``, ``v_mean`` are those of Baram
    (1980), eqs. (2.1)-(2.2), where a filter may be driven by a model other
    than the one that made the data.  :math:`R` must be positive definite so
    that every innovation covariance :math:`S = H P H^{\mathsf T} + R` is.
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
        Simulation
            ``states`` ``(*batch, N, n)`` with ``states[..., t, :] = x_t``
            and ``outputs`` ``(*batch, N, p)``; unpacks as
            ``states, outputs = model.simulate(...)``.

        Examples
        --------
        >>> import numpy as np
        >>> model = LinearModel(F=[[1.0]], H=[[1.0]], Q=[[0.1]], R=[[1.0]])
        >>> sim = model.simulate(50, np.random.default_rng(0), batch=3)
        >>> sim.states.shape, sim.outputs.shape
        ((3, 50, 1), (3, 50, 1))
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
        return Simulation(_batch_major(states, nb), _batch_major(outputs, nb))


# ---------------------------------------------------------------------------
# nonlinear models and the extended Kalman filter
# ---------------------------------------------------------------------------
_FD_SCALE = np.finfo(float).eps ** (1.0 / 3.0)


def numerical_jacobian(f, x, step=None) -> np.ndarray:
    r"""Central-difference Jacobian of ``f`` at ``x``, vectorised over a batch.

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

    See Also
    --------
    NonlinearModel : The model whose Jacobians default to these.

    Notes
    -----
    Central differences,

    .. math::

        J_{:,j} = \frac{f(x + h_j e_j) - f(x - h_j e_j)}{2 h_j}, \qquad
        h_j = \text{step} \cdot \max(1, |x_j|).

    All :math:`2n` perturbed points of every batch member are evaluated in one
    call of :math:`f` (an extra axis of size :math:`n` before the last), so the
    cost is one vectorised call.

    Examples
    --------
    >>> import numpy as np
    >>> numerical_jacobian(lambda x: np.stack([x[..., 0] * x[..., 1], x[..., 1]], -1), [2.0, 3.0]).round(8)
    array([[3., 2.],
           [0., 1.]])
    """
    f = as_callable(f, "f")
    x = as_float_array(x, "x", min_ndim=1, empty=False)
    step = _FD_SCALE if step is None else as_positive(step, "step", what="the relative step")
    return _numerical_jacobian(f, x, step)


def _numerical_jacobian(f, x: np.ndarray, step: float = _FD_SCALE) -> np.ndarray:
    """:func:`numerical_jacobian` without input checks (the EKF's loop)."""
    n = x.shape[-1]
    h = step * np.maximum(1.0, np.abs(x))
    # the step actually taken, (x + h) - x, is what must be divided by
    offsets = np.eye(n) * h[..., None, :]
    xp = x[..., None, :] + offsets
    xm = x[..., None, :] - offsets
    dx = np.diagonal(xp - xm, axis1=-2, axis2=-1)
    diff = np.asarray(f(xp)) - np.asarray(f(xm))  # (..., n, k)
    return _T(diff / dx[..., :, None])


def _check_model(model, name: str = "model") -> None:
    if not isinstance(model, LinearModel):
        hint = " (use extended_kalman_filter for a NonlinearModel)" if hasattr(model, "g") else ""
        raise InputTypeError(f"{name} must be a LinearModel, got {type(model).__name__}{hint}")


class NonlinearModel:
    r"""Nonlinear state-space model with additive Gaussian noise.

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

    See Also
    --------
    LinearModel : The linear special case.
    extended_kalman_filter : The filter of this model.
    numerical_jacobian : The default Jacobians.

    Notes
    -----
    The model of the lecture's EKF slide (LiU lecture, "Extended Kalman
    Filter"),

    .. math::

        x(t+1) = g(x(t), u(t), w(t)), \qquad y(t) = h(x(t)) + e(t),

    restricted to additive process noise, so that
    :math:`G_t = \partial g/\partial w = G` is constant.  The Jacobians
    :math:`F_t = \partial g/\partial x` and :math:`H_t = \partial h/\partial x`
    are the user's or central differences (:func:`numerical_jacobian`).
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
        g, h = as_callable(g, "g"), as_callable(h, "h")
        jac_g = as_callable(jac_g, "jac_g", optional=True)
        jac_h = as_callable(jac_h, "jac_h", optional=True)
        x0_mean = as_vector(x0_mean, "x0_mean")
        n = x0_mean.shape[0]
        R = as_matrix(R, "R")
        p = R.shape[0]
        R = as_covariance(R, "R", p)
        Q, G, x0_cov, w_mean, v_mean = _noise_terms(
            n, p, Q, G, x0_cov, w_mean, v_mean, n_from="x0_mean"
        )
        q = Q.shape[0]
        n_inputs = as_count(n_inputs, "n_inputs", minimum=0, what="the dimension of u")

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
            ("jacobian_g(x0_mean, u)", lambda: self._jacobian_g(self.x0_mean, u0), (n, n)),
            ("jacobian_h(x0_mean)", lambda: self._jacobian_h(self.x0_mean), (p, n)),
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
        numerical_jacobians = as_flag(numerical_jacobians, "numerical_jacobians")
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
        x = self._states(x)
        if u is not None:
            u = as_float_array(u, "u", min_ndim=1, empty=False)
        return self._jacobian_g(x, u)

    def _states(self, x) -> np.ndarray:
        x = as_float_array(x, "x", min_ndim=1, empty=False)
        if x.shape[-1] != self.n_states:
            raise ValueError(
                f"x must have n = {self.n_states} states along its last axis, got {x.shape}"
            )
        return x

    def _jacobian_g(self, x, u=None) -> np.ndarray:
        if self.jac_g is not None:
            return np.asarray(self.jac_g(x, u), dtype=float)
        x = np.asarray(x, dtype=float)
        if u is None:
            return _numerical_jacobian(lambda z: self.g(z, None), x)
        u = np.asarray(u)[..., None, :]  # one copy per perturbed point
        return _numerical_jacobian(lambda z: self.g(z, u), x)

    def jacobian_h(self, x) -> np.ndarray:
        """``dh/dx`` at ``x``: the user's ``jac_h`` or central differences."""
        return self._jacobian_h(self._states(x))

    def _jacobian_h(self, x) -> np.ndarray:
        if self.jac_h is not None:
            return np.asarray(self.jac_h(x), dtype=float)
        return _numerical_jacobian(self.h, np.asarray(x, dtype=float))

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
        return Simulation(_batch_major(states, nb), _batch_major(outputs, nb))
