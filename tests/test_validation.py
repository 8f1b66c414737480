"""course.validation: one rule per kind of input, applied by every module."""

import numpy as np
import pytest
from numpy.linalg import LinAlgError

from course import chi2, lsq, mismatched, nis, validation
from course import diagnosis as dg
from course import filters as kf

MODEL = kf.LinearModel([[0.5]], [[1.0]], [[1.0]], [[1.0]])
U = np.column_stack([np.ones(6), np.arange(6.0)])

#: Functions that take a count, called with the count ``n`` (10 is valid for all).
COUNT_TAKERS = {
    "lsq.data_snooping(max_removals)": lambda n: lsq.data_snooping(
        lsq.fit(U, np.arange(6.0)), max_removals=n
    ),
    "chi2 residual_threshold(dof)": lambda n: chi2.residual_threshold(n, 0.05),
    "diagnosis simulate_regression_records(n_records)": lambda n: dg.simulate_regression_records(
        U, [1, 1], sigma=1, n_records=n, rng=0
    ),
    "filters LinearModel.simulate(N)": lambda n: MODEL.simulate(n, 0),
    "filters LinearModel.simulate(batch)": lambda n: MODEL.simulate(3, 0, batch=n),
    "nis windowed_nis_threshold(window)": lambda n: nis.windowed_nis_threshold(n, 0.05),
    "nis nis_critical_values(K)": lambda n: nis.nis_critical_values(2, n),
    "nis extreme_eigenvalue(K)": lambda n: nis.extreme_eigenvalue(2, n),
    "nis consistency_interval(count)": lambda n: nis.consistency_interval(2, n),
    "mismatched residual_moments(N)": lambda n: mismatched.residual_moments(MODEL, MODEL, n),
    "mismatched simulate_records(M)": lambda n: mismatched.simulate_records(MODEL, MODEL, n, 3, 0),
    "mismatched mean_matrix(M)": lambda n: mismatched.mean_matrix(n, 1),
}


@pytest.mark.parametrize("name", sorted(COUNT_TAKERS))
def test_one_integer_rule_for_every_count(name):
    """10, np.int64(10) and the whole float 10.0 are accepted; 10.5, True, NaN and "10" are not."""
    call = COUNT_TAKERS[name]
    for good in (10, np.int64(10), 10.0, np.float64(10.0), np.array(10)):
        call(good)
    for bad in (10.5, True, np.nan, np.inf, "10", None):
        if bad is None and ("max_removals" in name or "batch" in name):
            continue  # None means "no limit" / "no batch" there
        with pytest.raises(ValueError, match="integer"):
            call(bad)


def test_whole_floats_give_the_same_answer_as_integers():
    assert chi2.residual_threshold(10.0, 0.05) == chi2.residual_threshold(10, 0.05)
    a = mismatched.simulate_records(MODEL, MODEL, 4.0, 3.0, np.random.default_rng(1))
    b = mismatched.simulate_records(MODEL, MODEL, 4, 3, np.random.default_rng(1))
    np.testing.assert_array_equal(a, b)


def test_counts_below_their_minimum_name_the_argument():
    with pytest.raises(ValueError, match=r"n_records .* positive integer, got 0"):
        COUNT_TAKERS["diagnosis simulate_regression_records(n_records)"](0)
    with pytest.raises(ValueError, match=r"M .* integer of at least 2, got 1"):
        mismatched.mean_matrix(1, 1)
    with pytest.raises(ValueError, match="max_removals must be a non-negative integer"):
        lsq.data_snooping(lsq.fit(U, np.arange(6.0)), max_removals=-1)


def test_indices_follow_the_same_rule():
    assert validation.as_index(2.0, "j", 4) == 2
    assert validation.as_index(-1, "t", 4, negative=True) == 3
    with pytest.raises(ValueError, match=r"in 0..3"):
        validation.as_index(-1, "j", 4)
    with pytest.raises(ValueError, match="integer"):
        validation.as_index(1.5, "j", 4)
    assert validation.as_indices(None, "free", 3) == []
    assert validation.as_indices(np.int64(2), "free", 3) == [2]
    with pytest.raises(ValueError, match=r"out of range 0..2"):
        validation.as_indices([0, 3], "free", 3)
    with pytest.raises(ValueError, match="at least one"):
        validation.as_indices([], "estimate", 3, allow_empty=False)


def test_real_numbers_variances_and_probabilities():
    assert validation.as_finite(np.float32(2.5), "x") == 2.5
    for bad in (np.nan, np.inf, "1", None, True, [1.0]):
        with pytest.raises(ValueError, match="x"):
            validation.as_finite(bad, "x")
    with pytest.raises(ValueError, match="must be positive"):
        validation.as_positive(-1e-300, "sigma")
    assert validation.as_variance(0.0, "q") == 0.0
    with pytest.raises(ValueError, match="it is a variance"):
        validation.as_variance(0.0, "r", positive=True)
    for bad in (0.0, 1.0, -0.1, np.nan, True, "0.05"):
        with pytest.raises(ValueError, match="alpha"):
            validation.as_probability(bad)


