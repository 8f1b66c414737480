"""Bad input to every public callable of course.filters (see tests/bad_input.py).

The NIS chain that ``course.filters`` re-exports (``windowed_nis``, ...) is
tested with ``course.nis``, the lecture's beta example and the observer with
``course.diagnosis``: each callable once, in its home.
"""

import numpy as np
from bad_input import (
    Arg,
    array,
    case,
    count,
    covariance,
    flag,
    function,
    generator,
    matrix,
    module_tests,
    obj,
    positive,
    scale,
    vector,
)

from course import filters as kf

F = np.array([[1.0, 0.1], [-0.2, 0.9]])
H = np.array([[1.0, 0.5]])
Q = np.array([[0.04]])
R = np.array([[0.25]])
G = np.array([[0.0], [1.0]])
X0 = np.array([1.0, -0.5])
P0 = np.array([[0.5, 0.1], [0.1, 0.3]])
B = np.array([[0.0], [0.1]])
MODEL = kf.LinearModel(F, H, Q, R, G=G, x0_mean=X0, x0_cov=P0, B=B)
PLAIN = kf.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.1]], R=[[1.0]])
N = 6
U = np.linspace(0.0, 1.0, N)[:, None]
_, Y = MODEL.simulate(N, np.random.default_rng(0), u=U)
_, Y_PLAIN = PLAIN.simulate(N, np.random.default_rng(1))


def g(x, u):
    return np.stack([x[..., 0] + 0.1 * x[..., 1], 0.9 * x[..., 1] - 0.1 * np.sin(x[..., 0])], -1)


def h(x):
    return x[..., :1] ** 2


def jac_g(x, u):
    one = np.ones_like(x[..., 0])
    return np.stack(
        [np.stack([one, 0.1 * one], -1), np.stack([-0.1 * np.cos(x[..., 0]), 0.9 * one], -1)],
        -2,
    )


NONLINEAR = kf.NonlinearModel(g, h, Q=0.01 * np.eye(2), R=R, x0_mean=X0, x0_cov=P0)
_, Y_NL = NONLINEAR.simulate(N, np.random.default_rng(2))
PHI = np.column_stack([np.ones(8), np.linspace(0.0, 1.0, 8)])
Y_RLS = PHI @ [1.0, -2.0] + 0.1 * np.random.default_rng(3).standard_normal(8)
KF_RESULT = kf.kalman_filter(PLAIN, Y_PLAIN)
RLS_RESULT = kf.recursive_least_squares(PHI, Y_RLS, r=0.01)


def model_arg(value, **kw):
    return obj(value, **kw).but(array=np.eye(2))


def signal(value, **kw):
    """A signal ``(N, d)`` or ``(*batch, N, d)`` (``(N,)`` is valid for one channel)."""
    return array(value, min_ndim=2, **kw).but(drop=("1-D",))


def state(value=X0):
    return array(value, min_ndim=1)


def state_cov(value=P0):
    """A covariance of a step function: ``(n, n)`` or a stack ``(..., n, n)``, PSD."""
    return covariance(value, psd=True).but(drop=("3-D",))


