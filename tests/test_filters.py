"""Tests of course.filters: models, Kalman filter, EKF, RLS, residual evaluation."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.linalg import LinAlgError
from scipy import stats

from course import diagnosis as dg
from course import filters as kf
from course import nis
from course.results import TestResult

MISS = 1e-4  # probability that a seeded Monte Carlo band misses by chance


def small_model(**kw):
    """A 2-state, 1-output model with every optional part switched on."""
    args = dict(
        F=[[1.0, 0.1], [-0.2, 0.9]],
        H=[[1.0, 0.5]],
        Q=[[0.04]],
        R=[[0.25]],
        G=[[0.0], [1.0]],
        x0_mean=[1.0, -0.5],
        x0_cov=[[0.5, 0.1], [0.1, 0.3]],
        w_mean=[0.2],
        v_mean=[-0.1],
        B=[[0.0], [0.1]],
    )
    args.update(kw)
    return kf.LinearModel(**args)


def dense_conditionals(model, y, u):
    """Brute force: stack x_0..x_{N-1} and y_0..y_{N-1} as one Gaussian vector.

    Returns the conditional means/covariances of x_t given y_0..y_t (filter)
    and given y_0..y_{t-1} (prediction), and the innovation moments, using
    only the joint mean and covariance (no recursion).
    """
    F, H, G, B = model.F, model.H, model.G, model.B
    n, p, N = model.n_states, model.n_outputs, y.shape[0]
    # x = M x0 + L (G w + B u) in stacked form; build mean and covariance directly
    mean = np.zeros(N * n)
    cov = np.zeros((N * n, N * n))
    Phi = [np.linalg.matrix_power(F, k) for k in range(N)]
    drive_mean = [G @ model.w_mean + B @ u[t] for t in range(N)]
    for i in range(N):
        m = Phi[i] @ model.x0_mean
        for s in range(i):
            m = m + Phi[i - 1 - s] @ drive_mean[s]
        mean[i * n : (i + 1) * n] = m
        for j in range(N):
            C = Phi[i] @ model.x0_cov @ Phi[j].T
            for s in range(min(i, j)):
                C = C + Phi[i - 1 - s] @ model.GQG @ Phi[j - 1 - s].T
            cov[i * n : (i + 1) * n, j * n : (j + 1) * n] = C
    Hb = np.kron(np.eye(N), H)
    ymean = Hb @ mean + np.tile(model.v_mean, N)
    ycov = Hb @ cov @ Hb.T + np.kron(np.eye(N), model.R)
    xycov = cov @ Hb.T
    Y = y.ravel()
    out = {k: [] for k in ("x_filt", "P_filt", "x_pred", "P_pred", "eps", "S")}
    for t in range(N):
        rows = slice(t * n, (t + 1) * n)
        for key_x, key_P, m in (("x_pred", "P_pred", t * p), ("x_filt", "P_filt", (t + 1) * p)):
            if m == 0:
                out[key_x].append(mean[rows])
                out[key_P].append(cov[rows, rows])
                continue
            Cyy, Cxy = ycov[:m, :m], xycov[rows, :m]
            out[key_x].append(mean[rows] + Cxy @ np.linalg.solve(Cyy, Y[:m] - ymean[:m]))
            out[key_P].append(cov[rows, rows] - Cxy @ np.linalg.solve(Cyy, Cxy.T))
        out["eps"].append(y[t] - H @ out["x_pred"][t] - model.v_mean)
        out["S"].append(H @ out["P_pred"][t] @ H.T + model.R)
    return {k: np.array(v) for k, v in out.items()}


# ---------------------------------------------------------------------------
# the model
# ---------------------------------------------------------------------------
def test_model_attributes_and_defaults():
    m = kf.LinearModel(F=np.eye(2), H=[[1.0, 0.0]], Q=np.eye(2), R=[[1.0]])
    assert (m.n_states, m.n_outputs, m.n_noise, m.n_inputs) == (2, 1, 2, 0)
    np.testing.assert_array_equal(m.G, np.eye(2))
    np.testing.assert_array_equal(m.x0_mean, [0.0, 0.0])
    np.testing.assert_array_equal(m.x0_cov, np.eye(2))
    np.testing.assert_array_equal(m.w_mean, [0.0, 0.0])
    np.testing.assert_array_equal(m.v_mean, [0.0])
    assert repr(m) == "LinearModel(n_states=2, n_outputs=1, n_noise=2, n_inputs=0)"
    with pytest.raises(ValueError):
        m.F[0, 0] = 5.0  # attributes are read-only


def test_model_does_not_alias_user_input():
    F = np.eye(2)
    m = kf.LinearModel(F=F, H=[[1.0, 0.0]], Q=np.eye(2), R=[[1.0]])
    F[0, 0] = 7.0
    assert m.F[0, 0] == 1.0


@pytest.mark.parametrize(
    "change, error, words",
    [
        (dict(F=[[1.0, 0.0]]), ValueError, "square"),
        (dict(H=[[1.0, 0.0, 0.0]]), ValueError, "H must have shape"),
        (dict(G=None), ValueError, "without G"),
        (dict(G=[[1.0, 0.0], [0.0, 1.0]]), ValueError, "G has 2 columns"),
        (dict(R=[[0.0]]), LinAlgError, "R is not positive definite"),
        (dict(R=[[1.0, 0.5], [0.4, 1.0]]), ValueError, "R must have shape"),
        (dict(Q=[[-1.0]]), LinAlgError, "Q is not positive semi-definite"),
        (dict(x0_cov=[[1.0, 2.0], [2.0, 1.0]]), LinAlgError, "x0_cov is not positive"),
        (dict(x0_cov=[[1.0, 0.2], [0.1, 1.0]]), ValueError, "x0_cov is not symmetric"),
        (dict(x0_mean=[1.0, 2.0, 3.0]), ValueError, "x0_mean must have length 2"),
        (dict(F=[[np.nan, 0.0], [0.0, 1.0]]), ValueError, "NaN"),
        (dict(w_mean=[0.0, 0.0]), ValueError, "w_mean must have length 1"),
        (dict(B=[[1.0]]), ValueError, "B must have shape"),
    ],
)
def test_model_validation_messages(change, error, words):
    with pytest.raises(error, match=words):
        small_model(**change)


def test_zero_process_noise_is_allowed():
    m = kf.LinearModel(F=[[1.0]], H=[[1.0]], Q=[[0.0]], R=[[1.0]])
    np.testing.assert_array_equal(m.GQG, [[0.0]])


def test_simulate_shapes_and_reproducibility():
    m = small_model()
    u = np.ones((30, 1))
    x, y = m.simulate(30, np.random.default_rng(1), u=u)
    assert x.shape == (30, 2) and y.shape == (30, 1)
    xb, yb = m.simulate(30, np.random.default_rng(1), batch=(4, 3), u=u)
    assert xb.shape == (4, 3, 30, 2) and yb.shape == (4, 3, 30, 1)
    _x2, y2 = m.simulate(30, np.random.default_rng(1), u=u)
    np.testing.assert_array_equal(y, y2)
    with pytest.raises(ValueError, match="pass u"):
        m.simulate(30, np.random.default_rng(1))
    with pytest.raises(ValueError, match="positive integer"):
        m.simulate(0, np.random.default_rng(1), u=u[:0])


def test_simulate_first_two_moments():
    """x_1 = F x_0 + G w_0 + B u_0 has mean F m0 + G w_mean + B u and cov F P0 F' + GQG'."""
    m = small_model()
    R = 40000
    x, y = m.simulate(2, np.random.default_rng(2), batch=R, u=np.ones((2, 1)))
    x1 = x[:, 1, :]
    mean = m.F @ m.x0_mean + m.G @ m.w_mean + m.B @ [1.0]
    cov = m.F @ m.x0_cov @ m.F.T + m.GQG
    # each sample mean within 4.5 standard errors
    se = np.sqrt(np.diag(cov) / R)
    assert np.all(np.abs(x1.mean(axis=0) - mean) < 4.5 * se)
    np.testing.assert_allclose(np.cov(x1.T), cov, rtol=0.05, atol=0.01)
    y0 = y[:, 0, 0]
    y_mean = m.H @ m.x0_mean + m.v_mean
    y_var = m.H @ m.x0_cov @ m.H.T + m.R
    assert abs(y0.mean() - y_mean[0]) < 4.5 * np.sqrt(y_var[0, 0] / R)


# ---------------------------------------------------------------------------
# the Kalman filter
# ---------------------------------------------------------------------------
def test_kalman_filter_equals_dense_gaussian_conditioning():
    m = small_model()
    rng = np.random.default_rng(3)
    N = 7
    u = rng.standard_normal((N, 1))
    _, y = m.simulate(N, rng, u=u)
    res = kf.kalman_filter(m, y, u=u)
    ref = dense_conditionals(m, y, u)
    for key in ("x_filt", "P_filt", "x_pred", "P_pred", "eps", "S"):
        np.testing.assert_allclose(getattr(res, key), ref[key], rtol=0, atol=1e-10, err_msg=key)
    # the gain is the one of the update x_filt = x_pred + K eps
    np.testing.assert_allclose(
        res.x_filt, res.x_pred + np.einsum("tij,tj->ti", res.K, res.eps), atol=1e-12
    )
    assert res.innovations is res.eps and res.gain is res.K


def test_kalman_filter_two_outputs_against_dense():
    m = kf.LinearModel(
        F=[[0.9, 0.2], [0.0, 0.7]],
        H=[[1.0, 0.0], [1.0, 1.0]],
        Q=np.diag([0.1, 0.2]),
        R=[[0.3, 0.1], [0.1, 0.2]],
    )
    rng = np.random.default_rng(4)
    _, y = m.simulate(6, rng)
    res = kf.kalman_filter(m, y)
    ref = dense_conditionals(m, y, np.zeros((6, 0)))
    for key in ("x_filt", "P_filt", "eps", "S"):
        np.testing.assert_allclose(getattr(res, key), ref[key], atol=1e-10, err_msg=key)
    # whitening: z = L^{-1} eps with S = L L^T, so |z|^2 = eps' S^-1 eps
    z = res.normalized_innovations()
    nis = np.einsum("ti,ti->t", res.eps, np.linalg.solve(res.S, res.eps[..., None])[..., 0])
    np.testing.assert_allclose(np.sum(z**2, axis=-1), nis, rtol=1e-12)
    np.testing.assert_allclose(res.nis(), nis, rtol=1e-12)


def test_batch_filter_equals_run_by_run():
    m = small_model()
    rng = np.random.default_rng(5)
    u = rng.standard_normal((20, 1))
    _, y = m.simulate(20, rng, batch=5, u=u)
    res = kf.kalman_filter(m, y, u=u)
    assert res.batch_shape == (5,) and res.P_filt.shape == (5, 20, 2, 2)
    for b in range(5):
        one = kf.kalman_filter(m, y[b], u=u)
        np.testing.assert_allclose(res.x_filt[b], one.x_filt, atol=1e-13)
        np.testing.assert_allclose(res.eps[b], one.eps, atol=1e-13)
        np.testing.assert_allclose(res.x_next[b], one.x_next, atol=1e-13)
    np.testing.assert_array_equal(res.S[3], one.S)


def test_riccati_gains_and_steady_state():
    m = small_model()
    rc = kf.riccati(m, 300)
    res = kf.kalman_filter(m, np.zeros((300, 1)), u=np.zeros((300, 1)))
    np.testing.assert_allclose(rc.K, res.K, atol=1e-14)
    np.testing.assert_array_equal(kf.riccati_gains(m, 300), rc.K)
    ss = kf.steady_state(m)
    np.testing.assert_allclose(rc.P_pred[-1], ss.P_pred, atol=1e-10)
    np.testing.assert_allclose(rc.K[-1], ss.K, atol=1e-10)
    # the DARE itself: P = F (P - P H' S^-1 H P) F' + GQG'
    P = ss.P_pred
    rhs = m.F @ (P - P @ m.H.T @ np.linalg.solve(ss.S, m.H @ P)) @ m.F.T + m.GQG
    np.testing.assert_allclose(P, rhs, atol=1e-12)


def test_joseph_form_keeps_covariances_symmetric_psd():
    # a badly scaled model: large prior, tiny measurement noise
    m = kf.LinearModel(
        F=[[1.0, 1.0], [0.0, 1.0]],
        H=[[1.0, 0.0]],
        Q=np.diag([0.0, 1e-8]),
        R=[[1e-10]],
        x0_cov=np.diag([1e8, 1e8]),
    )
    rc = kf.riccati(m, 200)
    for P in (rc.P_pred, rc.P_filt):
        np.testing.assert_array_equal(P, np.swapaxes(P, -1, -2))
        assert np.linalg.eigvalsh(P).min() > -1e-12 * np.abs(P).max()


def test_filter_input_errors():
    m = small_model()
    with pytest.raises(ValueError, match=r"y must have shape \(N, 1\)"):
        kf.kalman_filter(m, np.zeros((10, 2)), u=np.zeros((10, 1)))
    with pytest.raises(ValueError, match="NaN"):
        kf.kalman_filter(m, np.full((10, 1), np.nan), u=np.zeros((10, 1)))
    with pytest.raises(ValueError, match="u must have N = 10"):
        kf.kalman_filter(m, np.zeros((10, 1)), u=np.zeros((9, 1)))
    m0 = kf.LinearModel(F=[[1.0]], H=[[1.0]], Q=[[1.0]], R=[[1.0]])
    with pytest.raises(ValueError, match="no input"):
        kf.kalman_filter(m0, np.zeros(10), u=np.zeros(10))
    with pytest.raises(TypeError, match="LinearModel"):
        kf.kalman_filter("model", np.zeros(10))
    with pytest.raises(LinAlgError, match="x0_cov"):
        kf.kalman_filter(m0, np.zeros(10), x0_cov=[[-1.0]])
    # a 1-D record is accepted for one output
    assert kf.kalman_filter(m0, np.zeros(10)).eps.shape == (10, 1)


def test_innovations_are_white_standard_normal_under_h0():
    """Seeded Monte Carlo: eps_t/sqrt(S_t) i.i.d. N(0, 1) across runs and time."""
    m = small_model(x0_cov=np.eye(2))
    runs, N = 4000, 40
    u = np.sin(np.arange(N))[:, None]
    _, y = m.simulate(N, np.random.default_rng(6), batch=runs, u=u)
    z = kf.kalman_filter(m, y, u=u).normalized_innovations()[..., 0]
    n = z.size
    # mean: sum of n N(0,1) is N(0, n)
    assert abs(z.sum()) < stats.norm.isf(MISS / 2) * np.sqrt(n)
    # variance: sum of squares is chi2(n)
    lo, hi = stats.chi2.interval(1 - MISS, n)
    assert lo < np.sum(z**2) < hi
    # per time step the variance is 1 as well (chi2(runs) for each t, Bonferroni)
    lo_t, hi_t = stats.chi2.interval(1 - MISS / N, runs)
    ss = np.sum(z**2, axis=0)
    assert np.all((lo_t < ss) & (ss < hi_t))
    # whiteness: products at lags 1..3 are uncorrelated, zero-mean, unit-variance terms
    for lag in (1, 2, 3):
        prod = z[:, lag:] * z[:, :-lag]
        assert abs(prod.sum()) < stats.norm.isf(MISS / 6) * np.sqrt(prod.size)
    # Gaussian shape: the fourth moment is 3
    k4 = np.mean(z**4)
    assert abs(k4 - 3.0) < stats.norm.isf(MISS / 2) * np.sqrt(96.0 / n)


def test_innovations_of_a_wrong_model_are_not_white():
    """The same checks detect a mismatch: the filter assumes too little process noise."""
    truth = small_model(x0_cov=np.eye(2))
    wrong = small_model(x0_cov=np.eye(2), Q=[[0.0004]])
    _, y = truth.simulate(40, np.random.default_rng(7), batch=2000, u=np.zeros((40, 1)))
    z = kf.kalman_filter(wrong, y, u=np.zeros((40, 1))).normalized_innovations()[..., 0]
    _lo, hi = stats.chi2.interval(1 - MISS, z.size)
    assert np.sum(z**2) > hi


# ---------------------------------------------------------------------------
# the extended Kalman filter
# ---------------------------------------------------------------------------
def test_ekf_equals_kf_on_linear_model():
    m = small_model()
    rng = np.random.default_rng(8)
    u = rng.standard_normal((25, 3, 1))
    _, y = m.simulate(25, rng, batch=3, u=np.moveaxis(u, 0, 1))
    u = np.moveaxis(u, 0, 1)
    lin = kf.kalman_filter(m, y, u=u)
    ekf = kf.extended_kalman_filter(kf.NonlinearModel.from_linear(m), y, u=u)
    for key in ("x_pred", "P_pred", "eps", "S", "K", "x_filt", "P_filt", "x_next", "P_next"):
        np.testing.assert_allclose(
            getattr(ekf, key), getattr(lin, key), rtol=0, atol=1e-12, err_msg=key
        )
    # a LinearModel passed directly is converted the same way
    direct = kf.extended_kalman_filter(m, y, u=u)
    np.testing.assert_array_equal(direct.x_filt, ekf.x_filt)
    # numerical Jacobians agree to the accuracy of central differences
    num = kf.extended_kalman_filter(
        kf.NonlinearModel.from_linear(m, numerical_jacobians=True), y, u=u
    )
    np.testing.assert_allclose(num.x_filt, lin.x_filt, atol=1e-8)
    np.testing.assert_allclose(num.P_filt, lin.P_filt, atol=1e-8)


def test_numerical_jacobian_matches_analytic_on_a_batch():
    model = dg.beta_drift_model(Ts=0.1)
    rng = np.random.default_rng(9)
    z = rng.normal([1.0, 2.0], [0.5, 3.0], size=(50, 2))
    u = rng.standard_normal((50, 1))
    J_num = kf.numerical_jacobian(lambda x: model.g(x, u[:, None, :]), z)
    np.testing.assert_allclose(J_num, model.jac_g(z, u), rtol=1e-8, atol=1e-9)
    # a genuinely nonlinear function: f(x) = (sin x0 * x1, exp(x1))
    f = lambda x: np.stack([np.sin(x[..., 0]) * x[..., 1], np.exp(x[..., 1])], axis=-1)  # noqa: E731
    J = kf.numerical_jacobian(f, z)
    exact = np.zeros((50, 2, 2))
    exact[:, 0, 0] = np.cos(z[:, 0]) * z[:, 1]
    exact[:, 0, 1] = np.sin(z[:, 0])
    exact[:, 1, 1] = np.exp(z[:, 1])
    np.testing.assert_allclose(J, exact, rtol=1e-8, atol=1e-8)


def test_nonlinear_model_checks_function_shapes():
    with pytest.raises(ValueError, match=r"g\(x0_mean, u\) returned shape \(1,\)"):
        kf.NonlinearModel(
            lambda x, u: x[..., :1], lambda x: x[..., :1], np.eye(2), [[1.0]], [0.0, 0.0]
        )
    with pytest.raises(ValueError, match=r"h\(x0_mean\) returned shape \(2,\)"):
        kf.NonlinearModel(lambda x, u: x, lambda x: x, np.eye(2), [[1.0]], [0.0, 0.0])
    with pytest.raises(ValueError, match="g must be callable"):
        kf.NonlinearModel(np.eye(2), lambda x: x[..., :1], np.eye(2), [[1.0]], [0.0, 0.0])
    with pytest.raises(LinAlgError, match="R is not positive definite"):
        kf.NonlinearModel(lambda x, u: x, lambda x: x[..., :1], np.eye(2), [[-1.0]], [0.0, 0.0])


def test_ekf_numerical_and_analytic_jacobians_agree_on_lecture_model():
    exact = dg.beta_drift_model(Ts=0.1, q_beta=1e-4, q_x=1e-4, r=2.5e-3)
    numeric = kf.NonlinearModel(
        exact.g, exact.h, exact.Q, exact.R, exact.x0_mean, exact.x0_cov, n_inputs=1
    )
    rng = np.random.default_rng(10)
    u = np.where((np.arange(100) // 25) % 2 == 0, 0.5, 1.5)
    _, y = exact.simulate(100, rng, batch=4, u=u)
    a = kf.extended_kalman_filter(exact, y, u)
    b = kf.extended_kalman_filter(numeric, y, u)
    np.testing.assert_allclose(a.x_filt, b.x_filt, atol=1e-7)
    np.testing.assert_allclose(a.eps, b.eps, atol=1e-7)


def test_ekf_store_covariances_false():
    model = dg.beta_drift_model()
    u = np.ones(30)
    _, y = model.simulate(30, np.random.default_rng(11), batch=2, u=u)
    full = kf.extended_kalman_filter(model, y, u)
    lean = kf.extended_kalman_filter(model, y, u, store_covariances=False)
    assert lean.P_pred is None and lean.K is None and lean.P_filt is None
    np.testing.assert_array_equal(lean.eps, full.eps)
    np.testing.assert_array_equal(lean.S, full.S)


def test_step_functions_are_pure():
    m = small_model()
    x, P = m.x0_mean.copy(), m.x0_cov.copy()
    y = np.array([0.3])
    out1 = kf.kf_update(x, P, y, m.H, m.R, m.v_mean)
    out2 = kf.kf_update(x, P, y, m.H, m.R, m.v_mean)
    np.testing.assert_array_equal(x, m.x0_mean)
    np.testing.assert_array_equal(P, m.x0_cov)
    for a, b in zip(out1, out2):
        np.testing.assert_array_equal(a, b)
    xf, Pf = out1[:2]
    xp, Pp = kf.kf_predict(xf, Pf, m.F, m.GQG)
    np.testing.assert_allclose(xp, m.F @ xf)
    np.testing.assert_allclose(Pp, m.F @ Pf @ m.F.T + m.GQG)


def test_ekf_innovations_approximately_standard_normal_under_h0():
    """The EKF linearises, so N(0, S) holds only approximately: a looser band."""
    model = dg.beta_drift_model(Ts=0.1, q_beta=1e-4, q_x=1e-4, r=2.5e-3, x0_mean=(1.0, 0.5))
    u = np.where((np.arange(200) // 40) % 2 == 0, 0.5, 1.5)
    _, y = model.simulate(200, np.random.default_rng(12), batch=2000, u=u)
    z = kf.extended_kalman_filter(model, y, u, store_covariances=False).normalized_innovations()
    z = z[..., 0]
    assert abs(z.mean()) < 0.01
    assert abs(z.var() - 1.0) < 0.02
    assert abs(np.mean(z[:, 1:] * z[:, :-1])) < 0.01


# ---------------------------------------------------------------------------
# residual evaluation
# ---------------------------------------------------------------------------
def test_windowed_sum_against_naive():
    v = np.random.default_rng(13).random((3, 20))
    out = nis.windowed_sum(v, 5)
    assert np.all(np.isnan(out[:, :4]))
    for t in range(4, 20):
        np.testing.assert_allclose(out[:, t], v[:, t - 4 : t + 1].sum(axis=1), rtol=1e-12)
    with pytest.raises(ValueError, match="longer than the record"):
        nis.windowed_sum(v, 21)
    with pytest.raises(ValueError, match="positive integer"):
        nis.windowed_sum(v, 0)


def test_windowed_nis_threshold_and_windowed_test():
    assert nis.windowed_nis_threshold(10, 0.01) == pytest.approx(23.209251, abs=1e-6)
    assert nis.windowed_nis_threshold(5, 0.05, n_outputs=2) == pytest.approx(18.307038, abs=1e-6)
    with pytest.raises(ValueError, match=r"window .*positive integer"):
        nis.windowed_nis_threshold(0, 0.05)
    with pytest.raises(ValueError, match=r"window .*must be an integer"):
        nis.windowed_nis_threshold(2.5, 0.05)
    with pytest.raises(ValueError, match=r"n_outputs .*positive integer"):
        nis.windowed_nis_threshold(10, 0.05, n_outputs=0)
    with pytest.raises(ValueError, match="alpha"):
        nis.windowed_nis_threshold(10, 1.5)
    values = np.arange(1.0, 11.0)  # windowed sum over the last 4: 7+8+9+10 = 34
    res = nis.windowed_chi2_test(values, window=4, alpha=0.05)
    assert isinstance(res, TestResult)
    assert res.statistic == 34.0 and res.dof == 4
    assert res.critical_value == pytest.approx(stats.chi2.isf(0.05, 4))
    assert res.pvalue == pytest.approx(stats.chi2.sf(34.0, 4))
    assert res.reject
    early = nis.windowed_chi2_test(values, window=4, alpha=0.01, t=3)  # 1+2+3+4 < 13.28
    assert early.statistic == 10.0 and not early.reject
    with pytest.raises(ValueError, match="full window"):
        nis.windowed_chi2_test(values, window=4, t=2)
    assert repr(res).startswith("TestResult('windowed NIS test (L = 4, t = 9)', statistic=34")


def test_windowed_test_on_filter_result_and_false_alarm_rate():
    """Under H0 the windowed NIS at a fixed time exceeds chi2_{alpha}(L p) with probability alpha."""
    m = small_model(x0_cov=np.eye(2))
    runs, N, L, alpha = 20000, 30, 8, 0.05
    u = np.zeros((N, 1))
    _, y = m.simulate(N, np.random.default_rng(14), batch=runs, u=u)
    res = kf.kalman_filter(m, y, u=u)
    T = nis.windowed_nis(res, L)
    thr = nis.windowed_nis_threshold(L, alpha)
    # one sample per run: independent Bernoulli(alpha) trials
    alarms = int(np.sum(T[:, -1] > thr))
    lo, hi = stats.binom.interval(1 - MISS, runs, alpha)
    assert lo <= alarms <= hi
    single = nis.windowed_chi2_test(kf.kalman_filter(m, y[0], u=u), L, alpha)
    assert single.statistic == pytest.approx(T[0, -1])
    with pytest.raises(ValueError, match="one record"):
        nis.windowed_chi2_test(res, L, alpha)


def test_alarm_statistics_exact_small_case():
    T = np.array(
        [
            [np.nan, 0.0, 2.0, 0.0, 0.0, 0.0, 3.0, 0.0],  # false alarm at 2, detects at 6
            [np.nan, 0.0, 0.0, 0.0, 3.0, 3.0, 0.0, 0.0],  # detects at fault time 4
            [np.nan, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],  # misses
        ]
    )
    a = nis.alarm_statistics(T, threshold=1.0, fault_time=4)
    assert a.n_checked == 9 and a.false_alarm_rate == pytest.approx(1 / 9)
    assert a.run_false_alarm_probability == pytest.approx(1 / 3)
    assert a.detection_probability == pytest.approx(2 / 3)
    np.testing.assert_array_equal(a.delays, [2.0, 0.0, np.nan])
    assert a.median_delay == 1.0 and a.mean_delay == 1.0
    b = nis.alarm_statistics(T, threshold=1.0)
    assert b.false_alarm_rate == pytest.approx(4 / 21) and b.delays.size == 0
    with pytest.raises(ValueError, match="n_runs, N"):
        nis.alarm_statistics(T[0], 1.0)
    with pytest.raises(ValueError, match="fault_time"):
        nis.alarm_statistics(T, 1.0, fault_time=8)


def test_windowed_sum_skips_only_windows_with_undefined_samples():
    v = np.arange(1.0, 11.0)
    v[[0, 6]] = np.nan  # undefined samples, e.g. the diffuse start of RLS
    out = nis.windowed_sum(v, 3)
    expected = np.full(10, np.nan)
    for t in range(2, 10):
        window = v[t - 2 : t + 1]
        if not np.isnan(window).any():
            expected[t] = window.sum()
    np.testing.assert_array_equal(np.isnan(out), np.isnan(expected))
    np.testing.assert_allclose(out[~np.isnan(out)], expected[~np.isnan(expected)], rtol=1e-12)
    assert out[5] == 4.0 + 5.0 + 6.0 and out[9] == 8.0 + 9.0 + 10.0


def test_step_functions_check_shapes_and_positive_definiteness():
    x, P = np.zeros(2), np.eye(2)
    with pytest.raises(ValueError, match=r"H must be \(\.\.\., p, n\) = \(\.\.\., 1, 2\)"):
        kf.kf_update(x, P, np.zeros(1), np.eye(3)[:1], np.eye(1))
    with pytest.raises(ValueError, match=r"R must be \(\.\.\., 2, 2\)"):
        kf.kf_update(x, P, np.zeros(2), np.eye(2), np.eye(1))
    with pytest.raises(ValueError, match="P_pred must be"):
        kf.kf_update(x, np.eye(3), np.zeros(1), [[1.0, 0.0]], [[1.0]])
    with pytest.raises(ValueError, match="F must be"):
        kf.kf_predict(x, P, np.eye(3), np.eye(2))
    # an indefinite S (here R = -3 I) must not pass silently with two outputs either
    with pytest.raises(LinAlgError, match="not positive definite"):
        kf.kf_update(x, P, np.zeros(2), np.eye(2), -3.0 * np.eye(2))
    with pytest.raises(LinAlgError, match="not positive"):
        kf.kf_update(x, P, np.zeros(1), [[1.0, 0.0]], [[-3.0]])
    model = dg.beta_drift_model()
    with pytest.raises(ValueError, match="P_pred must be"):
        kf.ekf_update(model, np.zeros(2), np.eye(3), np.zeros(1))
    with pytest.raises(ValueError, match="P_filt must be"):
        kf.ekf_predict(model, np.zeros(2), np.eye(3), np.zeros(1))


def test_diffuse_rls_windowed_nis_is_chi2_after_the_start():
    """Recursive residuals after the diffuse start are i.i.d. N(0, 1): windows are chi2(L)."""
    rng = np.random.default_rng(31)
    N, k, M, L, alpha = 25, 3, 20000, 5, 0.05
    Phi = rng.standard_normal((N, k))
    Y = Phi @ [1.0, -2.0, 0.5] + 0.3 * rng.standard_normal((M, N))
    rec = kf.recursive_least_squares(Phi, Y, r=0.09)
    W = nis.windowed_nis(rec, L)
    start = rec.first + 1  # first sample with an innovation
    assert np.all(np.isnan(W[:, : start + L - 1])) and np.all(np.isfinite(W[:, start + L - 1 :]))
    lo, hi = stats.binom.interval(1 - MISS, M, alpha)
    thr = nis.windowed_nis_threshold(L, alpha)
    for t in (start + L - 1, N - 1):
        assert lo <= np.sum(W[:, t] > thr) <= hi
    one = kf.recursive_least_squares(Phi, Y[0], r=0.09)
    res = nis.windowed_chi2_test(one, L, alpha)
    assert res.statistic == pytest.approx(W[0, -1]) and res.dof == L
    with pytest.raises(ValueError, match="undefined"):
        nis.windowed_chi2_test(one, L, alpha, t=start + L - 2)


def test_residual_evaluation_input_errors():
    values = np.ones(10)
    with pytest.raises(ValueError, match=r"n_outputs .*positive integer"):
        nis.windowed_chi2_test(values, 3, n_outputs=0)
    with pytest.raises(ValueError, match="non-negative"):
        nis.windowed_chi2_test(-values, 3)
    with pytest.raises(ValueError, match="one record"):
        nis.windowed_chi2_test(np.ones((2, 10)), 3)
    with pytest.raises(ValueError, match=r"t .* must be an integer"):
        nis.windowed_chi2_test(values, 3, t=4.5)
    with pytest.raises(TypeError, match="FilterResult or an RLSResult"):
        nis.windowed_nis(values, 3)
    with pytest.raises(ValueError, match="threshold must be finite"):
        nis.alarm_statistics(np.ones((2, 3)), np.nan)
    with pytest.raises(ValueError, match="threshold must be a real number"):
        nis.alarm_statistics(np.ones((2, 3)), "high")
    with pytest.raises(ValueError, match=r"fault_time .* must be an integer"):
        nis.alarm_statistics(np.ones((2, 3)), 1.0, fault_time=1.5)


def test_lecture_model_input_errors():
    with pytest.raises(ValueError, match="q_beta must be a real number"):
        dg.beta_drift_model(q_beta="slow")
    with pytest.raises(ValueError, match="r must be positive"):
        dg.beta_drift_model(r=0.0)
    with pytest.raises(ValueError, match=r"Ts .* must be positive"):
        dg.beta_drift_model(Ts=0.0)
    with pytest.raises(ValueError, match="q_x must be non-negative"):
        dg.simulate_beta_system(np.ones(5), np.ones(5), np.random.default_rng(0), q_x=-1.0)
    # a g written for one state (x[1]) instead of a batch (x[..., 1]) is reported clearly
    with pytest.raises(ValueError, match=r"g\(x0_mean, u\) raised IndexError.*x\[\.\.\., i\]"):
        kf.NonlinearModel(
            lambda x, u: np.array([x[0], x[5]]),
            lambda x: x[..., :1],
            np.eye(2),
            [[1.0]],
            [0.0, 0.0],
        )


def test_empirical_threshold():
    x = np.arange(1, 1001, dtype=float)
    assert nis.empirical_threshold(x, 0.1) == pytest.approx(np.quantile(x, 0.9))
    with pytest.raises(ValueError, match="no finite"):
        nis.empirical_threshold([np.nan], 0.1)


# ---------------------------------------------------------------------------
# the lecture's example
# ---------------------------------------------------------------------------
def lecture_signals(N):
    t = np.arange(N)
    u = np.where((t // 50) % 2 == 0, 0.5, 1.5)
    beta = 1.0 + 0.4 * np.sin(2 * np.pi * t / 400)
    return u, beta


def test_drifting_beta_false_alarms_only_without_random_walk():
    """The lecture's point: a filter that takes beta constant alarms on a drift."""
    N, L, alpha, runs = 250, 10, 0.001, 200
    u, beta = lecture_signals(N)
    _, y = dg.simulate_beta_system(
        beta, u, np.random.default_rng(15), Ts=0.1, q_x=1e-4, r=2.5e-3, x0=0.5, batch=runs
    )
    thr = nis.windowed_nis_threshold(L, alpha)
    rates = {}
    for q_beta in (1e-4, 0.0):
        model = dg.beta_drift_model(Ts=0.1, q_beta=q_beta, q_x=1e-4, r=2.5e-3, x0_mean=(1.0, 0.5))
        res = kf.extended_kalman_filter(model, y, u, store_covariances=False)
        rates[q_beta] = nis.alarm_statistics(nis.windowed_nis(res, L), thr).false_alarm_rate
    assert rates[1e-4] < 0.01
    assert rates[0.0] > 0.1


