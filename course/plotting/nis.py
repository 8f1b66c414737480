"""Figures for the NIS / NIS-matrix chapter (notebook 05).

Every function takes ``ax=None`` (a new figure is made when it is None),
returns the axes it drew on and draws in the course style
(:mod:`course.plotting.style`): the scalar NIS test keeps pair 0, the
NIS-matrix test pair 1 in every figure.  Nothing here computes a statistic:
the numbers come from :mod:`course.nis`.
"""

from __future__ import annotations

import numpy as np

from . import _checks, axes_or_new
from .style import (
    LAW,
    REJECT,
    legend_outside,
    monte_carlo_dots,
    pair,
    sample_histogram,
    styled,
    theory_grid,
)

__all__ = [
    "plot_cdf_errors",
    "plot_consistency",
    "plot_detection",
    "plot_extreme_laws",
    "plot_sample_against_law",
    "plot_whitened_scatter",
]


@styled
def plot_sample_against_law(
    sample, law, ax=None, bins=60, label=None, law_label=None, grid=None, xlabel="value"
):
    """Histogram of a Monte Carlo sample (as a density) with a law's pdf on top.

    Parameters
    ----------
    sample : (n,) array_like
        Draws.
    law : frozen distribution or sequence of them
        Anything with ``pdf``; several laws are drawn as several curves.
    bins : int
        Histogram bins.
    label, law_label : str or sequence of str, optional
        Legend texts for the histogram and the curve(s).
    grid : array_like, optional
        Where to evaluate the pdf (a fine grid over the sample's range by default).
    xlabel : str
        Label of the horizontal axis.

    Returns
    -------
    matplotlib.axes.Axes
    """
    sample = _checks.array("sample", sample, what="draws")
    bins = _checks.positive_int("bins", bins)
    laws = law if isinstance(law, (list, tuple)) else [law]
    if not laws or not all(hasattr(one, "pdf") for one in laws):
        raise ValueError("law must be a distribution with a pdf method, or a list of them")
    ax = axes_or_new(ax)
    sample_histogram(ax, sample, bins=bins, label=label)
    if grid is None:
        lo, hi = np.quantile(sample, [0.0005, 0.9995])
        pad = 0.05 * (hi - lo)
        grid = theory_grid(max(lo - pad, 0.0) if lo >= 0 else lo - pad, hi + pad)
    else:
        grid = _checks.array("grid", grid, min_size=2, what="grid values")
    names = law_label if isinstance(law_label, (list, tuple)) else [law_label] * len(laws)
    for index, (one, name) in enumerate(zip(laws, names)):
        colour = LAW if index == 0 else pair(index).dark
        ax.plot(grid, one.pdf(grid), color=colour, ls=pair(index).ls, lw=2, label=name)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("density")
    if label or law_label:
        legend_outside(ax)
    return ax


