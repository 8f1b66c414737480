"""Input validation: the one place where the course decides what it accepts.

Every public function checks its arguments with these helpers, so the same
mistake gets the same message everywhere.  A message names the argument,
says what was wrong and what to do.  Nothing a user typed is silently
changed: values are converted only when the conversion is exact.

The rules
---------
Arrays (:func:`as_float_array`, :func:`as_vector`, :func:`as_matrix`)
    Converted to a float64 *copy* (the caller's array is never aliased or
    modified).  ``None``, strings, complex numbers, ragged sequences, NaN and
    inf are refused with :class:`ValueError`.
Covariances (:func:`as_covariance`)
    Square, symmetric to a relative tolerance ``1e-10`` and positive
    definite (or semi-definite with ``allow_singular=True``); an indefinite
    matrix raises :class:`numpy.linalg.LinAlgError`.
Counts and indices (:func:`as_count`, :func:`as_index`, :func:`as_indices`)
    **One rule for every integer argument**: Python and NumPy integers are
    accepted, and so is a float whose value is exactly an integer (``10.0``,
    ``1e4``, the result of ``N / 2`` for even ``N``): converting it changes
    nothing.  A fraction (``2.5``), NaN, inf, ``True``/``False``, strings and
    ``None`` are refused, as are values below the stated minimum.  (NumPy
    refuses every float as a size; the course accepts whole floats because
    ``1e4`` is how people write ten thousand, and refuses everything that
    would have to be rounded.)
Numbers (:func:`as_finite`, :func:`as_positive`, :func:`as_variance`, :func:`as_probability`)
    Real, finite scalars (a 0-d array counts as a scalar); positive,
    non-negative (a variance) or strictly inside (0, 1) (a level of
    significance or a power) where the name says so.
Covariances are positive definite *numerically*
    A covariance whose Cholesky factorisation succeeds only by rounding is
    refused as well: see :data:`SINGULAR_RTOL`.
Sizes (:func:`as_size`)
    ``None``, a count or a tuple of counts (the shape of random draws).
Standard deviations (:func:`as_std`)
    Positive and finite, and with a square that is a normal double: a
    ``sigma`` of ``1e300`` (or ``1e-300``) whose variance overflows (or
    underflows) is refused with advice to rescale the data, never turned
    into ``inf``, ``0`` or NaN further down.
Randomness (:func:`as_generator`)
    A :class:`numpy.random.Generator`, or a seed (an integer, a sequence of
    them or ``None``) for a new one; legacy ``RandomState`` objects are
    refused so that no code path touches numpy's global random state.
Everything else (:func:`as_flag`, :func:`as_callable`, :func:`as_law`)
    A flag is a ``bool`` (``"no"`` is not ``False``); a function must be
    callable; a law must have ``cdf``, ``sf``, ``ppf``, ``isf`` and ``rvs``.

A value of the wrong *type* raises :class:`InputTypeError`, which is both a
``ValueError`` (as every refusal of bad input) and a ``TypeError``.

Examples
--------
>>> from course.validation import as_count, as_probability
>>> as_count(1e4, "n_records")
10000
>>> as_count(2.5, "n_records")
Traceback (most recent call last):
...
ValueError: n_records must be an integer, got 2.5 (a fraction cannot be a count or an index)
>>> as_probability(0.05, "alpha")
0.05
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np
from numpy.linalg import LinAlgError

from course import _pivots
from course._pivots import _refuse_singular_pivots

__all__ = [
    "SINGULAR_RTOL",
    "SYMMETRY_RTOL",
    "InputTypeError",
    "as_callable",
    "as_count",
    "as_covariance",
    "as_covariance_stack",
    "as_finite",
    "as_flag",
    "as_float_array",
    "as_generator",
    "as_index",
    "as_indices",
    "as_law",
    "as_matrix",
    "as_positive",
    "as_probability",
    "as_size",
    "as_std",
    "as_variance",
    "as_vector",
]

#: Relative tolerance for "symmetric": ``|Q - Q^T| <= SYMMETRY_RTOL * max|Q|``.
SYMMETRY_RTOL = 1e-10

#: Relative tolerance for "numerically singular", per dimension of the matrix: a
#: covariance ``Q`` (m x m) with Cholesky factor ``L`` is singular when some
#: ``L_ii**2 <= SINGULAR_RTOL * m * Q_ii``.  ``L_ii**2 / Q_ii`` is the share of the
#: variance of variable ``i`` that the variables before it do not explain
#: (``1 - R_i**2``); below ``m`` rounding errors it is rounding, not information.
#: The rule is scale-free (``D Q D`` is singular exactly when ``Q`` is) and, like
#: the course's rank rule (:func:`course.linalg.rank_tolerance`), proportional to
#: ``m * eps``.
SINGULAR_RTOL = _pivots.SINGULAR_RTOL


class InputTypeError(TypeError, ValueError):
    """An argument of the wrong type (a ``ValueError`` like every refusal, and a ``TypeError``)."""


# ---------------------------------------------------------------------------
# arrays
# ---------------------------------------------------------------------------
def as_float_array(
    value: Any,
    name: str,
    ndim: int | None = None,
    *,
    min_ndim: int | None = None,
    finite: bool = True,
    empty: bool = True,
    nan: bool = False,
) -> np.ndarray:
    """Return ``value`` as a float64 copy, refusing NaN, inf and a wrong ndim.

    Parameters
    ----------
    value : array_like
        What the user passed.
    name : str
        The argument's name, used in error messages.
    ndim : int, optional
        Required number of dimensions.
    min_ndim : int, optional
        Smallest number of dimensions (leading batch axes are free).
    finite : bool, default True
        Refuse ``inf`` too (NaN is always refused); ``False`` for points
        where a law is evaluated (``cdf(inf)`` is 1).
    empty : bool, default True
        Accept an array without elements.
    nan : bool, default False
        Accept NaN, where it marks an undefined sample (a window not yet
        full); a user's data never get this.

    Returns
    -------
    numpy.ndarray
        A new float64 array (never a view of ``value``).

    Raises
    ------
    ValueError
        If the value is None, complex or not numeric, has the wrong number of
        dimensions, or contains NaN or inf.

    Examples
    --------
    >>> as_float_array([1, 2], "y")
    array([1., 2.])
    >>> as_float_array([1, float("nan")], "y")
    Traceback (most recent call last):
    ...
    ValueError: y contains NaN or inf (1 entries, first at index (1,)); remove or replace those values before fitting
    """
    if value is None:
        raise ValueError(f"{name} is None; pass an array of numbers")
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be numeric, got the string {value!r}")
    if isinstance(value, (dict, set)) or callable(value):
        raise ValueError(f"{name} must be an array of numbers, got {type(value).__name__}")
    if _is_complex(value):
        # float() would drop the imaginary part with only a warning: refuse instead.
        raise ValueError(
            f"{name} is complex; pass real numbers (e.g. np.real(...) if the "
            "imaginary parts are rounding noise)"
        )
    if _holds_text(value):
        # numpy reads "1.0" as 1.0: text typed by mistake must not pass as a number
        raise ValueError(f"{name} must be numeric, got text among its entries")
    try:
        array = np.array(value, dtype=float)  # a copy: callers may not mutate input
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name} must be numeric, got {type(value).__name__}: {exc}") from None
    if min_ndim is not None and array.ndim < min_ndim:
        raise ValueError(
            f"{name} must have at least {min_ndim} dimension(s), got shape {array.shape}"
            + (" (a scalar where an array is expected)" if array.ndim == 0 else "")
        )
    if ndim is not None and array.ndim != ndim:
        raise ValueError(
            f"{name} must be {ndim}-dimensional, got shape {array.shape}"
            + (
                " (pass a column as a 2-D array of shape (m, 1))"
                if ndim == 2 and array.ndim == 1
                else ""
            )
        )
    # (one test in the usual case, where every entry is finite)
    suspect = (finite or not nan) and not np.isfinite(array).all()
    bad_entries = np.zeros(array.shape if suspect else (), bool)
    if suspect and finite:
        bad_entries |= np.isinf(array)
    if suspect and not nan:
        bad_entries |= np.isnan(array)
    if suspect and bad_entries.any():
        bad = np.argwhere(bad_entries)
        where = tuple(int(i) for i in bad[0])
        what = " or ".join(w for w, on in (("NaN", not nan), ("inf", finite)) if on)
        raise ValueError(
            f"{name} contains {what} ({len(bad)} entries, first at index {where}); "
            "remove or replace those values before fitting"
        )
    if not empty and array.size == 0:
        raise ValueError(f"{name} is empty (shape {array.shape}); pass at least one value")
    return array


def _holds_text(value: Any) -> bool:
    """Whether an array, list or tuple holds a string (at any depth)."""
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "US":
            return True
        return value.dtype.kind == "O" and any(map(_holds_text_entry, value.flat))
    if isinstance(value, (list, tuple)):
        return any(map(_holds_text_entry, value))
    return False


def _holds_text_entry(entry: Any) -> bool:
    return isinstance(entry, (str, bytes)) or (
        isinstance(entry, (list, tuple, np.ndarray)) and _holds_text(entry)
    )


def _is_complex(value: Any) -> bool:
    try:
        return bool(np.iscomplexobj(value))
    except (TypeError, ValueError):  # ragged or non-numeric: reported by the caller
        return False


def as_vector(value: Any, name: str, size: int | None = None, *, empty: bool = False) -> np.ndarray:
    """Return a finite 1-D float array, of length ``size`` when given (non-empty by default).

    Examples
    --------
    >>> as_vector([1, 2, 3], "theta", 3)
    array([1., 2., 3.])
    >>> as_vector([[1, 2, 3]], "theta")
    Traceback (most recent call last):
    ...
    ValueError: theta must be a 1-D vector, got shape (1, 3); pass it flattened, e.g. np.ravel(...)
    """
    vector = as_float_array(value, name)
    if vector.ndim == 2 and 1 in vector.shape:
        raise ValueError(
            f"{name} must be a 1-D vector, got shape {vector.shape}; "
            "pass it flattened, e.g. np.ravel(...)"
        )
    if vector.ndim == 0:
        raise ValueError(
            f"{name} must be a 1-D vector, got the scalar {float(vector)!r}; "
            f"pass a sequence, e.g. [{float(vector)!r}]"
        )
    if vector.ndim != 1:
        raise ValueError(f"{name} must be a 1-D vector, got shape {vector.shape}")
    if size is not None and vector.shape[0] != size:
        raise ValueError(f"{name} must have length {size}, got {vector.shape[0]}")
    if not empty and vector.size == 0:
        raise ValueError(f"{name} is empty; pass at least one value")
    return vector


def as_matrix(
    value: Any,
    name: str,
    shape: tuple[int | None, int | None] | None = None,
    *,
    empty: bool = False,
) -> np.ndarray:
    """Return a finite 2-D float array, checking ``shape`` where given (None: any).

    An array without elements is refused unless ``empty`` is true.

    Examples
    --------
    >>> as_matrix([[1, 0], [0, 1]], "A", shape=(None, 2)).shape
    (2, 2)
    """
    matrix = as_float_array(value, name, ndim=2)
    if shape is not None:
        for axis, expected in enumerate(shape):
            if expected is not None and matrix.shape[axis] != expected:
                raise ValueError(f"{name} must have shape {_shape_text(shape)}, got {matrix.shape}")
    if not empty and matrix.size == 0:
        raise ValueError(
            f"{name} is empty (shape {matrix.shape}); pass at least one row and column"
        )
    return matrix


def as_covariance(value: Any, name: str, size: int, allow_singular: bool = False) -> np.ndarray:
    r"""Validate a covariance matrix: square ``size`` x ``size``, symmetric, PD.

    Parameters
    ----------
    value : array_like
        The covariance matrix.
    name : str
        Its name in error messages (``"Qyy"``, ``"R"``, ...).
    size : int
        Required dimension.
    allow_singular : bool
        Accept positive semi-definite matrices.

    Returns
    -------
    numpy.ndarray
        A float64 copy.

    Raises
    ------
    ValueError
        Wrong shape or not symmetric.
    numpy.linalg.LinAlgError
        Not positive definite, numerically included (not positive
        semi-definite with ``allow_singular``).

    See Also
    --------
    as_float_array : The check of any array of numbers.
    course.linalg.covariance_factor : The factor of a checked covariance.

    Notes
    -----
    Positive definiteness is decided by the Cholesky factorisation
    :math:`Q = LL^{\mathsf T}` (no eigendecomposition), with a relative
    tolerance on its diagonal: the matrix is *numerically singular*, and
    refused, when for some :math:`i`

    .. math::

        L_{ii}^2 \le \epsilon_s\, m\, Q_{ii}

    (:math:`\epsilon_s` = :data:`SINGULAR_RTOL`, four machine epsilons).
    :math:`L_{ii}^2 / Q_{ii}` is the part of the variance of variable :math:`i`
    that the variables before it leave unexplained; an exactly singular matrix
    (a variable that is a combination of others) leaves only rounding there,
    and its Cholesky factorisation may still "succeed".  With
    ``allow_singular=True`` the smallest eigenvalue must be at least
    :math:`-m\,\epsilon \max|Q|`.

    Examples
    --------
    >>> as_covariance([[2.0, 0.5], [0.5, 1.0]], "R", 2)
    array([[2. , 0.5],
           [0.5, 1. ]])
    >>> as_covariance([[1.0, 2.0], [2.0, 1.0]], "R", 2)
    Traceback (most recent call last):
    ...
    numpy.linalg.LinAlgError: R is not positive definite (smallest eigenvalue -1); a covariance matrix needs positive variances and correlations in [-1, 1]

    ``X X^T`` for a 3 x 2 matrix ``X`` is singular, but rounding leaves its
    smallest eigenvalue at +1.6e-15 and its Cholesky factorisation succeeds:

    >>> as_covariance([[2.0, 4.0, 5.0], [4.0, 10.0, 13.0], [5.0, 13.0, 17.0]], "Qyy", 3)
    Traceback (most recent call last):
    ...
    numpy.linalg.LinAlgError: Qyy is numerically singular: variable 2 is a linear combination of variables 0..1 up to rounding (1 - R^2 = 1.1e-16 < 2.7e-15); remove the redundant variable or add its independent variance
    """
    matrix = as_matrix(value, name, shape=(size, size))
    allow_singular = as_flag(allow_singular, "allow_singular")
    scale = max(float(np.max(np.abs(matrix))), np.finfo(float).tiny)
    asym = float(np.max(np.abs(matrix - matrix.T)))
    if asym > SYMMETRY_RTOL * scale:
        raise ValueError(
            f"{name} is not symmetric (largest |{name} - {name}^T| = {asym:.3g}); "
            "a covariance matrix must equal its transpose"
        )
    if allow_singular:
        smallest = float(np.linalg.eigvalsh(matrix / scale)[0]) * scale
        if smallest < -np.finfo(float).eps * size * scale:
            raise _not_definite(name, "positive semi-definite", smallest)
        return matrix
    # Cholesky of the correlation-scaled matrix: scale-free, and safe at 1e+-300.
    diagonal = np.diag(matrix)
    if np.any(diagonal <= 0):
        raise _not_definite(name, "positive definite", _smallest_eigenvalue(matrix, scale))
    std = np.sqrt(diagonal)
    correlation = matrix / std[:, None] / std[None, :]
    try:
        L = np.linalg.cholesky(correlation)
    except LinAlgError:
        raise _not_definite(
            name, "positive definite", _smallest_eigenvalue(matrix, scale)
        ) from None
    _refuse_singular_pivots(L, np.ones(size), name)
    return matrix


def as_covariance_stack(
    value: Any, name: str, size: int | None = None, *, allow_singular: bool = False
) -> np.ndarray:
    """A covariance ``(m, m)`` or a stack of them ``(..., m, m)``, each checked as by :func:`as_covariance`.

    Examples
    --------
    >>> as_covariance_stack(np.stack([np.eye(2), 2 * np.eye(2)]), "P", 2).shape
    (2, 2, 2)
    """
    allow_singular = as_flag(allow_singular, "allow_singular")
    stack = as_float_array(value, name, min_ndim=2, empty=False)
    m = stack.shape[-1]
    if stack.shape[-2] != m or (size is not None and m != size):
        expected = "(..., m, m)" if size is None else f"(..., {size}, {size})"
        raise ValueError(f"{name} must have shape {expected}, got {stack.shape}")
    scale = np.maximum(np.max(np.abs(stack), axis=(-2, -1), keepdims=True), np.finfo(float).tiny)
    if np.any(np.abs(stack - np.swapaxes(stack, -1, -2)) > SYMMETRY_RTOL * scale):
        raise ValueError(f"{name} is not symmetric; a covariance matrix must equal its transpose")
    if allow_singular:
        smallest = np.linalg.eigvalsh(stack / scale)[..., 0]
        if np.any(smallest < -np.finfo(float).eps * m):
            worst = float(np.min(smallest * scale[..., 0, 0]))
            raise _not_definite(name, "positive semi-definite", worst)
        return stack
    variances = np.diagonal(stack, axis1=-2, axis2=-1)
    if np.any(variances <= 0):
        raise _not_definite(name, "positive definite", float(np.min(variances)))
    std = np.sqrt(variances)
    try:
        L = np.linalg.cholesky(stack / std[..., :, None] / std[..., None, :])
    except LinAlgError:
        raise LinAlgError(
            f"{name} is not positive definite (Cholesky factorisation failed); a covariance "
            "matrix needs positive variances and correlations in [-1, 1]"
        ) from None
    _refuse_singular_pivots(L, np.ones(variances.shape), name)
    return stack


def _smallest_eigenvalue(matrix: np.ndarray, scale: float) -> float:
    return float(np.linalg.eigvalsh(matrix / scale)[0]) * scale


def _not_definite(name: str, kind: str, smallest: float) -> LinAlgError:
    return LinAlgError(
        f"{name} is not {kind} (smallest eigenvalue {smallest:.3g}); "
        "a covariance matrix needs positive variances and correlations in [-1, 1]"
    )


def _shape_text(shape: tuple[int | None, ...]) -> str:
    return "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"


# ---------------------------------------------------------------------------
# integers: one rule for counts and indices
# ---------------------------------------------------------------------------
def _integer(value: Any, name: str, what: str | None) -> int:
    """``value`` as an int under the course's one integer rule (see the module docstring)."""
    label = name if what is None else f"{name} ({what})"
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{label} must be an integer, got {value!r}")
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        number = float(value)
        if math.isfinite(number) and number.is_integer():
            return int(number)
        reason = (
            "a fraction cannot be a count or an index"
            if math.isfinite(number)
            else "it must be finite"
        )
        raise ValueError(f"{label} must be an integer, got {value!r} ({reason})")
    raise ValueError(f"{label} must be an integer, got {value!r}")


