"""Validating models with residuals: the library behind the course.

Importing :mod:`course` is free of side effects: no plotting backend is
chosen, no random state is touched and nothing is printed.  The modules are
imported lazily on first attribute access, so ``import course`` stays fast
and ``course.lsq`` still works.

Modules
-------
Topics (one per module of the course):

lsq
    Least-squares residuals, the overall model test, w-tests, data snooping,
    minimal detectable bias, the confidence band (module 1).
diagnosis
    Test quantities for fault diagnosis: decision structures, prediction
    errors, parameter estimates, likelihoods, the lecture's dynamic examples
    (modules 2 and 3).
filters
    State-space models, Kalman and extended Kalman filters, the Riccati
    recursion, recursive least squares (module 4).
nis
    The NIS chain (NIS, windows, thresholds, alarms), the NIS matrix and the
    exact laws of its extreme eigenvalues (modules 4 and 5).
mismatched
    Mismatched-filter tests over many records (module 6).

Shared pieces (one home each):

results
    The result vocabulary (:class:`~course.results.TestResult`), the
    :class:`~course.results.Law` protocol and the one decision path.
validation
    Every input check, with one rule per kind of input.
linalg
    Cholesky factors and whitening, QR and rank-revealing least squares, the
    one rank rule, read-only arrays.
chi2
    The chi-square law of a squared residual norm: threshold, power,
    non-centrality.
quadform
    Quadratic forms in normal variables and their exact laws (Imhof's
    method); the law behind module 6's tests.
distributions
    The base of the course's frozen laws (scipy's interface).
plotting
    Figures in the course's style (matplotlib is imported only there).
grading
    Releasing and grading the auto-graded assignments.

Sources
-------
The course follows published sources (a surveying textbook chapter, a lecture on test
quantities, a poster on the NIS matrix, Baram's paper on mismatched filters) and the results
it uses from Imhof, Davies, Chiani, Johnstone and others; each module names its sources, and
the course bibliography, :doc:`/docs/bibliography`, lists them all in full.

Conventions
-----------
Written once here; every public function follows them.

Argument order
    A *test* or *test quantity* takes the data it judges first, then the
    hypothesis it judges them against, then options: ``nis_test(innovations,
    S)``, ``prediction_error(y, U, nominal, free)``, ``mean_test(residuals,
    j, null)`` (as :mod:`scipy.stats` tests do).  A *fit* or *filter* takes
    the model first, then the data: ``lsq.fit(A, y)``,
    ``least_squares_residual(Phi, y)``, ``recursive_least_squares(Phi, y)``,
    ``kalman_filter(model, y)`` (as :func:`numpy.linalg.lstsq` does).  A
    *threshold* function takes the parameters of the null law first and
    ``alpha`` after them, and returns a float for a one-sided test and a
    :class:`~course.results.CriticalValues` ``(lower, upper)`` pair for a
    two-sided one: ``residual_threshold(dof, alpha)``,
    ``windowed_nis_threshold(window, alpha)``, ``nis_critical_values(m, K,
    alpha)``.
Batch axis
    Independent records (Monte Carlo runs, experiments) lead: ``(M, N)`` or
    ``(M, N, p)`` for ``M`` records of ``N`` samples; parameter vectors of a
    power curve are rows, ``(K, p)``.
Keyword-only parameters
    Scale parameters (``sigma``, variances ``r``, ``q``, a sampling interval
    ``Ts``) are keyword-only, so a number can never land in the wrong one.
Randomness
    Anything random takes ``rng=``: a :class:`numpy.random.Generator` or a
    seed for one; the global numpy state is never used.
Results
    Tests return a :class:`~course.results.TestResult` built by the one
    decision path (:meth:`~course.results.TestResult.from_null`), which
    unpacks as ``statistic, pvalue = result`` like scipy's; other
    multi-valued results are named objects (dataclasses or named tuples).
Names
    Every public object has one public name, in its one home module; the
    layers and the checklist for a new module are in ARCHITECTURE.md.
Laws
    Null laws are frozen, scipy-compatible distributions: ``cdf``, ``sf``,
    ``ppf``, ``isf``, ``rvs(size, rng=)``, ``support()``, ``median()``,
    ``logcdf``, ``logsf``, ``mean``, ``var``, ``interval``, ``expect``.
Input checks
    :mod:`course.validation`: bad input raises ``ValueError`` or
    ``numpy.linalg.LinAlgError`` naming the argument and what to do; a count
    is an integer (a whole float such as ``1e4`` counts as one); a
    covariance must be positive definite numerically, not only by rounding
    (:data:`course.validation.SINGULAR_RTOL`); a ``sigma`` whose square is not
    a double is refused with advice to rescale.
Changes
    The public API is what the modules' ``__all__`` list; CHANGELOG.md
    records every change to it.
"""

from importlib import import_module

#: The one place the version is written (pyproject.toml reads it from here).
__version__ = "0.2.0.dev0"

_SUBMODULES = {
    "results",
    "validation",
    "chi2",
    "linalg",
    "distributions",
    "lsq",
    "diagnosis",
    "filters",
    "nis",
    "quadform",
    "mismatched",
    "plotting",
    "grading",
}

__all__ = sorted(_SUBMODULES) + ["__version__"]


def __getattr__(name):
    if name in _SUBMODULES:
        module = import_module(f"{__name__}.{name}")
        globals()[name] = module
        return module
    raise AttributeError(f"module 'course' has no attribute {name!r}")


def __dir__():
    return __all__
