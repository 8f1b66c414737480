"""Tripwires on forbidden library functions, shared by the self-check and the grading runner.

A question may forbid functions (``"course.lsq.wls"``, ...) that would answer it outright.
:func:`wrap_forbidden` swaps such a function for a wrapper that reports calls made from the
student's notebook; what a report means (a warning in :mod:`course.grading.selfcheck`, a hit
against the running question in :mod:`course.grading.runner`) is up to the caller.
"""

from __future__ import annotations

import importlib
import sys
from builtins import getattr, setattr, str  # bound before student code runs (see runner)

__all__ = ["wrap_forbidden"]


def wrap_forbidden(dotted: str, record, user_ns: dict | None = None):
    """Replace the function ``dotted`` (``"package.module.name"``) by a reporting wrapper.

    Parameters
    ----------
    dotted : str
        Full dotted name of the function.
    record : callable
        ``record(dotted)``, called before the original on each call from notebook code.
    user_ns : dict, optional
        The notebook's namespace, which counts as notebook code even if it is named like a
        library module.

    Returns
    -------
    tuple or None
        ``(module, attr, original)`` to put the original back, or None when there is no such
        function (nothing is wrapped).
    """
    module_name, _, attr = dotted.rpartition(".")
    try:
        module = importlib.import_module(module_name)
        original = getattr(module, attr)
    except (ImportError, AttributeError):
        return None

    def wrapper(*args, __original=original, __name=dotted, **kwargs):
        caller = sys._getframe(1).f_globals
        # calls from inside the library (e.g. data_snooping -> w_tests) are allowed
        if caller is user_ns or not str(caller.get("__name__", "")).startswith("course."):
            record(__name)
        return __original(*args, **kwargs)

    wrapper.__name__ = getattr(original, "__name__", attr)
    wrapper.__doc__ = getattr(original, "__doc__", None)
    setattr(module, attr, wrapper)
    return module, attr, original
