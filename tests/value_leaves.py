"""The scalar leaves of an expected value, for the scans that look for answers where a student
could read them (tests/test_feedback_scan.py, tests/test_grading_seal.py)."""

from __future__ import annotations

import numpy as np

from course.grading.codec import Band


def leaves(value, out: list, limit: int | None = None) -> list:
    """Append the scalar leaves of ``value`` to ``out`` (each array's first ``limit`` elements)."""
    if isinstance(value, Band):
        leaves(value.lo, out, limit)
        leaves(value.hi, out, limit)
    elif isinstance(value, dict):
        for v in value.values():
            leaves(v, out, limit)
    elif isinstance(value, (tuple, list)):
        for v in value:
            leaves(v, out, limit)
    elif isinstance(value, np.ndarray):
        for v in value.ravel()[:limit].tolist():
            leaves(v, out, limit)
    elif isinstance(value, (float, int, complex, str, bool, np.generic)) or value is None:
        out.append(value.item() if isinstance(value, np.generic) else value)
    return out