def as_count(value: Any, name: str, *, minimum: int = 1, what: str | None = None) -> int:
    """A count (number of samples, records, steps, degrees of freedom) as an ``int``.

    Parameters
    ----------
    value : int or float
        An integer, or a float with an integral value (``1e4``).
    name : str
        The argument's name for messages.
    minimum : int, default 1
        Smallest accepted value (0 for "non-negative").
    what : str, optional
        What the count means, added to messages ("the number of records").

    Returns
    -------
    int

    Raises
    ------
    ValueError
        A fraction, NaN, inf, a bool, a non-number, or a value below ``minimum``.

    Examples
    --------
    >>> as_count(10.0, "N")
    10
    >>> as_count(0, "N", what="the number of samples")
    Traceback (most recent call last):
    ...
    ValueError: N (the number of samples) must be a positive integer, got 0
    """
    count = _integer(value, name, what)
    if count < minimum:
        label = name if what is None else f"{name} ({what})"
        kind = {0: "a non-negative integer", 1: "a positive integer"}.get(
            minimum, f"an integer of at least {minimum}"
        )
        raise ValueError(f"{label} must be {kind}, got {count}")
    return count


def as_index(
    value: Any, name: str, size: int, *, negative: bool = False, what: str | None = None
) -> int:
    """An index into a sequence of length ``size``, as a non-negative ``int``.

    Parameters
    ----------
    value : int or float
        The index (same integer rule as :func:`as_count`).
    name : str
        The argument's name for messages.
    size : int
        Length of the indexed sequence.
    negative : bool, default False
        Accept Python-style negative indices (``-1`` is the last); the
        returned index is always in ``0 .. size-1``.
    what : str, optional
        What is indexed, for messages.

    Examples
    --------
    >>> as_index(-1, "t", 10, negative=True)
    9
    >>> as_index(10, "j", 10)
    Traceback (most recent call last):
    ...
    ValueError: j must be an integer index in 0..9, got 10
    """
    index = _integer(value, name, what)
    label = name if what is None else f"{name} ({what})"
    low = -size if negative else 0
    if not low <= index < size:
        span = f"{low}..{size - 1}" if size else "an empty range"
        raise ValueError(f"{label} must be an integer index in {span}, got {index}")
    return index % size if size else index


