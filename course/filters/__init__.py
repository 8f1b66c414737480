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
    :class:`LinearModel`, :class:`NonlinearModel` (with ``simulate``),
    :func:`numerical_jacobian`.
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
observer live in :mod:`course.diagnosis`.  Their names are still importable
from here.

Gain convention: ``K_t = P(t|t-1) H^T S_t^{-1}`` is the *measurement-update*
gain, ``xhat(t|t) = xhat(t|t-1) + K_t eps_t``; the one-step predictor gain is
``F K_t``.
"""

from importlib import import_module

from course.filters._drivers import (
    FilterResult,
    RiccatiResult,
    extended_kalman_filter,
    kalman_filter,
    riccati,
    riccati_gains,
    steady_state,
)
from course.filters._models import LinearModel, NonlinearModel, numerical_jacobian
from course.filters._rls import RLSResult, recursive_least_squares
from course.filters._steps import ekf_predict, ekf_update, kf_predict, kf_update
from course.nis._alarms import AlarmStatistics, alarm_statistics, empirical_threshold
from course.nis._windowed import (
    windowed_chi2_test,
    windowed_nis,
    windowed_nis_threshold,
    windowed_sum,
)

# Names whose home is course.diagnosis (which imports this package): resolved on
# first access so that importing either package first works.
_FROM_DIAGNOSIS = {
    "ObserverResult": "course.diagnosis._observer",
    "observer_residuals": "course.diagnosis._observer",
    "beta_drift_model": "course.diagnosis._beta_example",
    "simulate_beta_system": "course.diagnosis._beta_example",
}

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


def __getattr__(name):
    if name in _FROM_DIAGNOSIS:
        value = getattr(import_module(_FROM_DIAGNOSIS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'course.filters' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
