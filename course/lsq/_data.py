"""The MUDE sea-level data sets shipped with the course."""

from __future__ import annotations

import io
from importlib import resources

import numpy as np

from course.validation import (
    as_index,
)


# ---------------------------------------------------------------------------
# data
# ---------------------------------------------------------------------------
def load_sea_level(case: int):
    """One of the four MUDE sea-level data sets shipped with the course.

    Parameters
    ----------
    case : {0, 1, 2, 3}
        0: a linear trend fits; 1: one outlier; 2: a quadratic term is
        missing; 3: the stated precision is too optimistic.

    Returns
    -------
    t : ndarray, shape (20,)
        Epochs 1, 2, ..., 20.
    y : ndarray, shape (20,)
        Sea-level observations; the source states a standard deviation of 2
        for every observation (and uses alpha = 0.05).

    Notes
    -----
    Data: TU Delft MUDE open course book, "overall model test" notebook,
    CC BY 4.0 (see ``course/data/sea_level_mude/README.md``).

    Examples
    --------
    >>> t, y = load_sea_level(1)
    >>> t.size, y.size
    (20, 20)
    """
    try:
        case = as_index(case, "case", 4)
    except ValueError:
        raise ValueError(f"case must be 0, 1, 2 or 3, got {case!r}") from None
    source = resources.files("course") / "data" / "sea_level_mude" / f"Dataset_{case}.txt"
    y = np.loadtxt(io.StringIO(source.read_text(encoding="utf-8")))
    return np.arange(1.0, y.size + 1.0), y
