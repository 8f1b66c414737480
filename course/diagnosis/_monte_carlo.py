"""Monte Carlo studies of a set of tests: simulated records, statistics, isolation rates.

The example models come from the LiU lecture on test quantities (full reference in the course
bibliography, :doc:`/docs/bibliography`).
"""

from __future__ import annotations

import html
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from course.diagnosis._common import _check_sigma, _indices, _records
from course.diagnosis._prediction_error import prediction_error
from course.diagnosis._structures import DecisionStructure, _check_structure, diagnosis_matrix
from course.validation import as_callable, as_count, as_flag, as_generator, as_matrix, as_vector


def simulate_regression_records(
    U: Any, theta: Any, *, sigma: float, n_records: int, rng: Any
) -> np.ndarray:
    r"""``n_records`` records of ``y = U theta + v``, ``v ~ N(0, sigma^2 I)``, as rows.

    Parameters
    ----------
    U : array_like, shape (N, p)
        Regressors, one column per parameter.
    theta : array_like, shape (p,)
        True parameter vector.
    sigma : float
        Noise standard deviation.
    n_records : int
        Number of independent records ``M``.
    rng : numpy.random.Generator
        Source of randomness (or a seed).

    Returns
    -------
    numpy.ndarray, shape (n_records, N)
        One record per row (records leading, the course's batch layout):
        every test quantity of this package takes it as it is.

    See Also
    --------
    linear_test_statistics : The test quantities of these records.
    isolation_monte_carlo : Detection and isolation rates by simulation.

    Notes
    -----
    The lecture's static fault model (LiU lecture, "Teststorheten är ett
    modellvalideringsmått")

    .. math::

        y(t) = \theta_1 u_1(t) + \theta_2 u_2(t) + \theta_3 u_3(t) + v(t)

    with white Gaussian noise.  The noise is drawn sample-major (an
    ``(N, n_records)`` draw, transposed), the order the course's seeded studies
    were computed with.

    Examples
    --------
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(5), np.arange(5.0)])
    >>> Y = simulate_regression_records(U, [1.0, 0.5], sigma=0.1, n_records=3, rng=0)
    >>> Y.shape
    (3, 5)
    """
    U = as_matrix(U, "U")
    theta = as_vector(theta, "theta")
    if theta.shape[0] != U.shape[1]:
        raise ValueError(
            f"theta has {theta.shape[0]} parameters but U has {U.shape[1]} columns; "
            "give one parameter per column of U"
        )
    sigma = _check_sigma(sigma)
    generator = as_generator(rng)
    n_records = as_count(n_records, "n_records", what="the number of records")
    noise = generator.standard_normal((U.shape[0], n_records)).T
    return np.ascontiguousarray(U @ theta + sigma * noise)


def linear_test_statistics(
    Y: Any, U: Any, nominal: Any, tests: Sequence[Sequence[int]]
) -> np.ndarray:
    r"""Prediction errors of several tests on many records: ``(M, n_tests)``.

    Parameters
    ----------
    Y : array_like, shape (M, N) or (N,)
        ``M`` records as rows (one record gives one row of output).
    U, nominal
        As in :func:`prediction_error`.
    tests : sequence of sequences of int
        The free parameters of each test.

    Returns
    -------
    numpy.ndarray, shape (M, n_tests)
        ``T_k`` of every record, one column per test.

    See Also
    --------
    prediction_error : The same quantity for one record.

    Notes
    -----
    Column :math:`k` is
    :math:`\min_{\theta \in \Theta_0^k} \lVert y - U\theta \rVert^2`
    (:func:`prediction_error`), computed for all :math:`M` records with one SVD
    of the free regressors per test.

    Examples
    --------
    >>> import numpy as np
    >>> U = np.eye(3)
    >>> linear_test_statistics([[2.0, 1.0, 1.0]], U, [1, 1, 1], [(0,), (1,)])
    array([[0., 1.]])
    """
    U = as_matrix(U, "U")
    U = as_matrix(U, "U")
    columns, _ = _records(Y, U.shape[0], "Y")
    rows = columns.T if columns.ndim == 2 else columns[None, :]
    if isinstance(tests, (str, bytes)) or not isinstance(tests, Sequence | np.ndarray):
        raise ValueError(
            f"tests must be a sequence of index sequences, one per test, e.g. [(0,), (1,)]; "
            f"got {tests!r}"
        )
    frees = [_indices(free, U.shape[1], f"tests[{k}]") for k, free in enumerate(tests)]
    if not frees:
        raise ValueError("tests names no test; give one sequence of free parameters per test")
    return np.column_stack([prediction_error(rows, U, nominal, free).statistic for free in frees])


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


def _modes_to_simulate(structure: DecisionStructure, modes) -> tuple:
    if isinstance(modes, (str, bytes)) or not isinstance(modes, Sequence | np.ndarray):
        raise ValueError(f"modes must be a list of mode names, got {modes!r}")
    chosen = []
    for mode in modes:
        try:
            chosen.append(structure.modes[structure.mode_index(mode)])
        except ValueError as exc:
            raise ValueError(f"modes: {exc}") from None
    return tuple(chosen)


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
    r"""Simulate every fault mode, run the tests, diagnose, and tabulate.

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

    See Also
    --------
    diagnosis_matrix : The diagnoses of each alarm pattern.
    simulate_regression_records : The records it simulates.

    Notes
    -----
    For each simulated mode :math:`F`: the alarm rate of test :math:`k`
    estimates :math:`P(T_k > J_k \mid F)` (:math:`\alpha` where the structure
    has a 0, the power where it has an X); the membership
    :math:`P(F' \in D \mid F)` with :math:`D` the single-fault diagnoses of
    :func:`diagnosis_matrix`; and "exact" is :math:`P(D = \{F\} \mid F)`.  Each
    is a binomial proportion over ``n_records`` records, with standard error at
    most :math:`0.5/\sqrt{n}`.

    Examples
    --------
    >>> ds = DecisionStructure.from_text('''
    ...        NF F1 F2 F3
    ...     T1  0  0  X  X
    ...     T2  0  X  0  X
    ...     T3  0  X  X  0''')
    >>> import numpy as np
    >>> U = np.column_stack([np.ones(20), np.linspace(0, 1, 20), np.cos(np.arange(20.0))])
    >>> theta = {"NF": [1, 1, 1], "F1": [2, 1, 1], "F2": [1, 2, 1], "F3": [1, 1, 2]}
    >>> def simulate(mode, n, rng):
    ...     return simulate_regression_records(U, theta[mode], sigma=0.1, n_records=n, rng=rng)
    >>> def statistics(Y):
    ...     return linear_test_statistics(Y, U, [1, 1, 1], [(0,), (1,), (2,)])
    >>> from course.chi2 import residual_threshold
    >>> J = [residual_threshold(19, 0.01, sigma=0.1)] * 3
    >>> iso = isolation_monte_carlo(ds, simulate, statistics, J, n_records=500, rng=0)
    >>> iso.exact.round(1)  # NF alone is never the diagnosis: no alarm rules nothing out
    array([0., 1., 1., 1.])
    """
    structure = _check_structure(structure)
    simulate = as_callable(simulate, "simulate")
    statistics = as_callable(statistics, "statistics")
    exoneration = as_flag(exoneration, "exoneration")
    rng = as_generator(rng)
    n_tests = len(structure.tests)
    thresholds = as_vector(thresholds, "thresholds", n_tests)
    modes = structure.modes if modes is None else _modes_to_simulate(structure, modes)
    n_records = as_count(n_records, "n_records", what="records per mode")
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