def as_indices(
    values: Any, name: str, size: int, *, allow_empty: bool = True, what: str | None = None
) -> list[int]:
    """Distinct indices into a sequence of length ``size``, sorted.

    ``None`` and an empty sequence give ``[]`` (unless ``allow_empty`` is
    False); a single integer is one index.

    Examples
    --------
    >>> as_indices([2, 0], "free", 3)
    [0, 2]
    >>> as_indices([0, 0], "free", 3)
    Traceback (most recent call last):
    ...
    ValueError: free contains repeated indices: [0, 0]
    """
    if values is None:
        items: list[Any] = []
    elif isinstance(values, (numbers.Number, np.generic)) or (
        isinstance(values, np.ndarray) and values.ndim == 0
    ):
        items = [values]
    elif isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
        raise ValueError(f"{name} must be a sequence of integer indices, got {values!r}")
    else:
        items = list(values)
    label = name if what is None else f"{name} ({what})"
    out = []
    for item in items:
        try:
            index = _integer(item, name, what)
        except ValueError:
            raise ValueError(f"{label} must be integer indices, got {item!r}") from None
        if not 0 <= index < size:
            raise ValueError(f"{label} index {index} is out of range 0..{size - 1}")
        out.append(index)
    if len(set(out)) != len(out):
        raise ValueError(f"{label} contains repeated indices: {out}")
    if not out and not allow_empty:
        raise ValueError(f"{label} must name at least one index")
    return sorted(out)