def test_generators_only():
    g = np.random.default_rng(1)
    assert validation.as_generator(g) is g
    assert isinstance(validation.as_generator(None), np.random.Generator)
    with pytest.raises(TypeError, match="Generator"):
        validation.as_generator(np.random.RandomState(0))


# ---------------------------------------------------------------------------
# the bad inputs issue 15 names, one by one (the tables of test_bad_input_*.py
# feed every class of bad input to every public callable; these are the
# reported cases, kept readable)
# ---------------------------------------------------------------------------
def test_issue_15_sigma_at_the_limits_of_floating_point():
    U = np.column_stack([np.ones(6), np.arange(6.0)])
    y = U @ [1.0, 0.5] + np.array([0.1, -0.2, 0.0, 0.2, -0.1, 0.05])
    for sigma in (1e300, 1e-300):  # OverflowError / ZeroDivisionError before
        with pytest.raises(ValueError, match=r"sigma .* units"):
            dg.prediction_error_test(y, U, [1.0, 0.5], sigma=sigma)
        with pytest.raises(ValueError, match="sigma"):
            dg.fault_noncentrality(U, [1.0, 0.5], [0], [1.0, 0.6], sigma=sigma)
    # a log-likelihood has an answer at every sigma: computed in logs, never NaN
    assert np.isfinite(dg.normal_log_likelihood(4.0, [3.0, 5.0], sigma=1e300))
    assert dg.normal_log_likelihood(4.0, [3.0, 5.0], sigma=1e-300) == -np.inf


def test_issue_15_numerically_singular_covariance():
    # exactly singular (X X^T of a 3 x 2 X) with a smallest eigenvalue of +1.6e-15 after rounding
    Q = np.array([[2.0, 4.0, 5.0], [4.0, 10.0, 13.0], [5.0, 13.0, 17.0]])
    assert np.linalg.eigvalsh(Q)[0] > 0
    with pytest.raises(LinAlgError, match="numerically singular"):
        validation.as_covariance(Q, "Qyy", 3)
    with pytest.raises(LinAlgError, match="numerically singular"):
        nis.nis(np.ones((4, 3)), Q)
    # the rule is scale-free: a regular covariance stays regular at 1e-300 and 1e300
    regular = np.array([[2.0, 0.5], [0.5, 1.0]])
    for scale in (1e-300, 1e300):
        validation.as_covariance(scale * regular, "R", 2)


def test_issue_15_contradictory_test_results():
    from scipy import stats

    from course.results import TestResult

    good = dict(
        name="z", statistic=2.5, alpha=0.05, critical_value=1.6449, pvalue=0.0062, reject=True,
        null=stats.norm(),
    )  # fmt: skip
    TestResult(**good)
    for bad in ({"reject": "no"}, {"pvalue": np.nan}, {"pvalue": 1.5}, {"reject": False}):
        with pytest.raises(ValueError, match=r"reject|pvalue"):
            TestResult(**{**good, **bad})


def test_issue_15_leaks_become_named_refusals():
    with pytest.raises(ValueError, match="size"):
        nis.simulate_extreme_eigenvalues(2, 10, size=2.5, rng=0)
    model = kf.NonlinearModel(lambda x, u: x, lambda x: x, Q=[[0.1]], R=[[1.0]], x0_mean=[0.0])
    with pytest.raises(ValueError, match="model"):
        kf.ekf_predict(None, [0.0], [[1.0]])
    with pytest.raises(ValueError, match="x_filt"):
        kf.ekf_predict(model, [], [[1.0]])
    with pytest.raises(ValueError, match="f must be callable"):
        kf.numerical_jacobian(None, [1.0])
    with pytest.raises(ValueError, match="beta"):
        dg.simulate_beta_system(0.8, [1.0], 0)
    with pytest.raises(ValueError, match="moments"):
        mismatched.moment_zscores(np.ones((3, 2, 1)), None)
    for matrix in (mismatched.mean_matrix, mismatched.covariance_matrix):
        with pytest.raises(ValueError, match=r"\bp\b"):
            matrix(3, -1)
    with pytest.raises(ValueError, match="structure"):
        dg.diagnoses(None, [True])
    with pytest.raises(ValueError, match="R"):
        kf.NonlinearModel(lambda x, u: x, lambda x: x, Q=np.zeros((0, 0)), R=np.zeros((0, 0)),
                          x0_mean=[0.0])  # fmt: skip
