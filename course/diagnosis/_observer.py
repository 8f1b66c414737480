"""An observer with parameter adaptation as a residual generator (Euler-discretised).

Source: the LiU lecture on test quantities (Linköping University, Swedish
slides; full reference in the course bibliography, :doc:`/docs/bibliography`),
slide "Mer generella dynamiska fall".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from course._signals import _as_signal
from course._stacked import _mv
from course.nis import windowed_sum
from course.validation import as_callable, as_float_array, as_matrix, as_positive, as_vector


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

    def windowed_energy(self, window: Any, *, Ts: float = 1.0) -> np.ndarray:
        """``T_t = Ts sum_{k=t-L+1}^{t} |r_k|^2``: the windowed integral of the squared residual.

        ``Ts`` (the sampling interval) is keyword-only.
        """
        Ts = as_positive(Ts, "Ts", what="the sampling interval")
        return Ts * windowed_sum(np.sum(self.r**2, axis=-1), window)


def observer_residuals(
    y: Any, u: Any, f: Any, h: Any, x0: Any, theta0: Any, K1: Any, K2: Any, *, Ts: float
) -> ObserverResult:
    r"""Observer-based residual generator with parameter adaptation, Euler-discretised.

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
        Sampling interval (keyword-only).

    Returns
    -------
    ObserverResult
        Use :meth:`ObserverResult.windowed_energy` for the lecture's
        ``T = integral over a window of (y - h(x_hat))^2``.

    See Also
    --------
    course.filters.extended_kalman_filter : The EKF as a residual generator.
    course.nis.windowed_sum : The window sum of the squared residual.

    Notes
    -----
    LiU lecture, "Mer generella dynamiska fall": the observer with a parameter
    update driven by the output error, and the test quantity

    .. math::

        T(t) = \int_{t-L}^{t} \bigl(y(\tau) - h(\hat x(\tau))\bigr)^2\, d\tau .

    Examples
    --------
    Estimating the constant ``beta`` of ``dx/dt = -beta x + u`` from noise-free data:

    >>> import numpy as np
    >>> N, Ts = 400, 0.05
    >>> u, x = np.ones(N), np.zeros(N)
    >>> for t in range(N - 1):
    ...     x[t + 1] = x[t] + Ts * (-2.0 * x[t] + u[t])
    >>> obs = observer_residuals(x, u, f=lambda x, u, th: -th * x + u, h=lambda x: x,
    ...                          x0=[0.0], theta0=[1.0], K1=[[2.0]],
    ...                          K2=lambda x, th, u: -5.0 * x[..., None], Ts=Ts)
    >>> round(float(obs.theta_hat[-1, 0]), 2)
    2.0
    """
    f, h = as_callable(f, "f"), as_callable(h, "h")
    x0 = as_vector(x0, "x0")
    theta0 = as_vector(theta0, "theta0")
    n, k = x0.shape[0], theta0.shape[0]
    h0 = np.shape(h(x0))
    if len(h0) != 1:
        raise ValueError(f"h(x0) must return a 1-D vector, got shape {h0}")
    p = h0[0]
    y = _as_signal(y, "y", p, width_from="h(x0)")
    N = y.shape[-2]
    if u is not None:
        u = as_float_array(u, "u", min_ndim=1, empty=False)
        if u.ndim == 1:
            u = u[:, None]
        if u.shape[-2] != N:
            raise ValueError(
                f"u must have the N = {N} samples of y along axis -2, got shape {u.shape}"
            )
    f0 = np.shape(f(x0, None if u is None else u[..., 0, :], theta0))
    if f0[-1:] != (n,):
        raise ValueError(
            f"f(x0, u, theta0) returned shape {f0}, expected ({n},): n = {n} states from x0, "
            f"k = {k} parameters from theta0"
        )
    batch = y.shape[:-2] if u is None else np.broadcast_shapes(y.shape[:-2], u.shape[:-2])
    Ts = as_positive(Ts, "Ts", what="the sampling interval")

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