# ---------------------------------------------------------------------------
# real numbers
# ---------------------------------------------------------------------------
def as_finite(value: Any, name: str, *, what: str | None = None) -> float:
    """A real, finite scalar as a ``float``.

    Examples
    --------
    >>> as_finite(3, "threshold")
    3.0
    >>> as_finite("3", "threshold")
    Traceback (most recent call last):
    ...
    ValueError: threshold must be a real number, got '3'
    """
    label = name if what is None else f"{name} ({what})"
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ValueError(f"{label} must be a real number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{label} must be finite, got {value!r}")
    return number


def as_positive(value: Any, name: str, *, what: str | None = None) -> float:
    """A positive, finite scalar (a standard deviation, a sampling interval).

    Examples
    --------
    >>> as_positive(0.2, "sigma")
    0.2
    >>> as_positive(0, "sigma", what="the noise standard deviation")
    Traceback (most recent call last):
    ...
    ValueError: sigma (the noise standard deviation) must be positive, got 0
    """
    number = as_finite(value, name, what=what)
    if number <= 0:
        label = name if what is None else f"{name} ({what})"
        raise ValueError(f"{label} must be positive, got {value!r}")
    return number


def as_variance(value: Any, name: str, *, positive: bool = False, what: str | None = None) -> float:
    """A variance: finite and non-negative (positive with ``positive=True``).

    Examples
    --------
    >>> as_variance(0.0, "q")
    0.0
    >>> as_variance(-1, "r", positive=True)
    Traceback (most recent call last):
    ...
    ValueError: r must be positive (it is a variance), got -1
    """
    number = as_finite(value, name, what=what)
    if number < 0 or (positive and number == 0):
        label = name if what is None else f"{name} ({what})"
        kind = "positive" if positive else "non-negative"
        raise ValueError(f"{label} must be {kind} (it is a variance), got {value!r}")
    return number


