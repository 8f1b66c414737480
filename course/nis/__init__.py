"""The NIS, the NIS matrix and the exact laws of its extreme eigenvalues.

A Kalman filter whose model is right produces innovations
``eps_k ~ N(0, S_k)``, independent over time.  Whitening them with the lower
Cholesky factor ``B_k`` of ``S_k`` (``S_k = B_k B_k^T``) gives
``z_k = B_k^{-1} eps_k ~ N(0, I_m)``.  Two statistics summarise ``K`` steps:

* the time-averaged **NIS** ``eps_bar = (1/K) sum_k eps_k^T S_k^{-1} eps_k``,
  with ``K * eps_bar ~ chi2(m K)``;
* the **NIS matrix** ``Pi = (1/K) sum_k z_k z_k^T``, with
  ``K * Pi ~ W_m(K, I)`` (a Wishart matrix), whose trace is ``eps_bar``.

The scalar NIS only sees the trace of ``Pi``.  The extreme eigenvalues
``lambda_min(Pi)`` and ``lambda_max(Pi)`` see a wrong innovation covariance
in any direction, and :func:`extreme_eigenvalue` gives their exact laws
(Chiani's Pfaffian closed forms, evaluated stably in double precision in
an orthonormal Laguerre basis, validated for ``m <= 30`` and ``K <= 10^5``
and refused beyond).

This package is the one home of the NIS chain: NIS -> window -> threshold ->
alarm.  The names live in private single-topic modules and are re-exported
here.

Statistics (``_statistics``)
    :func:`nis`, :func:`nees`, :func:`nis_matrix`, :func:`nis_matrix_eigenvalues`.
Windowed NIS (``_windowed``)
    :func:`windowed_sum`, :func:`windowed_nis`, :func:`windowed_nis_threshold`,
    :func:`windowed_chi2_test`.
Alarms (``_alarms``)
    :func:`empirical_threshold`, :func:`alarm_statistics`, :class:`AlarmStatistics`.
Laws (``_laws``, numerics in ``_pfaffians``)
    :func:`extreme_eigenvalue` (exact, or the Tracy-Widom shifted-gamma
    approximation), :class:`ExtremeEigenvalue`,
    :class:`TracyWidomApproximation`, :func:`prob_eigenvalues_within`,
    :func:`simulate_extreme_eigenvalues`; :data:`EXACT_LAW_LIMITS`, the sizes
    where the exact laws are validated (and served).
Tests and thresholds (``_consistency_tests``)
    :func:`nis_test`, :func:`nis_matrix_test`, :func:`nis_critical_values`,
    :func:`nis_matrix_critical_values`, :func:`consistency_interval`.

References
----------
.. [F] R. Forsling, "Matrix-Valued Statistics for Detecting Complex Model
   Errors in State Estimation", poster, eqs. (2)-(4) (full reference in the
   course bibliography, :doc:`/docs/bibliography`).
.. [C14] M. Chiani, "Distribution of the largest eigenvalue for real Wishart
   and Gaussian random matrices and a simple approximation for the
   Tracy-Widom distribution", J. Multivariate Anal. 129 (2014) 69-81.
.. [C17] M. Chiani, "On the probability that all eigenvalues of Gaussian,
   Wishart, and double Wishart random matrices lie within an interval",
   IEEE Trans. Inf. Theory 63(7) (2017) 4521-4531.
.. [J] I. M. Johnstone, "On the distribution of the largest eigenvalue in
   principal components analysis", Ann. Statist. 29 (2001) 295-327.
.. [BS] Y. Bar-Shalom, X. R. Li, T. Kirubarajan, "Estimation with
   Applications to Tracking and Navigation", Wiley 2001, Sec. 5.4.
"""

from course.nis._alarms import AlarmStatistics, alarm_statistics, empirical_threshold
from course.nis._consistency_tests import (
    consistency_interval,
    nis_critical_values,
    nis_matrix_critical_values,
    nis_matrix_test,
    nis_test,
)
from course.nis._laws import (
    EXACT_LAW_LIMITS,
    TW1_GAMMA,
    EigenvaluePair,
    ExtremeEigenvalue,
    TracyWidomApproximation,
    extreme_eigenvalue,
    prob_eigenvalues_within,
    simulate_extreme_eigenvalues,
)

# The Pfaffian itself is shown at work in notebook 05.
from course.nis._pfaffians import _pfaffian  # noqa: F401
from course.nis._statistics import nees, nis, nis_matrix, nis_matrix_eigenvalues
from course.nis._windowed import (
    windowed_chi2_test,
    windowed_nis,
    windowed_nis_threshold,
    windowed_sum,
)

__all__ = [
    "EXACT_LAW_LIMITS",
    "TW1_GAMMA",
    "AlarmStatistics",
    "EigenvaluePair",
    "ExtremeEigenvalue",
    "TracyWidomApproximation",
    "alarm_statistics",
    "consistency_interval",
    "empirical_threshold",
    "extreme_eigenvalue",
    "nees",
    "nis",
    "nis_critical_values",
    "nis_matrix",
    "nis_matrix_critical_values",
    "nis_matrix_eigenvalues",
    "nis_matrix_test",
    "nis_test",
    "prob_eigenvalues_within",
    "simulate_extreme_eigenvalues",
    "windowed_chi2_test",
    "windowed_nis",
    "windowed_nis_threshold",
    "windowed_sum",
]
