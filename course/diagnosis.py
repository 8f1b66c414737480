"""Test quantities for fault diagnosis: prediction errors, estimates, likelihoods.

This module follows the lecture on test quantities
(``seeds/test_quantities_lecture_sv.txt``, Swedish; English digest in
``seeds/README.md``).  Its one idea: a *test quantity* is a measure of how
well the model *under the null hypothesis* of a test explains the data.  It
is zero (or small) when that model can be true and large otherwise.

Public API
----------
Decision structures
    :class:`DecisionStructure` (tests x fault modes, entries 0 or X, shown as
    a table in Jupyter), :func:`diagnoses` (single-fault diagnosis from the
    alarms), :func:`diagnosis_matrix` (the same for many alarm patterns at
    once), :func:`multiple_fault_diagnoses` (minimal hitting sets of the
    conflicts) and :func:`linear_decision_structure` (the structure a set of
    prediction-error tests really has, given the regressors).
Prediction errors
    :func:`least_squares_residual` (rank-revealing, the residual is unique
    even when the parameters are not), :func:`prediction_error`,
    :func:`prediction_error_test` and :func:`nonlinear_prediction_error`.
    The recursive route (a Kalman filter on random-walk parameters; RLS when
    the walk has no steps) is :func:`course.filters.recursive_least_squares`,
    its windowed test quantity :func:`course.filters.windowed_nis` with the
    threshold :func:`course.filters.windowed_nis_threshold`.
Thresholds and power
    :func:`residual_threshold` (threshold on ``||residual||^2`` with known
    noise level), :func:`fault_noncentrality` (non-centrality a fault gives a
    test), :func:`prediction_error_power`.
Parameter estimates
    :func:`estimate_parameters`, :func:`parameter_estimate_test`,
    :func:`regression_parameter_test`, :func:`parameter_estimate_power`.
Likelihood
    :func:`normal_log_likelihood`, :func:`normal_likelihood`,
    :func:`maximum_likelihood`, :func:`likelihood_test`,
    :func:`glr_test`, :func:`linear_glr_test`, :func:`neyman_pearson_test`,
    :func:`mode_log_likelihoods`, :func:`bayes_ranking`.
Monte Carlo
    :func:`simulate_linear_regression`, :func:`linear_test_statistics`,
    :func:`isolation_monte_carlo`.

Conventions
-----------
The linear-in-parameters fault model of the lecture is
``y = U theta + v`` with ``v ~ N(0, sigma^2 I)``: the columns of ``U`` are the
signals ``u_i(t)``, ``nominal`` is the fault-free parameter vector and a set
of parameter indices ``free`` describes the parameter set of a null
hypothesis, ``Theta_0 = {theta : theta_j = nominal_j for every j not in
free}``.  Data may be one record ``y`` of shape ``(N,)`` or ``M`` records at
once as the columns of an ``(N, M)`` array; statistics then come back as
length-``M`` arrays, which is what makes the Monte Carlo studies fast.
"""

from __future__ import annotations

import html
import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import linalg as sla
from scipy import optimize, special, stats

from .distributions import FrozenDistribution, as_generator
from .linalg import (
    as_covariance,
    as_float_array,
    as_matrix,
    as_vector,
    check_alpha,
    check_full_column_rank,
    cholesky_lower,
    solve_spd,
    symmetrize,
)
from .results import TestResult, format_number

__all__ = [
    "DecisionStructure",
    "FaultRanking",
    "Hypotheses",
    "IsolationResult",
    "MLResult",
    "NonlinearFit",
    "ParameterEstimate",
    "RegressionFit",
    "bayes_ranking",
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
    "parameter_estimate_power",
    "parameter_estimate_test",
    "prediction_error",
    "prediction_error_power",
    "prediction_error_test",
    "regression_parameter_test",
    "residual_threshold",
    "simulate_linear_regression",
]

_ZERO_MARKS = {"0", "o", "O", "-", ""}
_X_MARKS = {"x", "X", "1"}


# ---------------------------------------------------------------------------
# decision structures
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Hypotheses:
    """The two hypotheses a test decides, as sets of fault modes.

    Attributes
    ----------
    test : str
        The test's name.
    null : tuple of str
        Modes with a 0 in the test's row: ``H0: Fp in null``.
    alternative : tuple of str
        Modes with an X: ``H1: Fp in alternative``.
    """

    test: str
    null: tuple
    alternative: tuple

    def __str__(self) -> str:
        return (
            f"{self.test}: H0: Fp in {{{', '.join(self.null)}}}  vs  "
            f"H1: Fp in {{{', '.join(self.alternative)}}}"
        )


class DecisionStructure:
    """Which fault modes each test is sensitive to (tests x modes, 0 or X).

    An ``X`` in row ``T`` and column ``F`` means that test ``T`` *may* alarm
    when the system is in mode ``F``; a ``0`` means it never does (up to its
    false-alarm rate).  Test ``T`` therefore decides
    ``H0: Fp in {modes with 0}`` against ``H1: Fp in {modes with X}``: an
    alarm rejects every mode with a 0 in its row.

    Parameters
    ----------
    sensitivity : array_like, shape (n_tests, n_modes)
        Entries ``True``/``1``/``"X"`` (sensitive) or ``False``/``0``/``"0"``.
    tests : sequence of str, optional
        Test names; ``T1, T2, ...`` by default.
    modes : sequence of str, optional
        Mode names; ``NF, F1, F2, ...`` by default when the first column is
        all zeros (a no-fault column), else ``F1, F2, ...``.

    Attributes
    ----------
    tests, modes : tuple of str
    sensitivity : numpy.ndarray of bool
        Read-only ``(n_tests, n_modes)`` array, ``True`` for X.

    Notes
    -----
    The decision structure of the lecture (test_quantities_lecture_sv.txt,
    "Teststorheten är ett modellvalideringsmått"): the row
    ``(0, 0, X, X)`` of a test over ``(NF, F1, F2, F3)`` means
    ``H0: Fp in {NF, F1}`` against ``H1: Fp in {F2, F3}``, and the model
    under H0 leaves ``theta_1`` free.  Mode ``i`` is isolable from mode ``j``
    when some row has an X under ``i`` and a 0 under ``j``
    (:meth:`isolability`).

    Examples
    --------
    The three tests of the lecture, each decoupling one parameter fault:

    >>> ds = DecisionStructure.from_text('''
    ...        NF F1 F2 F3
    ...     T1  0  0  X  X
    ...     T2  0  X  0  X
    ...     T3  0  X  X  0''')
    >>> print(ds.hypotheses("T1"))
    T1: H0: Fp in {NF, F1}  vs  H1: Fp in {F2, F3}
    >>> diagnoses(ds, {"T2": True, "T3": True})
    ('F1',)
    """

    def __init__(
        self, sensitivity, tests: Sequence[str] | None = None, modes: Sequence[str] | None = None
    ):
        matrix = _parse_sensitivity(sensitivity)
        n_tests, n_modes = matrix.shape
        if tests is None:
            tests = [f"T{k + 1}" for k in range(n_tests)]
        if modes is None:
            if n_modes > 1 and not matrix[:, 0].any():
                modes = ["NF"] + [f"F{k}" for k in range(1, n_modes)]
            else:
                modes = [f"F{k + 1}" for k in range(n_modes)]
        tests, modes = _names(tests, "tests", n_tests), _names(modes, "modes", n_modes)
        matrix.setflags(write=False)
        self._sensitivity = matrix
        self._tests = tests
        self._modes = modes

    @classmethod
    def from_text(cls, text: str) -> DecisionStructure:
        """Parse a table: a header line of mode names, then one line per test.

        Each test line is the test name followed by one ``0`` or ``X`` per
        mode, separated by white space (``|`` characters are ignored).
        """
        lines = [ln.replace("|", " ").split() for ln in str(text).strip().splitlines()]
        lines = [ln for ln in lines if ln]
        if len(lines) < 2:
            raise ValueError(
                "a decision structure table needs a header line of mode names and at "
                "least one test line, e.g. 'NF F1\\nT1 0 X'"
            )
        modes = lines[0]
        tests, rows = [], []
        for line in lines[1:]:
            if len(line) != len(modes) + 1:
                raise ValueError(
                    f"test line {' '.join(line)!r} has {len(line) - 1} entries but the header "
                    f"names {len(modes)} modes; give one 0 or X per mode after the test name"
                )
            tests.append(line[0])
            rows.append(line[1:])
        return cls(rows, tests=tests, modes=modes)

    # -- accessors -----------------------------------------------------------
    @property
    def tests(self) -> tuple:
        return self._tests

    @property
    def modes(self) -> tuple:
        return self._modes

    @property
    def sensitivity(self) -> np.ndarray:
        return self._sensitivity

    @property
    def shape(self) -> tuple:
        return self._sensitivity.shape

    def row_index(self, test) -> int:
        """Row index of ``test`` (a name or an index)."""
        return _lookup(test, self._tests, "test")

    def mode_index(self, mode) -> int:
        """Column index of ``mode`` (a name or an index)."""
        return _lookup(mode, self._modes, "mode")

    def row(self, test) -> dict:
        """``{mode: "0" or "X"}`` for one test."""
        k = self.row_index(test)
        return {m: ("X" if s else "0") for m, s in zip(self._modes, self._sensitivity[k])}

    def hypotheses(self, test) -> Hypotheses:
        """The hypotheses test ``test`` decides (0-modes against X-modes)."""
        k = self.row_index(test)
        row = self._sensitivity[k]
        return Hypotheses(
            test=self._tests[k],
            null=tuple(m for m, s in zip(self._modes, row) if not s),
            alternative=tuple(m for m, s in zip(self._modes, row) if s),
        )

    def isolability(self) -> np.ndarray:
        """``(n_modes, n_modes)`` bool: ``[i, j]`` true when mode i is isolable from j.

        Under the single-fault assumption mode ``i`` can be told apart from
        mode ``j`` when some test has an X for ``i`` and a 0 for ``j``: that
        test's alarm rules ``j`` out and is possible under ``i``.
        """
        S = self._sensitivity
        return (S[:, :, None] & ~S[:, None, :]).any(axis=0)

    # -- comparison and display ---------------------------------------------------
    def __eq__(self, other) -> bool:
        if not isinstance(other, DecisionStructure):
            return NotImplemented
        return (
            self._tests == other._tests
            and self._modes == other._modes
            and np.array_equal(self._sensitivity, other._sensitivity)
        )

    def __hash__(self):
        return hash((self._tests, self._modes, self._sensitivity.tobytes()))

    def to_text(self) -> str:
        """The table as aligned plain text (what ``print`` shows)."""
        width = max(len(t) for t in self._tests)
        cols = [max(len(m), 1) for m in self._modes]
        header = " " * width + "  " + "  ".join(m.rjust(c) for m, c in zip(self._modes, cols))
        lines = [header.rstrip()]
        for name, row in zip(self._tests, self._sensitivity):
            marks = "  ".join(("X" if s else "0").rjust(c) for s, c in zip(row, cols))
            lines.append(name.ljust(width) + "  " + marks)
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.to_text()

    def __repr__(self) -> str:
        return f"DecisionStructure(\n{self.to_text()}\n)"

    def _repr_html_(self) -> str:
        head = "".join(f"<th style='text-align:center'>{html.escape(m)}</th>" for m in self._modes)
        body = []
        for name, row in zip(self._tests, self._sensitivity):
            cells = "".join(f"<td style='text-align:center'>{'X' if s else '0'}</td>" for s in row)
            body.append(f"<tr><th style='text-align:left'>{html.escape(name)}</th>{cells}</tr>")
        return (
            "<table><caption>decision structure</caption>"
            f"<tr><th></th>{head}</tr>{''.join(body)}</table>"
        )


