"""Bad input to every public callable of course.quadform (see tests/bad_input.py).

The laws are scale-invariant: weights, ``sigma`` and covariances at the limits
of floating point (``1e±300``) must give a finite answer, never NaN or an
``OverflowError`` (issue 15, items 2 and 3).
"""

import dataclasses

import numpy as np
from bad_input import array, case, count, covariance, generator, matrix, module_tests, real

from course import quadform

WEIGHTS = np.array([1.0, 0.5, 2.0])
LAW = quadform.WeightedChiSquare(WEIGHTS)
A_FORM = np.array([[2.0, 0.3], [0.3, 1.0]])
COV = np.array([[1.0, 0.2], [0.2, 0.5]])
FORM = quadform.QuadraticForm(A_FORM, mean=[0.1, -0.2], cov=COV)


def weights(value=WEIGHTS):
    """Weights of the chi-square terms: real, non-empty; any scale gives the same law."""
    base = array(value, ndims=(1,))
    return dataclasses.replace(base, extreme={"1e300": value * 1e300, "1e-300": value * 1e-300})


def point(value=2.5):
    """Where a law is evaluated: real numbers (NaN refused)."""
    return array(value, ndims="any", shaped=False, empty_ok=True).but(drop=("inf",))


def dofs(value=(1, 2, 1)):
    """Degrees of freedom per term: a scalar broadcasts; Imhof's integral takes real h > 0."""
    return array(np.asarray(value, dtype=float), ndims=(1,), none_ok=True).but(
        drop=("scalar",), negative=[1.0, -1.0, 1.0]
    )


def noncentralities(value=(0.0, 1.0, 0.5)):
    return array(np.asarray(value, dtype=float), ndims=(1,), none_ok=True).but(
        drop=("scalar",), negative=[0.0, -1.0, 0.5]
    )


def tolerance(value=0.0):
    return real(value).but(negative=-1e-6)


def sigma(value=0.0):
    base = real(value).but(negative=-1.0)
    return dataclasses.replace(base, extreme={"1e300": 1e300, "1e-300": 1e-300})


def where(value=2.5):
    """The point c: a number or an array of them (the integrals are vectorised)."""
    return real(value).but(drop=("inf", "sequence"))


def integral_args(function):
    return case(
        function,
        c=where(),
        weights=weights(),
        dof=dofs(),
        noncentrality=noncentralities(),
        sigma=sigma(),
        atol=tolerance(),
        rtol=tolerance(1e-8),
    )


def approximation_args(function):
    return case(
        function,
        c=where(),
        weights=weights(),
        dof=dofs(),
        noncentrality=noncentralities(),
        sigma=sigma(),
    )


BATCH_WEIGHTS = np.array([[1.0, 0.5, 2.0], [0.3, -1.0, 1.5], [2.0, 0.0, 1.0]])


def batch_args(function):
    """Many laws (one row of weights each) at one point each, or at points per law."""
    weights = array(BATCH_WEIGHTS, ndims=(2,))
    return case(
        function,
        c=array(np.array([2.5, 1.0, 4.0]), ndims=(0, 1, 2)).but(drop=("inf",)),
        weights=dataclasses.replace(
            weights, extreme={"1e300": BATCH_WEIGHTS * 1e300, "1e-300": BATCH_WEIGHTS * 1e-300}
        ),
        dof=array(np.array([1.0, 2.0, 1.0]), ndims=(0, 1, 2), none_ok=True).but(
            negative=[1.0, -1.0, 1.0]
        ),
        noncentrality=array(np.array([0.0, 1.0, 0.5]), ndims=(0, 1, 2), none_ok=True).but(
            negative=[0.0, -1.0, 0.5]
        ),
        sigma=sigma(),
        atol=tolerance(),
        rtol=tolerance(1e-8),
    )


TABLE = {
    "imhof_cdf": integral_args(quadform.imhof_cdf),
    "imhof_sf": integral_args(quadform.imhof_sf),
    "imhof_cdf_batch": batch_args(quadform.imhof_cdf_batch),
    "imhof_sf_batch": batch_args(quadform.imhof_sf_batch),
    "liu_tang_zhang_cdf": approximation_args(quadform.liu_tang_zhang_cdf),
    "liu_tang_zhang_sf": approximation_args(quadform.liu_tang_zhang_sf),
    "inversion_integrands": case(
        quadform.inversion_integrands,
        c=real(2.5),
        weights=weights(),
        dof=dofs(),
        noncentrality=noncentralities(),
        u=array([0.1, 0.5, 1.0], none_ok=True).but(drop=("empty", "longer")),
    ),
    "WeightedChiSquare": case(
        quadform.WeightedChiSquare,
        weights=weights(),
        dof=dofs(),
        noncentrality=noncentralities(),
        sigma=sigma(),
        offset=real(0.0),
        atol=tolerance(),
        rtol=tolerance(1e-8),
    ),
    "WeightedChiSquare.approx_cdf": case(LAW.approx_cdf, x=point()),
    "WeightedChiSquare.approx_sf": case(LAW.approx_sf, x=point()),
    "WeightedChiSquare.cumulant": case(LAW.cumulant, j=count(2)),
    "WeightedChiSquare.mean": case(LAW.mean),
    "WeightedChiSquare.var": case(LAW.var),
    "QuadraticForm": case(
        quadform.QuadraticForm,
        A=matrix(A_FORM).but(asymmetric=np.array([[2.0, 0.9], [0.3, 1.0]])),
        mean=array(np.array([0.1, -0.2]), ndims=(1,), none_ok=True),
        cov=covariance(COV, psd=True, none_ok=True, extreme=True),  # x may be degenerate
        atol=tolerance(),
        rtol=tolerance(1e-8),
    ),
    "QuadraticForm.mean": case(FORM.mean),
    "QuadraticForm.var": case(FORM.var),
    "QuadraticForm.rvs_direct": case(
        FORM.rvs_direct,
        size=count(5, minimum=0).but(drop=("sequence",)),
        rng=generator(0),
    ),
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests("course.quadform", TABLE, exempt={})


# ---------------------------------------------------------------------------
# overflowing degrees of freedom (issue 38): no OverflowError, the normal limit where the
# law is normal to double precision, and no normal limit where it is not
# ---------------------------------------------------------------------------
def test_imhof_at_1e200_degrees_of_freedom_just_above_the_mean():
    """``imhof_cdf`` raised OverflowError at dof 1e200 and c just above the mean, and gave
    0.0 (with a warning) at the mean itself; the law is normal to double precision."""
    import warnings

    from course import quadform

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for dof in (1e41, 1e200, 1e300):
            assert quadform.imhof_cdf(dof * (1 + 1e-9), [1.0], [dof]) == 1.0
            assert quadform.imhof_cdf(dof, [1.0], [dof]) == 0.5
            assert quadform.imhof_sf(dof * (1 - 1e-9), [1.0], [dof]) == 1.0
        # and a noncentral term of huge non-centrality beside a small one
        assert quadform.imhof_cdf(1.0, [1.0, 0.5], [1e200, 3.0], [0.0, 1e199]) == 0.0
