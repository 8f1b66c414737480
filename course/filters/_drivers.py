"""Filter drivers over whole records (and batches of them) and the Riccati recursion.

Source: the LiU lecture on test quantities, slide "Extended Kalman Filter";
Y. Baram (1980), "Model validation using mismatched filters", (A17)-(A18)
(full references in the course bibliography, :doc:`/docs/bibliography`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.linalg import LinAlgError
from scipy import linalg as sla

from course import _unchecked
from course._stacked import _batch_major, _time_major
from course._unchecked import _symmetrize as symmetrize
from course.filters._models import (
    LinearModel,
    NonlinearModel,
    _check_model,
    _check_steps,
    _model_records,
)
from course.filters._steps import _ekf_predict as ekf_predict
from course.filters._steps import _ekf_update as ekf_update
from course.filters._steps import _innovation_covariance_overflow
from course.filters._steps import _kf_predict as kf_predict
from course.filters._steps import _kf_update as kf_update
from course.linalg import readonly as _readonly
from course.validation import InputTypeError, as_covariance, as_flag, as_vector


# ---------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------
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

    @property
    def n_outputs(self) -> int:
        """Number of outputs ``p`` per sample."""
        return self.eps.shape[-1]

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
        return _unchecked._normalized(self.eps, self.S)

    def nis(self) -> np.ndarray:
        """Normalised innovation squared ``eps_t^T S_t^{-1} eps_t``, shape ``(*batch, N)``.

        Under H0 each value is ``chi2(p)``.  Computed by the NIS's one home,
        :mod:`course.nis` (the same numbers as :func:`course.nis.nis` of
        ``eps`` and ``S``).
        """
        return _unchecked._nis(self.eps, self.S)


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
def _prior(model, x0_mean, x0_cov):
    n = model.n_states
    x0 = model.x0_mean if x0_mean is None else as_vector(x0_mean, "x0_mean", n)
    P0 = model.x0_cov if x0_cov is None else as_covariance(x0_cov, "x0_cov", n, allow_singular=True)
    return x0, P0


def riccati(model, N, x0_cov=None) -> RiccatiResult:
    r"""Covariance recursion (Riccati equation) of the model's own Kalman filter.

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

    Raises
    ------
    ValueError
        An ``S_t`` beyond double precision (``|H| ~ 1e160``; the gains alone,
        :func:`riccati_gains`, stay right there): rescale ``H`` and ``R``.

    See Also
    --------
    riccati_gains : The gains alone.
    steady_state : The limit of the recursion.
    kalman_filter : The filter that runs the recursion on data.

    Notes
    -----
    With :math:`P(0|-1)` = ``x0_cov``,

    .. math::

        S_t &= H P(t|t-1) H^{\mathsf T} + R, \\
        K_t &= P(t|t-1) H^{\mathsf T} S_t^{-1}, \\
        P(t|t) &= (I - K_t H) P(t|t-1) (I - K_t H)^{\mathsf T} + K_t R K_t^{\mathsf T}
        \quad \text{(Joseph form)}, \\
        P(t+1|t) &= F P(t|t) F^{\mathsf T} + G Q G^{\mathsf T}.

    The gains do not depend on the data, which is what a mismatched-filter
    analysis needs (Baram 1980, (A17)-(A18): the filter's gain comes from the
    Riccati recursion of its own model).

    Examples
    --------
    >>> import numpy as np
    >>> model = LinearModel(F=[[1.0]], H=[[1.0]], Q=[[0.01]], R=[[1.0]])
    >>> rec = riccati(model, 200)
    >>> rec.K.shape, round(float(rec.K[-1, 0, 0]), 4)
    ((200, 1, 1), 0.0951)
    """
    _check_model(model)
    out = _riccati(model, _check_steps(N), x0_cov)
    if not np.isfinite(out.S).all():
        raise _innovation_covariance_overflow(
            "S_t = H P(t|t-1) H^T + R", model.H, model.R, "the model's H"
        )
    return out


def _riccati(model, N, x0_cov) -> RiccatiResult:
    """:func:`riccati` without the check of ``S`` (the gains stay right where it overflows)."""
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

    See Also
    --------
    riccati : The whole recursion, covariances included.

    Notes
    -----
    See :func:`riccati` (Baram 1980, (A17)-(A18): the filter's gain comes
    from the Riccati recursion of its own model).

    Examples
    --------
    >>> import numpy as np
    >>> model = LinearModel(F=[[1.0]], H=[[1.0]], Q=[[0.01]], R=[[1.0]])
    >>> riccati_gains(model, 3)[:, 0, 0].round(4)
    array([0.5   , 0.3377, 0.258 ])
    """
    _check_model(model)
    return _riccati(model, _check_steps(N), x0_cov).K