def _parse_sensitivity(value) -> np.ndarray:
    if isinstance(value, DecisionStructure):
        return value.sensitivity.copy()
    try:
        rows = [list(row) for row in (value.tolist() if isinstance(value, np.ndarray) else value)]
    except TypeError:
        raise ValueError(
            "a decision structure is a 2-D table, one row per test and one entry per fault mode, "
            f"e.g. [[0, 0, 1], [0, 1, 0]]; got {value!r}"
        ) from None
    if not rows or not rows[0]:
        raise ValueError("a decision structure needs at least one test and one mode")
    width = len(rows[0])
    matrix = np.zeros((len(rows), width), dtype=bool)
    for k, row in enumerate(rows):
        if len(row) != width:
            raise ValueError(
                f"row {k} of the decision structure has {len(row)} entries, row 0 has {width}; "
                "every test needs one entry per fault mode"
            )
        for j, entry in enumerate(row):
            matrix[k, j] = _mark(entry, k, j)
    return matrix


def _mark(entry, k, j) -> bool:
    if isinstance(entry, str):
        if entry.strip() in _X_MARKS:
            return True
        if entry.strip() in _ZERO_MARKS:
            return False
    elif isinstance(entry, (bool, np.bool_)) or (
        isinstance(entry, (int, float, np.integer, np.floating)) and entry in (0, 1)
    ):
        return bool(entry)
    raise ValueError(
        f"entry ({k}, {j}) of the decision structure is {entry!r}; use 0 (not sensitive) "
        "or X (may alarm), or False/True"
    )


def _names(names, what, size) -> tuple:
    names = tuple(str(n) for n in names)
    if len(names) != size:
        raise ValueError(f"{what} names {len(names)} entries but the table has {size}")
    if len(set(names)) != len(names):
        raise ValueError(f"{what} names must be unique, got {list(names)}")
    return names


def _lookup(key, names, what) -> int:
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
        if not 0 <= int(key) < len(names):
            raise ValueError(f"{what} index {key} out of range 0..{len(names) - 1}")
        return int(key)
    try:
        return names.index(str(key))
    except ValueError:
        raise ValueError(f"unknown {what} {key!r}; the structure has {list(names)}") from None


def _alarm_vector(structure: DecisionStructure, alarms) -> np.ndarray:
    n_tests = len(structure.tests)
    if isinstance(alarms, Mapping):
        vector = np.zeros(n_tests, dtype=bool)
        for key, value in alarms.items():
            vector[structure.row_index(key)] = _as_alarm(value)
        return vector
    if isinstance(alarms, (str, bytes)):
        alarms = [alarms]
    items = list(alarms)
    if not items:  # no test named: nothing alarmed
        return np.zeros(n_tests, dtype=bool)
    if all(isinstance(a, str) for a in items):
        vector = np.zeros(n_tests, dtype=bool)
        for name in items:
            vector[structure.row_index(name)] = True
        return vector
    if len(items) != n_tests:
        raise ValueError(
            f"alarms has {len(items)} entries but the structure has {n_tests} tests "
            f"{list(structure.tests)}; pass one True/False (or TestResult) per test, "
            "the names of the tests that alarmed, or a {test: alarm} mapping"
        )
    return np.array([_as_alarm(a) for a in items], dtype=bool)


def _as_alarm(value) -> bool:
    if isinstance(value, TestResult):
        return value.reject
    if isinstance(value, (bool, np.bool_)) or value in (0, 1):
        return bool(value)
    raise ValueError(f"an alarm must be True/False, 0/1 or a TestResult, got {value!r}")


def diagnoses(structure: DecisionStructure, alarms, *, exoneration: bool = False) -> tuple:
    """The fault modes consistent with the alarms, assuming a single fault.

    Parameters
    ----------
    structure : DecisionStructure
        Tests x modes, 0 or X.
    alarms : mapping, sequence of bool/TestResult, or sequence of str
        ``{test: alarmed}``; one ``True``/``False`` (or a :class:`TestResult`,
        whose ``reject`` is used) per test in the structure's order; or the
        names of the tests that alarmed.
    exoneration : bool, default False
        Also let a test that did *not* alarm rule out the modes with an X in
        its row.  This reads X as "will alarm", which is rarely justified:
        a small fault or poor excitation may leave a sensitive test silent.

    Returns
    -------
    tuple of str
        The diagnoses: the modes, in the structure's order, that no alarm
        contradicts.  All modes when nothing alarmed; empty when the alarms
        cannot be explained by any single mode.

    Notes
    -----
    An alarm from test ``T`` rejects its null hypothesis, so it rules out
    every mode with a 0 in row ``T``.  Under the single-fault assumption the
    diagnoses are the intersection, over the alarmed tests, of the sets of
    modes with an X (the lecture's decision structure,
    test_quantities_lecture_sv.txt, "Teststorheten är ett
    modellvalideringsmått").

    *Multiple faults.*  If several faults may be present at once, a mode
    is no longer one column: a diagnosis is a *set* of faults.  Each alarm
    gives a *conflict*, the set of faults with an X in the alarmed row (at
    least one of them must be present).  A set of faults explains all
    alarms when it intersects every conflict, i.e. it is a *hitting set*,
    and the diagnosis statement is the collection of *minimal* hitting sets
    (Reiter 1987; de Kleer and Williams 1987), since any superset of a
    diagnosis is also consistent.  This needs the further assumption that
    a combination of faults can only make a test alarm if one of its
    members can.  See :func:`multiple_fault_diagnoses`.
    """
    if not isinstance(structure, DecisionStructure):
        raise ValueError(
            "structure must be a DecisionStructure (build one with DecisionStructure(...))"
        )
    alarm = _alarm_vector(structure, alarms)
    consistent = diagnosis_matrix(structure, alarm[None, :], exoneration=exoneration)[0]
    return tuple(m for m, ok in zip(structure.modes, consistent) if ok)


def diagnosis_matrix(
    structure: DecisionStructure, alarms, *, exoneration: bool = False
) -> np.ndarray:
    """Single-fault diagnoses of many alarm patterns at once.

    Parameters
    ----------
    structure : DecisionStructure
    alarms : array_like of bool, shape (M, n_tests)
        One alarm pattern per row.
    exoneration : bool, default False
        See :func:`diagnoses`.

    Returns
    -------
    numpy.ndarray of bool, shape (M, n_modes)
        ``[m, j]`` is true when mode ``j`` is a diagnosis of pattern ``m``.

    Notes
    -----
    Mode ``j`` is inconsistent with pattern ``m`` exactly when some alarmed
    test has a 0 for ``j``: ``any_k alarm[m, k] and not X[k, j]``, one
    boolean matrix product for all patterns.
    """
    alarms = np.asarray(alarms)
    if alarms.ndim != 2 or alarms.shape[1] != len(structure.tests):
        raise ValueError(
            f"alarms must have shape (M, {len(structure.tests)}), one column per test, "
            f"got {alarms.shape}"
        )
    if alarms.dtype != bool:
        if not np.isin(alarms, (0, 1)).all():
            raise ValueError("alarms must be boolean (or 0/1)")
        alarms = alarms.astype(bool)
    X = structure.sensitivity.astype(np.int64)
    ruled_out = (alarms.astype(np.int64) @ (1 - X)) > 0
    if exoneration:
        ruled_out |= ((~alarms).astype(np.int64) @ X) > 0
    return ~ruled_out


def multiple_fault_diagnoses(
    structure: DecisionStructure,
    alarms,
    *,
    no_fault: str | None = "NF",
    max_size: int | None = None,
) -> list:
    """Minimal multiple-fault diagnoses: the minimal hitting sets of the conflicts.

    Parameters
    ----------
    structure : DecisionStructure
    alarms : see :func:`diagnoses`
    no_fault : str or None, default "NF"
        Name of the no-fault column, which is not a fault and is left out.
    max_size : int, optional
        Largest number of simultaneous faults to consider.

    Returns
    -------
    list of tuple of str
        The minimal diagnoses, smallest first; ``[()]`` (the empty set:
        no fault) when nothing alarmed, ``[]`` when no combination explains
        the alarms.

    Notes
    -----
    Conflict of alarmed test ``T``: the faults with an X in its row.  A set
    of faults is a diagnosis when it meets every conflict; enumerating the
    candidate sets by increasing size and keeping those with no diagnosed
    subset gives the minimal ones (fine for the handful of faults of a
    course example; large systems need Reiter's HS-tree or similar).
    """
    alarm = _alarm_vector(structure, alarms)
    faults = [j for j, m in enumerate(structure.modes) if m != no_fault]
    S = structure.sensitivity
    conflicts = [frozenset(j for j in faults if S[k, j]) for k in np.flatnonzero(alarm)]
    if any(not c for c in conflicts):
        return []
    limit = len(faults) if max_size is None else int(max_size)
    found: list[frozenset] = []
    for size in range(limit + 1):
        for candidate in itertools.combinations(faults, size):
            cand = frozenset(candidate)
            if any(f <= cand for f in found):
                continue
            if all(cand & c for c in conflicts):
                found.append(cand)
    return [tuple(structure.modes[j] for j in sorted(f)) for f in found]