TABLE = {
    "LinearModel": case(
        kf.LinearModel,
        F=matrix(F),
        H=matrix(H),
        Q=covariance(Q, psd=True),
        R=covariance(R),
        G=matrix(G, none_ok=True),
        x0_mean=vector(X0, none_ok=True),
        x0_cov=covariance(P0, psd=True, none_ok=True),
        w_mean=vector([0.2], none_ok=True),
        v_mean=vector([-0.1], none_ok=True),
        B=matrix(B, none_ok=True, shaped=False),  # any number of inputs
    ),
    "LinearModel.simulate": case(
        MODEL.simulate,
        N=count(N),
        rng=generator(),
        batch=count(3, none_ok=True).but(drop=("sequence",), shape_with_fraction=(2, 1.5)),
        u=signal(U),
    ),
    "NonlinearModel": case(
        kf.NonlinearModel,
        g=function(g),
        h=function(h),
        Q=covariance(0.01 * np.eye(2), psd=True),
        R=covariance(R),
        x0_mean=vector(X0),
        x0_cov=covariance(P0, psd=True, none_ok=True),
        G=matrix(np.eye(2), none_ok=True),
        jac_g=function(jac_g, none_ok=True),
        jac_h=function(None, none_ok=True),
        w_mean=vector([0.0, 0.1], none_ok=True),
        v_mean=vector([0.1], none_ok=True),
        n_inputs=count(0, minimum=0),
    ),
    "NonlinearModel.from_linear": case(
        kf.NonlinearModel.from_linear, model=model_arg(MODEL), numerical_jacobians=flag(False)
    ),
    "NonlinearModel.jacobian_g": case(NONLINEAR.jacobian_g, x=state(), u=Arg(None)),
    "NonlinearModel.jacobian_h": case(NONLINEAR.jacobian_h, x=state()),
    "NonlinearModel.simulate": case(
        NONLINEAR.simulate,
        N=count(N),
        rng=generator(),
        batch=count(2, none_ok=True).but(drop=("sequence",)),
        u=Arg(None, {"given without inputs": U}),
    ),
    "FilterResult.normalized_innovations": case(KF_RESULT.normalized_innovations),
    "FilterResult.nis": case(KF_RESULT.nis),
    "RLSResult.normalized_innovations": case(RLS_RESULT.normalized_innovations, nan_ok=True),
    "RLSResult.nis": case(RLS_RESULT.nis, nan_ok=True),
    "kf_update": case(
        kf.kf_update,
        x_pred=state(),
        P_pred=state_cov(),
        y=state([0.3]),
        H=array(H, min_ndim=2),
        R=covariance(R).but(drop=("3-D",)),
        v_mean=array([0.1], min_ndim=1, none_ok=True),
    ),
    "kf_predict": case(
        kf.kf_predict,
        x_filt=state(),
        P_filt=state_cov(),
        F=array(F, min_ndim=2),
        GQG=state_cov(np.diag([0.01, 0.04])),
        offset=array([0.1, 0.0], min_ndim=1, none_ok=True),
    ),
    "ekf_update": case(
        kf.ekf_update,
        model=model_arg(NONLINEAR),
        x_pred=state().but(shorter=X0[:1]),
        P_pred=state_cov(),
        y=state([0.3]),
    ),
    "ekf_predict": case(
        kf.ekf_predict,
        model=model_arg(NONLINEAR),
        x_filt=state().but(shorter=X0[:1]),  # g indexes x[..., 1]: an IndexError inside
        P_filt=state_cov(),
        u=Arg(None, {"given without inputs": [1.0]}),
    ),
    "extended_kalman_filter": case(
        kf.extended_kalman_filter,
        model=model_arg(NONLINEAR),
        y=signal(Y_NL),
        u=Arg(None, {"given without inputs": U}),
        x0_mean=vector(X0, none_ok=True),
        x0_cov=covariance(P0, psd=True, none_ok=True),
        store_covariances=flag(True),
    ),
    "kalman_filter": case(
        kf.kalman_filter,
        model=model_arg(MODEL).but(nonlinear_model=NONLINEAR),
        y=signal(Y),
        u=signal(U),
        x0_mean=vector(X0, none_ok=True),
        x0_cov=covariance(P0, psd=True, none_ok=True),
    ),
    "numerical_jacobian": case(
        kf.numerical_jacobian,
        f=function(h),
        x=array(X0, min_ndim=1, shaped=False),  # h takes any number of states
        step=positive(1e-5, none_ok=True),
    ),
    "recursive_least_squares": case(
        kf.recursive_least_squares,
        nan_ok=True,  # no estimate before the regressors reach full rank (the diffuse start)
        Phi=matrix(PHI),
        y=array(Y_RLS, min_ndim=1),
        r=scale(0.01),
        q=Arg(None, {"negative": -1.0, "NaN": np.nan, "text": "q"}),
        theta0=Arg(None, {"without P0": [0.0, 0.0]}),
        P0=Arg(None, {"indefinite": -np.eye(2), "NaN": np.full((2, 2), np.nan)}),
    ),
    "riccati": case(
        kf.riccati,
        model=model_arg(MODEL),
        N=count(5),
        x0_cov=covariance(P0, psd=True, none_ok=True),
    ),
    "riccati_gains": case(
        kf.riccati_gains,
        model=model_arg(MODEL),
        N=count(5),
        x0_cov=covariance(P0, psd=True, none_ok=True),
    ),
    "steady_state": case(kf.steady_state, model=model_arg(MODEL)),
}

EXEMPT = {
    "FilterResult": "a result the library returns",
    "RLSResult": "a result the library returns",
    "RiccatiResult": "a result the library returns",
    "Simulation": "a result the library returns",
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests("course.filters", TABLE, EXEMPT)
