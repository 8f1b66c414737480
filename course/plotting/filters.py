"""Figures for Kalman filters and EKF residual generators (notebook 04).

Every function takes ``ax=None`` (a new figure is made when None) and returns
the axes it drew on.  Matplotlib is imported lazily by :func:`axes_or_new`.
"""

from __future__ import annotations

import numpy as np

from . import _mark_alarms, axes_or_new

__all__ = [
    "plot_alarm_rate",
    "plot_delay_histogram",
    "plot_estimate",
    "plot_normalized_histogram",
    "plot_residual",
    "plot_signals",
    "plot_test_statistic",
]


def _mark_fault(ax, fault_time, label="fault appears"):
    if fault_time is not None:
        ax.axvline(fault_time, color="k", ls=":", lw=1, label=label)


def plot_signals(t, y, u=None, ax=None, fault_time=None, y_label="y", u_label="u"):
    """Measured output ``y`` (and input ``u``) against time, the fault onset dotted.

    Parameters
    ----------
    t : (N,) array_like
        Time axis.
    y : (N,) or (N, p) array_like
        Output; the first channel is drawn.
    u : (N,) or (N, m) array_like, optional
        Input, drawn as a staircase (first channel).
    ax : matplotlib.axes.Axes, optional
    fault_time : float, optional
        Fault onset, drawn as a dotted vertical line.
    y_label, u_label : str
        Legend labels.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = axes_or_new(ax)
    ax.plot(t, np.asarray(y).reshape(len(t), -1)[:, 0], color="C0", lw=1, label=y_label)
    if u is not None:
        ax.plot(
            t,
            np.asarray(u).reshape(len(t), -1)[:, 0],
            color="C1",
            lw=1,
            ds="steps-post",
            label=u_label,
        )
    _mark_fault(ax, fault_time)
    ax.set_xlabel("t")
    ax.legend(loc="best")
    return ax


def plot_estimate(
    t,
    estimate,
    std,
    truth=None,
    ax=None,
    nsigma=2.0,
    label="estimate",
    truth_label="true value",
    fault_time=None,
):
    """An estimate with its ``± nsigma`` standard-deviation band and, optionally, the truth.

    Parameters
    ----------
    t, estimate, std : (N,) array_like
        Time, estimate (e.g. ``x_filt[:, 0]``) and its standard deviation
        (``sqrt(P_filt[:, 0, 0])``).
    truth : (N,) array_like, optional
    nsigma : float
        Half width of the band in standard deviations.
    ax : matplotlib.axes.Axes, optional
    label, truth_label : str
        Legend labels.
    fault_time : float, optional
        Fault onset, drawn dotted.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = axes_or_new(ax)
    estimate, std = np.asarray(estimate, float), np.asarray(std, float)
    ax.fill_between(
        t,
        estimate - nsigma * std,
        estimate + nsigma * std,
        color="C0",
        alpha=0.25,
        lw=0,
        label=f"± {nsigma:g} std",
    )
    ax.plot(t, estimate, color="C0", lw=1.2, label=label)
    if truth is not None:
        ax.plot(t, truth, color="k", lw=1, ls="--", label=truth_label)
    _mark_fault(ax, fault_time)
    ax.set_xlabel("t")
    ax.legend(loc="best")
    return ax


