"""Alarms of a thresholded statistic over many runs: empirical thresholds, false alarms, delays.

The last link of the NIS chain: the LiU lecture on test quantities leaves
threshold selection and the quality of a test to its next lecture (last
slide; full reference in the course bibliography, :doc:`/docs/bibliography`);
these are their Monte Carlo estimates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from course.results import format_number
from course.validation import as_finite, as_float_array, as_index, as_probability


def _with_undefined(value: Any, name: str) -> np.ndarray:
    """A float array of test quantities in which NaN marks undefined samples (inf is refused)."""
    return as_float_array(value, name, nan=True)


def empirical_threshold(null_statistic, alpha) -> float:
    """Threshold with a per-sample false-alarm rate ``alpha`` from fault-free runs.

    Parameters
    ----------
    null_statistic : array_like
        Test quantities simulated under H0, any shape (for instance a batch
        of windowed statistics); NaN entries (undefined samples) are ignored.
    alpha : float
        Designed false-alarm probability.

    Returns
    -------
    float
        The empirical ``1 - alpha`` quantile of the finite values.

    Notes
    -----
    For test quantities whose law under H0 is not known in closed form
    (the observer's windowed energy), ``J = F_hat^{-1}(1 - alpha)`` with
    ``F_hat`` the empirical distribution function of the simulated values
    (numpy's linear-interpolation quantile).  Its accuracy is that of a
    Monte Carlo quantile: simulate many more than ``1 / alpha`` values.

    Examples
    --------
    >>> import numpy as np
    >>> null = np.random.default_rng(0).chisquare(4, size=200_000)
    >>> round(empirical_threshold(null, 0.05), 1)   # chi2.isf(0.05, 4) = 9.49
    9.5
    """
    alpha = as_probability(alpha)
    values = _with_undefined(null_statistic, "null_statistic")
    values = values[~np.isnan(values)]
    if values.size == 0:
        raise ValueError("null_statistic has no finite values (all are NaN, undefined)")
    return float(np.quantile(values, 1.0 - alpha))


@dataclass(frozen=True, repr=False, eq=False)
class AlarmStatistics:
    """False alarms and detection delays of a thresholded statistic over many runs.

    Attributes
    ----------
    threshold : float
    false_alarm_rate : float
        Fraction of (run, sample) pairs before the fault (all samples without
        a fault) with a full window where the statistic exceeds the threshold.
    n_checked : int
        Number of such pairs.
    run_false_alarm_probability : float
        Fraction of runs with at least one alarm before the fault.
    detection_probability : float
        Fraction of runs with an alarm at or after the fault (NaN without one).
    delays : (n_runs,) ndarray
        First alarm time at or after ``fault_time`` minus ``fault_time``;
        NaN for runs that never alarm after the fault (empty without a fault).
    fault_time : int or None
    """

    threshold: float
    false_alarm_rate: float
    n_checked: int
    run_false_alarm_probability: float
    detection_probability: float
    delays: np.ndarray
    fault_time: int | None

    def __repr__(self) -> str:
        parts = [
            f"threshold={format_number(self.threshold)}",
            f"false_alarm_rate={format_number(self.false_alarm_rate, 4)}",
            f"run_false_alarm_probability={format_number(self.run_false_alarm_probability, 4)}",
        ]
        if self.fault_time is not None:
            parts += [
                f"detection_probability={format_number(self.detection_probability, 4)}",
                f"median_delay={format_number(self.median_delay, 4)}",
            ]
        return "AlarmStatistics(" + ", ".join(parts) + ")"

    @property
    def median_delay(self) -> float:
        """Median delay over the runs that detect (NaN if none does)."""
        d = self.delays[np.isfinite(self.delays)]
        return float(np.median(d)) if d.size else float("nan")

    @property
    def mean_delay(self) -> float:
        """Mean delay over the runs that detect (NaN if none does)."""
        d = self.delays[np.isfinite(self.delays)]
        return float(np.mean(d)) if d.size else float("nan")


def alarm_statistics(statistic, threshold, fault_time=None) -> AlarmStatistics:
    """Count false alarms and measure detection delays, vectorised over runs.

    Parameters
    ----------
    statistic : (n_runs, N) array_like
        A test quantity per run and sample (NaN where undefined, e.g. before
        the first full window).
    threshold : float
        Alarm when ``statistic > threshold``.
    fault_time : int, optional
        First faulty sample; without it every sample counts for false alarms.

    Returns
    -------
    AlarmStatistics

    Notes
    -----
    With alarms ``a_{i,t} = [T_{i,t} > threshold]`` (NaN never alarms):
    the false-alarm rate is ``sum a_{i,t} / #{(i, t) : t < fault_time,
    T_{i,t} defined}``, an estimate of the per-sample ``alpha`` of
    :func:`windowed_nis_threshold`; the run false-alarm probability is the
    fraction of runs with ``max_{t < fault_time} a_{i,t} = 1``, the
    quantity that grows with the record length (multiple testing); the
    delay of run ``i`` is ``min{t >= fault_time : a_{i,t}} - fault_time``.
    The lecture leaves the choice of threshold and the quality of a test
    (false alarms, detection) to the next lecture
    (LiU lecture, last slide); these are its Monte Carlo
    estimates.

    Examples
    --------
    >>> import numpy as np
    >>> T = np.array([[0.1, 2.0, 0.3, 5.0, 6.0], [0.2, 0.1, 0.2, 0.4, 7.0]])
    >>> stats = alarm_statistics(T, 1.0, fault_time=3)
    >>> stats.false_alarm_rate, stats.detection_probability, stats.delays
    (0.16666666666666666, 1.0, array([0., 1.]))
    """
    T = _with_undefined(statistic, "statistic")
    if T.ndim != 2 or T.size == 0:
        raise ValueError(
            f"statistic must have shape (n_runs, N), got {T.shape}; "
            "for a single run pass statistic[None, :]"
        )
    _n_runs, N = T.shape
    threshold = as_finite(threshold, "threshold")
    if fault_time is not None:
        fault_time = as_index(fault_time, "fault_time", N, what="the first faulty sample")
    end = N if fault_time is None else fault_time
    with np.errstate(invalid="ignore"):
        alarms = threshold < T  # NaN compares False
    before = alarms[:, :end]
    n_checked = int(np.isfinite(T[:, :end]).sum())
    rate = float(before.sum() / n_checked) if n_checked else float("nan")
    run_fa = float(before.any(axis=1).mean()) if end > 0 else float("nan")
    if fault_time is None:
        return AlarmStatistics(threshold, rate, n_checked, run_fa, float("nan"), np.empty(0), None)
    after = alarms[:, fault_time:]
    hit = after.any(axis=1)
    delays = np.where(hit, np.argmax(after, axis=1), np.nan).astype(float)
    return AlarmStatistics(
        threshold, rate, n_checked, run_fa, float(hit.mean()), delays, fault_time
    )