def linear_decision_structure(
    U, modes: Mapping[str, Sequence[int]], tests: Mapping[str, Sequence[int]], rtol: float = 1e-9
) -> DecisionStructure:
    """The decision structure that prediction-error tests really have for given signals.

    Parameters
    ----------
    U : array_like, shape (N, p)
        Regressors (one column per parameter) of ``y = U theta + v``.
    modes : mapping of str to sequence of int
        For each fault mode, the parameters that deviate in it (``()`` for NF).
    tests : mapping of str to sequence of int
        For each test, its free parameters (the faults it decouples).
    rtol : float
        A mode counts as invisible to a test when the part of its fault
        directions outside the span of the test's free columns is below
        ``rtol`` times their norm.

    Returns
    -------
    DecisionStructure
        X where some fault in the mode leaves a residual in the test, 0
        where every fault of the mode is absorbed by the free parameters.

    Notes
    -----
    The test's residual is ``(I - P) y`` with ``P`` the projection on the
    free columns, so a fault ``U_F d`` is seen exactly when
    ``(I - P) U_F != 0``; the lecture's "F2 is detected when U2 is not
    parallel to U1" is the case of one free column.
    """
    U = as_matrix(U, "U")
    p = U.shape[1]
    matrix = np.zeros((len(tests), len(modes)), dtype=bool)
    for k, free in enumerate(tests.values()):
        free = _indices(free, p, "test free parameters")
        basis = _range_basis(U[:, free])
        for j, faulty in enumerate(modes.values()):
            faulty = _indices(faulty, p, "mode parameters")
            if not faulty:
                continue
            D = U[:, faulty]
            leftover = D - basis @ (basis.T @ D)
            scale = max(np.linalg.norm(D), np.finfo(float).tiny)
            matrix[k, j] = np.linalg.norm(leftover) > rtol * scale
    return DecisionStructure(matrix, tests=list(tests), modes=list(modes))


# ---------------------------------------------------------------------------
# prediction errors: linear regression
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class RegressionFit:
    """Least-squares fit of a linear regression that may lack excitation.

    Attributes
    ----------
    theta : numpy.ndarray
        A minimising parameter vector, ``(p,)`` or ``(p, M)``: the unique one
        when ``rank == p``, else the one of smallest norm (any other differs
        by a null-space vector of the regressors and fits equally well).
    residual : numpy.ndarray
        ``Y - Phi theta`` (unique even when theta is not), ``(N,)`` or ``(N, M)``.
    statistic : float or numpy.ndarray
        ``T = ||residual||^2``, one per record.
    rank : int
        Numerical rank of the regressor matrix.
    dof : int
        ``N - rank``: the dimension of the residual space.
    n_parameters : int
        Number of estimated parameters (for :func:`prediction_error`, the
        free ones; ``theta`` then holds the full vector).
    """

    theta: np.ndarray
    residual: np.ndarray
    statistic: Any
    rank: int
    dof: int
    n_parameters: int

    @property
    def unique(self) -> bool:
        """True when the regressors have full column rank (theta is unique)."""
        return self.rank == self.n_parameters

    def __repr__(self) -> str:
        if np.ndim(self.statistic) == 0:
            stat = format_number(float(self.statistic))
        else:
            stat = f"<{np.size(self.statistic)} records>"
        return (
            f"RegressionFit(statistic={stat}, rank={self.rank} of {self.n_parameters}, "
            f"dof={self.dof}, unique={self.unique})"
        )


def _range_basis(Phi: np.ndarray, rcond: float | None = None):
    """Orthonormal basis of range(Phi) from the SVD, with its rank decision."""
    N, p = Phi.shape
    if p == 0 or N == 0:
        return np.zeros((N, 0))
    left, s, _ = np.linalg.svd(Phi, full_matrices=False)
    rank = _numerical_rank(s, N, p, rcond)
    return left[:, :rank]


def _numerical_rank(s, N, p, rcond):
    if s.size == 0 or s[0] == 0.0:
        return 0
    tol = (max(N, p) * np.finfo(float).eps if rcond is None else float(rcond)) * s[0]
    return int(np.sum(s > tol))


def _data(y, N: int | None, name: str = "y") -> np.ndarray:
    y = as_float_array(y, name)
    if y.ndim not in (1, 2):
        raise ValueError(
            f"{name} must be one record of shape (N,) or M records as columns of an (N, M) "
            f"array, got shape {y.shape}"
        )
    if N is not None and y.shape[0] != N:
        raise ValueError(
            f"shape mismatch: {name} has {y.shape[0]} samples but the regressors have {N} rows; "
            "one regressor row per sample is needed"
        )
    return y


def least_squares_residual(y, Phi, rcond: float | None = None) -> RegressionFit:
    """``min over theta of ||y - Phi theta||^2``, correct also without excitation.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, M)
        One record, or ``M`` records as columns.
    Phi : array_like, shape (N, p)
        Regressor matrix; it may be rank deficient and ``p`` may be 0.
    rcond : float, optional
        Singular values below ``rcond * s_max`` count as zero; by default
        ``max(N, p) * eps`` (numpy's ``matrix_rank`` rule).

    Returns
    -------
    RegressionFit

    Notes
    -----
    The minimum is ``T = ||(I - Phi (Phi^T Phi)^{-1} Phi^T) y||^2`` (the
    lecture's projection form, slide "Linjär regression;
    minstakvadrat-metoden").  Forming ``Phi^T Phi`` squares the condition
    number and fails when the regressors lack excitation, so the projection
    is computed from the thin SVD ``Phi = W S V^T``: with ``W_r`` the left
    singular vectors of the ``r`` non-negligible singular values,
    ``residual = y - W_r (W_r^T y)``, which is the orthogonal projection of
    ``y`` on the complement of range(Phi) whatever the rank; and
    ``theta = V_r S_r^{-1} W_r^T y`` is the minimum-norm minimiser.  Every
    minimiser gives the same residual (slide "Excitation": there is always
    one shortest distance from a point to a subspace).
    """
    Phi = as_matrix(Phi, "Phi")
    N, p = Phi.shape
    Y = _data(y, N)
    if p == 0:
        theta = np.zeros((0,) + Y.shape[1:])
        return _fit_result(theta, Y.copy(), 0, N, 0)
    left, s, right_t = np.linalg.svd(Phi, full_matrices=False)
    rank = _numerical_rank(s, N, p, rcond)
    W, V = left[:, :rank], right_t[:rank].T
    coords = W.T @ Y
    residual = Y - W @ coords
    scaled = coords / (s[:rank, None] if Y.ndim == 2 else s[:rank])
    theta = V @ scaled
    return _fit_result(theta, residual, rank, N, p)


def _fit_result(theta, residual, rank, N, p) -> RegressionFit:
    stat = np.sum(residual**2, axis=0)
    stat = float(stat) if residual.ndim == 1 else stat
    return RegressionFit(
        theta=theta,
        residual=residual,
        statistic=stat,
        rank=int(rank),
        dof=int(N - rank),
        n_parameters=int(p),
    )


def _indices(free, p: int, what: str = "free") -> list:
    if free is None:
        return []
    if isinstance(free, (int, np.integer)):
        free = [free]
    out = []
    for j in free:
        if isinstance(j, bool) or not isinstance(j, (int, np.integer)):
            raise ValueError(f"{what} must be parameter indices (integers), got {j!r}")
        if not 0 <= int(j) < p:
            raise ValueError(f"{what} index {j} out of range for {p} parameters (0..{p - 1})")
        out.append(int(j))
    if len(set(out)) != len(out):
        raise ValueError(f"{what} contains repeated indices: {out}")
    return sorted(out)


def _model(U, nominal):
    U = as_matrix(U, "U")
    nominal = as_vector(nominal, "nominal", U.shape[1])
    return U, nominal


def _split(U, nominal, free):
    """Regressors of the free parameters and the known part of the prediction."""
    p = U.shape[1]
    fixed = [j for j in range(p) if j not in free]
    return U[:, free], U[:, fixed] @ nominal[fixed]


def prediction_error(
    y, U, nominal, free: Sequence[int] = (), rcond: float | None = None
) -> RegressionFit:
    """Prediction-error test quantity ``T = min over theta in Theta_0 of ||y - U theta||^2``.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, M)
        Measurements (``M`` records as columns for a Monte Carlo study).
    U : array_like, shape (N, p)
        The signals ``u_i(t)`` of ``y(t) = sum_i theta_i u_i(t) + v(t)``.
    nominal : array_like, shape (p,)
        Fault-free parameter values.
    free : sequence of int, default ()
        Parameters left free under H0 (the faults the test decouples).  With
        no free parameters ``T = V(nominal, y)``, the prediction error of a
        single model.
    rcond : float, optional
        Rank tolerance, see :func:`least_squares_residual`.

    Returns
    -------
    RegressionFit
        ``theta`` is the full parameter vector (nominal values in the fixed
        places), ``statistic`` is ``T``.

    Notes
    -----
    ``V(theta, z) = sum_t (y(t) - yhat(t|theta))^2`` and
    ``T(z) = min over theta in Theta_0 of V(theta, z)`` (lecture, slide
    "Teststorhet baserad på prediktionsfelen").  With the fixed parameters
    moved to the left, ``y - U_fixed nominal_fixed = U_free theta_free + v``
    is a linear regression in the free parameters.

    Examples
    --------
    The lecture's test T1, H0: Fp in {NF, F1} (theta_1 free):

    >>> import numpy as np
    >>> U = np.array([[1., 0, 1], [2, 1, 0], [0, 1, 1], [1, 1, 1]])
    >>> y = U @ [3.0, 1, 1]           # a fault in theta_1 only
    >>> round(prediction_error(y, U, [1, 1, 1], free=[0]).statistic, 12)
    0.0
    """
    U, nominal = _model(U, nominal)
    free = _indices(free, U.shape[1])
    Y = _data(y, U.shape[0])
    Phi, known = _split(U, nominal, free)
    target = Y - (known[:, None] if Y.ndim == 2 else known)
    fit = least_squares_residual(target, Phi, rcond=rcond)
    theta = np.repeat(nominal[:, None], Y.shape[1], axis=1) if Y.ndim == 2 else nominal.copy()
    theta[free] = fit.theta
    return RegressionFit(
        theta=theta,
        residual=fit.residual,
        statistic=fit.statistic,
        rank=fit.rank,
        dof=fit.dof,
        n_parameters=len(free),
    )


