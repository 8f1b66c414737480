"""Figures for the NIS / NIS-matrix chapter.

Every function takes ``ax=None`` (a new figure is made when it is None) and
returns the axes it drew on.  Nothing here computes a statistic: the numbers
come from :mod:`course.nis`.
"""

from __future__ import annotations

import numpy as np

from course.plotting import axes_or_new

__all__ = [
    "plot_cdf_errors",
    "plot_consistency",
    "plot_detection",
    "plot_extreme_laws",
    "plot_sample_against_law",
]


def plot_sample_against_law(sample, law, ax=None, bins=60, label=None, law_label=None, grid=None):
    """Histogram of a Monte Carlo sample (as a density) with a law's pdf on top.

    Parameters
    ----------
    sample : array_like
        Draws.
    law : frozen distribution or sequence of them
        Anything with ``pdf``; several laws are drawn as several curves.
    bins : int
        Histogram bins.
    label, law_label : str or sequence of str, optional
        Legend texts for the histogram and the curve(s).
    grid : array_like, optional
        Where to evaluate the pdf (the sample's range by default).
    """
    ax = axes_or_new(ax)
    sample = np.asarray(sample, dtype=float)
    ax.hist(sample, bins=bins, density=True, alpha=0.35, color="C0", label=label)
    if grid is None:
        lo, hi = np.quantile(sample, [0.0005, 0.9995])
        pad = 0.05 * (hi - lo)
        grid = np.linspace(max(lo - pad, 0.0) if lo >= 0 else lo - pad, hi + pad, 400)
    laws = law if isinstance(law, (list, tuple)) else [law]
    names = law_label if isinstance(law_label, (list, tuple)) else [law_label] * len(laws)
    for index, (one, name) in enumerate(zip(laws, names)):
        ax.plot(grid, one.pdf(grid), color=f"C{index + 1}", lw=2, label=name)
    if label or law_label:
        ax.legend()
    return ax


def plot_extreme_laws(law_min, law_max, samples=None, ax=None, bins=80):
    """Densities of the smallest and largest eigenvalue, with optional MC histograms.

    Parameters
    ----------
    law_min, law_max : frozen distributions
        E.g. ``course.nis.extreme_eigenvalue(m, K, "min")`` and ``"max"``.
    samples : tuple of arrays, optional
        ``(lmin, lmax)`` Monte Carlo draws to show as histograms.
    """
    ax = axes_or_new(ax)
    lo = float(law_min.ppf(1e-4))
    hi = float(law_max.isf(1e-4))
    grid = np.linspace(lo, hi, 500)
    if samples is not None:
        for sample, color in zip(samples, ("C0", "C3")):
            ax.hist(sample, bins=bins, range=(lo, hi), density=True, alpha=0.3, color=color)
    ax.plot(grid, law_min.pdf(grid), color="C0", lw=2, label=r"$\lambda_{\min}$ (exact)")
    ax.plot(grid, law_max.pdf(grid), color="C3", lw=2, label=r"$\lambda_{\max}$ (exact)")
    ax.axvline(1.0, color="0.5", lw=1, ls=":")
    ax.set_xlabel(r"eigenvalue of $\Pi$")
    ax.set_ylabel("density")
    ax.legend()
    return ax


def plot_cdf_errors(x, errors, ax=None, xlabel="x"):
    """Curves of ``approximate CDF - exact CDF``, one per label.

    Parameters
    ----------
    x : mapping or array_like
        Common abscissa, or a mapping label -> abscissa per curve.
    errors : mapping
        Label -> array of errors.
    """
    ax = axes_or_new(ax)
    for label, err in errors.items():
        xs = x[label] if isinstance(x, dict) else x
        ax.plot(xs, err, lw=1.5, label=label)
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("approximate CDF - exact CDF")
    ax.legend()
    return ax


def plot_detection(K_values, probabilities, alpha=None, ax=None, title=None):
    """Probability of detection against the number of steps ``K``.

    Parameters
    ----------
    K_values : array_like
        Window lengths.
    probabilities : mapping
        Test name -> detection rates (same length as ``K_values``).
    alpha : float, optional
        Nominal false-alarm rate, drawn as a dotted line.
    """
    ax = axes_or_new(ax)
    markers = "osd^v"
    for index, (label, p) in enumerate(probabilities.items()):
        ax.plot(K_values, p, marker=markers[index % len(markers)], ms=4, lw=1.5, label=label)
    if alpha is not None:
        ax.axhline(alpha, color="0.5", lw=1, ls=":", label=rf"$\alpha$ = {alpha:g}")
    ax.set_xscale("log")
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("K (time steps in the window)")
    ax.set_ylabel(r"$p_{\mathrm{out}}$ (probability of detection)")
    if title:
        ax.set_title(title)
    ax.legend(fontsize="small")
    return ax


def plot_consistency(times, averages, interval, ax=None, label=None, ylabel="average"):
    """A sequence of averaged NIS/NEES values inside its two-sided interval.

    Points outside ``interval = (lower, upper)`` are marked.
    """
    ax = axes_or_new(ax)
    times = np.asarray(times)
    averages = np.asarray(averages, dtype=float)
    lower, upper = interval
    ax.plot(times, averages, lw=1.2, label=label)
    outside = (averages < lower) | (averages > upper)
    ax.plot(times[outside], averages[outside], "x", color="C3", ms=5)
    ax.axhline(lower, color="0.3", lw=1, ls="--")
    ax.axhline(upper, color="0.3", lw=1, ls="--")
    ax.set_xlabel("time step")
    ax.set_ylabel(ylabel)
    if label:
        ax.legend(fontsize="small")
    return ax
