"""Decision structures: which tests may alarm in which fault modes, and the diagnoses.

Source: the LiU lecture on test quantities (Linköping University, Swedish
slides; full reference in the course bibliography, :doc:`/docs/bibliography`),
slide "Teststorheten är ett modellvalideringsmått".
"""

from __future__ import annotations

import html
import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from course.diagnosis._common import _indices
from course.linalg import range_basis, readonly
from course.results import TestResult
from course.validation import InputTypeError, as_count, as_flag, as_index, as_matrix, as_positive

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

    See Also
    --------
    diagnoses : The diagnoses an alarm pattern leaves.
    linear_decision_structure : The structure a linear model implies.

    Notes
    -----
    The decision structure of the LiU lecture (slide
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
        readonly(matrix)
        self._sensitivity = matrix
        self._tests = tests
        self._modes = modes

    @classmethod
    def from_text(cls, text: str) -> DecisionStructure:
        """Parse a table: a header line of mode names, then one line per test.

        Each test line is the test name followed by one ``0`` or ``X`` per
        mode, separated by white space (``|`` characters are ignored).
        """
        if not isinstance(text, str):
            raise InputTypeError(
                f"text must be a string holding the table, got {type(text).__name__}"
            )
        lines = [ln.replace("|", " ").split() for ln in text.strip().splitlines()]
        lines = [ln for ln in lines if ln]
        if len(lines) < 2:
            raise ValueError(
                "text must hold a header line of mode names and at least one test line, "
                "e.g. 'NF F1\\nT1 0 X'"
            )
        modes = lines[0]
        tests, rows = [], []
        for line in lines[1:]:
            if len(line) != len(modes) + 1:
                raise ValueError(
                    f"text: test line {' '.join(line)!r} has {len(line) - 1} entries but the header "
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
            "sensitivity must be a 2-D table, one row per test and one entry per fault mode, "
            f"e.g. [[0, 0, 1], [0, 1, 0]]; got {value!r}"
        ) from None
    if not rows or not rows[0]:
        raise ValueError("sensitivity needs at least one test (row) and one mode (column)")
    width = len(rows[0])
    matrix = np.zeros((len(rows), width), dtype=bool)
    for k, row in enumerate(rows):
        if len(row) != width:
            raise ValueError(
                f"row {k} of sensitivity has {len(row)} entries, row 0 has {width}; "
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
        f"sensitivity entry ({k}, {j}) is {entry!r}; use 0 (not sensitive) "
        "or X (may alarm), or False/True"
    )


def _names(names, what, size) -> tuple:
    if isinstance(names, (str, bytes)) or not isinstance(names, Sequence | np.ndarray):
        raise InputTypeError(f"{what} must be a sequence of names (a list of str), got {names!r}")
    names = tuple(str(n) for n in names)
    if len(names) != size:
        raise ValueError(f"{what} names {len(names)} entries but the table has {size}")
    if len(set(names)) != len(names):
        raise ValueError(f"{what} names must be unique, got {list(names)}")
    return names


def _lookup(key, names, what) -> int:
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
        return as_index(key, what, len(names))
    try:
        return names.index(str(key))
    except ValueError:
        raise ValueError(f"unknown {what} {key!r}; the structure has {list(names)}") from None


def _check_structure(structure) -> DecisionStructure:
    if not isinstance(structure, DecisionStructure):
        raise InputTypeError(
            "structure must be a DecisionStructure (build one with DecisionStructure(...) or "
            f"DecisionStructure.from_text(...)), got {type(structure).__name__}"
        )
    return structure


def _alarmed_row(structure: DecisionStructure, test) -> int:
    try:
        return structure.row_index(test)
    except ValueError as exc:
        raise ValueError(f"alarms: {exc}") from None


def _alarm_vector(structure: DecisionStructure, alarms) -> np.ndarray:
    n_tests = len(structure.tests)
    if isinstance(alarms, Mapping):
        vector = np.zeros(n_tests, dtype=bool)
        for key, value in alarms.items():
            vector[_alarmed_row(structure, key)] = _as_alarm(value)
        return vector
    if isinstance(alarms, (str, bytes)):
        alarms = [alarms]
    if alarms is None or not isinstance(alarms, Sequence | np.ndarray):
        raise InputTypeError(
            "alarms must be one True/False (or TestResult) per test, the names of the tests "
            f"that alarmed, or a {{test: alarm}} mapping; got {alarms!r}"
        )
    items = list(alarms)
    if not items:  # no test named: nothing alarmed
        return np.zeros(n_tests, dtype=bool)
    if all(isinstance(a, str) for a in items):
        vector = np.zeros(n_tests, dtype=bool)
        for name in items:
            vector[_alarmed_row(structure, name)] = True
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
    if isinstance(value, (bool, np.bool_)) or (
        isinstance(value, (int, float, np.integer, np.floating)) and value in (0, 1)
    ):
        return bool(value)
    raise ValueError(f"alarms: an alarm must be True/False, 0/1 or a TestResult, got {value!r}")


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

    See Also
    --------
    diagnosis_matrix : The diagnoses of every alarm pattern at once.
    multiple_fault_diagnoses : Diagnoses when several faults may be present.

    Notes
    -----
    An alarm from test ``T`` rejects its null hypothesis, so it rules out
    every mode with a 0 in row ``T``.  Under the single-fault assumption the
    diagnoses are the intersection, over the alarmed tests, of the sets of
    modes with an X (the lecture's decision structure,
    LiU lecture, slide "Teststorheten är ett
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

    Examples
    --------
    >>> ds = DecisionStructure.from_text('''
    ...        NF F1 F2 F3
    ...     T1  0  0  X  X
    ...     T2  0  X  0  X
    ...     T3  0  X  X  0''')
    >>> diagnoses(ds, ["T2", "T3"])
    ('F1',)
    >>> diagnoses(ds, [])
    ('NF', 'F1', 'F2', 'F3')
    """
    structure = _check_structure(structure)
    alarm = _alarm_vector(structure, alarms)
    consistent = diagnosis_matrix(structure, alarm[None, :], exoneration=exoneration)[0]
    return tuple(m for m, ok in zip(structure.modes, consistent) if ok)


def diagnosis_matrix(
    structure: DecisionStructure, alarms, *, exoneration: bool = False
) -> np.ndarray:
    r"""Single-fault diagnoses of many alarm patterns at once.

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

    See Also
    --------
    diagnoses : The diagnoses of one alarm pattern.

    Notes
    -----
    Mode :math:`j` is inconsistent with pattern :math:`m` exactly when some
    alarmed test has a 0 for :math:`j`,

    .. math::

        \bigvee_k \bigl(a_{mk} \wedge \neg X_{kj}\bigr),

    one boolean matrix product for all patterns.

    Examples
    --------
    >>> ds = DecisionStructure.from_text('''
    ...        NF F1 F2 F3
    ...     T1  0  0  X  X
    ...     T2  0  X  0  X
    ...     T3  0  X  X  0''')
    >>> diagnosis_matrix(ds, [[False, True, True], [True, True, True]])
    array([[False,  True, False, False],
           [False, False, False, False]])
    """
    structure = _check_structure(structure)
    exoneration = as_flag(exoneration, "exoneration")
    if alarms is None or isinstance(alarms, (str, bytes)):
        raise InputTypeError(f"alarms must be a boolean array (M, n_tests), got {alarms!r}")
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

    See Also
    --------
    diagnoses : The single-fault diagnoses.

    Notes
    -----
    Conflict of alarmed test ``T``: the faults with an X in its row.  A set
    of faults is a diagnosis when it meets every conflict; enumerating the
    candidate sets by increasing size and keeping those with no diagnosed
    subset gives the minimal ones (fine for the handful of faults of a
    course example; large systems need Reiter's HS-tree or similar).

    Examples
    --------
    >>> ds = DecisionStructure.from_text('''
    ...        NF F1 F2 F3
    ...     T1  0  0  X  X
    ...     T2  0  X  0  X
    ...     T3  0  X  X  0''')
    >>> multiple_fault_diagnoses(ds, ["T1", "T2", "T3"])
    [('F1', 'F2'), ('F1', 'F3'), ('F2', 'F3')]
    """
    structure = _check_structure(structure)
    alarm = _alarm_vector(structure, alarms)
    if no_fault is not None and (not isinstance(no_fault, str) or no_fault not in structure.modes):
        raise ValueError(
            f"no_fault must be None or one of the modes {list(structure.modes)} (the no-fault "
            f"mode, left out of the fault sets), got {no_fault!r}"
        )
    faults = [j for j, m in enumerate(structure.modes) if m != no_fault]
    S = structure.sensitivity
    conflicts = [frozenset(j for j in faults if S[k, j]) for k in np.flatnonzero(alarm)]
    if any(not c for c in conflicts):
        return []
    limit = len(faults) if max_size is None else as_count(max_size, "max_size", minimum=0)
    found: list[frozenset] = []
    for size in range(limit + 1):
        for candidate in itertools.combinations(faults, size):
            cand = frozenset(candidate)
            if any(f <= cand for f in found):
                continue
            if all(cand & c for c in conflicts):
                found.append(cand)
    return [tuple(structure.modes[j] for j in sorted(f)) for f in found]


def _index_sets(value, name: str, p: int) -> dict:
    """``{name: sorted parameter indices}`` from a mapping of names to index sequences."""
    if not isinstance(value, Mapping):
        raise InputTypeError(
            f"{name} must be a mapping {{name: parameter indices}}, e.g. {{'F1': (0,)}}; "
            f"got {type(value).__name__}"
        )
    return {str(key): _indices(free, p, f"{name}[{key!r}]") for key, free in value.items()}


def linear_decision_structure(
    U, modes: Mapping[str, Sequence[int]], tests: Mapping[str, Sequence[int]], rtol: float = 1e-9
) -> DecisionStructure:
    r"""The decision structure that prediction-error tests really have for given signals.

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

    See Also
    --------
    DecisionStructure : The structure it returns.
    prediction_error_test : The tests whose structure it is.

    Notes
    -----
    The test's residual is :math:`(I - P)\,y` with :math:`P` the projection on
    the free columns, so a fault :math:`U_F d` is seen exactly when

    .. math::

        (I - P)\,U_F \ne 0;

    the lecture's "F2 is detected when :math:`U_2` is not parallel to
    :math:`U_1`" is the case of one free column.

    Examples
    --------
    With U2 parallel to U1, the test that leaves theta_1 free cannot see F2:

    >>> import numpy as np
    >>> u = np.linspace(1.0, 2.0, 10)
    >>> U = np.column_stack([u, -0.7 * u, np.cos(np.arange(10.0))])
    >>> modes = {"NF": (), "F1": (0,), "F2": (1,), "F3": (2,)}
    >>> print(linear_decision_structure(U, modes, {"T1": (0,), "T3": (2,)}))
        NF  F1  F2  F3
    T1   0   0   0   X
    T3   0   X   X   0
    """
    U = as_matrix(U, "U")
    p = U.shape[1]
    modes, tests = _index_sets(modes, "modes", p), _index_sets(tests, "tests", p)
    rtol = as_positive(rtol, "rtol", what="the relative tolerance")
    matrix = np.zeros((len(tests), len(modes)), dtype=bool)
    for k, free in enumerate(tests.values()):
        basis = range_basis(U[:, free])
        for j, faulty in enumerate(modes.values()):
            if not faulty:
                continue
            D = U[:, faulty]
            leftover = D - basis @ (basis.T @ D)
            scale = max(np.linalg.norm(D), np.finfo(float).tiny)
            matrix[k, j] = np.linalg.norm(leftover) > rtol * scale
    return DecisionStructure(matrix, tests=list(tests), modes=list(modes))