def plot_residual(
    t, residual, std=None, ax=None, nsigma=2.0, label="residual", fault_time=None, color="C3"
):
    """A residual (innovation) with an optional ``± nsigma sqrt(S_t)`` band around zero.

    Parameters
    ----------
    t : (N,) array_like
    residual : (N,) or (N, p) array_like
        The residual; the first channel is drawn.
    std : (N,) or (N, 1) array_like, optional
        Its standard deviation ``sqrt(S_t)`` (one output).
    ax : matplotlib.axes.Axes, optional
    nsigma : float
        Half width of the band.
    label : str
    fault_time : float, optional
    color : str

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = axes_or_new(ax)
    residual = np.asarray(residual, float).reshape(len(t), -1)[:, 0]
    if std is not None:
        std = np.asarray(std, float).reshape(len(t), -1)[:, 0]
        ax.fill_between(
            t, -nsigma * std, nsigma * std, color="0.8", lw=0, label=f"± {nsigma:g} sqrt(S)"
        )
    ax.plot(t, residual, color=color, lw=1, label=label)
    ax.axhline(0.0, color="k", lw=0.5)
    _mark_fault(ax, fault_time)
    ax.set_xlabel("t")
    ax.legend(loc="best")
    return ax


def plot_test_statistic(
    t, statistic, threshold, ax=None, label="test quantity", fault_time=None, color="C2", log=False
):
    """A thresholded test quantity; samples above the threshold are marked as alarms.

    Parameters
    ----------
    t : (N,) array_like
    statistic : (N,) array_like
        Test quantity (NaN where undefined).
    threshold : float
    ax : matplotlib.axes.Axes, optional
    label : str
    fault_time : float, optional
    color : str
    log : bool
        Logarithmic vertical axis.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = axes_or_new(ax)
    statistic = np.asarray(statistic, float)
    ax.plot(t, statistic, color=color, lw=1, label=label)
    ax.axhline(threshold, color="k", ls="--", lw=1, label="threshold")
    _mark_alarms(ax, t, statistic, threshold, "x", color="C3", ms=4)
    _mark_fault(ax, fault_time)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("t")
    ax.legend(loc="best")
    return ax


def plot_alarm_rate(t, statistic, threshold, ax=None, alpha=None, fault_time=None, label=None):
    """Fraction of Monte Carlo runs in alarm at each time step.

    Parameters
    ----------
    statistic : (n_runs, N) array_like
    alpha : float, optional
        The designed per-sample false-alarm probability, drawn as a line.
    t : (N,) array_like
    threshold : float
    ax : matplotlib.axes.Axes, optional
    fault_time : float, optional
    label : str, optional

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = axes_or_new(ax)
    statistic = np.asarray(statistic, float)
    with np.errstate(invalid="ignore"):
        rate = np.mean(statistic > threshold, axis=0)
    rate[np.all(np.isnan(statistic), axis=0)] = np.nan
    ax.plot(t, rate, lw=1.2, label=label or "fraction of runs in alarm")
    if alpha is not None:
        ax.axhline(alpha, color="k", ls="--", lw=1, label=f"design alpha = {alpha:g}")
    _mark_fault(ax, fault_time)
    ax.set_xlabel("t")
    ax.set_ylabel("P(alarm)")
    ax.legend(loc="best")
    return ax


def plot_delay_histogram(delays, ax=None, label=None, max_delay=None):
    """Histogram of detection delays (runs that never detect are counted in the title).

    Parameters
    ----------
    delays : (n_runs,) array_like
        Delays in samples, NaN for missed detections (``AlarmStatistics.delays``).
    ax : matplotlib.axes.Axes, optional
    label : str, optional
    max_delay : int, optional
        Delays above it are collected in the last bin.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    ax = axes_or_new(ax)
    delays = np.asarray(delays, float)
    hit = delays[np.isfinite(delays)]
    top = int(hit.max()) if max_delay is None and hit.size else int(max_delay or 1)
    bins = np.arange(-0.5, top + 1.5, 1.0)
    ax.hist(np.clip(hit, None, top), bins=bins, density=True, alpha=0.7, label=label)
    ax.set_xlabel("detection delay (samples)")
    ax.set_ylabel("fraction of runs")
    missed = int(np.sum(~np.isfinite(delays)))
    ax.set_title(f"{hit.size} detected, {missed} missed")
    if label:
        ax.legend(loc="best")
    return ax


def plot_normalized_histogram(z, ax=None, bins=60, label="normalised innovations"):
    """Histogram of normalised innovations against the N(0, 1) density.

    Parameters
    ----------
    z : array_like
        Normalised innovations (any shape; NaN ignored).
    ax : matplotlib.axes.Axes, optional
    bins : int
    label : str

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    from scipy import stats

    ax = axes_or_new(ax)
    z = np.asarray(z, float).ravel()
    z = z[np.isfinite(z)]
    ax.hist(z, bins=bins, density=True, alpha=0.6, label=label)
    grid = np.linspace(-4.5, 4.5, 300)
    ax.plot(grid, stats.norm.pdf(grid), color="k", lw=1.2, label="N(0, 1)")
    ax.set_xlabel("value")
    ax.legend(loc="best")
    return ax
