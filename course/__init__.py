"""Validating models with residuals: the library behind the course.

Importing :mod:`course` is free of side effects: no plotting backend is
chosen, no random state is touched and nothing is printed.  The topic
modules are imported lazily on first attribute access, so ``import course``
stays fast and ``course.lsq`` still works.

Modules
-------
results
    The shared result vocabulary (:class:`~course.results.TestResult`).
linalg
    Input validation and factorisation helpers shared by every module.
distributions
    A small base class for frozen distributions with the scipy interface.
lsq
    Least-squares residuals, the overall model test, w-tests, data snooping.
"""

from importlib import import_module

__version__ = "0.1.0"

_SUBMODULES = {
    "results",
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
_DEPRECATED = {"exercises"}  # old name of course.grading, kept for one release

__all__ = sorted(_SUBMODULES) + ["__version__"]


def __getattr__(name):
    if name in _SUBMODULES or name in _DEPRECATED:
        module = import_module(f"{__name__}.{name}")
        globals()[name] = module
        return module
    raise AttributeError(f"module 'course' has no attribute {name!r}")


def __dir__():
    return __all__