@styled
def plot_extreme_laws(law_min, law_max, samples=None, ax=None, bins=80, thresholds=None):
    """Densities of the smallest and largest eigenvalue, with optional MC histograms.

    Parameters
    ----------
    law_min, law_max : frozen distributions
        E.g. ``course.nis.extreme_eigenvalue(m, K, "min")`` and ``"max"``.
    samples : tuple of arrays, optional
        ``(lmin, lmax)`` Monte Carlo draws to show as histograms.
    bins : int
    thresholds : (float, float), optional
        The matrix test's critical values ``(lower, upper)``: the tails
        ``λ_min < lower`` and ``λ_max > upper`` are shaded.

    Returns
    -------
    matplotlib.axes.Axes
    """
    bins = _checks.positive_int("bins", bins)
    if samples is not None:
        if len(samples) != 2:
            raise ValueError("samples must be a pair (lmin, lmax) of arrays of draws")
        samples = (
            _checks.array("samples[0]", samples[0], what="draws of the smallest eigenvalue"),
            _checks.array("samples[1]", samples[1], what="draws of the largest eigenvalue"),
        )
    ax = axes_or_new(ax)
    lo = float(law_min.ppf(1e-4))
    hi = float(law_max.isf(1e-4))
    grid = theory_grid(lo, hi, 500)
    low, high = pair(0), pair(1)
    if samples is not None:
        for sample, name in zip(samples, ("min", "max")):
            sample_histogram(
                ax,
                sample,
                bins=bins,
                range=(lo, hi),
                label=rf"$\lambda_{{\{name}}}$, {sample.size} draws",
            )
    pdf_min, pdf_max = law_min.pdf(grid), law_max.pdf(grid)
    if thresholds is not None:
        lower, upper = (_checks.scalar("thresholds", v) for v in thresholds)
        ax.fill_between(
            grid,
            pdf_min,
            where=grid <= lower,
            color=REJECT.light,
            lw=0,
            label=r"critical region ($\alpha/2$ each)",
        )
        ax.fill_between(grid, pdf_max, where=grid >= upper, color=REJECT.light, lw=0)
    ax.plot(grid, pdf_min, color=low.dark, lw=2, label=r"$\lambda_{\min}$ (exact law)")
    ax.plot(grid, pdf_max, color=high.dark, lw=2, label=r"$\lambda_{\max}$ (exact law)")
    ax.axvline(1.0, color="0.5", lw=1, ls=":")
    ax.set_xlabel(r"eigenvalue of $\hat\Pi$")
    ax.set_ylabel("density")
    legend_outside(ax)
    return ax