def _count(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _check_sigma(sigma) -> float:
    try:
        value = float(sigma)
    except (TypeError, ValueError):
        raise ValueError(
            f"sigma must be a positive number (the noise standard deviation), got {sigma!r}"
        ) from None
    if not np.isfinite(value) or value <= 0:
        raise ValueError(
            f"sigma must be a positive, finite noise standard deviation, got {sigma!r}"
        )
    return value


def _scaled_chi2(dof, sigma):
    return stats.chi2(dof) if sigma == 1.0 else stats.chi2(dof, scale=sigma**2)


def residual_threshold(alpha: float, dof: int, sigma: float = 1.0) -> float:
    """Threshold ``J`` on ``T = ||residual||^2`` with false-alarm rate ``alpha``.

    Parameters
    ----------
    alpha : float
        False-alarm probability ``P(T > J | H0)``.
    dof : int
        Residual degrees of freedom ``N - rank``.
    sigma : float, default 1
        Noise standard deviation.

    Returns
    -------
    float
        ``J = sigma^2 * chi2.isf(alpha, dof)``.

    Notes
    -----
    Under H0 the residual is ``(I - P) v`` with ``v ~ N(0, sigma^2 I)`` and
    ``I - P`` an orthogonal projection of rank ``N - rank(Phi)``, so
    ``T / sigma^2 ~ chi2(N - rank)`` (Cochran's theorem).  The lecture
    leaves threshold selection to the next lecture (last slide).  The
    argument order follows ``scipy.stats.chi2.isf(alpha, dof)``; for a
    windowed sum of normalised innovations use
    :func:`course.filters.windowed_nis_threshold`.
    """
    alpha = check_alpha(alpha)
    dof = _check_dof(dof)
    return float(_check_sigma(sigma) ** 2 * stats.chi2.isf(alpha, dof))


def _check_dof(dof) -> int:
    if (
        isinstance(dof, bool)
        or not isinstance(dof, (int, float, np.integer, np.floating))
        or not np.isfinite(dof)
        or int(dof) != dof
        or dof < 1
    ):
        raise ValueError(
            f"dof must be a positive integer, got {dof!r}; with no residual degrees of freedom "
            "the model under H0 fits any data exactly and the test is void"
        )
    return int(dof)


def _void_test_message(dof_what: str) -> str:
    return (
        f"the test has no redundancy ({dof_what}): the model under H0 fits any data exactly, "
        "so T is identically 0 and carries no information; use more samples or fewer free parameters"
    )


def prediction_error_test(
    y,
    U,
    nominal,
    free: Sequence[int] = (),
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str = "prediction-error test",
    rcond: float | None = None,
) -> TestResult:
    """Chi-square test of the prediction error ``T = min over Theta_0 ||y - U theta||^2``.

    Parameters
    ----------
    y : array_like, shape (N,)
        One record.
    U, nominal, free, rcond
        As in :func:`prediction_error`.
    sigma : float
        Known noise standard deviation.
    alpha : float, default 0.05
        False-alarm rate.
    name : str
        Name shown in the result.

    Returns
    -------
    TestResult
        ``statistic = T``, ``null = sigma^2 chi2(N - rank)``, critical value
        ``sigma^2 chi2.isf(alpha, N - rank)``; details hold the normalised
        statistic ``T / sigma^2`` and the rank.

    Raises
    ------
    ValueError
        Bad shapes or NaN, ``sigma <= 0``, or no redundancy (``N = rank``).

    Notes
    -----
    See :func:`residual_threshold` for the null law and :func:`prediction_error`
    for ``T``.
    """
    alpha = check_alpha(alpha)
    sigma = _check_sigma(sigma)
    y = as_vector(y, "y")
    fit = prediction_error(y, U, nominal, free, rcond=rcond)
    if fit.dof < 1:
        raise ValueError(_void_test_message(f"N = rank = {fit.rank}"))
    null = _scaled_chi2(fit.dof, sigma)
    crit = sigma**2 * stats.chi2.isf(alpha, fit.dof)
    stat = fit.statistic
    return TestResult(
        name=name,
        statistic=stat,
        alpha=alpha,
        critical_value=crit,
        pvalue=stats.chi2.sf(stat / sigma**2, fit.dof),
        reject=stat > crit,
        null=null,
        dof=fit.dof,
        alternative="greater",
        details={"T/sigma^2": stat / sigma**2, "rank": fit.rank},
    )


def fault_noncentrality(U, nominal, free: Sequence[int], theta, sigma: float = 1.0) -> Any:
    """Non-centrality of a test's ``T / sigma^2`` when the data come from ``theta``.

    Parameters
    ----------
    U, nominal, free
        The test, as in :func:`prediction_error`.
    theta : array_like, shape (p,) or (p, K)
        True parameter vector(s).
    sigma : float
        Noise standard deviation.

    Returns
    -------
    float or numpy.ndarray
        ``lambda = ||(I - P)(U (theta - nominal))||^2 / sigma^2``, one per column.

    Notes
    -----
    With ``y = U theta + v`` the residual of the test is
    ``(I - P)(U (theta - nominal)) + (I - P) v``: the fault part is a fixed
    vector, so ``T / sigma^2`` is non-central chi-square with this
    non-centrality.  The free parameters' deviations are annihilated by
    ``I - P``: the test is blind to them, which is the decoupling.  (Not to
    be confused with :func:`course.lsq.noncentrality`, the non-centrality a
    test *needs* for a given power.)
    """
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    free = _indices(free, U.shape[1])
    theta = as_float_array(theta, "theta")
    if theta.ndim not in (1, 2) or theta.shape[0] != U.shape[1]:
        raise ValueError(
            f"theta must have shape ({U.shape[1]},) or ({U.shape[1]}, K), got {theta.shape}"
        )
    shift = U @ (theta - (nominal[:, None] if theta.ndim == 2 else nominal))
    basis = _range_basis(U[:, free])
    leftover = shift - basis @ (basis.T @ shift)
    lam = np.sum(leftover**2, axis=0) / sigma**2
    return float(lam) if theta.ndim == 1 else lam


def prediction_error_power(
    U, nominal, free: Sequence[int], theta, *, sigma: float, alpha: float = 0.05
) -> Any:
    """Probability that the prediction-error test alarms when the truth is ``theta``.

    Parameters
    ----------
    U, nominal, free
        The test, as in :func:`prediction_error`.
    theta : array_like, shape (p,) or (p, K)
        True parameter vector(s), e.g. a fault of growing size.
    sigma : float
        Noise standard deviation.
    alpha : float
        False-alarm rate of the test.

    Returns
    -------
    float or numpy.ndarray
        ``P(T > J)`` with ``J`` the threshold of :func:`residual_threshold`;
        equal to ``alpha`` when the fault is invisible to the test.

    Notes
    -----
    ``T / sigma^2 ~ chi2'(N - rank, lambda)`` (non-central chi-square, see
    :func:`fault_noncentrality`), so the power is
    ``ncx2.sf(chi2.isf(alpha, dof), dof, lambda)``: the answer to the
    lecture's closing question "how good is a test?".
    """
    alpha = check_alpha(alpha)
    U, nominal = _model(U, nominal)
    free = _indices(free, U.shape[1])
    lam = np.asarray(fault_noncentrality(U, nominal, free, theta, sigma))
    dof = U.shape[0] - _range_basis(U[:, free]).shape[1]
    if dof < 1:
        raise ValueError(_void_test_message(f"N - rank = {dof}"))
    crit = stats.chi2.isf(alpha, dof)
    power = np.where(lam > 0, stats.ncx2.sf(crit, dof, np.maximum(lam, 1e-300)), alpha)
    return float(power) if power.ndim == 0 else power


# ---------------------------------------------------------------------------
# prediction errors: general models
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class NonlinearFit:
    """Result of :func:`nonlinear_prediction_error`.

    Attributes
    ----------
    theta : numpy.ndarray
        Minimising full parameter vector (nominal values in fixed places).
    residual : numpy.ndarray
        ``y - yhat(theta)`` (flattened).
    statistic : float
        ``T = ||residual||^2``.
    success : bool
        Whether the optimiser reported convergence.
    message : str
        The optimiser's message.
    jacobian : numpy.ndarray
        Jacobian of the prediction w.r.t. the free parameters at the optimum.
    """

    theta: np.ndarray
    residual: np.ndarray
    statistic: float
    success: bool
    message: str
    jacobian: np.ndarray

    def __repr__(self) -> str:
        return (
            f"NonlinearFit(statistic={format_number(self.statistic)}, "
            f"theta=[{', '.join(format_number(float(v)) for v in self.theta)}], success={self.success})"
        )


def nonlinear_prediction_error(
    y,
    predict: Callable,
    nominal,
    free: Sequence[int] = (),
    *,
    theta_init=None,
    bounds=None,
    **options,
) -> NonlinearFit:
    """``T = min over theta in Theta_0 of sum_t ||y(t) - yhat(t|theta)||^2`` for any model.

    Parameters
    ----------
    y : array_like
        Measurements (any shape; compared element-wise with the prediction).
    predict : callable
        ``predict(theta)`` returns ``yhat(theta)`` with the shape of ``y``,
        for a full parameter vector ``theta``.
    nominal : array_like, shape (p,)
        Values of the parameters that are fixed under H0.
    free : sequence of int, default ()
        Parameters estimated under H0.
    theta_init : array_like, optional
        Starting values of the free parameters (their nominal values by default).
    bounds : (lower, upper), optional
        Bounds on the free parameters, as for :func:`scipy.optimize.least_squares`.
    **options
        Passed to :func:`scipy.optimize.least_squares` (e.g. ``x_scale``).

    Returns
    -------
    NonlinearFit

    Notes
    -----
    The general form of the lecture's prediction-error test quantity (slide
    "Minimering av V(θ, z)": general optimisation, system identification).
    The minimisation is local (trust-region reflective): for a criterion
    with several minima, start from several ``theta_init`` and keep the
    smallest ``T``.
    """
    nominal = as_vector(nominal, "nominal")
    p = nominal.size
    free = _indices(free, p)
    y = as_float_array(y, "y")

    def full(theta_free):
        theta = nominal.copy()
        theta[free] = theta_free
        return theta

    def residual(theta_free):
        pred = np.asarray(predict(full(theta_free)), dtype=float)
        if pred.shape != y.shape:
            raise ValueError(f"predict returned shape {pred.shape}, but y has shape {y.shape}")
        return (y - pred).ravel()

    if not free:
        r = residual(np.zeros(0))
        return NonlinearFit(
            theta=nominal.copy(),
            residual=r,
            statistic=float(r @ r),
            success=True,
            message="no free parameters",
            jacobian=np.zeros((r.size, 0)),
        )
    start = nominal[free] if theta_init is None else as_vector(theta_init, "theta_init", len(free))
    kwargs = dict(options)
    if bounds is not None:
        kwargs["bounds"] = bounds
    kwargs.setdefault("xtol", 1e-12)
    kwargs.setdefault("ftol", 1e-12)
    kwargs.setdefault("gtol", 1e-12)
    sol = optimize.least_squares(residual, start, **kwargs)
    r = residual(sol.x)
    return NonlinearFit(
        theta=full(sol.x),
        residual=r,
        statistic=float(r @ r),
        success=bool(sol.success),
        message=str(sol.message),
        jacobian=-sol.jac,
    )


# ---------------------------------------------------------------------------
# parameter estimates
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class ParameterEstimate:
    """Least-squares estimate of some parameters with the others at nominal.

    Attributes
    ----------
    theta : numpy.ndarray
        Full parameter vector ``(p,)`` or ``(p, M)``: estimates at
        ``indices``, nominal values elsewhere.
    indices : tuple of int
        The estimated parameters.
    covariance : numpy.ndarray
        ``(k, k)`` covariance of the estimated parameters,
        ``sigma^2 (Phi^T Phi)^{-1}``.
    """

    theta: np.ndarray
    indices: tuple
    covariance: np.ndarray

    @property
    def std(self) -> np.ndarray:
        """Standard deviations of the estimated parameters."""
        return np.sqrt(np.diag(self.covariance))

    def __repr__(self) -> str:
        if self.theta.ndim == 1:
            est = ", ".join(format_number(float(self.theta[j])) for j in self.indices)
            return f"ParameterEstimate(indices={self.indices}, estimate=[{est}])"
        return f"ParameterEstimate(indices={self.indices}, records={self.theta.shape[1]})"


def estimate_parameters(
    y, U, nominal, estimate: Sequence[int], *, sigma: float
) -> ParameterEstimate:
    """Estimate the parameters ``estimate`` by least squares, the rest at nominal.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, M)
    U, nominal
        As in :func:`prediction_error`.
    estimate : sequence of int
        Parameters to estimate (at least one).
    sigma : float
        Noise standard deviation (for the covariance).

    Returns
    -------
    ParameterEstimate

    Raises
    ------
    numpy.linalg.LinAlgError
        The regressors of the estimated parameters are not linearly
        independent (no excitation): the estimate is not unique.

    Notes
    -----
    ``theta_hat = R^{-1} Q^T (y - U_fixed nominal_fixed)`` from the thin QR
    factorisation ``U_est = Q R``, and ``Cov = sigma^2 R^{-1} R^{-T}``
    (``= sigma^2 (Phi^T Phi)^{-1}`` without forming ``Phi^T Phi``).  The
    lecture's warning (slide "Teststorheter baserade på
    parameterskattningar"): this needs excitation.
    """
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    est = _indices(estimate, U.shape[1], "estimate")
    if not est:
        raise ValueError("estimate must name at least one parameter")
    Y = _data(y, U.shape[0])
    Phi, known = _split(U, nominal, est)
    check_full_column_rank(Phi, "the regressors of the estimated parameters")
    Q, R = np.linalg.qr(Phi)
    target = Y - (known[:, None] if Y.ndim == 2 else known)
    theta_est = sla.solve_triangular(R, Q.T @ target, lower=False)
    R_inv = sla.solve_triangular(R, np.eye(len(est)), lower=False)
    cov = sigma**2 * symmetrize(R_inv @ R_inv.T)
    theta = np.repeat(nominal[:, None], Y.shape[1], axis=1) if Y.ndim == 2 else nominal.copy()
    theta[est] = theta_est
    return ParameterEstimate(theta=theta, indices=tuple(est), covariance=cov)


def parameter_estimate_test(
    estimate, covariance, nominal, alpha: float = 0.05, name: str = "parameter-estimate test"
) -> TestResult:
    """Test ``H0: theta = nominal`` from an estimate and its covariance.

    Parameters
    ----------
    estimate : float or array_like, shape (k,)
        The estimate ``theta_hat`` of the tested parameter(s).
    covariance : float or array_like, shape (k, k)
        Its covariance (a variance for one parameter).
    nominal : float or array_like, shape (k,)
        The fault-free value(s).
    alpha : float, default 0.05
    name : str

    Returns
    -------
    TestResult
        One parameter: ``statistic = |theta_hat - nominal|`` with null law
        ``halfnorm(scale=std)`` and threshold ``std * z_{alpha/2}``.
        Several: the Wald statistic
        ``(theta_hat - nominal)^T C^{-1} (theta_hat - nominal)`` with
        null law ``chi2(k)``.

    Notes
    -----
    The lecture's ``T = |theta_hat_i - theta_i^0|`` (slide "Teststorheter
    baserade på parameterskattningar").  For a Gaussian estimate,
    ``theta_hat - theta^0 ~ N(0, s^2)`` under H0, so ``T`` is half-normal
    and ``P(T > s z_{alpha/2}) = alpha``: the covariance turns a false-alarm
    rate into a threshold.  The Wald form is the same idea for a vector
    (a quadratic form in a Gaussian vector, ``chi2(k)``).
    """
    alpha = check_alpha(alpha)
    est = np.atleast_1d(as_float_array(estimate, "estimate"))
    if est.ndim != 1:
        raise ValueError(
            f"estimate must be a number or a 1-D vector, got shape {np.shape(estimate)}"
        )
    k = est.size
    nom = np.atleast_1d(as_float_array(nominal, "nominal"))
    if nom.shape != (k,):
        raise ValueError(f"nominal must have the shape of the estimate ({k},), got {nom.shape}")
    cov = as_float_array(covariance, "covariance")
    cov = as_covariance(cov.reshape(1, 1) if cov.ndim == 0 else cov, "covariance", k)
    diff = est - nom
    if k == 1:
        std = float(np.sqrt(cov[0, 0]))
        null = stats.halfnorm(scale=std)
        stat = abs(float(diff[0]))
        crit = std * stats.norm.isf(alpha / 2)
        return TestResult(
            name=name,
            statistic=stat,
            alpha=alpha,
            critical_value=crit,
            pvalue=stats.halfnorm.sf(stat / std),
            reject=stat > crit,
            null=null,
            alternative="greater",
            details={"estimate": float(est[0]), "std": std, "z": stat / std},
        )
    wald = float(diff @ solve_spd(cov, diff, "covariance"))
    crit = stats.chi2.isf(alpha, k)
    return TestResult(
        name=name,
        statistic=wald,
        alpha=alpha,
        critical_value=crit,
        pvalue=stats.chi2.sf(wald, k),
        reject=wald > crit,
        null=stats.chi2(k),
        dof=k,
        alternative="greater",
    )


def regression_parameter_test(
    y,
    U,
    nominal,
    estimate: Sequence[int],
    test,
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str | None = None,
) -> TestResult:
    """Estimate parameters ``estimate`` and test ``theta_test = nominal_test``.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal
        As in :func:`prediction_error`.
    estimate : sequence of int
        Parameters estimated together (the tested ones and the ones to
        decouple).
    test : int or sequence of int
        Parameter(s) compared with nominal; a subset of ``estimate``.
    sigma : float
    alpha : float
    name : str, optional

    Returns
    -------
    TestResult
        See :func:`parameter_estimate_test`.

    Notes
    -----
    The lecture's ``T1 = |theta_hat_2 - 1|`` with ``(theta_hat_1,
    theta_hat_2) = argmin sum (y - theta_1 u1 - theta_2 u2 - u3)^2``: the
    fault in ``theta_1`` is decoupled because ``theta_1`` is estimated too.
    """
    U, nominal = _model(U, nominal)
    est = _indices(estimate, U.shape[1], "estimate")
    tested = _indices(test, U.shape[1], "test")
    if not tested or not set(tested) <= set(est):
        raise ValueError(f"test {tested} must be a non-empty subset of estimate {est}")
    fit = estimate_parameters(as_vector(y, "y", U.shape[0]), U, nominal, est, sigma=sigma)
    pos = [est.index(j) for j in tested]
    if name is None:
        name = "parameter-estimate test of theta_" + ",".join(str(j + 1) for j in tested)
    return parameter_estimate_test(
        fit.theta[tested], fit.covariance[np.ix_(pos, pos)], nominal[tested], alpha=alpha, name=name
    )


def parameter_estimate_power(
    U, nominal, estimate: Sequence[int], test, theta, *, sigma: float, alpha: float = 0.05
) -> Any:
    """Alarm probability of :func:`regression_parameter_test` when the truth is ``theta``.

    Parameters
    ----------
    U, nominal, estimate, test, sigma, alpha
        As in :func:`regression_parameter_test`.
    theta : array_like, shape (p,) or (p, K)
        True parameter vector(s).

    Returns
    -------
    float or numpy.ndarray

    Notes
    -----
    The estimate is unbiased for the estimated parameters, but a deviation
    of a *fixed* parameter leaks into it through the regressors:
    ``E theta_hat = theta_est + (Phi^T Phi)^{-1} Phi^T U_fixed (theta - nominal)_fixed``.
    That leak is the isolation problem of the lecture.  With mean shift
    ``b`` and standard deviation ``s`` of the tested estimate, the power of
    the two-sided test is ``Phi((b - c)/s) + Phi((-b - c)/s)`` with
    ``c = s z_{alpha/2}``; for several tested parameters the Wald statistic
    is ``chi2'(k, b^T C^{-1} b)``.
    """
    alpha = check_alpha(alpha)
    U, nominal = _model(U, nominal)
    sigma = _check_sigma(sigma)
    p = U.shape[1]
    est = _indices(estimate, p, "estimate")
    tested = _indices(test, p, "test")
    if not tested or not set(tested) <= set(est):
        raise ValueError(f"test {tested} must be a non-empty subset of estimate {est}")
    theta = as_float_array(theta, "theta")
    if theta.ndim not in (1, 2) or theta.shape[0] != p:
        raise ValueError(f"theta must have shape ({p},) or ({p}, K), got {theta.shape}")
    # The mean of the estimate is the noise-free fit to U theta.
    mean = estimate_parameters(U @ theta, U, nominal, est, sigma=sigma)
    shift = mean.theta[tested] - (nominal[tested][:, None] if theta.ndim == 2 else nominal[tested])
    pos = [est.index(j) for j in tested]
    cov = mean.covariance[np.ix_(pos, pos)]
    if len(tested) == 1:
        s = float(np.sqrt(cov[0, 0]))
        c = stats.norm.isf(alpha / 2)
        b = shift[0] / s
        power = stats.norm.sf(c - b) + stats.norm.cdf(-c - b)
    else:
        L = cholesky_lower(cov, "covariance")
        lam = np.sum(sla.solve_triangular(L, shift, lower=True) ** 2, axis=0)
        k = len(tested)
        power = np.where(
            lam > 0, stats.ncx2.sf(stats.chi2.isf(alpha, k), k, np.maximum(lam, 1e-300)), alpha
        )
    power = np.asarray(power)
    return float(power) if power.ndim == 0 else power


# ---------------------------------------------------------------------------
# likelihood
# ---------------------------------------------------------------------------
def normal_log_likelihood(theta, z, sigma: float = 1.0) -> Any:
    """``log L(theta | z)`` for independent ``z_i ~ N(theta, sigma^2)``.

    Parameters
    ----------
    theta : float or array_like
        Parameter value(s); an array gives the log-likelihood on a grid.
    z : float or array_like
        The observations.
    sigma : float, default 1

    Returns
    -------
    float or numpy.ndarray, shaped like ``theta``

    Notes
    -----
    ``L(theta | z) = f(z | theta) = prod_i (2 pi sigma^2)^{-1/2}
    exp(-(z_i - theta)^2 / (2 sigma^2))`` (lecture, slides
    "Likelihood-funktionen, normalfördelning": independence makes the joint
    density the product).  Working with the logarithm avoids underflow for
    many observations.
    """
    sigma = _check_sigma(sigma)
    z = np.atleast_1d(as_float_array(z, "z")).ravel()
    theta = as_float_array(theta, "theta")
    sq = (
        np.sum((z[..., :] - theta[..., None]) ** 2, axis=-1)
        if theta.ndim
        else np.sum((z - theta) ** 2)
    )
    value = -0.5 * z.size * np.log(2 * np.pi * sigma**2) - sq / (2 * sigma**2)
    return float(value) if np.ndim(value) == 0 else value


def normal_likelihood(theta, z, sigma: float = 1.0) -> Any:
    """``L(theta | z) = f(z | theta)`` for independent ``z_i ~ N(theta, sigma^2)``.

    Parameters
    ----------
    theta : float or array_like
        Parameter value(s); an array gives the likelihood on a grid.
    z : float or array_like
        The observations.
    sigma : float, default 1

    Returns
    -------
    float or numpy.ndarray, shaped like ``theta``

    Notes
    -----
    ``L(theta | z) = prod_i (2 pi sigma^2)^{-1/2} exp(-(z_i - theta)^2 /
    (2 sigma^2))`` (lecture, slides "Likelihood-funktionen,
    normalfördelning"), computed as the exponential of
    :func:`normal_log_likelihood`.  For ``z = (3, 5)`` and ``sigma = 1`` the
    maximum is ``L(4) = e^{-1} / (2 pi)``.  Underflows to 0 for long records:
    use the log-likelihood there.
    """
    value = np.exp(normal_log_likelihood(theta, z, sigma))
    return float(value) if np.ndim(value) == 0 else value


@dataclass(frozen=True, repr=False, eq=False)
class MLResult:
    """Result of :func:`maximum_likelihood`.

    Attributes
    ----------
    theta : numpy.ndarray
        Maximiser (full vector, nominal values in fixed places).
    log_likelihood : float
        The maximum of ``log L``.
    success : bool
    message : str
    """

    theta: np.ndarray
    log_likelihood: float
    success: bool
    message: str

    def __repr__(self) -> str:
        return (
            f"MLResult(theta=[{', '.join(format_number(float(v)) for v in self.theta)}], "
            f"log_likelihood={format_number(self.log_likelihood)}, success={self.success})"
        )


def maximum_likelihood(
    log_likelihood: Callable,
    nominal,
    free: Sequence[int] | None = None,
    *,
    theta_init=None,
    bounds=None,
    method: str | None = None,
) -> MLResult:
    """Maximise ``log L(theta | z)`` over ``Theta_0`` numerically.

    Parameters
    ----------
    log_likelihood : callable
        ``log_likelihood(theta) -> float`` for a full parameter vector (the
        data are bound inside, e.g. with a lambda).
    nominal : array_like, shape (p,)
        Values of the parameters not in ``free``; also the default start.
    free : sequence of int, optional
        Parameters to maximise over; all of them by default.
    theta_init : array_like, optional
        Start for the free parameters.
    bounds : sequence of (low, high), optional
        Bounds of the free parameters.
    method : str, optional
        :func:`scipy.optimize.minimize` method (BFGS, or L-BFGS-B with bounds).

    Returns
    -------
    MLResult

    Notes
    -----
    ``theta_ML = argmax L(theta | z)`` (lecture, slide "Teststorheter
    baserade på likelihood-funktionen, forts.").  The optimiser minimises
    ``-log L``; it is local, so start it near the answer (a moment
    estimate, or a grid search) when the likelihood has several modes.
    """
    nominal = as_vector(nominal, "nominal")
    p = nominal.size
    free = list(range(p)) if free is None else _indices(free, p)

    def full(theta_free):
        theta = nominal.copy()
        theta[free] = theta_free
        return theta

    if not free:
        value = float(log_likelihood(nominal.copy()))
        return MLResult(
            theta=nominal.copy(), log_likelihood=value, success=True, message="no free parameters"
        )
    start = nominal[free] if theta_init is None else as_vector(theta_init, "theta_init", len(free))

    def objective(theta_free):
        value = float(log_likelihood(full(theta_free)))
        return np.inf if np.isnan(value) else -value

    sol = optimize.minimize(
        objective,
        start,
        method=method,
        bounds=bounds,
        options={"gtol": 1e-10} if method in (None, "BFGS") and bounds is None else None,
    )
    # BFGS often reports a precision loss at an optimum it cannot improve;
    # a polish by Nelder-Mead from there makes the answer trustworthy.
    if not sol.success and bounds is None:
        sol = optimize.minimize(
            objective,
            sol.x,
            method="Nelder-Mead",
            options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000},
        )
    return MLResult(
        theta=full(sol.x),
        log_likelihood=float(-sol.fun),
        success=bool(sol.success),
        message=str(sol.message),
    )


