"""Every API change of release 0.2 keeps the old call working, with a DeprecationWarning.

Each test calls the old form under ``pytest.warns`` and checks that it gives
what the new form gives (CHANGELOG.md lists the same changes).
"""

import numpy as np
import pytest

from course import diagnosis as dg
from course import filters as kf
from course import mismatched, nis
from course.quadform import QuadraticForm

U = np.column_stack([np.ones(12), np.linspace(0.0, 1.0, 12), np.cos(np.arange(12.0))])
NOMINAL = np.ones(3)


def records(M=5, seed=0):
    return dg.simulate_regression_records(U, NOMINAL, sigma=0.2, n_records=M, rng=seed)


def test_least_squares_residual_old_argument_order():
    y = records(1)[0]
    new = dg.least_squares_residual(U, y)
    with pytest.warns(DeprecationWarning, match="least_squares_residual\\(Phi, y\\)"):
        old = dg.least_squares_residual(y, U)
    assert old.statistic == new.statistic and old.rank == new.rank


def test_records_as_columns_still_work_and_answer_in_their_layout():
    Y = records()
    new = dg.prediction_error(Y, U, NOMINAL, [0])
    with pytest.warns(DeprecationWarning, match="records as columns"):
        old = dg.prediction_error(Y.T, U, NOMINAL, [0])
    np.testing.assert_allclose(old.statistic, new.statistic, rtol=1e-12)
    np.testing.assert_allclose(old.residual, new.residual.T, rtol=1e-12)
    np.testing.assert_allclose(old.theta, new.theta.T, rtol=1e-12)
    with pytest.warns(DeprecationWarning, match="records as columns"):
        old_est = dg.estimate_parameters(Y.T, U, NOMINAL, [0, 1], sigma=0.2)
    new_est = dg.estimate_parameters(Y, U, NOMINAL, [0, 1], sigma=0.2)
    np.testing.assert_allclose(old_est.theta, new_est.theta.T, rtol=1e-12)
    with pytest.warns(DeprecationWarning, match="records as columns"):
        old_T = dg.linear_test_statistics(Y.T, U, NOMINAL, [(0,), (1,)])
    np.testing.assert_allclose(old_T, dg.linear_test_statistics(Y, U, NOMINAL, [(0,), (1,)]))


def test_parameter_vectors_as_columns_still_work():
    thetas = np.array([[1.0, 1.0, 1.0], [1.0, 1.5, 1.0], [1.0, 2.0, 1.0], [1.0, 2.5, 1.0]])
    new = dg.prediction_error_power(U, NOMINAL, [0], thetas, sigma=0.2)
    with pytest.warns(DeprecationWarning, match="as columns"):
        old = dg.prediction_error_power(U, NOMINAL, [0], thetas.T, sigma=0.2)
    np.testing.assert_allclose(old, new)
    with pytest.warns(DeprecationWarning, match="as columns"):
        old = dg.parameter_estimate_power(U, NOMINAL, [0, 1], 1, thetas.T, sigma=0.2)
    np.testing.assert_allclose(
        old, dg.parameter_estimate_power(U, NOMINAL, [0, 1], 1, thetas, sigma=0.2)
    )


def test_simulate_linear_regression_is_the_transpose_of_the_new_function():
    new = dg.simulate_regression_records(U, NOMINAL, sigma=0.2, n_records=4, rng=3)
    with pytest.warns(DeprecationWarning, match="simulate_regression_records"):
        old = dg.simulate_linear_regression(U, NOMINAL, sigma=0.2, n_records=4, rng=3)
    np.testing.assert_array_equal(old, new.T)


def test_thresholds_in_the_old_alpha_first_order():
    with pytest.warns(DeprecationWarning, match="residual_threshold\\(dof, alpha"):
        old = dg.residual_threshold(0.01, 20, 0.5)
    assert old == dg.residual_threshold(20, 0.01, sigma=0.5)
    with pytest.warns(DeprecationWarning, match="windowed_nis_threshold\\(window, alpha"):
        old = kf.windowed_nis_threshold(0.01, 10, 2)
    assert old == kf.windowed_nis_threshold(10, 0.01, n_outputs=2)


