"""Detection, identification and adaptation (DIA), and the law of its estimator.

Data snooping stops at "which observation?"; DIA goes on to the estimate that a user
finally gets: x̂ of the null model when nothing is detected, else x̂ of the identified
alternative. That estimator is a mixture of the estimators of every hypothesis, weighted by
the probabilities of the decisions, and is not normal (Teunissen 2018, "Distributional
theory for the DIA method", *Journal of Geodesy* 92). The works cited here are in the
course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import linalg as sla
from scipy import special, stats

from course.chi2 import residual_threshold
from course.linalg import readonly
from course.lsq._alternatives import _bias_columns, _bias_space
from course.lsq._fit import LeastSquaresFit, _check_fit, _require_redundancy
from course.lsq._tests import _w_quantities, overall_model_test
from course.results import TestResult, format_number
from course.validation import as_count, as_float_array, as_generator, as_probability, as_vector

#: Working memory of one chunk of :func:`dia_monte_carlo` (its largest arrays, in bytes).
_CHUNK_BYTES = 16 * 2**20


class _ObservationNames(Sequence):
    """``("observation i", ...)`` for the default candidates, each name made when read.

    At m = 10⁵ a tuple of the names costs more than the whole DIA step; this reads alike
    (indexing, iteration, ``len``, equality with a tuple).
    """

    def __init__(self, indices: np.ndarray):
        self._indices = indices

    def __len__(self) -> int:
        return int(self._indices.size)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return tuple(f"observation {i}" for i in self._indices[k].tolist())
        return f"observation {int(self._indices[k])}"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sequence) and tuple(self) == tuple(other)

    def __hash__(self) -> int:
        return hash(tuple(self))

    def __repr__(self) -> str:
        return repr(tuple(self)) if len(self) <= 6 else f"<{len(self)} observations>"


@dataclass(frozen=True)
class _Candidates:
    """The alternatives: one outlier per testable observation, or the given bias spaces.

    ``singles`` (the default candidates, ``C_i = c_i``) holds the testable observations'
    indices and needs nothing m x m: with ``p_i = Q1^T L^{-1} c_i`` (row i of
    ``L^{-T} Q1``) the whitened bias space of ``c_i`` has ``Rc_i² = (Q_yy^{-1})_ii -
    |p_i|²`` (the w-test's squared denominator) and ``Qc_i^T ẽ = (L^{-T} ẽ)_i / Rc_i``, so
    ``T_i = w_i²``, ``∇̂_i = (L^{-T} ẽ)_i / Rc_i²`` and ``x̂_i = x̂_0 - R^{-1} p_i ∇̂_i``.
    """

    names: Sequence[str]
    dims: np.ndarray  # q_k
    singles: np.ndarray | None = None  # indices of the tested observations (default)
    denom2: np.ndarray = field(default_factory=lambda: np.empty(0))  # Rc_i² of the singles
    bases: tuple[np.ndarray, ...] = ()  # Qc_k, m x q_k (given candidates)
    bias_maps: tuple[np.ndarray, ...] = ()  # Rc_k (∇̂_k = Rc_k^{-1} Qc_k^T ẽ)
    whitened: tuple[np.ndarray, ...] = ()  # L^{-1} C_k, m x q_k


def _check_candidate_list(candidates: Any, m: int) -> list:
    """The candidates as a list of bias matrices, refusing a layout that would be misread."""
    if isinstance(candidates, (str, bytes)) or not hasattr(candidates, "__len__"):
        raise ValueError(
            "candidates must be a list of bias matrices C_k (each (m, q_k) or (m,)), "
            f"got {type(candidates).__name__}"
        )
    if isinstance(candidates, np.ndarray) and candidates.ndim != 3:
        # A list is read element by element: a matrix would be read row by row.
        raise ValueError(
            f"candidates must be a list of bias matrices C_k, got one array of shape "
            f"{candidates.shape} (m = {m}); pass list(C.T) to test each column of C as its "
            "own one-dimensional candidate, or [C] for one candidate spanned by all its columns"
        )
    columns = list(candidates)
    if not columns:
        raise ValueError("candidates is empty; pass at least one alternative's C")
    return columns


def _candidates(fit: LeastSquaresFit, candidates: Any) -> _Candidates:
    if candidates is None:
        # Every observation that can be tested: its own outlier (the w-tests' alternatives).
        _, denom2, testable = _w_quantities(fit)
        singles = np.flatnonzero(testable)
        if singles.size == 0:
            raise ValueError("no observation can be tested (no redundancy anywhere)")
        return _Candidates(
            names=_ObservationNames(singles),
            dims=np.ones(singles.size, dtype=int),
            singles=singles,
            denom2=denom2[singles],
        )
    columns = _check_candidate_list(candidates, fit.m)
    bases, dims, maps, whitened = [], [], [], []
    for k, C in enumerate(columns):
        C = _bias_columns(fit, C, f"candidates[{k}]")
        space = _bias_space(fit, C, f"candidates[{k}]")
        bases.append(space.Qc)
        dims.append(space.q)
        maps.append(space.Rc)
        whitened.append(space.C_w)
    return _Candidates(
        names=tuple(f"candidate {k}" for k in range(len(columns))),
        dims=np.array(dims),
        bases=tuple(bases),
        bias_maps=tuple(maps),
        whitened=tuple(whitened),
    )


def _adaptation(fit: LeastSquaresFit, whitened_columns: np.ndarray) -> np.ndarray:
    """``R^{-1} Q1^T L^{-1} C`` (n x q): how the bias ``∇`` moves x̂ (``x̂_k = x̂_0 - it @ ∇̂``)."""
    return sla.solve_triangular(fit._R, fit._Q1.T @ whitened_columns, lower=False)


def _single_adaptations(fit: LeastSquaresFit, singles: np.ndarray) -> np.ndarray:
    """:func:`_adaptation` of every single-observation candidate: ``R^{-1} p_i`` as columns."""
    P = fit._covariance.whiten_transpose(fit._Q1)[singles]  # rows p_i = Q1^T L^{-1} c_i
    return sla.solve_triangular(fit._R, P.T, lower=False)


def _chi2_log_sf(x: np.ndarray, dof: np.ndarray) -> np.ndarray:
    """``log P(chi2(dof) > x)``, finite where scipy's ``chi2.logsf`` underflows to -inf.

    scipy computes ``log(sf)``, so beyond about ``x = 1500`` every statistic gets -inf and
    large statistics of different dimensions can no longer be ranked. There the upper
    incomplete gamma function ``Q(s, z)`` (``s = dof/2``, ``z = x/2``; the far tail, so
    ``z > s + 1``) is evaluated in logarithms by its continued fraction (modified Lentz).
    """
    x, dof = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(dof, dtype=float))
    out = np.array(stats.chi2.logsf(x, dof), dtype=float)
    far = np.isneginf(out) & (x / 2.0 > dof / 2.0 + 1.0)
    if np.any(far):
        s, z = dof[far] / 2.0, x[far] / 2.0
        tiny = 1e-300
        b = z + 1.0 - s
        c = np.full_like(z, 1.0 / tiny)
        d = 1.0 / b
        h = d.copy()
        for i in range(1, 300):
            a = -i * (i - s)
            b = b + 2.0
            d = a * d + b
            d = np.where(np.abs(d) < tiny, tiny, d)
            c = b + a / c
            c = np.where(np.abs(c) < tiny, tiny, c)
            d = 1.0 / d
            delta = d * c
            h = h * delta
            if np.all(np.abs(delta - 1.0) < 1e-15):
                break
        out[far] = -z + s * np.log(z) - special.gammaln(s) + np.log(h)
    return out


def _identify(statistics: np.ndarray, dims: np.ndarray) -> np.ndarray:
    """Index of the most significant alternative per row (largest T for equal q).

    With candidates of different dimension the statistics are not comparable; each is
    ranked by its p-value under H0 (the smallest wins), compared in logarithms so that
    very large statistics, whose p-values underflow to 0, keep their order.
    """
    if np.all(dims == dims[0]):
        return np.argmax(statistics, axis=-1)
    return np.argmin(_chi2_log_sf(statistics, dims), axis=-1)


@dataclass(frozen=True, repr=False, eq=False)
class DIAResult:
    """Outcome of :func:`dia` on one data set.

    Attributes
    ----------
    detection : TestResult
        The overall model test (detection step).
    identified : int or None
        Index of the identified alternative among the candidates (None when
        nothing was detected).
    statistics : ndarray, shape (k,)
        ``T_q`` of every candidate (``w_i²`` for single observations).
    candidate_names : sequence of str
        What each candidate is (``"observation 6"``, ``"candidate 2"``); a tuple, or for
        the default candidates a sequence that makes each name when read.
    x_hat : ndarray, shape (n,)
        The DIA estimate: x̂ of H0 when nothing is detected, else x̂ of the
        identified alternative.
    x_hat_null : ndarray, shape (n,)
        x̂ of H0 (the least-squares fit as given).
    bias : ndarray or None
        The identified alternative's estimated bias ∇̂ (None when nothing was detected).
    """

    detection: TestResult
    identified: int | None
    statistics: np.ndarray
    candidate_names: Sequence[str]
    x_hat: np.ndarray
    x_hat_null: np.ndarray
    bias: np.ndarray | None

    @property
    def decision(self) -> str:
        """``"accept H0"`` or ``"adapted: <candidate>"``."""
        if self.identified is None:
            return "accept H0"
        return f"adapted: {self.candidate_names[self.identified]}"

    def __repr__(self) -> str:
        x = ", ".join(format_number(float(v), 5) for v in self.x_hat)
        return (
            f"DIAResult(detected={self.detection.reject}, decision={self.decision!r}, x_hat=[{x}])"
        )


def dia(fit: LeastSquaresFit, candidates: Any = None, alpha: float = 0.05) -> DIAResult:
    r"""Detection, identification and adaptation on one data set.

    Parameters
    ----------
    fit : LeastSquaresFit
        The fit under H0.
    candidates : list of array_like, optional
        The alternatives' bias matrices ``C_k`` (each ``(m, q_k)`` or ``(m,)``).
        Default: one outlier per testable observation (``C_i = c_i``).
    alpha : float
        Level of the detection step (the overall model test).

    Returns
    -------
    DIAResult
        The detection test, the identified alternative, every candidate's
        statistic and the DIA estimate x̂.

    See Also
    --------
    dia_monte_carlo : The law of the DIA estimator.
    data_snooping : Identification repeated until nothing is rejected.
    b_method : Levels for the detection and the one-dimensional tests.

    Notes
    -----
    Teunissen (2018): *detection* rejects H0 when the overall model test
    does; *identification* picks the alternative with the largest
    :math:`T_{q_k}` (for single observations, the largest :math:`|w_i|`; for
    alternatives of different dimension, whose statistics are not comparable, the
    smallest p-value under H0, compared in logarithms so that p-values below the
    smallest float keep their order); *adaptation*
    re-estimates x under it,

    .. math::

        \hat x_k = \hat x_0 - Q_{\hat x\hat x} A^{\mathsf T} Q_{yy}^{-1} C_k \hat\nabla_k,

    which equals the least-squares estimate of the model :math:`E(y) = Ax + C_k\nabla`.
    The DIA estimate :math:`\bar x` is :math:`\hat x_0` or :math:`\hat x_k`
    according to the decisions.

    Examples
    --------
    >>> import numpy as np
    >>> from course.lsq import fit
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> y = [2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53]
    >>> result = dia(fit(A, y, 0.01 * np.eye(10)), alpha=0.01)
    >>> result.decision, result.x_hat.round(3)
    ('adapted: observation 6', array([2.022, 0.502]))
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    _require_redundancy(fit, "DIA procedure")
    cands = _candidates(fit, candidates)
    detection = overall_model_test(fit, alpha)
    x0 = fit.x_hat
    if cands.singles is not None:
        numerator = fit._w_parts[0][cands.singles]  # c_i^T Qyy^{-1} ê
        statistics = numerator**2 / cands.denom2
    else:
        coordinates = [Qc.T @ fit._e_w for Qc in cands.bases]
        statistics = np.array([float(c @ c) for c in coordinates])
    if not detection.reject:
        return DIAResult(detection, None, readonly(statistics), cands.names, x0, x0, None)
    k = int(_identify(statistics, cands.dims))
    if cands.singles is not None:
        bias = np.array([numerator[k] / cands.denom2[k]])
        x_hat = x0 - _single_adaptations(fit, cands.singles[k : k + 1])[:, 0] * bias[0]
    else:
        bias = sla.solve_triangular(cands.bias_maps[k], coordinates[k], lower=False)
        x_hat = x0 - _adaptation(fit, cands.whitened[k]) @ bias
    return DIAResult(
        detection, k, readonly(statistics), cands.names, readonly(x_hat), x0, readonly(bias)
    )


@dataclass(frozen=True, repr=False, eq=False)
class DIAMonteCarlo:
    """Simulated DIA decisions and estimates (see :func:`dia_monte_carlo`).

    Attributes
    ----------
    errors : ndarray, shape (size, n)
        ``x̄ - x`` of the DIA estimator in each run.
    errors_null : ndarray, shape (size, n)
        ``x̂_0 - x`` of the plain least-squares estimator in the same runs.
    identified : ndarray of int, shape (size,)
        Identified candidate per run, ``-1`` where nothing was detected.
    candidate_names : sequence of str
        What each candidate is (as in :class:`DIAResult`).
    """

    errors: np.ndarray
    errors_null: np.ndarray
    identified: np.ndarray
    candidate_names: Sequence[str]

    @property
    def size(self) -> int:
        """Number of simulated data sets."""
        return int(self.identified.shape[0])

    @property
    def detection_rate(self) -> float:
        """Fraction of runs in which H0 was rejected."""
        return float(np.mean(self.identified >= 0))

    def identification_rate(self, k: int) -> float:
        """Fraction of runs in which candidate ``k`` was identified."""
        k = as_count(k, "k", minimum=0)
        if k >= len(self.candidate_names):
            raise ValueError(
                f"k must index one of the {len(self.candidate_names)} candidates, got {k}"
            )
        return float(np.mean(self.identified == k))

    def __repr__(self) -> str:
        return (
            f"DIAMonteCarlo(size={self.size}, candidates={len(self.candidate_names)}, "
            f"detection_rate={format_number(self.detection_rate, 4)})"
        )


def dia_monte_carlo(
    fit: LeastSquaresFit,
    candidates: Any = None,
    alpha: float = 0.05,
    bias: Any = None,
    size: int = 10_000,
    rng: Any = None,
) -> DIAMonteCarlo:
    r"""Simulate the DIA procedure on the fit's model: the law of the DIA estimator.

    Parameters
    ----------
    fit : LeastSquaresFit
        The model (design and ``Qyy``); its observations are not used.
    candidates : list of array_like, optional
        As for :func:`dia`.
    alpha : float
        Level of the detection step.
    bias : array_like, shape (m,), optional
        The true bias ``b`` in the observations (``C∇`` of the true
        alternative); zero (H0 true) when omitted.
    size : int
        Number of simulated data sets.
    rng : numpy.random.Generator
        Source of the noise (required: pass ``np.random.default_rng(seed)``).

    Returns
    -------
    DIAMonteCarlo
        Errors of the DIA and of the plain estimator, and the decisions.

    See Also
    --------
    dia : The procedure on one data set.

    Notes
    -----
    Each run draws :math:`y = Ax + b + e` with :math:`e \sim N(0, Q_{yy})` (x = 0:
    every estimator here is equivariant, so only the error matters) and applies
    :func:`dia`. The plain estimator :math:`\hat x_0` is normal; the DIA
    estimator :math:`\bar x = \hat x_0` on acceptance and :math:`\hat x_k` on
    identification of k is a mixture whose law Teunissen (2018) derives: it is
    not :math:`N(x, Q_{\hat x_k\hat x_k})` even when k is right, because it is
    conditioned on the decision. Vectorised: one whitened draw per run and one
    projection per candidate.

    Examples
    --------
    >>> import numpy as np
    >>> from course.lsq import fit
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> f = fit(A, np.zeros(10), 0.01 * np.eye(10))
    >>> mc = dia_monte_carlo(f, alpha=0.01, size=20_000, rng=np.random.default_rng(1))
    >>> round(mc.detection_rate, 3)
    0.01
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    size = as_count(size, "size")
    if rng is None:
        raise ValueError(
            "rng is required: pass a numpy.random.Generator, e.g. np.random.default_rng(1), "
            "so that the simulation can be repeated"
        )
    rng = as_generator(rng)
    _require_redundancy(fit, "DIA procedure")
    cands = _candidates(fit, candidates)
    m, n = fit.m, fit.n
    b = np.zeros(m) if bias is None else as_vector(as_float_array(bias, "bias"), "bias", m)
    critical = residual_threshold(fit.redundancy, alpha)  # the overall model test's
    shift = fit._covariance.whiten(b)
    if cands.singles is not None:
        adapt = _single_adaptations(fit, cands.singles)  # n x k, column i: R^{-1} p_i
        width = m
    else:
        adapt_k = [_adaptation(fit, C_w) for C_w in cands.whitened]
        width = m + int(cands.dims.sum())
    try:
        errors = np.empty((size, n))
        errors_null = np.empty((size, n))
        identified = np.full(size, -1)
    except MemoryError as exc:
        raise MemoryError(
            f"the results of {size} runs ({size * (2 * n + 1) * 8 / 1e9:.3g} GB) do not fit in "
            "memory; run fewer at a time, each with its own stream (rng.spawn), and combine"
        ) from exc
    # The draws in chunks of bounded memory: one Generator fills rows in order, so the chunks
    # see the same numbers as one (size, m) draw would.
    chunk = max(1, _CHUNK_BYTES // (8 * 4 * width))
    for start in range(0, size, chunk):
        rows = slice(start, min(start + chunk, size))
        noise = rng.standard_normal((rows.stop - rows.start, m)) + shift
        e_null, detected, choice, moves = _dia_chunk(
            fit, cands, noise, critical, adapt_k if cands.singles is None else adapt
        )
        errors_null[rows] = e_null
        errors[rows] = e_null - moves
        identified[rows] = np.where(detected, choice, -1)
    return DIAMonteCarlo(readonly(errors), readonly(errors_null), readonly(identified), cands.names)


def _dia_chunk(fit: LeastSquaresFit, cands: _Candidates, noise: np.ndarray, critical: float, adapt):
    """One chunk of :func:`dia_monte_carlo`: x̂_0's errors, detections, choices, adaptations."""
    Q1 = fit._Q1
    coefficients = noise @ Q1
    residuals = noise - coefficients @ Q1.T
    errors_null = sla.solve_triangular(fit._R, coefficients.T, lower=False).T
    detected = np.einsum("ij,ij->i", residuals, residuals) > critical
    moves = np.zeros_like(errors_null)
    if cands.singles is not None:
        # c_i^T Qyy^{-1} ẽ of every run at once (L^{-T} of the residuals, in observation order)
        numerators = fit._covariance.whiten_transpose(residuals.T).T[:, cands.singles]
        statistics = numerators**2 / cands.denom2
        choice = np.argmax(statistics, axis=1)
        runs = np.flatnonzero(detected)
        bias = numerators[runs, choice[runs]] / cands.denom2[choice[runs]]
        moves[runs] = adapt[:, choice[runs]].T * bias[:, None]
        return errors_null, detected, choice, moves
    coordinates = [residuals @ Qc for Qc in cands.bases]
    statistics = np.column_stack([np.einsum("ij,ij->i", c, c) for c in coordinates])
    choice = _identify(statistics, cands.dims)
    for k, (c, Rc, M) in enumerate(zip(coordinates, cands.bias_maps, adapt)):
        runs = detected & (choice == k)
        if np.any(runs):
            bias = sla.solve_triangular(Rc, c[runs].T, lower=False)
            moves[runs] = (M @ bias).T
    return errors_null, detected, choice, moves