@styled
def plot_cdf_errors(x, errors, ax=None, xlabel="point at which the CDFs are compared"):
    """Curves of ``approximate CDF - exact CDF``, one per label.

    Parameters
    ----------
    x : mapping or array_like
        Common abscissa, or a mapping label -> abscissa per curve.
    errors : mapping
        Label -> array of errors.
    xlabel : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    if not isinstance(errors, dict) or not errors:
        raise ValueError("errors must be a non-empty mapping label -> array of CDF errors")
    ax = axes_or_new(ax)
    for index, (label, err) in enumerate(errors.items()):
        xs = x[label] if isinstance(x, dict) else x
        xs = _checks.array(f"x[{label!r}]", xs, min_size=2)
        err = _checks.array(f"errors[{label!r}]", err, min_size=2)
        _checks.same_length(f"x[{label!r}]", xs, f"errors[{label!r}]", err)
        ax.plot(xs, err, lw=1.5, color=pair(index).dark, label=label)
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("approximate CDF − exact CDF")
    legend_outside(ax)
    return ax


@styled
def plot_detection(K_values, probabilities, alpha=None, ax=None, title=None, n_runs=None):
    """Probability of detection against the number of steps ``K`` (Monte Carlo).

    Parameters
    ----------
    K_values : array_like
        Window lengths.
    probabilities : mapping
        Test name -> detection rates (same length as ``K_values``); the
        first test takes pair 0, the second pair 1, ...
    alpha : float, optional
        Nominal false-alarm rate, drawn as a dotted line.
    title : str, optional
    n_runs : int, optional
        Runs per point: draws 95 % binomial error bars.

    Returns
    -------
    matplotlib.axes.Axes
    """
    K_values = _checks.array("K_values", K_values, what="window lengths")
    if np.any(K_values <= 0):
        raise ValueError("K_values must be positive window lengths")
    alpha = _checks.probability("alpha", alpha, allow_none=True)
    n_runs = _checks.positive_int("n_runs", n_runs, allow_none=True)
    if not isinstance(probabilities, dict) or not probabilities:
        raise ValueError("probabilities must be a non-empty mapping test name -> rates")
    ax = axes_or_new(ax)
    for index, (label, p) in enumerate(probabilities.items()):
        p = _checks.array(f"probabilities[{label!r}]", p, what="detection rates")
        _checks.same_length(f"probabilities[{label!r}]", p, "K_values", K_values)
        colours = pair(index)
        ax.plot(K_values, p, color=colours.dark, ls=colours.ls, lw=1.0, alpha=0.7, zorder=2)
        yerr = None if n_runs is None else 1.96 * np.sqrt(p * (1 - p) / n_runs)
        monte_carlo_dots(ax, K_values, p, colours, label=label, yerr=yerr)
    if alpha is not None:
        ax.axhline(alpha, color="0.4", lw=1, ls=":", label=rf"$\alpha$ = {alpha:g}")
    ax.set_xscale("log")
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("$K$ (time steps in the window)")
    ax.set_ylabel("probability of detection")
    if title:
        ax.set_title(title)
    legend_outside(ax)
    return ax


@styled
def plot_consistency(times, averages, interval, ax=None, label=None, ylabel="average", color=None):
    """A sequence of averaged NIS/NEES values inside its two-sided interval (shaded).

    Points outside ``interval = (lower, upper)`` are marked.

    Parameters
    ----------
    times, averages : (N,) array_like
    interval : (float, float)
        The two-sided acceptance interval of the average.
    label, ylabel : str, optional
    color : int or str, optional
        Colour pair of this sequence.

    Returns
    -------
    matplotlib.axes.Axes
    """
    times = _checks.array("times", times, what="times")
    averages = _checks.array("averages", averages, what="averaged NIS/NEES values")
    _checks.same_length("times", times, "averages", averages)
    lower, upper = (_checks.scalar("interval", v) for v in interval)
    if not lower < upper:
        raise ValueError(f"interval must be (lower, upper) with lower < upper, got {interval}")
    ax = axes_or_new(ax)
    colours = pair(color if color is not None else 0)
    if not any(getattr(p, "_course_band", False) for p in ax.patches):
        band = ax.axhspan(lower, upper, color="0.9", lw=0, label="95 % interval", zorder=0)
        band._course_band = True
    ax.plot(times, averages, lw=1.2, color=colours.dark, label=label)
    outside = (averages < lower) | (averages > upper)
    # the marked points get one legend entry per axes, however many sequences are drawn
    _, labels = ax.get_legend_handles_labels()
    first = outside.any() and "outside the interval" not in labels
    marker_label = "outside the interval" if first else None
    ax.plot(
        times[outside],
        averages[outside],
        "o",
        color=REJECT.dark,
        ms=3,
        ls="none",
        label=marker_label,
    )
    ax.set_xlabel("time step")
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
def plot_whitened_scatter(z, ax=None, thresholds=None, truth=None, label="whitened innovations"):
    r"""Whitened innovations as a scatter, their NIS-matrix ellipse against the unit circle.

    Parameters
    ----------
    z : (K, 2) array_like
        Whitened innovations ``z_k = B_k^{-1} ε_k`` of two outputs.
    ax : matplotlib.axes.Axes, optional
    thresholds : (float, float), optional
        The matrix test's critical values ``(lower, upper)`` for the
        eigenvalues: the test accepts exactly when the ellipse lies inside
        the shaded ring between the circles of radius ``sqrt(lower)`` and
        ``sqrt(upper)``.
    truth : (2, 2) array_like, optional
        The true covariance of ``z`` (identity when the filter's model is
        right), drawn as a dashed ellipse.
    label : str

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.nis.nis_matrix : The matrix whose ellipse it draws.
    course.nis.nis_matrix_critical_values : The rings of the matrix test.

    Notes
    -----
    With the NIS matrix :math:`\hat\Pi = \frac1K \sum_k z_k z_k^{\mathsf T}` the
    ellipse is :math:`\{\hat\Pi^{1/2} u : \lVert u \rVert = 1\}`: its
    semi-axes are the square roots of the eigenvalues of :math:`\hat\Pi`. The
    time-averaged NIS,

    .. math::

        \frac1K \sum_k \lVert z_k \rVert^2 = \operatorname{tr}\hat\Pi,

    is the mean squared radius of the points: it sees only the ellipse's size,
    drawn as the round ellipse with the same trace (the dotted circle of radius
    :math:`\sqrt{\operatorname{tr}\hat\Pi / 2}`, which is the unit circle when
    :math:`\hat\Pi = I`); the NIS matrix sees its shape. The frame is set by
    the circles and ellipses, not by the farthest point, so that a single
    outlier cannot shrink the picture; the points left outside are counted in
    the legend.
    """
    z = _checks.array("z", z, ndim=2, what="whitened innovations (K x 2)")
    if z.shape[1] != 2:
        raise ValueError(f"z must have two columns (two outputs), got shape {z.shape}")
    ax = axes_or_new(ax)
    K = z.shape[0]
    Pi = z.T @ z / K
    lam, V = np.linalg.eigh(Pi)
    angle = np.linspace(0, 2 * np.pi, 361)
    circle = np.vstack([np.cos(angle), np.sin(angle)])
    ellipse = V @ (np.sqrt(np.clip(lam, 0, None))[:, None] * (V.T @ circle))
    nis_avg = float(np.trace(Pi))
    if thresholds is not None:
        lower, upper = (_checks.scalar("thresholds", v, positive=True) for v in thresholds)
        ring = np.concatenate([np.sqrt(upper) * circle, np.sqrt(lower) * circle[:, ::-1]], axis=1)
        ax.fill(
            *ring,
            color=pair(2).light,
            alpha=0.5,
            lw=0,
            label=rf"accepted: all eigenvalues in [{lower:.2f}, {upper:.2f}]",
        )
    extent = [1.0, float(np.sqrt(max(lam.max(), 0.0)))]
    if thresholds is not None:
        extent.append(float(np.sqrt(upper)))
    if truth is not None:
        T = _checks.array("truth", truth, ndim=2, what="covariance entries")
        if T.shape != (2, 2):
            raise ValueError(f"truth must be a 2 x 2 covariance, got shape {T.shape}")
        w, U = np.linalg.eigh((T + T.T) / 2)
        if np.any(w <= 0):
            raise ValueError("truth must be positive definite")
        extent.append(float(np.sqrt(w.max())))
    reach = 1.6 * max(extent)
    hidden = int(np.sum(np.any(np.abs(z) > reach, axis=1)))
    if hidden:
        label = f"{label} ({hidden} outside the frame)"
    ax.plot(z[:, 0], z[:, 1], "o", ms=3, color=pair("NF").dark, alpha=0.5, label=label)
    ax.plot(*circle, color="k", lw=1, label="unit circle: the model's promise")
    ax.plot(
        *(np.sqrt(nis_avg / 2) * circle),
        ":",
        color=pair(0).dark,
        lw=1.5,
        label=(
            rf"what the NIS sees: a circle of radius $\sqrt{{\bar\epsilon/2}}$ = "
            rf"{np.sqrt(nis_avg / 2):.2f} (NIS $\bar\epsilon$ = mean $|z|^2$ = {nis_avg:.2f})"
        ),
    )
    ax.plot(
        *ellipse,
        color=pair(1).dark,
        lw=2,
        label=rf"NIS matrix: $\lambda$ = {lam[0]:.2f}, {lam[1]:.2f}",
    )
    for k in range(2):
        tip = np.sqrt(max(lam[k], 0)) * V[:, k]
        ax.plot([-tip[0], tip[0]], [-tip[1], tip[1]], color=pair(1).dark, lw=0.8)
    if truth is not None:
        ax.plot(
            *(U @ (np.sqrt(w)[:, None] * (U.T @ circle))),
            ls="--",
            color=pair(3).dark,
            lw=1.2,
            label="true covariance of $z$",
        )
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-reach, reach)
    ax.set_aspect("equal")
    ax.set_xlabel("$z_1$ (whitened output 1)")
    ax.set_ylabel("$z_2$ (whitened output 2)")
    legend_outside(ax)
    return ax
