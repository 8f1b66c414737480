"""Bad input to every public callable of course.mismatched (see tests/bad_input.py)."""

import dataclasses

import numpy as np
from bad_input import (
    Arg,
    array,
    case,
    choice,
    count,
    flag,
    generator,
    index,
    module_tests,
    obj,
    probability,
)

from course import mismatched as mm
from course.filters import LinearModel

TRUE = LinearModel(
    F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0.0], [0.0, 0.02]], R=[[1.0]]
)
FILT = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
NOISIER = LinearModel(F=TRUE.F, H=TRUE.H, Q=TRUE.Q, R=[[3.0]])
TWO_OUTPUTS = LinearModel(F=np.eye(2) * 0.5, H=np.eye(2), Q=np.eye(2), R=np.eye(2))
N, M = 4, 6
NULL = mm.residual_moments(TRUE, FILT, N)
ALT = mm.residual_moments(NOISIER, FILT, N)
R = mm.simulate_records(TRUE, FILT, M, N, np.random.default_rng(3))
NULL2 = mm.residual_moments(TWO_OUTPUTS, TWO_OUTPUTS, 3)
R2 = mm.simulate_records(TWO_OUTPUTS, TWO_OUTPUTS, M, 3, np.random.default_rng(4))


def residuals(value=R):
    """``(M, N, p)`` residuals of ``M >= 2`` records (``(M, N)`` for one output)."""
    base = array(value, ndims=(2, 3)).but(one_record=value[:1])
    # tiny residuals only: squares of 1e300 overflow (the statistics are of the order 1e600)
    return dataclasses.replace(base, extreme={"R * 1e-300": np.asarray(value, float) * 1e-300})


def model(value):
    return obj(value).but(array=np.eye(2), two_outputs=TWO_OUTPUTS)


def section(j=1, size=N):
    return index(j, size, negative=False)


def moments(value=NULL):
    return obj(value).but(array=np.eye(2))


def unit(value):
    return array(value).but(not_unit=2 * np.asarray(value, float))


def options_of_a_test(alternative="two-sided"):
    return {
        "null": moments().but(other_length=mm.residual_moments(TRUE, FILT, N + 2)),
        "alpha": probability(0.05),
        "alternative": choice(alternative),
        "power_against": obj(None, none_ok=True).but(
            other_length=mm.residual_moments(TRUE, FILT, N + 2)
        ),
    }


TABLE = {
    "ResidualMoments": case(
        mm.ResidualMoments,
        mean=array(NULL.mean),
        cov=array(NULL.cov),
        cross_cov=array(NULL.cross_cov),
    ),
    "ResidualMoments.C": case(NULL.C, j=section(0), k=section(2)),
    "ResidualMoments.stacked_cov": case(NULL.stacked_cov),
    "residual_moments": case(
        mm.residual_moments, true_model=model(TRUE), filter_model=model(FILT), N=count(N)
    ),
    "residual_moments_as_printed": case(
        mm.residual_moments_as_printed,
        true_model=model(TRUE),
        filter_model=model(FILT),
        N=count(N),
        misprint=choice("Q1_block"),
    ),
    "simulate_records": case(
        mm.simulate_records,
        true_model=model(TRUE),
        filter_model=model(FILT),
        M=count(M),
        N=count(N),
        rng=generator(),
    ),
    "moment_zscores": case(mm.moment_zscores, residuals=residuals(), moments=moments()),
    "principal_directions": case(
        mm.principal_directions, moments=moments(), j=section(1), k=section(2).but(drop=("None",))
    ),
    "mean_statistic": case(
        mm.mean_statistic, residuals=residuals().but(drop=("longer",)), j=section()
    ),
    "covariance_statistic": case(
        mm.covariance_statistic,
        residuals=residuals(R2).but(drop=("longer",)),
        j=section(1, 3),
        direction=Arg(None, {"not unit": [2.0, 0.0], "wrong length": [1.0], "NaN": [np.nan, 1.0]}),
    ),
    "correlation_statistic": case(
        mm.correlation_statistic,
        residuals=residuals(R2).but(drop=("longer",)),
        j=section(0, 3),
        k=section(2, 3),
        directions=Arg(
            None,
            {"not a pair": [1.0, 0.0], "not unit": ([2.0, 0.0], [1.0, 0.0]), "text": "uw"},
        ),
    ),
    "mean_matrix": case(mm.mean_matrix, M=count(3).but(one_record=1), p=count(2)),
    "covariance_matrix": case(
        mm.covariance_matrix,
        M=count(3).but(one_record=1),
        p=count(2),
        direction=Arg(None, {"not unit": [2.0, 0.0], "wrong length": [1.0], "NaN": [np.nan, 1.0]}),
    ),
    "correlation_matrix": case(
        mm.correlation_matrix,
        M=count(3).but(one_record=1),
        p=count(2),
        directions=Arg(None, {"not a pair": [1.0, 0.0], "text": "uw"}),
    ),
    "section_moments": case(mm.section_moments, moments=moments(), j=section(), M=count(M)),
    "pair_moments": case(
        mm.pair_moments, moments=moments(), j=section(1), k=section(3), M=count(M)
    ),
    "statistic_law": case(
        mm.statistic_law,
        moments=moments(),
        kind=choice("covariance"),
        j=section(2),
        M=count(M).but(one_record=1),
        k=Arg(None, {"out of range": N, "fraction": 0.5}),
        direction=Arg(None, {"not unit": [2.0], "NaN": [np.nan]}),
        full=flag(False),
    ),
    "mean_test": case(mm.mean_test, residuals=residuals(), j=section(), **options_of_a_test()),
    "covariance_test": case(
        mm.covariance_test,
        residuals=residuals(),
        j=section(2),
        **options_of_a_test(),
        gamma=Arg(None, {"out of range": 1, "fraction": 0.5, "text": "a"}),
    ),
    "correlation_test": case(
        mm.correlation_test,
        residuals=residuals(),
        j=section(1),
        k=section(3),
        **options_of_a_test("greater"),
        gamma=Arg(None, {"out of range": 1, "fraction": 0.5, "text": "a"}),
    ),
    "power": case(
        mm.power,
        null=moments(),
        alternative_moments=moments(ALT),
        kind=choice("covariance"),
        j=section(2),
        M=count(M).but(one_record=1),
        alpha=probability(0.05),
        k=Arg(None, {"out of range": N, "fraction": 0.5}),
        gamma=Arg(None, {"out of range": 1, "fraction": 0.5}),
        alternative=choice("two-sided"),
    ),
}

EXEMPT = {
    "EigenDirections": "a named tuple the library returns",
    "MomentZScores": "a named tuple the library returns",
    "SectionMoments": "a named tuple the library returns",
    "SingularDirections": "a named tuple the library returns",
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests("course.mismatched", TABLE, EXEMPT)
