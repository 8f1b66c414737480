"""Bad input to every public callable of course.diagnosis (see tests/bad_input.py)."""

import numpy as np
from bad_input import (
    Arg,
    array,
    case,
    count,
    covariance,
    fixed,
    flag,
    function,
    generator,
    indices,
    mapping,
    matrix,
    module_tests,
    obj,
    positive,
    probability,
    real,
    scale,
    vector,
)

from course import diagnosis as dg
from course.chi2 import residual_threshold

N = 8
T = np.arange(N, dtype=float)
U = np.column_stack([np.ones(N), T / N, np.cos(T)])
NOMINAL = np.array([1.0, 1.0, 1.0])
Y = U @ NOMINAL + 0.1 * np.random.default_rng(0).standard_normal(N)
Y_RECORDS = U @ NOMINAL + 0.1 * np.random.default_rng(1).standard_normal((4, N))
STRUCTURE = dg.DecisionStructure.from_text(
    """
       NF F1 F2 F3
    T1  0  0  X  X
    T2  0  X  0  X
    T3  0  X  X  0"""
)
MODES = {"NF": (), "F1": (0,), "F2": (1,), "F3": (2,)}
TESTS = [(0,), (1,), (2,)]
THETAS = {"NF": [1, 1, 1], "F1": [2, 1, 1], "F2": [1, 2, 1], "F3": [1, 1, 2]}
ZS = np.array([0.5, 1.7, 0.9, 1.2, 0.3, 2.1])


def poisson_log_likelihood(theta):
    return ZS.size * theta[0] - np.exp(theta[0]) * ZS.sum()


def gaussian_log_likelihood(theta):
    r = Y - U @ theta
    return -0.5 * r @ r / 0.01


def simulate(mode, n, rng):
    return dg.simulate_regression_records(U, THETAS[mode], sigma=0.1, n_records=n, rng=rng)


def statistics(Y):
    return dg.linear_test_statistics(Y, U, NOMINAL, TESTS)


def predict(theta):
    return theta[0] * (1.0 - np.exp(-theta[1] * T / N))


OBSERVER_N, OBSERVER_TS = 40, 0.05
OBS_U = np.ones(OBSERVER_N)
OBS_X = np.zeros(OBSERVER_N)
for _t in range(OBSERVER_N - 1):
    OBS_X[_t + 1] = OBS_X[_t] + OBSERVER_TS * (-2.0 * OBS_X[_t] + OBS_U[_t])
OBSERVER = dg.observer_residuals(
    OBS_X,
    OBS_U,
    f=lambda x, u, th: -th * x + u,
    h=lambda x: x,
    x0=[0.0],
    theta0=[1.0],
    K1=[[2.0]],
    K2=[[-1.0]],
    Ts=OBSERVER_TS,
)
LAW = dg.LogLikelihoodLaw(3, -1.0)


def records(value=Y):
    """One record ``(N,)`` or records as rows ``(M, N)``; records as columns are refused."""
    return array(value, ndims=(1, 2)).but(as_columns=Y_RECORDS.T)


def regressors(value=U):
    return matrix(value)


def nominal(value=NOMINAL):
    return vector(value)


def free(value=(0,), size=3):
    return indices(list(value), size)


def parameter_rows(value):
    """Parameter vectors: ``(p,)`` or rows ``(K, p)``; vectors as columns are refused."""
    return array(value, ndims=(1, 2)).but(as_columns=np.asarray(value).T)


def alarms_arg(value):
    return Arg(value, {"None": None, "unknown test": ["T9"], "number": 3.0, "NaN": [np.nan, 1, 0]})


