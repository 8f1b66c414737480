"""Validating a model with the residuals of a mismatched Kalman filter over many records.

The filter is often deliberately simpler than the model it is meant to
validate (fewer states, other noise levels).  Its residuals are then
correlated, non-zero mean and non-stationary *even when the model is right*,
so whiteness and chi-square tests do not apply.  Y. Baram (1980), "Model
validation using mismatched filters" (full reference in the course
bibliography, :doc:`/docs/bibliography`), uses many independent data records
instead: at a fixed time ``j`` the residuals of different records (a
*cross-record section*) are independent and identically distributed, and the
mean, covariance and correlation statistics of a section are quadratic forms
in normal variables whose laws Imhof's method computes
(:mod:`course.quadform`).

Notation: ``M^0`` is the model under test (``true_model`` when it holds),
``M^1`` the model inside the filter (``filter_model``), ``M^2`` an
alternative for the power.  Times are ``t = 0, ..., N-1`` as in
:mod:`course.filters` (the paper's ``j = 1, ..., N``).

Public API
----------
residual_moments(true_model, filter_model, N) -> ResidualMoments
    Means ``m_t``, covariances ``P_t`` and cross-covariances ``C(j, k)`` of the
    residuals, by the augmented-system recursion of the paper's appendix with
    its misprints corrected (see :data:`APPENDIX_MISPRINTS`).
residual_moments_as_printed(true_model, filter_model, N, misprint)
    The same recursion with one misprint of the appendix put back, to
    measure its effect against Monte Carlo (teaching only).
simulate_records(true_model, filter_model, M, N, rng) -> (M, N, p)
    Residuals of the filter on M independent records of the true model.
moment_zscores(residuals, moments)
    Standardised differences between sample and predicted moments (the
    Monte Carlo check of a moment computation).
principal_directions, mean_statistic, covariance_statistic, correlation_statistic
    The statistics of a cross-record section (Baram (2.5)-(2.17), corrected).
mean_matrix, covariance_matrix, correlation_matrix, section_moments, pair_moments
    The same statistics as quadratic forms ``phi^T A phi`` (Baram section 3).
statistic_law
    The law of a statistic under a model pair (exact, via Imhof's method).
mean_test, covariance_test, correlation_test, power
    Tests with critical regions from the law under ``(M^0, M^1)`` and power
    against ``(M^2, M^1)``; each test returns a :class:`~course.results.TestResult`.
"""

from course.mismatched._moments import (
    APPENDIX_MISPRINTS,
    EigenDirections,
    MomentZScores,
    ResidualMoments,
    SectionMoments,
    SingularDirections,
    moment_zscores,
    residual_moments,
    residual_moments_as_printed,
    simulate_records,
)
from course.mismatched._quadratic_forms import (
    correlation_matrix,
    covariance_matrix,
    mean_matrix,
    pair_moments,
    section_moments,
    statistic_law,
)
from course.mismatched._statistics import (
    correlation_statistic,
    covariance_statistic,
    mean_statistic,
    principal_directions,
)
from course.mismatched._tests import correlation_test, covariance_test, mean_test, power

__all__ = [
    "APPENDIX_MISPRINTS",
    "EigenDirections",
    "MomentZScores",
    "ResidualMoments",
    "SectionMoments",
    "SingularDirections",
    "correlation_matrix",
    "correlation_statistic",
    "correlation_test",
    "covariance_matrix",
    "covariance_statistic",
    "covariance_test",
    "mean_matrix",
    "mean_statistic",
    "mean_test",
    "moment_zscores",
    "pair_moments",
    "power",
    "principal_directions",
    "residual_moments",
    "residual_moments_as_printed",
    "section_moments",
    "simulate_records",
    "statistic_law",
]