def test_scale_parameters_passed_by_position():
    with pytest.warns(DeprecationWarning, match="sigma=..."):
        assert dg.fault_noncentrality(U, NOMINAL, [0], NOMINAL, 0.5) == 0.0
    with pytest.warns(DeprecationWarning, match="sigma=..."):
        old = dg.normal_log_likelihood(4.0, [3.0, 5.0], 2.0)
    assert old == dg.normal_log_likelihood(4.0, [3.0, 5.0], sigma=2.0)
    Phi = U[:, :2]
    y = records(1)[0]
    with pytest.warns(DeprecationWarning, match="r=..., q=..."):
        old = kf.recursive_least_squares(Phi, y, 0.04, 1e-4)
    new = kf.recursive_least_squares(Phi, y, r=0.04, q=1e-4)
    np.testing.assert_array_equal(old.theta, new.theta)
    with pytest.warns(DeprecationWarning, match="Ts=..."):
        model = kf.beta_drift_model(0.2)
    assert model.n_states == 2
    with pytest.warns(DeprecationWarning, match="Ts=..."):
        states, outputs = kf.simulate_beta_system(np.ones(5), np.ones(5), 0, 0.1)
    assert states.shape == (5, 2) and outputs.shape == (5, 1)


def test_random_state_is_now_rng():
    law = nis.extreme_eigenvalue(2, 10)
    with pytest.warns(DeprecationWarning, match="rng="):
        old = law.rvs(5, random_state=np.random.default_rng(1))
    np.testing.assert_array_equal(old, law.rvs(5, rng=np.random.default_rng(1)))
    with pytest.warns(DeprecationWarning, match="rng="):
        law.rvs(5, np.random.default_rng(1))  # the old positional form
    with pytest.warns(DeprecationWarning, match="rng="):
        old = nis.simulate_extreme_eigenvalues(2, 10, 3, random_state=4)
    np.testing.assert_array_equal(old.lmax, nis.simulate_extreme_eigenvalues(2, 10, 3, rng=4).lmax)
    form = QuadraticForm(np.eye(2))
    with pytest.warns(DeprecationWarning, match="rng="):
        form.rvs_direct(3, random_state=1)
    with pytest.raises(TypeError, match="rng= only"):
        law.rvs(5, random_state=1, rng=1)


def test_support_is_a_method_and_the_tuple_form_warns():
    law = nis.extreme_eigenvalue(2, 10)
    assert law.support() == (0.0, np.inf)
    with pytest.warns(DeprecationWarning, match="support\\(\\)"):
        lower, upper = law.support
    assert (lower, upper) == (0.0, np.inf)


def test_named_results_still_unpack_like_the_old_tuples():
    eps = np.random.default_rng(0).standard_normal((30, 2))
    law_min, law_max = nis.nis_matrix_test(eps, np.eye(2)).null  # was a tuple of laws
    assert law_min.which == "min" and law_max.which == "max"
    lo, hi = nis.nis_critical_values(2, 30)
    assert (lo, hi) == tuple(nis.nis_critical_values(2, 30))
    x, P = kf.kf_predict([1.0], [[1.0]], [[2.0]], [[0.5]])
    assert x[0] == 2.0 and P[0, 0] == 4.5
    m0 = kf.LinearModel([[0.5]], [[1.0]], [[1.0]], [[1.0]])
    moments = mismatched.residual_moments(m0, m0, 3)
    lam, V = mismatched.principal_directions(moments, 0)
    s, left, right = mismatched.principal_directions(moments, 0, 1)
    assert lam.shape == s.shape == (1,) and V.shape == left.shape == right.shape == (1, 1)
