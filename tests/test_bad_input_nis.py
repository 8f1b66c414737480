"""Bad input to every public callable of course.nis (see tests/bad_input.py)."""

import numpy as np
from bad_input import (
    Arg,
    array,
    case,
    choice,
    count,
    covariance,
    generator,
    index,
    module_tests,
    obj,
    probability,
    real,
)

from course import filters, nis

EPS = np.array([[0.3, -1.2], [1.1, 0.4], [-0.7, 0.9], [0.2, -0.1], [1.5, 0.6]])
S = np.array([[1.0, 0.3], [0.3, 0.5]])
MODEL = filters.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.1]], R=[[1.0]])
_, Y = MODEL.simulate(12, np.random.default_rng(0))
RESULT = filters.kalman_filter(MODEL, Y)
NIS_VALUES = np.array([0.3, 2.1, 0.8, 1.7, 0.2, 3.1, 0.9, 0.4])
STATISTIC = np.array([[0.1, 2.0, 0.3, 5.0, 6.0], [0.2, 0.1, 0.2, 0.4, 7.0]])
EXACT = nis.ExtremeEigenvalue(2, 20, "max")
TW = nis.TracyWidomApproximation(2, 20, "max")


def innovations(value=EPS):
    """(K, m) innovations, time on the second-to-last axis; leading axes are runs."""
    return array(value, min_ndim=2)


def dims(m=2, K=20, wishart=True):
    """The dimension and the number of steps (at least m for a Wishart law)."""
    K = count(K).but(smaller_than_m=1) if wishart else count(K)
    return {"m": count(m), "K": K}


def point(value=1.2):
    """A point where a law is evaluated."""
    return array(value, ndims="any", shaped=False, empty_ok=True).but(drop=("inf",))


def level(value=0.05):
    """A probability for ppf/isf."""
    return array(value, ndims="any", shaped=False, empty_ok=True).but(above_one=1.5, negative=-0.25)


def filter_output(value=RESULT):
    """A single-record filter result."""
    return obj(value).but(array_2d=np.ones((3, 4)))


TABLE = {
    "ExtremeEigenvalue": case(nis.ExtremeEigenvalue, **dims(), which=choice("max")),
    "ExtremeEigenvalue.cdf": case(EXACT.cdf, x=point().but(negative=-1.0)),
    "ExtremeEigenvalue.sf": case(EXACT.sf, x=point().but(negative=-1.0)),
    "ExtremeEigenvalue.pdf": case(EXACT.pdf, x=point().but(negative=-1.0)),
    "ExtremeEigenvalue.mean": case(EXACT.mean),
    "ExtremeEigenvalue.var": case(EXACT.var),
    "TracyWidomApproximation": case(nis.TracyWidomApproximation, **dims(), which=choice("min")),
    "TracyWidomApproximation.ppf": case(TW.ppf, q=level()),
    "TracyWidomApproximation.isf": case(TW.isf, q=level()),
    "TracyWidomApproximation.mean": case(TW.mean),
    "TracyWidomApproximation.var": case(TW.var),
    "alarm_statistics": case(
        nis.alarm_statistics,
        statistic=array(STATISTIC, shaped=False).but(
            nan_after_fault=np.where(np.arange(5) == 3, np.nan, STATISTIC),
            nan_in_one_run=np.where([[False] * 5, [True] + [False] * 4], np.nan, STATISTIC),
        ),
        threshold=real(1.0),
        fault_time=index(3, 5, none_ok=True),
    ),
    "consistency_interval": case(
        nis.consistency_interval, dof=count(2), count=count(100), alpha=probability(0.05)
    ),
    "empirical_threshold": case(
        nis.empirical_threshold,
        null_statistic=array(np.arange(1.0, 101.0), ndims="any", shaped=False).but(
            drop=("NaN",),  # a leading NaN is the undefined start of a record
            all_nan=np.full(5, np.nan),
            nan_inside=np.where(np.arange(100) == 50, np.nan, np.arange(1.0, 101.0)),
            nan_in_one_run=np.where(np.eye(2, 5, dtype=bool), np.nan, STATISTIC),
        ),
        alpha=probability(0.05),
    ),
    "extreme_eigenvalue": case(
        nis.extreme_eigenvalue, **dims(), which=choice("max"), method=choice("exact")
    ),
    "nees": case(nis.nees, errors=innovations(), P=covariance(S, ndims=(2, 3), extreme=True)),
    "nis": case(nis.nis, innovations=innovations(), S=covariance(S, ndims=(2, 3), extreme=True)),
    "nis_critical_values": case(
        nis.nis_critical_values, **dims(2, 50, False), alpha=probability(0.05)
    ),
    "nis_matrix": case(
        nis.nis_matrix,
        innovations=innovations(),
        S=covariance(S, ndims=(2, 3), extreme=True),
        window=count(3, none_ok=True).but(longer_than_record=6),
    ),
    "nis_matrix_critical_values": case(
        nis.nis_matrix_critical_values, **dims(2, 50), alpha=probability(0.05)
    ),
    "nis_matrix_eigenvalues": case(
        nis.nis_matrix_eigenvalues,
        innovations=innovations(),
        S=covariance(S, ndims=(2, 3), extreme=True),
    ),
    "nis_matrix_test": case(
        nis.nis_matrix_test,
        innovations=array(EPS).but(fewer_steps_than_outputs=EPS[:1]),
        S=covariance(S, ndims=(2, 3), extreme=True),
        alpha=probability(0.05),
    ),
    "nis_test": case(
        nis.nis_test,
        innovations=array(EPS),
        S=covariance(S, ndims=(2, 3), extreme=True),
        alpha=probability(0.05),
    ),
    "prob_eigenvalues_within": case(
        nis.prob_eigenvalues_within,
        **dims(2, 50),
        lower=real(0.553).but(negative=-0.5),
        upper=real(1.5848).but(drop=("inf",), below_lower=0.5),
    ),
    "simulate_extreme_eigenvalues": case(
        nis.simulate_extreme_eigenvalues,
        **dims(2, 20),
        size=count(4, minimum=0, none_ok=True).but(
            drop=("sequence",), shape_with_fraction=(2, 2.5)
        ),
        rng=generator(),
        chunk=count(100),
    ),
    "windowed_chi2_test": case(
        nis.windowed_chi2_test,
        result=Arg(
            NIS_VALUES,
            {
                "None": None,
                "text": "1 2",
                "2-D": np.ones((2, 8)),
                "inf": np.r_[np.inf, NIS_VALUES[1:]],
                "negative": -NIS_VALUES,
                "complex": NIS_VALUES + 1j,
            },
        ),
        window=count(4).but(longer_than_record=9),
        alpha=probability(0.05),
        t=index(-1, 8, negative=True),
        n_outputs=count(2, none_ok=True),
    ),
    "windowed_nis": case(
        nis.windowed_nis,
        nan_ok=True,
        result=filter_output(),
        window=count(4).but(longer_than_record=13),
    ),
    "windowed_nis_threshold": case(
        nis.windowed_nis_threshold, window=count(20), alpha=probability(0.001), n_outputs=count(2)
    ),
    "windowed_sum": case(
        nis.windowed_sum,
        nan_ok=True,
        values=array([1.0, 2.0, 3.0, 5.0, 6.0], ndims="any", shaped=False).but(drop=("NaN",)),
        window=count(2).but(longer_than_record=6),
    ),
}

EXEMPT = {
    "AlarmStatistics": "a result the library returns",
    "EigenvaluePair": "a named tuple the library returns",
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests("course.nis", TABLE, EXEMPT)