TABLE = {
    # -- decision structures ----------------------------------------------------
    "DecisionStructure": case(
        dg.DecisionStructure,
        sensitivity=Arg(
            [[0, 0, 1, 1], [0, 1, 0, 1]],
            {
                "None": None,
                "empty": np.zeros((0, 4)),
                "1-D": [0, 1, 1],
                "3-D": np.zeros((2, 2, 2)),
                "NaN": [[0, np.nan, 1, 1], [0, 1, 0, 1]],
                "bad mark": [["0", "Y", "X", "X"], ["0", "X", "0", "X"]],
                "number": 2.0,
            },
        ),
        tests=Arg(None, {"wrong count": ["T1"], "repeated": ["T1", "T1"], "text": "T1"}),
        modes=Arg(None, {"wrong count": ["NF"], "repeated": ["F", "F", "F", "F"], "text": "abc"}),
    ),
    "DecisionStructure.from_text": case(
        dg.DecisionStructure.from_text,
        text=Arg(
            "NF F1\nT1 0 X",
            {
                "None": None,
                "empty": "",
                "header only": "NF F1",
                "ragged": "NF F1\nT1 0",
                "number": 3.0,
            },
        ),
    ),
    "DecisionStructure.row_index": case(
        STRUCTURE.row_index,
        test=Arg("T2", {"unknown": "T9", "None": None, "fraction": 0.5, "out of range": 3}),
    ),
    "DecisionStructure.mode_index": case(
        STRUCTURE.mode_index,
        mode=Arg("F1", {"unknown": "F9", "None": None, "fraction": 0.5, "out of range": 4}),
    ),
    "DecisionStructure.row": case(STRUCTURE.row, test=Arg("T1", {"unknown": "T9", "None": None})),
    "DecisionStructure.hypotheses": case(
        STRUCTURE.hypotheses, test=Arg("T1", {"unknown": "T9", "None": None})
    ),
    "DecisionStructure.isolability": case(STRUCTURE.isolability),
    "DecisionStructure.to_text": case(STRUCTURE.to_text),
    "diagnoses": case(
        dg.diagnoses,
        structure=obj(STRUCTURE),
        alarms=alarms_arg(["T2", "T3"]),
        exoneration=flag(False),
    ),
    "diagnosis_matrix": case(
        dg.diagnosis_matrix,
        structure=obj(STRUCTURE),
        alarms=Arg(
            [[False, True, True], [True, True, True]],
            {
                "None": None,
                "wrong width": [[True, False]],
                "3-D": np.zeros((2, 2, 3), bool),
                "NaN": [[np.nan, 1.0, 0.0]],
                "text": "T1",
            },
        ),
        exoneration=flag(False),
    ),
    "multiple_fault_diagnoses": case(
        dg.multiple_fault_diagnoses,
        structure=obj(STRUCTURE),
        alarms=alarms_arg(["T1", "T2", "T3"]),
        no_fault=Arg("NF", {"unknown": "F9", "number": 3.0}),
        max_size=count(2, minimum=0, none_ok=True),
    ),
    "linear_decision_structure": case(
        dg.linear_decision_structure,
        U=matrix(U, shaped=False),  # columns no mode or test names are allowed
        modes=mapping(MODES).but(out_of_range={"NF": (), "F1": (7,)}),
        tests=mapping({"T1": (0,), "T3": (2,)}).but(out_of_range={"T1": (9,)}),
        rtol=positive(1e-9),
    ),
    "isolation_monte_carlo": case(
        dg.isolation_monte_carlo,
        structure=obj(STRUCTURE),
        simulate=function(simulate),
        statistics=function(statistics),
        thresholds=vector([residual_threshold(N - 1, 0.01, sigma=0.1)] * 3),
        n_records=count(20),
        rng=generator(),
        modes=Arg(None, {"unknown": ["F9"], "text": "NF"}),
        exoneration=flag(False),
    ),
    # -- prediction errors ---------------------------------------------------------
    "least_squares_residual": case(
        dg.least_squares_residual,
        Phi=matrix(U, shaped=False),  # any number of regressors
        y=records(),
        rcond=positive(1e-9, none_ok=True),
    ),
    "prediction_error": case(
        dg.prediction_error,
        y=records(),
        U=regressors(),
        nominal=nominal(),
        free=free(),
        rcond=positive(1e-9, none_ok=True),
    ),
    "prediction_error_test": case(
        dg.prediction_error_test,
        y=vector(Y),
        U=regressors(),
        nominal=nominal(),
        free=free(),
        sigma=scale(0.1),
        alpha=probability(0.05),
        name=fixed("prediction-error test"),
        rcond=positive(1e-9, none_ok=True),
    ),
    "prediction_error_power": case(
        dg.prediction_error_power,
        U=regressors(),
        nominal=nominal(),
        free=free(),
        theta=parameter_rows([[1.0, 1.0, 1.0], [1.0, 1.5, 1.0]]),
        sigma=scale(0.3),
        alpha=probability(0.05),
    ),
    "fault_noncentrality": case(
        dg.fault_noncentrality,
        U=regressors(),
        nominal=nominal(),
        free=free(),
        theta=parameter_rows([[1.0, 1.0, 1.0], [1.0, 1.5, 1.0]]),
        sigma=scale(0.3),
    ),
    "nonlinear_prediction_error": case(
        dg.nonlinear_prediction_error,
        y=array(predict([2.0, 1.4]), ndims="any"),
        predict=function(predict).but(
            returns_nan=lambda theta: np.full(N, np.nan),  # scipy: "Residuals are not finite"
        ),
        nominal=vector([2.0, 1.0], shaped=False),  # predict reads theta[0] and theta[1]
        free=free((1,), 2),
        theta_init=vector([1.2], none_ok=True),
        bounds=Arg(None, {"reversed": (2.0, 0.0), "NaN": (np.nan, 2.0), "text": "ab"}),
    ),
    # -- parameter estimates ---------------------------------------------------
    "estimate_parameters": case(
        dg.estimate_parameters,
        y=records(),
        U=regressors(),
        nominal=nominal(),
        estimate=free((0, 1)).but(none=None, empty=[]),
        sigma=scale(0.1),
    ),
    "parameter_estimate_test": case(
        dg.parameter_estimate_test,
        estimate=array([1.3, 0.9], ndims=(0, 1)),
        covariance=covariance([[0.01, 0.002], [0.002, 0.02]]),
        nominal=array([1.0, 1.0], ndims=(0, 1)),
        alpha=probability(0.05),
        name=fixed("parameter-estimate test"),
    ),
    "regression_parameter_test": case(
        dg.regression_parameter_test,
        y=vector(Y),
        U=regressors(),
        nominal=nominal(),
        estimate=free((0, 1)).but(none=None, empty=[]),
        test=free((1,)).but(none=None, empty=[], not_estimated=[2]),
        sigma=scale(0.1),
        alpha=probability(0.05),
        name=Arg(None),
    ),
    "parameter_estimate_power": case(
        dg.parameter_estimate_power,
        U=regressors(),
        nominal=nominal(),
        estimate=free((0, 1)).but(none=None, empty=[]),
        test=free((1,)).but(none=None, empty=[], not_estimated=[2]),
        theta=parameter_rows([[1.0, 1.0, 1.0], [1.0, 1.05, 1.0]]),
        sigma=scale(0.1),
        alpha=probability(0.05),
    ),
    # -- likelihoods -----------------------------------------------------------
    "normal_log_likelihood": case(
        dg.normal_log_likelihood,
        theta=array(4.0, ndims="any"),
        z=array([3.0, 5.0], ndims="any", shaped=False),
        sigma=scale(1.0),
    ),
    "normal_likelihood": case(
        dg.normal_likelihood,
        theta=array(4.0, ndims="any"),
        z=array([3.0, 5.0], ndims="any", shaped=False),
        sigma=scale(1.0),
    ),
    "maximum_likelihood": case(
        dg.maximum_likelihood,
        log_likelihood=function(poisson_log_likelihood),
        nominal=vector([0.0], shaped=False),  # the function reads theta[0] only
        free=Arg(None, {"out of range": [1], "repeated": [0, 0], "fraction": [0.5], "text": "0"}),
        theta_init=vector([0.1], none_ok=True),
        bounds=Arg(None, {"reversed": [(2.0, 0.0)], "NaN": [(np.nan, 2.0)], "text": "ab"}),
        method=Arg(None, {"unknown": "nonsense", "number": 3}),
    ),
    "LogLikelihoodLaw": case(dg.LogLikelihoodLaw, dof=count(3), c=real(-1.0)),
    "LogLikelihoodLaw.ppf": case(
        LAW.ppf, q=array(0.25, ndims="any", shaped=False).but(drop=("inf",), above_one=1.5)
    ),
    "LogLikelihoodLaw.isf": case(
        LAW.isf, q=array(0.25, ndims="any", shaped=False).but(drop=("inf",), above_one=1.5)
    ),
    "LogLikelihoodLaw.mean": case(LAW.mean),
    "LogLikelihoodLaw.var": case(LAW.var),
    "likelihood_test": case(
        dg.likelihood_test,
        y=vector(Y),
        U=regressors(),
        nominal=nominal(),
        free=free(),
        sigma=scale(0.1),
        alpha=probability(0.05),
        name=fixed("maximum-likelihood test"),
    ),
    "glr_test": case(
        dg.glr_test,
        log_likelihood=function(gaussian_log_likelihood),
        nominal=nominal(),
        free0=free((0,)),
        free1=Arg(None, {"out of range": [5], "smaller than free0": [], "text": "0"}),
        alpha=probability(0.05),
        theta_init=vector([1.0, 1.0, 1.0], none_ok=True),
        bounds=Arg(None, {"reversed": [(2.0, 0.0)] * 3, "text": "ab"}),
        name=fixed("glr"),
    ),
    "linear_glr_test": case(
        dg.linear_glr_test,
        y=vector(Y),
        U=regressors(),
        nominal=nominal(),
        free0=free((0,)),
        free1=Arg(None, {"out of range": [5], "smaller than free0": [], "text": "0"}),
        sigma=scale(0.1),
        alpha=probability(0.05),
        name=fixed("glr"),
    ),
    "neyman_pearson_test": case(
        dg.neyman_pearson_test,
        z=array([3.0, 5.0], ndims=(0, 1), shaped=False),  # a scalar is one observation
        theta0=array(0.0, ndims=(0, 1)),
        theta1=array(1.0, ndims=(0, 1)).but(equal_to_theta0=0.0),
        sigma=scale(1.0),
        regressors=Arg(
            None, {"wrong shape": np.ones((3, 1)), "NaN": [[np.nan], [1.0]], "text": "ab"}
        ),
        alpha=probability(0.05),
        name=fixed("NP"),
    ),
    "mode_log_likelihoods": case(
        dg.mode_log_likelihoods,
        y=vector(Y),
        U=regressors(),
        nominal=nominal(),
        modes=mapping(MODES).but(out_of_range={"NF": (), "F1": (7,)}),
        sigma=scale(0.1),
        prior_std=positive(1.0, none_ok=True),
    ),
    "bayes_ranking": case(
        dg.bayes_ranking,
        log_likelihoods=mapping({"NF": -3.0, "F1": -1.0}).but(
            nan={"NF": np.nan, "F1": -1.0}, other_modes={"NF": -3.0, "F2": -1.0}
        ),
        priors=mapping({"NF": 0.9, "F1": 0.1}).but(
            negative={"NF": 1.1, "F1": -0.1},
            not_summing_to_one={"NF": 0.9, "F1": 0.9},
            nan={"NF": np.nan, "F1": 0.1},
        ),
    ),
    # -- Monte Carlo -----------------------------------------------------------
    "simulate_regression_records": case(
        dg.simulate_regression_records,
        U=regressors(),
        theta=nominal(),
        sigma=scale(0.1),
        n_records=count(3),
        rng=generator(),
    ),
    "linear_test_statistics": case(
        dg.linear_test_statistics,
        Y=records(Y_RECORDS),
        U=regressors(),
        nominal=nominal(),
        tests=Arg(TESTS, {"None": None, "out of range": [(7,)], "text": "ab", "number": 3.0}),
    ),
    # -- the lecture's dynamic examples ----------------------------------------
    "beta_drift_model": case(
        dg.beta_drift_model,
        Ts=positive(0.1),
        q_beta=scale(1e-4, zero_ok=True),
        q_x=scale(1e-4, zero_ok=True),
        r=scale(1e-2),
        x0_mean=vector([1.0, 0.0]),
        x0_cov=covariance(np.diag([0.25, 0.01]), psd=True, none_ok=True),
    ),
    "simulate_beta_system": case(
        dg.simulate_beta_system,
        beta=array(0.8 + 0.002 * T, min_ndim=1),
        u=array(np.ones(N), min_ndim=1),
        rng=generator(),
        Ts=positive(0.1),
        q_x=scale(1e-4, zero_ok=True),
        r=scale(1e-2, zero_ok=True),
        x0=real(0.0),
        fault=array(np.where(T >= 5, 0.2, 0.0), min_ndim=1, none_ok=True),
        batch=count(3, none_ok=True).but(drop=("sequence",)),
    ),
    "observer_residuals": case(
        dg.observer_residuals,
        y=array(OBS_X, min_ndim=1),
        u=array(OBS_U, min_ndim=1, none_ok=True),
        f=function(lambda x, u, th: -th * x + u),
        h=function(lambda x: x),
        x0=vector([0.0]),
        theta0=vector([1.0]),
        K1=Arg(
            [[2.0]], {"None": None, "NaN": [[np.nan]], "wrong shape": [[1.0, 2.0]], "text": "k"}
        ),
        K2=Arg(
            [[-1.0]], {"None": None, "NaN": [[np.nan]], "wrong shape": [[1.0], [2.0]], "text": "k"}
        ),
        Ts=positive(OBSERVER_TS),
    ),
    "ObserverResult.windowed_energy": case(
        OBSERVER.windowed_energy,
        nan_ok=True,
        window=count(4).but(longer_than_record=41),
        Ts=positive(0.05),
    ),
}

EXEMPT = {
    "FaultRanking": "a result the library returns",
    "FaultRanking.as_dict": "a method of a result, without arguments",
    "FaultRanking.to_text": "formats a result the library built",
    "Hypotheses": "a result the library returns",
    "IsolationResult": "a result the library returns",
    "IsolationResult.to_text": "formats a result the library built",
    "MLResult": "a result the library returns",
    "NonlinearFit": "a result the library returns",
    "ObserverResult": "a result the library returns",
    "ParameterEstimate": "a result the library returns",
    "RegressionFit": "a result the library returns",
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests("course.diagnosis", TABLE, EXEMPT)
