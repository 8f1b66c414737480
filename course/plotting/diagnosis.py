"""Figures for the test-quantity notebooks (course.diagnosis).

Every function takes ``ax=None`` (a new figure when None) and returns the
axes it drew on.  Matplotlib is imported lazily, inside the functions.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from scipy import stats

from . import _mark_alarms, axes_or_new

__all__ = [
    "plot_criterion",
    "plot_density",
    "plot_isolation",
    "plot_likelihood",
    "plot_null_histogram",
    "plot_power_curves",
    "plot_recursive_estimates",
    "plot_residual_geometry",
    "plot_windowed_statistic",
]


def plot_residual_geometry(U1, U2, fault: float, ax=None):
    """The lecture's geometric picture of ``T = min over theta1 ||(1 - theta1) U1 - f U2||^2``.

    Parameters
    ----------
    U1, U2 : array_like, shape (N,)
        The signals of the decoupled parameter and of the faulty one.
    fault : float
        ``f = 1 - theta2``, the size of the fault in theta2.
    ax : matplotlib axes, optional

    Notes
    -----
    Everything happens in the plane spanned by ``U1`` and ``U2``, drawn in
    an orthonormal basis of it: ``e1`` along ``U1``, ``e2`` the part of
    ``U2`` orthogonal to ``U1``.  The free theta1 slides along the line
    through ``U1``; the best it can do is the orthogonal projection of
    ``f U2``, and ``sqrt(T)`` is the length of the perpendicular.  When
    ``U2`` is parallel to ``U1`` the perpendicular vanishes: the fault is
    invisible (the LiU lecture on test quantities, the geometric slide of
    ``T = min ||(1 - theta1) U1 - (1 - theta2) U2||^2``; full reference in
    the course bibliography, docs/bibliography.md).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    u1 = np.asarray(U1, dtype=float).ravel()
    u2 = np.asarray(U2, dtype=float).ravel()
    e1 = u1 / np.linalg.norm(u1)
    a = fault * u2
    along = float(e1 @ a)
    perp_vec = a - along * e1
    perp = float(np.linalg.norm(perp_vec))
    ortho = perp > 1e-12 * max(float(np.linalg.norm(a)), 1.0)
    point = np.array([along, perp])
    n1 = float(np.linalg.norm(u1))
    reach = max(abs(along), n1, perp, 1.0) * 1.25
    ax.plot([-reach, reach], [0, 0], color="0.7", lw=1, label=r"span$(U_1)$: $(1-\theta_1)U_1$")
    arrow = dict(arrowprops=dict(arrowstyle="->", lw=2), annotation_clip=False)
    ax.annotate(
        "",
        xy=(n1, 0),
        xytext=(0, 0),
        **{**arrow, "arrowprops": dict(arrowstyle="->", lw=2, color="C0")},
    )
    ax.text(n1, -0.08 * reach, r"$U_1$", color="C0", ha="center", va="top")
    ax.annotate(
        "",
        xy=tuple(point),
        xytext=(0, 0),
        **{**arrow, "arrowprops": dict(arrowstyle="->", lw=2, color="C1")},
    )
    ax.text(
        point[0],
        point[1] + 0.04 * reach,
        r"$(1-\theta_2)U_2$",
        color="C1",
        ha="center",
        va="bottom",
    )
    ax.plot([along], [0], "o", color="C2", label=r"best $(1-\hat\theta_1)U_1$")
    if ortho:
        ax.plot(
            [along, along],
            [0, perp],
            color="C3",
            lw=2,
            ls="--",
            label=rf"$\sqrt{{T}}$ = {perp:.3g}",
        )
    else:
        ax.plot([], [], color="C3", lw=2, ls="--", label=r"$\sqrt{T}$ = 0: $U_2 \parallel U_1$")
    ax.set_aspect("equal")
    margin = 0.15 * reach
    ax.set_xlim(min(0.0, along) - margin, max(n1, along) + margin)
    ax.set_ylim(-0.25 * reach, max(perp, 0.3 * reach) * 1.3)
    ax.set_xlabel(r"coordinate along $U_1$")
    ax.set_ylabel(r"coordinate orthogonal to $U_1$")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=3, fontsize="small")
    return ax


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
    ax = axes_or_new(ax)
    if z is None:
        z = np.linspace(theta - 4 * sigma, theta + 4 * sigma, 401)
    ax.plot(z, stats.norm.pdf(z, theta, sigma), color="C0", label=rf"$f(z\,|\,\theta={theta:g})$")
    if z_observed is not None:
        for zo in np.atleast_1d(z_observed):
            ax.plot([zo, zo], [0, stats.norm.pdf(zo, theta, sigma)], color="C3", ls=":")
            ax.plot([zo], [stats.norm.pdf(zo, theta, sigma)], "o", color="C3")
    ax.set_xlabel("$z$")
    ax.set_ylabel("density")
    ax.set_title(r"density: a function of $z$ for fixed $\theta$")
    ax.legend(fontsize="small")
    return ax