def test_sensor_fault_is_detected():
    N, L, alpha, runs, tf = 200, 10, 0.001, 500, 120
    u, beta = lecture_signals(N)
    fault = np.where(np.arange(N) >= tf, 0.2, 0.0)
    _, y = dg.simulate_beta_system(
        beta,
        u,
        np.random.default_rng(16),
        Ts=0.1,
        q_x=1e-4,
        r=2.5e-3,
        x0=0.5,
        fault=fault,
        batch=runs,
    )
    model = dg.beta_drift_model(Ts=0.1, q_beta=1e-4, q_x=1e-4, r=2.5e-3, x0_mean=(1.0, 0.5))
    res = kf.extended_kalman_filter(model, y, u, store_covariances=False)
    a = nis.alarm_statistics(
        nis.windowed_nis(res, L), nis.windowed_nis_threshold(L, alpha), fault_time=tf
    )
    assert a.detection_probability > 0.99
    assert a.median_delay <= 3


def test_simulate_beta_system_noise_free_recursion():
    u, beta = lecture_signals(30)
    st, y = dg.simulate_beta_system(
        beta, u, np.random.default_rng(0), Ts=0.1, q_x=0.0, r=0.0, x0=0.3, fault=np.full(30, 0.1)
    )
    x = 0.3
    for t in range(30):
        assert st[t, 1] == pytest.approx(x, abs=1e-14)
        assert y[t, 0] == pytest.approx(x + 0.1, abs=1e-14)
        x = x - 0.1 * beta[t] * x + 0.1 * u[t]
    np.testing.assert_array_equal(st[:, 0], beta)