def as_std(value: Any, name: str = "sigma", *, what: str | None = None) -> float:
    """A standard deviation whose variance is a normal double.

    Positive and finite like :func:`as_positive`, and ``value**2`` must lie
    between the smallest normal double (2.2e-308) and the largest (1.8e308):
    a ``sigma`` of ``1e300`` has a variance of ``1e600``, which no double
    holds.  Such a value is refused with advice to rescale rather than
    turned into ``inf`` or ``0`` (and NaN) further down.  Functions whose
    answer scales with ``sigma`` (test statistics ``|r / sigma|^2``) compute
    in scaled form and may take :func:`as_positive` instead.

    Examples
    --------
    >>> as_std(0.2)
    0.2
    >>> as_std(1e300)
    Traceback (most recent call last):
    ...
    ValueError: sigma = 1e+300 is too large: its square, the variance, overflows double precision; express the data in larger units so that sigma lies between 1e-150 and 1e150
    """
    number = as_positive(value, name, what=what)
    label = name if what is None else f"{name} ({what})"
    square = number * number
    if square > np.finfo(float).max or not math.isfinite(square):
        problem = "is too large: its square, the variance, overflows double precision"
        unit = "larger"
    elif square < np.finfo(float).tiny:
        problem = "is too small: its square, the variance, underflows double precision"
        unit = "smaller"
    else:
        return number
    raise ValueError(
        f"{label} = {number!r} {problem}; express the data in {unit} units so that "
        f"{name} lies between 1e-150 and 1e150"
    )