class LogLikelihoodLaw(FrozenDistribution):
    """Law of ``c - chi2(dof) / 2``: the maximised Gaussian log-likelihood under H0.

    Parameters
    ----------
    dof : int
    c : float
        The log-likelihood of a perfect fit, ``-(N/2) log(2 pi sigma^2)``.
    """

    def __init__(self, dof: int, c: float):
        self.dof = _check_dof(dof)
        self.c = float(c)
        self.support = (-np.inf, self.c)

    def _cdf(self, x):
        return stats.chi2.sf(2 * (self.c - x), self.dof)

    def _sf(self, x):
        return stats.chi2.cdf(2 * (self.c - x), self.dof)

    def _pdf(self, x):
        return 2 * stats.chi2.pdf(2 * (self.c - x), self.dof)

    def _rvs(self, size, rng):
        return self.c - 0.5 * rng.chisquare(self.dof, size=size)

    def ppf(self, q):
        return self.c - 0.5 * stats.chi2.isf(q, self.dof)

    def isf(self, q):
        return self.c - 0.5 * stats.chi2.ppf(q, self.dof)

    def mean(self):
        return self.c - 0.5 * self.dof

    def var(self):
        return 0.5 * self.dof

    def __repr__(self) -> str:
        return f"c - chi2({self.dof})/2 with c = {format_number(self.c)}"


