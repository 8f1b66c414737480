"""Bad input to every public callable of course.validation and course.linalg.

See tests/bad_input.py.  The checks of ``course.validation`` refuse a bad
*value* with a message that names the argument they were given (``"y"``
below); the building blocks of ``course.linalg`` refuse bad arrays like every
other public function.
"""

import dataclasses

import numpy as np
from bad_input import (
    Arg,
    array,
    case,
    covariance,
    flag,
    generator,
    matrix,
    module_tests,
    positive,
    real,
    vector,
)
from scipy import stats

from course import linalg, validation

A = np.column_stack([np.ones(4), np.arange(1.0, 5.0)])
B = np.array([14.0, 20.0, 20.0, 24.0])
S = np.array([[4.0, 2.0], [2.0, 2.0]])
L = np.linalg.cholesky(S)
V = np.array([[2.0, 2.0], [4.0, 3.0]])


def value_named_y(value, bad):
    """The value a check is given; its message must name ``name="y"``."""
    return Arg(value, bad, names=("y",))


ARRAY_BAD = {"None": None, "text": "1 2", "NaN": [1.0, np.nan], "inf": [np.inf], "complex": [1j]}
COUNT_BAD = {"fraction": 2.5, "NaN": np.nan, "bool": True, "text": "3", "None": None, "zero": 0}
REAL_BAD = {"NaN": np.nan, "inf": np.inf, "text": "1", "None": None, "sequence": [1.0, 2.0]}