def as_probability(value: Any, name: str = "alpha") -> float:
    """A probability strictly between 0 and 1 (a level of significance, a power).

    Examples
    --------
    >>> as_probability(0.05)
    0.05
    >>> as_probability(1.0, "power")
    Traceback (most recent call last):
    ...
    ValueError: power must lie strictly between 0 and 1, got 1.0
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a number in (0, 1), got {value!r}")
    number = float(value)
    if not 0.0 < number < 1.0:
        raise ValueError(f"{name} must lie strictly between 0 and 1, got {value!r}")
    return number


# ---------------------------------------------------------------------------
# randomness
# ---------------------------------------------------------------------------
def as_generator(rng: Any, name: str = "rng") -> np.random.Generator:
    """Return a :class:`numpy.random.Generator` from a Generator, a seed or None.

    Legacy ``RandomState`` objects and the global numpy state are refused:
    randomness in the course always flows through an explicit Generator.
    A seed is a non-negative integer (or a sequence of them), as
    :func:`numpy.random.default_rng` takes.

    Examples
    --------
    >>> g = as_generator(7)
    >>> as_generator(g) is g
    True
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, np.random.RandomState):
        raise InputTypeError(
            f"{name}: pass a numpy.random.Generator (np.random.default_rng(seed)), "
            "not a legacy RandomState"
        )
    try:
        return np.random.default_rng(rng)
    except (TypeError, ValueError) as exc:
        raise InputTypeError(
            f"{name} must be a numpy.random.Generator or a seed (a non-negative integer or "
            f"None), got {rng!r} ({exc})"
        ) from None


