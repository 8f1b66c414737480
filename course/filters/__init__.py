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

Contents
--------
The names live in private single-topic modules and are re-exported here
(see each function's docstring for its signature):

Models (``_models``)
    :class:`LinearModel`, :class:`NonlinearModel` (with ``simulate``, which
    returns a :class:`Simulation`), :func:`numerical_jacobian`.
Pure steps (``_steps``; state in, state out, any batch shape)
    :func:`kf_update`, :func:`kf_predict`, :func:`ekf_update`, :func:`ekf_predict`.
Drivers and results (``_drivers``)
    :func:`kalman_filter`, :func:`extended_kalman_filter`, :func:`riccati`,
    :func:`riccati_gains`, :func:`steady_state`, :class:`FilterResult`,
    :class:`RiccatiResult`.
Recursive least squares (``_rls``)
    :func:`recursive_least_squares` and :class:`RLSResult`: the Kalman
    filter of a random-walk parameter (the course's only RLS).

Residual evaluation (the windowed NIS, its threshold and test, alarm
statistics) lives in :mod:`course.nis`; the lecture's beta example and the
observer live in :mod:`course.diagnosis`.

Gain convention: ``K_t = P(t|t-1) H^T S_t^{-1}`` is the *measurement-update*
gain, ``xhat(t|t) = xhat(t|t-1) + K_t eps_t``; the one-step predictor gain is
``F K_t``.

Sources: the lecture on test quantities (the extended Kalman filter and RLS as residual
generators) and the classical Kalman-filter literature its functions cite; full references
in the course bibliography, :doc:`/docs/bibliography`.
"""

from course.filters._drivers import (
    FilterResult,
    RiccatiResult,
    extended_kalman_filter,
    kalman_filter,
    riccati,
    riccati_gains,
    steady_state,
)
from course.filters._models import LinearModel, NonlinearModel, Simulation, numerical_jacobian
from course.filters._rls import RLSResult, recursive_least_squares
from course.filters._steps import ekf_predict, ekf_update, kf_predict, kf_update

__all__ = [
    "FilterResult",
    "LinearModel",
    "NonlinearModel",
    "RLSResult",
    "RiccatiResult",
    "Simulation",
    "ekf_predict",
    "ekf_update",
    "extended_kalman_filter",
    "kalman_filter",
    "kf_predict",
    "kf_update",
    "numerical_jacobian",
    "recursive_least_squares",
    "riccati",
    "riccati_gains",
    "steady_state",
]
