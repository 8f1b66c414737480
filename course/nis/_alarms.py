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


def _with_undefined_start(value: Any, name: str, consequence: str) -> tuple[np.ndarray, int]:
    """A float array of test quantities (time on the last axis) and its undefined start.

    The undefined start is the leading samples that are NaN in every run (windows not yet
    full); any other NaN (a diverged run, a NaN in some runs only) is refused, since
    ``consequence`` (what ignoring it would do) would happen silently. inf is refused.
    """
    T = as_float_array(value, name, nan=True)
    if not np.isnan(T).any():
        return T, 0
    undefined = np.isnan(T).reshape(-1, T.shape[-1] if T.ndim else 1)
    in_every_run = undefined.all(axis=0)
    start = int(np.argmin(in_every_run)) if not in_every_run.all() else in_every_run.size
    later = undefined[:, start:]
    if later.any():
        run, sample = np.argwhere(later)[0]
        where = (*np.unravel_index(run, T.shape[:-1]), start + sample) if T.ndim else ()
        index = tuple(int(i) for i in where)
        raise ValueError(
            f"{name} is NaN at index {index} ({int(later.sum())} NaN in all) after its "
            "undefined start: only the leading samples that are NaN in every run (windows "
            "not yet full) may be NaN. A NaN later, or in some runs only, is a failed "
            f"computation (e.g. a diverged filter), not an undefined window, and {consequence}: "
            "find its cause, or leave the failed runs out"
        )
    return T, start


def empirical_threshold(null_statistic, alpha) -> float:
    r"""Threshold with a per-sample false-alarm rate ``alpha`` from fault-free runs.

    Parameters
    ----------
    null_statistic : array_like
        Test quantities simulated under H0, any shape, time on the last axis
        (for instance a batch ``(n_runs, N)`` of windowed statistics). Its
        undefined start, the leading samples that are NaN in every run
        (windows not yet full), is left out; any other NaN is refused.
    alpha : float
        Designed false-alarm probability.

    Returns
    -------
    float
        The empirical ``1 - alpha`` quantile of the values after the undefined start.

    Raises
    ------
    ValueError
        If ``null_statistic`` holds inf, or NaN other than its undefined
        start (a failed run: leaving it out would bias the threshold).

    See Also
    --------
    windowed_nis_threshold : The threshold when the law under H0 is a chi-square.
    alarm_statistics : False-alarm rate and detection delay of a threshold.

    Notes
    -----
    For test quantities whose law under H0 is not known in closed form
    (the observer's windowed energy), the threshold is the empirical quantile

    .. math::

        J = \hat F^{-1}(1 - \alpha),

    with :math:`\hat F` the empirical distribution function of the simulated
    values (numpy's linear-interpolation quantile).  Its accuracy is that of a
    Monte Carlo quantile: simulate many more than :math:`1/\alpha` values.

    Examples
    --------
    >>> import numpy as np
    >>> null = np.random.default_rng(0).chisquare(4, size=200_000)
    >>> round(empirical_threshold(null, 0.05), 1)   # chi2.isf(0.05, 4) = 9.49
    9.5
    """
    alpha = as_probability(alpha)
    values, start = _with_undefined_start(
        null_statistic, "null_statistic", "leaving it out would bias the threshold"
    )
    values = np.atleast_1d(values)[..., start:]
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
    r"""Count false alarms and measure detection delays, vectorised over runs.

    Parameters
    ----------
    statistic : (n_runs, N) array_like
        A test quantity per run and sample. Its undefined start, the leading
        samples that are NaN in every run (before the first full window), is
        not counted; any other NaN is refused.
    threshold : float
        Alarm when ``statistic > threshold``.
    fault_time : int, optional
        First faulty sample; without it every sample counts for false alarms.

    Returns
    -------
    AlarmStatistics

    Raises
    ------
    ValueError
        If ``statistic`` is not 2-D, holds inf, or holds NaN other than its
        undefined start (a failed run: counting it as "no alarm" would bias
        the rates and delays).

    See Also
    --------
    windowed_nis_threshold : The per-sample threshold these rates estimate.
    empirical_threshold : A threshold from simulated values.

    Notes
    -----
    With alarms :math:`a_{i,t} = [T_{i,t} > J]` (run :math:`i`, sample
    :math:`t`, threshold :math:`J`), :math:`t_0` the first sample after the
    undefined start and :math:`t_f` the fault time, the false-alarm rate is

    .. math::

        \hat\alpha = \frac{\sum_i \sum_{t_0 \le t < t_f} a_{i,t}}
                          {\#\{(i, t) : t_0 \le t < t_f\}},

    an estimate of the per-sample :math:`\alpha` of
    :func:`windowed_nis_threshold`; the run false-alarm probability is the
    fraction of runs with :math:`\max_{t < t_f} a_{i,t} = 1`, the quantity that
    grows with the record length (multiple testing); the delay of run :math:`i`
    is :math:`\min\{t \ge t_f : a_{i,t} = 1\} - t_f`.
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
    T, start = _with_undefined_start(
        statistic, "statistic", 'counting it as "no alarm" would bias the rates and delays'
    )
    if T.ndim != 2 or T.size == 0:
        raise ValueError(
            f"statistic must have shape (n_runs, N), got {T.shape}; "
            "for a single run pass statistic[None, :]"
        )
    n_runs, N = T.shape
    threshold = as_finite(threshold, "threshold")
    if fault_time is not None:
        fault_time = as_index(fault_time, "fault_time", N, what="the first faulty sample")
    end = N if fault_time is None else fault_time
    with np.errstate(invalid="ignore"):
        alarms = threshold < T  # the undefined start (NaN) compares False
    before = alarms[:, :end]
    n_checked = n_runs * max(end - start, 0)
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
