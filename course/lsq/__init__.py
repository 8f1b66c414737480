"""Least-squares residuals and the tests built on them.

This module follows Chapter 10 "Validation" of Tiberius, van der Marel,
Reudink and van Leijen (2021), *Surveying and Mapping*, TU Delft Open
Textbook (full reference in the course bibliography, :doc:`/docs/bibliography`):
the model of observation equations

.. math:: E(\\underline{y}) = A x, \\qquad D(\\underline{y}) = Q_{yy},

its best linear unbiased estimate, the least-squares residuals, the overall
model test (a chi-square test of the weighted squared norm of the residuals),
Baarda's w-test for single outliers, data snooping, the minimal detectable
bias (internal reliability) and the confidence band of the fitted model.

Public functions
----------------
fit
    Weighted least squares (BLUE): estimates, residuals and their covariances.
overall_model_test
    ``T = ê^T Qyy^{-1} ê ~ chi2(m - n)`` under H0.
w_tests
    One normalised residual per observation, two-sided normal test (or
    Student's t when the variance factor is estimated).
data_snooping
    Remove the most suspicious observation and refit, until nothing is rejected.
mdb
    The minimal detectable bias (the non-centrality it rests on is
    :func:`course.chi2.noncentrality`).
confidence_band
    Fitted values at new design rows with their confidence half-widths.
glr_test
    The test of a q-dimensional alternative ``E(y) = Ax + C∇`` (T_q, or F with
    an estimated variance); ``alternative_law`` gives its power.
b_method
    Baarda's B-method: the level of a q-dimensional test that detects the
    w-tests' reference bias with the same power.
minimal_detectable_bias
    The minimal detectable biases of a q-dimensional alternative;
    ``external_reliability`` their effect on x̂.
dia
    Detection, identification and adaptation; ``dia_monte_carlo`` the law of
    the DIA estimator.
load_sea_level
    The four MUDE sea-level data sets shipped with the course.
load_mauna_loa_co2
    The weekly Mauna Loa CO2 record 1958-2001 shipped with the course.

Numerics
--------
Everything is computed in the *whitened* problem. With a factor
``Qyy = L L^T`` (a vector of standard deviations for diagonal Qyy, a banded
Cholesky factor for sparse Qyy, a dense Cholesky factor otherwise, see
:func:`course.linalg.covariance_factor`) the model becomes
``L^{-1} y = (L^{-1} A) x + ε`` with ``D(ε) = I``; a thin QR factorisation
``L^{-1} A = Q1 R`` (Q1 of shape m x n) then gives the estimate
``x̂ = R^{-1} Q1^T L^{-1} y`` by a triangular solve, the covariance of the
estimate ``Qxx = R^{-1} R^{-T}``, the whitened residuals
``ẽ = L^{-1} y - Q1 Q1^T L^{-1} y`` and the w-test quantities, without ever
forming ``(A^T Qyy^{-1} A)^{-1}``, ``Qyy^{-1}`` or any m x m matrix. The
tests need only diagonals, so a fit costs O(m n²) time and O(m n) memory for
diagonal Qyy; the m x m matrices ``Qee`` and ``Qyy_hat`` are computed when
asked for.
"""

from course.lsq._alternatives import (
    BMethod,
    ExternalReliability,
    MinimalDetectableBias,
    alternative_law,
    b_method,
    external_reliability,
    glr_test,
    minimal_detectable_bias,
)
from course.lsq._data import load_mauna_loa_co2, load_sea_level
from course.lsq._dia import DIAMonteCarlo, DIAResult, dia, dia_monte_carlo
from course.lsq._fit import LeastSquaresFit, fit
from course.lsq._reliability import ConfidenceBand, confidence_band, mdb
from course.lsq._tests import (
    SnoopingResult,
    WTestResult,
    data_snooping,
    overall_model_test,
    w_tests,
)

__all__ = [
    "BMethod",
    "ConfidenceBand",
    "DIAMonteCarlo",
    "DIAResult",
    "ExternalReliability",
    "LeastSquaresFit",
    "MinimalDetectableBias",
    "SnoopingResult",
    "WTestResult",
    "alternative_law",
    "b_method",
    "confidence_band",
    "data_snooping",
    "dia",
    "dia_monte_carlo",
    "external_reliability",
    "fit",
    "glr_test",
    "load_mauna_loa_co2",
    "load_sea_level",
    "mdb",
    "minimal_detectable_bias",
    "overall_model_test",
    "w_tests",
]
