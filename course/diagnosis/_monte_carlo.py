"""Monte Carlo studies of a set of tests: simulated records, statistics, isolation rates."""

from __future__ import annotations

import html
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from course.diagnosis._common import _check_sigma, _count, _data
from course.diagnosis._prediction_error import prediction_error
from course.diagnosis._structures import DecisionStructure, diagnosis_matrix
from course.distributions import as_generator
from course.linalg import (
    as_matrix,
    as_vector,
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
