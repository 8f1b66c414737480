"""Figures for least-squares validation (notebook 01, Chapter 10).

Every function takes ``ax=None`` (a new figure is made when None) and returns
the axes it drew on. Matplotlib (and scipy for densities) are imported inside
the functions, so importing this module is cheap.
"""

from __future__ import annotations

import numpy as np

from . import axes_or_new

__all__ = [
    "line_design",
    "plot_chi2_histogram",
    "plot_confidence_band",
    "plot_error_bars",
    "plot_line_fit",
    "plot_sum_of_squares",
    "plot_w_tests",
    "sum_of_squares_grid",
]


def line_design(t, t0: float = 0.0, degree: int = 1) -> np.ndarray:
    """Design rows ``[1, (t - t0), (t - t0)^2 / 2, ...]`` of a polynomial motion model.

    Column k is ``(t - t0)^k / k!``: position, velocity, acceleration, ... as
    in the chapter's constant-velocity and constant-acceleration models.
    """
    dt = np.asarray(t, dtype=float) - t0
    columns = [np.ones_like(dt)]
    factorial = 1.0
    for k in range(1, degree + 1):
        factorial *= k
        columns.append(dt**k / factorial)
    return np.column_stack(columns)


def _default_design(fit, design):
    if design is not None:
        return design
    if fit.n != 2:
        raise ValueError(
            f"the fit has n = {fit.n} parameters: pass design=callable(t) -> rows of A "
            "(only the straight line [1, t] is assumed by default)"
        )
    return line_design


def _grid(t, design, num=200):
    t = np.asarray(t, dtype=float)
    span = t.max() - t.min()
    grid = np.linspace(t.min() - 0.05 * span, t.max() + 0.05 * span, num)
    return grid, design(grid)