def likelihood_test(
    y,
    U,
    nominal,
    free: Sequence[int] = (),
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str = "maximum-likelihood test",
) -> TestResult:
    """The lecture's likelihood test quantity ``T = max over Theta_0 of L``, reject when small.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal, free
        As in :func:`prediction_error`; the model is ``y = U theta + v``,
        ``v ~ N(0, sigma^2 I)``.
    sigma : float
    alpha : float

    Returns
    -------
    TestResult
        ``statistic = log max L`` (the log of the lecture's ``T``, which
        underflows for long records), ``alternative="less"``: H0 is
        rejected when the best achievable likelihood is *below* the
        critical value.

    Notes
    -----
    For this model ``max over Theta_0 of log L = -(N/2) log(2 pi sigma^2) -
    T_pe / (2 sigma^2)`` with ``T_pe`` the prediction error of
    :func:`prediction_error`: the likelihood test and the prediction-error
    test make the same decisions.  The null law is ``c - chi2(N - rank)/2``
    (lecture, "Teststorheter baserade på likelihood-funktionen, forts.":
    "H0 is rejected when T(z) is below a threshold").
    """
    alpha = check_alpha(alpha)
    sigma = _check_sigma(sigma)
    y = as_vector(y, "y")
    fit = prediction_error(y, U, nominal, free)
    if fit.dof < 1:
        raise ValueError(_void_test_message(f"N = rank = {fit.rank}"))
    c = -0.5 * y.size * np.log(2 * np.pi * sigma**2)
    stat = c - fit.statistic / (2 * sigma**2)
    null = LogLikelihoodLaw(fit.dof, c)
    crit = float(null.ppf(alpha))
    return TestResult(
        name=name,
        statistic=stat,
        alpha=alpha,
        critical_value=crit,
        pvalue=float(null.cdf(stat)),
        reject=stat < crit,
        null=null,
        dof=fit.dof,
        alternative="less",
        details={"prediction error T": fit.statistic},
    )


def glr_test(
    log_likelihood: Callable,
    nominal,
    free0: Sequence[int] = (),
    free1: Sequence[int] | None = None,
    *,
    alpha: float = 0.05,
    theta_init=None,
    bounds=None,
    name: str = "generalised likelihood ratio test",
) -> TestResult:
    """Generalised likelihood ratio test, calibrated by Wilks' theorem.

    Parameters
    ----------
    log_likelihood : callable
        ``log_likelihood(theta) -> float`` for a full parameter vector.
    nominal : array_like, shape (p,)
        Values of the parameters fixed under H0.
    free0 : sequence of int, default ()
        Parameters free under H0.
    free1 : sequence of int, optional
        Parameters free under H1 (a superset of ``free0``); all by default.
    alpha : float
    theta_init : array_like, shape (p,), optional
        Start of both maximisations (``nominal`` by default).
    bounds : sequence of (low, high) for all p parameters, optional

    Returns
    -------
    TestResult
        ``statistic = 2 (max_{Theta_1} log L - max_{Theta_0} log L)``,
        ``null = chi2(|free1| - |free0|)``.

    Notes
    -----
    ``Lambda = max_{Theta_0} L / max_{Theta_1} L`` and ``-2 log Lambda`` is
    asymptotically ``chi2(dim Theta_1 - dim Theta_0)`` under H0 (Wilks
    1938) when the hypotheses are nested, the true parameter is an
    *interior* point, the model is identifiable with a non-singular Fisher
    information, and the sample is large.  It fails, for example, when the
    null value lies on the boundary (a fault size restricted to be >= 0
    gives a 50:50 mixture of 0 and chi2(1)), or when a parameter is
    meaningless under H0 (the onset time of a fault of size 0).  For a
    linear-Gaussian model with known variance the law is exact:
    :func:`linear_glr_test`.  The lecture mentions generalised
    Neyman-Pearson results for composite hypotheses (slide
    "Neyman-Pearson lemma, likelihood-kvot").
    """
    alpha = check_alpha(alpha)
    nominal = as_vector(nominal, "nominal")
    p = nominal.size
    free0 = _indices(free0, p, "free0")
    free1 = list(range(p)) if free1 is None else _indices(free1, p, "free1")
    if not set(free0) < set(free1):
        raise ValueError(
            f"free0 {free0} must be a proper subset of free1 {free1} (nested hypotheses)"
        )
    start = nominal if theta_init is None else as_vector(theta_init, "theta_init", p)
    base = nominal.copy()
    # Under H1 the parameters outside free1 keep their nominal values.
    fit1 = maximum_likelihood(
        log_likelihood,
        np.where(np.isin(np.arange(p), free1), start, base),
        free1,
        bounds=None if bounds is None else [bounds[j] for j in free1],
    )
    init0 = np.where(np.isin(np.arange(p), free0), start, base)
    fit0 = maximum_likelihood(
        log_likelihood, init0, free0, bounds=None if bounds is None else [bounds[j] for j in free0]
    )
    stat = max(2.0 * (fit1.log_likelihood - fit0.log_likelihood), 0.0)
    dof = len(free1) - len(free0)
    crit = stats.chi2.isf(alpha, dof)
    return TestResult(
        name=name,
        statistic=stat,
        alpha=alpha,
        critical_value=crit,
        pvalue=stats.chi2.sf(stat, dof),
        reject=stat > crit,
        null=stats.chi2(dof),
        dof=dof,
        alternative="greater",
        details={
            "max log L under H0": fit0.log_likelihood,
            "max log L under H1": fit1.log_likelihood,
            "calibration": "Wilks (asymptotic)",
            "converged": fit0.success and fit1.success,
        },
    )