def steady_state(model) -> RiccatiResult:
    r"""Stationary Kalman filter from the discrete algebraic Riccati equation.

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

    See Also
    --------
    riccati : The time-varying recursion this is the limit of.

    Notes
    -----
    The stationary prediction covariance solves the discrete algebraic Riccati
    equation

    .. math::

        P = F P F^{\mathsf T} - F P H^{\mathsf T} (H P H^{\mathsf T} + R)^{-1} H P F^{\mathsf T}
            + G Q G^{\mathsf T},

    solved by :func:`scipy.linalg.solve_discrete_are` on the dual (transposed)
    system.

    Examples
    --------
    >>> import numpy as np
    >>> model = LinearModel(F=[[1.0]], H=[[1.0]], Q=[[0.01]], R=[[1.0]])
    >>> round(float(steady_state(model).K[0, 0]), 4)
    0.0951
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
    r"""Run the Kalman filter of ``model`` on one record or a batch of records.

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

    Raises
    ------
    ValueError
        An innovation covariance beyond double precision (``|H| ~ 1e160``),
        whose NIS would read 0: rescale ``y``, ``H`` and ``R`` as the message says.

    See Also
    --------
    kf_update : One measurement update.
    kf_predict : One time update.
    riccati : The covariances and gains alone.
    course.nis.nis : The normalised innovations of the result.

    Notes
    -----
    Each step is :func:`kf_update` then :func:`kf_predict` with offset
    :math:`B u_t + G \bar w`; the innovation
    :math:`\varepsilon_t = y_t - H \hat x(t|t-1) - \bar v` subtracts the
    measurement-noise mean :math:`\bar v` (``v_mean``).  Because the
    covariances are data-independent, they are computed once and shared by
    every run of the batch, so a batch costs little more than one run.

    Examples
    --------
    >>> import numpy as np
    >>> model = LinearModel(F=[[1.0]], H=[[1.0]], Q=[[0.01]], R=[[1.0]])
    >>> states, y = model.simulate(200, np.random.default_rng(0), batch=100)
    >>> result = kalman_filter(model, y)
    >>> result.eps.shape, round(float(result.nis().mean()), 1)  # NIS ~ chi2(1): mean 1
    ((100, 200, 1), 1.0)
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
    if not np.isfinite(S_all).all():
        t = int(np.argmin(np.isfinite(S_all).reshape(N, -1).all(axis=1)))
        raise _innovation_covariance_overflow(
            f"S_t = H P(t|t-1) H^T + R (at step t = {t})",
            model.H,
            model.R,
            "y, the model's H (and v_mean)",
        )
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


def extended_kalman_filter(
    model, y, u=None, x0_mean=None, x0_cov=None, store_covariances=True
) -> FilterResult:
    r"""Run the EKF of a :class:`NonlinearModel` on one record or a batch.

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

    Raises
    ------
    ValueError
        An innovation covariance beyond double precision (a Jacobian of
        ``h`` ~ 1e160), whose NIS would read 0: rescale ``y``, ``h`` and ``R``.

    See Also
    --------
    ekf_update : One measurement update.
    ekf_predict : One time update.
    kalman_filter : The linear filter.

    Notes
    -----
    Measurement update :func:`ekf_update`, then time update
    :func:`ekf_predict`, for :math:`t = 0, \dots, N-1`; every operation acts on
    the whole batch at once.

    Examples
    --------
    The linear model through the EKF gives the Kalman filter (exact Jacobians):

    >>> import numpy as np
    >>> model = LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.1]], R=[[1.0]])
    >>> _, y = model.simulate(50, np.random.default_rng(1))
    >>> ekf = extended_kalman_filter(model, y)
    >>> bool(np.allclose(ekf.eps, kalman_filter(model, y).eps))
    True
    """
    if isinstance(model, LinearModel):
        model = NonlinearModel.from_linear(model)
    if not isinstance(model, NonlinearModel):
        raise InputTypeError(
            f"model must be a NonlinearModel (or a LinearModel), got {type(model).__name__}"
        )
    store_covariances = as_flag(store_covariances, "store_covariances")
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
    if not np.isfinite(S_all).all():
        t = int(np.argmin(np.isfinite(S_all).reshape(N, -1).all(axis=1)))
        raise _innovation_covariance_overflow(
            f"S_t = H_t P(t|t-1) H_t^T + R (at step t = {t})",
            model._jacobian_h(x_pred[t]),
            model.R,
            "y, h (and v_mean)",
        )
    nb = len(batch)
    if store_covariances:
        P_pred, P_filt, K_all = (_batch_major(a, nb) for a in (P_pred, P_filt, K_all))
    else:
        P_pred = P_filt = K_all = None  # type: ignore[assignment]  # not kept: documented as None
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
