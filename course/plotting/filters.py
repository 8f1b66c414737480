"""Figures for Kalman filters and EKF residual generators (notebook 04).

Every function takes ``ax=None`` (a new figure is made when None), returns
the axes it drew on and draws in the course style
(:mod:`course.plotting.style`): each filter keeps its colour pair (pass
``color=pair(k)``), bands are the light shade of their estimate's colour,
the fault onset is a dotted red line. Matplotlib is imported lazily.
"""

from __future__ import annotations

import numpy as np

from . import _checks, _mark_alarms, axes_or_new
from .style import (
    LAW,
    REJECT,
    Pair,
    legend_outside,
    mark_time,
    pair,
    plain_log_axis,
    sample_histogram,
    styled,
    theory_grid,
    threshold_line,
)

__all__ = [
    "plot_alarm_rate",
    "plot_delay_histogram",
    "plot_estimate",
    "plot_kalman_timeline",
    "plot_normalized_histogram",
    "plot_residual",
    "plot_signals",
    "plot_test_statistic",
]


def _pair(color, default) -> Pair:
    if color is None:
        return default
    if isinstance(color, Pair):
        return color
    if isinstance(color, (int, np.integer)) or (isinstance(color, str) and color[:1] in "NF"):
        try:
            return pair(color)
        except ValueError:
            pass
    return Pair(color, color)


def _time(t):
    return _checks.array("t", t, what="times")


def _series(name, value, t, allow_nan=False):
    """A (N,) or (N, p) series aligned with ``t``; its first channel."""
    out = _checks.array(name, value, ndim=(1, 2), allow_nan=allow_nan, what="samples")
    if out.shape[0] != t.size:
        raise ValueError(f"{name} has {out.shape[0]} samples but t has {t.size}")
    return out.reshape(t.size, -1)[:, 0]


def _fault(ax, fault_time):
    if fault_time is not None:
        mark_time(ax, _checks.scalar("fault_time", fault_time))


