"""Figures for the test-quantity notebooks (course.diagnosis, notebooks 02 and 03).

Every function takes ``ax=None`` (a new figure when None), returns the axes
it drew on and draws in the course style (:mod:`course.plotting.style`):
fault modes keep their colour pair (``pair("F2")``) in every figure.
Matplotlib is imported lazily, inside the functions. The figures follow the LiU lecture on
test quantities (full reference in the course bibliography, :doc:`/docs/bibliography`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from . import _checks, _mark_alarms, axes_or_new
from .style import (
    LAW,
    REJECT,
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
    "plot_criterion",
    "plot_decision_structure",
    "plot_density",
    "plot_isolation",
    "plot_likelihood",
    "plot_null_histogram",
    "plot_power_curves",
    "plot_recursive_estimates",
    "plot_residual_geometry",
    "plot_windowed_statistic",
]


def _colour(key, index):
    """The pair of ``key`` (a mode name or int), else the index-th pair."""
    if key is None:
        return pair(index)
    return pair(key)


@styled
def plot_residual_geometry(U1, U2, fault: float, ax=None):
    r"""The lecture's geometric picture of ``T = min over theta1 ||(1 - theta1) U1 - f U2||^2``.

    Parameters
    ----------
    U1, U2 : array_like, shape (N,)
        The signals of the decoupled parameter and of the faulty one.
    fault : float
        ``f = 1 - theta2``, the size of the fault in theta2.
    ax : matplotlib axes, optional

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.diagnosis.linear_decision_structure : Which faults a test sees.

    Notes
    -----
    Everything happens in the plane spanned by :math:`U_1` and :math:`U_2`,
    drawn in an orthonormal basis of it: :math:`e_1` along :math:`U_1`,
    :math:`e_2` the part of :math:`U_2` orthogonal to :math:`U_1`.  The free
    :math:`\theta_1` slides along the line through :math:`U_1`; the best it can
    do is the orthogonal projection of :math:`f U_2`, and :math:`\sqrt T` is the
    length of the perpendicular,

    .. math::

        T = \min_{\theta_1} \lVert (1 - \theta_1) U_1 - (1 - \theta_2) U_2 \rVert^2 .

    When :math:`U_2` is parallel to :math:`U_1` the perpendicular vanishes: the
    fault is invisible (the LiU lecture on test quantities, the geometric
    slide; full reference in the course bibliography,
    :doc:`/docs/bibliography`).
    """
    u1 = _checks.array("U1", U1, what="signal samples")
    u2 = _checks.array("U2", U2, what="signal samples")
    _checks.same_length("U1", u1, "U2", u2)
    fault = _checks.scalar("fault", fault)
    n1 = float(np.linalg.norm(u1))
    if n1 == 0:
        raise ValueError("U1 is zero: the decoupled parameter has no signal to slide along")
    ax = axes_or_new(ax)
    e1 = u1 / n1
    a = fault * u2
    along = float(e1 @ a)
    perp = float(np.linalg.norm(a - along * e1))
    ortho = perp > 1e-12 * max(float(np.linalg.norm(a)), 1.0)
    reach = max(abs(along), n1, perp, 1.0) * 1.25
    free, faulty, best = pair(0), pair("F2"), pair(2)
    ax.plot(
        [-reach, reach], [0, 0], color=free.light, lw=3, label=r"span$(U_1)$: all $(1-\theta_1)U_1$"
    )

    def arrow(tip, colour):
        ax.annotate(
            "",
            xy=tip,
            xytext=(0, 0),
            arrowprops=dict(arrowstyle="-|>", lw=2, color=colour),
            annotation_clip=False,
        )

    arrow((n1, 0), free.dark)
    ax.text(n1, -0.08 * reach, r"$U_1$", color=free.dark, ha="center", va="top")
    arrow((along, perp), faulty.dark)
    ax.text(
        along,
        perp + 0.04 * reach,
        r"$(1-\theta_2)U_2$",
        color=faulty.dark,
        ha="center",
        va="bottom",
    )
    ax.plot([along], [0], "o", color=best.dark, label=r"best $(1-\hat\theta_1)U_1$", zorder=4)
    if ortho:
        ax.plot(
            [along, along],
            [0, perp],
            color=REJECT.dark,
            lw=2,
            ls="--",
            label=rf"$\sqrt{{T_1}}$ = {perp:.3g}: F2 seen",
        )
    else:
        ax.plot(
            [], [], color=REJECT.dark, lw=2, ls="--", label=r"$\sqrt{T_1}$ = 0: $U_2 \parallel U_1$"
        )
    ax.set_aspect("equal")
    margin = 0.15 * reach
    ax.set_xlim(min(0.0, along) - margin, max(n1, along) + margin)
    ax.set_ylim(-0.25 * reach, max(perp, 0.3 * reach) * 1.3)
    ax.set_xlabel(r"coordinate along $U_1$")
    ax.set_ylabel(r"coordinate orthogonal to $U_1$")
    legend_outside(ax, where="below")
    return ax


@styled
def plot_decision_structure(structure, alarms=None, ax=None, title=None):
    """A decision structure as a coloured grid, with an alarm pattern and its diagnoses.

    Parameters
    ----------
    structure : course.diagnosis.DecisionStructure
        Tests x modes, 0 or X.
    alarms : sequence of bool, mapping or sequence of test names, optional
        Which tests alarmed (as for :func:`course.diagnosis.diagnoses`).
        Alarmed rows are marked, the modes each alarm rules out (its 0
        cells) are struck out, and a last row shows the diagnoses.
    ax : matplotlib.axes.Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.diagnosis.diagnoses : The diagnoses of an alarm pattern.

    Notes
    -----
    An X cell (coloured in the mode's colour) says the test *may* alarm in
    that mode; a 0 cell that it must stay silent. An alarm rejects the
    test's null hypothesis, so it rules out every mode with a 0 in its row;
    under a single fault the diagnoses are the modes no alarm rules out.
    """
    from matplotlib.patches import Rectangle

    from ..diagnosis import diagnoses

    tests, modes = list(structure.tests), list(structure.modes)
    S = np.asarray(structure.sensitivity, dtype=bool)
    alarmed = None
    if alarms is not None:
        if isinstance(alarms, Mapping):
            unknown = set(alarms) - set(tests)
            if unknown:
                raise ValueError(f"alarms names unknown tests {sorted(unknown)}; tests are {tests}")
            alarmed = np.array([bool(alarms.get(t, False)) for t in tests])
        else:
            seq = list(alarms)
            if seq and all(isinstance(a, str) for a in seq):
                unknown = set(seq) - set(tests)
                if unknown:
                    raise ValueError(
                        f"alarms names unknown tests {sorted(unknown)}; tests are {tests}"
                    )
                alarmed = np.array([t in seq for t in tests])
            else:
                if len(seq) != len(tests):
                    raise ValueError(
                        f"alarms must have one entry per test ({len(tests)}), got {len(seq)}"
                    )
                alarmed = np.array([bool(getattr(a, "reject", a)) for a in seq])
        consistent = set(diagnoses(structure, list(alarmed)))
    ax = axes_or_new(ax)
    n_rows = len(tests) + (1 if alarmed is not None else 0)
    for i in range(len(tests)):
        for j, mode in enumerate(modes):
            colours = pair(mode) if mode == "NF" or mode[:1] == "F" else pair(j)
            fill = colours.light if S[i, j] else "white"
            ax.add_patch(Rectangle((j, i), 1, 1, fc=fill, ec="0.6", lw=1))
            ax.text(j + 0.5, i + 0.5, "X" if S[i, j] else "0", ha="center", va="center")
            if alarmed is not None and alarmed[i] and not S[i, j]:
                ax.plot([j + 0.15, j + 0.85], [i + 0.15, i + 0.85], color=REJECT.dark, lw=1.5)
                ax.plot([j + 0.15, j + 0.85], [i + 0.85, i + 0.15], color=REJECT.dark, lw=1.5)
        if alarmed is not None:
            ax.text(
                len(modes) + 0.15,
                i + 0.5,
                "alarm" if alarmed[i] else "silent",
                color=REJECT.dark if alarmed[i] else "0.4",
                fontweight="bold" if alarmed[i] else "normal",
                va="center",
            )
    if alarmed is not None:
        i = len(tests)
        for j, mode in enumerate(modes):
            ok = mode in consistent
            # a surviving mode keeps its own colour, as in its column above
            colours = pair(mode) if mode == "NF" or mode[:1] == "F" else pair(j)
            ax.add_patch(
                Rectangle(
                    (j, i + 0.1),
                    1,
                    0.9,
                    fc=colours.light if ok else "0.92",
                    ec=colours.dark if ok else "0.6",
                    lw=1.5 if ok else 1,
                )
            )
            ax.text(j + 0.5, i + 0.55, "✓" if ok else "–", ha="center", va="center")
    ax.set_xlim(0, len(modes) + (1.3 if alarmed is not None else 0))
    ax.set_ylim(n_rows + 0.1, 0)
    ax.set_xticks(np.arange(len(modes)) + 0.5, modes)
    ax.xaxis.tick_top()
    labels = tests + (["diagnoses"] if alarmed is not None else [])
    ax.set_yticks(np.arange(n_rows) + 0.5, labels)
    ax.tick_params(length=0)
    ax.grid(False)
    for side in ax.spines.values():
        side.set_visible(False)
    ax.set_aspect("equal")
    if title:
        ax.set_title(title)
    return ax


@styled
def plot_density(theta: float, sigma: float = 1.0, z_observed=None, ax=None, z=None):
    """The density ``f(z | theta)`` of ``N(theta, sigma^2)`` as a function of ``z``.

    An observed value is marked on the curve.

    Parameters
    ----------
    theta, sigma : float
        Mean and standard deviation.
    z_observed : float or array_like, optional
        Observations to mark.
    ax : matplotlib.axes.Axes, optional
    z : array_like, optional
        Grid of ``z`` values (``theta ± 4 sigma`` by default).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from scipy import stats

    theta = _checks.scalar("theta", theta)
    sigma = _checks.scalar("sigma", sigma, positive=True)
    if z_observed is not None:
        z_observed = _checks.array("z_observed", z_observed, ndim=(0, 1), what="observations")
    ax = axes_or_new(ax)
    if z is None:
        z = theory_grid(theta - 4 * sigma, theta + 4 * sigma)
    else:
        z = _checks.array("z", z, min_size=2, what="grid values")
    ax.plot(
        z,
        stats.norm.pdf(z, theta, sigma),
        color=pair(0).dark,
        label=rf"$f(z\,|\,\theta={theta:g})$",
    )
    if z_observed is not None:
        for k, zo in enumerate(np.atleast_1d(z_observed)):
            height = stats.norm.pdf(zo, theta, sigma)
            ax.plot([zo, zo], [0, height], color=REJECT.dark, ls=":")
            ax.plot(
                [zo], [height], "o", color=REJECT.dark, label="observed $z$" if k == 0 else None
            )
    ax.set_xlabel("$z$")
    ax.set_ylabel(r"density $f(z\,|\,\theta)$")
    ax.set_title(r"density: a function of $z$ for fixed $\theta$")
    legend_outside(ax, where="below")
    return ax


@styled
def plot_likelihood(z, sigma: float = 1.0, theta=None, ax=None, show_factors: bool = True):
    r"""The likelihood ``L(theta | z)`` of independent ``N(theta, sigma^2)`` observations.

    With several observations and ``show_factors``, each factor
    ``f(z_i | theta)`` is drawn dashed; the maximum is marked.

    Parameters
    ----------
    z : float or array_like
        Observations.
    sigma : float
    theta : array_like, optional
        Grid of parameter values.
    ax : matplotlib.axes.Axes, optional
    show_factors : bool

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.diagnosis.normal_likelihood : The likelihood it draws.

    Notes
    -----
    :math:`L(\theta \mid z) = \prod_i f(z_i \mid \theta)`, maximal at the
    sample mean (the lecture's normal-likelihood examples: :math:`z = 2`, and
    :math:`z = (3, 5)` with the maximum at :math:`\theta = 4`).
    """
    from scipy import stats

    z = _checks.array("z", z, ndim=(0, 1), what="observations").ravel()
    sigma = _checks.scalar("sigma", sigma, positive=True)
    show_factors = _checks.flag("show_factors", show_factors)
    ax = axes_or_new(ax)
    if theta is None:
        theta = theory_grid(z.min() - 4 * sigma, z.max() + 4 * sigma)
    theta = _checks.array("theta", theta, min_size=2, what="parameter values")
    factors = stats.norm.pdf(z[:, None], theta[None, :], sigma)
    like = np.prod(factors, axis=0)
    shown = f"{z[0]:g}" if z.size == 1 else "(" + ", ".join(f"{v:g}" for v in z) + ")"
    ax.plot(theta, like, color=pair(0).dark, lw=2, label=rf"$L(\theta\,|\,z = {shown})$")
    if show_factors and z.size > 1:
        for i, zi in enumerate(z):
            ax.plot(
                theta,
                factors[i],
                ls="--",
                lw=1,
                color=pair(i + 1).dark,
                label=rf"$f(z_{i + 1} = {zi:g}\,|\,\theta)$",
            )
    mle = float(z.mean())
    peak = float(np.prod(stats.norm.pdf(z, mle, sigma)))
    ax.axvline(mle, color=REJECT.dark, ls=":", lw=1)
    ax.plot([mle], [peak], "o", color=REJECT.dark, label=rf"maximum at $\theta$ = {mle:g}")
    ax.set_xlabel(r"$\theta$")
    ax.set_ylabel(r"likelihood $L(\theta\,|\,z)$")
    ax.set_title(r"likelihood: a function of $\theta$ for the observed $z$")
    legend_outside(ax, where="below")
    return ax


@styled
def plot_criterion(
    theta, values, ax=None, minimiser=None, label: str = r"$V(\theta_1)$", xlabel=r"$\theta_1$"
):
    """A 1-D criterion such as ``V(theta1) = sum (y - theta1 u1 - u2 - u3)^2``.

    Parameters
    ----------
    theta, values : array_like
        Grid and criterion values.
    ax : matplotlib.axes.Axes, optional
    minimiser : float, optional
        Marked with a vertical line.
    label, xlabel : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    theta = _checks.array("theta", theta, min_size=2, what="parameter values")
    values = _checks.array("values", values, min_size=2, what="criterion values")
    _checks.same_length("theta", theta, "values", values)
    minimiser = _checks.scalar("minimiser", minimiser, allow_none=True)
    ax = axes_or_new(ax)
    ax.plot(theta, values, color=pair(0).dark, label=label)
    if minimiser is not None:
        ax.axvline(minimiser, color=REJECT.dark, ls=":", label=rf"minimiser {minimiser:.4g}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("criterion")
    legend_outside(ax)
    return ax


@styled
def plot_null_histogram(
    samples,
    null,
    critical_value: float,
    ax=None,
    bins: int = 50,
    label: str = "simulated under H0",
    xlabel: str = "test quantity",
    null_label: str = "null density",
):
    """Histogram of a simulated test quantity with its null density; the α tail is shaded.

    Parameters
    ----------
    samples : (n,) array_like
        Simulated test quantities.
    null : frozen distribution
        Anything with a ``pdf`` method (the ``null`` of a ``TestResult``).
    critical_value : float
        The threshold; the tail beyond it is shaded.
    ax : matplotlib.axes.Axes, optional
    bins : int
    label, xlabel, null_label : str
        Legend text of the histogram, axis label and legend text of the density.

    Returns
    -------
    matplotlib.axes.Axes
    """
    samples = _checks.array("samples", samples, what="simulated test quantities")
    critical_value = _checks.scalar("critical_value", critical_value)
    bins = _checks.positive_int("bins", bins)
    if not hasattr(null, "pdf"):
        raise ValueError("null must be a distribution with a pdf method (e.g. scipy.stats.chi2(3))")
    ax = axes_or_new(ax)
    hi = max(np.quantile(samples, 0.999), critical_value * 1.1)
    lo = min(samples.min(), 0.0)
    sample_histogram(ax, samples, bins=bins, range=(lo, hi), label=label)
    grid = theory_grid(lo, hi)
    density = null.pdf(grid)
    shade_tail(ax, grid, density, upper=critical_value, label="critical region")
    ax.plot(grid, density, color=LAW, lw=2, label=null_label)
    threshold_line(ax, critical_value, label=f"threshold {critical_value:.4g}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("density")
    legend_outside(ax)
    return ax


@styled
def plot_power_curves(
    sizes,
    theory: Mapping[str, Sequence[float]],
    simulated: Mapping[str, Sequence[float]] | None = None,
    alpha: float | None = None,
    ax=None,
    xlabel: str = "fault size",
    theory_sizes=None,
    colors: Mapping[str, object] | None = None,
    n_records: int | None = None,
    linestyles: Mapping[str, str] | None = None,
):
    """Alarm probability against fault size: theory as lines, Monte Carlo as dots.

    Parameters
    ----------
    sizes : array_like
        Fault sizes of the Monte Carlo points (and of ``theory`` when
        ``theory_sizes`` is not given).
    theory : mapping of str to sequence of float
        Power curves, one per label.
    simulated : mapping of str to sequence of float, optional
        Monte Carlo rates at ``sizes``, matched to ``theory`` by label.
    alpha : float, optional
        Drawn as a horizontal line.
    ax : matplotlib.axes.Axes, optional
    xlabel : str
    theory_sizes : array_like, optional
        The fine grid (at least 200 points) on which ``theory`` was evaluated.
    colors : mapping of str to int or str, optional
        Colour pair of each label (a fault name such as ``"F2"`` keeps its
        colour across the course); by order otherwise.
    n_records : int, optional
        Records per Monte Carlo point: draws 95 % binomial error bars.
    linestyles : mapping of str to str, optional
        Line style of each label: two tests against one fault share the
        fault's colour and differ by line style.

    Returns
    -------
    matplotlib.axes.Axes
    """
    sizes = _checks.array("sizes", sizes, what="fault sizes")
    xs = sizes if theory_sizes is None else _checks.array("theory_sizes", theory_sizes, min_size=2)
    alpha = _checks.probability("alpha", alpha, allow_none=True)
    n_records = _checks.positive_int("n_records", n_records, allow_none=True)
    if not isinstance(theory, Mapping) or not theory:
        raise ValueError("theory must be a non-empty mapping label -> power values")
    ax = axes_or_new(ax)
    colors = dict(colors or {})
    for i, (label, given) in enumerate(theory.items()):
        curve = _checks.array(f"theory[{label!r}]", given, what="probabilities")
        if curve.size != xs.size:
            raise ValueError(
                f"theory[{label!r}] has {curve.size} values for {xs.size} sizes"
                + ("" if theory_sizes is not None else " (pass theory_sizes for a fine grid)")
            )
        ax.plot(
            xs,
            curve,
            color=_colour(colors.get(label), i).dark,
            ls=(linestyles or {}).get(label, _colour(colors.get(label), i).ls),
            label=f"{label} (theory)",
        )
    if simulated:
        keys = list(theory)
        for label, given in simulated.items():
            rates = _checks.array(f"simulated[{label!r}]", given, what="alarm rates")
            _checks.same_length(f"simulated[{label!r}]", rates, "sizes", sizes)
            i = keys.index(label) if label in keys else len(keys)
            yerr = None
            if n_records is not None:
                yerr = 1.96 * np.sqrt(np.clip(rates * (1 - rates), 0, None) / n_records)
            monte_carlo_dots(
                ax,
                sizes,
                rates,
                _colour(colors.get(label), i),
                label=f"{label} (Monte Carlo)",
                yerr=yerr,
            )
    if alpha is not None:
        ax.axhline(alpha, color="0.4", ls=":", label=rf"$\alpha$ = {alpha:g}")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("probability of alarm")
    legend_outside(ax)
    return ax


@styled
def plot_isolation(result, ax=None, cmap: str = "Reds"):
    """``P(mode among the diagnoses | true mode)``, coloured by its distance from the ideal.

    Parameters
    ----------
    result : course.diagnosis.IsolationResult
    ax : matplotlib.axes.Axes, optional
    cmap : str
        Colour map of the distance from the ideal table (white: ideal).

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.diagnosis.isolation_monte_carlo : The probabilities it draws.

    Notes
    -----
    The ideal table is not the identity: with no fault (row NF) no test
    should alarm, nothing is ruled out and *every* mode stays a diagnosis
    (ideal 1 everywhere); with a fault the true mode should be the only
    diagnosis (1 on the diagonal, 0 elsewhere, NF included). Each cell is
    coloured by ``|P - ideal|``, so a white table is a perfect one and the
    colour shows where isolation fails. The colour scale ends at the largest
    distance in the table (rounded up to a multiple of 0.05), not at 1, so
    that small failures are visible. A last column, after a gap, shows
    ``result.exact`` (the diagnosis is exactly the true mode; ideal 1 for a
    fault); for a mode no test reacts to it is zero by construction and is
    left grey.
    """
    M = _checks.array("result.membership", result.membership, ndim=2, what="probabilities")
    modes = list(result.structure.modes)
    simulated = list(result.simulated)
    ideal = np.zeros_like(M)
    for i, mode in enumerate(simulated):
        if mode not in modes:
            continue
        if not np.asarray(result.structure.sensitivity)[:, modes.index(mode)].any():
            ideal[i, :] = 1.0  # a mode no test reacts to: nothing can be ruled out
        else:
            ideal[i, modes.index(mode)] = 1.0
    exact = _checks.array("result.exact", result.exact, ndim=1, what="probabilities")
    undefined = np.array([ideal[i].all() for i in range(M.shape[0])])  # NF: exact is 0 by design
    # the table, a gap column, and the "exact" column
    table = np.full((M.shape[0], M.shape[1] + 2), np.nan)
    table[:, : M.shape[1]] = np.abs(M - ideal)
    table[:, -1] = np.where(undefined, np.nan, 1.0 - exact)
    top = max(0.05, float(np.ceil(np.nanmax(table) * 20) / 20))
    import matplotlib
    from matplotlib.patches import Rectangle

    colours = matplotlib.colormaps[cmap].with_extremes(bad="white")
    ax = axes_or_new(ax)
    image = ax.imshow(table, vmin=0, vmax=top, cmap=colours)
    for row in np.flatnonzero(undefined).tolist():
        ax.add_patch(
            Rectangle((table.shape[1] - 1.5, row - 0.5), 1, 1, color="0.85", lw=0, zorder=1)
        )
    ax.set_xticks([*range(len(modes)), table.shape[1] - 1], [*modes, "exact"])
    ax.set_yticks(range(len(simulated)), simulated)
    shown = [
        (i, j, M[i, j], ideal[i, j] == 1) for i in range(M.shape[0]) for j in range(M.shape[1])
    ]
    shown += [(i, table.shape[1] - 1, exact[i], not undefined[i]) for i in range(M.shape[0])]
    for i, j, value, ideal_one in shown:
        distance = table[i, j]
        ax.text(
            j,
            i,
            f"{value:.2f}",
            ha="center",
            va="center",
            color="white" if np.isfinite(distance) and distance > 0.6 * top else "black",
            fontweight="bold" if ideal_one else "normal",
            zorder=2,
        )
    ax.grid(False)
    ax.figure.colorbar(image, ax=ax, shrink=0.8, label="|P − ideal|")
    ax.set_xlabel("mode among the diagnoses")
    ax.set_ylabel("true mode")
    ax.set_title("P(mode is a diagnosis | true mode); bold: ideal 1")
    return ax


@styled
def plot_recursive_estimates(
    t, theta, nominal=None, labels: Sequence[str] | None = None, ax=None, band=None, colors=None
):
    """Recursive parameter estimates over time, with optional ±band and nominal lines.

    Parameters
    ----------
    t : (N,) array_like
    theta : (N,) or (N, k) array_like
        Estimates.
    nominal : float or array_like, optional
        Nominal values, drawn dotted.
    labels : sequence of str, optional
    ax : matplotlib.axes.Axes, optional
    band : (N,) or (N, k) array_like, optional
        Half width of a band around each estimate.
    colors : sequence of int or str, optional
        Colour pair of each estimate.

    Returns
    -------
    matplotlib.axes.Axes
    """
    t = _checks.array("t", t, what="times")
    theta = _checks.array("theta", theta, ndim=(1, 2), what="estimates")
    theta = theta[:, None] if theta.ndim == 1 else theta
    _checks.same_length("t", t, "theta", theta)
    if band is not None:
        b = _checks.array("band", band, ndim=(1, 2), what="band half-widths")
        b = b[:, None] if b.ndim == 1 else b
        if b.shape != theta.shape:
            raise ValueError(f"band must have the shape of theta {theta.shape}, got {b.shape}")
    ax = axes_or_new(ax)
    for i in range(theta.shape[1]):
        colours = _colour(colors[i] if colors is not None else None, i)
        name = labels[i] if labels is not None else rf"$\hat\theta_{i + 1}$"
        if band is not None:
            ax.fill_between(
                t,
                theta[:, i] - b[:, i],
                theta[:, i] + b[:, i],
                color=colours.light,
                alpha=0.7,
                lw=0,
                label=f"{name} ± band",
            )
        ax.plot(t, theta[:, i], color=colours.dark, label=name)
        if nominal is not None:
            ax.axhline(np.atleast_1d(nominal)[i], color=colours.dark, ls=":", lw=1)
    ax.set_xlabel("t [samples]")
    ax.set_ylabel("estimate")
    legend_outside(ax)
    return ax


@styled
def plot_windowed_statistic(
    t, statistic, threshold: float, ax=None, label: str = "windowed test quantity"
):
    """A test quantity over time with its threshold; alarms are marked.

    Parameters
    ----------
    t, statistic : (N,) array_like
        Times and the statistic (NaN where undefined, e.g. before the first
        full window).
    threshold : float
    ax : matplotlib.axes.Axes, optional
    label : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    t = _checks.array("t", t, what="times")
    statistic = _checks.array("statistic", statistic, allow_nan=True, what="test quantities")
    _checks.same_length("t", t, "statistic", statistic)
    threshold = _checks.scalar("threshold", threshold)
    ax = axes_or_new(ax)
    ax.plot(t, statistic, color=pair(0).dark, label=label)
    threshold_line(ax, threshold, label=f"threshold {threshold:.4g}", orientation="horizontal")
    _mark_alarms(ax, t, statistic, threshold)
    ax.set_xlabel("t [samples]")
    ax.set_ylabel("test quantity")
    legend_outside(ax)
    return ax
