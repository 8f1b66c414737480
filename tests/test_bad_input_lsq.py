"""Bad input to every public callable of course.lsq (see tests/bad_input.py).

``lsq.noncentrality`` is ``course.chi2.noncentrality``, tested there.
"""

import numpy as np
import pytest
from bad_input import (
    Arg,
    array,
    case,
    choice,
    count,
    covariance,
    generator,
    matrix,
    module_tests,
    obj,
    probability,
    vector,
)

from course import lsq

T = np.arange(1.0, 9.0)
A = np.column_stack([np.ones(8), T])
QYY = 0.5 * np.eye(8) + 0.3 * np.exp(-np.abs(T[:, None] - T[None, :]))
Y = A @ [1.0, 0.5] + np.array([0.3, -0.2, 0.1, 0.4, -0.5, 0.2, -0.1, 0.0])
FIT = lsq.fit(A, Y, QYY)
W = lsq.w_tests(FIT)
#: Two bias columns (a jump of the last three observations, an outlier in the second).
C2 = np.column_stack([np.r_[np.zeros(5), np.ones(3)], np.eye(8)[:, 1]])
MDB2 = lsq.minimal_detectable_bias(FIT, C2)
DIA_MC = lsq.dia_monte_carlo(FIT, size=20, rng=np.random.default_rng(0))


def bias_columns(value=C2):
    # one more column is another valid alternative (q = 3 <= m - n), not a bad input
    return matrix(value).but(drop=("longer",))


def design(value=A):
    return Arg(value, dict(matrix(value).bad), extreme={"A * 1e-300": value * 1e-300})


def fit_arg(value=FIT):
    return obj(value).but(array=np.eye(2))


TABLE = {
    "fit": case(lsq.fit, A=design(), y=array(Y), Qyy=covariance(QYY, none_ok=True)),
    "overall_model_test": case(lsq.overall_model_test, fit=fit_arg(), alpha=probability(0.05)),
    "w_tests": case(
        lsq.w_tests, fit=fit_arg(), alpha=probability(0.05), variance=choice("estimated")
    ),
    "glr_test": case(
        lsq.glr_test,
        fit=fit_arg(),
        C=bias_columns(),
        alpha=probability(0.05),
        variance=choice("known"),
    ),
    "alternative_law": case(
        lsq.alternative_law,
        fit=fit_arg(),
        C=bias_columns(),
        bias=vector([0.5, 0.2]),
        variance=choice("estimated"),
    ),
    "b_method": case(
        lsq.b_method,
        alpha_1=probability(0.001),
        power=probability(0.8),
        q=count(2).but(drop=("sequence",)),
    ),
    "minimal_detectable_bias": case(
        lsq.minimal_detectable_bias,
        fit=fit_arg(),
        C=bias_columns(),
        alpha=probability(0.001),
        power=probability(0.8),
    ),
    "MinimalDetectableBias.along": case(MDB2.along, direction=vector([1.0, 0.5])),
    "external_reliability": case(
        lsq.external_reliability, fit=fit_arg(), C=bias_columns(), bias=vector([0.5, 0.2])
    ),
    "dia": case(
        lsq.dia,
        fit=fit_arg(),
        candidates=obj([C2[:, 0], C2], none_ok=True),
        alpha=probability(0.05),
    ),
    "DIAMonteCarlo.identification_rate": case(
        DIA_MC.identification_rate, k=Arg(2, {"fraction": 2.5, "out of range": 8, "None": None})
    ),
    "dia_monte_carlo": case(
        lsq.dia_monte_carlo,
        fit=fit_arg(),
        candidates=obj(None, none_ok=True),
        alpha=probability(0.05),
        bias=vector(np.eye(8)[3], none_ok=True),
        size=count(50),
        rng=generator(0),
    ),
    "WTestResult.test": case(
        W.test, i=Arg(2, {"fraction": 2.5, "out of range": 8, "None": None, "text": "2"})
    ),
    "WTestResult.tests": case(W.tests),
    "WTestResult.summary": case(W.summary),
    "data_snooping": case(
        lsq.data_snooping,
        fit=fit_arg(),
        alpha=probability(0.01),
        max_removals=count(2, minimum=0, none_ok=True),
    ),
    "SnoopingResult.summary": case(lsq.data_snooping(lsq.fit(A, Y, QYY)).summary),
    "mdb": case(lsq.mdb, fit=fit_arg(), alpha=probability(0.001), power=probability(0.8)),
    "confidence_band": case(
        lsq.confidence_band,
        fit=fit_arg(),
        A_new=matrix(A[:3]).but(drop=("empty",)),
        level=probability(0.95),
    ),
    "load_sea_level": case(
        lsq.load_sea_level,
        case=Arg(0, {"fraction": 0.5, "out of range": 9, "None": None, "text": "0"}),
    ),
}