@styled
def plot_signals(
    t,
    y,
    u=None,
    ax=None,
    fault_time=None,
    y_label="output y",
    u_label="input u",
    xlabel="t [samples]",
    ylabel="signal",
):
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
    xlabel, ylabel : str
        Axis labels with units.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    t = _time(t)
    y = _series("y", y, t)
    u = None if u is None else _series("u", u, t)
    ax = axes_or_new(ax)
    ax.plot(t, y, color=pair(0).dark, lw=1, label=y_label)
    if u is not None:
        ax.plot(t, u, color=pair("NF").dark, lw=1, ds="steps-post", label=u_label)
    _fault(ax, fault_time)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
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
    color=None,
    xlabel="t [samples]",
    ylabel="estimate",
):
    """An estimate with its ``± nsigma`` standard-deviation band and, optionally, the truth.

    Parameters
    ----------
    t, estimate, std : (N,) array_like
        Time, estimate (e.g. ``x_filt[:, 0]``) and its standard deviation
        (``sqrt(P_filt[:, 0, 0])``); NaN where the estimate is undefined.
    truth : (N,) array_like, optional
    nsigma : float
        Half width of the band in standard deviations.
    ax : matplotlib.axes.Axes, optional
    label, truth_label : str
        Legend labels (the band is labelled ``label ± nsigma std``).
    fault_time : float, optional
        Fault onset, drawn dotted.
    color : int, str or Pair, optional
        Colour pair of this estimate: give each filter its own, so that two
        estimates on one axes stay apart.
    xlabel, ylabel : str
        Axis labels (give the quantity and its unit).

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    t = _time(t)
    # NaN marks an undefined estimate (e.g. the diffuse start of recursive least squares)
    estimate = _series("estimate", estimate, t, allow_nan=True)
    std = _series("std", std, t, allow_nan=True)
    if np.any(std < 0):
        raise ValueError("std must be >= 0 (standard deviations)")
    nsigma = _checks.scalar("nsigma", nsigma, positive=True)
    truth = None if truth is None else _series("truth", truth, t)
    colours = _pair(color, pair(0))
    ax = axes_or_new(ax)
    ax.fill_between(
        t,
        estimate - nsigma * std,
        estimate + nsigma * std,
        color=colours.light,
        alpha=0.6,
        lw=0,
        label=f"{label} ± {nsigma:g} std",
    )
    ax.plot(t, estimate, color=colours.dark, ls=colours.ls, lw=1.3, label=label)
    if truth is not None:
        ax.plot(t, truth, color="k", lw=1, ls="--", label=truth_label)
    _fault(ax, fault_time)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
def plot_residual(
    t,
    residual,
    std=None,
    ax=None,
    nsigma=2.0,
    label="residual",
    fault_time=None,
    color=None,
    xlabel="t [samples]",
    ylabel="residual",
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
    color : int, str or Pair, optional
        Colour pair (dark: the residual, light: its band).
    xlabel, ylabel : str
        Axis labels with units.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    t = _time(t)
    residual = _series("residual", residual, t)
    nsigma = _checks.scalar("nsigma", nsigma, positive=True)
    colours = _pair(color, pair(0))
    ax = axes_or_new(ax)
    if std is not None:
        std = _series("std", std, t)
        ax.fill_between(
            t,
            -nsigma * std,
            nsigma * std,
            color=colours.light,
            alpha=0.6,
            lw=0,
            label=rf"$\pm$ {nsigma:g}$\sqrt{{S_t}}$",
        )
    ax.plot(t, residual, color=colours.dark, ls=colours.ls, lw=1, label=label)
    ax.axhline(0.0, color="k", lw=0.5)
    _fault(ax, fault_time)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
def plot_test_statistic(
    t,
    statistic,
    threshold,
    ax=None,
    label="test quantity",
    fault_time=None,
    color=None,
    log=False,
    xlabel="t [samples]",
    ylabel="test quantity",
):
    """A thresholded test quantity; samples above the threshold are marked as alarms.

    Parameters
    ----------
    t : (N,) array_like
    statistic : (N,) array_like
        Test quantity (NaN where undefined, e.g. before the first full window).
    threshold : float
    ax : matplotlib.axes.Axes, optional
    label : str
    fault_time : float, optional
    color : int, str or Pair, optional
    log : bool
        Logarithmic vertical axis.
    xlabel, ylabel : str

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    t = _time(t)
    statistic = _checks.array("statistic", statistic, allow_nan=True, what="test quantities")
    _checks.same_length("t", t, "statistic", statistic)
    threshold = _checks.scalar("threshold", threshold)
    log = _checks.flag("log", log)
    colours = _pair(color, pair(0))
    ax = axes_or_new(ax)
    ax.plot(t, statistic, color=colours.dark, lw=1, label=label)
    threshold_line(ax, threshold, label=f"threshold {threshold:.4g}", orientation="horizontal")
    _mark_alarms(ax, t, statistic, threshold, "o", ms=3)
    _fault(ax, fault_time)
    if log:
        plain_log_axis(ax)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
