"""The MUDE sea-level data sets shipped with the course.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

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

    See Also
    --------
    load_mauna_loa_co2 : The other data set of notebook 1.
    fit : The least-squares fit of a record.

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


def load_mauna_loa_co2() -> tuple[np.ndarray, np.ndarray]:
    """The weekly Mauna Loa CO2 record 1958-2001 shipped with the course.

    Returns
    -------
    date : ndarray of datetime64[D], shape (2225,)
        The date of each week (a Saturday), weeks without data left out.
    co2 : ndarray, shape (2225,)
        The week's mean CO2 concentration in ppm (1999 calibration scale).

    See Also
    --------
    load_sea_level : The other data set of notebook 1.

    Notes
    -----
    Data: the Scripps CO2 program's continuous measurements at Mauna Loa, as published by
    C. D. Keeling and T. P. Whorf (2004), *Trends: A Compendium of Data on Global Change*,
    CDIAC; public domain (see ``course/data/mauna_loa_co2/README.md``). Of the 2284 weeks
    from 1958-03-29 to 2001-12-29, the 59 without a measurement are left out.

    Examples
    --------
    >>> date, co2 = load_mauna_loa_co2()
    >>> str(date[0]), float(co2[0]), date.size
    ('1958-03-29', 316.1, 2225)
    """
    source = resources.files("course") / "data" / "mauna_loa_co2" / "co2_weekly.csv"
    lines = source.read_text(encoding="utf-8").splitlines()[1:]  # below the header date,co2
    rows = [line.split(",") for line in lines if line.strip()]
    measured = [(day, ppm) for day, ppm in rows if ppm.strip()]
    date = np.array([f"{d[:4]}-{d[4:6]}-{d[6:8]}" for d, _ in measured], dtype="datetime64[D]")
    return date, np.array([float(ppm) for _, ppm in measured])