EXEMPT = {
    "BMethod": "a named tuple the library returns",
    "ConfidenceBand": "a named tuple the library returns",
    "DIAMonteCarlo": "a result the library returns",
    "DIAResult": "a result the library returns",
    "ExternalReliability": "a named tuple the library returns",
    "MinimalDetectableBias": "a result the library returns",
    "LeastSquaresFit": "a result the library returns",
    "SnoopingResult": "a result the library returns",
    "WTestResult": "a result the library returns",
    "load_mauna_loa_co2": "takes no argument: there is no input to refuse",
}

XFAIL: dict[str, str] = {}  # every case passes since least squares was rewritten (issue 15)

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests("course.lsq", TABLE, EXEMPT, XFAIL)


# ---------------------------------------------------------------------------
# scaled and overflowing input (issue 38): right where the answer is representable,
# else refused with a message that says what to rescale
# ---------------------------------------------------------------------------
E3 = np.eye(8)[:, 3]


def _power(C, bias, variance="known"):
    law = lsq.alternative_law(FIT, C, bias, variance)
    return lsq.glr_test(FIT, C, variance=variance).power(law)


SCALED = {
    "glr_test, C x 1e160": (
        lambda: lsq.glr_test(FIT, C2 * 1e160).statistic,
        lsq.glr_test(FIT, C2).statistic,
    ),
    "glr_test, C x 1e-200": (
        lambda: lsq.glr_test(FIT, C2 * 1e-200).statistic,
        lsq.glr_test(FIT, C2).statistic,
    ),
    "minimal_detectable_bias, C x 1e160": (
        lambda: lsq.minimal_detectable_bias(FIT, C2 * 1e160).lengths * 1e160,
        MDB2.lengths,
    ),
    "minimal_detectable_bias, C x 1e-200": (
        lambda: lsq.minimal_detectable_bias(FIT, C2 * 1e-200).lengths * 1e-200,
        MDB2.lengths,
    ),
    "dia, candidates x 1e160 and x 1e-200": (
        lambda: lsq.dia(FIT, [C2 * 1e160, E3 * 1e-200]).statistics,
        lsq.dia(FIT, [C2, E3]).statistics,
    ),
    "alternative_law, bias 1e200: power": (lambda: _power(E3, 1e200), 1.0),
    "alternative_law, bias 1e200, F: power": (lambda: _power(E3, 1e200, "estimated"), 1.0),
    "alternative_law, bias 1e10 (λ beyond scipy's ncx2): power": (
        lambda: _power(C2, [1e10, 0]),
        1.0,
    ),
    "MinimalDetectableBias.along([1e300, 1e300])": (
        lambda: MDB2.along([1e300, 1e300]),
        MDB2.along([1.0, 1.0]),
    ),
    "external_reliability, C x 1e300: overall": (
        lambda: lsq.external_reliability(FIT, C2 * 1e300, [0.5, 0.2]).overall / 1e300,
        lsq.external_reliability(FIT, C2, [0.5, 0.2]).overall,
    ),
    "b_method(q=10**12): alpha_q": (
        # ncx2(q, λ0) against chi2(q) at q = 1e12 shifts by λ0/sqrt(2q) standard deviations
        lambda: lsq.b_method(0.001, 0.8, q=10**12).alpha_q,
        0.7999966198,
    ),
}


@pytest.mark.parametrize("name", SCALED)
def test_scaled_input_gives_the_unscaled_answer(name):
    call, expected = SCALED[name]
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        got = call()
    np.testing.assert_allclose(got, expected, rtol=1e-9)


OVERFLOWING = {
    "glr_test, C x 1.79e308 (whitened C overflows)": (
        lambda: lsq.glr_test(FIT, C2 * 1.79e308),
        "rescale the columns of C",
    ),
    "b_method, power beyond 1 - 1e-15": (lambda: lsq.b_method(0.001, 1 - 2**-53), "power"),
    "minimal_detectable_bias, power beyond 1 - 1e-15": (
        lambda: lsq.minimal_detectable_bias(FIT, C2, power=1 - 2**-53),
        "power",
    ),
}


@pytest.mark.parametrize("name", OVERFLOWING)
def test_unrepresentable_input_is_refused_with_a_message(name):
    call, argument = OVERFLOWING[name]
    with pytest.raises(ValueError, match=argument):
        call()