def plot_alarm_rate(
    t,
    statistic,
    threshold,
    ax=None,
    alpha=None,
    fault_time=None,
    label=None,
    color=None,
    xlabel="t [samples]",
):
    """Fraction of Monte Carlo runs in alarm at each time step.

    Parameters
    ----------
    t : (N,) array_like
    statistic : (n_runs, N) array_like
        The test quantity of every run (NaN where undefined).
    threshold : float
    ax : matplotlib.axes.Axes, optional
    alpha : float, optional
        The designed per-sample false-alarm probability, drawn as a line.
    fault_time : float, optional
    label : str, optional
    color : int, str or Pair, optional
    xlabel : str

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    t = _time(t)
    statistic = _checks.array(
        "statistic", statistic, ndim=2, allow_nan=True, what="test quantities (runs x time)"
    )
    if statistic.shape[1] != t.size:
        raise ValueError(
            f"statistic must be (n_runs, N) with N = len(t) = {t.size}, got {statistic.shape}"
        )
    threshold = _checks.scalar("threshold", threshold)
    alpha = _checks.probability("alpha", alpha, allow_none=True)
    colours = _pair(color, pair(0))
    ax = axes_or_new(ax)
    with np.errstate(invalid="ignore"):
        rate = np.mean(statistic > threshold, axis=0)
    rate[np.all(np.isnan(statistic), axis=0)] = np.nan
    ax.plot(
        t,
        rate,
        lw=1.3,
        color=colours.dark,
        ls=colours.ls,
        label=label or "fraction of runs in alarm",
    )
    if alpha is not None:
        threshold_line(ax, alpha, label=rf"design $\alpha$ = {alpha:g}", orientation="horizontal")
    _fault(ax, fault_time)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("P(alarm)")
    legend_outside(ax)
    return ax


@styled
def plot_delay_histogram(delays, ax=None, label=None, max_delay=None, color=None):
    """Histogram of detection delays (runs that never detect are counted in the title).

    Parameters
    ----------
    delays : (n_runs,) array_like
        Delays in samples, NaN for missed detections (``AlarmStatistics.delays``).
    ax : matplotlib.axes.Axes, optional
    label : str, optional
    max_delay : int, optional
        Delays above it are collected in the last bin.
    color : int, str or Pair, optional

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.
    """
    delays = _checks.array("delays", delays, allow_nan=True, what="detection delays")
    max_delay = _checks.positive_int("max_delay", max_delay, allow_none=True)
    colours = _pair(color, pair(0))
    ax = axes_or_new(ax)
    hit = delays[np.isfinite(delays)]
    top = int(hit.max()) if max_delay is None and hit.size else int(max_delay or 1)
    bins = np.arange(-0.5, top + 1.5, 1.0)
    ax.hist(
        np.clip(hit, None, top),
        bins=bins,
        weights=np.full(hit.size, 1.0 / delays.size),
        color=colours.light,
        ec=colours.dark,
        lw=0.6,
        label=label,
    )
    ax.set_xlabel("detection delay [samples]" + (f" (last bin: ≥ {top})" if max_delay else ""))
    ax.set_ylabel("fraction of all runs")
    missed = int(np.sum(~np.isfinite(delays)))
    ax.set_title(f"{hit.size} detected, {missed} missed")
    if label:
        legend_outside(ax)
    return ax


@styled
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

    z = _checks.array("z", z, ndim=None, allow_nan=True, what="normalised innovations").ravel()
    z = z[np.isfinite(z)]
    bins = _checks.positive_int("bins", bins)
    ax = axes_or_new(ax)
    sample_histogram(ax, z, bins=bins, range=(-4.5, 4.5), label=label)
    grid = theory_grid(-4.5, 4.5)
    ax.plot(grid, stats.norm.pdf(grid), color=LAW, lw=2, label=r"$N(0, 1)$ density")
    ax.set_xlabel(r"normalised innovation $\varepsilon_t / \sqrt{S_t}$")
    ax.set_ylabel("density")
    legend_outside(ax)
    return ax


@styled
def plot_kalman_timeline(result, y=None, steps=None, state=0, ax=None, nsigma=2.0, t=None):
    r"""The Kalman filter's rhythm: predict, measure, update, over a few steps.

    Parameters
    ----------
    result : course.filters.FilterResult
        Of a single record (no batch axis), with covariances stored.
    y : (N,) or (N, 1) array_like, optional
        The measurements, drawn on the state's axis: meaningful when the
        chosen state is measured directly (``H = 1`` for it).
    steps : slice or sequence of int, optional
        Which time steps to show (default: the first 8).
    state : int
        Which state component to draw.
    ax : matplotlib.axes.Axes, optional
    nsigma : float
        Half width of the error bars in standard deviations.
    t : (N,) array_like, optional
        Times of the samples (0, 1, ... by default).

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.filters.kf_update : The measurement update it draws.
    course.filters.kf_predict : The time update it draws.

    Notes
    -----
    At each time step the prediction
    :math:`\hat x(t|t-1) \pm n_\sigma \sqrt{P(t|t-1)}` (light, left) meets the
    measurement :math:`y_t` (cross); the measurement update moves it by
    :math:`K_t \varepsilon_t` and shrinks the uncertainty to :math:`P(t|t)`
    (dark, right, solid arrow); the time update carries :math:`\hat x(t|t)` to
    the next prediction and lets the uncertainty grow again (dashed arrow).
    """
    for name in ("x_pred", "P_pred", "x_filt", "P_filt"):
        if getattr(result, name, None) is None:
            raise ValueError(
                f"result.{name} is missing: run the filter with its covariances stored"
            )
    x_pred = np.asarray(result.x_pred, dtype=float)
    if x_pred.ndim != 2:
        raise ValueError(
            f"result must hold one record (x_pred of shape (N, n)), got shape {x_pred.shape}"
        )
    N, n = x_pred.shape
    if not isinstance(state, (int, np.integer)) or isinstance(state, bool) or not 0 <= state < n:
        raise ValueError(f"state must be an index 0..{n - 1}, got {state!r}")
    nsigma = _checks.scalar("nsigma", nsigma, positive=True)
    times = np.arange(N, dtype=float) if t is None else _checks.array("t", t, what="times")
    if times.size != N:
        raise ValueError(f"t has {times.size} entries for {N} filter steps")
    if steps is None:
        steps = np.arange(min(N, 8))
    elif isinstance(steps, slice):
        steps = np.arange(N)[steps]
    else:
        steps = np.asarray(steps)
        if steps.ndim != 1 or steps.size == 0 or np.any((steps < 0) | (steps >= N)):
            raise ValueError(f"steps must be indices of filter steps 0..{N - 1}")
    if steps.size == 0:
        raise ValueError("steps selects no time step")
    xp = x_pred[steps, state]
    sp = np.sqrt(np.asarray(result.P_pred, float)[steps, state, state])
    xf = np.asarray(result.x_filt, float)[steps, state]
    sf = np.sqrt(np.asarray(result.P_filt, float)[steps, state, state])
    tt = times[steps]
    dt = np.min(np.diff(tt)) if tt.size > 1 else 1.0
    off = 0.18 * dt
    predict, update = pair(0), pair(1)
    ax = axes_or_new(ax)
    ax.errorbar(
        tt - off,
        xp,
        yerr=nsigma * sp,
        fmt="o",
        color=predict.dark,
        mfc=predict.light,
        capsize=3,
        label=rf"prediction $\hat x(t|t-1)$ $\pm${nsigma:g}$\sigma$",
    )
    ax.errorbar(
        tt + off,
        xf,
        yerr=nsigma * sf,
        fmt="s",
        color=update.dark,
        mfc=update.dark,
        capsize=3,
        label=rf"update $\hat x(t|t)$ $\pm${nsigma:g}$\sigma$",
    )
    if y is not None:
        yy = _checks.array("y", y, ndim=(1, 2), what="measurements").reshape(N, -1)[:, 0]
        ax.plot(tt, yy[steps], "x", color=REJECT.dark, ms=7, mew=2, label="measurement $y_t$")
    for k in range(steps.size):
        ax.annotate(
            "",
            xy=(tt[k] + off, xf[k]),
            xytext=(tt[k] - off, xp[k]),
            arrowprops=dict(arrowstyle="-|>", color=update.dark, lw=1.2),
        )
        if k + 1 < steps.size and steps[k + 1] == steps[k] + 1:
            ax.annotate(
                "",
                xy=(tt[k + 1] - off, xp[k + 1]),
                xytext=(tt[k] + off, xf[k]),
                arrowprops=dict(arrowstyle="-|>", color=predict.dark, lw=1.0, ls="--"),
            )
    ax.plot([], [], "-", color=update.dark, label=r"measurement update: $+K_t\varepsilon_t$")
    ax.plot([], [], "--", color=predict.dark, label="time update: predict")
    ax.set_xticks(tt)
    ax.set_xlabel("t [samples]")
    ax.set_ylabel(f"state {state + 1}")
    legend_outside(ax)
    return ax
