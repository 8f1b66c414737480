"""Test quantities for fault diagnosis: prediction errors, estimates, likelihoods.

This package follows a Linköping University fault-diagnosis lecture on test
quantities ("the LiU lecture", Swedish slides; full reference in the course
bibliography, :doc:`/docs/bibliography`).  Its one idea: a *test quantity* is a measure of how
well the model *under the null hypothesis* of a test explains the data.  It
is zero (or small) when that model can be true and large otherwise.

The public names live in private single-topic modules and are re-exported
here, so ``from course.diagnosis import prediction_error`` is the import path
(the layout of scipy's subpackages).

Decision structures (``_structures``)
    :class:`DecisionStructure`, :class:`Hypotheses`, :func:`diagnoses`,
    :func:`diagnosis_matrix`, :func:`multiple_fault_diagnoses`,
    :func:`linear_decision_structure`.
Prediction errors (``_prediction_error``)
    :class:`RegressionFit`, :func:`least_squares_residual`,
    :func:`prediction_error`, :func:`prediction_error_test`,
    :func:`fault_noncentrality`,
    :func:`prediction_error_power`, :class:`NonlinearFit`,
    :func:`nonlinear_prediction_error`.
Parameter estimates (``_parameter_estimates``)
    :class:`ParameterEstimate`, :func:`estimate_parameters`,
    :func:`parameter_estimate_test`, :func:`regression_parameter_test`,
    :func:`parameter_estimate_power`.
Likelihood (``_likelihood``)
    :func:`normal_log_likelihood`, :func:`normal_likelihood`,
    :class:`MLResult`, :func:`maximum_likelihood`, :class:`LogLikelihoodLaw`,
    :func:`likelihood_test`, :func:`glr_test`, :func:`linear_glr_test`,
    :func:`neyman_pearson_test`, :func:`mode_log_likelihoods`,
    :class:`FaultRanking`, :func:`bayes_ranking`.
Monte Carlo (``_monte_carlo``)
    :func:`simulate_regression_records`, :func:`linear_test_statistics`,
    :class:`IsolationResult`, :func:`isolation_monte_carlo`.
The lecture's dynamic examples (``_beta_example``, ``_observer``)
    :func:`beta_drift_model`, :func:`simulate_beta_system` (the first-order
    system with a drifting parameter), :class:`ObserverResult` and
    :func:`observer_residuals` (an observer with parameter adaptation as a
    residual generator).  The recursive route (a Kalman filter on
    random-walk parameters) is :func:`course.filters.recursive_least_squares`
    and its windowed test quantity :func:`course.nis.windowed_nis`.

Conventions
-----------
The linear-in-parameters fault model of the lecture is
``y = U theta + v`` with ``v ~ N(0, sigma^2 I)``: the columns of ``U`` are the
signals ``u_i(t)``, ``nominal`` is the fault-free parameter vector and a set
of parameter indices ``free`` describes the parameter set of a null
hypothesis, ``Theta_0 = {theta : theta_j = nominal_j for every j not in
free}``.  Data may be one record ``y`` of shape ``(N,)`` or ``M`` records at
once as the rows of an ``(M, N)`` array (records leading, as everywhere in
the course); statistics then come back as length-``M`` arrays, which is what
makes the Monte Carlo studies fast.  The test-quantity functions take the data first and the
hypothesis ``(U, nominal, free)`` after it, as the statistical tests of
:mod:`scipy.stats` do; :func:`least_squares_residual`, a fit, takes the
regressors first, as :func:`course.lsq.fit` does.
"""

from course.diagnosis._beta_example import beta_drift_model, simulate_beta_system
from course.diagnosis._likelihood import (
    FaultRanking,
    LogLikelihoodLaw,
    MLResult,
    bayes_ranking,
    glr_test,
    likelihood_test,
    linear_glr_test,
    maximum_likelihood,
    mode_log_likelihoods,
    neyman_pearson_test,
    normal_likelihood,
    normal_log_likelihood,
)
from course.diagnosis._monte_carlo import (
    IsolationResult,
    isolation_monte_carlo,
    linear_test_statistics,
    simulate_regression_records,
)
from course.diagnosis._observer import ObserverResult, observer_residuals
from course.diagnosis._parameter_estimates import (
    ParameterEstimate,
    estimate_parameters,
    parameter_estimate_power,
    parameter_estimate_test,
    regression_parameter_test,
)
from course.diagnosis._prediction_error import (
    NonlinearFit,
    RegressionFit,
    fault_noncentrality,
    least_squares_residual,
    nonlinear_prediction_error,
    prediction_error,
    prediction_error_power,
    prediction_error_test,
)
from course.diagnosis._structures import (
    DecisionStructure,
    Hypotheses,
    diagnoses,
    diagnosis_matrix,
    linear_decision_structure,
    multiple_fault_diagnoses,
)

__all__ = [
    "DecisionStructure",
    "FaultRanking",
    "Hypotheses",
    "IsolationResult",
    "LogLikelihoodLaw",
    "MLResult",
    "NonlinearFit",
    "ObserverResult",
    "ParameterEstimate",
    "RegressionFit",
    "bayes_ranking",
    "beta_drift_model",
    "diagnoses",
    "diagnosis_matrix",
    "estimate_parameters",
    "fault_noncentrality",
    "glr_test",
    "isolation_monte_carlo",
    "least_squares_residual",
    "likelihood_test",
    "linear_decision_structure",
    "linear_glr_test",
    "linear_test_statistics",
    "maximum_likelihood",
    "mode_log_likelihoods",
    "multiple_fault_diagnoses",
    "neyman_pearson_test",
    "nonlinear_prediction_error",
    "normal_likelihood",
    "normal_log_likelihood",
    "observer_residuals",
    "parameter_estimate_power",
    "parameter_estimate_test",
    "prediction_error",
    "prediction_error_power",
    "prediction_error_test",
    "regression_parameter_test",
    "simulate_beta_system",
    "simulate_regression_records",
]
