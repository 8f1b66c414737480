"""Figures for the mismatched-filter chapter (notebook 06).

Every function takes ``ax=None`` (a new figure is made when it is None) and
returns the axes it drew on.  The numbers come from :mod:`course.mismatched`
and :mod:`course.quadform`; nothing here computes a statistic.
"""

from __future__ import annotations

import numpy as np

from course.plotting import axes_or_new

__all__ = [
    "plot_cross_covariance",
    "plot_imhof_integrands",
    "plot_law_against_sample",
    "plot_power_curves",
    "plot_residual_band",
]


def plot_residual_band(moments, residuals=None, output=0, ax=None, n_records=20, sigmas=2.0):
    """Predicted mean and ``mean +/- sigmas * sd`` band of one residual channel over time.

    Parameters
    ----------
    moments : ResidualMoments
        Predicted moments (e.g. from ``residual_moments``).
    residuals : (M, N, p) array_like, optional
        Simulated or measured records; the first ``n_records`` are drawn thin.
    output : int
        Which residual component to show.
    """
    ax = axes_or_new(ax)
    t = np.arange(moments.n_steps)
    m = moments.mean[:, output]
    sd = np.sqrt(moments.cov[:, output, output])
    if residuals is not None:
        r = np.asarray(residuals, dtype=float)
        r = r[..., None] if r.ndim == 2 else r
        for i in range(min(n_records, r.shape[0])):
            ax.plot(
                t,
                r[i, :, output],
                color="0.6",
                lw=0.6,
                alpha=0.6,
                label="records" if i == 0 else None,
            )
        ax.plot(t, r[:, :, output].mean(axis=0), color="C1", lw=1.5, label="cross-record mean")
    ax.fill_between(
        t,
        m - sigmas * sd,
        m + sigmas * sd,
        color="C0",
        alpha=0.2,
        label=f"predicted mean $\\pm$ {sigmas:g} sd",
    )
    ax.plot(t, m, color="C0", lw=2, label="predicted mean $m_t$")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("time t")
    ax.set_ylabel("residual")
    ax.legend(loc="best", fontsize="small")
    return ax


def plot_cross_covariance(moments, ax=None, output=(0, 0), correlation=True):
    """Image of ``C(j, k)`` (or the correlation coefficients) over all pairs of times.

    The colour scale is set by the off-diagonal entries.
    """
    ax = axes_or_new(ax)
    a, b = output
    C = moments.cross_cov[:, :, a, b]
    title = "C(j, k)"
    if correlation:
        sd = np.sqrt(moments.cov[:, a, a])
        sd_b = np.sqrt(moments.cov[:, b, b])
        C = C / np.outer(sd, sd_b)
        title = "correlation of $r_j$ and $r_k$"
    # the colour scale follows the off-diagonal entries: the diagonal (the
    # variances, or correlation one) would otherwise wash everything out
    off = C[~np.eye(C.shape[0], dtype=bool)]
    limit = np.max(np.abs(off)) if off.size and np.max(np.abs(off)) > 0 else np.max(np.abs(C))
    image = ax.imshow(C, cmap="RdBu_r", vmin=-limit, vmax=limit, origin="lower")
    title += " (diagonal off the scale)"
    ax.figure.colorbar(image, ax=ax, shrink=0.8)
    ax.set_xlabel("k")
    ax.set_ylabel("j")
    ax.set_title(title)
    return ax


def plot_law_against_sample(
    sample,
    law,
    ax=None,
    bins=50,
    critical=None,
    label="Monte Carlo",
    law_label="exact law (Imhof)",
    grid=None,
):
    """Histogram of Monte Carlo values of a statistic with its exact density.

    ``critical`` (a number or a ``(lower, upper)`` pair) is drawn as dashed
    vertical lines.
    """
    ax = axes_or_new(ax)
    sample = np.asarray(sample, dtype=float)
    heights, _, _ = ax.hist(
        sample, bins=bins, density=True, color="0.75", edgecolor="white", label=label
    )
    if grid is None:
        lo, hi = np.quantile(sample, [0.0005, 0.9995])
        grid = np.linspace(lo, hi, 300)
    ax.plot(grid, law.pdf(grid), color="C0", lw=2, label=law_label)
    # a density with an integrable pole (chi2 with one degree of freedom)
    # must not flatten the histogram
    ax.set_ylim(0, 1.25 * np.max(heights))
    if critical is not None:
        for value in np.atleast_1d(critical):
            ax.axvline(value, color="C3", ls="--", lw=1.2)
        ax.plot([], [], color="C3", ls="--", label="critical value(s)")
    ax.set_ylabel("density")
    ax.legend(loc="best", fontsize="small")
    return ax


def plot_imhof_integrands(u, real_axis, contour, ax=None):
    """Imhof's real-axis integrand next to the integrand on the deformed contour."""
    ax = axes_or_new(ax)
    ax.plot(u, real_axis, color="C1", lw=1, label="Imhof's integrand on the real axis")
    ax.plot(u, contour, color="C0", lw=2, label="integrand on the saddle-point hyperbola")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("u")
    ax.legend(loc="best", fontsize="small")
    return ax


def plot_power_curves(M_values, powers, alpha=None, ax=None):
    """Power against the number of records; ``powers`` maps a label to values."""
    ax = axes_or_new(ax)
    for label, values in powers.items():
        ax.plot(M_values, values, marker="o", ms=3, label=label)
    if alpha is not None:
        ax.axhline(alpha, color="k", ls=":", lw=1, label=f"level $\\alpha$ = {alpha:g}")
    ax.set_xscale("log")
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("number of records M")
    ax.set_ylabel("power")
    ax.legend(loc="best", fontsize="small")
    return ax