def test_observer_tracks_state_and_parameter_without_noise():
    N, Ts, beta_true = 3000, 0.1, 1.3
    u = np.where((np.arange(N) // 50) % 2 == 0, 0.5, 1.5)
    _, y = dg.simulate_beta_system(
        np.full(N, beta_true), u, np.random.default_rng(0), Ts=Ts, q_x=0.0, r=0.0, x0=0.5
    )
    obs = dg.observer_residuals(
        y,
        u,
        f=lambda x, u, th: -th * x + u,
        h=lambda x: x,
        x0=[0.0],
        theta0=[0.8],
        K1=[[2.0]],
        K2=lambda x, th, u: -5.0 * x[..., None],
        Ts=Ts,
    )
    assert obs.r.shape == (N, 1) and obs.theta_hat.shape == (N, 1)
    assert abs(obs.theta_hat[-1, 0] - beta_true) < 1e-3
    assert np.max(np.abs(obs.r[-200:])) < 1e-3
    T = obs.windowed_energy(20, Ts=Ts)
    assert np.isnan(T[18]) and T[-1] < 1e-6


# ---------------------------------------------------------------------------
# recursive least squares
# ---------------------------------------------------------------------------
def regression_data(seed=17, N=60, k=3):
    rng = np.random.default_rng(seed)
    Phi = rng.standard_normal((N, k))
    Phi[:5, 2] = 0.0  # the third parameter is not excited at first
    y = Phi @ np.arange(1.0, k + 1) + 0.1 * rng.standard_normal(N)
    return Phi, y


def test_rls_equals_batch_least_squares():
    Phi, y = regression_data()
    r = 0.01
    res = kf.recursive_least_squares(Phi, y, r=r)
    assert res.first == 5  # rows 0..5 are the first with full column rank
    assert np.all(np.isnan(res.theta[:5])) and np.all(np.isnan(res.eps[:6]))
    for t in range(res.first, Phi.shape[0]):
        ls = np.linalg.lstsq(Phi[: t + 1], y[: t + 1], rcond=None)[0]
        np.testing.assert_allclose(res.theta[t], ls, rtol=0, atol=1e-10)


def test_rls_equals_course_lsq_fit():
    from course import lsq

    Phi, y = regression_data()
    r = 0.01
    res = kf.recursive_least_squares(Phi, y, r=r)
    fit = lsq.fit(Phi, y, r * np.eye(Phi.shape[0]))
    np.testing.assert_allclose(res.theta[-1], fit.x_hat, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.P[-1], fit.Qxx, rtol=1e-9, atol=1e-14)


def test_rls_batch_and_prior():
    Phi, y = regression_data()
    Y = np.stack([y, 2 * y])
    both = kf.recursive_least_squares(Phi, Y, r=0.01)
    np.testing.assert_allclose(both.theta[1, -1], 2 * both.theta[0, -1], rtol=1e-12)
    # with a prior: the regularised least-squares solution
    P0 = np.diag([2.0, 1.0, 0.5])
    th0 = np.array([0.5, 0.0, 1.0])
    res = kf.recursive_least_squares(Phi, y, r=0.01, theta0=th0, P0=P0)
    W = np.diag(1 / np.sqrt(np.diag(P0)))
    A = np.vstack([Phi / 0.1, W])
    b = np.concatenate([y / 0.1, W @ th0])
    np.testing.assert_allclose(res.theta[-1], np.linalg.lstsq(A, b, rcond=None)[0], atol=1e-10)
    assert res.first == 0 and np.all(np.isfinite(res.eps))


def test_rls_random_walk_equals_kalman_filter():
    """With a constant regressor RLS is the Kalman filter of a LinearModel (F = I, H = phi)."""
    rng = np.random.default_rng(18)
    phi = np.array([1.0, 0.5])
    Phi = np.tile(phi, (40, 1))
    y = rng.standard_normal(40)
    P0 = np.eye(2)
    res = kf.recursive_least_squares(Phi, y, r=0.3, q=0.01, theta0=[0.0, 0.0], P0=P0)
    m = kf.LinearModel(F=np.eye(2), H=[phi], Q=0.01 * np.eye(2), R=[[0.3]], x0_cov=P0)
    ref = kf.kalman_filter(m, y)
    np.testing.assert_allclose(res.theta, ref.x_filt, atol=1e-12)
    np.testing.assert_allclose(res.eps, ref.eps[:, 0], atol=1e-12)


def test_rls_diffuse_start_keeps_the_random_walk_noise():
    """Started without P0, RLS with q > 0 is the Kalman filter of the random walk from the
    least-squares fit of the first k rows (P = r (Phi_k^T Phi_k)^-1): a dense step-by-step
    reference. Dropping q after the diffuse start leaves P two orders of magnitude too small."""
    rng = np.random.default_rng(40)
    N, k, r, q = 60, 2, 0.05, 0.004
    Phi = np.column_stack([np.ones(N), np.sin(0.2 * np.arange(N))])
    theta_true = np.cumsum(np.sqrt(q) * rng.standard_normal((N, k)), axis=0) + [1.0, -0.5]
    y = np.sum(Phi * theta_true, axis=1) + np.sqrt(r) * rng.standard_normal(N)
    res = kf.recursive_least_squares(Phi, y, r=r, q=q)

    x = np.linalg.lstsq(Phi[:k], y[:k], rcond=None)[0]
    P = r * np.linalg.solve(Phi[:k].T @ Phi[:k], np.eye(k))
    assert res.first == k - 1
    np.testing.assert_allclose(res.theta[k - 1], x, atol=1e-10)
    for t in range(k, N):
        P = P + q * np.eye(k)
        phi = Phi[t]
        S = phi @ P @ phi + r
        gain = P @ phi / S
        x = x + gain * (y[t] - phi @ x)
        P = P - np.outer(gain, phi @ P)
        np.testing.assert_allclose(res.theta[t], x, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(res.P[t], P, rtol=1e-9, atol=1e-14)


def regressors_ch2():
    """Three regressors of chapter 2's lecture example (N = 30), as in tests/test_diagnosis.py."""
    rng = np.random.default_rng(20240501)
    t = np.arange(30)
    return np.column_stack([np.sin(0.3 * t) + 1.5, np.cos(0.17 * t), rng.standard_normal(30)])


def test_rls_with_prior_equals_regularised_batch_estimate():
    signals = regressors_ch2()
    rng = np.random.default_rng(13)
    sigma2 = 0.04
    y = signals @ [1.2, 0.8, 1.0] + np.sqrt(sigma2) * rng.standard_normal(signals.shape[0])
    theta0, P0 = np.zeros(3), 10.0 * np.eye(3)
    rec = kf.recursive_least_squares(signals, y, r=sigma2, theta0=theta0, P0=P0)
    # batch: minimise ||y - Phi th||^2 / s2 + (th - th0)^T P0^{-1} (th - th0)
    A = signals.T @ signals / sigma2 + np.eye(3) / 10.0
    b = signals.T @ y / sigma2 + theta0 / 10.0
    np.testing.assert_allclose(rec.theta[-1], np.linalg.solve(A, b), rtol=1e-9)
    np.testing.assert_allclose(rec.P[-1], np.linalg.solve(A, np.eye(3)), rtol=1e-8, atol=1e-14)
    # the innovation equals y_t minus the prediction from the estimate before it
    pred = np.concatenate([[signals[0] @ theta0], np.sum(signals[1:] * rec.theta[:-1], axis=1)])
    np.testing.assert_allclose(rec.innovations, y - pred, atol=1e-12)
    assert rec.innovations is rec.eps


def test_rls_innovations_are_white_under_H0():
    """Chapter 2's recursive test quantity: whole-record and windowed sums are chi2 under H0."""
    signals = regressors_ch2()
    rng = np.random.default_rng(14)
    sigma2, M, alpha = 0.09, 5000, 0.05
    N = signals.shape[0]
    theta0, P0 = np.ones(3), 0.25 * np.eye(3)
    theta = theta0[:, None] + 0.5 * rng.standard_normal((3, M))  # draw theta from the prior
    Y = signals @ theta + np.sqrt(sigma2) * rng.standard_normal((N, M))  # records as columns
    rec = kf.recursive_least_squares(signals, Y.T, r=sigma2, theta0=theta0, P0=P0)
    assert rec.theta.shape == (M, N, 3) and rec.innovations.shape == (M, N)
    z = rec.normalized_innovations()
    np.testing.assert_allclose(rec.nis(), z**2, rtol=1e-15)
    lo, hi = stats.binom.interval(1 - MISS, M, alpha)
    T = np.sum(z**2, axis=-1)
    assert lo <= np.sum(stats.chi2.isf(alpha, N) < T) <= hi
    W = nis.windowed_nis(rec, 10)
    assert W.shape == (M, N) and np.all(np.isnan(W[:, :9]))
    np.testing.assert_allclose(W[:, 9], np.sum(z[:, :10] ** 2, axis=-1))
    assert lo <= np.sum(W[:, -1] > stats.chi2.isf(alpha, 10)) <= hi


def test_drifting_parameter_is_tracked_by_the_random_walk_filter():
    rng = np.random.default_rng(15)
    N = 400
    phi = np.ones((N, 1))
    theta_true = np.where(np.arange(N) < 200, 1.0, 2.0)
    y = theta_true + 0.1 * rng.standard_normal(N)
    rls = kf.recursive_least_squares(phi, y, r=0.01, theta0=[1.0], P0=[[1.0]])
    walk = kf.recursive_least_squares(phi, y, r=0.01, q=1e-3, theta0=[1.0], P0=[[1.0]])
    assert abs(rls.theta[-1, 0] - 1.5) < 0.05  # RLS averages the whole record
    assert abs(walk.theta[-1, 0] - 2.0) < 0.1  # the random walk forgets


def test_rls_errors():
    Phi, y = regression_data()
    with pytest.raises(LinAlgError, match="never reaches full column rank"):
        kf.recursive_least_squares(np.ones((10, 2)), np.ones(10))
    with pytest.raises(ValueError, match="rows of Phi"):
        kf.recursive_least_squares(Phi, y[:-1])
    with pytest.raises(ValueError, match=r"r .*must be positive"):
        kf.recursive_least_squares(Phi, y, r=0.0)
    with pytest.raises(ValueError, match="theta0 without P0"):
        kf.recursive_least_squares(Phi, y, theta0=[0, 0, 0])


# ---------------------------------------------------------------------------
# figures (smoke test: every function draws and returns its axes)
# ---------------------------------------------------------------------------
def test_plot_functions_return_axes():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from course.plotting import filters as fplot

    t = np.arange(50)
    x = np.sin(t / 5.0)
    T = np.abs(np.random.default_rng(0).standard_normal((20, 50))) * 10
    T[:, :4] = np.nan
    axes = [
        fplot.plot_signals(t, x, np.sign(x), fault_time=30),
        fplot.plot_estimate(t, x, 0.1 * np.ones(50), truth=x, fault_time=30),
        fplot.plot_residual(t, x, std=np.ones(50), fault_time=30),
        fplot.plot_test_statistic(t, T[0], 15.0, fault_time=30, log=True),
        fplot.plot_alarm_rate(t, T, 15.0, alpha=0.01, fault_time=30),
        fplot.plot_delay_histogram(np.array([0.0, 2.0, np.nan, 5.0])),
        fplot.plot_normalized_histogram(np.random.default_rng(1).standard_normal(500)),
    ]
    for ax in axes:
        assert ax.has_data()
    assert axes[5].get_title() == "3 detected, 1 missed"
    plt.close("all")


def test_ekf_batch_equals_its_parts_filtered_apart():
    # Notebook 04 filters several Monte Carlo sweeps as one batch: that is honest only
    # if each run's numbers do not depend on the batch it is filtered in (to the bit).
    model = dg.beta_drift_model(Ts=0.1, q_beta=1e-4, q_x=1e-4, r=2.5e-3)
    u = np.where((np.arange(60) // 20) % 2 == 0, 0.5, 1.5)
    _, y = model.simulate(60, np.random.default_rng(12), batch=5, u=u)
    together = kf.extended_kalman_filter(model, y, u)
    for part in (slice(0, 2), slice(2, 5)):
        apart = kf.extended_kalman_filter(model, y[part], u)
        for name in ("eps", "S", "x_filt", "P_filt", "K"):
            np.testing.assert_array_equal(getattr(together, name)[part], getattr(apart, name))


def test_stacked_products_match_matmul():
    # the fast stacked products (entry by entry, stored entry-major) against numpy's matmul
    from course._stacked import _mm, _mv

    rng = np.random.default_rng(13)
    A, B, x = (
        rng.standard_normal((7, 2, 3)),
        rng.standard_normal((7, 3, 2)),
        rng.standard_normal((7, 3)),
    )
    np.testing.assert_allclose(_mm(A, B), A @ B, rtol=1e-14)
    np.testing.assert_allclose(_mm(A, B[0]), A @ B[0], rtol=1e-14)
    np.testing.assert_allclose(_mv(A, x), (A @ x[..., None])[..., 0], rtol=1e-14)
    assert _mm(A, B).shape == (7, 2, 2) and _mv(A, x).shape == (7, 2)


# ---------------------------------------------------------------------------
# extreme scales: the gain and the estimate are representable even where the sum of S is
# not; an S beyond double precision is refused (it would give a NIS of 0)
# ---------------------------------------------------------------------------
def test_kf_update_with_a_huge_output_matrix_still_updates():
    # S_ii = h^2 + 1 ~ 1.4e308 are doubles, their sum is not: each output is scaled
    h = 1.2e154
    two = kf.kf_update(np.zeros(2), np.eye(2), [1.0, 2.0], np.diag([h, h]), np.eye(2))
    assert np.isfinite(two.S).all()
    np.testing.assert_allclose(np.diag(two.S), [h * h, h * h], rtol=1e-12)
    np.testing.assert_allclose(two.x_filt * h, [1.0, 2.0], rtol=1e-12)
    np.testing.assert_allclose(two.K * h, np.eye(2), rtol=1e-12)
    np.testing.assert_allclose(two.P_filt, 0.0, atol=1e-300)


def test_kf_update_refuses_an_innovation_covariance_beyond_double_precision():
    # S = H P H^T + R ~ 1.25e320: the gain is representable but S (behind every NIS)
    # is not; it was returned as inf, which makes the NIS 0
    h = 1e160
    with pytest.raises(ValueError, match=r"S = H P_pred H\^T \+ R exceeds.*rescale"):
        kf.kf_update(np.zeros(2), np.eye(2), [1.0], [[h, 0.5 * h]], [[1.0]])


def test_recursive_least_squares_is_scale_equivariant_at_extreme_scales():
    # Phi * 2^532, y * 2^498, r * 2^996 is the same problem as the ordinary one (theta and P
    # scale by powers of two); |phi|^2 P0 ~ 1e330 used to overflow S, and theta stayed at theta0.
    rng = np.random.default_rng(0)
    Phi = np.column_stack([np.ones(30), np.linspace(0.0, 1.0, 30)])
    y = Phi @ [1.0, -2.0] + rng.standard_normal(30)
    theta0, P0 = np.array([0.5, 0.5]), 1e10 * np.eye(2)
    ref = kf.recursive_least_squares(Phi, y, r=1.0, theta0=theta0, P0=P0)
    b, a = 2.0**532, 2.0**498
    big = kf.recursive_least_squares(
        Phi * b, y * a, r=a * a, theta0=theta0 * (a / b), P0=P0 * (a / b) ** 2
    )
    np.testing.assert_allclose(big.theta * (b / a), ref.theta, rtol=1e-12)
    np.testing.assert_allclose(big.P * (b / a) ** 2, ref.P, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(big.eps / a, ref.eps, rtol=1e-12)
    # the first S, a^2 (1e10 + 1) ~ 6.7e309, is beyond double precision and says so (inf);
    # the NIS, scale-free, is representable and right (it was eps^2 / inf = 0)
    assert big.S[0] == np.inf and np.isfinite(big.S[1:]).all()
    np.testing.assert_allclose(big.nis(), ref.nis(), rtol=1e-12)
    np.testing.assert_allclose(
        big.normalized_innovations(), ref.normalized_innovations(), rtol=1e-12
    )
    # the diffuse start: regressors ~1e300 put P ~ r / |phi|^2 below double precision
    diffuse = kf.recursive_least_squares(Phi * 2.0**1000, y, r=1.0)
    plain = kf.recursive_least_squares(Phi, y, r=1.0)
    np.testing.assert_allclose(diffuse.theta[1:] * 2.0**1000, plain.theta[1:], rtol=1e-12)


def _huge_output_model():
    # |H| ~ 1e160: H P H^T + R ~ 1e320 is beyond double precision at every step
    return kf.LinearModel(F=np.eye(2), H=[[1e160, 5e159]], Q=0.01 * np.eye(2), R=[[1.0]])


def test_filter_drivers_refuse_an_innovation_covariance_beyond_double_precision():
    # the drivers returned S = inf and so a NIS of 0 at every step, without a word
    model = _huge_output_model()
    _, y = model.simulate(5, np.random.default_rng(3))
    remedy = r"S_t = H.* exceeds the range of doubles.*dividing y.* by c and R by c\^2"
    with pytest.raises(ValueError, match=remedy + r".*"):
        kf.kalman_filter(model, y)
    with pytest.raises(ValueError, match=r"at step t = 0"):
        kf.extended_kalman_filter(model, y)
    with pytest.raises(ValueError, match=r"S_t = H P\(t\|t-1\) H\^T \+ R exceeds.*model's H"):
        kf.riccati(model, 5)
    # the gains alone are representable and right: K = P H^T S^-1 with H scaled by 2^-531
    gains = kf.riccati_gains(model, 5)
    plain = kf.LinearModel(
        F=np.eye(2), H=[[1e160 / 2.0**531, 5e159 / 2.0**531]], Q=0.01 * np.eye(2), R=[[2.0**-1062]]
    )
    np.testing.assert_allclose(gains / 2.0**-531, kf.riccati_gains(plain, 5), rtol=1e-12)