def linear_glr_test(
    y,
    U,
    nominal,
    free0: Sequence[int] = (),
    free1: Sequence[int] | None = None,
    *,
    sigma: float,
    alpha: float = 0.05,
    name: str = "generalised likelihood ratio test (linear)",
) -> TestResult:
    """Exact GLR test of nested parameter sets in ``y = U theta + v``, known ``sigma``.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal
        As in :func:`prediction_error`.
    free0 : sequence of int
        Free parameters under H0.
    free1 : sequence of int, optional
        Free parameters under H1 (superset of ``free0``); all by default.
    sigma, alpha, name

    Returns
    -------
    TestResult
        ``statistic = (T0 - T1) / sigma^2`` with ``Ti`` the prediction
        errors under the two hypotheses, ``null = chi2(rank1 - rank0)``.

    Notes
    -----
    ``-2 log Lambda = (T0 - T1) / sigma^2`` for Gaussian noise of known
    variance, and ``T0 - T1 = ||(P1 - P0) y||^2`` with ``P1 - P0`` the
    projection on the part of range(U_free1) orthogonal to range(U_free0):
    exactly ``sigma^2 chi2(rank1 - rank0)`` under H0, for every ``N``.
    Wilks' theorem is exact here.
    """
    alpha = check_alpha(alpha)
    sigma = _check_sigma(sigma)
    U, nominal = _model(U, nominal)
    p = U.shape[1]
    free0 = _indices(free0, p, "free0")
    free1 = list(range(p)) if free1 is None else _indices(free1, p, "free1")
    if not set(free0) < set(free1):
        raise ValueError(
            f"free0 {free0} must be a proper subset of free1 {free1} (nested hypotheses)"
        )
    y = as_vector(y, "y", U.shape[0])
    fit0 = prediction_error(y, U, nominal, free0)
    fit1 = prediction_error(y, U, nominal, free1)
    dof = fit1.rank - fit0.rank
    if dof < 1:
        raise ValueError(
            "the extra parameters of H1 add no new regressor direction (rank did not grow), so the "
            "two hypotheses fit every record equally well; the test is void"
        )
    stat = max(fit0.statistic - fit1.statistic, 0.0) / sigma**2
    crit = stats.chi2.isf(alpha, dof)
    return TestResult(
        name=name,
        statistic=stat,
        alpha=alpha,
        critical_value=crit,
        pvalue=stats.chi2.sf(stat, dof),
        reject=stat > crit,
        null=stats.chi2(dof),
        dof=dof,
        alternative="greater",
        details={"T0": fit0.statistic, "T1": fit1.statistic},
    )


def neyman_pearson_test(
    z,
    theta0,
    theta1,
    *,
    sigma: float = 1.0,
    regressors=None,
    alpha: float = 0.05,
    name: str = "Neyman-Pearson test",
) -> TestResult:
    """Most powerful test of two simple hypotheses on a Gaussian mean.

    Parameters
    ----------
    z : array_like, shape (N,)
        Observations, ``z = regressors @ theta + v``, ``v ~ N(0, sigma^2 I)``.
    theta0, theta1 : float or array_like
        The parameter under H0 and under H1.
    sigma : float, default 1
    regressors : array_like, shape (N, p), optional
        A column of ones by default: ``z_i ~ N(theta, sigma^2)``.
    alpha : float

    Returns
    -------
    TestResult
        ``statistic = log f(z | theta1) - log f(z | theta0)``, reject when
        large; details hold the power ``P(reject | theta1)``.

    Notes
    -----
    Neyman-Pearson lemma (lecture, slide "Neyman-Pearson lemma,
    likelihood-kvot"): for ``H0: theta = theta0`` against
    ``H1: theta = theta1`` no test of level ``alpha`` has more power than
    the one rejecting for large ``f(z|theta1) / f(z|theta0)``.  Here
    ``log Lambda = (||z - m0||^2 - ||z - m1||^2) / (2 sigma^2)`` with
    ``mi = regressors @ theta_i`` is linear in ``z``: with
    ``d = ||m1 - m0|| / sigma`` it is ``N(-d^2/2, d^2)`` under H0 and
    ``N(d^2/2, d^2)`` under H1, so threshold and power are exact:
    ``power = Phi(d - z_alpha)``.
    """
    alpha = check_alpha(alpha)
    sigma = _check_sigma(sigma)
    z = np.atleast_1d(as_float_array(z, "z"))
    if z.ndim != 1:
        raise ValueError(f"z must be a 1-D vector of observations, got shape {z.shape}")
    N = z.size
    A = (
        np.ones((N, 1))
        if regressors is None
        else as_matrix(regressors, "regressors", shape=(N, None))
    )
    t0 = np.atleast_1d(as_float_array(theta0, "theta0"))
    t1 = np.atleast_1d(as_float_array(theta1, "theta1"))
    if t0.shape != (A.shape[1],) or t1.shape != (A.shape[1],):
        raise ValueError(
            f"theta0 and theta1 must have {A.shape[1]} element(s), got {t0.shape} and {t1.shape}"
        )
    m0, m1 = A @ t0, A @ t1
    d = float(np.linalg.norm(m1 - m0) / sigma)
    if d == 0:
        raise ValueError(
            "theta0 and theta1 give the same distribution of z: the hypotheses cannot be told apart"
        )
    stat = float((np.sum((z - m0) ** 2) - np.sum((z - m1) ** 2)) / (2 * sigma**2))
    null = stats.norm(loc=-(d**2) / 2, scale=d)
    crit = float(null.isf(alpha))
    power = float(stats.norm.sf(crit, loc=d**2 / 2, scale=d))
    return TestResult(
        name=name,
        statistic=stat,
        alpha=alpha,
        critical_value=crit,
        pvalue=float(null.sf(stat)),
        reject=stat > crit,
        null=null,
        alternative="greater",
        details={"power": power, "separation d": d},
    )


def mode_log_likelihoods(
    y,
    U,
    nominal,
    modes: Mapping[str, Sequence[int]],
    *,
    sigma: float,
    prior_std: float | None = None,
) -> dict:
    """``log P(y | F)`` for every fault mode of ``y = U theta + v``.

    Parameters
    ----------
    y : array_like, shape (N,)
    U, nominal
        As in :func:`prediction_error`.
    modes : mapping of str to sequence of int
        The parameters that may deviate in each mode (``()`` for NF).
    sigma : float
    prior_std : float, optional
        If given, the deviating parameters of a mode have the prior
        ``N(nominal, prior_std^2)`` and the *marginal* likelihood
        ``int f(y | theta) p(theta | F) dtheta`` is returned (the proper
        Bayesian evidence).  Otherwise the maximised likelihood
        ``max over Theta_F of L(theta | y)`` of the lecture.

    Returns
    -------
    dict of str to float

    Notes
    -----
    The lecture (slide "Likelihood och Bayes") uses ``max L`` as
    ``P(z | F_i)``.  Because ``Theta_NF`` lies in the closure of every
    ``Theta_Fi``, ``max over Theta_Fi of L >= L(nominal)`` for every record:
    with maximised likelihoods a fault mode always looks at least as likely
    as NF, and only the priors can favour NF.  The marginal likelihood
    charges a mode for its free parameter (an Occam factor) and prefers NF
    when the data do not need the fault.  Under ``F`` with the prior above,
    ``y ~ N(U nominal, sigma^2 I + prior_std^2 U_F U_F^T)``.
    """
    sigma = _check_sigma(sigma)
    U, nominal = _model(U, nominal)
    y = as_vector(y, "y", U.shape[0])
    N = y.size
    out = {}
    for mode, faulty in modes.items():
        faulty = _indices(faulty, U.shape[1], f"parameters of mode {mode!r}")
        if prior_std is None or not faulty:
            T = prediction_error(y, U, nominal, faulty).statistic
            out[str(mode)] = float(-0.5 * N * np.log(2 * np.pi * sigma**2) - T / (2 * sigma**2))
        else:
            tau = _check_sigma(prior_std)
            Uf = U[:, faulty]
            cov = sigma**2 * np.eye(N) + tau**2 * (Uf @ Uf.T)
            L = cholesky_lower(cov, "marginal covariance")
            w = sla.solve_triangular(L, y - U @ nominal, lower=True)
            out[str(mode)] = float(
                -0.5 * N * np.log(2 * np.pi) - np.sum(np.log(np.diag(L))) - 0.5 * w @ w
            )
    return out


