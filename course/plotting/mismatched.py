"""Figures for the mismatched-filter chapter (notebook 06 and its appendix).

Every function takes ``ax=None`` (a new figure is made when it is None),
returns the axes it drew on and draws in the course style
(:mod:`course.plotting.style`): the mean, covariance and correlation tests
keep pairs 0, 1 and 2 in every figure.  The numbers come from
:mod:`course.mismatched` and :mod:`course.quadform`; nothing here computes
a statistic. The figures follow Baram (1980) and Imhof (1961), listed in full in the course
bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import numpy as np

from . import _checks, axes_or_new
from .style import (
    LAW,
    legend_outside,
    monte_carlo_dots,
    pair,
    sample_histogram,
    shade_tail,
    styled,
    theory_grid,
    threshold_line,
)

__all__ = [
    "plot_cross_covariance",
    "plot_cross_record_section",
    "plot_imhof_integrands",
    "plot_law_against_sample",
    "plot_power_curves",
    "plot_records_matrix",
    "plot_residual_band",
]

_TESTS = {"mean test": 0, "covariance test": 1, "correlation test": 2}


def _records(residuals, output=0):
    r = _checks.array("residuals", residuals, ndim=(2, 3), what="residuals (records x time)")
    r = r[..., None] if r.ndim == 2 else r
    if not 0 <= output < r.shape[2]:
        raise ValueError(f"output must be an index 0..{r.shape[2] - 1}, got {output}")
    return r[:, :, output]


@styled
def plot_residual_band(moments, residuals=None, output=0, ax=None, n_records=20, sigmas=2.0):
    """Predicted mean and ``mean ± sigmas · sd`` band of one residual channel over time.

    Parameters
    ----------
    moments : ResidualMoments
        Predicted moments (e.g. from ``residual_moments``).
    residuals : (M, N) or (M, N, p) array_like, optional
        Simulated or measured records; the first ``n_records`` are drawn thin.
    output : int
        Which residual component to show.
    n_records : int
        How many records to draw.
    sigmas : float
        Half width of the band in standard deviations.

    Returns
    -------
    matplotlib.axes.Axes
    """
    n_records = _checks.positive_int("n_records", n_records)
    sigmas = _checks.scalar("sigmas", sigmas, positive=True)
    ax = axes_or_new(ax)
    t = np.arange(moments.n_steps)
    m = moments.mean[:, output]
    sd = np.sqrt(moments.cov[:, output, output])
    predicted, observed = pair(0), pair(1)
    if residuals is not None:
        r = _records(residuals, output)
        if r.shape[1] != t.size:
            raise ValueError(f"residuals have {r.shape[1]} time steps, the moments {t.size}")
        for i in range(min(n_records, r.shape[0])):
            ax.plot(t, r[i], color="0.7", lw=0.6, label="records" if i == 0 else None)
        ax.plot(
            t,
            r.mean(axis=0),
            color=observed.dark,
            lw=1.5,
            label=f"cross-record mean of {r.shape[0]} records",
        )
    ax.fill_between(
        t,
        m - sigmas * sd,
        m + sigmas * sd,
        color=predicted.light,
        alpha=0.5,
        lw=0,
        label=rf"predicted $m_t \pm$ {sigmas:g} sd",
    )
    ax.plot(t, m, color=predicted.dark, lw=2, label="predicted mean $m_t$")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("time step $t$")
    ax.set_ylabel("residual $r_t$")
    legend_outside(ax)
    return ax


@styled
def plot_records_matrix(residuals, j=None, output=0, ax=None, max_records=60):
    r"""Many records at once: a records × time image, with one cross-record section marked.

    Parameters
    ----------
    residuals : (M, N) or (M, N, p) array_like
        Residuals of M records over N time steps.
    j : int, optional
        The time of the cross-record section to outline.
    output : int
        Which residual component to show.
    max_records : int
        Show at most this many records (rows).

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    plot_cross_record_section : One column of the matrix.

    Notes
    -----
    Each row is one record (one repetition of the experiment); each column one
    time. Along a row the residuals of a mismatched filter are correlated; down
    a column (a cross-record section :math:`\varphi_j`) they are independent
    and identically distributed, because the records are independent
    repetitions.
    """
    from matplotlib.patches import Rectangle

    r = _records(residuals, output)
    max_records = _checks.positive_int("max_records", max_records)
    r = r[:max_records]
    M, N = r.shape
    ax = axes_or_new(ax)
    limit = np.max(np.abs(r))
    image = ax.imshow(
        r,
        aspect="auto",
        cmap="RdBu_r",
        vmin=-limit,
        vmax=limit,
        origin="upper",
        interpolation="nearest",
    )
    ax.figure.colorbar(image, ax=ax, shrink=0.85, label="residual $r_{i,t}$")
    if j is not None:
        if not isinstance(j, (int, np.integer)) or isinstance(j, bool) or not 0 <= j < N:
            raise ValueError(f"j must be a time index 0..{N - 1}, got {j!r}")
        ax.add_patch(Rectangle((j - 0.5, -0.5), 1, M, fill=False, ec="k", lw=2))
        ax.text(
            j + 0.8 if j < 0.7 * N else j - 0.8,
            0.93 * M,
            rf"cross-record section $\varphi_{{{j}}}$",
            ha="left" if j < 0.7 * N else "right",
            va="center",
            fontsize="small",
            bbox=dict(boxstyle="round", fc="white", ec="k", lw=0.8),
        )
    ax.grid(False)
    ax.set_xlabel("time step $t$ (along a record: correlated)")
    ax.set_ylabel("record $i$ (across records: independent)")
    return ax


@styled
def plot_cross_record_section(residuals, j, moments=None, output=0, ax=None, bins=20):
    """The residuals of one cross-record section against their predicted normal law.

    Parameters
    ----------
    residuals : (M, N) or (M, N, p) array_like
        Residuals of M records.
    j : int
        The time of the section.
    moments : ResidualMoments, optional
        Predicted moments: draws the density ``N(m_j, P_j)``.
    output : int
    bins : int

    Returns
    -------
    matplotlib.axes.Axes
    """
    from scipy import stats

    r = _records(residuals, output)
    bins = _checks.positive_int("bins", bins)
    if not isinstance(j, (int, np.integer)) or isinstance(j, bool) or not 0 <= j < r.shape[1]:
        raise ValueError(f"j must be a time index 0..{r.shape[1] - 1}, got {j!r}")
    section = r[:, j]
    ax = axes_or_new(ax)
    sample_histogram(ax, section, bins=bins, label=rf"$\varphi_{{{j}}}$: {section.size} records")
    if moments is not None:
        mean = float(moments.mean[j, output])
        sd = float(np.sqrt(moments.cov[j, output, output]))
        grid = theory_grid(mean - 4 * sd, mean + 4 * sd)
        ax.plot(
            grid,
            stats.norm.pdf(grid, mean, sd),
            color=LAW,
            lw=2,
            label=rf"predicted $N(m_{{{j}}}, P_{{{j}}})$",
        )
        ax.axvline(mean, color=pair(0).dark, ls=":", lw=1)
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set_xlabel(f"residual at $t$ = {j}")
    ax.set_ylabel("density")
    legend_outside(ax)
    return ax


@styled
def plot_cross_covariance(moments, ax=None, output=(0, 0), correlation=True, max_lag=None):
    """Image of ``C(j, k)`` (or the correlation coefficients) over all pairs of times.

    The diagonal (the variances, or correlation one) is left out of the
    colour scale, drawn in neutral grey (white would read as "no
    correlation"), so that the scale shows the off-diagonal structure.

    Parameters
    ----------
    moments : ResidualMoments
    output : (int, int)
        The residual components ``(a, b)`` of ``C(j, k)[a, b]``.
    correlation : bool
        Show correlation coefficients instead of covariances.
    max_lag : int, optional
        Leave out (grey) the entries with ``|j - k| > max_lag``.

    Returns
    -------
    matplotlib.axes.Axes
    """
    correlation = _checks.flag("correlation", correlation)
    ax = axes_or_new(ax)
    a, b = output
    C = np.array(moments.cross_cov[:, :, a, b], dtype=float)
    label = "$C(j, k)$"
    if correlation:
        sd = np.sqrt(moments.cov[:, a, a])
        sd_b = np.sqrt(moments.cov[:, b, b])
        C = C / np.outer(sd, sd_b)
        label = r"correlation of $r_j$ and $r_k$"
    C[np.eye(C.shape[0], dtype=bool)] = np.nan
    if max_lag is not None:
        lag = np.abs(np.subtract.outer(np.arange(C.shape[0]), np.arange(C.shape[0])))
        C[lag > max_lag] = np.nan
    limit = np.nanmax(np.abs(C)) if np.any(np.isfinite(C)) else 1.0
    import matplotlib

    # the diagonal (a correlation of one) is drawn grey: white would read as zero correlation
    cmap = matplotlib.colormaps["RdBu_r"].with_extremes(bad="0.55")
    image = ax.imshow(
        C, cmap=cmap, vmin=-limit, vmax=limit, origin="lower", interpolation="nearest"
    )
    ax.figure.colorbar(image, ax=ax, shrink=0.85, label=label + " (diagonal grey)")
    ax.grid(False)
    ax.set_xlabel("time $k$")
    ax.set_ylabel("time $j$")
    return ax


@styled
def plot_law_against_sample(
    sample,
    law,
    ax=None,
    bins=50,
    critical=None,
    label="Monte Carlo",
    law_label="exact law (Imhof)",
    grid=None,
    xlabel="statistic",
):
    """Histogram of Monte Carlo values of a statistic with its exact density.

    Parameters
    ----------
    sample : (n,) array_like
        Monte Carlo values of the statistic.
    law : frozen distribution
        Anything with ``pdf`` (and ``cdf``).
    bins : int
    critical : float or (float, float), optional
        Critical value(s); the tails beyond them are shaded.
    label, law_label, xlabel : str
    grid : array_like, optional
        Where to evaluate the density (a fine grid over the sample by default).

    Returns
    -------
    matplotlib.axes.Axes
    """
    sample = _checks.array("sample", sample, what="Monte Carlo values")
    bins = _checks.positive_int("bins", bins)
    if not hasattr(law, "pdf"):
        raise ValueError("law must be a distribution with a pdf method")
    ax = axes_or_new(ax)
    heights, _, _ = sample_histogram(ax, sample, bins=bins, label=label)
    if grid is None:
        lo, hi = np.quantile(sample, [0.0005, 0.9995])
        grid = theory_grid(lo, hi, 400)
    else:
        grid = _checks.array("grid", grid, min_size=2, what="grid values")
    density = law.pdf(grid)
    if critical is not None:
        values = _checks.array("critical", critical, ndim=(0, 1), what="critical values").ravel()
        lower = values[0] if values.size == 2 else None
        upper = values[-1]
        shade_tail(ax, grid, density, lower=lower, upper=upper, label="critical region")
        for value in values:
            threshold_line(ax, value)
    ax.plot(grid, density, color=LAW, lw=2, label=law_label)
    # a density with an integrable pole (chi2 with one degree of freedom)
    # must not flatten the histogram
    ax.set_ylim(0, 1.25 * np.max(heights))
    ax.set_xlabel(xlabel)
    ax.set_ylabel("density")
    legend_outside(ax)
    return ax


@styled
def plot_imhof_integrands(u, real_axis, contour, ax=None, log=False):
    """Imhof's real-axis integrand next to the integrand on the deformed contour.

    Parameters
    ----------
    u : (n,) array_like
        Integration variable.
    real_axis, contour : (n,) array_like
        The two integrands at ``u``.
    log : bool
        Draw their absolute values on logarithmic axes, which shows how
        fast each decays (a slow power law against a double exponential);
        exact zeros are left out.

    Returns
    -------
    matplotlib.axes.Axes
    """
    u = _checks.array("u", u, min_size=2, what="integration points")
    real_axis = _checks.array("real_axis", real_axis, min_size=2, what="integrand values")
    contour = _checks.array("contour", contour, min_size=2, what="integrand values")
    _checks.same_length("u", u, "real_axis", real_axis)
    _checks.same_length("u", u, "contour", contour)
    log = _checks.flag("log", log)
    ax = axes_or_new(ax)
    real_style, contour_style = pair(1), pair(0)
    curves = (
        (real_axis, real_style, 1, "Imhof's integrand on the real axis"),
        (contour, contour_style, 2, "integrand on the saddle-point hyperbola"),
    )
    for values, colours, width, label in curves:
        if log:
            shown = np.abs(values)
            keep = shown > 0
            ax.plot(u[keep], shown[keep], color=colours.dark, ls=colours.ls, lw=width, label=label)
        else:
            ax.plot(u, values, color=colours.dark, ls=colours.ls, lw=width, label=label)
    ax.set_xlabel("integration variable $u$")
    if log:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel(r"|integrand| at $u$ (log scale)")
    else:
        ax.axhline(0.0, color="k", lw=0.5)
        # one axis for two different integrands: name the quantity, and Imhof's form
        ax.set_ylabel(r"integrand at $u$ (Imhof: $\sin\theta(u)\,/\,(u\,\rho(u))$)")
    legend_outside(ax, where="below")
    return ax


@styled
def plot_power_curves(M_values, powers, alpha=None, ax=None, simulated=None, n_experiments=None):
    """Power against the number of records; ``powers`` maps a test name to values.

    Parameters
    ----------
    M_values : array_like
        Numbers of records.
    powers : mapping
        Test name -> exact power at each ``M`` ("mean test", "covariance
        test" and "correlation test" keep their colours).
    alpha : float, optional
        Level of the tests, drawn dotted.
    simulated : mapping, optional
        Test name -> ``(M, rate)`` pairs of Monte Carlo checks, drawn as dots.
    n_experiments : int, optional
        Experiments per Monte Carlo point: draws 95 % binomial error bars.

    Returns
    -------
    matplotlib.axes.Axes
    """
    M_values = _checks.array("M_values", M_values, what="numbers of records")
    alpha = _checks.probability("alpha", alpha, allow_none=True)
    if not isinstance(powers, dict) or not powers:
        raise ValueError("powers must be a non-empty mapping test name -> power values")
    ax = axes_or_new(ax)
    for index, (label, given) in enumerate(powers.items()):
        exact = _checks.array(f"powers[{label!r}]", given, what="power values")
        _checks.same_length(f"powers[{label!r}]", exact, "M_values", M_values)
        colours = pair(_TESTS.get(label, index))
        ax.plot(
            M_values,
            exact,
            marker=colours.marker,
            ls=colours.ls,
            ms=4,
            mfc="none",
            color=colours.dark,
            label=f"{label} (exact)",
        )
    for index, (label, points) in enumerate((simulated or {}).items()):
        Ms, given_rates = zip(*points)
        rates = _checks.array(f"simulated[{label!r}]", given_rates, what="rejection rates")
        yerr = None
        if n_experiments is not None:
            yerr = 1.96 * np.sqrt(rates * (1 - rates) / n_experiments)
        monte_carlo_dots(
            ax,
            np.asarray(Ms, float),
            rates,
            pair(_TESTS.get(label, index)),
            label=f"{label} (Monte Carlo)",
            yerr=yerr,
        )
    if alpha is not None:
        ax.axhline(alpha, color="0.4", ls=":", lw=1, label=rf"level $\alpha$ = {alpha:g}")
    ax.set_xscale("log")
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("number of records $M$")
    ax.set_ylabel("power")
    legend_outside(ax)
    return ax
