"""Figures for least-squares validation (notebook 01).

Every function takes ``ax=None`` (a new figure is made when None), returns
the axes it drew on and draws in the course style
(:mod:`course.plotting.style`). Matplotlib (and scipy for densities) are
imported inside the functions, so importing this module is cheap. The figures follow
Tiberius et al. (2021, Chapter 10) and Baarda (1968), listed in full in the course bibliography
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

import numpy as np

from . import _checks, axes_or_new
from .style import (
    LAW,
    REJECT,
    THEORY_POINTS,
    legend_outside,
    pair,
    sample_histogram,
    shade_tail,
    styled,
    theory_grid,
    threshold_line,
)

__all__ = [
    "line_design",
    "plot_chi2_histogram",
    "plot_confidence_band",
    "plot_data_snooping_loop",
    "plot_error_bars",
    "plot_line_fit",
    "plot_projection_geometry",
    "plot_residual_segments",
    "plot_sum_of_squares",
    "plot_w_tests",
    "sum_of_squares_grid",
]

_DATA = pair("data")
_FIT = pair(0)


def line_design(t, t0: float = 0.0, degree: int = 1) -> np.ndarray:
    """Design rows ``[1, (t - t0), (t - t0)^2 / 2, ...]`` of a polynomial motion model.

    Column k is ``(t - t0)^k / k!``: position, velocity, acceleration, ... as
    in the chapter's constant-velocity and constant-acceleration models.

    Examples
    --------
    >>> from course.plotting.lsq import line_design
    >>> line_design([1.0, 2.0], degree=2).tolist()
    [[1.0, 1.0, 0.5], [1.0, 2.0, 2.0]]
    """
    dt = np.asarray(t, dtype=float) - t0
    if not isinstance(degree, (int, np.integer)) or isinstance(degree, bool) or degree < 0:
        raise ValueError(f"degree must be a whole number >= 0, got {degree!r}")
    columns = [np.ones_like(dt)]
    factorial = 1.0
    for k in range(1, degree + 1):
        factorial *= k
        columns.append(dt**k / factorial)
    return np.column_stack(columns)


def _default_design(fit, design):
    if design is not None:
        if not callable(design):
            raise ValueError("design must be a callable t_grid -> rows of A")
        return design
    if fit.n != 2:
        raise ValueError(
            f"the fit has n = {fit.n} parameters: pass design=callable(t) -> rows of A "
            "(only the straight line [1, t] is assumed by default)"
        )
    return line_design


def _grid(t, design, num=None):
    span = t.max() - t.min()
    pad = 0.05 * span if span > 0 else 0.5
    grid = theory_grid(t.min() - pad, t.max() + pad, num or 0)
    return grid, design(grid)


def _t_and_y(t, y):
    t = _checks.array("t", t, what="observation times")
    y = _checks.array("y", y, what="observations")
    _checks.same_length("t", t, "y", y)
    return t, y


@styled
def plot_line_fit(
    t,
    y,
    fit,
    design=None,
    ax=None,
    data_label="observations",
    fit_label="least-squares fit",
    show_data=True,
    xlabel="t",
    ylabel="observation y",
    color=None,
):
    """Observations as circles and the fitted curve as a line.

    Parameters
    ----------
    t, y : array_like
        Observation times (regressor) and values.
    fit : course.lsq.LeastSquaresFit
        The fit whose ``x_hat`` is drawn.
    design : callable, optional
        ``design(t_grid) -> A_grid``, the rows of A at the given times; the
        straight line ``[1, t]`` by default (required when ``fit.n != 2``).
    ax : matplotlib axes, optional
    data_label, fit_label : str
        Legend texts.
    show_data : bool
        Draw the observations (switch off when they are already drawn, e.g.
        with error bars).
    xlabel, ylabel : str
        Axis labels; give the units (``"t [s]"``, ``"position [m]"``).
    color : str, optional
        Colour of the fitted curve (the first pair's dark shade by default).

    Returns
    -------
    matplotlib.axes.Axes
    """
    t, y = _t_and_y(t, y)
    show_data = _checks.flag("show_data", show_data)
    ax = axes_or_new(ax)
    design = _default_design(fit, design)
    grid, A_grid = _grid(t, design)
    if show_data:
        ax.plot(t, y, "o", color=_DATA.dark, mfc="none", label=data_label, zorder=4)
    ax.plot(grid, A_grid @ fit.x_hat, "-", color=color or _FIT.dark, label=fit_label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
def plot_residual_segments(
    t, y, fit, design=None, ax=None, xlabel="t", ylabel="observation y", annotate=None
):
    r"""The residuals as vertical segments between each observation and the fitted curve.

    Parameters
    ----------
    t, y : array_like
        Observation times and values (the data of ``fit``).
    fit : course.lsq.LeastSquaresFit
    design : callable, optional
        As for :func:`plot_line_fit`.
    xlabel, ylabel : str
        Axis labels with units.
    annotate : bool, optional
        Write each ``ê_i`` beside its segment (default: when there are at
        most 10 observations).

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.lsq.fit : The fit whose residuals it draws.
    plot_projection_geometry : The same residuals as a vector.

    Notes
    -----
    :math:`\hat e_i = y_i - \hat y_i` is the vertical distance of observation
    :math:`i` from the curve: least squares makes :math:`\sum_i \hat e_i^2`
    (weighted by :math:`Q_{yy}`) as small as any curve of the model can.
    """
    t, y = _t_and_y(t, y)
    if y.size != fit.m:
        raise ValueError(f"y has {y.size} observations but the fit has m = {fit.m}")
    ax = axes_or_new(ax)
    design = _default_design(fit, design)
    grid, A_grid = _grid(t, design)
    y_hat = np.asarray(fit.y_hat, dtype=float)
    e_hat = y - y_hat
    ax.plot(grid, A_grid @ fit.x_hat, "-", color=_FIT.dark, label="fitted curve ŷ(t)")
    up, down = pair(1), pair(2)
    for i, (ti, yi, fi, ei) in enumerate(zip(t, y, y_hat, e_hat)):
        colour = up.dark if ei >= 0 else down.dark
        ax.plot([ti, ti], [fi, yi], "-", color=colour, lw=2.2, zorder=3)
        if i == 0:
            ax.plot([], [], "-", color=up.dark, lw=2.2, label=r"residual $\hat e_i > 0$")
            ax.plot([], [], "-", color=down.dark, lw=2.2, label=r"residual $\hat e_i < 0$")
    ax.plot(t, y, "o", color=_DATA.dark, mfc="white", label="observation $y_i$", zorder=4)
    ax.plot(t, y_hat, ".", color=_FIT.dark, ms=6, label=r"fitted $\hat y_i$", zorder=4)
    if annotate is None:
        annotate = t.size <= 10
    if _checks.flag("annotate", bool(annotate)):
        for ti, yi, fi, ei in zip(t, y, y_hat, e_hat):
            ax.annotate(
                f"{ei:+.3g}" if abs(ei) > 1e-9 * max(1.0, abs(yi)) else "0",
                xy=(ti, (yi + fi) / 2),
                xytext=(5, 0),
                textcoords="offset points",
                va="center",
                fontsize="small",
            )
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
def plot_projection_geometry(A, y, ax=None, labels=("$a_1$", "$a_2$")):
    r"""Least squares as an orthogonal projection: ``ŷ`` in range(A), ``ê ⟂ range(A)``.

    Parameters
    ----------
    A : (3, 2) array_like
        A design matrix of three observations and two parameters (so that
        the picture fits in three dimensions); ``Q_yy = I``.
    y : (3,) array_like
        The observations.
    ax : 3-D matplotlib axes, optional
        Created (with ``projection="3d"``) when None.
    labels : (str, str)
        Names of the two columns of A.

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    plot_residual_segments : The same residuals along the record.

    Notes
    -----
    The picture is drawn in an orthonormal basis adapted to the plane (a
    rotation of the observation space, so lengths and angles are kept):
    :math:`\operatorname{range}(A)` is horizontal and its normal vertical.  The
    columns of :math:`A` span a plane, :math:`\operatorname{range}(A)`: every
    :math:`Ax` lies in it. The fitted observations :math:`\hat y = A\hat x` are
    the point of the plane closest to :math:`y`, so the residual vector
    :math:`\hat e = y - \hat y` is perpendicular to the plane:

    .. math::

        A^{\mathsf T} \hat e = 0 \quad \text{(the normal equations)}, \qquad
        \lVert y \rVert^2 = \lVert \hat y \rVert^2 + \lVert \hat e \rVert^2 .
    """
    A = _checks.array("A", A, ndim=2, what="design-matrix entries")
    y = _checks.array("y", y, what="observations")
    if A.shape != (3, 2) or y.shape != (3,):
        raise ValueError(
            f"the picture needs A of shape (3, 2) and y of shape (3,), got {A.shape} and {y.shape}"
        )
    if np.linalg.matrix_rank(A) < 2:
        raise ValueError("the columns of A must span a plane (A has rank < 2)")
    ax = axes_or_new(ax, projection="3d")
    if not hasattr(ax, "plot_surface"):
        raise ValueError("ax must be a 3-D axes (projection='3d')")
    # Draw in an orthonormal basis adapted to the plane (a rotation: lengths
    # and angles are those of the observation space): q1, q2 span range(A),
    # q3 is its normal, so the plane is horizontal and ê is vertical.
    Q, _ = np.linalg.qr(A, mode="complete")
    if Q[:, 2] @ y < 0:
        Q[:, 2] = -Q[:, 2]
    a = Q.T @ A
    x_hat = np.linalg.lstsq(A, y, rcond=None)[0]
    yc, y_hat = Q.T @ y, Q.T @ (A @ x_hat)
    y_hat[2] = 0.0
    e_hat = yc - y_hat
    reach = 1.15 * max(np.abs(a[:2]).max(), np.abs(yc[:2]).max(), 1.0)
    s, u = np.meshgrid(np.linspace(-reach, reach, 2), np.linspace(-reach, reach, 2))
    ax.plot_surface(s, u, np.zeros_like(s), color=_FIT.light, alpha=0.35, lw=0)
    ax.text(0.75 * reach, -0.95 * reach, 0, "range($A$)", color=_FIT.dark)

    def arrow(start, vector, colour, label, lw=2.0):
        ax.quiver(*start, *vector, color=colour, lw=lw, arrow_length_ratio=0.08, label=label)

    origin = np.zeros(3)
    for k in range(2):
        arrow(origin, a[:, k], _FIT.dark, None, lw=1.0)
        # column labels beyond the arrow tips and just under the plane, clear of y and ŷ
        ax.text(
            *(1.18 * a[:, k] - [0, 0, 0.1 * reach]),
            labels[k],
            color=_FIT.dark,
            ha="center",
            va="top",
        )
    arrow(origin, yc, _DATA.dark, "observations $y$")
    arrow(origin, y_hat, _FIT.dark, r"$\hat y = A\hat x$ in range($A$)")
    arrow(y_hat, e_hat, REJECT.dark, r"$\hat e = y - \hat y \perp$ range($A$)")
    ax.plot([yc[0], y_hat[0]], [yc[1], y_hat[1]], [0, 0], ":", color="0.4", lw=0.8)
    size = 0.1 * min(np.linalg.norm(e_hat), np.linalg.norm(y_hat))
    if size > 0:  # a right-angle mark at ŷ
        d1 = -y_hat / np.linalg.norm(y_hat) * size
        d2 = e_hat / np.linalg.norm(e_hat) * size
        corner = np.array([y_hat + d1, y_hat + d1 + d2, y_hat + d2])
        ax.plot(*corner.T, color="k", lw=0.8)
    ax.text(*(yc + [0, 0, 0.06 * reach]), "$y$", color=_DATA.dark, ha="center", va="bottom")
    ax.text(*(y_hat - [0, 0, 0.08 * reach]), r"$\hat y$", color=_FIT.dark, ha="center", va="top")
    ax.text(*(y_hat + 0.5 * e_hat), r"  $\hat e$", color=REJECT.dark, ha="left", va="center")
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-reach, reach)
    ax.set_zlim(-0.2 * reach, max(yc[2], 0.5 * reach))
    ax.set_xlabel("in range($A$), $q_1$")
    ax.set_ylabel("in range($A$), $q_2$")
    ax.set_zlabel(r"$\perp$ range($A$)")
    legend_outside(ax, where="below")
    return ax


@styled
def plot_error_bars(
    t, y, sigma, ax=None, level=0.95, label=None, xlabel="t", ylabel="observation y"
):
    """Observations with error bars ``± r σ``, ``r = norm.isf((1 - level)/2)`` (1.96 for 95 %).

    Parameters
    ----------
    t, y : array_like
        Observation times and values.
    sigma : float or array_like
        Standard deviation(s) of the observations.
    level : float
        Coverage of the error bars.
    label, xlabel, ylabel : str, optional
        Legend text and axis labels (give the units).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from scipy import stats

    t, y = _t_and_y(t, y)
    level = _checks.probability("level", level)
    sigma = _checks.array("sigma", sigma, ndim=(0, 1), what="standard deviations")
    if np.any(sigma <= 0):
        raise ValueError("sigma must be positive (standard deviations of the observations)")
    try:
        sigma = np.broadcast_to(sigma, y.shape)
    except ValueError:
        raise ValueError(
            f"sigma must be one number or one per observation ({y.size}), got {sigma.size}"
        ) from None
    ax = axes_or_new(ax)
    r = stats.norm.isf((1 - level) / 2)
    if label is None:
        label = rf"observations $\pm$ {r:.2f}$\sigma$"
    ax.errorbar(
        t, y, yerr=r * sigma, fmt="o", color=_DATA.dark, mfc="white", capsize=3, label=label
    )
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


@styled
def plot_confidence_band(
    t, fit, design=None, ax=None, level=0.95, t_grid=None, xlabel="t", ylabel="observation y"
):
    """Fitted curve with its dashed confidence band (Figure 10.3, right).

    Parameters
    ----------
    t : array_like
        Observation times (used to choose the plotting range).
    fit : course.lsq.LeastSquaresFit
    design : callable, optional
        ``design(t_grid) -> A_grid``; the straight line ``[1, t]`` by default
        (required when ``fit.n != 2``).
    level : float
        Confidence level of the band.
    t_grid : array_like, optional
        Where to draw the band (default: a fine grid over ``t``).
    xlabel, ylabel : str
        Axis labels with units.

    Returns
    -------
    matplotlib.axes.Axes
    """
    from ..lsq import confidence_band

    t = _checks.array("t", t, what="observation times")
    level = _checks.probability("level", level)
    ax = axes_or_new(ax)
    design = _default_design(fit, design)
    if t_grid is None:
        grid, A_grid = _grid(t, design)
    else:
        grid = _checks.array("t_grid", t_grid, min_size=2, what="times")
        A_grid = design(grid)
    y_hat, half = confidence_band(fit, A_grid, level=level)
    ax.fill_between(
        grid,
        y_hat - half,
        y_hat + half,
        color=_FIT.light,
        alpha=0.6,
        lw=0,
        label=f"{100 * level:.0f}% confidence band of ŷ(t)",
    )
    ax.plot(grid, y_hat, "-", color=_FIT.dark, label="fitted line ŷ(t)")
    ax.plot(grid, y_hat - half, "--", color=_FIT.dark, lw=1.0)
    ax.plot(grid, y_hat + half, "--", color=_FIT.dark, lw=1.0)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    return ax


def sum_of_squares_grid(A, y, x1_values, x2_values, Qyy=None):
    """``(y - A x)^T Qyy^{-1} (y - A x)`` on a grid of two parameters.

    Returns an array of shape ``(len(x2_values), len(x1_values))`` (rows
    follow ``x2``, as ``pcolormesh`` expects).

    Examples
    --------
    >>> import numpy as np
    >>> from course.plotting.lsq import sum_of_squares_grid
    >>> A = np.column_stack([np.ones(4), np.arange(1.0, 5.0)])
    >>> float(sum_of_squares_grid(A, [14.0, 20.0, 20.0, 24.0], [12.0], [3.0])[0, 0])
    6.0
    """
    from ..linalg import cholesky_lower, whiten

    A = _checks.array("A", A, ndim=2, what="design-matrix entries")
    y = _checks.array("y", y, what="observations")
    if A.shape[1] != 2:
        raise ValueError(
            f"the sum-of-squares surface needs exactly 2 parameters, A has {A.shape[1]}"
        )
    if A.shape[0] != y.size:
        raise ValueError(f"A has {A.shape[0]} rows but y has {y.size} observations")
    x1 = _checks.array("x1_values", x1_values, what="parameter values")
    x2 = _checks.array("x2_values", x2_values, what="parameter values")
    X1, X2 = np.meshgrid(x1, x2)
    residuals = y[:, None] - A @ np.vstack([X1.ravel(), X2.ravel()])
    if Qyy is not None:
        residuals = whiten(cholesky_lower(Qyy, "Qyy"), residuals)
    return np.sum(residuals**2, axis=0).reshape(X1.shape)


@styled
def plot_sum_of_squares(
    A,
    y,
    x1_values,
    x2_values,
    Qyy=None,
    log10=False,
    surface=False,
    ax=None,
    minimum=None,
    labels=(r"$x(t_0)$ [m]", r"$\dot x$ [m/s]"),
    value_unit=r"m$^2$",
):
    """The least-squares criterion over two parameters (Figure 10.2).

    Parameters
    ----------
    A, y, Qyy
        The model; ``A`` must have two columns.
    x1_values, x2_values : array_like
        Grid of the first and second parameter.
    log10 : bool
        Show ``log10`` of the sum of squares (reveals the valley's shape).
    surface : bool
        Draw a 3-D surface (a 3-D axes is created when ``ax`` is None);
        otherwise a filled contour map.
    minimum : (float, float), optional
        Where to mark the minimum (e.g. ``fit.x_hat``), with dotted lines.
    labels : (str, str)
        Axis labels of the two parameters, with units.
    value_unit : str
        Unit of the sum of squares (the unit of ``y`` squared) for the colour
        or z axis; unused when ``Qyy`` weights it into a pure number.

    Returns
    -------
    matplotlib.axes.Axes
    """
    log10 = _checks.flag("log10", log10)
    surface = _checks.flag("surface", surface)
    S = sum_of_squares_grid(A, y, x1_values, x2_values, Qyy)
    Z = np.log10(S) if log10 else S
    X1, X2 = np.meshgrid(np.asarray(x1_values, float), np.asarray(x2_values, float))
    if Qyy is None:  # plain sum of squares: the unit of y squared
        zlabel = (
            rf"$\log_{{10}}$(sum of squares / 1 {value_unit})"
            if log10
            else f"sum of squared residuals [{value_unit}]"
        )
    else:  # weighted by Q_yy^-1: a pure number
        zlabel = r"$\log_{10}$ weighted sum of squares" if log10 else "weighted sum of squares"
    if minimum is not None:
        minimum = _checks.array("minimum", minimum, what="parameter values")
        if minimum.size != 2:
            raise ValueError(f"minimum must hold the two parameters, got {minimum.size} values")
    if surface:
        ax = axes_or_new(ax, projection="3d")
        ax.plot_surface(X1, X2, Z, cmap="viridis", linewidth=0, antialiased=True, alpha=0.9)
        ax.set_zlabel(zlabel)
        if minimum is not None:
            value = sum_of_squares_grid(A, y, minimum[:1], minimum[1:], Qyy)[0, 0]
            zmin = np.log10(value) if log10 else value
            # a 3-D marker at the bottom of the bowl is hidden by the surface: draw a stem from
            # the minimum up above the surface, with the marker at both ends
            top = float(np.nanmax(Z))
            ax.plot(
                [minimum[0]] * 2,
                [minimum[1]] * 2,
                [zmin, top],
                color=REJECT.dark,
                lw=1.5,
                zorder=10,
            )
            ax.scatter(
                [minimum[0]] * 2,
                [minimum[1]] * 2,
                [zmin, top],
                color=REJECT.dark,
                s=30,
                depthshade=False,
                zorder=11,
            )
            ax.text(minimum[0], minimum[1], top, "  minimum", color=REJECT.dark, zorder=12)
    else:
        ax = axes_or_new(ax)
        mesh = ax.pcolormesh(X1, X2, Z, shading="auto", cmap="viridis")
        ax.contour(X1, X2, Z, levels=12, colors="white", linewidths=0.5)
        ax.figure.colorbar(mesh, ax=ax, label=zlabel)
        ax.grid(False)
        if minimum is not None:
            ax.axvline(minimum[0], color=REJECT.dark, linestyle=":")
            ax.axhline(minimum[1], color=REJECT.dark, linestyle=":")
            ax.plot([minimum[0]], [minimum[1]], "o", color=REJECT.dark)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    return ax


@styled
def plot_chi2_histogram(T, dof, ax=None, alpha=None, bins=40, noncentrality=None):
    """Histogram of simulated statistics against the chi-square(dof) density.

    Parameters
    ----------
    T : (n,) array_like
        Simulated values of the overall-model-test statistic, one per record.
    dof : int
        Degrees of freedom ``m - n``.
    alpha : float, optional
        Shade the critical region ``T > chi2.isf(alpha, dof)`` and draw the
        critical value.
    bins : int
        Number of histogram bins.
    noncentrality : float, optional
        Also draw the non-central ``chi2(dof, λ)`` density of the statistic
        under an alternative (an outlier or a model error).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from scipy import stats

    T = _checks.array("T", T, what="simulated statistics (one per record)")
    dof = _checks.positive_int("dof", dof)
    alpha = _checks.probability("alpha", alpha, allow_none=True)
    bins = _checks.positive_int("bins", bins)
    lam = _checks.scalar("noncentrality", noncentrality, allow_none=True)
    if lam is not None and lam < 0:
        raise ValueError(f"noncentrality must be >= 0, got {lam:g}")
    ax = axes_or_new(ax)
    upper = max(float(np.quantile(T, 0.995)), stats.chi2.isf(0.002, dof))
    if lam is not None:
        upper = max(upper, float(stats.ncx2.isf(0.005, dof, lam)) if lam > 0 else upper)
    sample_histogram(ax, T, bins=bins, range=(0, upper), label=f"simulated $T$ ({T.size} records)")
    grid = theory_grid(0.0, upper, THEORY_POINTS + 1)[1:]  # the density may be infinite at 0
    density = stats.chi2.pdf(grid, dof)
    if alpha is not None:
        k = stats.chi2.isf(alpha, dof)
        shade_tail(ax, grid, density, upper=k, label=rf"critical region, $\alpha$ = {alpha:g}")
        threshold_line(ax, k, label=rf"$\chi^2_{{\alpha}}({dof})$ = {k:.4g}")
    ax.plot(grid, density, color=LAW, lw=2, label=rf"$\chi^2({dof})$ density")
    if lam is not None:
        ax.plot(
            grid,
            stats.ncx2.pdf(grid, dof, lam) if lam > 0 else density,
            color=pair(1).dark,
            ls=pair(1).ls,
            lw=2,
            label=rf"$\chi^2({dof}, \lambda = {lam:.3g})$ under the alternative",
        )
    ax.set_xlabel(r"$T = \hat e^{T} Q_{yy}^{-1} \hat e$")
    ax.set_ylabel("density")
    legend_outside(ax)
    return ax


@styled
def plot_w_tests(w_result, ax=None, index=None, xlabel="observation"):
    """Bar chart of the w-statistics with the two-sided critical region shaded.

    Parameters
    ----------
    w_result : course.lsq.WTestResult
    index : array_like, optional
        Labels of the bars (e.g. the epochs or original indices); default 0..m-1.
    xlabel : str
        Label of the horizontal axis.

    Returns
    -------
    matplotlib.axes.Axes
    """
    w = _checks.array("w_result.statistic", w_result.statistic, allow_nan=True, what="w-statistics")
    x = np.arange(w.size) if index is None else _checks.array("index", index, what="labels")
    _checks.same_length("index", x, "w_result.statistic", w)
    ax = axes_or_new(ax)
    reject = np.asarray(w_result.reject, dtype=bool)
    colors = np.where(reject, REJECT.dark, pair(0).dark)
    k = w_result.critical_value
    top = max(1.15 * np.nanmax(np.abs(w)), 1.5 * k)
    if any(other.has_data() for other in ax.get_shared_y_axes().get_siblings(ax)):
        top = max(top, *np.abs(ax.get_ylim()))  # never cut the bars of a panel sharing the axis
    ax.axhspan(k, 10 * top, color=REJECT.light, alpha=0.35, lw=0, label="critical region")
    ax.axhspan(-10 * top, -k, color=REJECT.light, alpha=0.35, lw=0)
    ax.bar(x, np.nan_to_num(w), color=colors, width=0.7, zorder=3)
    # legend entries only for what the bars show: no "rejected" when nothing is
    if reject.any():
        ax.bar([np.nan], [0], color=REJECT.dark, label="rejected")
    if not reject.all():
        ax.bar([np.nan], [0], color=pair(0).dark, label="accepted")
    threshold_line(
        ax,
        k,
        label=rf"$\pm N_{{\alpha/2}}$ = ±{k:.3f} ($\alpha$ = {w_result.alpha:g})",
        orientation="horizontal",
    )
    threshold_line(ax, -k, orientation="horizontal")
    ax.axhline(0, color="0.5", linewidth=0.5)
    ax.set_ylim(-top, top)
    if w.size <= 12:
        ax.set_xticks(x)
    else:
        ax.xaxis.get_major_locator().set_params(integer=True)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(r"$w_i = \hat e_i / \sigma_{\hat e_i}$")
    legend_outside(ax)
    return ax


@styled
def plot_data_snooping_loop(result=None, ax=None):
    """The detection–identification–adaptation loop of data snooping, as a diagram.

    Parameters
    ----------
    result : course.lsq.SnoopingResult, optional
        When given, the rounds of this run are written beside the loop
        (which observation was removed at which ``|w|``) and the way out it
        took is highlighted.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes

    See Also
    --------
    course.lsq.data_snooping : The loop it draws.

    Notes
    -----
    Detection: the overall model test asks whether anything is wrong.
    Identification: the w-tests point at the observation most likely to be
    wrong (the largest ``|w_i|``). Adaptation: remove it and fit again; then
    test again. The loop ends when nothing is rejected or no redundancy is
    left (Chapter 10.3 of the least-squares textbook; Baarda 1968).
    """
    from matplotlib.patches import FancyBboxPatch

    ax = axes_or_new(ax)
    removed = bool(result is not None and result.removed)
    ax.set_xlim(0, 10.2)
    ax.set_ylim(-0.9 if result is not None else 0.4, 6.3)
    ax.set_axis_off()
    width, height = 2.9, 1.2
    boxes = {
        "fit": (4.6, 5.5, "fit\n" + r"$\hat x,\ \hat e = y - A\hat x$", pair("NF")),
        "omt": (
            4.6,
            3.4,
            "detection: overall model test\n" + r"$T > \chi^2_\alpha(m-n)$?",
            pair(0),
        ),
        "w": (4.6, 1.3, "identification: w-tests\n" + r"largest $|w_i| > N_{\alpha/2}$?", pair(1)),
        "remove": (
            8.6,
            1.3,
            "adaptation\nremove observation $i$\n(if redundancy is left)",
            pair(2),
        ),
        "accept": (1.25, 3.4, "accept:\nmodel and data\nconsistent", pair(3)),
        "model": (1.25, 1.3, "no single outlier:\nlook for a\nmodel error", pair(4)),
    }
    for x, y, text, colours in boxes.values():
        w = width if x > 3 else 2.3
        ax.add_patch(
            FancyBboxPatch(
                (x - w / 2, y - height / 2),
                w,
                height,
                boxstyle="round,pad=0.08",
                fc=colours.light,
                ec=colours.dark,
                lw=1.2,
            )
        )
        ax.text(x, y, text, ha="center", va="center", fontsize="small")

    def link(a, b, label, highlight=False, style="arc3", offset=(0.0, 0.15)):
        ax.annotate(
            "",
            xy=b,
            xytext=a,
            arrowprops=dict(
                arrowstyle="-|>",
                lw=2.2 if highlight else 1.2,
                color=REJECT.dark if highlight else "0.25",
                connectionstyle=style,
                shrinkA=0,
                shrinkB=0,
            ),
        )
        if label:
            ax.text(
                (a[0] + b[0]) / 2 + offset[0],
                (a[1] + b[1]) / 2 + offset[1],
                label,
                ha="center",
                va="bottom",
                fontsize="small",
            )

    top, bottom = height / 2 + 0.08, -height / 2 - 0.08
    link((4.6, 5.5 + bottom), (4.6, 3.4 + top), None, highlight=removed)
    accepted = stuck = False
    if result is not None:
        from ..lsq import overall_model_test

        final = result.fit
        accepted = final.redundancy > 0 and not overall_model_test(final, result.alpha).reject
        stuck = not accepted
    link((4.6 - 1.53, 3.4), (1.25 + 1.23, 3.4), "no", highlight=accepted)
    link(
        (4.6, 3.4 + bottom),
        (4.6, 1.3 + top),
        "yes",
        offset=(0.25, -0.1),
        highlight=removed or stuck,
    )
    link((4.6 - 1.53, 1.3), (1.25 + 1.23, 1.3), "no", highlight=stuck)
    link((4.6 + 1.53, 1.3), (8.6 - 1.53, 1.3), "yes", highlight=removed)
    link(
        (8.6, 1.3 + top),
        (4.6 + 1.53, 5.5),
        None,
        highlight=removed,
        style="angle,angleA=90,angleB=0,rad=0",
    )
    ax.text(8.75, 3.6, "fit again\nand retest", ha="left", va="center", fontsize="small")
    if result is not None:
        lines = []
        for k, (wt, kept) in enumerate(zip(result.rounds, result.round_indices), start=1):
            j = wt.largest
            verdict = f"remove {kept[j]}" if wt.reject[j] else "nothing rejected"
            lines.append(f"round {k}: largest |w| = {abs(float(wt.statistic[j])):.2f} → {verdict}")
        lines.append(f"stopped: {result.stop_reason}")
        if result.fit.redundancy > 0:
            lines.append("final fit " + ("accepted" if accepted else "still rejected"))
        ax.text(
            0.1,
            -0.3,
            "this run:  " + ";  ".join(lines),
            ha="left",
            va="center",
            fontsize="small",
            wrap=True,
        )
    return ax