@dataclass(frozen=True, repr=False, eq=False)
class FaultRanking:
    """Fault modes ranked by posterior probability (see :func:`bayes_ranking`).

    Attributes
    ----------
    modes : tuple of str
        Most probable first.
    posterior, prior, log_likelihood : tuple of float
        In the order of ``modes``.
    """

    modes: tuple
    posterior: tuple
    prior: tuple
    log_likelihood: tuple

    def as_dict(self) -> dict:
        """``{mode: posterior}``."""
        return dict(zip(self.modes, self.posterior))

    def to_text(self, digits: int = 4) -> str:
        """The ranking as aligned plain text, numbers rounded to ``digits`` significant digits."""
        width = max(len(m) for m in self.modes)
        lines = [f"{'mode'.ljust(width)}  {'prior':>8}  {'posterior':>10}"]
        for m, pr, po in zip(self.modes, self.prior, self.posterior):
            lines.append(
                f"{m.ljust(width)}  {format_number(pr, digits):>8}  {format_number(po, digits):>10}"
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"FaultRanking(\n{self.to_text()}\n)"

    def _repr_html_(self) -> str:
        rows = "".join(
            f"<tr><th style='text-align:left'>{html.escape(m)}</th><td>{format_number(pr, 4)}</td>"
            f"<td>{format_number(po, 4)}</td></tr>"
            for m, pr, po in zip(self.modes, self.prior, self.posterior)
        )
        return (
            "<table><caption>fault modes ranked by posterior probability</caption>"
            f"<tr><th>mode</th><th>prior</th><th>posterior</th></tr>{rows}</table>"
        )


def bayes_ranking(
    log_likelihoods: Mapping[str, float], priors: Mapping[str, float]
) -> FaultRanking:
    """Rank fault modes by ``P(F | z)`` from ``log P(z | F)`` and priors ``P(F)``.

    Parameters
    ----------
    log_likelihoods : mapping of str to float
        ``log P(z | F)`` per mode, e.g. from :func:`mode_log_likelihoods`.
    priors : mapping of str to float
        Prior probabilities of the same modes, positive and summing to 1.

    Returns
    -------
    FaultRanking

    Notes
    -----
    Bayes' rule ``P(F_i | z) = P(z | F_i) P(F_i) / sum_j P(z | F_j) P(F_j)``
    (lecture, slide "Likelihood och Bayes"), computed with log-sum-exp so
    that tiny likelihoods do not underflow.
    """
    modes = list(log_likelihoods)
    if set(modes) != set(priors):
        raise ValueError(
            f"log_likelihoods and priors must name the same modes, got {sorted(modes)} and {sorted(priors)}"
        )
    if not modes:
        raise ValueError("at least one mode is needed")
    logl = np.array([float(log_likelihoods[m]) for m in modes])
    prior = np.array([float(priors[m]) for m in modes])
    if np.any(np.isnan(logl)) or np.any(logl == np.inf):
        raise ValueError("log-likelihoods must be finite numbers or -inf")
    if np.any(~np.isfinite(prior)) or np.any(prior <= 0):
        raise ValueError("priors must be positive probabilities")
    if abs(prior.sum() - 1.0) > 1e-9:
        raise ValueError(
            f"priors must sum to 1, they sum to {prior.sum():.6g}; normalise them first"
        )
    if np.all(logl == -np.inf):
        raise ValueError(
            "every mode has likelihood 0 (log-likelihood -inf): the data are impossible under all "
            "modes, so Bayes' rule cannot rank them; check the model or the noise level"
        )
    log_post = logl + np.log(prior)
    log_post = log_post - special.logsumexp(log_post)
    post = np.exp(log_post)
    order = sorted(range(len(modes)), key=lambda i: (-post[i], i))
    return FaultRanking(
        modes=tuple(modes[i] for i in order),
        posterior=tuple(float(post[i]) for i in order),
        prior=tuple(float(prior[i]) for i in order),
        log_likelihood=tuple(float(logl[i]) for i in order),
    )


# ---------------------------------------------------------------------------
# Monte Carlo
# ---------------------------------------------------------------------------
def simulate_linear_regression(U, theta, *, sigma: float, n_records: int, rng) -> np.ndarray:
    """``M`` records of ``y = U theta + v``, ``v ~ N(0, sigma^2 I)``, as columns.

    Parameters
    ----------
    U : array_like, shape (N, p)
    theta : array_like, shape (p,)
    sigma : float
    n_records : int
    rng : numpy.random.Generator

    Returns
    -------
    numpy.ndarray, shape (N, n_records)

    Notes
    -----
    The lecture's static fault model ``y(t) = theta_1 u1(t) + theta_2 u2(t)
    + theta_3 u3(t) + v(t)`` (test_quantities_lecture_sv.txt, "Teststorheten
    är ett modellvalideringsmått") with white Gaussian noise; records as
    columns so every test quantity is one matrix operation for all of them.
    """
    U = as_matrix(U, "U")
    theta = as_vector(theta, "theta", U.shape[1])
    sigma = _check_sigma(sigma)
    rng = as_generator(rng)
    n_records = _count(n_records, "n_records")
    return (U @ theta)[:, None] + sigma * rng.standard_normal((U.shape[0], n_records))


def linear_test_statistics(Y, U, nominal, tests: Sequence[Sequence[int]]) -> np.ndarray:
    """Prediction errors of several tests on many records: ``(M, n_tests)``.

    Parameters
    ----------
    Y : array_like, shape (N, M)
    U, nominal
        As in :func:`prediction_error`.
    tests : sequence of sequences of int
        The free parameters of each test.

    Returns
    -------
    numpy.ndarray, shape (M, n_tests)
        ``T_k`` of every record, one column per test.

    Notes
    -----
    Column ``k`` is ``min over Theta_0^k of ||y - U theta||^2``
    (:func:`prediction_error`), computed for all ``M`` records with one
    SVD of the free regressors per test.
    """
    Y = _data(Y, None, "Y")
    Y = Y[:, None] if Y.ndim == 1 else Y
    return np.column_stack([prediction_error(Y, U, nominal, free).statistic for free in tests])


@dataclass(frozen=True, repr=False, eq=False)
class IsolationResult:
    """Outcome of :func:`isolation_monte_carlo`.

    Attributes
    ----------
    structure : DecisionStructure
    simulated : tuple of str
        The modes simulated (rows of the matrices).
    alarm_rate : numpy.ndarray, shape (n_simulated, n_tests)
        ``P(test k alarms | mode)``.
    membership : numpy.ndarray, shape (n_simulated, n_modes)
        ``P(mode j is among the diagnoses | mode)``: the isolation
        performance; the ideal is the identity with a column for NF.
    exact : numpy.ndarray, shape (n_simulated,)
        ``P(the diagnoses are exactly {mode} | mode)``.
    n_records : int
    """

    structure: DecisionStructure
    simulated: tuple
    alarm_rate: np.ndarray
    membership: np.ndarray
    exact: np.ndarray
    n_records: int

    def to_text(self, digits: int = 3) -> str:
        """The membership table (and "exact") as aligned plain text with ``digits`` decimals."""
        modes = self.structure.modes
        width = max(max(len(m) for m in self.simulated), len("true"))
        col = max(max(len(m) for m in modes), digits + 3)
        head = (
            "true".ljust(width)
            + "  "
            + "  ".join(m.rjust(col) for m in modes)
            + "  "
            + "exact".rjust(col)
        )
        lines = [head]
        for i, mode in enumerate(self.simulated):
            cells = [f"{v:.{digits}f}".rjust(col) for v in self.membership[i]]
            cells.append(f"{self.exact[i]:.{digits}f}".rjust(col))
            lines.append(mode.ljust(width) + "  " + "  ".join(cells))
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"IsolationResult(n_records={self.n_records}, P(mode in diagnoses | true mode):\n{self.to_text()}\n)"

    def _repr_html_(self) -> str:
        modes = self.structure.modes
        head = "".join(f"<th>{html.escape(m)}</th>" for m in modes) + "<th>exact</th>"
        rows = []
        for i, mode in enumerate(self.simulated):
            cells = "".join(f"<td>{v:.3f}</td>" for v in self.membership[i])
            rows.append(f"<tr><th>{html.escape(mode)}</th>{cells}<td>{self.exact[i]:.3f}</td></tr>")
        return (
            f"<table><caption>P(mode in diagnoses | true mode), {self.n_records} records per mode</caption>"
            f"<tr><th>true</th>{head}</tr>{''.join(rows)}</table>"
        )


def isolation_monte_carlo(
    structure: DecisionStructure,
    simulate: Callable,
    statistics: Callable,
    thresholds,
    *,
    n_records: int,
    rng,
    modes: Sequence[str] | None = None,
    exoneration: bool = False,
) -> IsolationResult:
    """Simulate every fault mode, run the tests, diagnose, and tabulate.

    Parameters
    ----------
    structure : DecisionStructure
        Gives the tests (its rows, in order) and the modes.
    simulate : callable
        ``simulate(mode, n_records, rng) -> data`` for one mode name.
    statistics : callable
        ``statistics(data) -> (n_records, n_tests)`` array of test
        quantities, columns in the structure's test order.
    thresholds : array_like, shape (n_tests,)
        A test alarms when its quantity exceeds its threshold.
    n_records : int
        Records per mode.
    rng : numpy.random.Generator
    modes : sequence of str, optional
        Modes to simulate (all of the structure's by default).
    exoneration : bool
        See :func:`diagnoses`.

    Returns
    -------
    IsolationResult

    Notes
    -----
    For each simulated mode ``F``: the alarm rate of test ``k`` estimates
    ``P(T_k > J_k | F)`` (``alpha`` where the structure has a 0, the power
    where it has an X); the membership ``P(F' in D | F)`` with ``D`` the
    single-fault diagnoses of :func:`diagnosis_matrix`; and "exact" is
    ``P(D = {F} | F)``.  Each is a binomial proportion over ``n_records``
    records, with standard error at most ``0.5 / sqrt(n_records)``.
    """
    if not isinstance(structure, DecisionStructure):
        raise ValueError("structure must be a DecisionStructure")
    rng = as_generator(rng)
    n_tests = len(structure.tests)
    thresholds = as_vector(thresholds, "thresholds", n_tests)
    modes = (
        structure.modes
        if modes is None
        else tuple(structure.modes[structure.mode_index(m)] for m in modes)
    )
    n_records = _count(n_records, "n_records")
    alarm_rate = np.empty((len(modes), n_tests))
    membership = np.empty((len(modes), len(structure.modes)))
    exact = np.empty(len(modes))
    for i, mode in enumerate(modes):
        stat = np.asarray(statistics(simulate(mode, n_records, rng)), dtype=float)
        if stat.shape != (n_records, n_tests):
            raise ValueError(
                f"statistics returned shape {stat.shape}, expected ({n_records}, {n_tests})"
            )
        alarms = stat > thresholds
        D = diagnosis_matrix(structure, alarms, exoneration=exoneration)
        alarm_rate[i] = alarms.mean(axis=0)
        membership[i] = D.mean(axis=0)
        j = structure.mode_index(mode)
        only = D[:, j] & (D.sum(axis=1) == 1)
        exact[i] = only.mean()
    return IsolationResult(
        structure=structure,
        simulated=tuple(modes),
        alarm_rate=alarm_rate,
        membership=membership,
        exact=exact,
        n_records=n_records,
    )