TABLE = {
    # -- validation ---------------------------------------------------------------
    "as_float_array": case(
        validation.as_float_array, value=value_named_y([1.0, 2.0], ARRAY_BAD), name="y", ndim=None
    ),
    "as_vector": case(
        validation.as_vector,
        value=value_named_y([1.0, 2.0], {**ARRAY_BAD, "2-D": [[1.0, 2.0]], "long": [1.0, 2, 3]}),
        name="y",
        size=2,
    ),
    "as_matrix": case(
        validation.as_matrix,
        value=value_named_y(np.eye(2), {**ARRAY_BAD, "1-D": [1.0, 2.0], "shape": np.ones((2, 3))}),
        name="y",
        shape=(None, 2),
    ),
    "as_covariance": case(
        validation.as_covariance,
        value=Arg(
            S,
            dict(covariance(S).bad),
            names=("y",),
        ),
        name="y",
        size=2,
        allow_singular=flag(False),
    ),
    "as_covariance_stack": case(
        validation.as_covariance_stack,
        value=Arg(
            np.stack([S, 2 * S]),
            dict(covariance(np.stack([S, 2 * S]), min_ndim=2).bad),
            names=("y",),
        ),
        name="y",
        size=2,
        allow_singular=flag(False),
    ),
    "as_std": case(
        validation.as_std,
        value=value_named_y(0.2, {**REAL_BAD, "zero": 0.0, "1e300": 1e300, "1e-300": 1e-300}),
        name="y",
    ),
    "as_size": case(
        validation.as_size,
        value=value_named_y(
            (2, 3), {"fraction": 2.5, "negative": (2, -1), "text": "3", "NaN": np.nan}
        ),
        name="y",
    ),
    "as_flag": case(
        validation.as_flag,
        value=value_named_y(True, {"text": "no", "None": None, "number": 1}),
        name="y",
    ),
    "as_callable": case(
        validation.as_callable, value=value_named_y(np.sin, {"None": None, "number": 3.0}), name="y"
    ),
    "as_law": case(
        validation.as_law,
        value=value_named_y(stats.norm(), {"None": None, "number": 3.0}),
        name="y",
    ),
    "as_count": case(validation.as_count, value=value_named_y(3, COUNT_BAD), name="y"),
    "as_index": case(
        validation.as_index,
        value=value_named_y(1, {**COUNT_BAD, "out of range": 3, "zero": -1}),
        name="y",
        size=3,
    ),
    "as_indices": case(
        validation.as_indices,
        values=value_named_y([0, 2], {"out of range": [3], "repeated": [0, 0], "text": "0"}),
        name="y",
        size=3,
    ),
    "as_finite": case(validation.as_finite, value=value_named_y(1.5, REAL_BAD), name="y"),
    "as_positive": case(
        validation.as_positive, value=value_named_y(1.5, {**REAL_BAD, "zero": 0.0}), name="y"
    ),
    "as_variance": case(
        validation.as_variance, value=value_named_y(1.5, {**REAL_BAD, "negative": -1.0}), name="y"
    ),
    "as_probability": case(
        validation.as_probability,
        value=value_named_y(0.05, {**REAL_BAD, "one": 1.0, "zero": 0.0}),
        name="y",
    ),
    "as_generator": case(validation.as_generator, rng=generator()),
    # -- linalg ---------------------------------------------------------------------
    "readonly": case(linalg.readonly, array=Arg(np.zeros(2), {"list": [1.0], "None": None})),
    "symmetrize": case(linalg.symmetrize, P=array(S, min_ndim=2)),
    "psd_sqrt": case(linalg.psd_sqrt, C=covariance(S, psd=True, extreme=True)),
    "cholesky_lower": case(
        linalg.cholesky_lower, matrix=covariance(S, extreme=True), name="matrix"
    ),
    "covariance_factor": case(
        linalg.covariance_factor,
        value=dataclasses.replace(
            covariance(S, none_ok=True).but(drop=("1-D",)), names=("S",)
        ),  # a 1-D value is valid: the variances of uncorrelated observations
        name="S",
        size=Arg(2, {"fraction": 2.5, "None": None, "text": "2", "negative": -1}),
    ),
    "cholesky_factor": case(linalg.cholesky_factor, S=covariance(S, min_ndim=2), name="S"),
    "whiten": case(
        linalg.whiten,
        L=matrix(L).but(singular=np.zeros((2, 2))),
        values=array([2.0, 2.0], ndims=(1, 2)),
    ),
    "whiten_vectors": case(
        linalg.whiten_vectors,
        L=array(L, min_ndim=2).but(singular=np.zeros((2, 2))),
        vectors=array(V, min_ndim=1),
    ),
    "whitened_squared_norms": case(
        linalg.whitened_squared_norms,
        L=array(L, min_ndim=2).but(singular=np.zeros((2, 2))),
        vectors=array(V, min_ndim=1),
    ),
    "solve_spd": case(
        linalg.solve_spd, matrix=covariance(S), rhs=array([2.0, 2.0], ndims=(1, 2)), name="matrix"
    ),
    "rank_tolerance": case(
        linalg.rank_tolerance,
        shape=Arg((10, 2), {"None": None, "negative": (-1, 2), "fraction": (2.5, 2), "text": "ab"}),
        largest=real(1.0).but(negative=-1.0),
        rtol=positive(1e-12, none_ok=True),
    ),
    "numerical_rank": case(
        linalg.numerical_rank,
        singular_values=vector([3.0, 1e-20], shaped=False, empty_ok=True).but(negative=[-1.0]),
        shape=Arg((5, 2), {"None": None, "negative": (-1, 2), "fraction": (2.5, 2)}),
        rtol=positive(1e-12, none_ok=True),
    ),
    "matrix_rank": case(
        linalg.matrix_rank,
        A=matrix(A, shaped=False, empty_ok=True),
        rtol=positive(1e-12, none_ok=True),
    ),
    "range_basis": case(
        linalg.range_basis,
        A=matrix(A, shaped=False, empty_ok=True),
        rtol=positive(1e-12, none_ok=True),
    ),
    "column_rank_deficiency": case(
        linalg.column_rank_deficiency,
        A=matrix(A, shaped=False, empty_ok=True),
        rtol=positive(1e-12, none_ok=True),
    ),
    "check_full_column_rank": case(
        linalg.check_full_column_rank, A=matrix(A, shaped=False), name="A"
    ),
    "qr_solve": case(
        linalg.qr_solve, A=matrix(A, shaped=False), b=array(B, ndims=(1, 2)), full=flag(False)
    ),
    "lstsq_min_norm": case(
        linalg.lstsq_min_norm,
        A=matrix(A, shaped=False),
        b=array(B, ndims=(1, 2)),
        rtol=positive(1e-12, none_ok=True),
    ),
}

EXEMPT = {
    "InputTypeError": "an exception class",
    "QRSolution": "a named tuple the library returns",
    "MinNormSolution": "a named tuple the library returns",
    "CovarianceFactor": "built only by covariance_factor, which validates (case above)",
    **{
        f"CovarianceFactor.{method}": "works on arrays lsq.fit has already validated"
        for method in (
            "dense",
            "diagonal",
            "inverse_diagonal",
            "take",
            "whiten",
            "whiten_transpose",
            "whiten_unit",
        )
    },
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests(("course.validation", "course.linalg"), TABLE, EXEMPT)