def plot_likelihood(z, sigma: float = 1.0, theta=None, ax=None, show_factors: bool = True):
    """The likelihood ``L(theta | z)`` of independent ``N(theta, sigma^2)`` observations.

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

    Notes
    -----
    ``L(theta | z) = prod_i f(z_i | theta)``, maximal at the sample mean
    (lecture slides "Likelihood-funktionen, normalfördelning": ``z = 2`` and
    ``z = (3, 5)`` with the maximum at ``theta = 4``).
    """
    ax = axes_or_new(ax)
    z = np.atleast_1d(np.asarray(z, dtype=float))
    if theta is None:
        theta = np.linspace(z.min() - 4 * sigma, z.max() + 4 * sigma, 801)
    theta = np.asarray(theta, dtype=float)
    factors = stats.norm.pdf(z[:, None], theta[None, :], sigma)
    like = np.prod(factors, axis=0)
    label = (
        "L(θ | z = "
        + (f"{z[0]:g}" if z.size == 1 else "(" + ", ".join(f"{v:g}" for v in z) + ")")
        + ")"
    )
    ax.plot(theta, like, color="C0", lw=2, label=label)
    if show_factors and z.size > 1:
        for i, zi in enumerate(z):
            ax.plot(
                theta,
                factors[i],
                ls="--",
                lw=1,
                color=f"C{i + 1}",
                label=f"f(z{i + 1} = {zi:g} | θ)",
            )
    mle = float(z.mean())
    peak = float(np.prod(stats.norm.pdf(z, mle, sigma)))
    ax.axvline(mle, color="C3", ls=":", lw=1)
    ax.plot([mle], [peak], "o", color="C3", label=f"maximum at θ = {mle:g}")
    ax.set_xlabel(r"$\theta$")
    ax.set_ylabel("likelihood")
    ax.set_title(r"likelihood: a function of $\theta$ for the observed $z$")
    ax.legend(fontsize="small")
    return ax


def plot_criterion(theta, values, ax=None, minimiser=None, label: str = r"$V(\theta_1)$"):
    """A 1-D criterion such as ``V(theta1) = sum (y - theta1 u1 - u2 - u3)^2``.

    Parameters
    ----------
    theta, values : array_like
        Grid and criterion values.
    ax : matplotlib.axes.Axes, optional
    minimiser : float, optional
        Marked with a vertical line.
    label : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    ax.plot(theta, values, color="C0", label=label)
    if minimiser is not None:
        ax.axvline(minimiser, color="C3", ls=":", label=rf"minimiser {minimiser:.4g}")
    ax.set_xlabel(r"$\theta_1$")
    ax.set_ylabel("criterion")
    ax.legend(fontsize="small")
    return ax


def plot_null_histogram(
    samples, null, critical_value: float, ax=None, bins: int = 50, label: str = "simulated under H0"
):
    """Histogram of a simulated test quantity with its null density and threshold.

    Parameters
    ----------
    samples : array_like
        Simulated test quantities.
    null : frozen distribution
        Anything with a ``pdf`` method (the ``null`` of a ``TestResult``).
    critical_value : float
        The threshold; the tail beyond it is shaded.
    ax : matplotlib.axes.Axes, optional
    bins : int
    label : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    samples = np.asarray(samples, dtype=float).ravel()
    hi = max(np.quantile(samples, 0.999), critical_value * 1.1)
    lo = min(samples.min(), 0.0) if samples.min() >= 0 else samples.min()
    ax.hist(samples, bins=bins, range=(lo, hi), density=True, color="0.75", label=label)
    grid = np.linspace(lo, hi, 400)
    ax.plot(grid, null.pdf(grid), color="C0", lw=2, label="null density")
    ax.axvline(critical_value, color="C3", ls="--", label=f"threshold {critical_value:.4g}")
    tail = grid[grid >= critical_value]
    ax.fill_between(tail, null.pdf(tail), color="C3", alpha=0.3)
    ax.set_xlabel("test quantity")
    ax.set_ylabel("density")
    ax.legend(fontsize="small")
    return ax