def plot_line_fit(
    t,
    y,
    fit,
    design=None,
    ax=None,
    data_label="observations",
    fit_label="least-squares fit",
    show_data=True,
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
    show_data : bool
        Draw the observations (switch off when they are already drawn, e.g.
        with error bars).
    """
    ax = axes_or_new(ax)
    design = _default_design(fit, design)
    grid, A_grid = _grid(t, design)
    if show_data:
        ax.plot(t, y, "o", color="C0", mfc="none", label=data_label)
    ax.plot(grid, A_grid @ fit.x_hat, "-", color="C3", label=fit_label)
    ax.set_xlabel("t")
    ax.set_ylabel("y")
    ax.legend(loc="best")
    return ax


def plot_error_bars(t, y, sigma, ax=None, level=0.95, label=None):
    """Observations with error bars ``± r σ``, ``r = norm.isf((1 - level)/2)`` (1.96 for 95 %)."""
    from scipy import stats

    ax = axes_or_new(ax)
    r = stats.norm.isf((1 - level) / 2)
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), np.shape(y))
    if label is None:
        label = f"observations ± {r:.2f}σ"
    ax.errorbar(t, y, yerr=r * sigma, fmt="o", color="C0", mfc="none", capsize=4, label=label)
    ax.set_xlabel("t")
    ax.set_ylabel("y")
    ax.legend(loc="best")
    return ax


def plot_confidence_band(t, fit, design=None, ax=None, level=0.95, t_grid=None):
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
    """
    from ..lsq import confidence_band

    ax = axes_or_new(ax)
    design = _default_design(fit, design)
    if t_grid is None:
        grid, A_grid = _grid(t, design)
    else:
        grid = np.asarray(t_grid, dtype=float)
        A_grid = design(grid)
    y_hat, half = confidence_band(fit, A_grid, level=level)
    ax.plot(grid, y_hat, "-", color="C3", label="fitted line ŷ(t)")
    ax.plot(grid, y_hat - half, "--", color="C0", label=f"{100 * level:.0f}% confidence band")
    ax.plot(grid, y_hat + half, "--", color="C0")
    ax.set_xlabel("t")
    ax.set_ylabel("y")
    ax.legend(loc="best")
    return ax


def sum_of_squares_grid(A, y, x1_values, x2_values, Qyy=None):
    """``(y - A x)^T Qyy^{-1} (y - A x)`` on a grid of two parameters.

    Returns an array of shape ``(len(x2_values), len(x1_values))`` (rows
    follow ``x2``, as ``pcolormesh`` expects).
    """
    from ..linalg import cholesky_lower, whiten

    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    if A.shape[1] != 2:
        raise ValueError(
            f"the sum-of-squares surface needs exactly 2 parameters, A has {A.shape[1]}"
        )
    X1, X2 = np.meshgrid(np.asarray(x1_values, float), np.asarray(x2_values, float))
    residuals = y[:, None] - A @ np.vstack([X1.ravel(), X2.ravel()])
    if Qyy is not None:
        residuals = whiten(cholesky_lower(Qyy, "Qyy"), residuals)
    return np.sum(residuals**2, axis=0).reshape(X1.shape)


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
    labels=("x(t0)", "ẋ"),
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
        Axis labels of the two parameters.
    """
    S = sum_of_squares_grid(A, y, x1_values, x2_values, Qyy)
    Z = np.log10(S) if log10 else S
    X1, X2 = np.meshgrid(x1_values, x2_values)
    zlabel = "log10 sum of squares" if log10 else "sum of squares"
    if surface:
        ax = axes_or_new(ax, projection="3d")
        ax.plot_surface(X1, X2, Z, cmap="viridis", linewidth=0, antialiased=True, alpha=0.9)
        ax.set_zlabel(zlabel)
        if minimum is not None:
            from ..lsq import fit as _fit

            value = _fit(A, y, Qyy).squared_norm
            zmin = np.log10(value) if log10 else value
            ax.scatter([minimum[0]], [minimum[1]], [zmin], color="C3", s=30)
    else:
        ax = axes_or_new(ax)
        mesh = ax.pcolormesh(X1, X2, Z, shading="auto", cmap="viridis")
        ax.contour(X1, X2, Z, levels=12, colors="white", linewidths=0.5)
        ax.figure.colorbar(mesh, ax=ax, label=zlabel)
        if minimum is not None:
            ax.axvline(minimum[0], color="C3", linestyle=":")
            ax.axhline(minimum[1], color="C3", linestyle=":")
            ax.plot([minimum[0]], [minimum[1]], "o", color="C3")
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    return ax


def plot_chi2_histogram(T, dof, ax=None, alpha=None, bins=40):
    """Histogram of simulated statistics against the chi-square(dof) density.

    Parameters
    ----------
    T : array_like
        Simulated values of the overall-model-test statistic.
    dof : int
        Degrees of freedom ``m - n``.
    alpha : float, optional
        Draw the critical value ``chi2.isf(alpha, dof)`` as a vertical line.
    """
    from scipy import stats

    ax = axes_or_new(ax)
    T = np.asarray(T, dtype=float)
    upper = max(float(np.quantile(T, 0.995)), stats.chi2.isf(0.005, dof))
    ax.hist(
        T,
        bins=bins,
        range=(0, upper),
        density=True,
        color="C0",
        alpha=0.5,
        label=f"simulated T ({T.size} runs)",
    )
    grid = np.linspace(1e-3, upper, 400)
    ax.plot(grid, stats.chi2.pdf(grid, dof), color="C3", label=f"χ²({dof}) density")
    if alpha is not None:
        k = stats.chi2.isf(alpha, dof)
        ax.axvline(k, color="k", linestyle="--", label=f"critical value, α = {alpha:g}")
    ax.set_xlabel("T")
    ax.set_ylabel("density")
    ax.legend(loc="best")
    return ax


def plot_w_tests(w_result, ax=None, index=None):
    """Bar chart of the w-statistics with the two-sided critical lines.

    Parameters
    ----------
    w_result : course.lsq.WTestResult
    index : array_like, optional
        Labels of the bars (e.g. the epochs or original indices); default 0..m-1.
    """
    ax = axes_or_new(ax)
    w = np.asarray(w_result.w, dtype=float)
    x = np.arange(w.size) if index is None else np.asarray(index)
    colors = np.where(w_result.reject, "C3", "C0")
    ax.bar(x, np.nan_to_num(w), color=colors)
    k = w_result.critical_value
    ax.axhline(k, color="k", linestyle="--", label=f"±{k:.3f} (α = {w_result.alpha:g})")
    ax.axhline(-k, color="k", linestyle="--")
    ax.axhline(0, color="0.5", linewidth=0.5)
    if w.size <= 25:
        ax.set_xticks(x)
    ax.set_xlabel("observation")
    ax.set_ylabel("w")
    ax.legend(loc="best")
    return ax