# ---------------------------------------------------------------------------
# sizes, flags, functions, laws
# ---------------------------------------------------------------------------
def as_size(value: Any, name: str = "size") -> tuple[int, ...] | None:
    """The shape of random draws: ``None``, a count, or a tuple of counts (0 allowed).

    Examples
    --------
    >>> as_size(3), as_size((2, 1e3)), as_size(None)
    ((3,), (2, 1000), None)
    >>> as_size(2.5)
    Traceback (most recent call last):
    ...
    ValueError: size must be an integer, got 2.5 (a fraction cannot be a count or an index)
    """
    if value is None:
        return None
    if isinstance(value, (numbers.Number, np.generic)) or (
        isinstance(value, np.ndarray) and value.ndim == 0
    ):
        return (as_count(value, name, minimum=0),)
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise ValueError(f"{name} must be None, an integer or a tuple of integers, got {value!r}")
    return tuple(as_count(n, name, minimum=0) for n in value)


def as_flag(value: Any, name: str) -> bool:
    """A yes/no option: ``True`` or ``False`` (numpy bools too), nothing else.

    ``bool("no")`` is ``True``: a string, a number or ``None`` is refused
    rather than read as a truth value.

    Examples
    --------
    >>> as_flag(False, "full")
    False
    >>> as_flag("no", "full")
    Traceback (most recent call last):
    ...
    course.validation.InputTypeError: full must be True or False, got 'no'
    """
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise InputTypeError(f"{name} must be True or False, got {value!r}")