def plot_power_curves(
    sizes,
    theory: Mapping[str, Sequence[float]],
    simulated: Mapping[str, Sequence[float]] | None = None,
    alpha: float | None = None,
    ax=None,
    xlabel: str = "fault size",
):
    """Alarm probability against fault size: theory as lines, Monte Carlo as markers.

    Parameters
    ----------
    sizes : array_like
        Fault sizes.
    theory : mapping of str to sequence of float
        Power curves, one per label.
    simulated : mapping of str to sequence of float, optional
        Monte Carlo rates, matched to ``theory`` by label.
    alpha : float, optional
        Drawn as a horizontal line.
    ax : matplotlib.axes.Axes, optional
    xlabel : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    sizes = np.asarray(sizes, dtype=float)
    for i, (label, values) in enumerate(theory.items()):
        ax.plot(sizes, values, color=f"C{i}", label=f"{label} (theory)")
    if simulated:
        keys = list(theory)
        for label, values in simulated.items():
            i = keys.index(label) if label in keys else len(keys)
            ax.plot(sizes, values, "o", ms=4, color=f"C{i}", label=f"{label} (Monte Carlo)")
    if alpha is not None:
        ax.axhline(alpha, color="0.5", ls=":", label=f"alpha = {alpha:g}")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("probability of alarm")
    ax.legend(fontsize="small")
    return ax


def plot_isolation(result, ax=None, cmap: str = "Blues"):
    """Heat map of ``P(mode in diagnoses | true mode)`` from an IsolationResult.

    Parameters
    ----------
    result : course.diagnosis.IsolationResult
    ax : matplotlib.axes.Axes, optional
    cmap : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    M = np.asarray(result.membership)
    ax.imshow(M, vmin=0, vmax=1, cmap=cmap)
    modes = result.structure.modes
    ax.set_xticks(range(len(modes)), modes)
    ax.set_yticks(range(len(result.simulated)), result.simulated)
    for i in range(M.shape[0]):
        for j in range(M.shape[1]):
            ax.text(
                j,
                i,
                f"{M[i, j]:.2f}",
                ha="center",
                va="center",
                color="white" if M[i, j] > 0.6 else "black",
            )
    ax.set_xlabel("mode among the diagnoses")
    ax.set_ylabel("true mode")
    ax.set_title("P(mode is a diagnosis | true mode)")
    return ax


def plot_recursive_estimates(
    t, theta, nominal=None, labels: Sequence[str] | None = None, ax=None, band=None
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

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    theta = np.asarray(theta, dtype=float)
    theta = theta[:, None] if theta.ndim == 1 else theta
    for i in range(theta.shape[1]):
        name = labels[i] if labels is not None else rf"$\hat\theta_{i + 1}$"
        ax.plot(t, theta[:, i], color=f"C{i}", label=name)
        if band is not None:
            b = np.asarray(band, dtype=float)
            b = b[:, None] if b.ndim == 1 else b
            ax.fill_between(
                t, theta[:, i] - b[:, i], theta[:, i] + b[:, i], color=f"C{i}", alpha=0.2
            )
        if nominal is not None:
            ax.axhline(np.atleast_1d(nominal)[i], color=f"C{i}", ls=":", lw=1)
    ax.set_xlabel("t")
    ax.set_ylabel("estimate")
    ax.legend(fontsize="small")
    return ax


def plot_windowed_statistic(
    t, statistic, threshold: float, ax=None, label: str = "windowed test quantity"
):
    """A test quantity over time with its threshold; alarms are marked.

    Parameters
    ----------
    t, statistic : (N,) array_like
    threshold : float
    ax : matplotlib.axes.Axes, optional
    label : str

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = axes_or_new(ax)
    statistic = np.asarray(statistic, dtype=float)
    ax.plot(t, statistic, color="C0", label=label)
    ax.axhline(threshold, color="C3", ls="--", label=f"threshold {threshold:.4g}")
    _mark_alarms(ax, t, statistic, threshold, ".", color="C3")
    ax.set_xlabel("t")
    ax.set_ylabel("test quantity")
    ax.legend(fontsize="small")
    return ax