def as_callable(value: Any, name: str, *, optional: bool = False) -> Any:
    """A function (or ``None`` when ``optional``).

    Examples
    --------
    >>> as_callable(None, "jac_h", optional=True) is None
    True
    >>> as_callable(3.0, "f")
    Traceback (most recent call last):
    ...
    course.validation.InputTypeError: f must be callable (a function), got float 3.0
    """
    if value is None and optional:
        return None
    if not callable(value):
        raise InputTypeError(
            f"{name} must be callable (a function), got {type(value).__name__} {value!r}"
        )
    return value


_LAW_METHODS = ("cdf", "sf", "ppf", "isf")


def as_law(value: Any, name: str) -> Any:
    """A frozen law: an object with ``cdf``, ``sf``, ``ppf`` and ``isf`` (scipy's interface).

    Examples
    --------
    >>> from scipy import stats
    >>> as_law(stats.chi2(2), "null").mean()
    np.float64(2.0)
    >>> as_law(2.0, "null")
    Traceback (most recent call last):
    ...
    course.validation.InputTypeError: null must be a frozen law with cdf, sf, ppf and isf (e.g. scipy.stats.chi2(2)), got float
    """
    if not all(callable(getattr(value, method, None)) for method in _LAW_METHODS):
        raise InputTypeError(
            f"{name} must be a frozen law with cdf, sf, ppf and isf "
            f"(e.g. scipy.stats.chi2(2)), got {type(value).__name__}"
        )
    return value
